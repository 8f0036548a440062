/*
 * Sequence inputs (issue #29): flat folders of .bin, .pcd or .ply scans, frames/ and velodyne/,
 * mixed formats refused, pose files in the kitti, tum and kitti-camera formats (TUM matched to
 * the frames by time) and a bad poses.txt that does not matter when poses are not read.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/sequence.h>

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>

#include "test_util.h"

namespace fs = std::filesystem;
using namespace pcl_movers;

namespace {

using test_util::TempDir;
using test_util::writeFile;

/** A cloud whose first x is `offset`, so frames can be told apart. */
pcl::PointCloud<pcl::PointXYZI> makeCloud(float offset) {
  pcl::PointCloud<pcl::PointXYZI> cloud;
  for (int i = 0; i < 5; ++i) {
    pcl::PointXYZI p;
    p.x = offset + i;
    p.y = 1.0f;
    p.z = -0.5f * i;
    p.intensity = 0.1f * i;
    cloud.push_back(p);
  }
  return cloud;
}

/** Writes frame `number` as `folder/NNNNNN.ext` (.pcd, .bin or .ply). */
void writeFrame(const fs::path& folder, int number, const std::string& ext) {
  fs::create_directories(folder);
  char name[32];
  std::snprintf(name, sizeof(name), "%06d%s", number, ext.c_str());
  const std::string path = (folder / name).string();
  const auto cloud = makeCloud(static_cast<float>(number));
  if (ext == ".pcd") {
    pcl::io::savePCDFileBinary(path, cloud);
  } else if (ext == ".ply") {
    pcl::io::savePLYFileBinary(path, cloud);
  } else {
    std::ofstream out(path, std::ios::binary);
    for (const auto& p : cloud) {
      const float v[4] = {p.x, p.y, p.z, p.intensity};
      out.write(reinterpret_cast<const char*>(v), sizeof(v));
    }
  }
}

std::string expectInputError(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected InputError";
  return {};
}

/** A KITTI pose line of a yaw `yaw` and translation (x, y, z). */
std::string kittiLine(double yaw, double x, double y, double z) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%.9f %.9f 0 %.9f %.9f %.9f 0 %.9f 0 0 1 %.9f\n", std::cos(yaw),
                -std::sin(yaw), x, std::sin(yaw), std::cos(yaw), y, z);
  return buf;
}

}  // namespace

// Every layout gives the same frames, in order, with the file's own numbers.
TEST(SequenceInputs, FlatFoldersOfEachFormatAndSubfolders) {
  for (const std::string ext : {".bin", ".pcd", ".ply"}) {
    for (const std::string sub : {"", "frames", "velodyne"}) {
      TempDir dir;
      for (int n = 40; n < 43; ++n) writeFrame(dir.path() / sub, n, ext);
      io::SequenceReader reader(dir.str());
      ASSERT_EQ(reader.size(), 3u) << ext << " in '" << sub << "'";
      EXPECT_EQ(reader.frameNumber(0), 40);
      EXPECT_EQ(reader.frameNumber(2), 42);
      EXPECT_EQ(reader.frameName(1), "000041");
      pcl::PointCloud<pcl::PointXYZI> cloud;
      reader.read(1, cloud);
      ASSERT_EQ(cloud.size(), 5u) << ext;
      EXPECT_FLOAT_EQ(cloud[0].x, 41.0f) << ext;
      EXPECT_FLOAT_EQ(cloud[4].z, -2.0f) << ext;
      EXPECT_NEAR(cloud[3].intensity, 0.3f, 1e-6) << ext;
    }
  }
}

TEST(SequenceInputs, ScanBlobKeepsTheFileFieldsAndOrder) {
  TempDir dir;
  pcl::PointCloud<pcl::PointXYZINormal> cloud;  // fields beyond x y z intensity
  for (int i = 0; i < 4; ++i) {
    pcl::PointXYZINormal p;
    p.x = 3.0f - i, p.y = 0, p.z = 0, p.intensity = float(i), p.curvature = 10.0f + i;
    cloud.push_back(p);
  }
  const std::string path = (dir.path() / "7.ply").string();
  pcl::io::savePLYFileBinary(path, cloud);
  pcl::PCLPointCloud2 blob;
  io::readScanBlob(path, blob);
  EXPECT_EQ(blob.width * blob.height, 4u);
  bool has_curvature = false;
  for (const auto& f : blob.fields) has_curvature |= f.name == "curvature";
  EXPECT_TRUE(has_curvature);
  pcl::PointCloud<pcl::PointXYZINormal> back;
  pcl::fromPCLPointCloud2(blob, back);
  EXPECT_FLOAT_EQ(back[2].x, 1.0f);
  EXPECT_FLOAT_EQ(back[2].curvature, 12.0f);
}

