/*
 * Per-point moving labels of detections in SemanticKITTI-MOS layout (pcl_movers_detect
 * --point-labels): one uint32 per input point, class in the low 16 bits, instance in the high 16.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/io/tracks.h>

#include <cstdint>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief SemanticKITTI class of a point without a return (NaN or zero range). */
constexpr std::uint16_t kNoReturnClass = 0;
/** \brief SemanticKITTI-MOS "static": a return not on a mover. */
constexpr std::uint16_t kStaticClass = 9;

/** \brief The SemanticKITTI moving class of a mover from its box (TrackRow length, width,
 * height [m]), for trackers that give no class. The rule, with L / S the longer / shorter
 * horizontal side:
 *  - L > 7 m: 258 moving-truck;
 *  - L > 2.5 m: 252 moving-car (cars, vans);
 *  - height > 1 m and L < 1.2 m: 254 moving-person;
 *  - height > 1 m, L <= 2.5 m and S < 1.2 m: 253 moving-bicyclist;
 *  - else 251 moving (class unknown): small, flat or wide-and-short boxes (a car seen only from
 *    behind, a fragment).
 * A box is only what the points of one frame show: a car seen end-on can pass for a cyclist. */
std::uint16_t moverClassFromBox(double length, double width, double height);

/** \brief The labels of one frame. Per input point, in the input's order: `has_return` (a
 * finite, non-zero-range point) and `mover_track` (the id of the mover track it belongs to, -1
 * when on none). Points of a mover get moverClassFromBox() of its row in `rows` (251 when the
 * row is missing) and the track id (its low 16 bits) as instance; other returns 9; points without
 * a return 0. */
std::vector<std::uint32_t> movingPointLabels(const std::vector<bool>& has_return,
                                             const std::vector<int>& mover_track,
                                             const std::vector<TrackRow>& rows);

}  // namespace io
}  // namespace pcl_movers
