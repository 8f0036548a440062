/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/range_image_region_growing.h>

#include <pcl/console/print.h>

#include <algorithm>
#include <cmath>

namespace pcl_movers {

template <typename PointT>
int RangeImageRegionGrowing<PointT>::findRoot(int i) {
  while (parent_[i] != i) {
    parent_[i] = parent_[parent_[i]];
    i = parent_[i];
  }
  return i;
}

template <typename PointT>
void RangeImageRegionGrowing<PointT>::segment(std::vector<pcl::PointIndices>& clusters) {
  clusters.clear();
  if (!initCompute()) return;
  if (input_->empty()) {
    deinitCompute();
    return;
  }
  if (!input_->isOrganized() ||
      static_cast<std::size_t>(input_->width) * input_->height != input_->size()) {
    PCL_ERROR(
        "[pcl_movers::RangeImageRegionGrowing::segment] The input cloud is not organized "
        "(width %u, height %u, %zu points): region growing needs the range image (rows = beams); "
        "organize the scan first (pcl_movers::RangeImageOrganizer).\n",
        input_->width, input_->height, input_->size());
    deinitCompute();
    return;
  }
  if (!(depth_threshold_factor_ >= 0.f) || !(min_depth_threshold_ >= 0.f) || max_gap_ < 0) {
    PCL_ERROR(
        "[pcl_movers::RangeImageRegionGrowing::segment] Depth threshold factor, floor and max gap "
        "must be >= 0.\n");
    deinitCompute();
    return;
  }

  const int width = static_cast<int>(input_->width);
  const int height = static_cast<int>(input_->height);
  const int n = width * height;
  const Eigen::Vector3f origin = input_->sensor_origin_.template head<3>();

  // range_ < 0 marks cells that do not take part (NaN, or not in indices_).
  range_.assign(n, -1.f);
  auto setRange = [&](int i) {
    const PointT& p = (*input_)[i];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
      range_[i] = (p.getVector3fMap() - origin).norm();
  };
  if (fake_indices_)
    for (int i = 0; i < n; ++i) setRange(i);
  else
    for (const auto i : *indices_)
      if (i >= 0 && i < n) setRange(i);

  parent_.resize(n);
  for (int i = 0; i < n; ++i) parent_[i] = i;

  const float k = depth_threshold_factor_;
  const float floor = min_depth_threshold_;
  const bool wrap = wrap_around_ && width > 1;
  // Forward half of the 8-neighbourhood: right, down-left, down, down-right.
  constexpr int kDirections[4][2] = {{0, 1}, {1, -1}, {1, 0}, {1, 1}};
  const int max_steps = 1 + max_gap_;

  auto join = [this](int a, int b) {
    const int root_a = findRoot(a), root_b = findRoot(b);
    // The smaller index becomes the root, so roots are the first cell of their cluster.
    if (root_a < root_b)
      parent_[root_b] = root_a;
    else if (root_b < root_a)
      parent_[root_a] = root_b;
  };
  // Bridging along the row (see setBridgeLength()): the columns are assumed to span 360°, as in
  // RangeImageOrganizer's images, so one column is 2π / width rad of azimuth.
  const float bridge = bridge_length_;
  const float column_angle = 2.f * static_cast<float>(M_PI) / static_cast<float>(width);
  constexpr int kMaxBridgeColumns = 64;

  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const int i = row * width + col;
      const float ra = range_[i];
      if (ra < 0.f) continue;
      if (bridge > 0.f) {
        // Along the row, look past empty cells and past nearer cells (a pole or a sign in front
        // of a car) for the first cell at about this cell's depth, up to `bridge` metres away.
        // Compared in float first: near the sensor (ra -> 0) the quotient overflows an int.
        const float columns = bridge / (ra * column_angle);
        const int reach =
            columns >= static_cast<float>(kMaxBridgeColumns)
                ? kMaxBridgeColumns
                : std::max(max_steps, std::min(kMaxBridgeColumns, static_cast<int>(columns) + 1));
        const float threshold_a = std::max(k * ra, floor);
        for (int step = 1; step <= reach; ++step) {
          int c = col + step;
          if (c >= width) {
            if (!wrap) break;
            c -= width;
          }
          const int j = row * width + c;
          if (j == i) break;
          const float rb = range_[j];
          if (rb < 0.f || rb < ra - threshold_a) continue;  // empty or in front: look further
          if (std::abs(ra - rb) <= std::max(k * std::min(ra, rb), floor) &&
              (step <= max_steps ||
               ((*input_)[i].getVector3fMap() - (*input_)[j].getVector3fMap()).squaredNorm() <=
                   bridge * bridge))
            join(i, j);
          break;
        }
      }
      for (const auto& dir : kDirections) {
        if (bridge > 0.f && dir[0] == 0) continue;  // the row was handled above
        for (int step = 1; step <= max_steps; ++step) {
          const int r = row + dir[0] * step;
          if (r >= height) break;
          int c = col + dir[1] * step;
          if (c < 0 || c >= width) {
            if (!wrap) break;
            c = (c + width) % width;
          }
          const int j = r * width + c;
          if (j == i) break;  // a full turn on a tiny image
          const float rb = range_[j];
          if (rb < 0.f) continue;  // empty: look one cell further (gap bridging)
          if (std::abs(ra - rb) <= std::max(k * std::min(ra, rb), floor)) join(i, j);
          break;  // only the first valid cell in each direction is a neighbour
        }
      }
    }
  }

  // Collect: roots come first in row-major order, so one pass numbers the clusters.
  std::vector<int> cluster_of(n, -1);
  std::vector<int> sizes;
  for (int i = 0; i < n; ++i) {
    if (range_[i] < 0.f) continue;
    const int root = findRoot(i);
    if (cluster_of[root] < 0) {
      cluster_of[root] = static_cast<int>(sizes.size());
      sizes.push_back(0);
    }
    cluster_of[i] = cluster_of[root];
    ++sizes[cluster_of[i]];
  }
  std::vector<int> output_of(sizes.size(), -1);
  for (std::size_t c = 0; c < sizes.size(); ++c) {
    if (sizes[c] < min_cluster_size_ || sizes[c] > max_cluster_size_) continue;
    output_of[c] = static_cast<int>(clusters.size());
    clusters.emplace_back();
    clusters.back().header = input_->header;
    clusters.back().indices.reserve(sizes[c]);
  }
  for (int i = 0; i < n; ++i) {
    if (cluster_of[i] < 0) continue;
    const int out = output_of[cluster_of[i]];
    if (out >= 0) clusters[out].indices.push_back(i);
  }
  std::stable_sort(clusters.begin(), clusters.end(),
                   [](const pcl::PointIndices& a, const pcl::PointIndices& b) {
                     return a.indices.size() > b.indices.size();
                   });
  deinitCompute();
}

}  // namespace pcl_movers

#define PCL_MOVERS_INSTANTIATE_RangeImageRegionGrowing(T) \
  template class pcl_movers::RangeImageRegionGrowing<T>;