TEST(SequenceInputs, MixedFormatsAndScanFilesAreNamed) {
  TempDir dir;
  for (int n = 0; n < 3; ++n) writeFrame(dir.path(), n, ".pcd");
  for (int n = 0; n < 2; ++n) writeFrame(dir.path(), n, ".bin");
  const std::string what = expectInputError([&] { io::SequenceReader reader(dir.str()); });
  EXPECT_NE(what.find("2 .bin and 3 .pcd files: keep one format"), std::string::npos) << what;
  EXPECT_NE(what.find(dir.str()), std::string::npos) << what;

  const std::string file = (dir.path() / "000000.pcd").string();
  const std::string on_file = expectInputError([&] { io::SequenceReader reader(file); });
  EXPECT_NE(on_file.find(file), std::string::npos) << on_file;
  EXPECT_NE(on_file.find("sequence folder is expected"), std::string::npos) << on_file;

  TempDir empty;
  writeFile(empty.path() / "notes.txt", "no scans\n");
  const std::string none = expectInputError([&] { io::SequenceReader reader(empty.str()); });
  EXPECT_NE(none.find("no frames"), std::string::npos) << none;
}

TEST(SequenceInputs, KittiPoseFileGivenByPath) {
  TempDir dir;
  for (int n = 0; n < 3; ++n) writeFrame(dir.path() / "velodyne", n, ".bin");
  writeFile(dir.path() / "poses.txt", "not a pose\n");  // ignored: --poses wins
  const fs::path poses = dir.path() / "elsewhere.txt";
  writeFile(poses, kittiLine(0, 0, 0, 0) + kittiLine(0.1, 1, 0, 0) + kittiLine(0.2, 2, 0.5, 0));
  io::SequenceOptions options;
  options.poses_path = poses.string();
  io::SequenceReader reader(dir.str(), options);
  ASSERT_TRUE(reader.hasPoses());
  EXPECT_NEAR(reader.pose(2).translation().y(), 0.5, 1e-9);
  EXPECT_NE(reader.poseSource().find("elsewhere.txt"), std::string::npos);

  options.poses_path = (dir.path() / "missing.txt").string();
  const std::string what = expectInputError([&] { io::SequenceReader r(dir.str(), options); });
  EXPECT_NE(what.find("missing.txt"), std::string::npos) << what;
}

// --estimate-poses reads no pose file: a bad poses.txt does not stop it.
TEST(SequenceInputs, BadPosesTxtIsNotReadWithoutPoses) {
  TempDir dir;
  for (int n = 0; n < 2; ++n) writeFrame(dir.path(), n, ".pcd");
  writeFile(dir.path() / "poses.txt", "1 2 3\n");
  const std::string what = expectInputError([&] { io::SequenceReader reader(dir.str()); });
  EXPECT_NE(what.find("poses.txt"), std::string::npos) << what;
  io::SequenceOptions options;
  options.load_poses = false;
  io::SequenceReader reader(dir.str(), options);
  EXPECT_EQ(reader.size(), 2u);
  EXPECT_FALSE(reader.hasPoses());
}

