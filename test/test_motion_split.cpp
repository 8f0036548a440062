/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <gtest/gtest.h>
#include <pcl_movers/motion_split.h>

#include <vector>

namespace {

using Sight = pcl_movers::FreeSpaceMap::Sight;
using Sights = std::vector<std::vector<Sight>>;

/** A judge that answers from `sights` (per cluster, per point). */
pcl_movers::MotionSplitter::Judge judgeFrom(const Sights& sights) {
  return [&sights](std::size_t c, const std::vector<int>& positions, std::vector<Sight>& out) {
    out.clear();
    for (const int k : positions) out.push_back(sights[c][static_cast<std::size_t>(k)]);
  };
}

/** The distances of a cluster's points, read from a range image. */
pcl_movers::MotionSplitter::Ranges rangesFrom(const std::vector<float>& image,
                                              const std::vector<pcl::PointIndices>& clusters) {
  return [&image, &clusters](std::size_t c, std::vector<float>& out) {
    out.clear();
    for (const int i : clusters[c].indices) out.push_back(image[static_cast<std::size_t>(i)]);
  };
}

/** A 12 × 60 range image holding one cluster: a wall at 10 m (seen where it is) with, in front of
 * it, a walker-sized block of cells 0.5 m nearer (rows 2-9, columns 20-25) seen as `walker`. */
struct WallAndWalker {
  static constexpr int kWidth = 60, kHeight = 12;
  std::vector<float> ranges = std::vector<float>(kWidth * kHeight, 0.0f);
  std::vector<pcl::PointIndices> clusters = std::vector<pcl::PointIndices>(1);
  std::vector<std::vector<Sight>> sights = std::vector<std::vector<Sight>>(1);
  explicit WallAndWalker(Sight walker) {
    for (int r = 0; r < kHeight; ++r)
      for (int c = 0; c < kWidth; ++c) {
        const bool on_walker = r >= 2 && r <= 9 && c >= 20 && c <= 25;
        ranges[r * kWidth + c] = on_walker ? 9.5f : 10.0f;
        clusters[0].indices.push_back(r * kWidth + c);
        sights[0].push_back(on_walker ? walker : Sight::kAt);
      }
  }
};

bool isWalkerCell(int i) {
  const int r = i / WallAndWalker::kWidth, c = i % WallAndWalker::kWidth;
  return r >= 2 && r <= 9 && c >= 20 && c <= 25;
}

}  // namespace

TEST(MotionSplitter, SplitsTheSeenThroughPartOffTheStaticRest) {
  WallAndWalker scene(Sight::kThrough);
  // The wall cells the walker hid back then are no static evidence; they stay with the wall
  // since they lie a depth step behind the walker.
  for (int c = 26; c <= 29; ++c)
    for (int r = 2; r <= 9; ++r) scene.sights[0][r * WallAndWalker::kWidth + c] = Sight::kBefore;
  pcl_movers::MotionSplitter splitter;
  ASSERT_EQ(splitter.split(WallAndWalker::kWidth, WallAndWalker::kHeight, scene.clusters,
                           judgeFrom(scene.sights), rangesFrom(scene.ranges, scene.clusters)),
            1);
  const auto& out = scene.clusters;
  ASSERT_EQ(out.size(), 2u);  // the wall in the cluster's place, the walker appended
  EXPECT_EQ(out[0].indices.size(), WallAndWalker::kWidth * WallAndWalker::kHeight - 48u);
  ASSERT_EQ(out[1].indices.size(), 48u);
  for (const int i : out[1].indices) EXPECT_TRUE(isWalkerCell(i)) << i;
  for (const int i : out[0].indices) EXPECT_FALSE(isWalkerCell(i)) << i;
}

// The detector splits a cluster's cells and its world points alike (findSplits() once, then
// applySplits() on both lists): a list whose indices correspond position by position to the
// clusters' stays in step with them, whatever its own index order.
TEST(MotionSplitter, AppliesASplitToACorrespondingListPositionByPosition) {
  WallAndWalker scene(Sight::kThrough);
  scene.clusters.push_back(scene.clusters[0]);  // a second, static cluster before the parts
  scene.sights.push_back(std::vector<Sight>(scene.sights[0].size(), Sight::kAt));
  std::vector<pcl::PointIndices> world(scene.clusters.size());
  const auto worldIndexOf = [](int cell) { return 7 * (1000 - cell); };  // descending order
  for (std::size_t c = 0; c < world.size(); ++c)
    for (const int i : scene.clusters[c].indices) world[c].indices.push_back(worldIndexOf(i));
  pcl_movers::MotionSplitter splitter;
  const auto splits =
      splitter.findSplits(WallAndWalker::kWidth, WallAndWalker::kHeight, scene.clusters,
                          judgeFrom(scene.sights), rangesFrom(scene.ranges, scene.clusters));
  ASSERT_EQ(splits.size(), 1u);
  EXPECT_EQ(splits[0].cluster, 0u);
  EXPECT_EQ(splitter.applySplits(splits, scene.clusters), 1);
  EXPECT_EQ(splitter.applySplits(splits, world), 1);
  ASSERT_EQ(scene.clusters.size(), 3u);  // wall rest, the static cluster, the walker
  ASSERT_EQ(world.size(), 3u);
  EXPECT_EQ(scene.clusters[2].indices.size(), 48u);
  for (std::size_t c = 0; c < world.size(); ++c) {
    ASSERT_EQ(world[c].indices.size(), scene.clusters[c].indices.size()) << c;
    for (std::size_t k = 0; k < world[c].indices.size(); ++k)
      EXPECT_EQ(world[c].indices[k], worldIndexOf(scene.clusters[c].indices[k])) << c << " " << k;
  }
}

