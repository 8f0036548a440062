/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>
#include <pcl_movers/sensor_model.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

namespace pcl_movers {

namespace detail {

/** \brief The sensor-independent part of SensorModel::estimate, on (w = 1/ρ, t = z/ρ, azimuth)
 * of each point. */
SensorModel estimateBeams(const std::vector<float>& w, const std::vector<float>& t,
                          const std::vector<float>& azimuth, int num_beams, int columns);

}  // namespace detail

template <typename PointT>
SensorModel SensorModel::estimate(const pcl::PointCloud<PointT>& cloud, int num_beams,
                                  int columns) {
  if (num_beams < 0) throw InputError("SensorModel::estimate: negative number of beams");
  if (columns < 0) throw InputError("SensorModel::estimate: negative number of columns");
  // Only ρ and z/ρ matter; points very near the sensor (the car's roof, the sensor's own housing)
  // carry no usable elevation, and far ones are rare enough to be noise.
  std::vector<float> w, t, azimuth;
  w.reserve(cloud.size());
  t.reserve(cloud.size());
  azimuth.reserve(cloud.size());
  for (const auto& p : cloud.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const float rho = std::sqrt(p.x * p.x + p.y * p.y);
    if (rho < 2.f || rho > 150.f) continue;
    w.push_back(1.f / rho);
    t.push_back(p.z / rho);
    azimuth.push_back(std::atan2(p.y, p.x));
  }
  return detail::estimateBeams(w, t, azimuth, num_beams, columns);
}

}  // namespace pcl_movers
