/*
 * pcl_movers_corpus end to end on a tiny corpus: both splits reported (check first), scenes
 * reused on a second run, and the same numbers from the same command (determinism).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "test_util.h"

namespace fs = std::filesystem;

namespace {

using test_util::readFile;

std::string tool(const std::string& name) {
  const char* dir = std::getenv("PCL_MOVERS_TOOLS_DIR");
  return std::string(dir && *dir ? dir : PCL_MOVERS_BINARY_DIR "/apps") + "/pcl_movers_" + name;
}

/** The per-run JSON lines without their wall times. */
std::string withoutTimes(const std::string& jsonl) {
  return std::regex_replace(jsonl, std::regex("\"seconds\": [0-9.e+-]+"), "\"seconds\": _");
}

int runCorpus(const fs::path& out, const fs::path& log) {
  const std::string cmd = tool("corpus") + " " + out.string() +
                          " --families parking --seeds 2 --frames 12 --split all --modes centroid"
                          " --jobs 2 >" +
                          log.string() + " 2>&1";
  return std::system(cmd.c_str());
}

}  // namespace

TEST(CorpusTool, ReportsBothSplitsReusesScenesAndIsDeterministic) {
  if (access(tool("corpus").c_str(), X_OK) != 0 || access(tool("detect").c_str(), X_OK) != 0)
    GTEST_SKIP() << "pcl_movers_corpus / pcl_movers_detect not built";
  const fs::path dir = fs::temp_directory_path() / ("corpus_tool_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  ASSERT_EQ(runCorpus(dir / "a", dir / "a.log"), 0) << readFile(dir / "a.log");
  const std::string report = readFile(dir / "a" / "report-all.md");
  const std::size_t check = report.find("## Scene corpus, check split");
  const std::size_t tune = report.find("## Scene corpus, tune split");
  ASSERT_NE(check, std::string::npos) << report;
  ASSERT_NE(tune, std::string::npos) << report;
  EXPECT_LT(check, tune);
  EXPECT_NE(report.find("| parking |", check), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "a" / "scenes" / "parking-1" / "objects.txt"));
  EXPECT_TRUE(fs::exists(dir / "a" / "runs" / "centroid" / "parking-2" / "tracks.csv"));
  const std::string first = withoutTimes(readFile(dir / "a" / "results-all.jsonl"));
  EXPECT_NE(first.find("\"scene\": \"parking-2\""), std::string::npos);
  // Point labels written and scored (moving-point IoU) in the report and the JSON lines.
  EXPECT_TRUE(
      fs::exists(dir / "a" / "runs" / "centroid" / "parking-2" / "labels" / "000011.label"));
  EXPECT_NE(first.find("\"mos\": {\"tp\": "), std::string::npos) << first;
  EXPECT_NE(report.find("| moving IoU % |", check), std::string::npos) << report;

  // Again into the same folder: the scenes are reused, the numbers are the same.
  const auto stamp = fs::last_write_time(dir / "a" / "scenes" / "parking-1" / "objects.txt");
  ASSERT_EQ(runCorpus(dir / "a", dir / "a2.log"), 0) << readFile(dir / "a2.log");
  EXPECT_EQ(fs::last_write_time(dir / "a" / "scenes" / "parking-1" / "objects.txt"), stamp);
  EXPECT_EQ(withoutTimes(readFile(dir / "a" / "results-all.jsonl")), first);
  EXPECT_NE(readFile(dir / "a" / "report-all.md").find("(0.0 min of worker time simulating"),
            std::string::npos);

  // A scene cached by an older simulator (another output version in its stamp, e.g. other
  // labels) is simulated again.
  const fs::path stamp_file = dir / "a" / "scenes" / "parking-1" / "corpus_stamp.txt";
  std::string old_stamp = readFile(stamp_file);
  const std::size_t version = old_stamp.find("# simulator output version: ");
  ASSERT_NE(version, std::string::npos) << old_stamp;
  old_stamp.erase(version, old_stamp.find('\n', version) + 1 - version);
  std::ofstream(stamp_file) << old_stamp;
  ASSERT_EQ(runCorpus(dir / "a", dir / "a3.log"), 0) << readFile(dir / "a3.log");
  EXPECT_NE(fs::last_write_time(dir / "a" / "scenes" / "parking-1" / "objects.txt"), stamp);
  EXPECT_EQ(withoutTimes(readFile(dir / "a" / "results-all.jsonl")), first);

  // And into a fresh folder: simulated anew, the same numbers.
  ASSERT_EQ(runCorpus(dir / "b", dir / "b.log"), 0) << readFile(dir / "b.log");
  EXPECT_EQ(withoutTimes(readFile(dir / "b" / "results-all.jsonl")), first);
  fs::remove_all(dir);
}
