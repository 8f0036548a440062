/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/motion_split.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace pcl_movers {

using Sight = FreeSpaceMap::Sight;

int MotionSplitter::split(int width, int height, const std::vector<float>& ranges,
                          const std::vector<pcl::PointIndices>& clusters,
                          const std::vector<std::vector<Sight>>& sights,
                          std::vector<pcl::PointIndices>& out) {
  const int min_points = std::max(1, parameters_.min_points);
  out.clear();
  out.reserve(clusters.size());
  std::vector<pcl::PointIndices> parts;
  if (member_.size() != static_cast<std::size_t>(width) * height)
    member_.assign(static_cast<std::size_t>(width) * height, -1);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const auto& idx = clusters[c].indices;
    const auto& sight = sights[c];
    const auto through = std::count(sight.begin(), sight.end(), Sight::kThrough);
    const auto at = std::count(sight.begin(), sight.end(), Sight::kAt);
    // Only a cluster that holds both a moving part and a static surface is split: one seen
    // through everywhere it was seen is a mover on its own (or two joined, which the tracker's
    // split of merged clusters handles), one seen where it is everywhere is static.
    if (through < min_points || at < min_points) {
      out.push_back(clusters[c]);
      continue;
    }
    const std::size_t first_part = parts.size();
    growParts(width, height, ranges, clusters[c], sight, parts);
    pcl::PointIndices rest;
    rest.header = clusters[c].header;
    for (std::size_t k = 0; k < idx.size(); ++k)
      if (part_of_[k] == 0) rest.indices.push_back(idx[k]);
    // The rest of a cluster all of whose points went into parts is not kept as a sliver.
    if (static_cast<int>(rest.indices.size()) >= min_points || parts.size() == first_part)
      out.push_back(std::move(rest));
  }
  const int found = static_cast<int>(parts.size());
  for (auto& part : parts) out.push_back(std::move(part));
  return found;
}

void MotionSplitter::forEachNeighbour(int width, int height, int cell,
                                      const std::function<void(int)>& visit) const {
  // The 8 neighbours, and along a row past up to max_gap cells that hold no point of the cluster
  // (dropouts), as region growing bridges them; never past a point of the cluster.
  const int reach = std::max(0, parameters_.max_gap) + 1;
  const int row = cell / width, col = cell % width;
  for (int r = std::max(0, row - 1); r <= std::min(height - 1, row + 1); ++r) {
    const std::size_t base = static_cast<std::size_t>(r) * width;
    if (r != row && member_[base + col] >= 0) visit(member_[base + col]);
    for (const int dir : {-1, 1})
      for (int c = col + dir, steps = 0; c >= 0 && c < width && steps < reach; c += dir, ++steps)
        if (member_[base + c] >= 0) {
          visit(member_[base + c]);
          break;
        }
  }
}

void MotionSplitter::growParts(int width, int height, const std::vector<float>& ranges,
                               const pcl::PointIndices& cluster, const std::vector<Sight>& sight,
                               std::vector<pcl::PointIndices>& parts) {
  const auto& idx = cluster.indices;
  const int n = static_cast<int>(idx.size());
  const int min_points = std::max(1, parameters_.min_points);
  for (int k = 0; k < n; ++k) member_[static_cast<std::size_t>(idx[k])] = k;
  part_of_.assign(static_cast<std::size_t>(n), 0);
  // A part grows from a seen-through seed over neighbours that were not seen where they are
  // (kAt: static, stops it) and continue its surface within the depth step: a walker is a smooth
  // surface, while seen-through points of porous foliage lie at random depths among static ones.
  const auto joins = [&](int from, int to) {
    return sight[static_cast<std::size_t>(to)] != Sight::kAt &&
           std::abs(ranges[static_cast<std::size_t>(idx[from])] -
                    ranges[static_cast<std::size_t>(idx[to])]) <= parameters_.depth_step;
  };
  // part_of_: 0 = not in a part yet, kGrowing while grown, then kPart or kRejected; kGrouped
  // once in an output part.
  constexpr int kGrowing = 1, kPart = 2, kGrouped = 3, kRejected = -1;
  const std::size_t first_part = parts.size();
  int through_in_parts = 0, through_all = 0;
  for (int seed = 0; seed < n; ++seed) {
    const bool seen_through = sight[static_cast<std::size_t>(seed)] == Sight::kThrough;
    through_all += seen_through;
    if (!seen_through || part_of_[seed] != 0) continue;
    queue_.assign(1, seed);
    part_of_[seed] = kGrowing;
    int through = 0;
    for (std::size_t q = 0; q < queue_.size(); ++q) {
      const int k = queue_[q];
      through += sight[static_cast<std::size_t>(k)] == Sight::kThrough;
      forEachNeighbour(width, height, idx[k], [&](int j) {
        if (part_of_[j] != 0 || !joins(k, j)) return;
        part_of_[j] = kGrowing;
        queue_.push_back(j);
      });
    }
    const int size = static_cast<int>(queue_.size());
    const bool accepted = size >= min_points && through >= min_points &&
                          through >= parameters_.min_through_fraction * static_cast<float>(size);
    for (const int k : queue_) part_of_[k] = accepted ? kPart : kRejected;
    if (accepted) through_in_parts += through;
  }
  // Touching parts are one object whose surface folds by more than the depth step (a car's
  // side and back): they were grown apart only to keep the growth on smooth surfaces.
  for (int seed = 0; seed < n; ++seed) {
    if (part_of_[seed] != kPart) continue;
    queue_.assign(1, seed);
    part_of_[seed] = kGrouped;
    for (std::size_t q = 0; q < queue_.size(); ++q)
      forEachNeighbour(width, height, idx[queue_[q]], [&](int j) {
        if (part_of_[j] != kPart) return;
        part_of_[j] = kGrouped;
        queue_.push_back(j);
      });
    parts.emplace_back();
    parts.back().header = cluster.header;
    for (const int k : queue_) parts.back().indices.push_back(idx[k]);
    std::sort(parts.back().indices.begin(), parts.back().indices.end());
  }
  // The parts must hold most of the cluster's seen-through points: a mover's evidence is
  // concentrated in it, while porous foliage is seen through here and there all over, and a
  // few of its patches happen to be smooth.
  const bool concentrated =
      through_in_parts >= parameters_.min_through_fraction * static_cast<float>(through_all);
  if (!concentrated) parts.resize(first_part);
  for (int k = 0; k < n; ++k) {
    if (part_of_[k] == kRejected || !concentrated) part_of_[k] = 0;  // with the static rest
    member_[static_cast<std::size_t>(idx[k])] = -1;
  }
}

}  // namespace pcl_movers
