/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/line_fit.h>

#include <algorithm>
#include <cmath>

namespace pcl_movers {

LineFit fitVelocity(const std::vector<Eigen::Vector3d>& history, double min_sigma) {
  LineFit fit;
  const std::size_t n = history.size();
  fit.positions = n;
  if (n < 3) return fit;  // a line through two points has no scatter to judge it by
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& h : history) mean += h;
  mean /= static_cast<double>(n);
  double stt = 0;
  Eigen::Vector2d sxt = Eigen::Vector2d::Zero();
  for (const auto& h : history) {
    const double dt = h.z() - mean.z();
    stt += dt * dt;
    sxt += dt * (h.head<2>() - mean.head<2>());
  }
  fit.mean_position = mean.head<2>();
  fit.mean_time = mean.z();
  fit.time_spread = stt;
  if (!(stt > 0)) return fit;
  const Eigen::Vector2d velocity = sxt / stt;
  double ss = 0;
  for (const auto& h : history) {
    const Eigen::Vector2d r = h.head<2>() - mean.head<2>() - velocity * (h.z() - mean.z());
    ss += r.squaredNorm();
  }
  // Per-axis σ of the positions about the line: 2 (n - 2) degrees of freedom over x and y.
  fit.sigma = std::max(min_sigma, std::sqrt(ss / (2.0 * static_cast<double>(n - 2))));
  fit.sigma_v = fit.sigma / std::sqrt(stt);
  fit.velocity = velocity;
  fit.valid = true;
  return fit;
}

double speedSignificanceRatio(std::size_t positions, double false_rate) {
  if (positions < 3 || !(false_rate > 0) || !(false_rate < 1))
    return std::numeric_limits<double>::infinity();
  const double dof = 2.0 * static_cast<double>(positions - 2);
  // F(2, ν) has the survival function (1 + 2 f / ν)^(-ν/2), so its (1 - α) quantile is closed.
  const double f = 0.5 * dof * (std::pow(false_rate, -2.0 / dof) - 1.0);
  return std::sqrt(2.0 * f);
}

}  // namespace pcl_movers
