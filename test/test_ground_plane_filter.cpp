/*
 * Tests of pcl_movers::GroundPlaneFilter on synthetic terrain with known answers (flat, ramp,
 * rolling hills, kerb, boxes and walls on top) and, when present, on a labelled KITTI scan.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/segmentation_metrics.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <random>
#include <set>

using pcl_movers::GroundPlaneFilter;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace {

constexpr float kSensorHeight = 1.73f;

/** A synthetic scan: ground points on a polar pattern like a spinning LiDAR's (denser near),
 * plus object points, each flagged with its truth. */
struct Scene {
  Cloud::Ptr cloud{new Cloud};
  std::vector<int> is_ground;  ///< 1 ground, 0 object, -1 not scored

  void add(float x, float y, float z, int ground) {
    cloud->push_back(pcl::PointXYZ(x, y, z));
    is_ground.push_back(ground);
  }
};

/** Ground z(x, y) sampled on rings 3..70 m (spacing growing with range) at 0.5° azimuth steps,
 * with a little noise. */
Scene makeGround(const std::function<float(float, float)>& z_of, unsigned seed = 1) {
  Scene scene;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, 0.02f);
  for (float r = 3.f; r < 70.f; r *= 1.04f)
    for (float az = -180.f; az < 180.f; az += 0.5f) {
      const float x = r * std::cos(az * float(M_PI) / 180.f);
      const float y = r * std::sin(az * float(M_PI) / 180.f);
      scene.add(x, y, z_of(x, y) + noise(rng), 1);
    }
  return scene;
}

/** A box's vertical faces from `bottom` to `bottom + height` above the terrain. */
void addBox(Scene& scene, const std::function<float(float, float)>& z_of, float cx, float cy,
            float length, float width, float height) {
  const float step = 0.1f;
  const float base = z_of(cx, cy);
  for (float h = 0.f; h <= height; h += step)
    for (float t = -0.5f; t <= 0.5f; t += step / std::max(length, width)) {
      const float z = base + h;
      // The lowest 30 cm of an object cannot be told from ground by height alone (it is
      // within the classification threshold): not scored. Everything above must be non-ground.
      const int ground = h < 0.3f ? -1 : 0;
      scene.add(cx + t * length, cy - width / 2, z, ground);
      scene.add(cx + t * length, cy + width / 2, z, ground);
      scene.add(cx - length / 2, cy + t * width, z, ground);
      scene.add(cx + length / 2, cy + t * width, z, ground);
    }
}

struct Score {
  double precision = 0, recall = 0;
  std::size_t object_points_as_ground_high = 0;  ///< object points > 0.3 m up called ground
};

/** Precision/recall of the filter's ground output against the scene's truth. */
Score score(const Scene& scene, const pcl::Indices& ground) {
  std::vector<bool> called(scene.cloud->size(), false);
  for (const auto i : ground) called[i] = true;
  std::size_t tp = 0, fp = 0, fn = 0;
  for (std::size_t i = 0; i < called.size(); ++i) {
    if (scene.is_ground[i] < 0) continue;
    if (called[i] && scene.is_ground[i]) ++tp;
    if (called[i] && !scene.is_ground[i]) ++fp;
    if (!called[i] && scene.is_ground[i]) ++fn;
  }
  Score s;
  s.precision = tp + fp ? double(tp) / double(tp + fp) : 0.0;
  s.recall = tp + fn ? double(tp) / double(tp + fn) : 0.0;
  return s;
}

pcl::Indices groundOf(const Cloud::Ptr& cloud) {
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(cloud);
  filter.setNegative(true);  // ground
  pcl::Indices ground;
  filter.filter(ground);
  return ground;
}

void expectGoodSeparation(const std::function<float(float, float)>& z_of, const char* name) {
  Scene scene = makeGround(z_of);
  addBox(scene, z_of, 12.f, 4.f, 4.5f, 1.8f, 1.5f);    // car
  addBox(scene, z_of, -8.f, -6.f, 0.6f, 0.6f, 1.8f);   // person
  addBox(scene, z_of, 30.f, -10.f, 4.5f, 1.8f, 1.5f);  // far car
  addBox(scene, z_of, 5.f, 20.f, 20.f, 0.3f, 3.f);     // wall
  const Score s = score(scene, groundOf(scene.cloud));
  EXPECT_GT(s.precision, 0.97) << name;
  EXPECT_GT(s.recall, 0.97) << name;
}

}  // namespace

