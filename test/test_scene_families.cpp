/*
 * Tests of the scene corpus generator: families, the split rule, the YAML round trip, blind frames,
 * reversing, and that the scenes hold what the corpus promises (slow walkers, people close to
 * structures, fast traffic).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>
#include <pcl_movers/sim/scene_families.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

using namespace pcl_movers;
using namespace pcl_movers::sim;

namespace {

SceneOptions shortScenes() {
  SceneOptions o;
  o.frames = 60;
  return o;
}

/** Footprint half-sizes of a static object (the simulator's defaults where the scene gives none).
 */
Eigen::Vector2d halfSize(const ObjectSpec& o) {
  if (o.size.x() > 0) return 0.5 * o.size.head<2>();
  if (o.type == "car") return {2.2, 0.9};
  if (o.type == "van") return {2.5, 1.0};
  if (o.type == "truck") return {4.0, 1.25};
  const double r = o.type == "tree" ? (o.trunk_radius > 0 ? o.trunk_radius : 0.2)
                                    : (o.radius > 0 ? o.radius : (o.type == "brush" ? 1.0 : 0.1));
  return {r, r};
}

/** Distance from a point to the footprint's edge (boxes; round objects as their square). */
double distanceToFootprint(const ObjectSpec& o, const Eigen::Vector2d& p) {
  const Eigen::Vector2d d = p - o.trajectory.start;
  const double c = std::cos(o.trajectory.heading), s = std::sin(o.trajectory.heading);
  const Eigen::Vector2d local(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  const Eigen::Vector2d h = halfSize(o);
  const Eigen::Vector2d out(std::max(0.0, std::abs(local.x()) - h.x()),
                            std::max(0.0, std::abs(local.y()) - h.y()));
  return out.norm();
}

/** A mover's footprint half-sizes as the simulator builds it (lidar_simulator.cpp defaults). */
Eigen::Vector2d moverHalfSize(const ObjectSpec& o) {
  if (o.size.x() > 0) return 0.5 * o.size.head<2>();
  if (o.type == "person") return {0.3, 0.3};
  if (o.type == "cyclist") return {0.9, 0.3};
  return halfSize(o);
}

/** Whether two footprints (centre, heading, half-sizes) overlap: the separating-axis test. */
bool footprintsOverlap(const Trajectory::State& a, const Eigen::Vector2d& ha,
                       const Trajectory::State& b, const Eigen::Vector2d& hb) {
  const Eigen::Vector2d d = b.position - a.position;
  const auto axis = [](double heading) {
    return Eigen::Vector2d(std::cos(heading), std::sin(heading));
  };
  const auto reach = [&](const Eigen::Vector2d& n, double heading, const Eigen::Vector2d& h) {
    return h.x() * std::abs(n.dot(axis(heading))) + h.y() * std::abs(n.dot(axis(heading + M_PI_2)));
  };
  for (const double heading : {a.heading, a.heading + M_PI_2, b.heading, b.heading + M_PI_2}) {
    const Eigen::Vector2d n = axis(heading);
    if (std::abs(n.dot(d)) > reach(n, a.heading, ha) + reach(n, b.heading, hb)) return false;
  }
  return true;
}

}  // namespace

TEST(SceneFamilies, SplitRuleAndSensorsCoverBothHalves) {
  EXPECT_EQ(splitOf(1), Split::kTune);
  EXPECT_EQ(splitOf(2), Split::kCheck);
  EXPECT_EQ(splitName(splitOf(7)), "tune");
  std::map<std::string, std::set<std::string>> halves;  // sensor → splits seen
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    EXPECT_EQ(sensorOfSeed(seed), sensorOfSeed(seed % 2 ? seed + 1 : seed - 1)) << seed;
    halves[sensorOfSeed(seed)].insert(splitName(splitOf(seed)));
  }
  ASSERT_EQ(halves.size(), sceneSensors().size());
  for (const auto& kv : halves) EXPECT_EQ(kv.second.size(), 2u) << kv.first;
}

TEST(SceneFamilies, UnknownFamilyAndSeedZeroAreErrors) {
  EXPECT_THROW(generateScene("motorway", 1), InputError);
  EXPECT_THROW(generateScene("urban", 0), InputError);
}

