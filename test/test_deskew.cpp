/*
 * Tests of per-point times and de-skewing: the simulator's rolling sweep and its `time` field,
 * io::readPointTimes on the drivers' field names, deskewScan and pcl_movers_detect's --deskew.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/deskew.h>
#include <pcl_movers/io/point_times.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>
#include <pcl_movers/sim/scene_families.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using namespace pcl_movers;
using namespace pcl_movers::sim;

namespace {

constexpr int kPole = 1;  // track id of the pole (first object)

/** A flat scene with a pole and a wall, the ego driving at `speed` and turning at `turn_deg`/s. */
Scenario staticScene(const std::string& sweep, double speed, double turn_deg) {
  Scenario sc;
  sc.frames = 4;
  sc.sensor.preset = "hdl64";
  sc.sensor.range_noise = 0.0;
  sc.sensor.dropout = 0.0;
  sc.sensor.min_range = 1.0;
  sc.sensor.sweep = sweep;
  sc.ego.speed = speed;
  sc.ego.segments.push_back({10.0, -1.0, turn_deg * M_PI / 180.0, false});
  ObjectSpec pole;  // right of the road ahead: taken 60 % into the sweep
  pole.type = "pole";
  pole.trajectory.start = {2.0 * speed * 0.1 + 10.0, -8.0};
  pole.radius = 0.15;
  ObjectSpec wall;  // across the road ahead, its face at wallFace(speed)
  wall.type = "wall";
  wall.trajectory.start = {2.0 * speed * 0.1 + 25.0, 0.0};
  wall.trajectory.heading = M_PI / 2;
  wall.size = {12.0, 0.4, 2.5};
  sc.objects = {pole, wall};
  return sc;
}

struct Scan {
  pcl::PointCloud<pcl::PointXYZI> cloud;
  std::vector<std::uint32_t> labels;
  std::vector<io::GroundTruthObject> objects;
  Eigen::Isometry3d pose;
};

Scan simulate(const LidarSimulator& sim, int frame) {
  Scan s;
  sim.simulate(frame, s.cloud, s.labels, s.objects, s.pose);
  return s;
}

/** Mean x, y of the returns labelled with `track`. */
Eigen::Vector2d centroid(const Scan& s, int track) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int n = 0;
  for (std::size_t k = 0; k < s.cloud.size(); ++k)
    if (int(s.labels[k] >> 16) == track && std::isfinite(s.cloud[k].x)) {
      sum += Eigen::Vector2d(s.cloud[k].x, s.cloud[k].y);
      ++n;
    }
  EXPECT_GT(n, 20) << "track " << track;
  return n > 0 ? Eigen::Vector2d(sum / n) : sum;
}

/** The column times of a rolling scan, as the simulator writes them. */
std::vector<float> columnTimes(const LidarSimulator& sim, const Scan& s) {
  std::vector<float> t(s.cloud.size());
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = float(sim.columnTime(int(k % s.cloud.width)));
  return t;
}

/** World x of the face of staticScene()'s wall. */
double wallFace(double speed) {
  return 2.0 * speed * 0.1 + 24.8;
}

/** Worst distance of the wall's points from its face plane x = `face` (world = sensor frame of
 * frame 0, the ego starting at the origin heading +x on flat ground). */
double wallError(const Scan& s, double face) {
  double worst = 0;
  for (std::size_t k = 0; k < s.cloud.size(); ++k)
    if (int(s.labels[k] >> 16) == 2 && std::isfinite(s.cloud[k].x)) {
      const Eigen::Vector3d w = s.pose * s.cloud[k].getVector3fMap().cast<double>();
      worst = std::max(worst, std::abs(w.x() - face));
    }
  return worst;
}

std::string tempDir(const std::string& name) {
  std::string tmpl = "/tmp/pcl_movers_" + name + "_XXXXXX";
  std::vector<char> buf(tmpl.begin(), tmpl.end());
  buf.push_back('\0');
  EXPECT_NE(mkdtemp(buf.data()), nullptr);
  return buf.data();
}

}  // namespace

