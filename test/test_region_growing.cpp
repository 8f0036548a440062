/*
 * Tests of pcl_movers::RangeImageRegionGrowing on small ray-cast range images with known objects.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/segmentation_metrics.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/range_image_region_growing.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <vector>

using pcl_movers::RangeImageRegionGrowing;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace {

struct Box {
  Eigen::Vector3f min, max;
};

/** Ray-casts axis-aligned boxes into an organized cloud: `rows` beams from +10° to -10°, `columns`
 * azimuth steps over 360° (column 0 looks backwards, azimuth decreasing with column as in
 * SensorModel). Misses are NaN. */
Cloud::Ptr rayCast(const std::vector<Box>& boxes, int rows = 32, int columns = 720) {
  Cloud::Ptr cloud(new Cloud(columns, rows));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const float elevation = (10.f - 20.f * float(r) / float(rows - 1)) * float(M_PI) / 180.f;
      const float azimuth = float(M_PI) - (float(c) + 0.5f) * 2.f * float(M_PI) / float(columns);
      const Eigen::Vector3f dir(std::cos(elevation) * std::cos(azimuth),
                                std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      float best = std::numeric_limits<float>::infinity();
      for (const auto& box : boxes) {  // slab method
        float t0 = 0.f, t1 = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) {
          const float inv = 1.f / dir[a];
          float ta = box.min[a] * inv, tb = box.max[a] * inv;
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
        }
        if (t0 <= t1 && t0 > 0.f) best = std::min(best, t0);
      }
      auto& p = cloud->at(c, r);
      if (std::isfinite(best))
        p.getVector3fMap() = best * dir;
      else
        p.x = p.y = p.z = nan;
    }
  cloud->is_dense = false;
  return cloud;
}

/** Region growing with the given rules; the row bridge is off unless asked for, so the tests of
 * the 8-neighbour and gap rules see those rules alone. */
std::vector<pcl::PointIndices> segment(const Cloud::Ptr& cloud, float k = 0.05f, bool wrap = true,
                                       int gap = 2, float bridge = 0.f) {
  RangeImageRegionGrowing<pcl::PointXYZ> rg;
  rg.setInputCloud(cloud);
  rg.setDepthThresholdFactor(k);
  rg.setWrapAround(wrap);
  rg.setMaxGap(gap);
  rg.setBridgeLength(bridge);
  std::vector<pcl::PointIndices> clusters;
  rg.segment(clusters);
  return clusters;
}

std::size_t finiteCount(const Cloud& cloud) {
  std::size_t n = 0;
  for (const auto& p : cloud) n += std::isfinite(p.x);
  return n;
}

/** Indices of the finite points: every return taken as an object point (no ground). */
pcl::Indices finiteIndices(const Cloud& cloud) {
  pcl::Indices indices;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (std::isfinite(cloud[i].x)) indices.push_back(static_cast<int>(i));
  return indices;
}

/** A box in front of the sensor at range `d`, and a second one 1 m further that starts where the
 * first one ends in azimuth (they touch in the range image). Sizes scale with d so both cover the
 * same image cells at any range. */
std::vector<Box> steppedPair(float d) {
  const float s = d / 5.f;
  return {Box{{d, -1.0f * s, -0.6f * s}, {d + 0.5f, 0.0f, 0.6f * s}},
          Box{{d + 1.f, -0.01f * s, -0.6f * s}, {d + 1.5f, 1.0f * s, 0.6f * s}}};
}

}  // namespace

TEST(RangeImageRegionGrowing, DepthProportionalThresholdAt5mAnd60m) {
  // At 5 m a 1 m depth step is 20 % of the range: two objects. At 60 m the same 1 m step is
  // under the 5 % threshold (3 m): one object, as the sampling there cannot resolve the gap.
  const auto near = segment(rayCast(steppedPair(5.f)));
  EXPECT_EQ(near.size(), 2u);
  const auto far = segment(rayCast(steppedPair(60.f)));
  EXPECT_EQ(far.size(), 1u);
  // A fixed (non-proportional) threshold could not do both: with k = 0 and only the 0.1 m floor
  // the far pair splits too.
  EXPECT_GE(segment(rayCast(steppedPair(60.f)), 0.f).size(), 2u);
}

