/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/kalman_filter_cv.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace pcl_movers {

void KalmanFilterCV::initialize(const Eigen::Vector2d& position,
                                const Eigen::Matrix2d& position_covariance,
                                const Eigen::Vector2d& velocity, double velocity_sigma) {
  state_.head<2>() = position;
  state_.tail<2>() = velocity;
  covariance_.setZero();
  covariance_.topLeftCorner<2, 2>() = position_covariance;
  covariance_.bottomRightCorner<2, 2>() =
      Eigen::Matrix2d::Identity() * (velocity_sigma * velocity_sigma);
  initialized_ = true;
}

void KalmanFilterCV::predict(double dt) {
  if (dt <= 0.0) return;
  Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
  F(0, 2) = dt;
  F(1, 3) = dt;
  const double q = acceleration_noise_ * acceleration_noise_;
  const double dt2 = dt * dt, dt3 = dt2 * dt, dt4 = dt3 * dt;
  Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();
  Q(0, 0) = Q(1, 1) = q * dt4 / 4.0;
  Q(0, 2) = Q(2, 0) = Q(1, 3) = Q(3, 1) = q * dt3 / 2.0;
  Q(2, 2) = Q(3, 3) = q * dt2;
  state_ = F * state_;
  covariance_ = F * covariance_ * F.transpose() + Q;
}

double KalmanFilterCV::mahalanobisSquared(const Eigen::Vector2d& z,
                                          const Eigen::Matrix2d& measurement_covariance) const {
  const Eigen::Vector2d innovation = z - state_.head<2>();
  const Eigen::Matrix2d S = innovationCovariance(measurement_covariance);
  return innovation.dot(S.ldlt().solve(innovation));
}

void KalmanFilterCV::update(const Eigen::Vector2d& z,
                            const Eigen::Matrix2d& measurement_covariance) {
  Eigen::Matrix<double, 2, 4> H = Eigen::Matrix<double, 2, 4>::Zero();
  H(0, 0) = H(1, 1) = 1.0;
  const Eigen::Matrix2d S = innovationCovariance(measurement_covariance);
  const Eigen::Matrix<double, 4, 2> K = covariance_ * H.transpose() * S.inverse();
  state_ += K * (z - state_.head<2>());
  const Eigen::Matrix4d I_KH = Eigen::Matrix4d::Identity() - K * H;
  covariance_ = I_KH * covariance_ * I_KH.transpose() + K * measurement_covariance * K.transpose();
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
}

}  // namespace pcl_movers
