/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
// The mover decision's rules on hand-made tracks, without a tracker: each named test, in order,
// and the reason it writes.
#include <pcl_movers/mover_decision.h>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

using pcl_movers::DetectorParameters;
using pcl_movers::MoverDecision;
using pcl_movers::MoverReason;
using pcl_movers::Track;

namespace {

/// A registered 1.8 m tall track whose last `n` positions, 0.1 s apart, move at `speed` along x.
Track movingTrack(double speed, int n) {
  Track t;
  t.id = 1;
  t.model.reset(new pcl_movers::SurfaceDensity);
  t.max_height = t.max_standing_height = 1.8;
  t.features.height = 1.8;
  t.features.points = 40;
  t.similarity = 0.9;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d p(speed * 0.1 * k, 0, 0.1 * k);
    t.history.push_back(p);
    t.long_history.push_back(p);
    t.registered.push_back(p);
  }
  t.hits = n;
  t.age = n;
  return t;
}

/// movingTrack() with no speed vote in its window.
Track unvotedTrack(double speed, int n) {
  Track t = movingTrack(speed, n);
  t.fast.assign(5, 0);
  return t;
}

/// A 3 m/s track with every speed vote of its window, its last view a poor match (B 0.5), so the
/// vote rule decides, not the early confirmation of well-measured motion.
Track votedFastTrack() {
  Track t = movingTrack(3.0, 6);
  t.fast.assign(5, 1);
  t.similarity = 0.5;
  return t;
}

MoverDecision decisionWithoutFreeSpace() {
  MoverDecision decision;
  decision.setParameters(DetectorParameters());
  return decision;  // no free-space map: the free-space tests are off
}

/// Every stored scan saw a wall 20 m ahead, so `points`, a 0.45 m × 0.8 m patch 10 m ahead, fill
/// space seen through: a decision with this map gives their views free-space votes.
struct SeenThroughWall {
  SeenThroughWall() {
    pcl::PointCloud<pcl::PointXYZ> wall;
    for (int i = -40; i <= 40; ++i)
      for (int k = -20; k <= 20; ++k) wall.push_back(pcl::PointXYZ(20.0f, 0.05f * i, 0.05f * k));
    map.setHistory(params.free_space.long_lag + 1);
    for (int f = 0; f <= params.free_space.lag; ++f)
      map.addScan(wall, Eigen::Isometry3d::Identity());
    for (int i = -4; i <= 4; ++i)
      for (int k = -4; k <= 4; ++k) points.emplace_back(10.0f, 0.05f * i, 0.1f * k);
    decision.setParameters(params);
    decision.setFreeSpaceMap(&map);
  }
  SeenThroughWall(const SeenThroughWall&) = delete;  // the decision points to this map
  SeenThroughWall& operator=(const SeenThroughWall&) = delete;

  const DetectorParameters params;
  pcl_movers::FreeSpaceMap map;
  std::vector<Eigen::Vector3f> points;
  MoverDecision decision;
};

}  // namespace

TEST(MoverDecision, VotesFastOnlyForALineFasterThanTheThresholdBeyondItsScatter) {
  const auto decision = decisionWithoutFreeSpace();
  Track fast = movingTrack(1.5, 6);  // exact positions: σ is the floor
  decision.voteFast(fast, true);
  ASSERT_EQ(fast.fast.size(), 1u);
  EXPECT_EQ(fast.fast.back(), 1);
  Track slow = movingTrack(0.6, 6);  // below decision.speed (1.2 m/s)
  decision.voteFast(slow, true);
  EXPECT_EQ(slow.fast.back(), 0);
  // The same positions scattered ±0.6 m across the line (a far, coarsely sampled object): the
  // fitted speed is above the threshold, but not beyond twice its σ from the scatter.
  Track scattered = movingTrack(1.5, 6);
  for (int k = 0; k < 6; ++k) scattered.history[k].y() = k % 2 ? -0.6 : 0.6;
  decision.voteFast(scattered, true);
  EXPECT_EQ(scattered.fast.back(), 0);
}

