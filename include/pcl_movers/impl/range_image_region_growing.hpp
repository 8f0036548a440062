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
  if (!initCompute()) {
    clusters.clear();
    return;
  }
  if (input_->empty()) {
    clusters.clear();
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
    clusters.clear();
    deinitCompute();
    return;
  }
  if (!(depth_threshold_factor_ >= 0.f) || !(min_depth_threshold_ >= 0.f) || max_gap_ < 0) {
    PCL_ERROR(
        "[pcl_movers::RangeImageRegionGrowing::segment] Depth threshold factor, floor and max gap "
        "must be >= 0.\n");
    clusters.clear();
    deinitCompute();
    return;
  }

  const int width = static_cast<int>(input_->width);
  const int height = static_cast<int>(input_->height);
  const int n = width * height;
  const Eigen::Vector3f origin = input_->sensor_origin_.template head<3>();

  const float k = depth_threshold_factor_;
  const float floor = min_depth_threshold_;
  // range_ < 0 marks cells that do not take part (NaN, or not in indices_). threshold_ holds
  // max(k * range, floor) of every valid cell, computed once: the depth rule of two cells,
  // |r_a - r_b| <= max(k * min(r_a, r_b), floor), is then min(threshold_a, threshold_b) as
  // k * r is increasing in r, with no multiplication per neighbour test.
  range_.assign(n, -1.f);
  threshold_.resize(n);
  auto setRange = [&](int i) {
    const PointT& p = (*input_)[i];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) {
      const float r = (p.getVector3fMap() - origin).norm();
      range_[i] = r;
      threshold_[i] = std::max(k * r, floor);
    }
  };
  if (fake_indices_)
    for (int i = 0; i < n; ++i) setRange(i);
  else
    for (const auto i : *indices_)
      if (i >= 0 && i < n) setRange(i);

  parent_.resize(n);
  for (int i = 0; i < n; ++i) parent_[i] = i;

  const bool wrap = wrap_around_ && width > 1;
  // Forward half of the 8-neighbourhood: right, down-left, down, down-right.
  constexpr int kDirections[4][2] = {{0, 1}, {1, -1}, {1, 0}, {1, 1}};
  const int max_steps = 1 + max_gap_;

  // The root of a set is its smallest cell (the smaller root wins every union), so roots come
  // first in row-major order. `root_i` caches the root of the cell being processed: only its own
  // joins change its set while it is processed, so one findRoot per cell instead of one per join.
  int root_i = 0;
  auto join = [this, &root_i](int j) {
    const int root_j = findRoot(j);
    if (root_j < root_i) {
      parent_[root_i] = root_j;
      root_i = root_j;
    } else if (root_i < root_j) {
      parent_[root_j] = root_i;
    }
  };
  auto depthMatch = [this](int a, int b) {
    return std::abs(range_[a] - range_[b]) <= std::min(threshold_[a], threshold_[b]);
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
      root_i = findRoot(i);
      if (bridge > 0.f) {
        // Along the row, look past empty cells and past nearer cells (a pole or a sign in front
        // of a car) for the first cell at about this cell's depth, up to `bridge` metres away.
        const float nearest = ra - threshold_[i];
        // The usual case first: the next cell is valid and not nearer, so the search ends there
        // (a first step is within max_steps: no 3D check, and no reach to compute).
        const float next = col + 1 < width ? range_[i + 1] : -1.f;
        if (!(next < 0.f || next < nearest)) {
          if (depthMatch(i, i + 1)) join(i + 1);
        } else {
          // Compared in float first: near the sensor (ra -> 0) the quotient overflows an int.
          const float columns = bridge / (ra * column_angle);
          const int reach =
              columns >= static_cast<float>(kMaxBridgeColumns)
                  ? kMaxBridgeColumns
                  : std::max(max_steps, std::min(kMaxBridgeColumns, static_cast<int>(columns) + 1));
          // From step 2 when the first cell was looked at above.
          for (int step = col + 1 < width ? 2 : 1; step <= reach; ++step) {
            int c = col + step;
            if (c >= width) {
              if (!wrap) break;
              c -= width;
            }
            const int j = row * width + c;
            if (j == i) break;
            const float rb = range_[j];
            if (rb < 0.f || rb < nearest) continue;  // empty or in front: look further
            if (depthMatch(i, j) &&
                (step <= max_steps ||
                 ((*input_)[i].getVector3fMap() - (*input_)[j].getVector3fMap()).squaredNorm() <=
                     bridge * bridge))
              join(j);
            break;
          }
        }
      }
      // Away from the first and last columns no scan leaves the image sideways: the cells of a
      // direction are then i + step * stride, inside the image while below n.
      if (col >= max_steps && col + max_steps < width) {
        if (!(bridge > 0.f)) {
          for (int j = i + 1; j <= i + max_steps; ++j) {
            if (range_[j] < 0.f) continue;
            if (depthMatch(i, j)) join(j);
            break;
          }
        }
        for (int dc = -1; dc <= 1; ++dc) {
          const int stride = width + dc;
          for (int step = 1, j = i + stride; step <= max_steps && j < n; ++step, j += stride) {
            if (range_[j] < 0.f) continue;  // empty: look one cell further (gap bridging)
            if (depthMatch(i, j)) join(j);
            break;  // only the first valid cell in each direction is a neighbour
          }
        }
        continue;
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
          if (j == i) break;              // a full turn on a tiny image
          if (range_[j] < 0.f) continue;  // empty: look one cell further (gap bridging)
          if (depthMatch(i, j)) join(j);
          break;  // only the first valid cell in each direction is a neighbour
        }
      }
    }
  }

  // Collect. Every parent is a smaller cell of the same set (roots are their set's smallest
  // cell, path halving only shortens links), so in row-major order a cell's parent is numbered
  // before the cell: one pass numbers the sets with no root search. The sizes then give the
  // output order and every cluster's exact size, so the output is filled in one pass with no
  // reallocation and no sort of the index vectors themselves.
  std::vector<int>& set_of = set_of_;
  set_of.resize(n);
  set_sizes_.clear();
  for (int i = 0; i < n; ++i) {
    if (range_[i] < 0.f) continue;
    const int p = parent_[i];
    if (p == i) {
      set_of[i] = static_cast<int>(set_sizes_.size());
      set_sizes_.push_back(1);
    } else {
      set_of[i] = set_of[p];
      ++set_sizes_[set_of[i]];
    }
  }
  // Kept sets, largest first; ties in order of their first cell (as a stable sort by size).
  set_order_.clear();
  for (std::size_t c = 0; c < set_sizes_.size(); ++c)
    if (set_sizes_[c] >= min_cluster_size_ && set_sizes_[c] <= max_cluster_size_)
      set_order_.push_back(static_cast<int>(c));
  std::stable_sort(set_order_.begin(), set_order_.end(),
                   [this](int a, int b) { return set_sizes_[a] > set_sizes_[b]; });
  std::vector<int>& output_of = set_output_;
  output_of.assign(set_sizes_.size(), -1);
  // The caller's vector is reused: its index vectors keep their capacity between frames.
  clusters.resize(set_order_.size());
  // Each cluster gets its exact size up front and is filled through a write cursor.
  cursor_.resize(set_order_.size());
  for (std::size_t o = 0; o < set_order_.size(); ++o) {
    output_of[set_order_[o]] = static_cast<int>(o);
    clusters[o].header = input_->header;
    clusters[o].indices.resize(set_sizes_[set_order_[o]]);
    cursor_[o] = clusters[o].indices.data();
  }
  for (int i = 0; i < n; ++i) {
    if (range_[i] < 0.f) continue;
    const int out = output_of[set_of[i]];
    if (out >= 0) *cursor_[out]++ = i;
  }
  deinitCompute();
}

