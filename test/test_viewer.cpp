/*
 * Tests of the viewer: the scene helpers of pcl_movers/viz/scene_style.h (colours, boxes, trails,
 * camera projection, argument parsing) and the pcl_movers_viewer tool itself, run as a program:
 * off-screen rendering must put mover-red pixels where the mover projects, and bad inputs must
 * fail cleanly. Rendering needs an X display (CI runs ctest under xvfb-run); without DISPLAY those
 * tests skip.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/tracks.h>
#include <pcl_movers/viz/scene_style.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "test_image.h"

namespace fs = std::filesystem;
using namespace pcl_movers;

namespace {

// ------------------------------------------------------------------ helpers

bool hasDisplay() {
  const char* d = std::getenv("DISPLAY");
  return d && *d;
}

std::string toolPath() {
  return std::string(PCL_MOVERS_BINARY_DIR) + "/apps/pcl_movers_viewer";
}

/** A fresh folder under the build tree, removed at the end of the test. */
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) {
    path = fs::path(PCL_MOVERS_BINARY_DIR) / "test_viewer_tmp" /
           (name + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

struct RunResult {
  int code = -1;
  std::string output;  // stdout + stderr
};

RunResult runTool(const std::string& args, const fs::path& log) {
  const std::string cmd = "\"" + toolPath() + "\" " + args + " > \"" + log.string() + "\" 2>&1";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  std::ifstream in(log);
  std::stringstream s;
  s << in.rdbuf();
  r.output = s.str();
  return r;
}

using test_util::countRed;
using test_util::Image;
using test_util::isMoverRed;
using test_util::readPpm;

/** Red pixels inside the image rectangle covered by a box's projected corners (+ a few pixels). */
int countRedInBox(const Image& im, const viz::CameraView& cam, const viz::OrientedBox& box,
                  int grow = 4) {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const auto& c : box.corners()) {
    const auto p = viz::projectToPixel(cam, c, im.width, im.height);
    if (!p) return -1;
    x0 = std::min(x0, p->x()), y0 = std::min(y0, p->y());
    x1 = std::max(x1, p->x()), y1 = std::max(y1, p->y());
  }
  int n = 0;
  for (int y = std::max(0, int(y0) - grow); y <= std::min(im.height - 1, int(y1) + grow); ++y)
    for (int x = std::max(0, int(x0) - grow); x <= std::min(im.width - 1, int(x1) + grow); ++x)
      n += isMoverRed(im.at(x, y));
  return n;
}

/** A small synthetic sequence: flat ground, a mover box (track 7) driving along +x at 5 m/s and
 * a stationary pole (track 3); tracks.csv with both; identity poses advancing 1 m per frame. */
struct SyntheticScene {
  fs::path seq, det;
  Eigen::Vector3d mover_center{12.0, 3.0, -0.95};  // frame 1
  static constexpr int kFrames = 3;

  explicit SyntheticScene(const fs::path& root) : seq(root / "seq"), det(root / "det") {
    fs::create_directories(seq / "frames");
    fs::create_directories(det);
    std::vector<Eigen::Isometry3d> poses;
    std::vector<double> times;
    std::vector<io::TrackRow> rows;
    for (int f = 0; f < kFrames; ++f) {
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.translation() = Eigen::Vector3d(1.0 * f, 0, 0);
      poses.push_back(pose);
      times.push_back(0.1 * f);
      // The mover moves 0.5 m/frame in the world; the sensor 1 m/frame: in the sensor frame it
      // falls back 0.5 m per frame.
      const Eigen::Vector3d mover = mover_center + Eigen::Vector3d(-0.5 * (f - 1), 0, 0);
      const Eigen::Vector3d pole(8.0 - f, -4.0, -0.7);
      pcl::PointCloud<pcl::PointXYZI> cloud;
      auto add = [&](double x, double y, double z) {
        pcl::PointXYZI p;
        p.x = float(x), p.y = float(y), p.z = float(z), p.intensity = 0.5f;
        cloud.push_back(p);
      };
      for (double x = -10; x <= 40; x += 0.3)
        for (double y = -15; y <= 15; y += 0.3) add(x, y, -1.7);
      // Mover: 4 x 2 x 1.5 m box surface, dense.
      for (double u = -2; u <= 2; u += 0.1)
        for (double z = -1.7; z <= -0.2; z += 0.1) {
          add(mover.x() + u, mover.y() - 1, z);
          add(mover.x() + u, mover.y() + 1, z);
        }
      for (double u = -2; u <= 2; u += 0.1)
        for (double v = -1; v <= 1; v += 0.1) add(mover.x() + u, mover.y() + v, -0.2);
      for (double z = -1.7; z <= 1.5; z += 0.05)
        for (double a = 0; a < 6.28; a += 0.5)
          add(pole.x() + 0.1 * std::cos(a), pole.y() + 0.1 * std::sin(a), z);
      cloud.width = static_cast<std::uint32_t>(cloud.size());
      cloud.height = 1;
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.pcd", f);
      pcl::io::savePCDFileBinary((seq / "frames" / name).string(), cloud);

      io::TrackRow m;
      m.frame = f, m.time = 0.1 * f, m.track_id = 7, m.mover = true;
      m.x = mover.x(), m.y = mover.y(), m.z = mover.z();
      const Eigen::Vector3d w = pose * mover;
      m.wx = w.x(), m.wy = w.y(), m.wz = w.z();
      m.vx = 5.0, m.vy = 0, m.speed = 5.0;
      m.length = 4, m.width = 2, m.height = 1.5, m.yaw = 0, m.similarity = 0.9, m.points = 500;
      rows.push_back(m);
      io::TrackRow s;
      s.frame = f, s.time = 0.1 * f, s.track_id = 3, s.mover = false;
      s.x = pole.x(), s.y = pole.y(), s.z = pole.z();
      const Eigen::Vector3d ws = pose * pole;
      s.wx = ws.x(), s.wy = ws.y(), s.wz = ws.z();
      s.length = 0.3, s.width = 0.3, s.height = 3.2, s.similarity = 0.9, s.points = 400;
      rows.push_back(s);
    }
    io::writePoses((seq / "poses.txt").string(), poses);
    io::writeTimes((seq / "times.txt").string(), times);
    io::writeTracks((det / "tracks.csv").string(), rows);
  }
};

// ------------------------------------------------------------------ scene helpers (no display)

TEST(SceneStyle, TrackColorsAreCoolAndDistinct) {
  const viz::SceneStyle style;
  std::set<std::tuple<int, int, int>> seen;
  for (int id = 0; id < 200; ++id) {
    const viz::Color c = viz::trackColor(id);
    // Never warm: red must not dominate, so no static track looks like a mover or the selection.
    EXPECT_LT(c.r, std::max(c.g, c.b)) << "track " << id;
    EXPECT_NE(c, style.mover_points);
    EXPECT_NE(c, style.mover_box);
    // Not magenta-like either (ground truth): green must not be the weakest channel by far.
    EXPECT_FALSE(c.r > 150 && c.b > 150 && c.g < 120) << "track " << id;
    seen.insert({c.r, c.g, c.b});
    if (id > 0) {
      const viz::Color p = viz::trackColor(id - 1);
      EXPECT_GT(std::abs(c.r - p.r) + std::abs(c.g - p.g) + std::abs(c.b - p.b), 40)
          << "tracks " << id - 1 << " and " << id << " look alike";
    }
  }
  EXPECT_GT(seen.size(), 150u);
  EXPECT_EQ(viz::trackColor(5), viz::trackColor(5));  // stable across calls
}

TEST(SceneStyle, OrientedBoxCornersAndContains) {
  viz::OrientedBox box;
  box.center = Eigen::Vector3d(10, 5, -1);
  box.length = 4, box.width = 2, box.height = 1.5, box.yaw = M_PI / 2;  // long side along y
  const auto c = box.corners();
  for (const auto& p : c) {
    EXPECT_NEAR(std::abs(p.x() - 10), 1.0, 1e-9);
    EXPECT_NEAR(std::abs(p.y() - 5), 2.0, 1e-9);
    EXPECT_NEAR(std::abs(p.z() + 1), 0.75, 1e-9);
  }
  EXPECT_TRUE(box.contains({10, 6.9, -1}));
  EXPECT_FALSE(box.contains({11.5, 5, -1}));      // beyond the width
  EXPECT_TRUE(box.contains({11.2, 5, -1}, 0.3));  // but inside the margin
  EXPECT_FALSE(box.contains({10, 5, 0.0}));       // above
  io::TrackRow row;
  row.x = 1, row.y = 2, row.z = 3, row.length = 4, row.width = 5, row.height = 6, row.yaw = 0.7;
  const auto b = viz::OrientedBox::fromTrack(row);
  EXPECT_EQ(b.center, Eigen::Vector3d(1, 2, 3));
  EXPECT_DOUBLE_EQ(b.yaw, 0.7);
}

TEST(SceneStyle, LineSetGeometry) {
  viz::LineSet set;
  viz::OrientedBox box;
  box.length = box.width = box.height = 2;
  set.addBox(box, {1, 2, 3});
  EXPECT_EQ(set.size(), 12u);
  for (const auto& s : set.segments) EXPECT_NEAR((s.a - s.b).norm(), 2.0, 1e-5);  // cube edges
  set.addArrow({0, 0, 0}, {3, 0, 0}, {9, 9, 9});
  EXPECT_EQ(set.size(), 15u);
  // The head strokes start at the tip and point back.
  for (std::size_t k = 13; k < 15; ++k) {
    EXPECT_NEAR(set.segments[k].a.x(), 3.0, 1e-6);
    EXPECT_LT(set.segments[k].b.x(), 3.0);
  }
  set.addArrow({0, 0, 0}, {0.001, 0, 0}, {9, 9, 9});  // too short: nothing
  EXPECT_EQ(set.size(), 15u);
  set.addPolyline({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}}, {5, 5, 5});
  EXPECT_EQ(set.size(), 18u);
}