TEST(RangeImageRegionGrowing, SeparateObjectsAndAllPointsAssigned) {
  const std::vector<Box> boxes = {
      {{8.f, -1.f, -1.f}, {12.f, 1.f, 0.5f}},    // car ahead
      {{-6.f, 3.f, -1.f}, {-5.5f, 3.5f, 0.8f}},  // person behind-left
      {{2.f, -20.f, -1.f}, {20.f, -19.f, 2.f}},  // wall on the right
  };
  const auto cloud = rayCast(boxes);
  const auto clusters = segment(cloud);
  ASSERT_EQ(clusters.size(), 3u);
  std::size_t total = 0;
  for (const auto& c : clusters) total += c.indices.size();
  EXPECT_EQ(total, finiteCount(*cloud));
  // Largest first.
  EXPECT_GE(clusters[0].indices.size(), clusters[1].indices.size());
  EXPECT_GE(clusters[1].indices.size(), clusters[2].indices.size());
  // Each cluster lies within one box.
  for (const auto& c : clusters) {
    int box_of_first = -1;
    for (const auto i : c.indices) {
      const Eigen::Vector3f p = (*cloud)[i].getVector3fMap();
      int which = -1;
      for (std::size_t b = 0; b < boxes.size(); ++b)
        if ((p.array() >= boxes[b].min.array() - 1e-3f).all() &&
            (p.array() <= boxes[b].max.array() + 1e-3f).all())
          which = static_cast<int>(b);
      ASSERT_GE(which, 0);
      if (box_of_first < 0) box_of_first = which;
      EXPECT_EQ(which, box_of_first);
    }
  }
}

TEST(RangeImageRegionGrowing, WrapAroundJoinsClusterSplitAtAzimuthPi) {
  // A box straight behind the sensor spans the first and last columns of the image.
  const auto cloud = rayCast({{{-10.f, -1.f, -1.f}, {-9.f, 1.f, 1.f}}});
  ASSERT_TRUE(std::isfinite(cloud->at(0, 16).x));
  ASSERT_TRUE(std::isfinite(cloud->at(cloud->width - 1, 16).x));
  EXPECT_EQ(segment(cloud, 0.05f, true).size(), 1u);
  EXPECT_EQ(segment(cloud, 0.05f, false).size(), 2u);
}

TEST(RangeImageRegionGrowing, GapBridgingOverEmptyCells) {
  const auto cloud = rayCast({{{10.f, -2.f, -1.f}, {11.f, 2.f, 1.f}}});
  // Blank two whole columns through the object (a dark window, a lost return).
  int blanked = 0;
  for (std::uint32_t c = 0; c < cloud->width && blanked < 2; ++c)
    if (std::isfinite(cloud->at(c, 16).x) && std::isfinite(cloud->at(c + 3, 16).x)) {
      for (std::uint32_t r = 0; r < cloud->height; ++r)
        for (std::uint32_t cc = c + 1; cc <= c + 2; ++cc)
          cloud->at(cc, r).x = std::numeric_limits<float>::quiet_NaN();
      blanked = 2;
    }
  ASSERT_EQ(blanked, 2);
  EXPECT_EQ(segment(cloud, 0.05f, true, 0).size(), 2u);  // the paper's strict rule splits it
  EXPECT_EQ(segment(cloud, 0.05f, true, 2).size(), 1u);  // bridging two empty cells joins it
}

/** Number of clusters with at least `min_points` points among `clusters` holding any point of
 * `box`. */
std::size_t clustersIn(const std::vector<pcl::PointIndices>& clusters, const Cloud& cloud,
                       const Box& box) {
  std::size_t n = 0;
  for (const auto& c : clusters)
    for (const auto i : c.indices) {
      const Eigen::Vector3f p = cloud[i].getVector3fMap();
      if ((p.array() >= box.min.array() - 1e-3f).all() &&
          (p.array() <= box.max.array() + 1e-3f).all()) {
        ++n;
        break;
      }
    }
  return n;
}

