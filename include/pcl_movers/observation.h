/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/PointIndices.h>

#include <limits>
#include <vector>

namespace pcl_movers {

/** \brief One object cluster of a frame, as segmentation hands it to tracking.
 *
 * What the tracker cannot see in the cluster's points alone: whether a nearer object bounds it
 * (so its extent there, and the centroid, can slide while it emerges or hides), whether it was
 * cut from a merged cluster, and what it stands on. MoverDetector builds them once per frame
 * from the range image (RangeImageRegionGrowing::occludedSides() and occluderFloors()) and the
 * ground filter; MoverTracker::update() reads them. */
struct Observation {
  /// The cluster's points, as indices into the world cloud handed to MoverTracker::update().
  pcl::PointIndices indices;
  /// A side is bounded by a nearer object: the extent there is not the object's.
  bool occluded = false;
  /// Cut from a cluster that held two tracks' objects (MoverTracker::splitMergedClusters()): it
  /// is tracked below segment.min_cluster_points, and its side along the cut is not the
  /// object's extent (so it is also `occluded`).
  bool split_part = false;
  /// What the object stands on (world z): the lowest point of a nearer object hiding its lower
  /// part (a parked car below a walker's head), else the ground under it; NaN = unknown.
  double floor_z = std::numeric_limits<double>::quiet_NaN();
  /// How rough its surface is in the range image [m] (clusterRoughness()): foliage is porous,
  /// rays end at random depths in it; NaN = unknown.
  float roughness = std::numeric_limits<float>::quiet_NaN();
};

/** \brief Observations of plain clusters: nothing known besides their points. */
inline std::vector<Observation> observationsOf(const std::vector<pcl::PointIndices>& clusters) {
  std::vector<Observation> observations(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c) observations[c].indices = clusters[c];
  return observations;
}

}  // namespace pcl_movers