pcl::PointCloud<pcl::PointXYZ> groundAndBox(std::size_t& first_box_point) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (double x = 0; x < 20; x += 0.2)
    for (double y = -5; y < 5; y += 0.2) cloud.push_back({float(x), float(y), -1.7f});
  first_box_point = cloud.size();
  for (double x = 9; x <= 11; x += 0.1)
    for (double z = -1.6; z <= 0.0; z += 0.1) cloud.push_back({float(x), 1.0f, float(z)});
  cloud.push_back({std::nanf(""), 0.f, 0.f});
  return cloud;
}

TEST(SceneStyle, GroundMaskSeparatesGroundFromObjects) {
  std::size_t first_box = 0;
  const auto cloud = groundAndBox(first_box);
  const auto mask = viz::estimateGroundMask(cloud);
  ASSERT_EQ(mask.size(), cloud.size());
  for (std::size_t i = 0; i < first_box; ++i) ASSERT_TRUE(mask[i]) << "ground point " << i;
  int box_ground = 0, box_total = 0;
  for (std::size_t i = first_box; i + 1 < cloud.size(); ++i, ++box_total)
    box_ground += mask[i] ? 1 : 0;
  // Only the lowest ~25 cm of the box counts as ground.
  EXPECT_LT(box_ground, box_total / 4);
  EXPECT_FALSE(mask.back());  // NaN
}