// A rolling sweep at 20 m/s (straight, and turning at 30 deg/s) tears the pole away from where
// the instant scan has it; de-skewing with the previous frame's pose puts it back.
TEST(Deskew, RollingSweepOfAStaticSceneIsPutBack) {
  for (const double turn : {0.0, 30.0}) {
    SCOPED_TRACE("turn rate " + std::to_string(turn) + " deg/s");
    const LidarSimulator instant(staticScene("instant", 20.0, turn));
    const LidarSimulator rolling(staticScene("rolling", 20.0, turn));
    const Scan ref = simulate(instant, 2);
    Scan scan = simulate(rolling, 2);
    EXPECT_TRUE(ref.pose.isApprox(scan.pose, 1e-12));  // the frame pose: the sweep's start
    const Eigen::Vector2d truth = centroid(ref, kPole);
    const double before = (centroid(scan, kPole) - truth).norm();
    const StampedPose frame{scan.pose, rolling.time(2), true};
    const StampedPose previous{rolling.pose(1), rolling.time(1), true};
    ASSERT_TRUE(deskewScan(scan.cloud, columnTimes(rolling, scan), frame, previous));
    const double after = (centroid(scan, kPole) - truth).norm();
    EXPECT_GT(before, 0.9);  // ~60 % of 2 m
    EXPECT_LT(after, 0.1);
    EXPECT_LT(wallError(scan, wallFace(20.0)), 0.1);
    // The next frame's pose (used at a sequence's first frame) does the same.
    Scan again = simulate(rolling, 2);
    const StampedPose next{rolling.pose(3), rolling.time(3), true};
    deskewScan(again.cloud, columnTimes(rolling, again), frame, next);
    EXPECT_LT((centroid(again, kPole) - truth).norm(), 0.1);
  }
}

TEST(Deskew, InstantSweepIsUnchangedAndGroundTruthIsAtTheFrameTime) {
  const LidarSimulator instant(staticScene("instant", 20.0, 0.0));
  const LidarSimulator rolling(staticScene("rolling", 20.0, 0.0));
  EXPECT_EQ(instant.columnTime(1000), 0.0);
  EXPECT_NEAR(rolling.columnTime(1100), 0.05, 1e-12);  // half of the 2200 columns, 10 Hz
  const Scan a = simulate(instant, 1), b = simulate(rolling, 1);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (std::size_t i = 0; i < a.objects.size(); ++i)
    EXPECT_TRUE(a.objects[i].center.isApprox(b.objects[i].center, 1e-9));
  EXPECT_LT(wallError(a, wallFace(20.0)), 0.05);
  EXPECT_GT(wallError(b, wallFace(20.0)), 0.8);  // taken ~0.05 s into the sweep: ~1 m nearer
}

TEST(Deskew, ScanWithoutTimesIsUnchanged) {
  const LidarSimulator instant(staticScene("instant", 20.0, 0.0));
  Scan scan = simulate(instant, 2);
  const pcl::PointCloud<pcl::PointXYZI> copy = scan.cloud;
  const StampedPose frame{scan.pose, 0.2, true}, previous{instant.pose(1), 0.1, true};
  EXPECT_FALSE(deskewScan(scan.cloud, {}, frame, previous));
  ASSERT_EQ(std::memcmp(copy.points.data(), scan.cloud.points.data(),
                        copy.size() * sizeof(pcl::PointXYZI)),
            0);
  // Through ScanDeskewer on a PCD without a time field: unchanged in auto, an error with "on".
  const std::string dir = tempDir("deskew_notimes");
  const std::string path = dir + "/000000.pcd";
  pcl::io::savePCDFileBinary(path, scan.cloud);
  ScanDeskewer automatic("auto");
  EXPECT_FALSE(automatic.apply(path, scan.cloud, frame, previous));
  EXPECT_EQ(std::memcmp(copy.points.data(), scan.cloud.points.data(),
                        copy.size() * sizeof(pcl::PointXYZI)),
            0);
  EXPECT_NE(automatic.toJson().find("\"frames\": 0"), std::string::npos);
  ScanDeskewer required("on");
  EXPECT_THROW(required.apply(path, scan.cloud, frame, previous), InputError);
  EXPECT_THROW(ScanDeskewer("sometimes"), InputError);
  EXPECT_THROW(deskewScan(scan.cloud, std::vector<float>(3, 0.f), frame, previous), InputError);
  fs::remove_all(dir);
}

// The simulator writes `time` only for a rolling sweep; readPointTimes gives it back per point.
TEST(PointTimes, SimulatorWritesTimeFieldForRollingSweep) {
  const std::string dir = tempDir("point_times");
  for (const std::string sweep : {"instant", "rolling"}) {
    Scenario sc = staticScene(sweep, 10.0, 0.0);
    sc.sensor.preset = "vlp16";
    sc.frames = 2;
    const LidarSimulator sim(sc);
    writeSequence(sim, dir + "/" + sweep, false);
    const std::string frame = dir + "/" + sweep + "/frames/000001.pcd";
    const std::vector<float> times = io::readPointTimes(frame);
    if (sweep == "instant") {
      EXPECT_TRUE(times.empty());
      EXPECT_EQ(io::pointTimeField(frame), "");
      continue;
    }
    EXPECT_EQ(io::pointTimeField(frame), "time");
    pcl::PointCloud<pcl::PointXYZI> cloud;
    io::readScan(frame, cloud);
    ASSERT_EQ(times.size(), cloud.size());
    ASSERT_EQ(cloud.width, 1800u);
    for (std::size_t k = 0; k < times.size(); k += 97)
      EXPECT_FLOAT_EQ(times[k], float(double(k % 1800) / 18000.0)) << k;
  }
  fs::remove_all(dir);
}

