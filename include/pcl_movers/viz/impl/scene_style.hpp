/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/viz/scene_style.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace pcl_movers {
namespace viz {

template <typename PointT>
std::vector<bool> estimateGroundMask(const pcl::PointCloud<PointT>& cloud, double cell_size,
                                     double tolerance) {
  std::vector<bool> mask(cloud.size(), false);
  if (cloud.empty() || !(cell_size > 0)) return mask;
  // Cell key packs two 32-bit cell indices; a hash map keeps memory proportional to the occupied
  // cells, whatever the extent of the scan.
  auto key = [](long long ix, long long iy) {
    return (static_cast<unsigned long long>(ix) << 32) ^
           (static_cast<unsigned long long>(iy) & 0xFFFFFFFFull);
  };
  auto cellOf = [&](const PointT& p, long long& ix, long long& iy) {
    ix = static_cast<long long>(std::floor(p.x / cell_size));
    iy = static_cast<long long>(std::floor(p.y / cell_size));
  };
  std::unordered_map<unsigned long long, float> lowest;
  lowest.reserve(cloud.size() / 8 + 16);
  for (const auto& p : cloud.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    long long ix, iy;
    cellOf(p, ix, iy);
    auto it = lowest.find(key(ix, iy));
    if (it == lowest.end())
      lowest.emplace(key(ix, iy), p.z);
    else
      it->second = std::min(it->second, p.z);
  }
  // The 3x3 neighbourhood minimum: a car roof whose own cell holds no road points still sees the
  // road in a neighbouring cell.
  std::unordered_map<unsigned long long, float> floor_of;
  floor_of.reserve(lowest.size());
  for (const auto& p : cloud.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    long long ix, iy;
    cellOf(p, ix, iy);
    const auto k = key(ix, iy);
    if (floor_of.count(k)) continue;
    float m = std::numeric_limits<float>::max();
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy) {
        auto it = lowest.find(key(ix + dx, iy + dy));
        if (it != lowest.end()) m = std::min(m, it->second);
      }
    floor_of.emplace(k, m);
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    long long ix, iy;
    cellOf(p, ix, iy);
    mask[i] = p.z <= floor_of[key(ix, iy)] + tolerance;
  }
  return mask;
}

template <typename PointT>
PointLabels labelPointsFromTracks(const pcl::PointCloud<PointT>& cloud,
                                  const std::vector<bool>& ground_mask,
                                  const std::vector<io::TrackRow>& frame_rows, double margin,
                                  double fallback_radius) {
  PointLabels labels;
  labels.classes.assign(cloud.size(), PointClass::Unassigned);
  labels.track_ids.assign(cloud.size(), -1);
  std::vector<OrientedBox> boxes;
  boxes.reserve(frame_rows.size());
  for (const auto& row : frame_rows) boxes.push_back(OrientedBox::fromTrack(row));
  // A horizontal bounding radius per box lets most points skip the exact test cheaply.
  std::vector<double> reach(boxes.size());
  for (std::size_t t = 0; t < boxes.size(); ++t) {
    const auto& b = boxes[t];
    reach[t] = (b.length > 0 && b.width > 0) ? 0.5 * std::hypot(b.length, b.width) + margin
                                             : fallback_radius;
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& pt = cloud[i];
    if (!std::isfinite(pt.x) || !std::isfinite(pt.y) || !std::isfinite(pt.z)) continue;
    if (i < ground_mask.size() && ground_mask[i]) {
      labels.classes[i] = PointClass::Ground;
      continue;
    }
    const Eigen::Vector3d p(pt.x, pt.y, pt.z);
    double best = std::numeric_limits<double>::max();
    int best_t = -1;
    for (std::size_t t = 0; t < boxes.size(); ++t) {
      const auto& b = boxes[t];
      const double d = std::hypot(p.x() - b.center.x(), p.y() - b.center.y());
      if (d > reach[t]) continue;
      const bool has_box = b.length > 0 && b.width > 0 && b.height > 0;
      if (has_box ? b.contains(p, margin) : (p - b.center).norm() <= fallback_radius) {
        if (d < best) {
          best = d;
          best_t = static_cast<int>(t);
        }
      }
    }
    if (best_t >= 0) {
      const auto& row = frame_rows[static_cast<std::size_t>(best_t)];
      labels.classes[i] = row.mover ? PointClass::Mover : PointClass::Static;
      labels.track_ids[i] = row.track_id;
    }
  }
  return labels;
}

template <typename PointT>
std::vector<OrientedBox> fitTrackBoxes(const pcl::PointCloud<PointT>& cloud,
                                       const PointLabels& labels,
                                       const std::vector<io::TrackRow>& frame_rows) {
  std::vector<OrientedBox> boxes;
  boxes.reserve(frame_rows.size());
  std::unordered_map<int, std::size_t> slot;
  for (const auto& row : frame_rows) {
    slot[row.track_id] = boxes.size();
    boxes.push_back(OrientedBox::fromTrack(row));
  }
  const std::size_t n = boxes.size();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> lo(n, Eigen::Vector3d::Constant(inf));
  std::vector<Eigen::Vector3d> hi(n, Eigen::Vector3d::Constant(-inf));
  std::vector<int> count(n, 0);
  for (std::size_t i = 0; i < cloud.size() && i < labels.track_ids.size(); ++i) {
    const int id = labels.track_ids[i];
    if (id < 0) continue;
    auto it = slot.find(id);
    if (it == slot.end()) continue;
    const auto& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const auto& b = boxes[it->second];
    const double c = std::cos(b.yaw), s = std::sin(b.yaw);
    const Eigen::Vector3d local(c * p.x + s * p.y, -s * p.x + c * p.y, p.z);  // box axes
    lo[it->second] = lo[it->second].cwiseMin(local);
    hi[it->second] = hi[it->second].cwiseMax(local);
    ++count[it->second];
  }
  for (std::size_t t = 0; t < n; ++t) {
    if (count[t] < 3) continue;
    auto& b = boxes[t];
    const Eigen::Vector3d mid = 0.5 * (lo[t] + hi[t]);
    const Eigen::Vector3d extent = hi[t] - lo[t];
    const double c = std::cos(b.yaw), s = std::sin(b.yaw);
    b.center = Eigen::Vector3d(c * mid.x() - s * mid.y(), s * mid.x() + c * mid.y(), mid.z());
    b.length = std::max(b.length, extent.x());
    b.width = std::max(b.width, extent.y());
    b.height = std::max(b.height, extent.z());
  }
  return boxes;
}

template <typename PointT>
std::vector<Color> colorPoints(const pcl::PointCloud<PointT>& cloud, const PointLabels& labels,
                               const std::vector<int>& movers, const SceneStyle& style) {
  std::vector<Color> colors(cloud.size(), style.ground);
  auto mix = [](const Color& a, const Color& b, double t) {
    t = std::clamp(t, 0.0, 1.0);
    return Color{static_cast<std::uint8_t>(std::lround(a.r + (b.r - a.r) * t)),
                 static_cast<std::uint8_t>(std::lround(a.g + (b.g - a.g) * t)),
                 static_cast<std::uint8_t>(std::lround(a.b + (b.b - a.b) * t))};
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointClass c = i < labels.classes.size() ? labels.classes[i] : PointClass::Unassigned;
    const int id = i < labels.track_ids.size() ? labels.track_ids[i] : -1;
    const bool is_mover = c == PointClass::Mover ||
                          (id >= 0 && std::find(movers.begin(), movers.end(), id) != movers.end());
    if (c == PointClass::Ground)
      colors[i] = style.ground;
    else if (is_mover)
      colors[i] = style.mover_points;
    else if (id >= 0)
      colors[i] = trackColor(id);
    else  // height shading from 2 m below to 2 m above the sensor
      colors[i] = mix(style.unassigned_low, style.unassigned_high, (cloud[i].z + 2.0) / 4.0);
  }
  return colors;
}

}  // namespace viz
}  // namespace pcl_movers
