/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/free_space_map.h>

#include <algorithm>
#include <stdexcept>

namespace pcl_movers {

void FreeSpaceMap::setResolution(double azimuth_deg, double elevation_deg) {
  if (!(azimuth_deg > 0.01 && azimuth_deg <= 10 && elevation_deg > 0.01 && elevation_deg <= 10))
    throw std::invalid_argument(
        "FreeSpaceMap::setResolution: cell sizes must be in (0.01, 10] deg");
  az_res_deg_ = static_cast<float>(azimuth_deg);
  el_res_deg_ = static_cast<float>(elevation_deg);
  cols_ = static_cast<int>(std::ceil(360.0f / az_res_deg_));
  rows_ = static_cast<int>(std::ceil((max_el_deg_ - min_el_deg_) / el_res_deg_));
  scans_.clear();  // stored images have the old layout
}

FreeSpaceMap::Evidence FreeSpaceMap::test(const std::vector<Eigen::Vector3f>& world_points,
                                          int frames_ago) const {
  Evidence e;
  if (frames_ago < 0 || frames_ago >= static_cast<int>(scans_.size())) return e;
  const Scan& s = scans_[static_cast<std::size_t>(frames_ago)];
  for (const auto& w : world_points) {
    const Eigen::Vector3f q = s.world_to_sensor * w;
    const float rxy = std::sqrt(q.x() * q.x() + q.y() * q.y());
    const float d = std::sqrt(rxy * rxy + q.z() * q.z());
    if (!(d > 0.5f)) continue;
    const int row = cellRow(detail::fastAtan2Deg(q.z(), rxy));
    const int col = cellCol(detail::fastAtan2Deg(q.y(), q.x()));
    // Nearest return over the window: a ray that passed just beside an edge never counts.
    float nearest = 0.0f;
    for (int dr = -win_rows_; dr <= win_rows_; ++dr) {
      const int r = row + dr;
      if (r < 0 || r >= rows_) continue;
      for (int dc = -win_cols_; dc <= win_cols_; ++dc) {
        int c = col + dc;
        c = c >= cols_ ? c - cols_ : (c < 0 ? c + cols_ : c);
        const float v = s.range[static_cast<std::size_t>(r) * cols_ + c];
        if (v > 0.0f && (nearest == 0.0f || v < nearest)) nearest = v;
      }
    }
    if (nearest == 0.0f) continue;  // nothing returned around there: unknown
    ++e.tested;
    const float margin = static_cast<float>(std::max(margin_, margin_per_metre_ * d));
    if (nearest > d + margin) ++e.seen_through;
  }
  return e;
}

}  // namespace pcl_movers