TEST(RangeImageRegionGrowing, RowBridgeJoinsACarBehindAPole) {
  // A car at 10 m with a 15 cm pole at 6 m in front of it: the pole's cells are nearer, so the
  // strict rule (and the empty-cell gap) cut the car in two. The row bridge looks past them.
  const Box car{{10.f, -2.f, -1.f}, {11.5f, 2.f, 0.5f}};
  const Box pole{{6.f, -0.075f, -1.f}, {6.15f, 0.075f, 1.f}};
  const auto cloud = rayCast({car, pole});
  EXPECT_EQ(clustersIn(segment(cloud, 0.05f, true, 2, 0.f), *cloud, car), 2u);
  const auto bridged = segment(cloud, 0.05f, true, 2, 0.5f);
  EXPECT_EQ(clustersIn(bridged, *cloud, car), 1u);
  EXPECT_EQ(clustersIn(bridged, *cloud, pole), 1u);
  EXPECT_EQ(bridged.size(), 2u);  // the pole stays its own object
  // A wide occluder (1 m at 5 m hides 2 m of the car) is more than the bridge: two pieces.
  const Box wall{{5.f, -0.5f, -1.f}, {5.3f, 0.5f, 1.f}};
  const auto hidden = rayCast({car, wall});
  EXPECT_EQ(clustersIn(segment(hidden, 0.05f, true, 2, 0.5f), *hidden, car), 2u);
}

TEST(RangeImageRegionGrowing, RowBridgeStopsAtBackground) {
  // Two boxes at 10 m, 0.3 m apart sideways. With nothing behind them the gap is empty and within
  // the bridge: one cluster (as Euclidean clustering at 0.5 m). With a wall behind, the gap shows
  // a farther surface, which ends the search: two objects.
  const Box left{{10.f, -1.3f, -1.f}, {11.f, -0.15f, 0.5f}};
  const Box right{{10.f, 0.15f, -1.f}, {11.f, 1.3f, 0.5f}};
  const Box wall{{16.f, -5.f, -5.f}, {16.5f, 5.f, 2.f}};  // fills the gap in every row
  const auto open = rayCast({left, right});
  EXPECT_EQ(segment(open, 0.05f, true, 2, 0.f).size(), 2u);
  EXPECT_EQ(segment(open, 0.05f, true, 2, 0.5f).size(), 1u);
  const auto walled = rayCast({left, right, wall});
  const auto clusters = segment(walled, 0.05f, true, 2, 0.5f);
  EXPECT_EQ(clustersIn(clusters, *walled, left), 1u);
  EXPECT_EQ(clustersIn(clusters, *walled, right), 1u);
  EXPECT_EQ(clusters.size(), 3u);
}

TEST(RangeImageRegionGrowing, ClusterSizeLimits) {
  const std::vector<Box> boxes = {{{8.f, -1.f, -1.f}, {12.f, 1.f, 0.5f}},
                                  {{-6.f, 3.f, -0.2f}, {-5.9f, 3.1f, 0.2f}}};
  const auto cloud = rayCast(boxes);
  const auto all = segment(cloud);
  ASSERT_EQ(all.size(), 2u);
  const int small = static_cast<int>(all[1].indices.size());
  RangeImageRegionGrowing<pcl::PointXYZ> rg;
  rg.setInputCloud(cloud);
  rg.setMinClusterSize(small + 1);
  std::vector<pcl::PointIndices> clusters;
  rg.segment(clusters);
  ASSERT_EQ(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].indices, all[0].indices);
  rg.setMinClusterSize(1);
  rg.setMaxClusterSize(small);
  rg.segment(clusters);
  ASSERT_EQ(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].indices, all[1].indices);
}