template <typename PointT>
void RangeImageRegionGrowing<PointT>::cellLabels(const PointCloud& organized,
                                                 const pcl::Indices& objects,
                                                 const std::vector<pcl::PointIndices>& clusters,
                                                 CellLabels& labels) {
  // Ground cells are "valid" (they end a run) but never occluders.
  std::vector<int>& label = labels.label;
  const std::size_t n = organized.size();
  label.assign(n, kEmptyCell);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& q = organized[i];
    if (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z)) label[i] = kGroundCell;
  }
  for (const auto i : objects)
    if (i >= 0 && static_cast<std::size_t>(i) < n && label[i] == kGroundCell)
      label[i] = kObjectCell;
  for (std::size_t c = 0; c < clusters.size(); ++c)
    for (const auto i : clusters[c].indices)
      if (i >= 0 && static_cast<std::size_t>(i) < n && label[i] != kEmptyCell)
        label[i] = static_cast<int>(c);
}

template <typename PointT>
void RangeImageRegionGrowing<PointT>::occludedSides(const PointCloud& organized,
                                                    const pcl::Indices& objects,
                                                    const std::vector<pcl::PointIndices>& clusters,
                                                    float k, float d_min, int max_gap,
                                                    bool wrap_around, float min_fraction,
                                                    std::vector<std::uint8_t>& sides) {
  CellLabels labels;
  cellLabels(organized, objects, clusters, labels);
  occludedSides(organized, labels, clusters, k, d_min, max_gap, wrap_around, min_fraction, sides);
}