TEST(MoverDecision, TestsRunInOrderAndTheFirstFailedIsTheReason) {
  const auto decision = decisionWithoutFreeSpace();
  const std::vector<Track> none;
  const std::vector<Eigen::Vector3f> points;
  {  // large structures first
    Track t = movingTrack(3.0, 6);
    t.large = true;
    decision.decide(t, points, none);
    EXPECT_FALSE(t.mover);
    EXPECT_EQ(t.reason, MoverReason::kLarge);
  }
  {  // young: fewer than decision.min_age updates, motion not beyond doubt (a scattered line)
    Track t = movingTrack(3.0, 3);
    t.history[1].y() = 0.3;
    decision.decide(t, points, none);
    EXPECT_EQ(t.reason, MoverReason::kYoung);
  }
  {  // low: never as tall as decision.min_height, not even from what it stands on
    Track t = movingTrack(3.0, 6);
    t.fast.assign(5, 1);
    t.max_height = t.max_standing_height = 0.3;
    decision.decide(t, points, none);
    EXPECT_EQ(t.reason, MoverReason::kLow);
  }
  {  // no motion: no speed votes and no sustained line
    Track t = unvotedTrack(0.0, 6);
    decision.decide(t, points, none);
    EXPECT_FALSE(t.mover);
    EXPECT_EQ(t.reason, MoverReason::kNoMotion);
  }
  {  // fast: votes of the window and a consistent displacement
    Track t = votedFastTrack();
    decision.decide(t, points, none);
    EXPECT_TRUE(t.mover);
    EXPECT_EQ(t.reason, MoverReason::kFast);
  }
}

TEST(MoverDecision, FastVotesWithoutDisplacementAreNoMotion) {
  // Speed votes from a jittering velocity, but the measurements did not get anywhere.
  const auto decision = decisionWithoutFreeSpace();
  Track t = votedFastTrack();
  t.history.back().x() = t.history.front().x() + 0.2;
  decision.decide(t, {}, {});
  EXPECT_FALSE(t.mover);
  EXPECT_EQ(t.reason, MoverReason::kNoMotion);
}

TEST(MoverDecision, AWellMeasuredYoungTrackIsConfirmedBeforeTheMinimumAge) {
  const auto decision = decisionWithoutFreeSpace();
  Track t = movingTrack(8.0, 3);  // three exact registered positions at 8 m/s, B 0.9, 40 points
  ASSERT_LT(t.hits, decision.getParameters().decision.min_age);
  decision.decide(t, {}, {});
  EXPECT_TRUE(t.mover);
  EXPECT_EQ(t.reason, MoverReason::kWellMeasured);
  // The same positions from a poor match keep waiting for the vote rule.
  Track poor = movingTrack(8.0, 3);
  poor.similarity = 0.5;
  decision.decide(poor, {}, {});
  EXPECT_EQ(poor.reason, MoverReason::kYoung);
}

TEST(MoverDecision, ASlowWalkerOnAStraightLineIsASustainedMover) {
  // 0.6 m/s for 1.5 s (16 registered positions), below decision.speed: no speed votes.
  const auto decision = decisionWithoutFreeSpace();
  Track walker = unvotedTrack(0.6, 16);
  decision.decide(walker, {}, {});
  EXPECT_TRUE(walker.mover);
  EXPECT_EQ(walker.reason, MoverReason::kSustained);
  // A parked car's registration wobble, as large but on no line, is not.
  Track parked = unvotedTrack(0.0, 16);
  for (std::size_t k = 0; k < parked.long_history.size(); ++k)
    parked.long_history[k].head<2>() =
        Eigen::Vector2d(0.3 * std::sin(1.7 * k), 0.3 * std::cos(2.3 * k));
  decision.decide(parked, {}, {});
  EXPECT_FALSE(parked.mover);
  EXPECT_EQ(parked.reason, MoverReason::kNoMotion);
}