TEST(SceneStyle, PointsInsideTrackBoxesTakeTheTrack) {
  std::size_t first_box = 0;
  const auto cloud = groundAndBox(first_box);
  const auto mask = viz::estimateGroundMask(cloud);
  io::TrackRow mover;
  mover.track_id = 4, mover.mover = true, mover.x = 10, mover.y = 1, mover.z = -0.8;
  mover.length = 2.2, mover.width = 0.5, mover.height = 1.8;
  const auto labels = viz::labelPointsFromTracks(cloud, mask, {mover});
  int in_mover = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (i < first_box) {
      EXPECT_EQ(labels.classes[i], viz::PointClass::Ground);
      EXPECT_EQ(labels.track_ids[i], -1);
    } else if (labels.classes[i] == viz::PointClass::Mover) {
      EXPECT_EQ(labels.track_ids[i], 4);
      ++in_mover;
    }
  }
  EXPECT_GT(in_mover, static_cast<int>(cloud.size() - first_box) / 2);
  const auto colors = viz::colorPoints(cloud, labels, {4});
  const viz::SceneStyle style;
  EXPECT_EQ(colors[0], style.ground);
  EXPECT_EQ(colors[cloud.size() - 2], style.mover_points);  // top of the box
  // The same box as a stationary track gets the track colour instead.
  mover.mover = false;
  const auto labels2 = viz::labelPointsFromTracks(cloud, mask, {mover});
  const auto colors2 = viz::colorPoints(cloud, labels2, {});
  EXPECT_EQ(colors2[cloud.size() - 2], viz::trackColor(4));
  // Without tracks nothing is a mover.
  const auto labels3 = viz::labelPointsFromTracks(cloud, mask, {});
  for (auto c : labels3.classes) EXPECT_NE(c, viz::PointClass::Mover);
}

TEST(SceneStyle, TrackBoxesCentredOnTheirPoints) {
  // Only the near face (x = 10) of a 4 m x 2 m car seen from the origin, yaw 0: the centroid is on
  // the face, the box must cover the points, not stick out 1 m in front of them.
  pcl::PointCloud<pcl::PointXYZ> cloud;
  viz::PointLabels labels;
  for (int i = 0; i <= 40; ++i)  // integer steps: the extent must be exactly 4 m x 1.5 m
    for (int k = 0; k <= 15; ++k) {
      cloud.push_back({10.f, float(-2.0 + 0.1 * i), float(-1.5 + 0.1 * k)});
      labels.classes.push_back(viz::PointClass::Mover);
      labels.track_ids.push_back(6);
    }
  io::TrackRow row;
  row.track_id = 6, row.x = 10, row.y = 0, row.z = -0.75;
  row.length = 4.2, row.width = 0.3, row.height = 1.5, row.yaw = M_PI / 2;  // long side along y
  io::TrackRow lonely = row;
  lonely.track_id = 8, lonely.x = 20;  // no points: keeps its centroid
  const auto boxes = viz::fitTrackBoxes(cloud, labels, {row, lonely});
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_NEAR(boxes[0].center.x(), 10.0, 1e-5);
  EXPECT_NEAR(boxes[0].center.y(), 0.0, 1e-5);
  EXPECT_NEAR(boxes[0].center.z(), -0.75, 1e-5);
  EXPECT_NEAR(boxes[0].length, 4.2, 1e-9);  // the CSV size is kept when it covers the points
  for (const auto& p : cloud)
    EXPECT_TRUE(boxes[0].contains(p.getVector3fMap().cast<double>(), 1e-4));
  // A box given too small grows to its points; one given off-centre moves onto them.
  row.length = 1.0, row.y = 1.5;
  const auto grown = viz::fitTrackBoxes(cloud, labels, {row});
  EXPECT_NEAR(grown[0].length, 4.0, 0.05);
  EXPECT_NEAR(grown[0].center.y(), 0.0, 0.05);
  EXPECT_EQ(boxes[1].center, Eigen::Vector3d(20, 0, -0.75));
}