TEST(RangeImageRegionGrowing, ReusedSegmenterAndOutputMatchFreshOnes) {
  // segment() reuses its work buffers and the caller's cluster vector (the index vectors keep
  // their capacity between frames): a frame with many clusters followed by one with fewer, and
  // back, must give exactly what a fresh segmenter writes into an empty vector.
  std::vector<Box> many;
  for (int b = 0; b < 6; ++b) {
    const float x = 6.f + 3.f * static_cast<float>(b);
    many.push_back({{x, -8.f + 3.f * static_cast<float>(b), -1.f},
                    {x + 1.f, -7.f + 3.f * static_cast<float>(b), 0.5f}});
  }
  const auto frame_a = rayCast(many);
  const auto frame_b = rayCast({{{8.f, -1.f, -1.f}, {12.f, 1.f, 0.5f}}});
  frame_a->header.frame_id = "a";
  frame_b->header.frame_id = "b";
  RangeImageRegionGrowing<pcl::PointXYZ> reused;
  reused.setBridgeLength(0.5f);
  std::vector<pcl::PointIndices> clusters;
  for (const auto& frame : {frame_a, frame_b, frame_a, frame_b}) {
    RangeImageRegionGrowing<pcl::PointXYZ> fresh;
    fresh.setBridgeLength(0.5f);
    fresh.setInputCloud(frame);
    std::vector<pcl::PointIndices> expected;
    fresh.segment(expected);
    reused.setInputCloud(frame);
    reused.segment(clusters);
    ASSERT_EQ(clusters.size(), expected.size());
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      EXPECT_EQ(clusters[c].indices, expected[c].indices);
      EXPECT_EQ(clusters[c].header.frame_id, frame->header.frame_id);
    }
  }
  EXPECT_EQ(segment(frame_a, 0.05f, true, 2, 0.5f).size(), 6u);
  EXPECT_EQ(segment(frame_b, 0.05f, true, 2, 0.5f).size(), 1u);
}

TEST(RangeImageRegionGrowing, IndicesRestrictTheInput) {
  const auto cloud = rayCast({{{8.f, -1.f, -1.f}, {12.f, 1.f, 0.5f}}});
  const auto all = segment(cloud);
  ASSERT_EQ(all.size(), 1u);
  // Keep only every cell of the left half of the object's columns.
  pcl::IndicesPtr subset(new pcl::Indices);
  std::uint32_t min_col = cloud->width, max_col = 0;
  for (const auto i : all[0].indices) {
    min_col = std::min<std::uint32_t>(min_col, i % cloud->width);
    max_col = std::max<std::uint32_t>(max_col, i % cloud->width);
  }
  for (const auto i : all[0].indices)
    if (i % cloud->width <= (min_col + max_col) / 2) subset->push_back(i);
  RangeImageRegionGrowing<pcl::PointXYZ> rg;
  rg.setInputCloud(cloud);
  rg.setIndices(subset);
  std::vector<pcl::PointIndices> clusters;
  rg.segment(clusters);
  ASSERT_EQ(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].indices, *subset);
}

TEST(RangeImageRegionGrowing, SensorOriginIsTheRangeReference) {
  // The stepped pair at 5 m is two clusters. Moved 100 m away together with the sensor origin it
  // must stay two; measured from the frame origin (ranges ~105 m, threshold ~5 m) it would be one.
  const auto cloud = rayCast(steppedPair(5.f));
  ASSERT_EQ(segment(cloud).size(), 2u);
  const Eigen::Vector3f shift(100.f, -30.f, 4.f);
  for (auto& p : *cloud) p.getVector3fMap() += shift;
  EXPECT_EQ(segment(cloud).size(), 1u);
  cloud->sensor_origin_ = Eigen::Vector4f(shift.x(), shift.y(), shift.z(), 0.f);
  EXPECT_EQ(segment(cloud).size(), 2u);
}