TEST(MoverDecision, ASlowLineNeedsNoFullWindowOnlyItsSignificance) {
  // 1 m/s for 0.7 s (8 positions), below decision.speed: under half of decision.slow_window, and
  // enough for the F-test at the 0.1 m position σ floor; a walker need not wait 1.1 s.
  const auto decision = decisionWithoutFreeSpace();
  Track walker = unvotedTrack(1.0, 8);
  decision.decide(walker, {}, {});
  EXPECT_TRUE(walker.mover);
  EXPECT_EQ(walker.reason, MoverReason::kSustained);
  // The same walker over 0.5 s: 6 positions cannot tell 0.5 m from the σ floor's scatter.
  Track short_line = unvotedTrack(1.0, 6);
  decision.decide(short_line, {}, {});
  EXPECT_FALSE(short_line.mover);
  EXPECT_EQ(short_line.reason, MoverReason::kNoMotion);
}

TEST(MoverDecision, ALineFasterThanTheSpeedThresholdIsNotSustainedMotion) {
  // A stretch of wall registered sliding along with the sensor at 17 m/s, on a straight line,
  // with no speed vote: the speed votes judge fast lines, the slow path does not take them.
  const auto decision = decisionWithoutFreeSpace();
  Track wall = unvotedTrack(17.0, 16);
  decision.decide(wall, {}, {});
  EXPECT_FALSE(wall.mover);
  EXPECT_EQ(wall.reason, MoverReason::kNoMotion);
}

TEST(MoverDecision, AConfirmedMoverLatchesAfterAFullWindowOfPositiveDecisions) {
  const auto decision = decisionWithoutFreeSpace();
  const int window = decision.getParameters().decision.window;
  Track t = votedFastTrack();
  for (int k = 0; k < window; ++k) {
    EXPECT_FALSE(t.confirmed) << k;
    decision.decide(t, {}, {});
    EXPECT_TRUE(t.mover);
  }
  EXPECT_TRUE(t.confirmed);
  // Now it stays a mover while it stands still (a car waiting at a light).
  t.fast.assign(5, 0);
  decision.decide(t, {}, {});
  EXPECT_TRUE(t.mover);
  EXPECT_EQ(t.reason, MoverReason::kLatched);
}

TEST(MoverDecision, ALowViewBesideAMoverIsItsFragmentNotAMover) {
  // Seen only above what hides it (a standing height from a nearer object below), but next to
  // a moving track: more likely that object's own upper part than a walker behind a car.
  const auto decision = decisionWithoutFreeSpace();
  Track part = votedFastTrack();
  part.max_height = 0.3;
  part.max_standing_height = 1.7;
  decision.decide(part, {}, {});
  EXPECT_TRUE(part.mover) << "alone, measured from what hides it, it stands tall enough";
  Track car = movingTrack(3.0, 6);
  car.id = 2;
  car.max_length = 4.5;
  car.mover = true;
  Track beside = votedFastTrack();
  beside.max_height = 0.3;
  beside.max_standing_height = 1.7;
  decision.decide(beside, {}, {car});
  EXPECT_FALSE(beside.mover);
  EXPECT_EQ(beside.reason, MoverReason::kLow);
}

TEST(MoverDecision, WithAFreeSpaceMapMotionAloneIsNotEnough) {
  // A map holding no scan has seen nothing through: kinematic evidence without free-space votes.
  auto decision = decisionWithoutFreeSpace();
  pcl_movers::FreeSpaceMap map;
  decision.setFreeSpaceMap(&map);
  Track t = votedFastTrack();
  const std::vector<Eigen::Vector3f> points = {{1.5f, 0, 0}, {1.6f, 0, 0.5f}};
  decision.decide(t, points, {});
  EXPECT_FALSE(t.mover);
  EXPECT_EQ(t.reason, MoverReason::kNoFreeSpace);
}

TEST(MoverDecision, APorousViewGivesNoFreeSpaceVote) {
  // Every stored scan saw a wall 20 m ahead, so the track's points 10 m ahead fill space seen
  // through: a solid view gets its free-space votes and is a mover. Foliage is seen through
  // wherever it stands, so a view as rough as a tree's (free_space.porous_roughness) gets none.
  const SeenThroughWall scene;
  const DetectorParameters& params = scene.params;
  const MoverDecision& decision = scene.decision;
  const std::vector<Eigen::Vector3f>& points = scene.points;
  for (const double roughness : {0.04, 0.5}) {
    Track t = votedFastTrack();
    t.features.roughness = roughness;
    for (int update = 0; update < params.free_space.votes; ++update) decision.decide(t, points, {});
    SCOPED_TRACE("roughness " + std::to_string(roughness));
    EXPECT_EQ(t.mover, roughness < params.free_space.porous_roughness);
    if (!t.mover) EXPECT_EQ(t.reason, MoverReason::kNoFreeSpace);
  }
}

