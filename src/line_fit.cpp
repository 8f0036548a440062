/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/line_fit.h>

#include <Eigen/Cholesky>

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

QuadraticFit fitAcceleration(const std::vector<Eigen::Vector3d>& positions, double min_sigma) {
  QuadraticFit fit;
  const std::size_t n = positions.size();
  if (n < 4) return fit;  // three positions fit any quadratic exactly: no scatter to judge by
  double mean_t = 0;
  for (const auto& q : positions) mean_t += q.z();
  mean_t /= static_cast<double>(n);
  // Normal equations of the basis (1, τ, τ²/2), τ = t - mean_t (centred for conditioning).
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 3, 2> atb = Eigen::Matrix<double, 3, 2>::Zero();
  for (const auto& q : positions) {
    const double tau = q.z() - mean_t;
    const Eigen::Vector3d row(1.0, tau, 0.5 * tau * tau);
    ata += row * row.transpose();
    atb += row * q.head<2>().transpose();
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
  if (ldlt.info() != Eigen::Success || !(std::abs(ldlt.vectorD().minCoeff()) > 1e-12)) return fit;
  const Eigen::Matrix<double, 3, 2> coef = ldlt.solve(atb);
  double ss = 0;
  for (const auto& q : positions) {
    const double tau = q.z() - mean_t;
    const Eigen::Vector3d row(1.0, tau, 0.5 * tau * tau);
    ss += (q.head<2>() - coef.transpose() * row).squaredNorm();
  }
  // Per-axis σ about the quadratic: 2 (n - 3) degrees of freedom over x and y.
  fit.sigma = std::max(min_sigma, std::sqrt(ss / (2.0 * static_cast<double>(n - 3))));
  const double var_a = ldlt.solve(Eigen::Vector3d::UnitZ())(2);
  if (!(var_a > 0)) return fit;
  fit.acceleration = coef.row(2).transpose();
  fit.sigma_a = fit.sigma * std::sqrt(var_a);
  fit.valid = true;
  return fit;
}

}  // namespace pcl_movers
