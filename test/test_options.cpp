/*
 * The command line of every pcl_movers_* tool (issue #29): one option style from one option table
 * per tool: --kebab-case options, older spellings accepted with a deprecation warning, unknown
 * options refused by name, a help that lists every option with its default, and errors that name
 * the file or option at fault.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/eval/segmentation_metrics.h>
#include <pcl_movers/io/ground_truth.h>

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <string>
#include <vector>

#include "test_util.h"

namespace fs = std::filesystem;

namespace {

using test_util::readFile;
using test_util::runTool;
using test_util::TempDir;
using test_util::toolBuilt;
using test_util::writeFile;

const char* const kTools[] = {"detect",   "ground", "segment", "organize",          "register",
                              "simulate", "eval",   "viewer",  "eval_segmentation", "ego_motion",
                              "corpus"};

std::string kebab(std::string key) {
  std::replace(key.begin(), key.end(), '_', '-');
  return "--" + key;
}

/** The options a help text lists: "--name" at the start of an (indented) line. */
std::set<std::string> helpOptions(const std::string& help) {
  std::set<std::string> options;
  const std::regex line("(^|\n) {2,}(--[a-z0-9.-]+)");
  for (std::sregex_iterator it(help.begin(), help.end(), line, std::regex_constants::match_default),
       end;
       it != end; ++it)
    options.insert((*it)[2]);
  return options;
}

#define SKIP_UNLESS_BUILT(tool) \
  if (!toolBuilt(tool)) GTEST_SKIP() << "pcl_movers_" << tool << " is not built"

