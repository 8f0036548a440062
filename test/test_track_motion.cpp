/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
// TrackMotion's rules on hand-made tracks, without a tracker.
#include <pcl_movers/track_motion.h>

#include <gtest/gtest.h>

#include <cmath>

using pcl_movers::DetectorParameters;
using pcl_movers::Track;
using pcl_movers::TrackMotion;

namespace {

TrackMotion motion() {
  TrackMotion m;
  m.setParameters(DetectorParameters());
  return m;
}

/// An established track at `velocity` (σ `velocity_sigma` [m/s]), its last update at t = 0.
Track establishedTrack(const Eigen::Vector2d& velocity, double velocity_sigma = 0.1) {
  Track t;
  const Eigen::Matrix2d cov = Eigen::Matrix2d::Identity() * 0.01;
  t.filter.initialize(Eigen::Vector2d::Zero(), cov, velocity, velocity_sigma);
  t.velocity_filter = t.filter;
  t.hits = 10;
  t.unoccluded_updates = 10;
  for (int k = -5; k <= 0; ++k) t.history.emplace_back(velocity.x() * 0.1 * k, 0, 0.1 * k);
  return t;
}

/// Moves both filters `dt` ahead, as MoverTracker does before associating.
void predict(Track& t, double dt) {
  t.filter.predict(dt);
  t.velocity_filter.predict(dt);
}

}  // namespace

TEST(TrackMotion, VelocitiesTurnWithTheRegisteredHeading) {
  const auto m = motion();
  Track t = establishedTrack(Eigen::Vector2d(10, 0));
  // The registration now maps the view onto the model with a yaw of -0.2 rad: the object turned
  // by +0.2 rad since the model's yaw (0).
  m.turn(t, -0.2);
  EXPECT_NEAR(t.filter.velocity().x(), 10 * std::cos(0.2), 1e-9);
  EXPECT_NEAR(t.filter.velocity().y(), 10 * std::sin(0.2), 1e-9);
  EXPECT_NEAR(t.velocity_filter.velocity().y(), 10 * std::sin(0.2), 1e-9);
  EXPECT_DOUBLE_EQ(t.model_yaw, -0.2);
  m.turn(t, -0.2);  // no further turn
  EXPECT_NEAR(t.filter.velocity().y(), 10 * std::sin(0.2), 1e-9);
}

TEST(TrackMotion, AnEstablishedTrackAcceleratesNoFasterThanTheLimit) {
  // A single measurement 2 m ahead of a track at rest (a cluster that jumped to another object)
  // may change its velocity by at most acceleration_limit · dt.
  // Its velocity is vague (σ 5 m/s), so the filter alone would follow the jump.
  const auto m = motion();
  const double limit = m.getParameters().track.acceleration_limit;
  Track t = establishedTrack(Eigen::Vector2d::Zero(), 5.0);
  predict(t, 0.1);
  m.measure(t, Eigen::Vector3d(2, 0, 0), true, false, 0.9, 10.0, 0.1);
  EXPECT_NEAR(t.filter.velocity().norm(), limit * 0.1, 1e-9);
  DetectorParameters unlimited;
  unlimited.track.acceleration_limit = 1e6;
  TrackMotion free;
  free.setParameters(unlimited);
  Track u = establishedTrack(Eigen::Vector2d::Zero(), 5.0);
  predict(u, 0.1);
  free.measure(u, Eigen::Vector3d(2, 0, 0), true, false, 0.9, 10.0, 0.1);
  EXPECT_GT(u.filter.velocity().norm(), 2 * limit * 0.1);
}

TEST(TrackMotion, OccludedViewsLeaveTheReportedVelocityCoasting) {
  // A car at 8 m/s slides behind a nearer object: its registered positions now lag (towards
  // "no motion"). The reported velocity coasts through them, then the first unoccluded view
  // moves the filter onto the measurement and keeps the velocity.
  const auto m = motion();
  Track t = establishedTrack(Eigen::Vector2d(8, 0));
  double time = 0;
  for (int k = 1; k <= 3; ++k) {
    time += 0.1;
    predict(t, 0.1);
    m.measure(t, Eigen::Vector3d(0.8 * k * 0.5, 0, 0), true, true, 0.9, 10.0, time);
    t.last_time = time;
    EXPECT_NEAR(t.velocity_filter.velocity().x(), 8.0, 1e-9) << k;
  }
  EXPECT_EQ(t.skipped_run, 3);
  time += 0.1;
  predict(t, 0.1);
  const Eigen::Vector3d seen(1.0, 0, 0);  // 1.4 m behind where 8 m/s would have taken it
  m.measure(t, seen, true, false, 0.9, 10.0, time);
  EXPECT_EQ(t.skipped_run, 0);
  EXPECT_NEAR(t.velocity_filter.position().x(), 1.0, 1e-9);
  EXPECT_NEAR(t.velocity_filter.velocity().x(), 8.0, 1e-9);
  // Without the skip (occluded_skip 0) the slide drags the reported velocity down.
  DetectorParameters no_skip;
  no_skip.track.occluded_skip = 0;
  TrackMotion dragged;
  dragged.setParameters(no_skip);
  Track u = establishedTrack(Eigen::Vector2d(8, 0));
  time = 0;
  for (int k = 1; k <= 3; ++k) {
    time += 0.1;
    predict(u, 0.1);
    dragged.measure(u, Eigen::Vector3d(0.8 * k * 0.5, 0, 0), true, true, 0.9, 10.0, time);
    u.last_time = time;
  }
  EXPECT_LT(u.velocity_filter.velocity().x(), 7.0);
}

TEST(TrackMotion, TheThirdRegistrationRestartsTheFiltersFromTheLine) {
  // A young far track (σ 0.8 m at 80 m) converges slowly from its rest prior; at its third
  // registered position the filter restarts from the line through the three.
  const auto m = motion();
  Track t;
  t.filter.initialize(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity() * 0.01,
                      Eigen::Vector2d::Zero(), 6.0);
  t.hits = 1;
  t.history.emplace_back(0, 0, 0);
  double time = 0;
  for (int k = 1; k <= 2; ++k) {
    time += 0.1;
    t.filter.predict(0.1);
    const Eigen::Vector3d p(2.0 * k, 0, 0);  // 20 m/s
    const double sigma = m.measure(t, p, true, false, 0.9, 80.0, time);
    t.last_time = time;
    ++t.hits;
    t.history.emplace_back(p.x(), p.y(), time);
    m.refit(t, p, true, false, sigma, time);
  }
  ASSERT_EQ(t.hits, 3);
  EXPECT_NEAR(t.filter.velocity().x(), 20.0, 1e-6);
  EXPECT_NEAR(t.filter.position().x(), 4.0, 1e-6);
}