TEST(MoverDecision, PorousIsJudgedOnTheMedianOfTheRecentViews) {
  // The seen-through wall of the test above. A bush's views flicker around the roughness bound: its
  // smoother views must not collect the votes its rougher ones are denied. A solid object with
  // one rough view among smooth ones keeps its votes.
  const SeenThroughWall scene;
  const DetectorParameters& params = scene.params;
  const MoverDecision& decision = scene.decision;
  const std::vector<Eigen::Vector3f>& points = scene.points;
  const double bound = params.free_space.porous_roughness;
  const auto decideViews = [&](const std::vector<double>& roughness) {
    Track t = votedFastTrack();
    for (const double r : roughness) {
      t.features.roughness = r;
      decision.decide(t, points, {});
    }
    return t;
  };
  const Track bush =
      decideViews({1.3 * bound, 0.8 * bound, 1.3 * bound, 0.8 * bound, 1.3 * bound, 0.8 * bound});
  EXPECT_FALSE(bush.mover);
  EXPECT_EQ(bush.reason, MoverReason::kNoFreeSpace);
  const Track car = decideViews({0.2 * bound, 1.5 * bound, 0.2 * bound, 0.2 * bound});
  EXPECT_TRUE(car.mover);
}

TEST(MoverDecision, ASpeedVoteWithMostOfItsViewSeenThroughIsAMoverAtOnce) {
  // The seen-through wall above: one update's view whose points all lie in space the scan
  // free_space.lag frames back saw empty, with that update's speed vote, is a mover before the
  // free-space votes of the window add up (`free_space`); each of the rule's conditions alone
  // withholds it.
  const SeenThroughWall scene;
  const DetectorParameters& params = scene.params;
  ASSERT_GT(params.free_space.votes, 1);  // else the vote count would pass at the first update
  const auto decideOnce = [&](Track t, const std::vector<Eigen::Vector3f>& points) {
    scene.decision.decide(t, points, {});
    return t;
  };
  const Track seen = decideOnce(votedFastTrack(), scene.points);
  EXPECT_TRUE(seen.mover);
  EXPECT_EQ(seen.reason, MoverReason::kFreeSpace);

  Track no_vote = votedFastTrack();
  no_vote.fast.back() = 0;  // still three votes of five, but none from this update
  EXPECT_FALSE(decideOnce(no_vote, scene.points).mover);

  Track occluded = votedFastTrack();
  occluded.features.occluded = true;
  EXPECT_FALSE(decideOnce(occluded, scene.points).mover);

  // Seen only above what hides it: a parked car's top rising into a sensor's lowest beams.
  Track never_tall = votedFastTrack();
  never_tall.max_height = never_tall.features.height = 0.5;
  EXPECT_FALSE(decideOnce(never_tall, scene.points).mover);

  // A centroid track (no model): its speed vote slides with its partial views.
  Track centroid = votedFastTrack();
  centroid.model.reset();
  EXPECT_FALSE(decideOnce(centroid, scene.points).mover);

  // Half of the view on the wall where the stored scans saw it, less than alone_fraction seen
  // through once a few more points lie there.
  std::vector<Eigen::Vector3f> on_wall = scene.points;
  for (int k = 0; k < static_cast<int>(scene.points.size()) + 5; ++k)
    on_wall.emplace_back(20.0f, 0.05f * (k % 9 - 4), 0.1f * (k / 9 - 4));
  const Track half = decideOnce(votedFastTrack(), on_wall);
  EXPECT_FALSE(half.mover);
  EXPECT_EQ(half.reason, MoverReason::kNoFreeSpace);
}
