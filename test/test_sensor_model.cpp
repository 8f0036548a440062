/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/sensor_model.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace {

constexpr float kDeg = float(M_PI / 180.0);
using pcl_movers::InputError;
using pcl_movers::SensorModel;

TEST(SensorModel, PresetsHaveTheDocumentedLayout) {
  struct Expected {
    const char* name;
    int rows, columns;
    float top_deg, bottom_deg;
  };
  for (const Expected& e :
       {Expected{"hdl64", 64, 2200, 1.94f, -25.0f}, Expected{"hdl32", 32, 2048, 10.67f, -30.67f},
        Expected{"vlp16", 16, 1800, 15.f, -15.f}, Expected{"os1_64", 64, 2048, 16.6f, -16.6f},
        Expected{"ladar2d", 60, 360, 9.75f, -19.75f}}) {
    SCOPED_TRACE(e.name);
    const SensorModel m = SensorModel::fromName(e.name);
    EXPECT_EQ(m.name(), e.name);
    EXPECT_EQ(m.rows(), e.rows);
    EXPECT_EQ(m.columns(), e.columns);
    EXPECT_NEAR(m.elevations().front() / kDeg, e.top_deg, 0.01);
    EXPECT_NEAR(m.elevations().back() / kDeg, e.bottom_deg, 0.01);
    for (int r = 0; r + 1 < m.rows(); ++r) EXPECT_GT(m.elevations()[r], m.elevations()[r + 1]);
    EXPECT_EQ(m.verticalOffsets().size(), std::size_t(m.rows()));
  }
  EXPECT_TRUE(SensorModel::hdl64().isFullRevolution());
  EXPECT_FALSE(SensorModel::ladar2d().isFullRevolution());
  EXPECT_NEAR(SensorModel::ladar2d().azimuthMax() - SensorModel::ladar2d().azimuthMin(), 90 * kDeg,
              1e-5);
  // KITTI's lasers sit above the origin: upper block ~0.21 m, lower block ~0.12 m.
  EXPECT_NEAR(SensorModel::hdl64().verticalOffsets().front(), 0.21, 0.01);
  EXPECT_NEAR(SensorModel::hdl64().verticalOffsets().back(), 0.12, 0.01);
}

TEST(SensorModel, UnknownPresetAndBadLayoutsThrow) {
  EXPECT_THROW(SensorModel::fromName("hdl65"), InputError);
  EXPECT_THROW(SensorModel::fromName(""), InputError);
  try {
    SensorModel::fromName("velodyne");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("velodyne"), std::string::npos);
  }
  EXPECT_THROW(SensorModel({}, 100), InputError);
  EXPECT_THROW(SensorModel({0.f}, 0), InputError);
  EXPECT_THROW(SensorModel({std::nanf("")}, 10), InputError);
  EXPECT_THROW(SensorModel({0.f}, 10, 1.f, -1.f), InputError);
  SensorModel m({0.f, 0.1f}, 10);
  EXPECT_THROW(m.setVerticalOffsets({0.f}), InputError);
  EXPECT_THROW(m.setVerticalOffsets({0.f, std::nanf("")}), InputError);
}

TEST(SensorModel, ElevationsAreSortedTopToBottom) {
  const SensorModel m({-0.1f, 0.2f, 0.05f}, 100);
  ASSERT_EQ(m.rows(), 3);
  EXPECT_FLOAT_EQ(m.elevations()[0], 0.2f);
  EXPECT_FLOAT_EQ(m.elevations()[1], 0.05f);
  EXPECT_FLOAT_EQ(m.elevations()[2], -0.1f);
}

