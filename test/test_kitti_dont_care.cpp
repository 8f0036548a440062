/*
 * KITTI DontCare regions: the calib and label readers, the projection into camera 2's image, and
 * the real 0000-a files.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/eval/kitti_dont_care.h>
#include <pcl_movers/io/ground_truth.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using pcl_movers::InputError;
using pcl_movers::eval::DontCareRegions;
using pcl_movers::eval::ImageBox;
using pcl_movers::eval::KittiCalibration;
using pcl_movers::eval::projectToImage;
using pcl_movers::eval::readKittiCalibration;
using pcl_movers::eval::readKittiDontCareBoxes;

namespace {

/** The calib.txt of kitti-tracking-0000-a (drive 2011_09_26), as written there. */
const char* const kRealCalib =
    "R0_rect: 9.999239e-01 9.837760e-03 -7.445048e-03 -9.869795e-03 9.999421e-01 -4.278459e-03 "
    "7.402527e-03 4.351614e-03 9.999631e-01\n"
    "Tr_velo_cam: 7.533745e-03 -9.999714e-01 -6.166020e-04 -4.069766e-03 1.480249e-02 "
    "7.280733e-04 -9.998902e-01 -7.631618e-02 9.998621e-01 7.523790e-03 1.480755e-02 "
    "-2.717806e-01\n"
    "P2: 7.215377e+02 0.000000e+00 6.095593e+02 4.485728e+01 0.000000e+00 7.215377e+02 "
    "1.728540e+02 2.163791e-01 0.000000e+00 0.000000e+00 1.000000e+00 2.745884e-03\n";

fs::path tempFile(const std::string& name, const std::string& text) {
  // One folder per test: ctest runs the tests of this file in parallel processes.
  const fs::path dir = fs::temp_directory_path() / "pcl_movers_kitti_dont_care_test" /
                       ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

/** The message of the InputError that `f` throws; fails the test when it throws none. */
template <typename F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError thrown";
  return "";
}

std::string dataDir() {
  return std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a";
}

}  // namespace

TEST(KittiDontCare, ProjectsAKnownPointWithTheRealCalibration) {
  const auto calib = readKittiCalibration(tempFile("calib.txt", kRealCalib).string());
  // Sensor point p = (10, 2, -1), by hand from the matrices above:
  //   Tr_velo_cam · [p; 1]: x = 7.533745e-3·10 - 0.9999714·2 + 6.166020e-4 - 4.069766e-3
  //                           = -1.928058514
  //                         y = 1.480249e-2·10 + 7.280733e-4·2 + 0.9998902 - 7.631618e-2
  //                           =  1.073055067
  //                         z = 0.9998621·10 + 7.523790e-3·2 - 1.480755e-2 - 0.2717806
  //                           =  9.727080430
  //   R0_rect · that       = (-1.989773911, 1.050405564, 9.717118517)   (z > 0: in front)
  //   P2 · [that; 1]       = (721.5377·x + 609.5593·z + 44.85728,
  //                           721.5377·y + 172.854·z + 0.2163791, z + 2.745884e-3)
  //                        = (4532.320349791, 2437.766398081, 9.719864401)
  //   pixel                = (4532.320349791 / 9.719864401, 2437.766398081 / 9.719864401)
  //                        = (466.294607, 250.802511)
  Eigen::Vector2d pixel;
  ASSERT_TRUE(projectToImage(calib, Eigen::Vector3d(10, 2, -1), pixel));
  EXPECT_NEAR(pixel.x(), 466.294607, 1e-5);
  EXPECT_NEAR(pixel.y(), 250.802511, 1e-5);
}

