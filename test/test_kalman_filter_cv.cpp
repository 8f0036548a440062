/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <gtest/gtest.h>
#include <pcl_movers/kalman_filter_cv.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

using pcl_movers::KalmanFilterCV;

// Hand-computed, per axis: P0 = diag(1, 4) (position var 1, velocity sigma 2), dt = 1, σa = 1:
//   F P Fᵀ = [[5, 4], [4, 4]],  Q = [[1/4, 1/2], [1/2, 1]]  →  P⁻ = [[5.25, 4.5], [4.5, 5]].
// Measurement z = 1 with R = 1:  S = 6.25,  K = [0.84, 0.72],  x = 0.84, v = 0.72,
//   P⁺ = [[0.84, 0.72], [0.72, 5 - 0.72·4.5 = 1.76]].
TEST(KalmanFilterCV, PredictMatchesHandComputedStep) {
  KalmanFilterCV kf(1.0);
  kf.initialize(Eigen::Vector2d(0, 0), Eigen::Matrix2d::Identity(), Eigen::Vector2d(0, 0), 2.0);
  kf.predict(1.0);
  const auto& P = kf.getCovariance();
  EXPECT_NEAR(P(0, 0), 5.25, 1e-12);
  EXPECT_NEAR(P(0, 2), 4.5, 1e-12);
  EXPECT_NEAR(P(2, 2), 5.0, 1e-12);
  EXPECT_NEAR(P(1, 1), 5.25, 1e-12);
  EXPECT_NEAR(P(0, 1), 0.0, 1e-12);  // axes stay independent
  EXPECT_NEAR(kf.mahalanobisSquared(Eigen::Vector2d(1, 0), Eigen::Matrix2d::Identity()), 0.16,
              1e-12);
}

TEST(KalmanFilterCV, UpdateMatchesHandComputedStep) {
  KalmanFilterCV kf(1.0);
  kf.initialize(Eigen::Vector2d(0, 0), Eigen::Matrix2d::Identity(), Eigen::Vector2d(0, 0), 2.0);
  kf.predict(1.0);
  kf.update(Eigen::Vector2d(1, 0), Eigen::Matrix2d::Identity());
  const auto& x = kf.getState();
  EXPECT_NEAR(x(0), 0.84, 1e-12);
  EXPECT_NEAR(x(2), 0.72, 1e-12);
  EXPECT_NEAR(x(1), 0.0, 1e-12);
  EXPECT_NEAR(x(3), 0.0, 1e-12);
  const auto& P = kf.getCovariance();
  EXPECT_NEAR(P(0, 0), 0.84, 1e-12);
  EXPECT_NEAR(P(0, 2), 0.72, 1e-12);
  EXPECT_NEAR(P(2, 2), 1.76, 1e-12);
}

TEST(KalmanFilterCV, PredictMovesStateWithVelocity) {
  KalmanFilterCV kf(0.0);
  kf.initialize(Eigen::Vector2d(1, 2), Eigen::Matrix2d::Identity() * 0.01, Eigen::Vector2d(3, -1),
                0.1);
  kf.predict(0.5);
  EXPECT_NEAR(kf.position().x(), 2.5, 1e-12);
  EXPECT_NEAR(kf.position().y(), 1.5, 1e-12);
  EXPECT_NEAR(kf.speed(), std::sqrt(10.0), 1e-12);
  // Zero process noise: covariance is exactly F P Fᵀ.
  EXPECT_NEAR(kf.getCovariance()(0, 0), 0.01 + 0.25 * 0.01, 1e-12);
  // dt = 0 or negative changes nothing.
  const auto before = kf.getState();
  kf.predict(0.0);
  EXPECT_TRUE(kf.getState().isApprox(before));
}

TEST(KalmanFilterCV, ConvergesToTrueVelocityFromNoisyPositions) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.1);
  KalmanFilterCV kf(0.5);
  const Eigen::Vector2d v(4.0, -1.5);
  const Eigen::Matrix2d R = Eigen::Matrix2d::Identity() * 0.01;
  kf.initialize(Eigen::Vector2d(0, 0), R);
  for (int k = 1; k <= 60; ++k) {
    kf.predict(0.1);
    const Eigen::Vector2d truth = v * (0.1 * k);
    kf.update(truth + Eigen::Vector2d(noise(rng), noise(rng)), R);
  }
  EXPECT_NEAR(kf.velocity().x(), 4.0, 0.3);
  EXPECT_NEAR(kf.velocity().y(), -1.5, 0.3);
  // Covariance stays symmetric positive definite.
  const auto& P = kf.getCovariance();
  EXPECT_TRUE(P.isApprox(P.transpose()));
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(P);
  EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
}
