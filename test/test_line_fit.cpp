/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/line_fit.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using pcl_movers::fitAcceleration;
using pcl_movers::fitVelocity;
using pcl_movers::speedSignificanceRatio;

TEST(LineFit, FitVelocityUsesScatterOfPositions) {
  std::vector<Eigen::Vector3d> history;
  history.emplace_back(0, 0, 0);
  history.emplace_back(0.14, 0, 0.1);
  const auto two = fitVelocity(history, 0.1);
  EXPECT_FALSE(two.valid);  // no scatter from 2 points
  EXPECT_TRUE(std::isinf(two.sigma_v));
  // Walking at 1.4 m/s, positions exact: σ is the floor (0.1 m) over sqrt(Σ(t - t̄)²).
  for (int k = 2; k < 6; ++k) history.emplace_back(0.14 * k, 0, 0.1 * k);
  const auto fit = fitVelocity(history, 0.1);
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.velocity.x(), 1.4, 1e-9);
  EXPECT_NEAR(fit.velocity.y(), 0.0, 1e-9);
  EXPECT_NEAR(fit.sigma, 0.1, 1e-12);
  EXPECT_NEAR(fit.sigma_v, 0.1 / std::sqrt(0.175), 1e-9);
  EXPECT_GT(fit.velocity.norm(), 2.0 * fit.sigma_v);
  // The line's centre and spread (what velocity_fit_init restarts the filter from).
  EXPECT_EQ(fit.positions, 6u);
  EXPECT_NEAR(fit.mean_time, 0.25, 1e-12);
  EXPECT_NEAR(fit.mean_position.x(), 0.35, 1e-12);
  EXPECT_NEAR(fit.mean_position.y(), 0.0, 1e-12);
  EXPECT_NEAR(fit.time_spread, 0.175, 1e-12);
  // A static object whose registered positions scatter by a few tenths of a metre (a far,
  // coarsely sampled object): the line through them is faster than mover_speed, but the
  // scatter about it makes it no evidence of motion.
  std::vector<Eigen::Vector3d> noisy;
  const double xs[6] = {0.2, -0.2, 0.1, -0.25, 0.15, -0.1};
  const double ys[6] = {-0.5, 0.4, -0.4, 0.6, -0.1, 0.6};
  for (int k = 0; k < 6; ++k) noisy.emplace_back(xs[k], ys[k], 0.1 * k);
  const auto scattered = fitVelocity(noisy, 0.1);
  ASSERT_TRUE(scattered.valid);
  EXPECT_GT(scattered.sigma, 0.1);  // the scatter, above the floor
  EXPECT_GT(scattered.velocity.norm(), 1.2);
  EXPECT_LT(scattered.velocity.norm(), 2.0 * scattered.sigma_v);
}

// The early-confirmation threshold is the F(2, 2(n-2)) quantile of |v|² / (2 σ_v²): for a static
// object with white position noise the line fit must exceed it at the stated false-positive rate.
TEST(LineFit, SpeedSignificanceRatioIsTheFQuantile) {
  EXPECT_TRUE(std::isinf(speedSignificanceRatio(2, 0.001)));
  EXPECT_TRUE(std::isinf(speedSignificanceRatio(4, 0.0)));
  // ν = 2: f = 1/α - 1; ν = 4: f = 2 (1/√α - 1).
  EXPECT_NEAR(speedSignificanceRatio(3, 0.001), std::sqrt(2.0 * 999.0), 1e-9);
  EXPECT_NEAR(speedSignificanceRatio(4, 0.001), std::sqrt(4.0 * (std::sqrt(1000.0) - 1)), 1e-9);
  // More positions: a weaker ratio suffices.
  EXPECT_GT(speedSignificanceRatio(4, 0.001), speedSignificanceRatio(6, 0.001));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (const std::size_t n : {3u, 4u, 6u}) {
    const double alpha = 0.02;
    const double ratio = speedSignificanceRatio(n, alpha);
    const int trials = 20000;
    int rejected = 0;
    for (int i = 0; i < trials; ++i) {
      std::vector<Eigen::Vector3d> history;
      for (std::size_t k = 0; k < n; ++k) history.emplace_back(noise(rng), noise(rng), 0.1 * k);
      const auto fit = fitVelocity(history, 1e-9);  // σ from the scatter alone
      rejected += fit.velocity.norm() >= ratio * fit.sigma_v;
    }
    // Binomial σ of the rate at 20000 trials: 0.001.
    EXPECT_NEAR(static_cast<double>(rejected) / trials, alpha, 0.005) << n;
  }
}

// Hand-computed: four positions at t = 0..3 on x = t² (a = 2 m/s²) plus ε·(-1, 3, -3, 1), which is
// orthogonal to 1, t and t² (the cubic of equally spaced points): the quadratic is exactly t², the
// residuals are the perturbation, Σr² = 20ε² over 2·(4 - 3) degrees of freedom, so σ = ε·√10; the
// τ²/2 column centred is (0.5, -0.5, -0.5, 0.5) with unit norm, so σ_a = σ.
TEST(LineFit, FitAccelerationMatchesHandComputedQuadratic) {
  const double eps = 0.1;
  const double bump[4] = {-1, 3, -3, 1};
  std::vector<Eigen::Vector3d> positions;
  for (int k = 0; k < 4; ++k) positions.emplace_back(k * k + eps * bump[k], 5.0, 10.0 + k);
  const auto fit = fitAcceleration(positions, 0.01);
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.acceleration.x(), 2.0, 1e-9);
  EXPECT_NEAR(fit.acceleration.y(), 0.0, 1e-9);
  EXPECT_NEAR(fit.sigma, eps * std::sqrt(10.0), 1e-9);
  EXPECT_NEAR(fit.sigma_a, eps * std::sqrt(10.0), 1e-9);
  // The floor: without the perturbation the scatter is 0 and σ is the floor.
  for (int k = 0; k < 4; ++k) positions[k].x() = k * k;
  const auto exact = fitAcceleration(positions, 0.05);
  ASSERT_TRUE(exact.valid);
  EXPECT_NEAR(exact.acceleration.x(), 2.0, 1e-9);
  EXPECT_NEAR(exact.sigma, 0.05, 1e-12);
  EXPECT_NEAR(exact.sigma_a, 0.05, 1e-9);
  // Three positions fit any quadratic: not valid.
  positions.pop_back();
  EXPECT_FALSE(fitAcceleration(positions, 0.05).valid);
}