TEST(SceneFamilies, YamlReadsBackToTheSameScene) {
  for (const auto& family : sceneFamilies())
    for (std::uint64_t seed : {1, 2, 5}) {
      const Scenario sc = generateScene(family, seed, shortScenes());
      const std::string yaml = toYaml(sc);
      const Scenario back = parseScenario(yaml, family + ".yaml");
      EXPECT_EQ(toYaml(back), yaml) << family << " " << seed;
      ASSERT_EQ(back.objects.size(), sc.objects.size());
      for (std::size_t i = 0; i < sc.objects.size(); ++i) {
        EXPECT_EQ(back.objects[i].trajectory.start, sc.objects[i].trajectory.start);
        EXPECT_EQ(back.objects[i].trajectory.heading, sc.objects[i].trajectory.heading);
        EXPECT_EQ(back.objects[i].trajectory.speed, sc.objects[i].trajectory.speed);
      }
      EXPECT_EQ(back.ego.start, sc.ego.start);
      EXPECT_EQ(back.sensor.height, sc.sensor.height);
      EXPECT_EQ(back.blind_frames, sc.blind_frames);
    }
}

TEST(SceneFamilies, SameSeedSameSceneOtherSeedOtherScene) {
  for (const auto& family : sceneFamilies()) {
    EXPECT_EQ(toYaml(generateScene(family, 3)), toYaml(generateScene(family, 3)));
    EXPECT_NE(toYaml(generateScene(family, 3)), toYaml(generateScene(family, 4)));
  }
}

TEST(SceneFamilies, GeneratedAndReadBackScenesSimulateIdentically) {
  const Scenario sc = generateScene("parking", 2, shortScenes());
  const Scenario back = parseScenario(toYaml(sc), "parking.yaml");
  LidarSimulator a(sc), b(back);
  for (int frame : {0, 37}) {
    pcl::PointCloud<pcl::PointXYZI> ca, cb;
    std::vector<std::uint32_t> la, lb;
    std::vector<io::GroundTruthObject> oa, ob;
    Eigen::Isometry3d pa, pb;
    a.simulate(frame, ca, la, oa, pa);
    b.simulate(frame, cb, lb, ob, pb);
    ASSERT_EQ(ca.size(), cb.size());
    EXPECT_EQ(la, lb);
    EXPECT_TRUE(pa.isApprox(pb, 0.0));
    std::size_t same = 0;
    for (std::size_t i = 0; i < ca.size(); ++i)
      same += (ca[i].x == cb[i].x || (std::isnan(ca[i].x) && std::isnan(cb[i].x))) ? 1 : 0;
    EXPECT_EQ(same, ca.size());
  }
}

TEST(SceneFamilies, EachFamilyHasItsTraffic) {
  for (const auto& family : sceneFamilies()) {
    std::set<std::string> mover_types;
    double fastest = 0, slowest_person = 1e9;
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      const Scenario sc = generateScene(family, seed);
      EXPECT_EQ(sc.frames, 150);
      EXPECT_GE(sc.sensor.height, 1.5);
      EXPECT_LE(sc.sensor.height, 2.5);
      for (const ObjectSpec& o : sc.objects) {
        if (!o.mover) continue;
        mover_types.insert(o.type);
        fastest = std::max(fastest, o.trajectory.speed);
        if (o.type == "person") slowest_person = std::min(slowest_person, o.trajectory.speed);
      }
    }
    EXPECT_TRUE(mover_types.count("person")) << family;
    EXPECT_TRUE(mover_types.count("car") || mover_types.count("van")) << family;
    EXPECT_LT(slowest_person, 1.0) << family << ": no slow walker in 12 scenes";
    EXPECT_GE(slowest_person, 0.55) << family << ": walkers this slow are no targets (0.5 m/s)";
    if (family == "highway") EXPECT_GT(fastest, 30.0);
  }
}

TEST(SceneFamilies, MoversNeverPassThroughEachOther) {
  // Traffic drawn lane by lane had faster cars drive through slower ones in their lane and cars
  // through crossing walkers: two targets in one place, which no sensor can show as two.
  for (const auto& family : sceneFamilies()) {
    int movers = 0;
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      const Scenario sc = generateScene(family, seed);
      const double horizon = sc.frames / sc.rate_hz;
      std::vector<const ObjectSpec*> ms;
      for (const ObjectSpec& o : sc.objects)
        if (o.mover) ms.push_back(&o);
      movers += static_cast<int>(ms.size());
      for (std::size_t i = 0; i < ms.size(); ++i) {
        const Trajectory pi(ms[i]->trajectory, horizon + 1.0);
        for (std::size_t j = i + 1; j < ms.size(); ++j) {
          const Trajectory pj(ms[j]->trajectory, horizon + 1.0);
          for (int f = 0; f < sc.frames; ++f) {
            const double t = f / sc.rate_hz;
            ASSERT_FALSE(
                footprintsOverlap(pi.at(t), moverHalfSize(*ms[i]), pj.at(t), moverHalfSize(*ms[j])))
                << family << "-" << seed << ": " << ms[i]->type << " " << i << " and "
                << ms[j]->type << " " << j << " overlap at frame " << f;
          }
        }
      }
    }
    EXPECT_GE(movers, 4 * 12) << family << ": the check must not empty the scenes";
  }
}

