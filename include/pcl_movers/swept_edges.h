/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <Eigen/Core>
#include <vector>

namespace pcl_movers {

class FreeSpaceMap;

/** \brief The displacement of an object whose view grew or shrank between two frames, read from
 * the one edge of the view whose move the free space confirms (sweptEdgeShift()).
 *
 * While a vehicle emerges from behind a nearer object, hides behind one, or is uncovered as the
 * sensor passes, its view's extent changes along its length, and the density registration has
 * a flat optimum: every shift that keeps one view inside the other matches equally well, and
 * the registered position slides towards the prediction (an emerging truck read at 1.6 m/s of
 * 6.8). Of the view's two edges along its long axis one is the object's and one is bounded by
 * the occluder. The object's edge is the one whose move swept through space the sensor saw
 * empty: where it advanced, the previous scan saw through the new part; where it retreated,
 * this scan sees through the part left. The occluder-bounded edge sweeps space that was or is
 * hidden, and a static object uncovered or hidden gives no such evidence at all. */
struct SweptEdges {
  /// The view's long horizontal axis (unit, world x-y).
  Eigen::Vector2d axis = Eigen::Vector2d::UnitX();
  /// Moves of the view's low and high edges along `axis` since the previous view [m].
  double low_shift = 0, high_shift = 0;
  /// Whether the free space confirms each edge's move.
  bool low_confirmed = false, high_confirmed = false;
  /// The displacement along `axis` [m]: the move of the only confirmed edge; valid only when
  /// `measured`.
  double shift = 0;
  /// True when the extent changed by at least the minimum and exactly one edge's move is
  /// confirmed.
  bool measured = false;
};

/** \brief Settings of sweptEdgeShift(); defaults for a scanning ladar at 10 Hz. */
struct SweptEdgesParameters {
  /// The view's extent along its long axis must change by this much [m], and a strip is judged
  /// only this far beyond the edge's other place: the free-space margin near the sensor
  /// (FreeSpaceParameters::margin), within which a swept strip is not seen through.
  double min_change = 0.3;
  /// Only views this many times longer than wide: the long axis of a compact view (a walker) is
  /// noise, and the extent along a vehicle's length is what grows and shrinks behind occluders.
  double min_elongation = 2.5;
  /// A strip's move is confirmed when at least this many of its points farther than min_change
  /// from the edge's other place are judged, and at least this fraction of those are seen
  /// through: most of it, as space an object left or entered is (a partial view's growth into
  /// space that was hidden is not).
  int min_points = 6;
  double min_fraction = 0.8;
};

/** \brief Compares `view` (world points of this frame) with `previous_view` (world points of the
 * same object in the previous frame) along the long axis of `view`, and
 * judges each edge's swept strip against `map`: the strip an edge advanced into against the scan
 * one frame back, the strip it retreated from against the latest scan. `map` must hold the
 * current scan as its latest. Both views should hold every point of their clusters: the
 * extremes of a subsample wander by tenths of a metre, as much as min_change. */
SweptEdges sweptEdgeShift(const std::vector<Eigen::Vector3f>& previous_view,
                          const std::vector<Eigen::Vector3f>& view, const FreeSpaceMap& map,
                          const SweptEdgesParameters& parameters = SweptEdgesParameters());

}  // namespace pcl_movers
