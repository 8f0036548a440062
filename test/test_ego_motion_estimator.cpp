/*
 * EgoMotionEstimator: a synthetic street moved by known transforms (with a mover in it), and
 * (when the shared data is present) 5 real KITTI frames against their reference poses.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/ego_motion_estimator.h>
#include <pcl_movers/io/sequence.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

namespace fs = std::filesystem;

namespace {

/** Uniform random points on an axis-aligned box's surface-like patch: a rectangle spanned by
 * `u` and `v` from `origin`. */
void samplePatch(std::mt19937& rng, const Eigen::Vector3d& origin, const Eigen::Vector3d& u,
                 const Eigen::Vector3d& v, double density, std::vector<Eigen::Vector3d>& out) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int n = static_cast<int>(density * u.norm() * v.norm());
  for (int i = 0; i < n; ++i) out.push_back(origin + unit(rng) * u + unit(rng) * v);
}

/** Side faces and top of a box [x0,x1]x[y0,y1]x[z0,z1]. */
void sampleBox(std::mt19937& rng, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
               double density, std::vector<Eigen::Vector3d>& out) {
  const Eigen::Vector3d d = hi - lo;
  const Eigen::Vector3d ex(d.x(), 0, 0), ey(0, d.y(), 0), ez(0, 0, d.z());
  samplePatch(rng, lo, ex, ez, density, out);
  samplePatch(rng, lo + ey, ex, ez, density, out);
  samplePatch(rng, lo, ey, ez, density, out);
  samplePatch(rng, lo + ex, ey, ez, density, out);
  samplePatch(rng, lo + ez, ex, ey, density, out);
}

/** A street: ground, two building fronts with recesses, a wall across the far end, pillars and
 * parked cars; plus one car driving across (`mover_offset` moves it along y). Every call samples
 * new random points, so no two scans share exact points (as with a real scanner). */
pcl::PointCloud<pcl::PointXYZ> streetScan(std::mt19937& rng, const Eigen::Isometry3d& sensor_pose,
                                          double mover_offset) {
  std::vector<Eigen::Vector3d> world;
  samplePatch(rng, {-40, -15, -1.73}, {80, 0, 0}, {0, 30, 0}, 6.0, world);  // ground
  for (int i = 0; i < 8; ++i) {  // building fronts with 1 m recesses every 10 m
    const double x0 = -40 + 10 * i;
    const double y_left = 9 + (i % 2), y_right = -11 - (i % 3 == 0);
    samplePatch(rng, {x0, y_left, -1.73}, {10, 0, 0}, {0, 0, 8}, 6.0, world);
    samplePatch(rng, {x0, y_right, -1.73}, {10, 0, 0}, {0, 0, 8}, 6.0, world);
    samplePatch(rng, {x0, 9, -1.73}, {0, 1, 0}, {0, 0, 8}, 6.0, world);
  }
  samplePatch(rng, {40, -15, -1.73}, {0, 30, 0}, {0, 0, 6}, 6.0, world);  // far wall
  for (int i = 0; i < 6; ++i)                                             // pillars along the kerbs
    sampleBox(rng, {-25.0 + 10 * i, 6.5, -1.73}, {-24.6 + 10 * i, 6.9, 2.5}, 30.0, world);
  sampleBox(rng, {5, -8, -1.73}, {9.5, -6.2, -0.3}, 15.0, world);     // parked car
  sampleBox(rng, {-12, -8, -1.73}, {-7.5, -6.2, -0.3}, 15.0, world);  // parked car
  sampleBox(rng, {15, -3 + mover_offset, -1.73}, {19.5, -1.2 + mover_offset, -0.2}, 15.0,
            world);  // a car crossing the street
  const Eigen::Isometry3d to_sensor = sensor_pose.inverse();
  pcl::PointCloud<pcl::PointXYZ> scan;
  scan.reserve(world.size());
  for (const auto& p : world) {
    const Eigen::Vector3f q = (to_sensor * p).cast<float>();
    scan.push_back(pcl::PointXYZ(q.x(), q.y(), q.z()));
  }
  return scan;
}

double yawDeg(const Eigen::Matrix3d& r) {
  return std::atan2(r(1, 0), r(0, 0)) * 180.0 / M_PI;
}

}  // namespace