TEST(RangeImageRegionGrowing, EmptyNanAndUnorganizedInputs) {
  std::vector<pcl::PointIndices> clusters(3);
  RangeImageRegionGrowing<pcl::PointXYZ> rg;

  Cloud::Ptr empty(new Cloud);
  rg.setInputCloud(empty);
  rg.segment(clusters);
  EXPECT_TRUE(clusters.empty());

  const auto nans = rayCast({});
  ASSERT_EQ(finiteCount(*nans), 0u);
  clusters.resize(2);
  rg.setInputCloud(nans);
  rg.segment(clusters);
  EXPECT_TRUE(clusters.empty());

  Cloud::Ptr unorganized(new Cloud);
  for (int i = 0; i < 100; ++i) unorganized->push_back(pcl::PointXYZ(10.f, 0.01f * i, 0.f));
  clusters.resize(2);
  rg.setInputCloud(unorganized);
  rg.segment(clusters);
  EXPECT_TRUE(clusters.empty());
}

TEST(RangeImageRegionGrowing, WorksForPointXYZI) {
  pcl::PointCloud<pcl::PointXYZI>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZI>(4, 2));
  for (std::uint32_t c = 0; c < 4; ++c) {
    cloud->at(c, 0).getVector3fMap() = Eigen::Vector3f(10.f, 0.1f * c, 0.f);
    cloud->at(c, 1).getVector3fMap() = Eigen::Vector3f(c < 2 ? 10.f : 20.f, 0.1f * c, -0.1f);
  }
  RangeImageRegionGrowing<pcl::PointXYZI> rg;
  rg.setInputCloud(cloud);
  rg.setWrapAround(false);
  rg.setMinClusterSize(1);  // clusters of 6 and 2 points
  std::vector<pcl::PointIndices> clusters;
  rg.segment(clusters);
  ASSERT_EQ(clusters.size(), 2u);
  EXPECT_EQ(clusters[0].indices, (pcl::Indices{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(clusters[1].indices, (pcl::Indices{6, 7}));
}

TEST(SegmentationMetrics, RecoveredOverAndUnderSegmented) {
  // Instances 1..4 with 40 points each (instance 5 has 10: below min_points, not scored).
  std::vector<int> instance, cluster;
  auto add = [&](int inst, int clus, int count) {
    for (int i = 0; i < count; ++i) {
      instance.push_back(inst);
      cluster.push_back(clus);
    }
  };
  add(1, 0, 40);                  // 1: one clean cluster
  add(2, 1, 20), add(2, 2, 20);   // 2: split in two -> over-segmented
  add(3, 3, 40), add(0, 3, 100);  // 3: whole, but inside a cluster of 140 -> merged
  add(4, -1, 36), add(4, 4, 4);   // 4: mostly removed -> missed
  add(5, 5, 10);
  const auto s = pcl_movers::eval::scoreObjects(instance, cluster, 30, 0.8);
  EXPECT_EQ(s.instances, 4u);
  EXPECT_EQ(s.recovered, 2u);  // 1 and 3
  EXPECT_EQ(s.clean, 1u);      // 1
  EXPECT_EQ(s.over_segmented, 1u);
  EXPECT_EQ(s.under_segmented, 1u);
  EXPECT_EQ(s.missed, 1u);
}

TEST(SegmentationMetrics, StuffInstancesByConnectedComponents) {
  // Two poles 3 m apart (class 80, no instance id) and one car with instance id 7.
  std::vector<std::uint32_t> labels;
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 20; ++i) {
    labels.push_back(80), points.emplace_back(0.f, 0.f, 0.1f * i);
    labels.push_back(80), points.emplace_back(3.f, 0.f, 0.1f * i);
    labels.push_back(pcl_movers::io::makeLabel(10, 7)), points.emplace_back(10.f, 0.1f * i, 0.f);
  }
  const auto inst = pcl_movers::eval::instancesFromLabels(labels, points);
  EXPECT_NE(inst[0], inst[1]);  // the two poles
  EXPECT_EQ(inst[0], inst[3]);  // same pole
  EXPECT_EQ(inst[2], inst[5]);  // the car
  for (const auto i : inst) EXPECT_GT(i, 0);
}

TEST(RangeImageRegionGrowing, KittiObjectsRecovered) {
  const std::string dir = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-odometry-00";
  if (!std::filesystem::exists(dir + "/labels/000000.label"))
    GTEST_SKIP() << "KITTI odometry data not found in " << dir;
  using PointI = pcl::PointXYZI;
  pcl::PointCloud<PointI>::Ptr scan(new pcl::PointCloud<PointI>);
  pcl_movers::io::readScan(dir + "/velodyne/000000.bin", *scan);
  const auto labels = pcl_movers::io::readLabels(dir + "/labels/000000.label");
  ASSERT_EQ(labels.size(), scan->size());
  pcl_movers::RangeImageOrganizer<PointI> organizer;
  organizer.setSensorModel(pcl_movers::SensorModel::hdl64());
  organizer.setInputCloud(scan);
  pcl::PointCloud<PointI>::Ptr image(new pcl::PointCloud<PointI>);
  organizer.organize(*image);
  pcl_movers::GroundPlaneFilter<PointI> ground(true);
  ground.setInputCloud(image);
  ground.setKeepOrganized(true);
  pcl::PointCloud<PointI>::Ptr objects(new pcl::PointCloud<PointI>);
  ground.filter(*objects);
  RangeImageRegionGrowing<PointI> rg;
  rg.setInputCloud(objects);
  std::vector<pcl::PointIndices> clusters;
  rg.segment(clusters);

  const auto& index_image = organizer.getIndexImage();
  std::vector<int> cluster_of(scan->size(), -1);
  std::vector<std::uint8_t> placed(scan->size(), 0);
  for (const auto i : index_image)
    if (i >= 0) placed[i] = 1;
  for (std::size_t k = 0; k < clusters.size(); ++k)
    for (const auto c : clusters[k].indices) cluster_of[index_image[c]] = static_cast<int>(k);
  std::vector<Eigen::Vector3f> points;
  for (const auto& p : *scan) points.push_back(p.getVector3fMap());
  const auto score = pcl_movers::eval::scoreObjects(
      pcl_movers::eval::instancesFromLabels(labels, points), cluster_of, 30, 0.8, &placed);
  ASSERT_GT(score.instances, 10u);
  // Generous bound; the evaluation command prints the exact rates.
  EXPECT_GT(score.rate(score.recovered), 0.8);
}

// A car at 20 m partly hidden by a post at 10 m: the car's cluster ends at the post on one side
// (occluded) and at empty space on the other; the post and a lone box end at empty space only.
TEST(RangeImageRegionGrowing, OccludedSidesFlagTheSideBoundedByANearerObject) {
  const std::vector<Box> boxes{Box{{20.f, -2.f, -1.f}, {22.f, 2.f, 0.5f}},    // car
                               Box{{10.f, 0.8f, -1.f}, {10.5f, 1.4f, 1.5f}},  // post
                               Box{{-15.f, 3.f, -1.f}, {-13.f, 6.f, 0.5f}}};  // lone box
  const Cloud::Ptr cloud = rayCast(boxes);
  const auto clusters = segment(cloud);
  ASSERT_EQ(clusters.size(), 3u);
  const pcl::Indices objects = finiteIndices(*cloud);
  std::vector<std::uint8_t> sides;
  RangeImageRegionGrowing<pcl::PointXYZ>::occludedSides(*cloud, objects, clusters, 0.05f, 0.1f, 2,
                                                        true, 0.3f, sides);
  ASSERT_EQ(sides.size(), 3u);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const auto& p = (*cloud)[clusters[c].indices.front()];
    if (p.x > 15.f) {  // the car: exactly one side occluded
      EXPECT_TRUE(sides[c] == RangeImageRegionGrowing<pcl::PointXYZ>::kOccludedLeft ||
                  sides[c] == RangeImageRegionGrowing<pcl::PointXYZ>::kOccludedRight)
          << int(sides[c]);
    } else {
      EXPECT_EQ(sides[c], 0) << "cluster at x " << p.x;
    }
  }
  // The post taken as ground (not in the objects, no cluster): nothing occludes the car.
  for (const auto& c : clusters) {
    if (!((*cloud)[c.indices.front()].x > 15.f)) continue;
    const std::vector<pcl::PointIndices> car{c};
    RangeImageRegionGrowing<pcl::PointXYZ>::occludedSides(*cloud, c.indices, car, 0.05f, 0.1f, 2,
                                                          true, 0.3f, sides);
    ASSERT_EQ(sides.size(), 1u);
    EXPECT_EQ(sides[0], 0);
  }
}