TEST(SequenceInputs, TumPosesInOrderAndMatchedByTime) {
  TempDir dir;
  for (int n = 0; n < 4; ++n) writeFrame(dir.path(), n, ".bin");
  writeFile(dir.path() / "times.txt", "0.0\n0.1\n0.2\n0.3\n");
  // Twice the frame rate, starting a little before the first frame: interpolated at 0.1 s.
  std::string tum = "# timestamp x y z qx qy qz qw\n";
  for (int k = 0; k < 8; ++k) {
    const double t = -0.02 + 0.05 * k, yaw = 0.4 * t / 0.33;
    char line[200];
    std::snprintf(line, sizeof(line), "%.3f %.6f 0 0 0 0 %.9f %.9f\n", t, 10.0 * t,
                  std::sin(0.5 * yaw), std::cos(0.5 * yaw));
    tum += line;
  }
  writeFile(dir.path() / "traj.tum", tum);
  io::SequenceOptions options;
  options.poses_path = (dir.path() / "traj.tum").string();
  options.poses_format = io::parsePoseFormat("tum");
  io::SequenceReader reader(dir.str(), options);
  ASSERT_EQ(reader.poses().size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    const double t = reader.time(i);
    EXPECT_NEAR(reader.pose(i).translation().x(), 10.0 * t, 1e-6) << "frame " << i;
    const Eigen::Matrix3d R = reader.pose(i).linear();
    EXPECT_NEAR(std::atan2(R(1, 0), R(0, 0)), 0.4 * t / 0.33, 1e-6) << "frame " << i;
  }

  // Same count as frames: taken in order, whatever the stamps.
  writeFile(dir.path() / "four.tum",
            "100 1 0 0 0 0 0 1\n200 2 0 0 0 0 0 1\n300 3 0 0 0 0 0 1\n400 4 0 0 0 0 0 1\n");
  options.poses_path = (dir.path() / "four.tum").string();
  io::SequenceReader in_order(dir.str(), options);
  EXPECT_DOUBLE_EQ(in_order.pose(3).translation().x(), 4.0);

  // Too far from every pose: the frame and the nearest pose time are named.
  writeFile(dir.path() / "short.tum", "0.0 0 0 0 0 0 0 1\n0.05 1 0 0 0 0 0 1\n0.1 2 0 0 0 0 0 1\n");
  options.poses_path = (dir.path() / "short.tum").string();
  const std::string what = expectInputError([&] { io::SequenceReader r(dir.str(), options); });
  EXPECT_NE(what.find("short.tum"), std::string::npos) << what;
  EXPECT_NE(what.find("frame 2"), std::string::npos) << what;
  EXPECT_NE(what.find("nearest pose is at 0.1"), std::string::npos) << what;

  writeFile(dir.path() / "bad.tum", "0.0 0 0 0 0 0 0\n");
  options.poses_path = (dir.path() / "bad.tum").string();
  const std::string bad = expectInputError([&] { io::SequenceReader r(dir.str(), options); });
  EXPECT_NE(bad.find("bad.tum:1"), std::string::npos) << bad;
  EXPECT_NE(expectInputError([] { io::parsePoseFormat("tumm"); }).find("--poses-format"),
            std::string::npos);
}

// kitti-camera: velodyne pose = Tr^-1 * P_cam * Tr, on a synthetic calib and, when present, on the
// real KITTI odometry 00 files (the first pose is the identity in both frames).
TEST(SequenceInputs, KittiCameraPosesWithCalib) {
  TempDir dir;
  for (int n = 0; n < 2; ++n) writeFrame(dir.path() / "velodyne", n, ".bin");
  // Tr: velodyne x forward -> camera z forward (x right = -y_velo, y down = -z_velo).
  writeFile(dir.path() / "calib.txt",
            "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27\n");
  // The camera moves 2 m along its z (forward) axis.
  writeFile(dir.path() / "cam.txt", kittiLine(0, 0, 0, 0) + "1 0 0 0 0 1 0 0 0 0 1 2\n");
  io::SequenceOptions options;
  options.poses_path = (dir.path() / "cam.txt").string();
  options.poses_format = io::PoseFormat::kitti_camera;
  EXPECT_NE(expectInputError([&] { io::SequenceReader r(dir.str(), options); }).find("--calib"),
            std::string::npos);
  options.calib_path = (dir.path() / "calib.txt").string();
  io::SequenceReader reader(dir.str(), options);
  EXPECT_NEAR(reader.pose(1).translation().x(), 2.0, 1e-9);  // forward in the velodyne frame
  EXPECT_NEAR(reader.pose(1).translation().y(), 0.0, 1e-9);
  EXPECT_NEAR(reader.pose(1).translation().z(), 0.0, 1e-9);

  const fs::path real = fs::path(PCL_MOVERS_SHARED_DATA) / "kitti-odometry-00";
  if (!fs::exists(real / "calib.txt") || !fs::exists(real / "poses_cam0.txt"))
    GTEST_SKIP() << real << " with calib.txt and poses_cam0.txt is absent (synthetic part ran)";
  options.poses_path = (real / "poses_cam0.txt").string();
  options.calib_path = (real / "calib.txt").string();
  io::SequenceReader odometry(real.string(), options);
  ASSERT_EQ(odometry.size(), odometry.poses().size());
  const Eigen::Isometry3d tr = io::readKittiCalibTr(options.calib_path);
  const auto cam = io::readPoses(options.poses_path);
  for (std::size_t i = 0; i < odometry.size(); ++i) {
    const Eigen::Matrix4d expect = (tr.inverse() * cam[i] * tr).matrix();
    EXPECT_TRUE(odometry.pose(i).matrix().isApprox(expect, 1e-9)) << "frame " << i;
  }
  // The car drives forward: along the velodyne x axis of the first frame, not up.
  const Eigen::Vector3d last = odometry.pose(odometry.size() - 1).translation();
  EXPECT_GT(last.x(), 1.0);
  EXPECT_LT(std::abs(last.z()), 0.2 * last.x());
}