TEST(PointTimes, OusterNanosecondsAndAbsoluteTimestamps) {
  const std::string dir = tempDir("point_times_drivers");
  for (const std::string field : {"t", "timestamp"}) {
    pcl::PCLPointCloud2 cloud;
    cloud.width = 3;
    cloud.height = 1;
    const bool ns = field == "t";
    std::uint32_t offset = 0;
    for (const char* name : {"x", "y", "z"}) {
      pcl::PCLPointField f;
      f.name = name;
      f.offset = offset;
      f.datatype = pcl::PCLPointField::FLOAT32;
      f.count = 1;
      cloud.fields.push_back(f);
      offset += 4;
    }
    pcl::PCLPointField f;
    f.name = field;
    f.offset = offset;
    f.datatype = ns ? pcl::PCLPointField::UINT32 : pcl::PCLPointField::FLOAT64;
    f.count = 1;
    cloud.fields.push_back(f);
    cloud.point_step = offset + (ns ? 4 : 8);
    cloud.row_step = cloud.point_step * cloud.width;
    cloud.data.assign(cloud.row_step, 0);
    for (std::uint32_t i = 0; i < 3; ++i) {
      std::uint8_t* p = &cloud.data[i * cloud.point_step + offset];
      if (ns) {
        const std::uint32_t v = 25000000u * i;  // 0, 25, 50 ms
        std::memcpy(p, &v, 4);
      } else {
        const double v = 1700000000.0 + 0.025 * i;  // absolute seconds
        std::memcpy(p, &v, 8);
      }
    }
    const std::string path = dir + "/" + field + ".pcd";
    ASSERT_EQ(pcl::PCDWriter().writeBinary(path, cloud), 0);
    EXPECT_EQ(io::pointTimeField(path), field);
    const std::vector<float> times = io::readPointTimes(path);
    ASSERT_EQ(times.size(), 3u);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(times[i], 0.025 * i, 1e-6) << field;
  }
  EXPECT_THROW(io::readPointTimes(dir + "/missing.pcd"), InputError);
  fs::remove_all(dir);
}

// pcl_movers_detect de-skews a rolling sweep's frames with --deskew auto and says so in
// summary.json.
TEST(DeskewTool, DetectReportsDeskewedFrames) {
  const std::string dir = tempDir("deskew_tool");
  Scenario sc = staticScene("rolling", 10.0, 0.0);
  sc.sensor.preset = "vlp16";
  sc.frames = 3;
  writeSequence(LidarSimulator(sc), dir + "/seq", false);
  for (const std::string mode : {"auto", "off"}) {
    const std::string out = dir + "/out_" + mode;
    const std::string cmd = std::string(PCL_MOVERS_BINARY_DIR) + "/apps/pcl_movers_detect " + dir +
                            "/seq " + out + " --deskew " + mode + " > " + dir + "/log 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::ifstream in(out + "/summary.json");
    std::stringstream text;
    text << in.rdbuf();
    const std::string expected = mode == "auto"
                                     ? "\"deskew\": {\"mode\": \"auto\", \"time_field\": "
                                       "\"time\", \"frames\": 3"
                                     : "\"deskew\": {\"mode\": \"off\"";
    EXPECT_NE(text.str().find(expected), std::string::npos) << text.str();
  }
  fs::remove_all(dir);
}

TEST(PointTimes, ScenarioSweepKeyIsCheckedAndRoundTrips) {
  const std::string base = "ego: {start: [0, 0]}\nsensor:\n  preset: vlp16\n  sweep: ";
  EXPECT_EQ(parseScenario(base + "rolling\n", "s.yaml").sensor.sweep, "rolling");
  EXPECT_EQ(parseScenario("ego: {start: [0, 0]}\n", "s.yaml").sensor.sweep, "instant");
  try {
    parseScenario(base + "sideways\n", "s.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:4: 'sensor.sweep'"), std::string::npos)
        << e.what();
  }
  Scenario sc = staticScene("rolling", 5.0, 0.0);
  EXPECT_EQ(parseScenario(toYaml(sc), "gen.yaml").sensor.sweep, "rolling");
  sc.sensor.sweep = "instant";
  EXPECT_EQ(toYaml(sc).find("sweep"), std::string::npos);  // generated scenes unchanged
}