TEST(SceneStyle, ParseFrameRange) {
  auto r = viz::parseFrameRange("2:5", 10);
  EXPECT_EQ(r.first, 2u);
  EXPECT_EQ(r.last, 5u);
  r = viz::parseFrameRange("7", 10);
  EXPECT_EQ(r.first, 7u);
  EXPECT_EQ(r.last, 7u);
  r = viz::parseFrameRange("3:", 10);
  EXPECT_EQ(r.last, 9u);
  r = viz::parseFrameRange(":4", 10);
  EXPECT_EQ(r.first, 0u);
  EXPECT_EQ(r.last, 4u);
  for (const char* bad : {"5:2", "0:10", "10", "a:b", "-1:3", ":", "", "1:2:3", "2.5"})
    EXPECT_THROW(viz::parseFrameRange(bad, 10), InputError) << bad;
  try {
    viz::parseFrameRange("5:12", 10);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
  }
}

TEST(SceneStyle, ParseImageSize) {
  EXPECT_EQ(viz::parseImageSize("1280x720"), std::make_pair(1280, 720));
  EXPECT_EQ(viz::parseImageSize("64X48"), std::make_pair(64, 48));
  for (const char* bad :
       {"0x10", "abc", "100x", "x100", "100x-5", "1e3x100", "9000x100", "640*480"})
    EXPECT_THROW(viz::parseImageSize(bad), InputError) << bad;
  EXPECT_EQ(viz::parseCameraPreset("bird"), viz::CameraPreset::Bird);
  EXPECT_THROW(viz::parseCameraPreset("free"), InputError);
  EXPECT_EQ(viz::parseCameraPreset("free", true), viz::CameraPreset::Free);
}

TEST(SceneStyle, ProjectionMatchesCameraPresets) {
  const int w = 800, h = 600;
  for (auto preset : {viz::CameraPreset::Chase, viz::CameraPreset::Bird}) {
    const auto cam = viz::cameraView(preset);
    const auto centre = viz::projectToPixel(cam, cam.focal, w, h);
    ASSERT_TRUE(centre);
    EXPECT_NEAR(centre->x(), w / 2.0, 1e-6);
    EXPECT_NEAR(centre->y(), h / 2.0, 1e-6);
    // Forward (+x) is up in the image, left (+y) is left, for both presets.
    const auto ahead = viz::projectToPixel(cam, cam.focal + Eigen::Vector3d(5, 0, 0), w, h);
    const auto left = viz::projectToPixel(cam, cam.focal + Eigen::Vector3d(0, 5, 0), w, h);
    ASSERT_TRUE(ahead && left);
    EXPECT_LT(ahead->y(), h / 2.0);
    EXPECT_LT(left->x(), w / 2.0);
    // Behind the camera: nothing.
    EXPECT_FALSE(viz::projectToPixel(cam, 2 * cam.position - cam.focal, w, h));
  }
}

TEST(SceneStyle, TrailsMapWorldPositionsIntoTheCurrentSensorFrame) {
  std::vector<io::TrackRow> rows;
  for (int f = 0; f < 6; ++f) {
    if (f == 2) continue;  // a missed frame
    io::TrackRow r;
    r.frame = f, r.track_id = 1, r.wx = 10.0 + f, r.wy = 2, r.wz = 0;
    r.x = r.wx - 3.0 * f, r.y = 2;
    rows.push_back(r);
  }
  viz::TrackIndex index(rows);
  EXPECT_EQ(index.lastFrame(), 5);
  EXPECT_EQ(index.frame(3).size(), 1u);
  EXPECT_TRUE(index.frame(2).empty());
  Eigen::Isometry3d world_to_sensor = Eigen::Isometry3d::Identity();
  world_to_sensor.translation() = Eigen::Vector3d(-15, 0, 0);  // sensor at x = 15
  const auto trail = index.trail(1, 5, 3, world_to_sensor);    // frames 3, 4, 5
  ASSERT_EQ(trail.size(), 3u);
  EXPECT_NEAR(trail.front().x(), 13.0 - 15.0, 1e-9);
  EXPECT_NEAR(trail.back().x(), 15.0 - 15.0, 1e-9);
  EXPECT_EQ(index.trail(1, 5, 10, world_to_sensor).size(), 5u);
  EXPECT_TRUE(index.trail(99, 5, 10, world_to_sensor).empty());
  EXPECT_EQ(index.sensorTrail(1, 4, 2).size(), 2u);
}