// A walker's head and shoulders seen over a parked car: hidden from below by the nearer car, so
// its floor is the car's lowest point. The car (nothing below it) and a box in front of a farther
// wall (what is below it is farther) have none.
TEST(RangeImageRegionGrowing, OccluderFloorsFindTheLowestPointOfTheNearerObjectBelow) {
  // The car seen from the side: a thin slab, so that its roof gives no returns of its own.
  const std::vector<Box> boxes{Box{{10.f, -1.f, -1.5f}, {10.2f, 1.f, -0.3f}},      // parked car
                               Box{{14.f, -0.25f, -0.45f}, {14.5f, 0.25f, 0.1f}},  // head
                               Box{{-15.f, 3.f, -0.2f}, {-13.f, 6.f, 0.5f}},       // box
                               Box{{-30.f, -2.f, -3.f}, {-29.f, 12.f, 3.f}}};      // wall
  const Cloud::Ptr cloud = rayCast(boxes);
  const auto clusters = segment(cloud);  // the box cuts the wall in two
  ASSERT_GE(clusters.size(), 4u);
  const pcl::Indices objects = finiteIndices(*cloud);
  std::vector<int> floors;
  RangeImageRegionGrowing<pcl::PointXYZ>::occluderFloors(*cloud, objects, clusters, 0.05f, 0.1f, 2,
                                                         0.5f, floors);
  ASSERT_EQ(floors.size(), clusters.size());
  int heads = 0;
  float car_low = std::numeric_limits<float>::infinity();
  for (const auto& c : clusters)
    if ((*cloud)[c.indices.front()].x > 9.f && (*cloud)[c.indices.front()].x < 10.5f)
      for (const auto i : c.indices) car_low = std::min(car_low, (*cloud)[i].z);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const auto& p = (*cloud)[clusters[c].indices.front()];
    if (p.x > 13.f) {  // the head
      ++heads;
      ASSERT_GE(floors[c], 0);
      EXPECT_FLOAT_EQ((*cloud)[floors[c]].z, car_low);
      EXPECT_LT(car_low, -1.3f);
    } else {
      EXPECT_EQ(floors[c], -1) << "cluster at x " << p.x;
    }
  }
  EXPECT_EQ(heads, 1);
  // The car taken for ground (not among the objects, no cluster): nothing hides the head.
  for (const auto& c : clusters) {
    if (!((*cloud)[c.indices.front()].x > 13.f)) continue;
    const std::vector<pcl::PointIndices> head{c};
    RangeImageRegionGrowing<pcl::PointXYZ>::occluderFloors(*cloud, c.indices, head, 0.05f, 0.1f, 2,
                                                           0.5f, floors);
    ASSERT_EQ(floors.size(), 1u);
    EXPECT_EQ(floors[0], -1);
  }
}

