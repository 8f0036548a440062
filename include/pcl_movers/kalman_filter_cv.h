/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <Eigen/Core>

namespace pcl_movers {

/** \brief Constant-velocity Kalman filter in the horizontal plane.
 *
 * State `[x, y, vx, vy]` (world frame, metres and m/s), measurement `[x, y]`. The process noise is
 * the discrete white-noise-acceleration model: per axis `Q = σa² · [dt⁴/4, dt³/2; dt³/2, dt²]`, so
 * `σa` (setAccelerationNoise) is the standard deviation of the unmodelled acceleration in m/s². The
 * height of an object is taken from the measurement directly by the tracker: vehicles and people
 * move on the ground, so a vertical state would only add noise.
 */
class KalmanFilterCV {
 public:
  using State = Eigen::Vector4d;
  using Covariance = Eigen::Matrix4d;

  KalmanFilterCV() = default;
  /** \param acceleration_noise σa [m/s²] of the white-noise acceleration model */
  explicit KalmanFilterCV(double acceleration_noise) : acceleration_noise_(acceleration_noise) {}

  /** \brief Starts the filter at `position` with covariance `position_covariance`, and `velocity`
   * with an isotropic standard deviation `velocity_sigma` [m/s] (large for a newborn track whose
   * velocity is unknown). */
  void initialize(const Eigen::Vector2d& position, const Eigen::Matrix2d& position_covariance,
                  const Eigen::Vector2d& velocity = Eigen::Vector2d::Zero(),
                  double velocity_sigma = 10.0);

  /** \brief Propagates state and covariance by `dt` seconds (dt ≥ 0). */
  void predict(double dt);

  /** \brief Position the filter would predict after `dt` seconds, without changing the state. */
  Eigen::Vector2d predictedPosition(double dt) const {
    return state_.head<2>() + dt * state_.tail<2>();
  }

  /** \brief Innovation covariance `S = H P Hᵀ + R` of a position measurement with covariance R. */
  Eigen::Matrix2d innovationCovariance(const Eigen::Matrix2d& measurement_covariance) const {
    return covariance_.topLeftCorner<2, 2>() + measurement_covariance;
  }

  /** \brief Squared Mahalanobis distance of measurement `z` from the current (predicted) position,
   * used for gating: about chi²(2) distributed for a correct association. */
  double mahalanobisSquared(const Eigen::Vector2d& z,
                            const Eigen::Matrix2d& measurement_covariance) const;

  /** \brief Standard Kalman update with position measurement `z` (covariance R). Uses the Joseph
   * form so P stays symmetric positive definite over long tracks. */
  void update(const Eigen::Vector2d& z, const Eigen::Matrix2d& measurement_covariance);

  /** \brief Sets σa [m/s²]. */
  void setAccelerationNoise(double sigma) { acceleration_noise_ = sigma; }
  double getAccelerationNoise() const { return acceleration_noise_; }

  bool isInitialized() const { return initialized_; }
  const State& getState() const { return state_; }
  const Covariance& getCovariance() const { return covariance_; }
  Eigen::Vector2d position() const { return state_.head<2>(); }
  Eigen::Vector2d velocity() const { return state_.tail<2>(); }
  double speed() const { return state_.tail<2>().norm(); }
  /** \brief Overwrites the state (e.g. to clamp the velocity after an acceleration-limit check). */
  void setState(const State& state) { state_ = state; }
  void setCovariance(const Covariance& covariance) { covariance_ = covariance; }

 private:
  double acceleration_noise_ = 2.0;
  State state_ = State::Zero();
  Covariance covariance_ = Covariance::Identity();
  bool initialized_ = false;
};

}  // namespace pcl_movers