template <typename PointT>
void RangeImageRegionGrowing<PointT>::occludedSides(const PointCloud& organized,
                                                    const CellLabels& labels,
                                                    const std::vector<pcl::PointIndices>& clusters,
                                                    float k, float d_min, int max_gap,
                                                    bool wrap_around, float min_fraction,
                                                    std::vector<std::uint8_t>& sides) {
  sides.assign(clusters.size(), 0);
  const int width = static_cast<int>(organized.width);
  const std::size_t n = organized.size();
  if (organized.height < 1 || width < 2 ||
      static_cast<std::size_t>(width) * organized.height != n || labels.label.size() != n)
    return;
  const std::vector<int>& label = labels.label;
  const auto range = [&organized](std::size_t i) { return organized[i].getVector3fMap().norm(); };
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    int boundary[2] = {0, 0}, occluded[2] = {0, 0};
    for (const auto i : clusters[c].indices) {
      if (i < 0 || static_cast<std::size_t>(i) >= n) continue;
      const int row = i / width, col = i % width;
      const float r = range(static_cast<std::size_t>(i));
      for (int side = 0; side < 2; ++side) {
        const int step = side == 0 ? -1 : 1;
        int j = -1;
        bool fov_edge = false;
        for (int s = 1; s <= max_gap + 1; ++s) {
          int cc = col + step * s;
          if (cc < 0 || cc >= width) {
            fov_edge = !wrap_around;
            if (fov_edge) break;
            cc = (cc + width) % width;
          }
          const int idx = row * width + cc;
          if (label[idx] != kEmptyCell) {
            j = idx;
            break;
          }
        }
        if (j >= 0 && label[j] == static_cast<int>(c)) continue;  // inside the cluster
        ++boundary[side];
        // The edge of a field of view narrower than a full turn hides what lies beyond it as a
        // nearer object would: an object entering the view grows from that side (a truck
        // overtaking a forward-looking ladar: its registered speed was 28 m/s of its 31).
        if (fov_edge) {
          ++occluded[side];
          continue;
        }
        // Empty beyond the gap, or ground: no nearer surface ends the cluster here.
        if (j < 0 || label[j] == kGroundCell) continue;
        const float rj = range(static_cast<std::size_t>(j));
        if (rj < r - std::max(k * rj, d_min)) ++occluded[side];
      }
    }
    for (int side = 0; side < 2; ++side)
      if (occluded[side] > 0 &&
          static_cast<float>(occluded[side]) >= min_fraction * static_cast<float>(boundary[side]))
        sides[c] |= side == 0 ? kOccludedLeft : kOccludedRight;
  }
}

