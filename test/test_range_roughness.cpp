/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
// clusterRoughness() on hand-made range images: 16 rows × 64 columns, every cell of a cluster
// at a range the test chooses, the other cells taking no part (negative range).
#include <pcl_movers/range_roughness.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

using pcl_movers::clusterRoughness;

namespace {

constexpr int kRows = 16, kCols = 64;

struct Image {
  std::vector<float> range = std::vector<float>(kRows * kCols, -1.0f);
  std::vector<int> cell_cluster = std::vector<int>(kRows * kCols, -2);
  std::vector<pcl::PointIndices> clusters;

  /// A cluster filling rows [r0, r1] × columns [c0, c1], cell (r, c) at range_of(r, c).
  void add(int r0, int r1, int c0, int c1, const std::function<float(int, int)>& range_of) {
    pcl::PointIndices cluster;
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        const auto cell = static_cast<std::size_t>(r * kCols + c);
        range[cell] = range_of(r, c);
        cluster.indices.push_back(r * kCols + c);
        cell_cluster[cell] = static_cast<int>(clusters.size());
      }
    clusters.push_back(cluster);
  }
  std::vector<float> roughness() const {
    std::vector<float> out;
    clusterRoughness(range, kCols, cell_cluster, clusters, out);
    return out;
  }
};

}  // namespace

TEST(RangeRoughness, SolidSurfacesAreSmoothFoliageIsRough) {
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 0.02f);             // a sensor's range noise
  std::exponential_distribution<float> penetration(1.0f / 0.5f);  // rays ending inside foliage
  Image image;
  image.add(2, 13, 2, 12, [&](int, int) { return 20.0f + noise(rng); });  // a walker, a car's back
  // A car's side seen nearly along the line of sight: each column 0.3 m further than the last,
  // the rows of a column at one range.
  image.add(2, 13, 20, 35, [&](int, int c) { return 15.0f + 0.3f * (c - 20) + noise(rng); });
  image.add(0, 15, 40, 60, [&](int, int) { return 25.0f + penetration(rng); });  // a tree
  const auto rough = image.roughness();
  EXPECT_LT(rough[0], 0.05f);
  EXPECT_LT(rough[1], 0.05f);  // the smaller of rows and columns: the columns are smooth
  EXPECT_GT(rough[2], 0.2f);   // about the median step between two penetration depths
}

TEST(RangeRoughness, OneRowIsJudgedAlongItAndTooFewPairsAreUnknown) {
  Image image;
  image.add(5, 5, 10, 30, [](int, int c) { return 10.0f + ((c % 2) != 0 ? 0.6f : 0.0f); });
  image.add(9, 10, 40, 40, [](int, int) { return 10.0f; });  // one column of two cells
  const auto rough = image.roughness();
  EXPECT_NEAR(rough[0], 0.6f, 0.01f);
  EXPECT_TRUE(std::isnan(rough[1]));
}

TEST(RangeRoughness, OnlyNeighboursOfTheSameClusterCount) {
  // Two smooth clusters side by side at very different ranges: the step between them is not
  // either one's roughness.
  Image image;
  image.add(2, 13, 10, 20, [](int, int) { return 10.0f; });
  image.add(2, 13, 21, 31, [](int, int) { return 30.0f; });
  const auto rough = image.roughness();
  EXPECT_LT(rough[0], 0.01f);
  EXPECT_LT(rough[1], 0.01f);
}