TEST(SceneStyle, SensorPoseFittedFromTrackRows) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(5, -2, 0.1);
  std::vector<io::TrackRow> rows;
  for (const Eigen::Vector3d p : {Eigen::Vector3d(10, 0, -1), Eigen::Vector3d(4, 6, -0.5),
                                  Eigen::Vector3d(-3, -7, 0), Eigen::Vector3d(20, 3, -1)}) {
    io::TrackRow r;
    r.x = p.x(), r.y = p.y(), r.z = p.z();
    const Eigen::Vector3d w = pose * p;
    r.wx = w.x(), r.wy = w.y(), r.wz = w.z();
    rows.push_back(r);
  }
  const auto fitted = viz::fitSensorPose(rows);
  ASSERT_TRUE(fitted);
  EXPECT_TRUE(fitted->matrix().isApprox(pose.matrix(), 1e-6));
  // Velocity arrows turn with the ego: world +x is sensor -0.3 rad.
  io::TrackRow m = rows[0];
  m.vx = 2.0, m.vy = 0;
  const auto arrow = viz::velocityArrow(m, pose, 1.5);
  const Eigen::Vector3d d = arrow.second - arrow.first;
  EXPECT_NEAR(d.norm(), 3.0, 1e-9);
  EXPECT_NEAR(std::atan2(d.y(), d.x()), -0.3, 1e-9);
  // Collinear rows or too few rows: no pose.
  std::vector<io::TrackRow> line(3, rows[0]);
  for (int k = 0; k < 3; ++k) line[k].x += k, line[k].wx += k;
  EXPECT_FALSE(viz::fitSensorPose(line));
  rows.resize(2);
  EXPECT_FALSE(viz::fitSensorPose(rows));
}

TEST(SceneStyle, SelectionCyclesMoversFirst) {
  std::vector<io::TrackRow> rows(4);
  rows[0].track_id = 1;
  rows[1].track_id = 5, rows[1].mover = true;
  rows[2].track_id = 3;
  rows[3].track_id = 9, rows[3].mover = true;
  EXPECT_EQ(viz::nextSelectedTrack(rows, -1), 5);
  EXPECT_EQ(viz::nextSelectedTrack(rows, 5), 9);
  EXPECT_EQ(viz::nextSelectedTrack(rows, 9), 1);
  EXPECT_EQ(viz::nextSelectedTrack(rows, 1), 3);
  EXPECT_EQ(viz::nextSelectedTrack(rows, 3), 5);
  EXPECT_EQ(viz::nextSelectedTrack({}, 3), -1);
  io::TrackRow sel = rows[1];
  sel.speed = 5.0;
  const std::string text = viz::overlayText(12, 77, 1.2, 2, &sel);
  EXPECT_NE(text.find("frame 12/76"), std::string::npos) << text;
  EXPECT_NE(text.find("movers: 2"), std::string::npos) << text;
  EXPECT_NE(text.find("track 5 (mover): 5.0 m/s"), std::string::npos) << text;
  // The overlay names the frame as tracks.csv does: index and file number.
  const std::string with_file = viz::overlayText(3, 77, 0.3, 0, nullptr, "", 43);
  EXPECT_NE(with_file.find("frame 3/76 (file 000043)"), std::string::npos) << with_file;
}

// ------------------------------------------------------------------ the tool

class ViewerTool : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(toolPath()))
      GTEST_SKIP() << "pcl_movers_viewer not built (" << toolPath() << ")";
  }
};