TEST(KittiDontCare, PointsBehindTheCameraAreInNoBox) {
  const auto calib = readKittiCalibration(tempFile("calib.txt", kRealCalib).string());
  // (-10, 0, 0) lies 10.27 m behind the camera; dividing by the negative depth would put it at
  // pixel (605.7, 185.5), right in the image.
  Eigen::Vector2d pixel(-1, -1);
  EXPECT_FALSE(projectToImage(calib, Eigen::Vector3d(-10, 0, 0), pixel));
  EXPECT_EQ(pixel, Eigen::Vector2d(-1, -1));
  const DontCareRegions everywhere(calib, {{0, {ImageBox{-1e6, -1e6, 1e6, 1e6}}}});
  EXPECT_FALSE(everywhere.contains(0, Eigen::Vector3d(-10, 0, 0)));
  EXPECT_TRUE(everywhere.contains(0, Eigen::Vector3d(10, 2, -1)));
  EXPECT_FALSE(everywhere.contains(1, Eigen::Vector3d(10, 2, -1)));  // no box in frame 1
}

TEST(KittiDontCare, CalibrationKeysAndErrors) {
  // KITTI tracking's devkit spelling: no colons, R_rect, Tr_velo_to_cam; other keys skipped.
  std::istringstream real(kRealCalib);
  std::string r0, tr, p2;
  std::getline(real, r0);
  std::getline(real, tr);
  std::getline(real, p2);
  const std::string devkit = "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n" + p2 + "\nR_rect " + r0.substr(9) +
                             "\nTr_velo_to_cam " + tr.substr(13) + "\nTr_imu_velo: 1 2 3\n";
  const auto a = readKittiCalibration(tempFile("devkit.txt", devkit).string());
  const auto b = readKittiCalibration(tempFile("calib.txt", kRealCalib).string());
  EXPECT_EQ(a.p2, b.p2);
  EXPECT_EQ(a.r0_rect, b.r0_rect);
  EXPECT_EQ(a.tr_velo_cam, b.tr_velo_cam);
  EXPECT_NEAR(b.p2(0, 3), 44.85728, 1e-12);
  EXPECT_NEAR(b.r0_rect(2, 1), 4.351614e-03, 1e-12);

  auto bad = [](const std::string& name, const std::string& text) {
    const std::string path = tempFile(name, text).string();
    return errorOf([&] { readKittiCalibration(path); });
  };
  EXPECT_NE(bad("no_p2.txt", r0 + "\n" + tr + "\n").find("no_p2.txt: no P2"), std::string::npos);
  EXPECT_NE(bad("short.txt", r0 + "\nP2: 1 2 3\n").find("short.txt:2: P2: expected 12 numbers"),
            std::string::npos);
  EXPECT_NE(bad("nan.txt", "\n" + r0.substr(0, r0.size() - 12) + " x9.999e-01\n")
                .find("nan.txt:2: R0_rect: expected a number, got 'x9.999e-01'"),
            std::string::npos);
  EXPECT_NE(bad("twice.txt", p2 + "\n" + p2 + "\n").find("twice.txt:2: P2 given twice"),
            std::string::npos);
  EXPECT_NE(errorOf([] {
              readKittiCalibration("/nonexistent/calib.txt");
            }).find("/nonexistent/calib.txt"),
            std::string::npos);
}