template <typename PointT>
void RangeImageRegionGrowing<PointT>::occluderFloors(const PointCloud& organized,
                                                     const pcl::Indices& objects,
                                                     const std::vector<pcl::PointIndices>& clusters,
                                                     float k, float d_min, int max_gap,
                                                     float min_fraction, std::vector<int>& floors) {
  CellLabels labels;
  cellLabels(organized, objects, clusters, labels);
  occluderFloors(organized, labels, clusters, k, d_min, max_gap, min_fraction, floors);
}

template <typename PointT>
void RangeImageRegionGrowing<PointT>::occluderFloors(const PointCloud& organized,
                                                     const CellLabels& labels,
                                                     const std::vector<pcl::PointIndices>& clusters,
                                                     float k, float d_min, int max_gap,
                                                     float min_fraction, std::vector<int>& floors) {
  floors.assign(clusters.size(), -1);
  const int width = static_cast<int>(organized.width), height = static_cast<int>(organized.height);
  const std::size_t n = organized.size();
  if (height < 2 || width < 1 || static_cast<std::size_t>(width) * height != n ||
      labels.label.size() != n)
    return;
  const std::vector<int>& label = labels.label;
  // Lowest point of every cluster.
  std::vector<int> lowest(clusters.size(), -1);
  for (std::size_t c = 0; c < clusters.size(); ++c)
    for (const auto i : clusters[c].indices) {
      if (i < 0 || static_cast<std::size_t>(i) >= n || label[i] != static_cast<int>(c)) continue;
      if (lowest[c] < 0 || organized[i].z < organized[lowest[c]].z) lowest[c] = i;
    }
  const auto range = [&organized](std::size_t i) { return organized[i].getVector3fMap().norm(); };
  // Per column: the cluster's lowest cell there (rows run top to bottom), -1 = none; the columns
  // a cluster touched are reset after it.
  std::vector<int> bottom_of(static_cast<std::size_t>(width), -1);
  std::vector<int> bottom;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    bottom.clear();
    for (const auto i : clusters[c].indices) {
      if (i < 0 || static_cast<std::size_t>(i) >= n || label[i] != static_cast<int>(c)) continue;
      int& b = bottom_of[static_cast<std::size_t>(i % width)];
      if (b < 0) bottom.push_back(i % width);
      if (b < 0 || i > b) b = i;  // same column: a larger index is a lower row
    }
    for (int& col : bottom) {
      const int cell = bottom_of[static_cast<std::size_t>(col)];
      bottom_of[static_cast<std::size_t>(col)] = -1;
      col = cell;
    }
    int hidden = 0, floor = -1;
    for (const int b : bottom) {
      const int row = b / width, col = b % width;
      int j = -1;
      for (int s = 1; s <= max_gap + 1 && row + s < height; ++s) {
        const int idx = (row + s) * width + col;
        if (label[idx] != kEmptyCell) {
          j = idx;
          break;
        }
      }
      if (j < 0 || label[j] == kGroundCell || label[j] == static_cast<int>(c)) continue;
      const float r = range(static_cast<std::size_t>(b)), rj = range(static_cast<std::size_t>(j));
      if (!(rj < r - std::max(k * rj, d_min))) continue;
      ++hidden;
      const int low = label[j] >= 0 ? lowest[static_cast<std::size_t>(label[j])] : j;
      if (floor < 0 || organized[low].z < organized[floor].z) floor = low;
    }
    if (hidden > 0 &&
        static_cast<float>(hidden) >= min_fraction * static_cast<float>(bottom.size()))
      floors[c] = floor;
  }
}

}  // namespace pcl_movers

#define PCL_MOVERS_INSTANTIATE_RangeImageRegionGrowing(T) \
  template class pcl_movers::RangeImageRegionGrowing<T>;