TEST_F(ViewerTool, HelpListsKeysAndDefaults) {
  TempDir tmp("help");
  const auto r = runTool("-h", tmp.path / "log");
  EXPECT_EQ(r.code, 0);
  for (const char* s :
       {"--screenshot-dir", "--detections", "--movers-only", "--point-labels", "--pcap", "space",
        "tab", "1 / 2 / 3", "(default: chase)", "(default: 1280x720)"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s << "\n" << r.output;
}

TEST_F(ViewerTool, BadInputsFailWithClearMessages) {
  TempDir tmp("bad");
  SyntheticScene scene(tmp.path);
  const std::string seq = "\"" + scene.seq.string() + "\"";
  const fs::path shots = tmp.path / "shots";
  const std::string out = " --screenshot-dir \"" + shots.string() + "\"";
  // Bad tracks.csv: garbage row; another with frames beyond the sequence.
  fs::create_directories(tmp.path / "garbage");
  std::ofstream(tmp.path / "garbage" / "tracks.csv")
      << io::tracksCsvHeader() << "\n1,0.1,2,1,not-a-number\n";
  fs::create_directories(tmp.path / "late");
  {
    io::TrackRow r;
    r.frame = 40;
    io::writeTracks((tmp.path / "late" / "tracks.csv").string(), {r});
  }
  struct Case {
    std::string args, expect;
  };
  // Each run costs about a second of tool start-up, so only one case per kind of error here; the
  // parsers themselves are covered exhaustively by the SceneStyle tests above.
  const std::vector<Case> cases = {
      {"\"" + (tmp.path / "nope").string() + "\"" + out, "no such sequence folder"},
      {seq + " --detections \"" + (tmp.path / "garbage").string() + "\"" + out, "tracks.csv"},
      {seq + " --detections \"" + (tmp.path / "late").string() + "\"" + out, "frame 40"},
      {seq + " --frames 1:9" + out, "out of range"},
      {seq + " --size 0x10" + out, "--size"},
      {seq + " --camera top" + out, "unknown camera"},
      {seq + " --bogus" + out, "--bogus"},
      {seq + " --ground-truth" + out, "objects.txt"},
  };
  for (const auto& c : cases) {
    const auto r = runTool(c.args, tmp.path / "log");
    EXPECT_NE(r.code, 0) << c.args;
    EXPECT_NE(r.output.find(c.expect), std::string::npos)
        << c.args << "\nexpected '" << c.expect << "' in:\n"
        << r.output;
    EXPECT_EQ(r.output.find("Segmentation"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(shots)) << "output folder left behind by: " << c.args;
  }
  // A non-empty output folder is not written into without --overwrite.
  fs::create_directories(shots);
  std::ofstream(shots / "000001.png") << "mine";
  const auto r = runTool(seq + out, tmp.path / "log");
  EXPECT_NE(r.code, 0);
  std::ifstream kept(shots / "000001.png");
  std::string content;
  kept >> content;
  EXPECT_EQ(content, "mine");
}

TEST_F(ViewerTool, RendersTheMoverInRedWhereItProjects) {
  if (!hasDisplay()) GTEST_SKIP() << "no X display (DISPLAY unset): run the tests under xvfb-run";
  TempDir tmp("render");
  SyntheticScene scene(tmp.path);
  const int w = 640, h = 480;
  // One camera here (the KITTI test below checks the chase camera): each run costs seconds.
  for (const char* camera : {"bird"}) {
    const fs::path shots = tmp.path / (std::string("shots_") + camera);
    const auto r = runTool("\"" + scene.seq.string() + "\" --detections \"" + scene.det.string() +
                               "\" --frames 1 --size 640x480 --format ppm --camera " + camera +
                               " --screenshot-dir \"" + shots.string() + "\"",
                           tmp.path / "log");
    ASSERT_EQ(r.code, 0) << r.output;
    Image im;
    ASSERT_TRUE(readPpm(shots / "000001.ppm", im));
    ASSERT_EQ(im.width, w);
    ASSERT_EQ(im.height, h);
    // Not blank: a good share of pixels differ from the background.
    const viz::SceneStyle style;
    std::size_t drawn = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const auto* p = im.at(x, y);
        drawn += (p[0] != style.background.r || p[1] != style.background.g ||
                  p[2] != style.background.b);
      }
    EXPECT_GT(drawn, static_cast<std::size_t>(w * h / 20)) << camera;
    // Mover-red pixels where the mover's box projects, and (almost) nowhere else.
    const auto cam = viz::cameraView(viz::parseCameraPreset(camera));
    viz::OrientedBox box;
    box.center = scene.mover_center;
    box.length = 4, box.width = 2, box.height = 1.5;
    const int inside = countRedInBox(im, cam, box);
    const int total = countRed(im);
    EXPECT_GT(inside, 30) << camera;
    EXPECT_GE(inside, total * 9 / 10) << camera << ": red pixels away from the mover";
  }
  // Without detections the same frame has no mover colour at all: red comes from the tracks.
  const fs::path plain = tmp.path / "plain";
  const auto r = runTool("\"" + scene.seq.string() +
                             "\" --frames 1 --size 640x480 --format ppm --camera bird"
                             " --screenshot-dir \"" +
                             plain.string() + "\"",
                         tmp.path / "log");
  ASSERT_EQ(r.code, 0) << r.output;
  Image im;
  ASSERT_TRUE(readPpm(plain / "000001.ppm", im));
  EXPECT_EQ(countRed(im), 0);
}

// --pcap: the viewer decodes a capture's sweeps and detects while playing. The simulated scene's
// capture (data/scenarios/sample.yaml as HDL-32E packets) gives one image per sweep; its mover
// turns red once the tracker confirms it, never on the first sweep (no track is a mover there).
TEST_F(ViewerTool, PlaysACaptureDetectingItsMovers) {
  if (!hasDisplay()) GTEST_SKIP() << "no X display (DISPLAY unset): run the tests under xvfb-run";
  const std::string simulate = std::string(PCL_MOVERS_BINARY_DIR) + "/apps/pcl_movers_simulate";
  if (access(simulate.c_str(), X_OK) != 0) GTEST_SKIP() << "pcl_movers_simulate not built";
  TempDir tmp("pcap");
  const fs::path pcap = tmp.path / "scene.pcap";
  const std::string sim = "\"" + simulate +
                          "\" \"" PCL_MOVERS_SOURCE_DIR "/data/scenarios/sample.yaml\" \"" +
                          (tmp.path / "scene").string() + "\" --sensor hdl32 --pcap \"" +
                          pcap.string() + "\" > \"" + (tmp.path / "sim.log").string() + "\" 2>&1";
  ASSERT_EQ(std::system(sim.c_str()), 0);
  const fs::path shots = tmp.path / "shots";
  const auto r = runTool("--pcap \"" + pcap.string() +
                             "\" --sensor hdl32 --frames 0:30 --size 320x240 --format ppm "
                             "--camera bird --screenshot-dir \"" +
                             shots.string() + "\"",
                         tmp.path / "log");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("full hdl32 sweeps"), std::string::npos) << r.output;
  std::size_t images = 0;
  for (const auto& e : fs::directory_iterator(shots)) images += e.path().extension() == ".ppm";
  EXPECT_EQ(images, 31u);
  Image first, last;
  ASSERT_TRUE(readPpm(shots / "000000.ppm", first));
  ASSERT_TRUE(readPpm(shots / "000030.ppm", last));
  EXPECT_EQ(countRed(first), 0);
  EXPECT_GT(countRed(last), 10) << "no mover detected in the capture's sweep 30";
  // A capture and a folder together, a missing capture, --detections with a capture.
  const std::string out = " --screenshot-dir \"" + (tmp.path / "bad").string() + "\"";
  for (const auto& c : std::vector<std::pair<std::string, std::string>>{
           {"--pcap \"" + pcap.string() + "\" \"" + (tmp.path / "scene").string() + "\"",
            "exclude each other"},
           {"--pcap \"" + (tmp.path / "none.pcap").string() + "\"", "none.pcap"},
           {"--pcap \"" + pcap.string() + "\" --detections \"" + tmp.path.string() + "\"",
            "--detections"},
           {"--pcap \"" + pcap.string() + "\" --sensor os1_64", "os1_64"}}) {
    const auto b = runTool(c.first + out, tmp.path / "log");
    EXPECT_NE(b.code, 0) << c.first;
    EXPECT_NE(b.output.find(c.second), std::string::npos) << c.first << "\n" << b.output;
  }
}

// --movers-only draws the mover (its points, box, arrow, trail) and nothing else: the ground and
// the pole vanish, the mover stays where it was.
TEST_F(ViewerTool, MoversOnlyDrawsOnlyTheMovers) {
  if (!hasDisplay()) GTEST_SKIP() << "no X display (DISPLAY unset): run the tests under xvfb-run";
  TempDir tmp("movers_only");
  SyntheticScene scene(tmp.path);
  const int w = 640, h = 480;
  auto render = [&](const std::string& name, const std::string& extra, Image& im) {
    const fs::path shots = tmp.path / name;
    const auto r = runTool("\"" + scene.seq.string() + "\" --detections \"" + scene.det.string() +
                               "\" --frames 1 --size 640x480 --format ppm --camera bird" + extra +
                               " --screenshot-dir \"" + shots.string() + "\"",
                           tmp.path / "log");
    ASSERT_EQ(r.code, 0) << r.output;
    ASSERT_TRUE(readPpm(shots / "000001.ppm", im));
  };
  const viz::SceneStyle style;
  auto drawn = [&](const Image& im) {
    std::size_t n = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const auto* p = im.at(x, y);
        n += (p[0] != style.background.r || p[1] != style.background.g ||
              p[2] != style.background.b);
      }
    return n;
  };
  Image all, movers;
  render("all", "", all);
  render("movers", " --movers-only", movers);
  const auto cam = viz::cameraView(viz::CameraPreset::Bird);
  viz::OrientedBox box;
  box.center = scene.mover_center;
  box.length = 4, box.width = 2, box.height = 1.5;
  EXPECT_GT(countRedInBox(movers, cam, box), 30) << "the mover must still be drawn";
  EXPECT_LT(drawn(movers) * 4, drawn(all)) << "ground and pole must be left out";
}