TEST(Options, KebabCaseParameterIsAccepted) {
  SKIP_UNLESS_BUILT("detect");
  const auto r = runTool(
      "detect", {"--ground.sensor-height", "1.91", "--segment.max-gap", "3", "--print-config"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ground.sensor_height = 1.91"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("segment.max_gap = 3"), std::string::npos) << r.out;
  EXPECT_EQ(r.err.find("deprecated"), std::string::npos) << r.err;
}

TEST(Options, OldSpellingIsAcceptedWithAWarning) {
  SKIP_UNLESS_BUILT("detect");
  const auto r = runTool("detect", {"--ground.sensor_height", "1.91", "--print-config"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ground.sensor_height = 1.91"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("warning: --ground.sensor_height is deprecated, use --ground.sensor-height"),
            std::string::npos)
      << r.err;
  // The flat keys of earlier versions, in both spellings.
  for (const std::string flat : {"--sensor-height", "--sensor_height"}) {
    const auto old = runTool("detect", {flat, "1.92", "--print-config"});
    EXPECT_EQ(old.exit_code, 0) << old.err;
    EXPECT_NE(old.out.find("ground.sensor_height = 1.92"), std::string::npos) << old.out;
    EXPECT_NE(old.err.find("warning: " + flat + " is deprecated, use --ground.sensor-height"),
              std::string::npos)
        << old.err;
  }
  // Renamed options of other tools: the old spelling still works, with the same warning.
  if (toolBuilt("eval")) {
    const auto e = runTool("eval", {"--dontcare", "x.txt", "-5"});
    EXPECT_NE(e.err.find("warning: --dontcare is deprecated, use --dont-care"), std::string::npos)
        << e.err;
    EXPECT_EQ(e.err.find("unknown option"), std::string::npos) << e.err;
  }
  if (toolBuilt("organize")) {
    const auto o = runTool("organize", {"--calibration", "x.xml", "a", "b"});
    EXPECT_NE(o.err.find("warning: --calibration is deprecated, use --calib"), std::string::npos)
        << o.err;
  }
}

TEST(Options, ConfigFileTakesSnakeAndKebabKeys) {
  SKIP_UNLESS_BUILT("detect");
  TempDir dir;
  writeFile(dir.path() / "a.cfg", "sensor_height = 1.81\nmin-cluster-points = 11\n");
  const auto r = runTool("detect", {"--config", (dir.path() / "a.cfg").string(), "--print-config"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("sensor_height = 1.81"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("min_cluster_points = 11"), std::string::npos) << r.out;
}

TEST(Options, UnknownOptionIsRefusedByName) {
  int checked = 0;
  for (const char* tool : kTools) {
    if (!toolBuilt(tool)) continue;
    SCOPED_TRACE(tool);
    const auto r = runTool(tool, {"--no-such-option", "a", "b"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("unknown option --no-such-option"), std::string::npos) << r.err;
    ++checked;
  }
  if (checked == 0) GTEST_SKIP() << "no tool built";
}

// Every option the help lists is one the tool accepts, and every option is --kebab-case: the
// help and the parser come from the same table.
TEST(Options, HelpListsWhatTheToolAccepts) {
  int checked = 0;
  for (const char* tool : kTools) {
    if (!toolBuilt(tool)) continue;
    SCOPED_TRACE(tool);
    const auto help = runTool(tool, {"-h"});
    ASSERT_EQ(help.exit_code, 0);
    const auto options = helpOptions(help.out + help.err);
    EXPECT_GE(options.size(), 3u) << help.out;
    for (const auto& option : options) {
      EXPECT_EQ(option.find('_'), std::string::npos) << option;
      // With a dummy value and no positional arguments the tool fails, but not on the option.
      const auto r = runTool(tool, {option, "1"});
      EXPECT_EQ(r.err.find("unknown option"), std::string::npos) << option << ": " << r.err;
    }
    ++checked;
  }
  if (checked == 0) GTEST_SKIP() << "no tool built";
}

TEST(Options, DetectHelpListsEveryParameterWithItsDefault) {
  SKIP_UNLESS_BUILT("detect");
  const auto r = runTool("detect", {"--help"});
  ASSERT_EQ(r.exit_code, 0);
  const std::string help = r.out + r.err;
  pcl_movers::DetectorParameters().forEachParameter(
      [&](const std::string& key, const auto& value, const char*) {
        const std::regex line(
            "\n +" + kebab(key) + " [A-Z0-9|]+ .*\\(default: " +
            std::regex_replace(pcl_movers::detail::formatValue(value), std::regex("[.+]"), "\\$&") +
            "\\)");
        EXPECT_TRUE(std::regex_search(help, line)) << kebab(key) << " with its default";
      });
  for (const char* option : {"--rate", "--poses", "--poses-format", "--labelled-clouds"})
    EXPECT_NE(help.find(std::string("\n  ") + option + " "), std::string::npos) << option;
  EXPECT_NE(help.find("(default: 10)"), std::string::npos);  // --rate
}

TEST(Options, ValueMissingNamesTheOption) {
  SKIP_UNLESS_BUILT("detect");
  const auto r = runTool("detect", {"seq", "out", "--rate"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--rate needs a value"), std::string::npos) << r.err;
}

// ------------------------------------------------------------------ errors name the culprit
TEST(Options, UnwritableOutputIsNamed) {
  SKIP_UNLESS_BUILT("ground");
  TempDir dir;
  // A scan, and an output below a regular file: no one (not even root) can create it.
  std::string pcd =
      "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 3\n"
      "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n5 0 -1.7 1\n6 1 -1.7 1\n7 0 0 1\n";
  writeFile(dir.path() / "scan.pcd", pcd);
  writeFile(dir.path() / "a_file", "x");
  const std::string out = (dir.path() / "a_file" / "out.pcd").string();
  const auto r = runTool("ground", {(dir.path() / "scan.pcd").string(), out});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(out), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("Error during open"), std::string::npos) << r.err;
}

// pcl_movers_ground with its own defaults gives what docs/evaluation.md reports for them: it
// organizes a raw KITTI .bin scan into a range image, as the detector and the evaluation do, so the
// local-slope test runs. Without that step it scored 93.3-94.8 % precision on these frames (the
// plane test alone); the evaluation reports 97-98 % with the local-slope test.
TEST(GroundTool, DefaultsOnARawKittiScanGiveTheEvaluatedPrecision) {
  SKIP_UNLESS_BUILT("ground");
  const fs::path kitti = fs::path(PCL_MOVERS_SHARED_DATA) / "kitti-odometry-00";
  if (!fs::exists(kitti / "labels" / "000000.label"))
    GTEST_SKIP() << "SemanticKITTI frames not found at " << kitti
                 << " (set PCL_MOVERS_SHARED_DATA)";
  TempDir dir;
  const std::string out = (dir.path() / "000000.pcd").string();
  const auto r = runTool("ground", {(kitti / "velodyne" / "000000.bin").string(), out});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  pcl::PointCloud<pcl::PointXYZL> labelled;
  ASSERT_EQ(pcl::io::loadPCDFile(out, labelled), 0);
  const auto truth = pcl_movers::eval::groundTruthFromLabels(
      pcl_movers::io::readLabels((kitti / "labels" / "000000.label").string()));
  ASSERT_EQ(truth.size(), labelled.size());
  std::vector<std::uint8_t> is_ground(labelled.size());
  for (std::size_t i = 0; i < labelled.size(); ++i) is_ground[i] = labelled[i].label == 1;
  const auto score = pcl_movers::eval::scoreGround(truth, is_ground);
  EXPECT_GT(score.precision(), 0.96);
  EXPECT_GT(score.recall(), 0.90);
}

TEST(Options, DetectOnASingleScanSaysItTakesAFolder) {
  SKIP_UNLESS_BUILT("detect");
  TempDir dir;
  writeFile(dir.path() / "000001.pcd", "not read");
  for (const std::string scan : {"000001.pcd", "missing.bin"}) {
    const std::string path = (dir.path() / scan).string();
    const auto r = runTool("detect", {path, (dir.path() / "out").string()});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find(path), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("takes a sequence folder"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("not a single scan"), std::string::npos) << r.err;
  }
}

}  // namespace