TEST(SceneFamilies, PeopleWalkCloseToStructures) {
  // At the time a walker is placed beside a wall, parked car or pole it passes within 0.3-0.5 m
  // of it (0.3 m body radius): its centre within 0.85 m of the footprint.
  for (const std::string family : {"urban", "parking", "highway"}) {
    int close = 0;
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const Scenario sc = generateScene(family, seed);
      const double horizon = sc.frames / sc.rate_hz;
      for (const ObjectSpec& p : sc.objects) {
        if (!p.mover || p.type != "person") continue;
        const Trajectory path(p.trajectory, horizon);
        double nearest = 1e9;
        for (double t = 0; t <= horizon; t += 0.1)
          for (const ObjectSpec& s : sc.objects)
            if (!s.mover) nearest = std::min(nearest, distanceToFootprint(s, path.at(t).position));
        close += nearest < 0.85 && nearest > 0.05 ? 1 : 0;
      }
    }
    EXPECT_GE(close, 3) << family;
  }
}

TEST(SceneFamilies, BlindFramesHaveNoReturn) {
  Scenario sc = generateScene("open", 1, shortScenes());
  sc.blind_frames = {10, 11};
  LidarSimulator sim(sc);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  std::vector<std::uint32_t> labels;
  std::vector<io::GroundTruthObject> objects;
  Eigen::Isometry3d pose;
  auto finite = [&]() {
    std::size_t n = 0;
    for (const auto& p : cloud) n += std::isfinite(p.x) ? 1 : 0;
    return n;
  };
  sim.simulate(11, cloud, labels, objects, pose);
  EXPECT_EQ(finite(), 0u);
  EXPECT_FALSE(objects.empty());  // still listed, with no points
  for (const auto& o : objects) EXPECT_EQ(o.n_points, 0);
  for (auto l : labels) EXPECT_EQ(l, 0u);
  sim.simulate(12, cloud, labels, objects, pose);
  EXPECT_GT(finite(), 1000u);
}

TEST(SceneFamilies, BlindFramesParseAndAreChecked) {
  const std::string head = "frames: 20\nego: {start: [0, 0]}\n";
  EXPECT_EQ(parseScenario(head + "blind_frames: [5, 3, 5]\n", "s.yaml").blind_frames,
            (std::vector<int>{3, 5}));
  EXPECT_THROW(parseScenario(head + "blind_frames: [20]\n", "s.yaml"), InputError);
  EXPECT_THROW(parseScenario(head + "blind_frames: [-1]\n", "s.yaml"), InputError);
}

TEST(SceneFamilies, ReversingMovesAgainstTheHeading) {
  TrajectorySpec spec;
  spec.heading = M_PI / 2;  // the body points +y
  spec.segments = {{1.0, 2.0, 0.0, true}};
  const Trajectory path(spec, 3.0);
  const Trajectory::State s = path.at(2.0);
  EXPECT_NEAR(s.position.x(), 0.0, 1e-9);
  EXPECT_NEAR(s.position.y(), -3.0, 1e-6);  // 1 m ramping up, then 2 m at 2 m/s, towards -y
  EXPECT_NEAR(s.heading, M_PI / 2, 1e-12);
  EXPECT_TRUE(s.reverse);
  const std::string yaml =
      "ego: {start: [0, 0]}\nmovers:\n  - type: car\n    start: [0, 0]\n"
      "    segments:\n      - {duration: 1, speed: 2, reverse: true}\n";
  EXPECT_TRUE(parseScenario(yaml, "s.yaml").objects[0].trajectory.segments[0].reverse);
  EXPECT_THROW(parseScenario(yaml.substr(0, yaml.size() - 6) + "yes}\n", "s.yaml"), InputError);
}