// A labelled/ folder copied from another run is refused, naming it: its run_key.txt differs
// from summary.json's run_key, or its clouds are named after frames the sequence lacks.
TEST_F(ViewerTool, RefusesALabelledFolderOfAnotherRun) {
  TempDir tmp("foreign_labelled");
  SyntheticScene scene(tmp.path);
  const fs::path labelled = scene.det / "labelled";
  fs::create_directories(labelled);
  std::ofstream(scene.det / "summary.json") << "{\n  \"run_key\": \"1111222233334444\"\n}\n";
  std::ofstream(labelled / "run_key.txt") << "9999888877776666\n";
  const std::string args = "\"" + scene.seq.string() + "\" --detections \"" + scene.det.string() +
                           "\" --screenshot-dir \"" + (tmp.path / "shots").string() + "\"";
  auto r = runTool(args, tmp.path / "log");
  EXPECT_NE(r.code, 0) << r.output;
  EXPECT_NE(r.output.find(labelled.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("another run"), std::string::npos) << r.output;
  // The matching stamp is accepted as far as the labelled clouds go; a cloud of a frame the
  // sequence does not have is not.
  std::ofstream(labelled / "run_key.txt") << "1111222233334444\n";
  std::ofstream(labelled / "000042.pcd") << "not read: refused before";
  r = runTool(args, tmp.path / "log");
  EXPECT_NE(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("000042.pcd"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("another sequence"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path / "shots"));
}

TEST_F(ViewerTool, WritesPngScreenshotsOfAFrameRange) {
  if (!hasDisplay()) GTEST_SKIP() << "no X display (DISPLAY unset): run the tests under xvfb-run";
  TempDir tmp("png");
  SyntheticScene scene(tmp.path);
  const fs::path shots = tmp.path / "shots";
  const auto r =
      runTool("\"" + scene.seq.string() + "\" --detections \"" + scene.det.string() +
                  "\" --frames 0:2 --size 320x200 --screenshot-dir \"" + shots.string() + "\"",
              tmp.path / "log");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* name : {"000000.png", "000001.png", "000002.png"}) {
    std::ifstream in(shots / name, std::ios::binary);
    ASSERT_TRUE(in) << name;
    unsigned char head[24] = {};
    in.read(reinterpret_cast<char*>(head), 24);
    const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    EXPECT_TRUE(std::equal(sig, sig + 8, head)) << name;
    // IHDR: big-endian width and height.
    const int width = (head[16] << 24) | (head[17] << 16) | (head[18] << 8) | head[19];
    const int height = (head[20] << 24) | (head[21] << 16) | (head[22] << 8) | head[23];
    EXPECT_EQ(width, 320);
    EXPECT_EQ(height, 200);
    // A uniform 320x200 PNG compresses to well under 1 kB; a rendered scene does not.
    EXPECT_GT(fs::file_size(shots / name), 4000u) << name;
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(shots), fs::directory_iterator()), 3);
}