// The detector labels the cells once and hands the labels to both occlusion tests: they must
// answer exactly as the calls that label the cells themselves, and labels of another image size
// (stale ones) are refused (no flags) instead of being read out of bounds.
TEST(RangeImageRegionGrowing, SharedCellLabelsGiveTheSameOcclusionAnswers) {
  using RG = RangeImageRegionGrowing<pcl::PointXYZ>;
  const std::vector<Box> boxes{Box{{20.f, -2.f, -1.f}, {22.f, 2.f, 0.5f}},           // car
                               Box{{10.f, 0.8f, -1.f}, {10.5f, 1.4f, 1.5f}},         // post
                               Box{{9.f, -3.f, -1.5f}, {9.2f, -1.f, -0.3f}},         // low car
                               Box{{13.f, -2.25f, -0.45f}, {13.5f, -1.75f, 0.1f}}};  // head
  const Cloud::Ptr cloud = rayCast(boxes);
  const auto clusters = segment(cloud);
  ASSERT_GE(clusters.size(), 4u);
  const pcl::Indices objects = finiteIndices(*cloud);
  std::vector<std::uint8_t> sides, shared_sides;
  std::vector<int> floors, shared_floors;
  RG::occludedSides(*cloud, objects, clusters, 0.05f, 0.1f, 2, true, 0.3f, sides);
  RG::occluderFloors(*cloud, objects, clusters, 0.05f, 0.1f, 2, 0.5f, floors);
  RG::CellLabels labels;
  RG::cellLabels(*cloud, objects, clusters, labels);
  ASSERT_EQ(labels.label.size(), cloud->size());
  RG::occludedSides(*cloud, labels, clusters, 0.05f, 0.1f, 2, true, 0.3f, shared_sides);
  RG::occluderFloors(*cloud, labels, clusters, 0.05f, 0.1f, 2, 0.5f, shared_floors);
  EXPECT_EQ(shared_sides, sides);
  EXPECT_EQ(shared_floors, floors);
  // The scene has both answers to share: an occluded side (the car behind the post) and a floor
  // (the head above the low car).
  EXPECT_TRUE(std::any_of(sides.begin(), sides.end(), [](std::uint8_t s) { return s != 0; }));
  EXPECT_TRUE(std::any_of(floors.begin(), floors.end(), [](int f) { return f >= 0; }));
  labels.label.pop_back();
  RG::occludedSides(*cloud, labels, clusters, 0.05f, 0.1f, 2, true, 0.3f, shared_sides);
  RG::occluderFloors(*cloud, labels, clusters, 0.05f, 0.1f, 2, 0.5f, shared_floors);
  EXPECT_EQ(shared_sides, std::vector<std::uint8_t>(clusters.size(), 0));
  EXPECT_EQ(shared_floors, std::vector<int>(clusters.size(), -1));
}

