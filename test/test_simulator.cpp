/*
 * Tests of the scene simulator: exact ranges, noise, labels vs objects.txt, occlusion, foliage,
 * motion, determinism, limited field of view.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
using namespace pcl_movers;
using namespace pcl_movers::sim;

namespace {

/** A flat, empty, noise-free scene; tests add what they need. */
Scenario emptyScene() {
  Scenario sc;
  sc.frames = 5;
  sc.sensor.range_noise = 0.0;
  sc.sensor.dropout = 0.0;
  sc.sensor.min_range = 0.5;
  sc.sensor.max_range = 80.0;
  sc.ego.speed = 0.0;
  return sc;
}

ObjectSpec staticObject(const std::string& type, double x, double y, double yaw_deg = 0,
                        Eigen::Vector3d size = Eigen::Vector3d::Zero()) {
  ObjectSpec o;
  o.type = type;
  o.trajectory.start = {x, y};
  o.trajectory.heading = yaw_deg * M_PI / 180.0;
  o.size = size;
  return o;
}

struct Frame {
  pcl::PointCloud<pcl::PointXYZI> cloud;
  std::vector<std::uint32_t> labels;
  std::vector<io::GroundTruthObject> objects;
  Eigen::Isometry3d pose;
};

Frame simulate(const LidarSimulator& sim, int f) {
  Frame fr;
  sim.simulate(f, fr.cloud, fr.labels, fr.objects, fr.pose);
  return fr;
}

const io::GroundTruthObject* findObject(const Frame& fr, int track) {
  for (const auto& o : fr.objects)
    if (o.track_id == track) return &o;
  return nullptr;
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path tempDir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("pcl_movers_test_sim_" + name);
  fs::remove_all(p);
  return p;
}

}  // namespace

TEST(LidarSimulator, OrganizedLayoutAndExactGroundRanges) {
  Scenario sc = emptyScene();
  LidarSimulator sim(sc);
  const Frame fr = simulate(sim, 0);
  const SensorModel& s = sim.getSensor();
  ASSERT_EQ(fr.cloud.height, std::uint32_t(s.rows()));
  ASSERT_EQ(fr.cloud.width, std::uint32_t(s.columns()));
  ASSERT_EQ(fr.labels.size(), fr.cloud.size());
  EXPECT_FALSE(fr.cloud.is_dense);
  int ground = 0, sky = 0;
  double worst = 0;
  for (int r = 0; r < s.rows(); ++r) {
    const double el = s.elevations()[r];
    for (int c = 0; c < s.columns(); ++c) {
      const auto& p = fr.cloud.at(c, r);
      const double expected = el < 0 ? sc.sensor.height / -std::sin(el) : 1e9;
      if (expected > sc.sensor.max_range) {
        EXPECT_TRUE(std::isnan(p.x)) << "row " << r << " col " << c;
        EXPECT_EQ(fr.labels[std::size_t(r) * s.columns() + c], 0u);
        ++sky;
        continue;
      }
      ASSERT_FALSE(std::isnan(p.x)) << "row " << r << " col " << c;
      const double range = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
      worst = std::max(worst, std::abs(range - expected));
      // The point lies in its own beam and column.
      EXPECT_NEAR(std::atan2(p.y, p.x), std::remainder(s.azimuthOf(c), 2 * M_PI), 1e-4);
      EXPECT_EQ(io::labelClass(fr.labels[std::size_t(r) * s.columns() + c]),
                io::semantic::kTerrain);
      ++ground;
    }
  }
  EXPECT_LT(worst, 2e-3);  // float storage of up to 80 m
  EXPECT_GT(ground, 10000);
  EXPECT_GT(sky, 1000);
  EXPECT_TRUE(fr.objects.empty());
}

TEST(LidarSimulator, ExactRangeToWallFace) {
  Scenario sc = emptyScene();
  sc.objects.push_back(staticObject("wall", 20.0, 0.0, 0, {1.0, 30.0, 5.0}));
  LidarSimulator sim(sc);
  const Frame fr = simulate(sim, 0);
  int hits = 0;
  for (std::size_t i = 0; i < fr.cloud.size(); ++i) {
    if (io::labelInstance(fr.labels[i]) != 1) continue;
    ++hits;
    EXPECT_EQ(io::labelClass(fr.labels[i]), io::semantic::kFence);
    EXPECT_NEAR(fr.cloud[i].x, 19.5, 2e-3);  // front face of the 1 m thick wall
    EXPECT_LE(std::abs(fr.cloud[i].y), 15.0 + 1e-3);
    EXPECT_LE(fr.cloud[i].z, 5.0 - sc.sensor.height + 1e-3);
  }
  EXPECT_GT(hits, 1000);
  const io::GroundTruthObject* wall = findObject(fr, 1);
  ASSERT_NE(wall, nullptr);
  EXPECT_EQ(wall->n_points, hits);
  EXPECT_EQ(wall->type, "Wall");
  EXPECT_NEAR(wall->center.x(), 20.0, 1e-9);
}

