/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <limits>
#include <vector>

namespace pcl_movers {

/** \brief Least-squares line through measured positions (x, y, time), see fitVelocity(). */
struct LineFit {
  bool valid = false;  ///< false with fewer than 3 positions or no time span
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  ///< slope of the line [m/s]
  /// σ of the velocity per axis: `sigma` / sqrt(`time_spread`); infinite when not valid.
  double sigma_v = std::numeric_limits<double>::infinity();
  /// σ of one position about the line per axis (the scatter, at least the floor) [m].
  double sigma = std::numeric_limits<double>::infinity();
  Eigen::Vector2d mean_position = Eigen::Vector2d::Zero();  ///< centre of the line
  double mean_time = 0;                                     ///< time of mean_position [s]
  double time_spread = 0;                                   ///< Σ (t - mean_time)² [s²]
  std::size_t positions = 0;
};

/** \brief Least-squares line through measured positions (x, y, time): its velocity, the
 * velocity's σ (per axis) from the scatter of the positions about the line (at least
 * `min_sigma`), and the means and spread a caller needs to restart a filter from the line. */
LineFit fitVelocity(const std::vector<Eigen::Vector3d>& history, double min_sigma);

/** \brief The |v| / σ_v a line fit of `positions` positions must reach for "velocity = 0" to be
 * rejected at `false_rate`: with σ estimated from the scatter (2 (n - 2) degrees of freedom,
 * σ_v as LineFit::sigma_v), |v|² / (2 σ_v²) of a static object follows F(2, 2 (n - 2)), whose
 * quantile has the closed form ν/2 · (false_rate^(-2/ν) - 1). Infinite below 3 positions. */
double speedSignificanceRatio(std::size_t positions, double false_rate);

/** \brief Least-squares quadratic through measured positions (x, y, time), see
 * fitAcceleration(). */
struct QuadraticFit {
  bool valid = false;  ///< false with fewer than 4 positions or a degenerate time spread
  Eigen::Vector2d acceleration = Eigen::Vector2d::Zero();  ///< second derivative [m/s²]
  /// σ of the acceleration per axis, from `sigma`; infinite when not valid.
  double sigma_a = std::numeric_limits<double>::infinity();
  /// σ of one position about the quadratic per axis (the scatter, at least the floor) [m].
  double sigma = std::numeric_limits<double>::infinity();
};

/** \brief Least-squares quadratic `p + v·τ + a·τ²/2` through measured positions (x, y, time):
 * its acceleration and the acceleration's σ (per axis) from the scatter of the positions about
 * the quadratic (at least `min_sigma`). */
QuadraticFit fitAcceleration(const std::vector<Eigen::Vector3d>& positions, double min_sigma);

}  // namespace pcl_movers
