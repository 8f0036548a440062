/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/surface_density.h>

#include <cmath>

namespace pcl_movers {

template <typename PointT>
void SurfaceDensity::compute(const pcl::PointCloud<PointT>& cloud,
                             const Eigen::Vector3f& sensor_origin, const Eigen::Vector3f& centre) {
  std::vector<Eigen::Vector3f> points;
  std::vector<float> sigmas;
  points.reserve(cloud.size());
  sigmas.reserve(cloud.size());
  for (const auto& p : cloud.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const Eigen::Vector3f v(p.x, p.y, p.z);
    points.push_back(v);
    sigmas.push_back(sigmaAtRange((v - sensor_origin).norm()));
  }
  computeFromPoints(points, sigmas, centre);
}

}  // namespace pcl_movers