TEST(LidarSimulator, RangeNoiseAndDropoutHaveTheRequestedStatistics) {
  Scenario sc = emptyScene();
  sc.sensor.range_noise = 0.05;
  sc.sensor.dropout = 0.1;
  LidarSimulator sim(sc);
  const Frame fr = simulate(sim, 0);
  const SensorModel& s = sim.getSensor();
  double sum = 0, sum2 = 0;
  int n = 0, expected_returns = 0;
  for (int r = 0; r < s.rows(); ++r) {
    const double el = s.elevations()[r];
    if (el >= 0) continue;
    const double expected = sc.sensor.height / -std::sin(el);
    if (expected > sc.sensor.max_range - 1.0) continue;
    for (int c = 0; c < s.columns(); ++c) {
      ++expected_returns;
      const auto& p = fr.cloud.at(c, r);
      if (std::isnan(p.x)) continue;
      const double e = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z) - expected;
      sum += e;
      sum2 += e * e;
      ++n;
    }
  }
  const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.005);
  EXPECT_NEAR(sigma, 0.05, 0.005);
  EXPECT_NEAR(1.0 - double(n) / expected_returns, 0.1, 0.01);
}

TEST(LidarSimulator, OccludedObjectGetsNoHits) {
  Scenario sc = emptyScene();
  sc.objects.push_back(staticObject("building", 12.0, 0.0, 0, {2.0, 12.0, 6.0}));  // id 1
  sc.objects.push_back(staticObject("car", 22.0, 0.0));                            // id 2, behind
  sc.objects.push_back(staticObject("car", 22.0, 15.0));                           // id 3, visible
  const Frame fr = simulate(LidarSimulator(sc), 0);
  ASSERT_NE(findObject(fr, 2), nullptr);
  EXPECT_EQ(findObject(fr, 2)->n_points, 0);
  EXPECT_GT(findObject(fr, 3)->n_points, 100);
  // Without the building the same car is seen well.
  sc.objects.erase(sc.objects.begin());
  const Frame open = simulate(LidarSimulator(sc), 0);
  EXPECT_GT(findObject(open, 1)->n_points, 100);
}

TEST(LidarSimulator, ObjectAcrossTheRangeLimitKeepsItsRowWhileItHasPoints) {
  // A 4.4 m car pointing at the sensor with its centre 1 m beyond max_range: its near end is in
  // range and returns points, so it must have a ground-truth box (a detection of those points
  // would otherwise count as a false alarm). A car wholly beyond the range has no row.
  Scenario sc = emptyScene();
  sc.sensor.max_range = 40.0;
  sc.objects.push_back(staticObject("car", 41.0, 0.0));   // id 1, centre out, near end in
  sc.objects.push_back(staticObject("car", 0.0, 50.0));   // id 2, wholly out of range
  sc.objects.push_back(staticObject("car", 20.0, 10.0));  // id 3, in range
  const Frame fr = simulate(LidarSimulator(sc), 0);
  const auto* cut = findObject(fr, 1);
  ASSERT_NE(cut, nullptr);
  EXPECT_GT(cut->n_points, 0);
  EXPECT_GT(cut->center.norm(), sc.sensor.max_range);
  EXPECT_EQ(findObject(fr, 2), nullptr);
  ASSERT_NE(findObject(fr, 3), nullptr);
}