// Splits whose static rests are under min_points remove their clusters, in whatever order the
// splits come; the parts follow the clusters in the splits' order.
TEST(MotionSplitter, AppliedSplitsRemoveClustersLeftWithTooFewPointsInAnyOrder) {
  std::vector<pcl::PointIndices> clusters(3);
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 20; ++k) clusters[c].indices.push_back(100 * c + k);
  std::vector<int> all_but_three(17);
  for (int k = 0; k < 17; ++k) all_but_three[k] = k + 3;  // a rest of 3 < min_points (8)
  const std::vector<pcl_movers::MotionSplitter::ClusterSplit> splits = {{1, {all_but_three}},
                                                                        {0, {all_but_three}}};
  pcl_movers::MotionSplitter splitter;
  EXPECT_EQ(splitter.applySplits(splits, clusters), 2);
  ASSERT_EQ(clusters.size(), 3u);  // cluster 2, then the parts of clusters 1 and 0
  EXPECT_EQ(clusters[0].indices.size(), 20u);
  EXPECT_EQ(clusters[0].indices.front(), 200);
  EXPECT_EQ(clusters[1].indices.front(), 103);
  EXPECT_EQ(clusters[2].indices.front(), 3);
  EXPECT_EQ(clusters[2].indices.size(), 17u);
}

TEST(MotionSplitter, GrowsOverHiddenPointsOfThePartsSurfaceOnly) {
  WallAndWalker scene(Sight::kThrough);
  // The walker's lower half was hidden back then (by something nearer): it continues the
  // seen-through upper half's surface and goes with it.
  for (int r = 6; r <= 9; ++r)
    for (int c = 20; c <= 25; ++c) scene.sights[0][r * WallAndWalker::kWidth + c] = Sight::kBefore;
  pcl_movers::MotionSplitter splitter;
  ASSERT_EQ(splitter.split(WallAndWalker::kWidth, WallAndWalker::kHeight, scene.clusters,
                           judgeFrom(scene.sights), rangesFrom(scene.ranges, scene.clusters)),
            1);
  EXPECT_EQ(scene.clusters.back().indices.size(), 48u);
}

TEST(MotionSplitter, LeavesClustersWithoutBothAMovingAndAStaticPart) {
  pcl_movers::MotionSplitter splitter;
  // A walker standing by the wall: seen where it is.
  WallAndWalker standing(Sight::kAt);
  EXPECT_EQ(
      splitter.split(WallAndWalker::kWidth, WallAndWalker::kHeight, standing.clusters,
                     judgeFrom(standing.sights), rangesFrom(standing.ranges, standing.clusters)),
      0);
  ASSERT_EQ(standing.clusters.size(), 1u);
  EXPECT_EQ(standing.clusters[0].indices.size(),
            size_t{WallAndWalker::kWidth * WallAndWalker::kHeight});
  // A cluster seen through everywhere it was tested (a mover alone, or two joined) is whole.
  WallAndWalker moving(Sight::kThrough);
  for (auto& s : moving.sights[0])
    if (s == Sight::kAt) s = Sight::kUnknown;
  EXPECT_EQ(splitter.split(WallAndWalker::kWidth, WallAndWalker::kHeight, moving.clusters,
                           judgeFrom(moving.sights), rangesFrom(moving.ranges, moving.clusters)),
            0);
  ASSERT_EQ(moving.clusters.size(), 1u);
  // A few seen-through points on a wall (a gap in foliage, a pose error) are no part.
  WallAndWalker speckled(Sight::kAt);
  for (int k = 0; k < 20; ++k)
    speckled.sights[0][k * 31 % speckled.sights[0].size()] = Sight::kThrough;
  EXPECT_EQ(
      splitter.split(WallAndWalker::kWidth, WallAndWalker::kHeight, speckled.clusters,
                     judgeFrom(speckled.sights), rangesFrom(speckled.ranges, speckled.clusters)),
      0);
}
