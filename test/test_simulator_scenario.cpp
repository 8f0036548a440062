/*
 * Tests of the scenario format: the YAML subset, every feature, shipped scenarios, and the
 * rejection of bad files with file, line, key and reason.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>
#include <pcl_movers/sim/yaml_lite.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

using namespace pcl_movers;
using namespace pcl_movers::sim;

namespace {

const char* kMinimal = "ego:\n  start: [0, 0]\n";

/** Parses `text` expecting an InputError whose message contains every string in `parts`. */
void expectRejected(const std::string& text, const std::vector<std::string>& parts) {
  try {
    parseScenario(text, "bad.yaml");
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const auto& p : parts)
      EXPECT_NE(msg.find(p), std::string::npos) << "message '" << msg << "' lacks '" << p << "'";
  }
}

}  // namespace

TEST(YamlLite, BlockAndFlowCollections) {
  const YamlNode root = parseYaml(
      "# comment\n"
      "a: 1\n"
      "b:\n"
      "  c: hello world  # trailing comment\n"
      "  d: [1, [2, 3], {x: 4}]\n"
      "list:\n"
      "  - plain\n"
      "  - k: v\n"
      "    k2: 'q # not a comment'\n"
      "  - {p: [1,\n"
      "         2]}\n"
      "seq_same_indent:\n"
      "- 5\n",
      "t.yaml");
  ASSERT_TRUE(root.isMap());
  EXPECT_EQ(root.find("a")->scalar, "1");
  EXPECT_EQ(root.find("b")->find("c")->scalar, "hello world");
  const YamlNode* d = root.find("b")->find("d");
  ASSERT_TRUE(d->isSequence());
  EXPECT_EQ(d->sequence[1].sequence[1].scalar, "3");
  EXPECT_EQ(d->sequence[2].find("x")->scalar, "4");
  const YamlNode* list = root.find("list");
  ASSERT_EQ(list->sequence.size(), 3u);
  EXPECT_EQ(list->sequence[0].scalar, "plain");
  EXPECT_EQ(list->sequence[1].find("k2")->scalar, "q # not a comment");
  EXPECT_EQ(list->sequence[1].line, 8u);
  EXPECT_EQ(list->sequence[2].find("p")->sequence.size(), 2u);
  EXPECT_EQ(root.find("seq_same_indent")->sequence[0].scalar, "5");
}