TEST(LidarSimulator, FoliageIsPorous) {
  Scenario sc = emptyScene();
  ObjectSpec bush = staticObject("brush", 10.0, 0.0);
  bush.radius = 1.5;
  bush.size.z() = 2.5;
  sc.objects.push_back(bush);
  sc.objects.push_back(staticObject("wall", 16.0, 0.0, 0, {0.5, 8.0, 3.0}));
  const Frame fr = simulate(LidarSimulator(sc), 0);
  const int bush_points = findObject(fr, 1)->n_points;
  EXPECT_GT(bush_points, 100);
  // Some wall points are seen through the bush: their columns point at the bush.
  int through = 0, bush_depth_spread = 0;
  for (std::size_t i = 0; i < fr.cloud.size(); ++i) {
    const auto& p = fr.cloud[i];
    if (io::labelInstance(fr.labels[i]) == 2) {
      // Does the ray to this wall point cross the bush's ellipsoid (centre 10, 0, 1.125 above
      // ground, radii 1.5, 1.2, 1.375)?
      const Eigen::Vector3d radii(1.5, 1.2, 1.375);
      const Eigen::Vector3d c(10.0, 0.0, 1.125 - sc.sensor.height);
      const Eigen::Vector3d d = p.getVector3fMap().cast<double>().normalized();
      const Eigen::Vector3d os = (-c).cwiseQuotient(radii), ds = d.cwiseQuotient(radii);
      const double a = ds.squaredNorm(), b = os.dot(ds), cc = os.squaredNorm() - 1.0;
      if (b * b - a * cc > 0) ++through;
    }
    if (io::labelInstance(fr.labels[i]) == 1 && p.x > 9.0) ++bush_depth_spread;
  }
  EXPECT_GT(through, 0);
  EXPECT_GT(bush_depth_spread, 10);  // penetration: returns from inside the crown
}

TEST(LidarSimulator, LabelsAgreeWithObjectsOnTheSample) {
  const std::string path = std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/sample.yaml";
  Scenario sc = loadScenario(path);
  LidarSimulator sim(sc);
  for (int f : {0, 17, sc.frames - 1}) {
    const Frame fr = simulate(sim, f);
    std::map<int, int> counts;
    std::size_t ground = 0;
    for (std::size_t i = 0; i < fr.labels.size(); ++i) {
      const std::uint32_t l = fr.labels[i];
      if (std::isnan(fr.cloud[i].x)) {
        EXPECT_EQ(l, 0u);
        continue;
      }
      EXPECT_NE(l, 0u);
      if (io::labelInstance(l) == 0) {
        EXPECT_TRUE(io::semantic::isGround(io::labelClass(l)));
        ++ground;
      } else {
        ++counts[io::labelInstance(l)];
      }
    }
    EXPECT_GT(ground, 20000u);
    std::size_t rows_with_points = 0;
    for (const auto& o : fr.objects) {
      EXPECT_EQ(o.n_points, counts[o.track_id]) << "frame " << f << " track " << o.track_id;
      if (o.n_points > 0) ++rows_with_points;
    }
    std::size_t instances = 0;
    for (const auto& kv : counts) instances += kv.second > 0;
    EXPECT_EQ(rows_with_points, instances);  // every object hit has a row
    // Every labelled point lies in its object's box (flat ground; 10 cm for noise).
    for (std::size_t i = 0; i < fr.labels.size(); ++i) {
      const int id = io::labelInstance(fr.labels[i]);
      if (id == 0) continue;
      const io::GroundTruthObject* o = findObject(fr, id);
      ASSERT_NE(o, nullptr);
      EXPECT_TRUE(o->contains(fr.cloud[i].getVector3fMap().cast<double>(), 0.2, 0.2))
          << "track " << id << " point " << fr.cloud[i].getVector3fMap().transpose();
    }
  }
  // The moving van, car and pedestrian are movers; the parked car and the standing person not.
  const Frame fr = simulate(sim, 0);
  EXPECT_TRUE(findObject(fr, 1)->moving);
  EXPECT_TRUE(findObject(fr, 3)->moving);
  EXPECT_EQ(findObject(fr, 3)->type, "Pedestrian");
  EXPECT_FALSE(findObject(fr, 4)->moving);
  EXPECT_FALSE(findObject(fr, 5)->moving);
}