TEST(KittiDontCare, LabelReaderKeepsDontCareBoxesAndNamesBadLines) {
  const std::string labels =
      "0 -1 DontCare -1 -1 -10 219.31 188.49 245.5 218.56 -1000 -1000 -1000 -10 -1 -1 -1\n"
      "0 0 Van 0 0 -1.79 296.7 161.7 455.2 292.4 2 1.82 4.43 -4.55 1.86 13.41 -2.12\n"
      "\n"
      "3 -1 DontCare -1 -1 -10 47.5 195.2 115.4 221.4 -1000 -1000 -1000 -10 -1 -1 -1 0.5\n";
  const auto boxes = readKittiDontCareBoxes(tempFile("labels.txt", labels).string());
  ASSERT_EQ(boxes.size(), 2u);
  ASSERT_EQ(boxes.at(0).size(), 1u);  // the Van row is not a DontCare box
  EXPECT_DOUBLE_EQ(boxes.at(0)[0].x1, 219.31);
  EXPECT_DOUBLE_EQ(boxes.at(0)[0].y2, 218.56);
  EXPECT_DOUBLE_EQ(boxes.at(3)[0].x2, 115.4);

  auto bad = [](const std::string& name, const std::string& text) {
    const std::string path = tempFile(name, text).string();
    return errorOf([&] { readKittiDontCareBoxes(path); });
  };
  const std::string good = labels.substr(0, labels.find('\n') + 1);
  EXPECT_NE(bad("cols.txt", good + "1 -1 DontCare -1 -1 -10 1 2 3\n")
                .find("cols.txt:2: expected 17 or 18 columns"),
            std::string::npos);
  EXPECT_NE(bad("num.txt", "0 0 Van 0 0 -1.79 296.7 abc 455.2 292.4 2 1.82 4.43 -4.55 1.86 13 -2\n")
                .find("num.txt:1: column 8: expected a number, got 'abc'"),
            std::string::npos);
  EXPECT_NE(bad("frame.txt", "1.5 -1 DontCare -1 -1 -10 1 2 3 4 -1000 -1000 -1000 -10 -1 -1 -1\n")
                .find("frame.txt:1: frame must be an integer"),
            std::string::npos);
  EXPECT_NE(bad("flip.txt", "2 -1 DontCare -1 -1 -10 30 2 10 4 -1000 -1000 -1000 -10 -1 -1 -1\n")
                .find("flip.txt:1: DontCare box has x1 > x2"),
            std::string::npos);
  EXPECT_NE(errorOf([] {
              readKittiDontCareBoxes("/nonexistent/labels.txt");
            }).find("/nonexistent/labels.txt"),
            std::string::npos);
}

// The real files: the sensor-frame box centres of objects.txt project into their KITTI 2-D boxes,
// and a point picked inside frame 0's first DontCare box is in the regions there.
TEST(KittiDontCare, RealSequenceFiles) {
  const std::string dir = dataDir();
  if (!fs::exists(dir + "/labels_kitti_tracking.txt") || !fs::exists(dir + "/calib.txt"))
    GTEST_SKIP() << "KITTI data not found at " << dir << " (set PCL_MOVERS_SHARED_DATA)";
  const auto regions =
      DontCareRegions::fromFiles(dir + "/labels_kitti_tracking.txt", dir + "/calib.txt");
  EXPECT_EQ(regions.size(), 122u);
  // Frame 0's DontCare box (219.31, 188.49)-(245.5, 218.56): (26.602, 13.848, -0.733) projects to
  // about (232.0, 202.5) in it, 30 m away.
  EXPECT_TRUE(regions.contains(0, Eigen::Vector3d(26.602, 13.848, -0.733)));
  EXPECT_FALSE(regions.contains(0, Eigen::Vector3d(10, 2, -1)));  // pixel (466, 251)

  // Frame 0's labelled 2-D boxes (x1 y1 x2 y2) of tracks 0-2, from labels_kitti_tracking.txt.
  const std::map<int, ImageBox> labelled = {
      {0, {296.744956, 161.752147, 455.226042, 292.372804}},
      {1, {737.619499, 161.531951, 931.112229, 374.0}},
      {2, {1106.137292, 166.576807, 1204.470628, 323.876144}}};
  int checked = 0;
  for (const auto& o : pcl_movers::io::readObjects(dir + "/objects.txt")) {
    if (o.frame != 0 || !labelled.count(o.track_id)) continue;
    Eigen::Vector2d pixel;
    ASSERT_TRUE(projectToImage(regions.calibration(), o.center, pixel)) << o.track_id;
    EXPECT_TRUE(labelled.at(o.track_id).contains(pixel))
        << "track " << o.track_id << " projects to " << pixel.transpose();
    ++checked;
  }
  EXPECT_EQ(checked, 3);
}
