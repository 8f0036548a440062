/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/point_labels.h>

#include <algorithm>
#include <map>

namespace pcl_movers {
namespace io {

std::uint16_t moverClassFromBox(double length, double width, double height) {
  const double longer = std::max(length, width), shorter = std::min(length, width);
  if (longer > 7.0) return 258;                                      // moving-truck
  if (longer > 2.5) return semantic::kMovingCar;                     // 252
  if (height > 1.0 && longer < 1.2) return semantic::kMovingPerson;  // 254
  if (height > 1.0 && shorter < 1.2) return 253;                     // moving-bicyclist
  return 251;                                                        // moving, class unknown
}

std::vector<std::uint32_t> movingPointLabels(const std::vector<bool>& has_return,
                                             const std::vector<int>& mover_track,
                                             const std::vector<TrackRow>& rows) {
  if (has_return.size() != mover_track.size())
    throw InputError("movingPointLabels: " + std::to_string(has_return.size()) + " points but " +
                     std::to_string(mover_track.size()) + " track ids");
  std::map<int, std::uint16_t> class_of;
  for (const TrackRow& r : rows)
    if (r.mover) class_of[r.track_id] = moverClassFromBox(r.length, r.width, r.height);
  std::vector<std::uint32_t> labels(has_return.size(), makeLabel(kNoReturnClass, 0));
  for (std::size_t j = 0; j < labels.size(); ++j) {
    if (!has_return[j]) continue;
    const int track = mover_track[j];
    if (track < 0) {
      labels[j] = makeLabel(kStaticClass, 0);
      continue;
    }
    const auto it = class_of.find(track);
    labels[j] = makeLabel(it == class_of.end() ? 251 : it->second,
                          static_cast<std::uint16_t>(track & 0xFFFF));
  }
  return labels;
}

}  // namespace io
}  // namespace pcl_movers