TEST(SensorModel, RowOfPicksTheNearestBeamAndRejectsOutside) {
  const SensorModel m = SensorModel::vlp16();  // -15..15 step 2
  for (int r = 0; r < m.rows(); ++r) {
    EXPECT_EQ(m.rowOf(m.elevations()[r]), r);
    EXPECT_EQ(m.rowOf(m.elevations()[r] + 0.9f * kDeg), r);
    EXPECT_EQ(m.rowOf(m.elevations()[r] - 0.9f * kDeg), r);
  }
  EXPECT_EQ(m.rowOf(15.9f * kDeg), 0);
  EXPECT_EQ(m.rowOf(16.1f * kDeg), -1);
  EXPECT_EQ(m.rowOf(-16.1f * kDeg), -1);
  EXPECT_EQ(m.rowOf(std::nanf("")), -1);
}

TEST(SensorModel, ColumnOfInvertsAzimuthOfAndWraps) {
  const SensorModel m = SensorModel::hdl64();
  for (int c = 0; c < m.columns(); ++c) ASSERT_EQ(m.columnOf(m.azimuthOf(c)), c);
  // Column 0 looks backwards, azimuth decreases with the column: forward is the middle.
  EXPECT_EQ(m.columnOf(float(M_PI) - 1e-4f), 0);
  EXPECT_EQ(m.columnOf(0.f), m.columns() / 2);
  EXPECT_EQ(m.columnOf(-float(M_PI) + 1e-4f), m.columns() - 1);
  EXPECT_EQ(m.columnOf(float(3 * M_PI) - 1e-4f), 0);  // wrapped
  const SensorModel ladar = SensorModel::ladar2d();
  EXPECT_EQ(ladar.columnOf(float(M_PI)), -1);  // behind a forward-looking sensor
  EXPECT_EQ(ladar.columnOf(0.f), ladar.columns() / 2);
}

TEST(SensorModel, RowOfPointUsesTheVerticalOffsets) {
  const SensorModel m = SensorModel::hdl64();
  // Points of beam k at any range: z = ρ·tan θ_k + h_k. Near ones are degrees away from θ_k as
  // seen from the origin, yet must land in row k.
  int wrong_without_offsets = 0;
  for (int k = 0; k < m.rows(); ++k)
    for (const float rho : {2.5f, 4.f, 7.f, 15.f, 40.f, 90.f}) {
      const float z = rho * std::tan(m.elevations()[k]) + m.verticalOffsets()[k];
      EXPECT_EQ(m.rowOfPoint(rho, z), k) << "beam " << k << " rho " << rho;
      wrong_without_offsets += m.rowOf(std::atan2(z, rho)) != k;
    }
  EXPECT_GT(wrong_without_offsets, 50);      // the offsets matter
  EXPECT_EQ(m.rowOfPoint(10.f, 10.f), -1);   // 45° up
  EXPECT_EQ(m.rowOfPoint(10.f, -10.f), -1);  // 45° down
  EXPECT_EQ(m.rowOfPoint(0.f, 1.f), -1);
}

/** A synthetic scan of `model`: every beam sees walls at ranges from 3 to 60 m. */
pcl::PointCloud<pcl::PointXYZ> syntheticScan(const SensorModel& model, unsigned seed,
                                             int per_beam = 1500) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> azimuth(-float(M_PI), float(M_PI));
  std::uniform_real_distribution<float> log_range(std::log(3.f), std::log(60.f));
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int k = 0; k < model.rows(); ++k)
    for (int i = 0; i < per_beam; ++i) {
      const float a = azimuth(rng), rho = std::exp(log_range(rng));
      cloud.push_back(
          pcl::PointXYZ(rho * std::cos(a), rho * std::sin(a),
                        rho * std::tan(model.elevations()[k]) + model.verticalOffsets()[k]));
    }
  return cloud;
}

