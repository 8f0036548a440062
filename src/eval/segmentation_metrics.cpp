/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/segmentation_metrics.h>
#include <pcl_movers/io/ground_truth.h>

#include <cmath>
#include <map>
#include <unordered_map>

namespace pcl_movers {
namespace eval {

namespace {

constexpr std::uint16_t kLaneMarking = 60;

bool isThing(std::uint16_t c) {
  return c == 10 || c == 11 || c == 13 || c == 15 || c == 16 || c == 18 || c == 20 || c == 30 ||
         c == 31 || c == 32 || (c >= 252 && c <= 259);
}

bool isStuffObject(std::uint16_t c) {
  return c == io::semantic::kTrunk || c == io::semantic::kPole;
}

/** Connected components of `members` (indices into points) with a voxel hash: points closer than
 * `tol` join. Voxel size = tol, so only the 27 neighbouring voxels need checking. */
std::vector<int> connectedComponents(const std::vector<int>& members,
                                     const std::vector<Eigen::Vector3f>& points, float tol) {
  const std::size_t n = members.size();
  std::vector<int> parent(n);
  for (std::size_t i = 0; i < n; ++i) parent[i] = static_cast<int>(i);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  auto key = [tol](const Eigen::Vector3f& p, int dx, int dy, int dz) {
    const auto q = [tol](float v, int d) {
      return static_cast<std::int64_t>(std::floor(v / tol)) + d;
    };
    return (q(p.x(), dx) * 73856093) ^ (q(p.y(), dy) * 19349663) ^ (q(p.z(), dz) * 83492791);
  };
  std::unordered_multimap<std::int64_t, int> grid;
  for (std::size_t i = 0; i < n; ++i) grid.emplace(key(points[members[i]], 0, 0, 0), int(i));
  const float tol2 = tol * tol;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = points[members[i]];
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto range = grid.equal_range(key(p, dx, dy, dz));
          for (auto it = range.first; it != range.second; ++it) {
            const int j = it->second;
            if ((points[members[j]] - p).squaredNorm() > tol2) continue;
            const int a = find(static_cast<int>(i)), b = find(j);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
          }
        }
  }
  std::vector<int> component(n);
  for (std::size_t i = 0; i < n; ++i) component[i] = find(static_cast<int>(i));
  return component;
}

}  // namespace

std::vector<GroundTruth> groundTruthFromLabels(const std::vector<std::uint32_t>& labels) {
  std::vector<GroundTruth> truth(labels.size());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const auto c = io::labelClass(labels[i]);
    if (c == io::semantic::kUnlabeled || c == io::semantic::kOutlier)
      truth[i] = GroundTruth::kIgnore;
    else if (io::semantic::isGround(c) || c == kLaneMarking)
      truth[i] = GroundTruth::kGround;
    else
      truth[i] = GroundTruth::kObject;
  }
  return truth;
}

GroundScore scoreGround(const std::vector<GroundTruth>& truth,
                        const std::vector<std::uint8_t>& is_ground) {
  GroundScore s;
  const std::size_t n = std::min(truth.size(), is_ground.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (truth[i] == GroundTruth::kIgnore) continue;
    const bool t = truth[i] == GroundTruth::kGround, p = is_ground[i] != 0;
    s.tp += t && p;
    s.fp += !t && p;
    s.fn += t && !p;
    s.tn += !t && !p;
  }
  return s;
}

std::vector<int> instancesFromLabels(const std::vector<std::uint32_t>& labels,
                                     const std::vector<Eigen::Vector3f>& points,
                                     float stuff_tolerance) {
  std::vector<int> instance(labels.size(), 0);
  int next = 1;
  std::map<std::uint32_t, int> thing_ids;  // full label -> dense id
  std::map<std::uint16_t, std::vector<int>> stuff;
  for (std::size_t i = 0; i < labels.size() && i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    const auto c = io::labelClass(labels[i]);
    if (isThing(c) && io::labelInstance(labels[i]) != 0) {
      auto it = thing_ids.find(labels[i]);
      if (it == thing_ids.end()) it = thing_ids.emplace(labels[i], next++).first;
      instance[i] = it->second;
    } else if (isStuffObject(c)) {
      stuff[c].push_back(static_cast<int>(i));
    }
  }
  for (const auto& [cls, members] : stuff) {
    const auto component = connectedComponents(members, points, stuff_tolerance);
    std::unordered_map<int, int> ids;
    for (std::size_t k = 0; k < members.size(); ++k) {
      auto it = ids.find(component[k]);
      if (it == ids.end()) it = ids.emplace(component[k], next++).first;
      instance[members[k]] = it->second;
    }
  }
  return instance;
}

ObjectScore scoreObjects(const std::vector<int>& instance_of, const std::vector<int>& cluster_of,
                         std::size_t min_points, double min_fraction,
                         const std::vector<std::uint8_t>* scored,
                         std::vector<InstanceOutcome>* outcomes) {
  if (outcomes) outcomes->clear();
  const std::size_t n = std::min(instance_of.size(), cluster_of.size());
  auto use = [&](std::size_t i) { return !scored || (i < scored->size() && (*scored)[i]); };
  std::unordered_map<int, std::size_t> instance_size, cluster_size;
  std::map<std::pair<int, int>, std::size_t> overlap;  // (instance, cluster) -> points
  for (std::size_t i = 0; i < n; ++i) {
    if (!use(i)) continue;
    if (cluster_of[i] >= 0) ++cluster_size[cluster_of[i]];
    if (instance_of[i] <= 0) continue;
    ++instance_size[instance_of[i]];
    if (cluster_of[i] >= 0) ++overlap[{instance_of[i], cluster_of[i]}];
  }
  ObjectScore s;
  for (const auto& [inst, size] : instance_size) {
    if (size < min_points) continue;
    ++s.instances;
    std::size_t best = 0, pieces = 0;
    int best_cluster = -1;
    for (auto it = overlap.lower_bound({inst, -1}); it != overlap.end() && it->first.first == inst;
         ++it) {
      if (it->second > best) best = it->second, best_cluster = it->first.second;
      if (double(it->second) >= 0.1 * double(size)) ++pieces;
    }
    const bool recovered = double(best) >= min_fraction * double(size);
    const bool under =
        best_cluster >= 0 && 2 * best < cluster_size[best_cluster] && double(best) >= 0.1 * size;
    if (recovered) ++s.recovered;
    if (recovered && !under) ++s.clean;
    if (under) ++s.under_segmented;
    if (!recovered && pieces >= 2) ++s.over_segmented;
    if (!recovered && pieces < 2 && !under) ++s.missed;
    if (outcomes) {
      InstanceOutcome o;
      o.instance = inst;
      o.points = size;
      o.share = double(best) / double(size);
      o.recovered = recovered;
      o.under_segmented = under;
      o.over_segmented = !recovered && pieces >= 2;
      o.missed = !recovered && pieces < 2 && !under;
      outcomes->push_back(o);
    }
  }
  return s;
}

std::vector<int> clusterIds(const std::vector<pcl::PointIndices>& clusters,
                            std::size_t num_points) {
  std::vector<int> ids(num_points, -1);
  for (std::size_t c = 0; c < clusters.size(); ++c)
    for (const auto i : clusters[c].indices)
      if (i >= 0 && static_cast<std::size_t>(i) < num_points) ids[i] = static_cast<int>(c);
  return ids;
}

}  // namespace eval
}  // namespace pcl_movers