TEST_F(ViewerTool, KittiMoverIsRedInTheChaseView) {
  if (!hasDisplay()) GTEST_SKIP() << "no X display (DISPLAY unset): run the tests under xvfb-run";
  const fs::path seq = fs::path(PCL_MOVERS_SHARED_DATA) / "kitti-tracking-0000-a";
  if (!fs::exists(seq / "objects.txt"))
    GTEST_SKIP() << "KITTI data not found in " << seq << " (PCL_MOVERS_SHARED_DATA)";
  // tracks.csv made from the ground truth (what a perfect detector would write).
  TempDir tmp("kitti");
  const io::SequenceReader reader(seq.string());
  std::vector<io::TrackRow> rows;
  const int frame = 20;
  io::GroundTruthObject van;
  bool found = false;
  for (const auto& o : io::readObjects(reader.objectsPath())) {
    if (o.frame != frame) continue;
    io::TrackRow r;
    r.frame = o.frame, r.track_id = o.track_id, r.mover = o.moving;
    r.x = o.center.x(), r.y = o.center.y(), r.z = o.center.z();
    const Eigen::Vector3d w = reader.pose(frame) * o.center;
    r.wx = w.x(), r.wy = w.y(), r.wz = w.z();
    r.length = o.length, r.width = o.width, r.height = o.height, r.yaw = o.yaw;
    r.points = o.n_points;
    rows.push_back(r);
    if (o.moving && o.type == "Van") van = o, found = true;
  }
  ASSERT_TRUE(found) << "no moving van in frame " << frame;
  io::writeTracks((tmp.path / "tracks.csv").string(), rows);
  const fs::path shots = tmp.path / "shots";
  const auto r = runTool("\"" + seq.string() + "\" --detections \"" + tmp.path.string() +
                             "\" --frames 20 --size 640x360 --format ppm --camera chase"
                             " --screenshot-dir \"" +
                             shots.string() + "\"",
                         tmp.path / "log");
  ASSERT_EQ(r.code, 0) << r.output;
  Image im;
  ASSERT_TRUE(readPpm(shots / "000020.ppm", im));
  const int inside = countRedInBox(im, viz::cameraView(viz::CameraPreset::Chase),
                                   viz::OrientedBox::fromGroundTruth(van));
  EXPECT_GT(inside, 100) << "too few mover-red pixels on the moving van";
}

}  // namespace