TEST(SensorModel, EstimateRecoversIrregularBeams) {
  // 24 unevenly spaced beams (0.4° to 1.0° apart), no offsets.
  std::vector<float> elevations;
  float e = 3.f;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> spacing(0.4f, 1.0f);
  for (int k = 0; k < 24; ++k, e -= spacing(rng)) elevations.push_back(e * kDeg);
  const SensorModel truth(elevations, 1000);
  const auto cloud = syntheticScan(truth, 1);
  const SensorModel estimated = SensorModel::estimate(cloud);
  ASSERT_EQ(estimated.rows(), truth.rows());
  // Columns from the points per beam (1500, at random azimuths) + 2 %.
  EXPECT_NEAR(estimated.columns(), 1530, 40);
  for (int k = 0; k < truth.rows(); ++k) {
    EXPECT_NEAR(estimated.elevations()[k] / kDeg, truth.elevations()[k] / kDeg, 0.02) << k;
    EXPECT_NEAR(estimated.verticalOffsets()[k], 0.f, 0.01) << k;
  }
  EXPECT_EQ(SensorModel::estimate(cloud, 24, 900).columns(), 900);
}

TEST(SensorModel, EstimateRecoversTwoBlocksWithOffsets) {
  // The KITTI HDL-64E layout: two blocks at different heights above the origin.
  const SensorModel truth = SensorModel::hdl64();
  const auto cloud = syntheticScan(truth, 2, 800);
  const SensorModel estimated = SensorModel::estimate(cloud, 64);
  ASSERT_EQ(estimated.rows(), 64);
  double worst = 0.0;
  for (int k = 0; k < 64; ++k) {
    worst =
        std::max(worst, std::abs(double(estimated.elevations()[k] - truth.elevations()[k])) / kDeg);
    EXPECT_NEAR(estimated.verticalOffsets()[k], truth.verticalOffsets()[k], 0.01) << k;
  }
  EXPECT_LT(worst, 0.02);
}

TEST(SensorModel, EstimateUndoesTheMotionCorrectionOfTheScan) {
  // A scan corrected for the sensor's motion, as KITTI odometry's: each point moved along its ray
  // by the car's travel between its firing and mid-turn, D·(u - 1/2)·cos φ with u the fraction of
  // the turn after the seam behind the car (φ = ±180°) and D = 0.9 m per turn (9 m/s at 10 Hz):
  // the two sides of the seam move by ±0.45 m and each beam splits into two lines there.
  const SensorModel truth = SensorModel::hdl64();
  auto cloud = syntheticScan(truth, 3, 800);
  constexpr float kTravel = 0.9f;
  for (auto& p : cloud) {
    const float phi = std::atan2(p.y, p.x), rho = std::hypot(p.x, p.y);
    const float u = (phi + float(M_PI)) / float(2 * M_PI);
    const float moved = kTravel * (u - 0.5f) * std::cos(phi);
    p.x *= (rho + moved) / rho;
    p.y *= (rho + moved) / rho;
  }
  const SensorModel estimated = SensorModel::estimate(cloud);
  ASSERT_EQ(estimated.rows(), 64);
  double worst = 0.0;
  for (int k = 0; k < 64; ++k) {
    worst =
        std::max(worst, std::abs(double(estimated.elevations()[k] - truth.elevations()[k])) / kDeg);
    EXPECT_NEAR(estimated.verticalOffsets()[k], truth.verticalOffsets()[k], 0.02) << k;
  }
  EXPECT_LT(worst, 0.05);
}

TEST(SensorModel, EstimateRejectsCloudsWithoutBeams) {
  pcl::PointCloud<pcl::PointXYZ> empty;
  EXPECT_THROW(SensorModel::estimate(empty), InputError);
  pcl::PointCloud<pcl::PointXYZ> nan_cloud;
  for (int i = 0; i < 1000; ++i)
    nan_cloud.push_back(pcl::PointXYZ(std::nanf(""), std::nanf(""), std::nanf("")));
  EXPECT_THROW(SensorModel::estimate(nan_cloud), InputError);
  // More beams asked for than there are.
  const auto cloud = syntheticScan(SensorModel::vlp16(), 3, 300);
  EXPECT_THROW(SensorModel::estimate(cloud, 40), InputError);
  EXPECT_EQ(SensorModel::estimate(cloud).rows(), 16);
  EXPECT_THROW(SensorModel::estimate(cloud, -1), InputError);
}

