/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pcl_movers {

/** \brief The fragments of movers among an organized cloud's clusters: per cluster, the index of
 * the mover cluster it is a part of, or -1.
 *
 * Region growing splits an object where its range jumps (a car's wheels behind its body line,
 * its far side seen through the windows, a walker's legs), and a tracker follows one cluster per
 * object, so the other parts stay static clusters. A cluster that is not a mover is a fragment of
 * a mover when it touches the mover's cluster in the range image (a cell within `max_gap` + 1
 * rows and columns, as region growing looks) and every one of its points lies within the mover's
 * box grown by `margin` [m]: the box is the mover cluster's extent in x/y along `yaw[c]` [rad,
 * the cloud's frame]. A static object beside a mover reaches beyond its box (a wall, a parked
 * car); one small enough to fit is taken, at the cost of a few points. A fragment of two
 * movers goes to the later one in cluster order.
 *
 * A mover's cluster with fewer points than the mover `born_part_of` names is a fragment of it too,
 * by the same test: a second track born on a part of a large mover passing close by (a car's
 * front split off its side, moving with it but slower while its young registration slides),
 * which the tracker cannot tell from an object of its own. Only the birth tells them apart: a
 * walker beside a car moving its way is as close and moves as much with it, but its track was
 * born on its own. Owners are resolved to the end of such a chain (each step has more points, so
 * it ends, whatever `born_part_of` holds): a fragment's owner is never a fragment.
 *
 * \param organized the cloud the clusters index (row-major, width × height)
 * \param clusters its clusters
 * \param mover per cluster: whether it is a mover's
 * \param yaw per cluster: the heading of its box (only movers' are read)
 * \param max_gap empty cells region growing bridges (SegmentationParameters::max_gap)
 * \param margin how far [m] a fragment may reach beyond its mover's box
 * \param wrap_around whether the first and last columns are neighbours (a 360° sensor), as in
 * region growing (RangeImageRegionGrowing::setWrapAround)
 * \param born_part_of per cluster: the mover cluster whose fragment its track was born as, or -1
 * (only movers' are read); empty: a mover is never a fragment */
template <typename PointT>
std::vector<int> findMoverFragments(const pcl::PointCloud<PointT>& organized,
                                    const std::vector<pcl::PointIndices>& clusters,
                                    const std::vector<bool>& mover, const std::vector<double>& yaw,
                                    int max_gap, float margin, bool wrap_around = true,
                                    const std::vector<int>& born_part_of = {}) {
  std::vector<int> owner(clusters.size(), -1);
  const int width = static_cast<int>(organized.width), height = static_cast<int>(organized.height);
  if (height < 2 || width < 2 || std::none_of(mover.begin(), mover.end(), [](bool m) { return m; }))
    return owner;
  std::vector<int> cluster_of(organized.size(), -1);  // per cell: its cluster, -1 for none
  for (std::size_t c = 0; c < clusters.size(); ++c)
    for (const auto i : clusters[c].indices)
      cluster_of[static_cast<std::size_t>(i)] = static_cast<int>(c);
  const int reach = max_gap + 1;
  std::vector<int> touching;
  for (std::size_t m = 0; m < clusters.size(); ++m) {
    if (!mover[m]) continue;
    const auto mayBePart = [&](int f) {
      if (!mover[f]) return true;
      // The part holds less of the object than its owner: once it holds more, its own track is
      // the better estimate (the owner has shrunk to a remnant).
      return !born_part_of.empty() &&
             born_part_of[static_cast<std::size_t>(f)] == static_cast<int>(m) &&
             clusters[f].indices.size() < clusters[m].indices.size();
    };
    touching.clear();
    for (const auto i : clusters[m].indices) {
      const int row = i / width, col = i % width;
      for (int r = std::max(0, row - reach); r <= std::min(height - 1, row + reach); ++r)
        for (int dc = -reach; dc <= reach; ++dc) {
          int c = col + dc;
          if (c < 0 || c >= width) {
            if (!wrap_around || reach >= width) continue;
            c += c < 0 ? width : -width;
          }
          const int f = cluster_of[static_cast<std::size_t>(r) * width + c];
          if (f >= 0 && mayBePart(f) &&
              std::find(touching.begin(), touching.end(), f) == touching.end())
            touching.push_back(f);
        }
    }
    if (touching.empty()) continue;
    // The mover's box along its own heading.
    const Eigen::Vector2f u(static_cast<float>(std::cos(yaw[m])),
                            static_cast<float>(std::sin(yaw[m])));
    const Eigen::Vector2f v(-u.y(), u.x());
    const auto along = [&](int i) {
      const Eigen::Vector2f q(organized[i].x, organized[i].y);
      return Eigen::Vector2f(q.dot(u), q.dot(v));
    };
    Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector2f hi = -lo;
    for (const auto i : clusters[m].indices) {
      lo = lo.cwiseMin(along(i));
      hi = hi.cwiseMax(along(i));
    }
    lo.array() -= margin;
    hi.array() += margin;
    for (const int f : touching) {
      const auto& idx = clusters[f].indices;
      if (std::all_of(idx.begin(), idx.end(), [&](int i) {
            const Eigen::Vector2f a = along(i);
            return (a.array() >= lo.array()).all() && (a.array() <= hi.array()).all();
          }))
        owner[f] = static_cast<int>(m);
    }
  }
  for (auto& o : owner)  // each step has more points, so it ends
    while (o >= 0 && owner[static_cast<std::size_t>(o)] >= 0)
      o = owner[static_cast<std::size_t>(o)];
  return owner;
}

}  // namespace pcl_movers