TEST(Scenario, EveryFeatureParses) {
  const Scenario sc = parseScenario(
      "name: all\nseed: 12\nframes: 7\nrate_hz: 5\n"
      "sensor: {preset: vlp16, height: 2.0, max_range: 60, min_range: 1.5, range_noise: 0.01,"
      " dropout: 0.05}\n"
      "terrain:\n  type: rolling\n  height: 1\n  slope: [0.01, 0.02]\n  amplitude: 0.8\n"
      "  wavelength: 35\n  surface: sidewalk\n  road_width: 9\n"
      "roads:\n  - points: [[0, -20], [0, 20]]\n    width: 6\n"
      "ego:\n  start: [1, 2]\n  heading: 90\n  speed: 4\n  segments:\n"
      "    - {duration: 2, turn_rate: 10}\n    - {duration: 1, speed: 0}\n"
      "movers:\n  - type: truck\n    start: [10, 0]\n    speed: 8\n    size: [9, 2.5, 3.5]\n"
      "  - {type: cyclist, start: [0, 10], heading: -90, speed: 5}\n"
      "statics:\n  - {type: tree, position: [5, 5], height: 9, radius: 2, trunk_radius: 0.3,"
      " trunk_height: 3}\n"
      "  - {type: wall, position: [0, 30], yaw: 10, size: [20, 0.3, 2]}\n"
      "clutter:\n  - {type: brush, count: 4, region: [-30, 30, 20, 40], min_spacing: 1}\n",
      "all.yaml");
  EXPECT_EQ(sc.name, "all");
  EXPECT_EQ(sc.seed, 12u);
  EXPECT_EQ(sc.frames, 7);
  EXPECT_DOUBLE_EQ(sc.rate_hz, 5.0);
  EXPECT_EQ(sc.sensor.preset, "vlp16");
  EXPECT_DOUBLE_EQ(sc.sensor.dropout, 0.05);
  EXPECT_EQ(sc.terrain.type, "rolling");
  EXPECT_DOUBLE_EQ(sc.terrain.slope.y(), 0.02);
  EXPECT_EQ(sc.roads.size(), 1u);
  EXPECT_NEAR(sc.ego.heading, M_PI / 2, 1e-12);
  ASSERT_EQ(sc.ego.segments.size(), 2u);
  EXPECT_NEAR(sc.ego.segments[0].turn_rate, 10 * M_PI / 180, 1e-12);
  EXPECT_LT(sc.ego.segments[0].speed, 0);  // keeps speed
  ASSERT_EQ(sc.objects.size(), 4u);
  EXPECT_TRUE(sc.objects[0].mover);
  EXPECT_DOUBLE_EQ(sc.objects[0].size.x(), 9.0);
  EXPECT_FALSE(sc.objects[2].mover);
  EXPECT_DOUBLE_EQ(sc.objects[2].trunk_height, 3.0);
  ASSERT_EQ(sc.clutter.size(), 1u);
  EXPECT_EQ(sc.clutter[0].count, 4);
  LidarSimulator sim(sc);
  EXPECT_EQ(sim.getObjectCount(), 8u);  // 4 explicit + 4 clutter
  EXPECT_EQ(sim.getSensor().name(), "vlp16");
}

TEST(Scenario, ShippedScenariosLoad) {
  for (const char* name : {"sample", "open", "urban", "wooded"}) {
    const std::string path =
        std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/" + name + ".yaml";
    const Scenario sc = loadScenario(path);
    int movers = 0, people = 0;
    for (const auto& o : sc.objects) {
      movers += o.mover;
      people += o.mover && o.type == "person";
    }
    EXPECT_GE(movers, 2) << name;
    EXPECT_GE(people, 1) << name;
    if (std::string(name) != "sample") {
      EXPECT_GE(sc.frames, 150) << name;
      EXPECT_GE(movers, 4) << name;
    }
    LidarSimulator sim(sc);
    EXPECT_GT(sim.getObjectCount(), sc.objects.size() - 1) << name;
  }
}