TEST(SensorModel, EstimateOnRealKittiScanMatchesThePreset) {
  const std::string path =
      std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a/frames/000000.pcd";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "KITTI data not found: " << path;
  pcl::PointCloud<pcl::PointXYZI> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(path, cloud), 0);
  const SensorModel estimated = SensorModel::estimate(cloud);
  const SensorModel preset = SensorModel::hdl64();
  ASSERT_EQ(estimated.rows(), 64);
  for (int k = 0; k < 64; ++k) {
    EXPECT_NEAR(estimated.elevations()[k] / kDeg, preset.elevations()[k] / kDeg, 0.1) << k;
    EXPECT_NEAR(estimated.verticalOffsets()[k], preset.verticalOffsets()[k], 0.03) << k;
  }
}

/** Estimates the layout from one real KITTI scan and compares it with the preset: 64 beams, each
 * within 0.1° (the beams are >= 0.27° apart) and its vertical offset within 3 cm. */
void expectEstimateMatchesPreset(const std::string& relative) {
  const std::string path = std::string(PCL_MOVERS_SHARED_DATA) + "/" + relative;
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "KITTI data not found: " << path;
  pcl::PointCloud<pcl::PointXYZI> cloud;
  pcl_movers::io::readScan(path, cloud);
  const SensorModel estimated = SensorModel::estimate(cloud);
  const SensorModel preset = SensorModel::hdl64();
  ASSERT_EQ(estimated.rows(), 64) << path;
  for (int k = 0; k < 64; ++k) {
    EXPECT_NEAR(estimated.elevations()[k] / kDeg, preset.elevations()[k] / kDeg, 0.1) << k;
    EXPECT_NEAR(estimated.verticalOffsets()[k], preset.verticalOffsets()[k], 0.03) << k;
  }
}

TEST(SensorModel, EstimateOnKittiCity22MatchesThePreset) {
  expectEstimateMatchesPreset("kitti-city-22/frames/000000.pcd");
}

TEST(SensorModel, EstimateOnKittiObject3MatchesThePreset) {
  expectEstimateMatchesPreset("kitti-object-3/velodyne/000000.bin");
}

// Known miss of issue #2, kept visible as a disabled test (run with
// --gtest_also_run_disabled_tests). KITTI odometry scans are motion-corrected: each point was
// moved along its ray by the car's travel (0.86 m per turn in odometry 00), which jumps at the
// seam behind the car and split the lower beams into double peaks (before: 27-48 of 64 beams).
// estimate() now undoes that displacement (EstimateUndoesTheMotionCorrectionOfTheScan) and finds
// 64 beams in 3 of the 6 frames (56-64), including this one, but the lower block's beams, which hit
// only the road at one range each, get offsets of ~0.16-0.19 m instead of ~0.12 m and elevations
// up to ~0.8° off: their elevation and offset cannot be told apart from one range, and the
// per-band offset prior is off on these scans.
TEST(SensorModel, DISABLED_EstimateOnKittiOdometry00MatchesThePreset) {
  expectEstimateMatchesPreset("kitti-odometry-00/velodyne/000000.bin");
}

}  // namespace

