/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/motion_split.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace pcl_movers {

using Sight = FreeSpaceMap::Sight;

std::vector<MotionSplitter::ClusterSplit> MotionSplitter::findSplits(
    int width, int height, const std::vector<pcl::PointIndices>& clusters, const Judge& judge,
    const Ranges& ranges) {
  const int min_points = std::max(1, parameters_.min_points);
  const int stride = std::max(1, parameters_.sample_stride);
  std::vector<ClusterSplit> splits;
  if (member_.size() != static_cast<std::size_t>(width) * height)
    member_.assign(static_cast<std::size_t>(width) * height, -1);
  indexSampledCells(width, height);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const auto& idx = clusters[c].indices;
    const int n = static_cast<int>(idx.size());
    if (n < 2 * min_points) continue;  // no part and static rest of min_points each in it
    // One point in stride first. Only a cluster that holds both a moving part and a static
    // surface is split: one seen through everywhere it was seen is a mover on its own (or two
    // joined, which the tracker's split of merged clusters handles), one seen where it is
    // everywhere is static, and so are most clusters.
    sight_.assign(static_cast<std::size_t>(n), Sight::kUnknown);
    judged_.assign(static_cast<std::size_t>(n), 0);
    positions_.clear();
    for (int k = 0; k < n; ++k)
      if (sampled_cells_[static_cast<std::size_t>(idx[k])]) positions_.push_back(k);
    int through = 0, at = 0;
    judgePositions(c, judge, through, at);
    if (through * stride < min_points || at * stride < min_points) continue;
    // Then every point: the parts grow from every seen-through point, and the cluster must hold
    // min_points of each kind.
    positions_.clear();
    for (int k = 0; k < n; ++k)
      if (!judged_[static_cast<std::size_t>(k)]) positions_.push_back(k);
    judgePositions(c, judge, through, at);
    if (through < min_points || at < min_points) continue;
    ranges(c, ranges_);
    auto parts = growParts(width, height, clusters[c], through);
    if (!parts.empty()) splits.push_back(ClusterSplit{c, std::move(parts)});
  }
  return splits;
}

void MotionSplitter::judgePositions(std::size_t cluster, const Judge& judge, int& through,
                                    int& at) {
  if (positions_.empty()) return;
  judge(cluster, positions_, judged_sights_);
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    const auto k = static_cast<std::size_t>(positions_[i]);
    sight_[k] = judged_sights_[i];
    judged_[k] = 1;
    through += sight_[k] == Sight::kThrough;
    at += sight_[k] == Sight::kAt;
  }
}

int MotionSplitter::applySplits(const std::vector<ClusterSplit>& splits,
                                std::vector<pcl::PointIndices>& clusters) {
  const int min_points = std::max(1, parameters_.min_points);
  std::vector<pcl::PointIndices> parts;
  std::vector<std::size_t> emptied;  // clusters whose rest is no object
  for (const auto& split : splits) {
    auto& idx = clusters[split.cluster].indices;
    in_part_.assign(idx.size(), 0);
    for (const auto& positions : split.parts) {
      parts.emplace_back();
      parts.back().header = clusters[split.cluster].header;
      parts.back().indices.reserve(positions.size());
      for (const int k : positions) {
        parts.back().indices.push_back(idx[static_cast<std::size_t>(k)]);
        in_part_[static_cast<std::size_t>(k)] = 1;
      }
    }
    // The static rest keeps the cluster's place; a rest under min_points is no object.
    std::size_t kept = 0;
    for (std::size_t k = 0; k < idx.size(); ++k)
      if (!in_part_[k]) idx[kept++] = idx[k];
    idx.resize(static_cast<int>(kept) >= min_points ? kept : 0);
    if (idx.empty()) emptied.push_back(split.cluster);
  }
  const int found = static_cast<int>(parts.size());
  std::sort(emptied.begin(), emptied.end());  // erased from the back, whatever the splits' order
  for (auto it = emptied.rbegin(); it != emptied.rend(); ++it)
    clusters.erase(clusters.begin() + static_cast<std::ptrdiff_t>(*it));
  for (auto& part : parts) clusters.push_back(std::move(part));
  return found;
}

bool MotionSplitter::sampled(int width, int cell) const {
  // Diagonals, not every stride-th index: a cluster's points are in row-major order, and every
  // stride-th of them leaves whole columns unsampled when the image width is a multiple of it.
  const int stride = std::max(1, parameters_.sample_stride);
  return (cell / width + cell % width) % stride == 0;
}

void MotionSplitter::indexSampledCells(int width, int height) {
  const int stride = std::max(1, parameters_.sample_stride);
  const std::size_t cells = static_cast<std::size_t>(width) * height;
  if (sampled_cells_.size() == cells && sampled_width_ == width && sampled_stride_ == stride)
    return;
  sampled_cells_.resize(cells);
  for (std::size_t cell = 0; cell < cells; ++cell)
    sampled_cells_[cell] = sampled(width, static_cast<int>(cell)) ? 1 : 0;
  sampled_width_ = width;
  sampled_stride_ = stride;
}

template <typename Visit>
void MotionSplitter::forEachNeighbour(int width, int height, int cell, const Visit& visit) const {
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

std::vector<std::vector<int>> MotionSplitter::growParts(int width, int height,
                                                        const pcl::PointIndices& cluster,
                                                        int through_all) {
  const std::vector<Sight>& sight = sight_;
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
           std::abs(ranges_[static_cast<std::size_t>(from)] -
                    ranges_[static_cast<std::size_t>(to)]) <= parameters_.depth_step;
  };
  // part_of_: 0 = not in a part yet, kGrowing while grown, then kPart or kRejected; kGrouped
  // once in an output part.
  constexpr int kGrowing = 1, kPart = 2, kGrouped = 3, kRejected = -1;
  std::vector<std::vector<int>> parts;
  int through_in_parts = 0;
  for (int seed = 0; seed < n; ++seed) {
    if (part_of_[seed] != 0 || sight[static_cast<std::size_t>(seed)] != Sight::kThrough) continue;
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
    std::sort(queue_.begin(), queue_.end(), [&](int a, int b) { return idx[a] < idx[b]; });
    parts.push_back(queue_);
  }
  // The parts must hold most of the cluster's seen-through points: a mover's evidence is
  // concentrated in it, while porous foliage is seen through here and there all over, and a few of
  // its patches happen to be smooth.
  const bool concentrated =
      through_in_parts >= parameters_.min_through_fraction * static_cast<float>(through_all);
  if (!concentrated) parts.clear();
  for (int k = 0; k < n; ++k) member_[static_cast<std::size_t>(idx[k])] = -1;
  return parts;
}

}  // namespace pcl_movers