// An image narrower than a full turn ends at the edges of the field of view: a car straddling an
// edge is seen in part, as if an occluder hid the rest, and its registered position would slide
// while it enters the view. The same image taken as a full turn joins the car across the seam and
// finds nothing hidden.
TEST(RangeImageRegionGrowing, TheEdgeOfAFieldOfViewHidesLikeANearerObject) {
  using RG = RangeImageRegionGrowing<pcl::PointXYZ>;
  const Cloud::Ptr cloud =
      rayCast({Box{{-12.f, -1.f, -1.f}, {-10.f, 1.f, 1.f}}});  // behind: the seam
  const pcl::Indices objects = finiteIndices(*cloud);
  const auto halves = segment(cloud, 0.05f, false);
  ASSERT_EQ(halves.size(), 2u);
  std::vector<std::uint8_t> sides;
  RG::occludedSides(*cloud, objects, halves, 0.05f, 0.1f, 2, false, 0.3f, sides);
  ASSERT_EQ(sides.size(), 2u);
  for (std::size_t c = 0; c < halves.size(); ++c) {
    const int column = halves[c].indices.front() % static_cast<int>(cloud->width);
    // The half at the first columns is cut on its left (towards column 0), the other on its right.
    EXPECT_EQ(sides[c], column < 10 ? RG::kOccludedLeft : RG::kOccludedRight)
        << "column " << column;
  }
  const auto whole = segment(cloud, 0.05f, true);
  ASSERT_EQ(whole.size(), 1u);
  RG::occludedSides(*cloud, objects, whole, 0.05f, 0.1f, 2, true, 0.3f, sides);
  EXPECT_EQ(sides, std::vector<std::uint8_t>{0});
}