// MOS ground truth: an object's points have a moving class only in the frames where it moves
// (> io::semantic::kMovingLabelSpeed); a mover that stops, a parked car and a standing person keep
// their static classes, whatever the track's `moving` flag.
TEST(LidarSimulator, MovingLabelsOnlyWhileMoving) {
  Scenario sc = emptyScene();
  sc.frames = 60;
  ObjectSpec car = staticObject("car", 10.0, 6.0, 0);
  car.mover = true;
  car.trajectory.speed = 4.0;
  car.trajectory.segments = {{2.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {2.0, 4.0, 0.0}};  // stop and go
  sc.objects.push_back(car);
  sc.objects.push_back(staticObject("car", 12.0, -6.0, 0));  // parked
  ObjectSpec person = staticObject("person", 8.0, 3.0, 90);  // a mover standing still
  person.mover = true;
  sc.objects.push_back(person);
  LidarSimulator sim(sc);
  int moving_frames = 0, standing_frames = 0;
  for (int f = 0; f < sc.frames; f += 2) {
    const Frame fr = simulate(sim, f);
    const io::GroundTruthObject* o = findObject(fr, 1);
    ASSERT_NE(o, nullptr);
    const bool moves = o->speed > io::semantic::kMovingLabelSpeed;
    (moves ? moving_frames : standing_frames) += 1;
    std::map<int, std::set<int>> classes;  // track -> classes of its points
    for (const std::uint32_t l : fr.labels)
      if (io::labelInstance(l) > 0) classes[io::labelInstance(l)].insert(io::labelClass(l));
    ASSERT_FALSE(classes[1].empty()) << "frame " << f;
    EXPECT_EQ(classes[1], std::set<int>{moves ? io::semantic::kMovingCar : io::semantic::kCar})
        << "frame " << f << ", speed " << o->speed;
    EXPECT_EQ(classes[2], std::set<int>{io::semantic::kCar}) << "frame " << f;
    EXPECT_EQ(classes[3], std::set<int>{io::semantic::kPerson}) << "frame " << f;
  }
  EXPECT_GT(moving_frames, 5);
  EXPECT_GT(standing_frames, 2);
}

TEST(LidarSimulator, MoversAndEgoFollowTheirTrajectories) {
  Scenario sc = emptyScene();
  sc.frames = 30;
  sc.ego.speed = 5.0;
  ObjectSpec car = staticObject("car", 30.0, 5.0, 180);
  car.mover = true;
  car.trajectory.speed = 10.0;
  sc.objects.push_back(car);
  LidarSimulator sim(sc);
  for (int f : {0, 10, 20}) {
    const Frame fr = simulate(sim, f);
    EXPECT_NEAR(fr.pose.translation().x(), 0.5 * f, 1e-6);  // 5 m/s at 10 Hz
    const io::GroundTruthObject* o = findObject(fr, 1);
    ASSERT_NE(o, nullptr);
    // World x of the car's box centre: 30 - 10 t (the box centre is at the car's position).
    const Eigen::Vector3d world = fr.pose * o->center;
    EXPECT_NEAR(world.x(), 30.0 - 1.0 * f, 1e-3);
    EXPECT_NEAR(world.y(), 5.0, 1e-3);
    EXPECT_NEAR(std::abs(o->yaw), M_PI, 1e-6);
    EXPECT_NEAR(o->speed, 10.0, 1e-9);
    EXPECT_TRUE(o->moving);
    EXPECT_GT(o->n_points, 20);
  }
}

TEST(Trajectory, StopStartAndTurn) {
  TrajectorySpec spec;
  spec.speed = 4.0;
  spec.segments = {{2.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {2.0, 4.0, 0.0}};
  const Trajectory stop_go(spec, 10.0);
  EXPECT_NEAR(stop_go.at(1.0).speed, 2.0, 1e-9);
  EXPECT_NEAR(stop_go.at(2.5).speed, 0.0, 1e-9);
  EXPECT_NEAR(stop_go.at(2.5).position.x(), 4.0, 1e-3);  // ramp 4→0 over 2 s covers 4 m
  EXPECT_NEAR(stop_go.at(3.0).position.x(), 4.0, 1e-3);
  EXPECT_NEAR(stop_go.at(5.0).position.x(), 8.0, 1e-3);  // ramp 0→4 over 2 s covers 4 m
  EXPECT_NEAR(stop_go.at(6.0).position.x(), 12.0, 1e-3);

  TrajectorySpec turn;
  turn.speed = M_PI / 2;  // quarter circle of radius 1 m in 1 s
  turn.segments = {{1.0, -1.0, M_PI / 2}};
  const Trajectory t(turn, 3.0);
  EXPECT_NEAR(t.at(1.0).heading, M_PI / 2, 1e-9);
  EXPECT_NEAR(t.at(1.0).position.x(), 1.0, 1e-3);
  EXPECT_NEAR(t.at(1.0).position.y(), 1.0, 1e-3);
  EXPECT_NEAR(t.at(2.0).position.y(), 1.0 + M_PI / 2, 1e-3);  // straight on afterwards
}

TEST(LidarSimulator, RollingTerrainPointsLieOnTheSurface) {
  Scenario sc = emptyScene();
  sc.terrain.type = "rolling";
  sc.terrain.amplitude = 1.0;
  sc.terrain.wavelength = 30.0;
  sc.terrain.slope = {0.03, -0.02};
  sc.ego.speed = 5.0;
  LidarSimulator sim(sc);
  const Frame fr = simulate(sim, 3);
  const Eigen::Isometry3d T = sim.worldPose(3);
  int n = 0;
  double worst = 0;
  for (std::size_t i = 0; i < fr.cloud.size(); ++i) {
    if (std::isnan(fr.cloud[i].x)) continue;
    const Eigen::Vector3d w = T * fr.cloud[i].getVector3fMap().cast<double>();
    worst = std::max(worst, std::abs(w.z() - sim.terrainHeight(w.x(), w.y())));
    ++n;
  }
  EXPECT_GT(n, 20000);
  EXPECT_LT(worst, 0.01);
  // The vehicle is tilted by the slope: its z axis is not vertical.
  EXPECT_LT(T.linear()(2, 2), 0.99999);
}

TEST(LidarSimulator, Ladar2dHasALimitedFieldOfView) {
  Scenario sc = emptyScene();
  sc.sensor.preset = "ladar2d";
  sc.objects.push_back(staticObject("car", 15.0, 0.0));
  sc.objects.push_back(staticObject("car", -15.0, 0.0));  // behind: outside the field of view
  const Frame fr = simulate(LidarSimulator(sc), 0);
  EXPECT_EQ(fr.cloud.width, 360u);
  EXPECT_EQ(fr.cloud.height, 60u);
  for (const auto& p : fr.cloud)
    if (!std::isnan(p.x)) EXPECT_GT(p.x, 0.0f);
  EXPECT_GT(findObject(fr, 1)->n_points, 50);
  EXPECT_EQ(findObject(fr, 2)->n_points, 0);
}

TEST(LidarSimulator, SameSeedSameBytesOtherSeedOtherNoise) {
  const std::string path = std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/sample.yaml";
  Scenario sc = loadScenario(path);
  sc.frames = 3;
  const fs::path a = tempDir("a"), b = tempDir("b"), c = tempDir("c");
  writeSequence(LidarSimulator(sc), a.string(), false);
  writeSequence(LidarSimulator(sc), b.string(), false);
  for (const char* f : {"frames/000000.pcd", "frames/000002.pcd", "labels/000002.label",
                        "poses.txt", "times.txt", "objects.txt", "scenario.yaml"}) {
    ASSERT_TRUE(fs::exists(a / f)) << f;
    EXPECT_EQ(readFile(a / f), readFile(b / f)) << f;
  }
  sc.seed += 1;
  writeSequence(LidarSimulator(sc), c.string(), false);
  EXPECT_NE(readFile(a / "frames/000001.pcd"), readFile(c / "frames/000001.pcd"));
  // The written sequence reads back through the project's reader.
  io::SequenceReader reader(a.string());
  ASSERT_EQ(reader.size(), 3u);
  EXPECT_TRUE(reader.hasPoses());
  pcl::PointCloud<pcl::PointXYZI> cloud;
  reader.read(1, cloud);
  EXPECT_EQ(cloud.height, 64u);
  EXPECT_EQ(io::readLabels(reader.labelPath(1)).size(), cloud.size());
  EXPECT_FALSE(io::readObjects(reader.objectsPath()).empty());
  for (const auto& d : {a, b, c}) fs::remove_all(d);
}

TEST(WriteSequence, RefusesNonEmptyFolderUnlessOverwrite) {
  Scenario sc = emptyScene();
  sc.frames = 2;
  sc.sensor.preset = "vlp16";
  const fs::path out = tempDir("refuse");
  fs::create_directories(out);
  { std::ofstream(out / "precious.txt") << "keep me"; }
  EXPECT_THROW(writeSequence(LidarSimulator(sc), out.string(), false), InputError);
  EXPECT_FALSE(fs::exists(out / "frames"));
  EXPECT_FALSE(fs::exists(out.string() + ".simulate-partial"));
  writeSequence(LidarSimulator(sc), out.string(), true);
  EXPECT_TRUE(fs::exists(out / "frames/000001.pcd"));
  EXPECT_TRUE(fs::exists(out / "precious.txt"));  // only the sequence's own files are replaced
  // A shorter rerun leaves no stale frames behind.
  sc.frames = 1;
  writeSequence(LidarSimulator(sc), out.string(), true);
  EXPECT_FALSE(fs::exists(out / "frames/000001.pcd"));
  fs::remove_all(out);
}