TEST(Scenario, RejectsBadFilesWithFileLineKeyAndReason) {
  // Unknown keys, at the top and nested.
  expectRejected(std::string(kMinimal) + "colour: red\n", {"bad.yaml:3", "unknown key 'colour'"});
  expectRejected(std::string(kMinimal) + "sensor:\n  preset: hdl64\n  rnage: 3\n",
                 {"bad.yaml:5", "'sensor'", "unknown key 'rnage'"});
  expectRejected(std::string(kMinimal) + "movers:\n  - type: car\n    start: [1, 2]\n    sped: 3\n",
                 {"bad.yaml:6", "movers[0]", "unknown key 'sped'"});
  // Missing fields.
  expectRejected("frames: 10\n", {"bad.yaml:1", "missing required key 'ego'"});
  expectRejected(std::string(kMinimal) + "movers:\n  - start: [1, 2]\n",
                 {"bad.yaml:4", "movers[0]", "missing required key 'type'"});
  expectRejected(std::string(kMinimal) + "statics:\n  - {type: building, position: [0, 0]}\n",
                 {"bad.yaml:4", "statics[0]", "'size'"});
  // Negative or zero sizes and out-of-range values.
  expectRejected(
      std::string(kMinimal) + "statics:\n  - {type: car, position: [0, 0], size: [4, -2, 1]}\n",
      {"bad.yaml:4", "statics[0].size", "positive"});
  expectRejected(
      std::string(kMinimal) + "statics:\n  - type: tree\n    position: [0, 0]\n    radius: -1\n",
      {"bad.yaml:6", "statics[0].radius", "positive"});
  expectRejected(std::string(kMinimal) + "sensor: {max_range: 0}\n",
                 {"bad.yaml:3", "sensor.max_range", "positive"});
  expectRejected(std::string(kMinimal) + "sensor: {dropout: 1.5}\n", {"sensor.dropout"});
  expectRejected(std::string(kMinimal) + "frames: 0\n", {"bad.yaml:3", "'frames'"});
  expectRejected("ego:\n  start: [0, 0]\n  segments:\n    - {duration: -1}\n",
                 {"bad.yaml:4", "segments[0].duration", "positive"});
  // Wrong types and unknown names.
  expectRejected(std::string(kMinimal) + "seed: abc\n", {"bad.yaml:3", "'seed'", "number"});
  expectRejected("ego:\n  start: [0]\n", {"bad.yaml:2", "ego.start", "2 numbers"});
  expectRejected(std::string(kMinimal) + "movers:\n  - {type: tree, start: [0, 0]}\n",
                 {"bad.yaml:4", "unknown type 'tree'"});
  expectRejected(std::string(kMinimal) + "sensor: {preset: hdl65}\n",
                 {"bad.yaml:3", "sensor.preset"});
  expectRejected(std::string(kMinimal) + "terrain: {type: hilly}\n",
                 {"bad.yaml:3", "terrain.type", "hilly"});
  // Malformed syntax.
  expectRejected("ego:\n  start: [0, 0\n", {"bad.yaml:", "'['"});
  expectRejected("ego:\n  start: [0, 0]\n    speed: 3\n", {"bad.yaml:3", "indentation"});
  expectRejected("ego:\n  start [0, 0]\n", {"bad.yaml:2", "key: value"});
  expectRejected("ego:\n\tstart: [0, 0]\n", {"bad.yaml:2", "tab"});
  expectRejected(std::string(kMinimal) + "name: 'open\n", {"bad.yaml:3", "unterminated"});
  expectRejected(std::string(kMinimal) + "frames: 3\nframes: 4\n",
                 {"bad.yaml:4", "duplicate key 'frames'"});
  // Missing file.
  EXPECT_THROW(loadScenario("/nonexistent/scenario.yaml"), InputError);
}

TEST(SimulateTool, RejectsBadInputWithoutWritingAnything) {
  const std::string tool = std::string(PCL_MOVERS_BINARY_DIR) + "/apps/pcl_movers_simulate";
  if (!std::filesystem::exists(tool)) GTEST_SKIP() << "pcl_movers_simulate not built: " << tool;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "pcl_movers_test_simulate_tool";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string bad = (dir / "bad.yaml").string(), out = (dir / "out").string();
  { std::ofstream(bad) << "ego:\n  start: [0, 0]\n  sped: 3\n"; }
  auto run = [&](const std::string& args) {
    return std::system((tool + " " + args + " > /dev/null 2>&1").c_str());
  };
  EXPECT_EQ(run("-h"), 0);
  EXPECT_NE(run(bad + " " + out), 0);
  EXPECT_NE(
      run(std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/sample.yaml " + out + " --bogus"),
      0);
  EXPECT_NE(run(std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/sample.yaml " + out +
                " --frames -2"),
            0);
  EXPECT_FALSE(std::filesystem::exists(out));
  // A good run with a reduced sensor, then a refused rerun into the non-empty folder.
  const std::string good = std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/sample.yaml " +
                           out + " --frames 2 --sensor vlp16";
  EXPECT_EQ(run(good), 0);
  EXPECT_TRUE(std::filesystem::exists(out + "/frames/000001.pcd"));
  EXPECT_TRUE(std::filesystem::exists(out + "/labels/000001.label"));
  EXPECT_NE(run(good), 0);
  EXPECT_EQ(run(good + " --overwrite"), 0);
  std::filesystem::remove_all(dir);
}