TEST(EgoMotionEstimator, RecoversKnownMotionOfSyntheticStreet) {
  std::mt19937 rng(42);
  pcl_movers::EgoMotionEstimator<pcl::PointXYZ> estimator;
  // 0.9 m and 1.5 deg of yaw per frame, with a little pitch and roll: like a car at 32 km/h.
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.linear() = (Eigen::AngleAxisd(1.5 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(0.2 * M_PI / 180, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(-0.1 * M_PI / 180, Eigen::Vector3d::UnitX()))
                      .matrix();
  step.translation() = Eigen::Vector3d(0.9, 0.05, 0.01);
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d estimate;
  for (int f = 0; f < 6; ++f) {
    estimate = estimator.estimate(streetScan(rng, truth, 1.0 * f));
    if (f == 0) EXPECT_TRUE(estimate.isApprox(Eigen::Isometry3d::Identity()));
    const double err = (estimate.translation() - truth.translation()).norm();
    EXPECT_LT(err, 0.05) << "frame " << f;
    EXPECT_LT(std::abs(yawDeg(truth.linear().transpose() * estimate.linear())), 0.2)
        << "frame " << f;
    if (f < 5) truth = truth * step;
  }
  EXPECT_EQ(estimator.getFrameCount(), 6u);
  EXPECT_GT(estimator.getLastCorrespondences(), 100);
  EXPECT_LT(estimator.getLastFitness(), 0.1);
  // The last frame-to-frame motion is the step.
  EXPECT_LT((estimator.getLastMotion().translation() - step.translation()).norm(), 0.05);

  // reset(): the next scan is the new origin.
  estimator.reset();
  EXPECT_EQ(estimator.getFrameCount(), 0u);
  EXPECT_TRUE(
      estimator.estimate(streetScan(rng, truth, 0.0)).isApprox(Eigen::Isometry3d::Identity()));
}

TEST(EgoMotionEstimator, PlanarModeKeepsZRollPitch) {
  std::mt19937 rng(7);
  pcl_movers::EgoMotionEstimator<pcl::PointXYZ> estimator;
  estimator.setPlanarMotion(true);
  EXPECT_TRUE(estimator.getPlanarMotion());
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d estimate;
  for (int f = 0; f < 4; ++f) {
    estimate = estimator.estimate(streetScan(rng, truth, 0.0));
    truth.translation() += Eigen::Vector3d(0.7, -0.1, 0.0);
    truth.linear() =
        Eigen::AngleAxisd((f + 1) * 2.0 * M_PI / 180, Eigen::Vector3d::UnitZ()).matrix() *
        Eigen::Matrix3d::Identity();
  }
  // estimate is frame 3: truth was advanced once more after it, so rebuild frame 3's pose.
  Eigen::Isometry3d frame3 = Eigen::Isometry3d::Identity();
  frame3.translation() = Eigen::Vector3d(2.1, -0.3, 0.0);
  frame3.linear() = Eigen::AngleAxisd(6.0 * M_PI / 180, Eigen::Vector3d::UnitZ()).matrix();
  EXPECT_LT((estimate.translation() - frame3.translation()).norm(), 0.05);
  EXPECT_NEAR(estimate.translation().z(), 0.0, 1e-9);  // z is not estimated in planar mode
  EXPECT_NEAR((estimate.linear() * Eigen::Vector3d::UnitZ()).z(), 1.0, 1e-9);  // no roll/pitch
  EXPECT_NEAR(yawDeg(estimate.linear()), 6.0, 0.2);
}

TEST(EgoMotionEstimator, DegenerateScansDoNotCrash) {
  pcl_movers::EgoMotionEstimator<pcl::PointXYZI> estimator;
  pcl::PointCloud<pcl::PointXYZI> empty;
  EXPECT_TRUE(estimator.estimate(empty).isApprox(Eigen::Isometry3d::Identity()));
  pcl::PointCloud<pcl::PointXYZI> nans;
  pcl::PointXYZI p;
  p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
  nans.push_back(p);
  const Eigen::Isometry3d pose = estimator.estimate(nans);
  EXPECT_TRUE(pose.matrix().allFinite());
  EXPECT_EQ(estimator.getLastCorrespondences(), 0);
}

TEST(EgoMotionEstimator, KittiTrackingFiveFrames) {
  const std::string folder = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a";
  if (!fs::exists(folder + "/poses.txt"))
    GTEST_SKIP() << "shared KITTI data not found at " << folder;
  pcl_movers::io::SequenceReader seq(folder);
  ASSERT_GE(seq.size(), 5u);
  ASSERT_TRUE(seq.hasPoses());
  pcl_movers::EgoMotionEstimator<pcl::PointXYZI> estimator;
  pcl::PointCloud<pcl::PointXYZI> scan;
  Eigen::Isometry3d estimate;
  for (std::size_t i = 0; i < 5; ++i) {
    seq.read(i, scan);
    estimate = estimator.estimate(scan);
  }
  const Eigen::Isometry3d& reference = seq.pose(4);
  const double travelled = reference.translation().norm();
  ASSERT_GT(travelled, 1.0);  // the car does move ~1.4 m in these frames
  // Generous: 10 cm after ~1.4 m (the reference is itself an estimate) and half a degree.
  EXPECT_LT((estimate.translation() - reference.translation()).norm(), 0.10);
  EXPECT_LT(std::abs(yawDeg(reference.linear().transpose() * estimate.linear())), 0.5);
}
