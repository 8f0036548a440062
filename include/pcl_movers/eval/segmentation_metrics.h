/*
 * Scoring of ground removal and object segmentation against point-wise labels (SemanticKITTI
 * `.label` files, or the simulator's labels in the same format).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/PointIndices.h>

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pcl_movers {
namespace eval {

/** \brief Ground truth of one point for ground scoring. */
enum class GroundTruth : std::int8_t { kIgnore = -1, kObject = 0, kGround = 1 };

/** \brief Point-wise ground truth from SemanticKITTI labels: ground = road, parking, sidewalk,
 * other-ground, terrain (io::semantic::isGround) and lane-marking (60, merged into road by
 * SemanticKITTI's own learning map); unlabelled (0) and outlier (1) points are ignored. */
std::vector<GroundTruth> groundTruthFromLabels(const std::vector<std::uint32_t>& labels);

/** \brief Confusion counts of a ground classifier (positive = ground). */
struct GroundScore {
  std::size_t tp = 0, fp = 0, fn = 0, tn = 0;
  double precision() const { return tp + fp ? double(tp) / double(tp + fp) : 0.0; }
  double recall() const { return tp + fn ? double(tp) / double(tp + fn) : 0.0; }
  GroundScore& operator+=(const GroundScore& o) {
    tp += o.tp, fp += o.fp, fn += o.fn, tn += o.tn;
    return *this;
  }
};

/** \brief Scores `is_ground` (one flag per point, same order as `truth`). */
GroundScore scoreGround(const std::vector<GroundTruth>& truth,
                        const std::vector<std::uint8_t>& is_ground);

/** \brief Object instances of a labelled scan, one id per point (0 = none).
 *
 * Things (car, bicycle, motorcycle, truck, other-vehicle, person, bicyclist, motorcyclist and the
 * moving classes 252-259) use the label's instance id. SemanticKITTI gives no instance ids to
 * trunks (71) and poles (80), so their points are split into instances by 3D connected components
 * (points closer than `stuff_tolerance` metres join), class by class. Ids are dense, 1..N.
 * `points` holds the points in label order (non-finite points get no instance). */
std::vector<int> instancesFromLabels(const std::vector<std::uint32_t>& labels,
                                     const std::vector<Eigen::Vector3f>& points,
                                     float stuff_tolerance = 0.5f);

/** \brief Object-recovery counts.
 *
 * For each instance with at least `min_points` scored points, the cluster holding most of them
 * is its best cluster; with share = (its points in that cluster) / (its points):
 *  - **recovered**: share >= `min_fraction` (0.8) — one cluster holds the object;
 *  - **under-segmented**: the best cluster is mostly other points (the instance is less than half
 *    of it): the object was merged with another object, a wall, vegetation or left-over ground;
 *  - **over-segmented**: not recovered, and at least two clusters each hold >= 10 % of it;
 *  - **missed**: neither (mostly removed as ground, or in clusters below the size limit).
 * recovered and under-segmented can both hold; "clean" = recovered and not under-segmented.
 */
struct ObjectScore {
  std::size_t instances = 0, recovered = 0, clean = 0, over_segmented = 0, under_segmented = 0,
              missed = 0;
  double rate(std::size_t n) const { return instances ? double(n) / double(instances) : 0.0; }
  ObjectScore& operator+=(const ObjectScore& o) {
    instances += o.instances, recovered += o.recovered, clean += o.clean;
    over_segmented += o.over_segmented, under_segmented += o.under_segmented, missed += o.missed;
    return *this;
  }
};

/** \brief The outcome of one scored instance (see ObjectScore for the definitions). */
struct InstanceOutcome {
  int instance = 0;
  std::size_t points = 0;  ///< scored points of the instance
  double share = 0.0;      ///< fraction of them in its best cluster
  bool recovered = false, under_segmented = false, over_segmented = false, missed = false;
};

/** \brief Scores clusters against instances. `instance_of` and `cluster_of` hold one entry per
 * point (same order); instance 0 = none, cluster -1 = in no cluster. Points where `scored` is
 * false (if given) are left out entirely (e.g. points the organizer could not place). When
 * `outcomes` is given it receives one entry per scored instance (to break results down by
 * class). */
ObjectScore scoreObjects(const std::vector<int>& instance_of, const std::vector<int>& cluster_of,
                         std::size_t min_points = 30, double min_fraction = 0.8,
                         const std::vector<std::uint8_t>* scored = nullptr,
                         std::vector<InstanceOutcome>* outcomes = nullptr);

/** \brief Per-point cluster ids (-1 = none) from a cluster list over `num_points` points. */
std::vector<int> clusterIds(const std::vector<pcl::PointIndices>& clusters, std::size_t num_points);

}  // namespace eval
}  // namespace pcl_movers