namespace {
/** Frame 0 of a simulated street as `preset` would record it, unorganized: no-return cells
 * dropped and the point order shuffled (what a driver or a converter hands over). */
pcl::PointCloud<pcl::PointXYZI> unorganizedScan(const SensorModel& sensor) {
  auto scenario = pcl_movers::sim::parseScenario(
      "name: s\nseed: 2\nframes: 1\nsensor: {preset: vlp16, height: 1.73, max_range: 80}\n"
      "terrain: {type: plane, height: 0}\nego: {start: [0, 0], heading: 0, speed: 5}\n"
      "movers:\n  - {type: car, start: [15, 3], heading: 180, speed: 8}\n"
      // A street between buildings: every beam, the upward ones too, returns all around.
      "statics:\n  - {type: building, position: [0, 14], yaw: 0, size: [80, 8, 15]}\n"
      "  - {type: building, position: [0, -14], yaw: 0, size: [80, 8, 15]}\n"
      "  - {type: building, position: [36, 0], yaw: 0, size: [8, 20, 15]}\n"
      "  - {type: building, position: [-36, 0], yaw: 0, size: [8, 20, 15]}\n"
      "  - {type: tree, position: [8, -7], height: 7, radius: 2}\n",
      "s.yaml");
  pcl_movers::sim::LidarSimulator simulator(scenario);
  simulator.setSensor(sensor);
  pcl::PointCloud<pcl::PointXYZI> organized, cloud;
  std::vector<std::uint32_t> labels;
  std::vector<pcl_movers::io::GroundTruthObject> truth;
  Eigen::Isometry3d pose;
  simulator.simulate(0, organized, labels, truth, pose);
  for (const auto& p : organized)
    if (std::isfinite(p.x)) cloud.push_back(p);
  std::shuffle(cloud.begin(), cloud.end(), std::mt19937(11));
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  return cloud;
}
}  // namespace

// "auto" on the presets' unorganized scans: the right beam count and columns, and the preset
// recognized (so the image, and the detection, are the preset's); a layout no preset has is
// estimated and kept.
TEST(SensorModel, EstimateAndRecognizeOnUnorganizedScans) {
  // (Not hdl64: the simulator fires its beams from the origin, without the KITTI calibration's
  // 0.12/0.21 m offsets, so its scans are not the preset's; KITTI's are, see below.)
  for (const char* name : {"vlp16", "hdl32", "os1_64"}) {
    SCOPED_TRACE(name);
    const SensorModel preset = SensorModel::fromName(name);
    const SensorModel estimated = SensorModel::estimate(unorganizedScan(preset));
    EXPECT_EQ(estimated.rows(), preset.rows());
    EXPECT_NEAR(estimated.columns(), preset.columns(), 0.03 * preset.columns());
    const SensorModel recognized = SensorModel::recognize(estimated);
    EXPECT_EQ(recognized.name(), name);
    EXPECT_EQ(recognized.columns(), preset.columns());
  }
  // 24 uneven beams, 1200 columns: no preset's.
  std::vector<float> elevations;
  for (int k = 0; k < 24; ++k) elevations.push_back((4.f - 1.1f * k - 0.02f * k * k) * kDeg);
  const SensorModel custom(elevations, 1200);
  const SensorModel estimated = SensorModel::estimate(unorganizedScan(custom));
  EXPECT_EQ(estimated.rows(), 24);
  EXPECT_NEAR(estimated.columns(), 1200, 36);
  EXPECT_EQ(SensorModel::recognize(estimated).name(), "estimated");
  // A preset's beams with another column count (an OS1-64 in 1024-column mode) keep theirs.
  SensorModel half = SensorModel::os1_64();
  half.setColumns(1024);
  const SensorModel os1_1024 = SensorModel::recognize(SensorModel::estimate(unorganizedScan(half)));
  EXPECT_EQ(os1_1024.name(), "os1_64");
  EXPECT_NEAR(os1_1024.columns(), 1024, 40);
}

// KITTI's HDL-64E scans are recognized as the hdl64 preset (estimated alone, ~2160 columns: a few
// clusters, and on city-22 the mover decisions, differed from the preset's 2200).
TEST(SensorModel, RecognizesKittiAsHdl64) {
  const std::string path = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-city-22/frames/000000.pcd";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "KITTI data not found at " << path;
  pcl::PointCloud<pcl::PointXYZI> cloud;
  pcl_movers::io::readScan(path, cloud);
  const SensorModel estimated = SensorModel::estimate(cloud);
  EXPECT_EQ(estimated.rows(), 64);
  EXPECT_NEAR(estimated.columns(), 2200, 0.03 * 2200);
  EXPECT_EQ(SensorModel::recognize(estimated).name(), "hdl64");
}
