/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
// findMoverFragments() on a hand-made organized cloud: a range image of 16 rows × 64 columns
// looking along +x, every cell of an object at its range, the rest empty.
#include <pcl_movers/mover_fragments.h>

#include <pcl/point_types.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using pcl_movers::findMoverFragments;

namespace {

constexpr int kRows = 16, kCols = 64;
constexpr float kAzimuthStep = 0.01f, kElevationStep = 0.02f;  // [rad]

struct Scene {
  pcl::PointCloud<pcl::PointXYZ> cloud{kCols, kRows, pcl::PointXYZ()};
  std::vector<pcl::PointIndices> clusters;
  float azimuth_step = kAzimuthStep;  ///< [rad] per column; 2π / kCols: a full turn
  bool wrap_around = false;

  Scene() {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (auto& p : cloud) p.x = p.y = p.z = nan;
  }
  /// A cluster filling rows [r0, r1] × columns [c0, c1] at horizontal range `range`.
  std::size_t add(int r0, int r1, int c0, int c1, float range) {
    pcl::PointIndices cluster;
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        const float azimuth = (c - kCols / 2) * azimuth_step;
        const float elevation = (kRows / 2 - r) * kElevationStep;
        auto& p = cloud.at(c, r);
        p.x = range * std::cos(azimuth);
        p.y = range * std::sin(azimuth);
        p.z = range * std::tan(elevation);
        cluster.indices.push_back(r * kCols + c);
      }
    clusters.push_back(cluster);
    return clusters.size() - 1;
  }
  std::vector<int> fragments(const std::vector<bool>& mover, float margin = 0.5f,
                             const std::vector<int>& born_part_of = {}) const {
    // Boxes along the columns' direction (y, across the line of sight) would do as well; x is
    // the mover's heading here.
    return findMoverFragments(cloud, clusters, mover, std::vector<double>(clusters.size(), 0.0),
                              /*max_gap=*/2, margin, wrap_around, born_part_of);
  }
};

}  // namespace

TEST(MoverFragments, APartSplitOffAtARangeStepBelongsToItsMover) {
  // A car's body at 10 m (columns 20-39: ~2 m wide across the line of sight) and its wheels
  // 0.4 m further, in the rows just below: region growing splits them at the range step.
  Scene s;
  const auto body = s.add(4, 9, 20, 39, 10.0f);
  const auto wheels = s.add(10, 11, 22, 37, 10.4f);
  const auto owner = s.fragments({true, false});
  EXPECT_EQ(owner[wheels], static_cast<int>(body));
  EXPECT_EQ(owner[body], -1);  // a mover is nobody's fragment
}

TEST(MoverFragments, AStaticObjectReachingBeyondTheMoversBoxIsNot) {
  // A wall behind a walker: it touches the walker in the image, but reaches metres beyond the
  // walker's box across the line of sight.
  Scene s;
  s.add(4, 12, 30, 33, 10.0f);                    // walker: ~0.3 m wide
  const auto wall = s.add(2, 14, 10, 29, 10.3f);  // 10 columns at 10.3 m: ~2 m to its side
  EXPECT_EQ(s.fragments({true, false})[wall], -1);
}

TEST(MoverFragments, APartFarBehindTheMoverIsNot) {
  // Touching in the image but 3 m further along the line of sight: not within the box.
  Scene s;
  s.add(4, 9, 20, 39, 10.0f);
  const auto behind = s.add(10, 11, 22, 37, 13.0f);
  EXPECT_EQ(s.fragments({true, false})[behind], -1);
  // With a margin that reaches it, it is taken: the box, not the range step, decides.
  EXPECT_EQ(s.fragments({true, false}, 3.5f)[behind], 0);
}

TEST(MoverFragments, OnlyClustersTouchingTheMoverInTheImage) {
  // Within the box but five rows below (beyond max_gap + 1): another object, not a split part.
  Scene s;
  s.add(2, 6, 20, 39, 10.0f);
  const auto apart = s.add(12, 13, 22, 37, 10.0f);
  EXPECT_EQ(s.fragments({true, false})[apart], -1);
  // Three rows below (two empty rows between): what region growing would bridge.
  Scene t;
  t.add(2, 6, 20, 39, 10.0f);
  const auto near = t.add(9, 10, 22, 37, 10.4f);
  EXPECT_EQ(t.fragments({true, false})[near], 0);
}

TEST(MoverFragments, NoMoverNoFragmentsAndMoversKeepTheirOwnPoints) {
  Scene s;
  s.add(4, 9, 20, 39, 10.0f);
  s.add(10, 11, 22, 37, 10.4f);
  EXPECT_EQ(s.fragments({false, false}), std::vector<int>({-1, -1}));
  EXPECT_EQ(s.fragments({true, true}), std::vector<int>({-1, -1}));
}

TEST(MoverFragments, TheColumnSeamOfAFullTurnJoinsAsInRegionGrowing) {
  // A 360° image: columns 0 and 63 are neighbours. A mover at 2 m in the last four columns,
  // and its part split off 0.1 m behind it in the first two, across the seam.
  Scene s;
  s.azimuth_step = 2.0f * static_cast<float>(M_PI) / kCols;
  s.add(4, 9, 60, 63, 2.0f);
  const auto part = s.add(4, 9, 0, 1, 2.1f);
  s.wrap_around = true;
  EXPECT_EQ(s.fragments({true, false})[part], 0);
  s.wrap_around = false;  // a sensor with a narrower field of view: the edges are apart
  EXPECT_EQ(s.fragments({true, false})[part], -1);
}

TEST(MoverFragments, AMoverBornAsALargerMoversPartIsItsPart) {
  // A car's body and its front split off at a range step, each tracked as a mover.
  Scene s;
  const auto body = s.add(4, 9, 20, 39, 10.0f);
  const auto front = s.add(10, 11, 22, 37, 10.4f);
  const std::vector<bool> movers{true, true};
  // The front's track was born as the body's fragment: it is a part.
  auto owner = s.fragments(movers, 0.5f, {-1, static_cast<int>(body)});
  EXPECT_EQ(owner[front], static_cast<int>(body));
  EXPECT_EQ(owner[body], -1);
  // Born on its own (a walker met later beside the car): never a part, however close.
  EXPECT_EQ(s.fragments(movers, 0.5f, {-1, -1}), std::vector<int>({-1, -1}));
  EXPECT_EQ(s.fragments(movers), std::vector<int>({-1, -1}));
}

TEST(MoverFragments, AMoverBornAPartIsNoneWhenItNoLongerFits) {
  // The part's track, born on the body, has drifted off the body's grown box (its own object
  // after all): the geometric test still applies.
  Scene s;
  const auto body = s.add(4, 9, 20, 39, 10.0f);
  const auto far = s.add(10, 11, 22, 37, 13.0f);
  EXPECT_EQ(s.fragments({true, true}, 0.5f, {-1, static_cast<int>(body)})[far], -1);
}

TEST(MoverFragments, APartOfAPartBelongsToTheLargestMover) {
  // Body, a mover part of it (its front), and a static part of that front (a wheel): both go to
  // the body, so that a fragment's owner is never a fragment.
  Scene s;
  const auto body = s.add(4, 9, 20, 39, 10.0f);
  const auto front = s.add(10, 11, 22, 37, 10.4f);
  const auto wheel = s.add(12, 12, 24, 30, 10.6f);
  const auto owner = s.fragments({true, true, false}, 0.5f, {-1, static_cast<int>(body), -1});
  EXPECT_EQ(owner[front], static_cast<int>(body));
  EXPECT_EQ(owner[wheel], static_cast<int>(body));
}