TEST(GroundPlaneFilter, FlatGroundWithObjects) {
  expectGoodSeparation([](float, float) { return -kSensorHeight; }, "flat");
}

TEST(GroundPlaneFilter, RampAheadOfTheVehicle) {
  // Flat to 10 m, then an 8 % ramp up: 4.8 m higher at 70 m, far above any global plane's
  // threshold.
  expectGoodSeparation(
      [](float x, float) { return -kSensorHeight + (x > 10.f ? 0.08f * (x - 10.f) : 0.f); },
      "ramp");
}

TEST(GroundPlaneFilter, RollingTerrain) {
  expectGoodSeparation(
      [](float x, float y) {
        return -kSensorHeight + 1.2f * std::sin(x / 14.f) * std::cos(y / 17.f) +
               0.4f * std::sin((x + y) / 9.f) * (std::hypot(x, y) / 70.f);
      },
      "rolling");
}

TEST(GroundPlaneFilter, KerbAndSidewalkAreGround) {
  // Road, a 15 cm kerb at y = 5 m, sidewalk beyond: both sides are ground.
  expectGoodSeparation([](float, float y) { return -kSensorHeight + (y > 5.f ? 0.15f : 0.f); },
                       "kerb");
}

TEST(GroundPlaneFilter, AGlobalThresholdFailsOnTheRamp) {
  // Sanity check of the test itself: on the ramp a fixed height threshold loses the far ground,
  // so the local planes above are what makes RampAheadOfTheVehicle pass.
  auto z_of = [](float x, float) { return -kSensorHeight + (x > 10.f ? 0.08f * (x - 10.f) : 0.f); };
  Scene scene = makeGround(z_of);
  pcl::Indices ground;
  for (std::size_t i = 0; i < scene.cloud->size(); ++i)
    if ((*scene.cloud)[i].z < -kSensorHeight + 0.25f) ground.push_back(static_cast<int>(i));
  EXPECT_LT(score(scene, ground).recall, 0.9);
}

TEST(GroundPlaneFilter, NegativeAndDefaultAreComplementary) {
  auto z_of = [](float, float) { return -kSensorHeight; };
  Scene scene = makeGround(z_of);
  addBox(scene, z_of, 10.f, 0.f, 4.f, 2.f, 1.5f);
  scene.add(std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f, 0);

  GroundPlaneFilter<pcl::PointXYZ> filter(true);
  filter.setInputCloud(scene.cloud);
  pcl::Indices non_ground, ground;
  filter.filter(non_ground);
  const pcl::Indices removed_non_ground = *filter.getRemovedIndices();
  filter.setNegative(true);
  filter.filter(ground);

  std::set<int> all(non_ground.begin(), non_ground.end());
  for (const auto i : ground) EXPECT_TRUE(all.insert(i).second) << "point " << i << " in both";
  // Every finite point is in exactly one output; the NaN point in neither.
  EXPECT_EQ(all.size(), scene.cloud->size() - 1);
  EXPECT_EQ(all.count(static_cast<int>(scene.cloud->size() - 1)), 0u);
  // The removed indices of the default mode are the ground plus the NaN point.
  EXPECT_EQ(removed_non_ground.size(), ground.size() + 1);
  EXPECT_FALSE(non_ground.empty());
  EXPECT_GT(ground.size(), non_ground.size());
  // Output order follows input order.
  EXPECT_TRUE(std::is_sorted(non_ground.begin(), non_ground.end()));
}

TEST(GroundPlaneFilter, KeepOrganizedKeepsLayout) {
  // An organized 10 x N cloud: ground rows and object rows.
  auto z_of = [](float, float) { return -kSensorHeight; };
  Scene scene = makeGround(z_of);
  const std::size_t width = 100;
  scene.cloud->resize(width * 10);
  scene.cloud->width = static_cast<std::uint32_t>(width);
  scene.cloud->height = 10;
  for (std::size_t c = 0; c < width; ++c)  // the first row: a wall 1 m up at 8 m
    (*scene.cloud)[c] = pcl::PointXYZ(8.f, -5.f + 0.1f * float(c), -0.7f);

  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(scene.cloud);
  filter.setKeepOrganized(true);
  Cloud out;
  filter.filter(out);
  ASSERT_EQ(out.size(), scene.cloud->size());
  EXPECT_EQ(out.width, scene.cloud->width);
  EXPECT_EQ(out.height, scene.cloud->height);
  EXPECT_FALSE(out.is_dense);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < out.size(); ++i)
    if (std::isfinite(out[i].x)) {
      ++kept;
      EXPECT_LT(i, width) << "a ground point survived";
      EXPECT_EQ(out[i].z, (*scene.cloud)[i].z);
    }
  EXPECT_GT(kept, width * 9 / 10);
}

TEST(GroundPlaneFilter, FollowsTheSensorOrigin) {
  // The same scene shifted by (50, -20, 7) with sensor_origin_ set accordingly classifies alike.
  auto z_of = [](float x, float) { return -kSensorHeight + (x > 10.f ? 0.08f * (x - 10.f) : 0.f); };
  Scene scene = makeGround(z_of);
  addBox(scene, z_of, 12.f, 4.f, 4.5f, 1.8f, 1.5f);
  const Score reference = score(scene, groundOf(scene.cloud));
  const Eigen::Vector3f shift(50.f, -20.f, 7.f);
  for (auto& p : *scene.cloud) p.getVector3fMap() += shift;
  scene.cloud->sensor_origin_ = Eigen::Vector4f(shift.x(), shift.y(), shift.z(), 0.f);
  const Score shifted = score(scene, groundOf(scene.cloud));
  EXPECT_GT(shifted.recall, 0.97);
  EXPECT_NEAR(shifted.precision, reference.precision, 0.01);
  EXPECT_NEAR(shifted.recall, reference.recall, 0.01);
}

TEST(GroundPlaneFilter, Deterministic) {
  auto z_of = [](float x, float y) {
    return -kSensorHeight + 0.5f * std::sin(x / 10.f + y / 13.f);
  };
  Scene scene = makeGround(z_of, 7);
  addBox(scene, z_of, 10.f, 0.f, 4.f, 2.f, 1.5f);
  EXPECT_EQ(groundOf(scene.cloud), groundOf(scene.cloud));
}

TEST(GroundPlaneFilter, EmptyAndNanOnlyInputs) {
  GroundPlaneFilter<pcl::PointXYZ> filter(true);
  Cloud::Ptr empty(new Cloud);
  filter.setInputCloud(empty);
  pcl::Indices out{1, 2, 3};
  filter.filter(out);
  EXPECT_TRUE(out.empty());

  Cloud::Ptr nans(new Cloud);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < 50; ++i) nans->push_back(pcl::PointXYZ(nan, nan, nan));
  nans->is_dense = false;
  filter.setInputCloud(nans);
  filter.filter(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(filter.getRemovedIndices()->size(), 50u);
  filter.setNegative(true);
  filter.filter(out);
  EXPECT_TRUE(out.empty());
}

TEST(GroundPlaneFilter, InvalidParametersGiveNoOutput) {
  auto z_of = [](float, float) { return -kSensorHeight; };
  Scene scene = makeGround(z_of);
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(scene.cloud);
  filter.setRingEdges({5.f, 3.f});
  pcl::Indices out;
  filter.filter(out);
  EXPECT_TRUE(out.empty());
}

TEST(GroundPlaneFilter, KittiSemanticLabels) {
  const std::string dir = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-odometry-00";
  if (!std::filesystem::exists(dir + "/labels/000000.label"))
    GTEST_SKIP() << "KITTI odometry data not found in " << dir;
  pcl::PointCloud<pcl::PointXYZI>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZI>);
  pcl_movers::io::readScan(dir + "/velodyne/000000.bin", *cloud);
  const auto labels = pcl_movers::io::readLabels(dir + "/labels/000000.label");
  ASSERT_EQ(labels.size(), cloud->size());

  GroundPlaneFilter<pcl::PointXYZI> filter;
  filter.setInputCloud(cloud);
  filter.setNegative(true);
  pcl::Indices ground;
  filter.filter(ground);
  std::vector<std::uint8_t> called(cloud->size(), 0);
  for (const auto i : ground) called[i] = 1;
  const auto score =
      pcl_movers::eval::scoreGround(pcl_movers::eval::groundTruthFromLabels(labels), called);
  const double precision = score.precision(), recall = score.recall();
  // Generous bounds (pcl_movers_eval_segmentation prints the exact numbers). Much of the
  // remaining false ground is SemanticKITTI "vegetation" lying at ground level.
  EXPECT_GT(precision, 0.85);
  EXPECT_GT(recall, 0.95);
}
