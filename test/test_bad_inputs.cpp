/*
 * The bad-input matrix (issue #8, docs/reliability.md): every built pcl_movers_* tool is run as a
 * user would run it — as a separate process, under `timeout` — on files a real recording can
 * produce: missing, empty, not a PCD, truncated, without x/y/z, all NaN, with Inf, one point,
 * duplicate points, huge coordinates, poses.txt/times.txt that do not match the frames,
 * non-monotonic times, an output that exists or cannot be created, an unknown flag.
 *
 * Each row states the expected outcome:
 *  - kFail:   exit code != 0 (not a signal, not the timeout), a message on stderr naming the
 * problem (one of the row's keywords, case-insensitive), and nothing left at the output path (or,
 * when the output existed before, it is unchanged).
 *  - kEither: inputs that are legitimately processable (a single point, duplicate points, one
 *             empty frame among good ones): exit 0, or a clean failure as for kFail. Never a crash.
 *  - kPass:   a control row on good input; it must succeed, which proves the failures above are
 *             caused by the bad input and not by a tool that always fails.
 * In every row: no signal, no sanitizer report, no hang (60 s timeout).
 *
 * A tool that is not built is skipped with a message. All inputs are generated in a temp folder.
 *
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/tracks.h>
#include <pcl_movers/sensor_model.h>
#include <pcl_movers/sim/capture.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.h"

namespace fs = std::filesystem;

namespace {

using test_util::readFile;
using test_util::writeFile;

enum class Expect { kFail, kEither, kPass };

struct Row {
  std::string name;  ///< what the row checks, for messages
  std::string args;  ///< arguments after the tool, already quoted
  Expect expect = Expect::kFail;
  std::vector<std::string> keywords;  ///< kFail/kEither: stderr must contain one of these
  std::string output;                 ///< path the tool would write ("" = none)
};

struct RunResult {
  int exit_code = -1;
  bool signalled = false;
  bool timed_out = false;
  std::string out, err;
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string quote(const std::string& s) {
  return "'" + s + "'";
}

/** Recursive listing with sizes and contents' hash, to prove "unchanged". */
std::map<std::string, std::size_t> snapshot(const std::string& path) {
  std::map<std::string, std::size_t> files;
  std::error_code ec;
  if (!fs::exists(path, ec)) return files;
  if (fs::is_regular_file(path, ec)) {
    files[path] = std::hash<std::string>()(readFile(path));
    return files;
  }
  for (const auto& e : fs::recursive_directory_iterator(path, ec))
    files[e.path().string()] =
        e.is_regular_file() ? std::hash<std::string>()(readFile(e.path())) : std::size_t(0);
  return files;
}

// ------------------------------------------------------------------ PCD writing
struct P {
  float x, y, z, i;
};

void writePcd(const std::string& path, const std::vector<P>& pts, bool binary = false,
              std::size_t width = 0, std::size_t height = 1) {
  if (width == 0) width = pts.size();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z intensity\n"
         "SIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH "
      << width << "\nHEIGHT " << height << "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << pts.size()
      << "\nDATA " << (binary ? "binary" : "ascii") << "\n";
  if (binary) {
    out.write(reinterpret_cast<const char*>(pts.data()),
              static_cast<std::streamsize>(pts.size() * sizeof(P)));
  } else {
    out.precision(9);
    for (const auto& p : pts) out << p.x << " " << p.y << " " << p.z << " " << p.i << "\n";
  }
}

/** The inputs, built once for all tools. */
class BadInputs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/pcl_movers_bad_inputs_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    const std::string d = dir_ + "/in/";
    fs::create_directories(d);

    // A good sequence from the simulator: 4 frames of a VLP-16, a car ahead, a person crossing.
    const std::string scenario_text =
        "name: bad_inputs\nseed: 3\nframes: 4\nrate_hz: 10\n"
        "sensor: {preset: vlp16, height: 1.73, max_range: 60, min_range: 2.0}\n"
        "terrain: {type: plane, height: 0}\n"
        "ego: {start: [0, 0], heading: 0, speed: 5}\n"
        "movers:\n  - {type: car, start: [15, 3], heading: 180, speed: 8}\n"
        "  - {type: person, start: [10, -6], heading: 90, speed: 1.4}\n"
        "statics:\n  - {type: tree, position: [8, 8], height: 6, radius: 2}\n";
    writeFile(d + "scenario.yaml", scenario_text);
    const auto scenario = pcl_movers::sim::parseScenario(scenario_text, "scenario.yaml");
    pcl_movers::sim::LidarSimulator simulator(scenario);
    pcl_movers::sim::writeSequence(simulator, d + "seq_good", false);
    good_frame_ = d + "seq_good/frames/000000.pcd";

    // Velodyne captures: the good sequence as packets, the same cut after 5 packets (no full
    // sweep; a VLP-16 turn is 75 packets of 1248 bytes after a 16-byte record header), text.
    pcl_movers::sim::writeCapture(simulator, d + "good.pcap", false);
    writeFile(d + "short.pcap", readFile(d + "good.pcap").substr(0, 24 + 5 * (16 + 1248)));
    writeFile(d + "not_a_capture.pcap", "this is a text file, not a packet capture\n");

    // Single-file inputs.
    writeFile(d + "empty.pcd", "");
    writeFile(d + "not_a_pcd.pcd", "this is a text file, not a point cloud\n\x01\x02\x03");
    {  // a good binary frame cut in the middle of its data
      const std::string full = readFile(good_frame_);
      writeFile(d + "truncated.pcd", full.substr(0, full.size() / 2));
    }
    writeFile(d + "no_xyz.pcd",
              "VERSION 0.7\nFIELDS a b c\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\n"
              "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n1 2 3\n4 5 6\n7 8 9\n");
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    writePcd(d + "all_nan.pcd", std::vector<P>(512, P{nan, nan, nan, 0}), true, 32, 16);
    writePcd(d + "header_only.pcd", {});
    {
      std::vector<P> pts(200, P{inf, -inf, inf, 0});
      for (std::size_t k = 0; k < pts.size(); k += 2) pts[k] = P{nan, inf, 0, 0};
      writePcd(d + "inf.pcd", pts);
    }
    writePcd(d + "single.pcd", {P{8.f, 1.f, -1.2f, 10.f}});
    writePcd(d + "duplicates.pcd", std::vector<P>(1000, P{8.f, 1.f, -1.2f, 10.f}));
    {
      std::vector<P> pts;
      for (int k = 0; k < 500; ++k)
        pts.push_back(P{1e30f * float(k % 7 - 3), 3e37f, -1e35f * float(k % 5), 1.f});
      writePcd(d + "huge.pcd", pts);
    }
    writeFile(d + "a_file", "a regular file, so a path below it cannot be created\n");

    // Sequence folders.
    auto sequence = [&](const std::string& name, const std::string& frame_source) {
      fs::create_directories(d + name + "/frames");
      for (int f = 0; f < 3; ++f)
        fs::copy_file(frame_source, d + name + "/frames/00000" + std::to_string(f) + ".pcd");
      return d + name + "/";
    };
    fs::create_directories(d + "seq_no_frames");
    for (const char* kind : {"empty", "not_a_pcd", "truncated", "no_xyz", "all_nan", "inf",
                             "single", "duplicates", "huge"})
      sequence(std::string("seq_") + kind, d + kind + ".pcd");
    // One empty (all-NaN) frame between good ones: a dropout in a real recording.
    {
      const std::string s = d + "seq_nan_frame/";
      fs::create_directories(s + "frames");
      for (int f = 0; f < 4; ++f)
        fs::copy_file(
            f == 2 ? d + "all_nan.pcd" : d + "seq_good/frames/00000" + std::to_string(f) + ".pcd",
            s + "frames/00000" + std::to_string(f) + ".pcd");
      fs::copy_file(d + "seq_good/poses.txt", s + "poses.txt");
      fs::copy_file(d + "seq_good/times.txt", s + "times.txt");
    }
    // One truncated frame between good ones: a malformed file, not a blind frame.
    {
      const std::string s = d + "seq_truncated_frame/";
      fs::create_directories(s + "frames");
      for (int f = 0; f < 4; ++f)
        fs::copy_file(
            f == 2 ? d + "truncated.pcd" : d + "seq_good/frames/00000" + std::to_string(f) + ".pcd",
            s + "frames/00000" + std::to_string(f) + ".pcd");
      fs::copy_file(d + "seq_good/poses.txt", s + "poses.txt");
      fs::copy_file(d + "seq_good/times.txt", s + "times.txt");
    }
    // Good frames with broken side files.
    auto variant = [&](const std::string& name) {
      const std::string s = d + name + "/";
      fs::create_directories(s);
      fs::copy(d + "seq_good/frames", s + "frames", fs::copy_options::recursive);
      fs::copy_file(d + "seq_good/poses.txt", s + "poses.txt");
      fs::copy_file(d + "seq_good/times.txt", s + "times.txt");
      return s;
    };
    {
      const std::string s = variant("seq_poses_short");
      const std::string poses = readFile(s + "poses.txt");
      writeFile(s + "poses.txt", poses.substr(0, poses.find('\n') + 1));  // 1 pose, 4 frames
    }
    {
      const std::string s = variant("seq_poses_malformed");
      writeFile(s + "poses.txt",
                "1 0 0 0 0 1 0 0 0 0 1\n1 0 0 0 0 1 0 0 0 0 1 0\n"
                "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
    }
    {
      const std::string s = variant("seq_poses_nan");
      writeFile(s + "poses.txt",
                "1 0 0 0 0 1 0 0 0 0 1 0\nnan 0 0 0 0 1 0 0 0 0 1 0\n"
                "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
    }
    {
      const std::string s = variant("seq_times_long");
      writeFile(s + "times.txt", "0\n0.1\n0.2\n0.3\n0.4\n0.5\n");  // 6 times, 4 frames
    }
    {
      const std::string s = variant("seq_times_nonmonotonic");
      writeFile(s + "times.txt", "0\n0.2\n0.1\n0.3\n");
    }
    {
      const std::string s = variant("seq_times_garbage");
      writeFile(s + "times.txt", "0\n0.1\nabc\n0.3\n");
    }

    // Outputs that must be refused: an existing non-empty folder (and file), and a path whose
    // parent is a regular file.
    fs::create_directories(dir_ + "/existing_out");
    writeFile(dir_ + "/existing_out/keep.txt", "user data\n");
    writeFile(dir_ + "/existing_file.pcd", "user data\n");

    // Scenario files for the simulator.
    writeFile(d + "empty.yaml", "");
    writeFile(d + "garbage.yaml", std::string("\x7f\x45\x4c\x46\x02\x01\x01\0\0\0", 10));
    writeFile(d + "unknown_key.yaml",
              "frames: 2\nsensor: {preset: vlp16}\nego: {start: [0, 0], speed: 1}\nwheels: 4\n");
    writeFile(d + "negative.yaml",
              "frames: 2\nsensor: {preset: vlp16}\nstatics:\n"
              "  - {type: wall, position: [5, 0], size: [-3, 0.3, 2]}\n");
    writeFile(d + "bad_syntax.yaml", "frames: 2\nsensor: {preset: vlp16\nmovers: [[[\n");
    writeFile(d + "zero_frames.yaml", "frames: 0\nsensor: {preset: vlp16}\n");
    writeFile(d + "small.yaml",
              "frames: 2\nsensor: {preset: vlp16}\n"
              "ego: {start: [0, 0], speed: 1}\n");

    // Evaluation inputs: the good sequence's objects.txt and a few tracks.
    pcl_movers::io::TrackRow row;
    row.frame = 0;
    row.track_id = 1;
    row.mover = true;
    row.x = 15;
    row.y = 3;
    row.points = 50;
    pcl_movers::io::writeTracks(d + "tracks.csv", {row});
    writeFile(d + "tracks_bad_header.csv", "a,b,c\n1,2,3\n");
    writeFile(d + "tracks_garbage.csv",
              std::string(pcl_movers::io::tracksCsvHeader()) + "\n0,0,1,1,x,y,z\n");
    writeFile(d + "tracks_nan.csv", std::string(pcl_movers::io::tracksCsvHeader()) +
                                        "\n0,0,1,1,nan,0,0,0,0,0,0,0,0,4,2,1.5,0,0.5,50\n");
  }

  static void TearDownTestSuite() {
    std::error_code ec;
    if (!dir_.empty() && !std::getenv("PCL_MOVERS_KEEP_BAD_INPUTS")) fs::remove_all(dir_, ec);
  }

  static std::string in(const std::string& name) { return dir_ + "/in/" + name; }
  static std::string out(const std::string& name) { return dir_ + "/out/" + name; }

  /** Tools come from this build; PCL_MOVERS_TOOLS_DIR overrides (an installed suite, or another
   * build dir) so the matrix can be run against any set of binaries. */
  static std::string toolPath(const std::string& tool) {
    const char* dir = std::getenv("PCL_MOVERS_TOOLS_DIR");
    return std::string(dir && *dir ? dir : PCL_MOVERS_BINARY_DIR "/apps") + "/pcl_movers_" + tool;
  }
  static bool toolBuilt(const std::string& tool) {
    return access(toolPath(tool).c_str(), X_OK) == 0;
  }

  static RunResult run(const std::string& tool, const std::string& args) {
    static int counter = 0;
    const std::string base = dir_ + "/log" + std::to_string(counter++);
    // -k: a tool that ignores SIGTERM is killed 5 s later; the test can never hang.
    const std::string command = "cd " + quote(dir_) + " && timeout -k 5 60 " +
                                quote(toolPath(tool)) + " " + args + " >" + quote(base + ".out") +
                                " 2>" + quote(base + ".err") + " </dev/null";
    const int status = std::system(command.c_str());
    RunResult r;
    r.out = readFile(base + ".out");
    r.err = readFile(base + ".err");
    if (WIFSIGNALED(status)) {
      r.signalled = true;
    } else if (WIFEXITED(status)) {
      r.exit_code = WEXITSTATUS(status);
      r.timed_out = r.exit_code == 124 || r.exit_code == 137;
      // The shell reports a child killed by a signal as 128 + signal number.
      r.signalled = r.exit_code > 128 && !r.timed_out;
    }
    return r;
  }

  /** Runs all rows of one tool and checks them. */
  static void check(const std::string& tool, const std::vector<Row>& rows) {
    for (const auto& row : rows) {
      SCOPED_TRACE("pcl_movers_" + tool + " " + row.args + "   [" + row.name + "]");
      // Fresh output location per row; an "existing" output is snapshotted instead.
      const bool preexisting = !row.output.empty() && fs::exists(row.output);
      if (!row.output.empty() && !preexisting) fs::create_directories(dir_ + "/out");
      const auto before = snapshot(row.output);
      const RunResult r = run(tool, row.args);
      const std::string err = lower(r.err);
      EXPECT_FALSE(r.timed_out) << "hung (killed by the 60 s timeout)";
      EXPECT_FALSE(r.signalled) << "died by a signal (exit status " << r.exit_code << "); stderr:\n"
                                << r.err;
      for (const char* marker :
           {"addresssanitizer", "leaksanitizer", "runtime error:", "undefinedbehaviorsanitizer"})
        EXPECT_EQ(err.find(marker), std::string::npos) << "sanitizer report:\n" << r.err;
      // Each row starts from a clean output location (a kPass/kEither success writes there).
      auto cleanup = [&] {
        std::error_code ec;
        if (!preexisting && !row.output.empty()) fs::remove_all(row.output, ec);
      };
      if (row.expect == Expect::kPass || (row.expect == Expect::kEither && r.exit_code == 0)) {
        EXPECT_EQ(r.exit_code, 0) << "good input must succeed; stderr:\n" << r.err;
        cleanup();
        continue;
      }
      EXPECT_NE(r.exit_code, 0) << "bad input accepted; stdout:\n"
                                << r.out << "\nstderr:\n"
                                << r.err;
      bool named = false;
      for (const auto& k : row.keywords) named = named || err.find(lower(k)) != std::string::npos;
      if (r.exit_code != 0)
        EXPECT_TRUE(named) << "stderr does not name the problem (expected one of: "
                           << ::testing::PrintToString(row.keywords) << "); stderr:\n"
                           << r.err;
      if (!row.output.empty() && r.exit_code != 0) {
        if (preexisting)
          EXPECT_EQ(snapshot(row.output), before) << "existing output was modified";
        else
          EXPECT_FALSE(fs::exists(row.output)) << "half-written output left behind: " << row.output;
      }
      cleanup();
    }
  }

  /** Rows every tool shares. */
  static std::vector<Row> commonRows() {
    return {
        {"unknown flag", "--no-such-flag", Expect::kFail, {"--no-such-flag"}},
        {"no arguments", "", Expect::kFail, {"usage", "argument", "expected"}},
    };
  }

  /** Rows for tools taking INPUT (file or sequence folder) and OUTPUT; `output_is_file` for a
   * single-file input when OUTPUT is a file. */
  static std::vector<Row> scanRows(const std::string& tool, bool file_inputs,
                                   const std::string& output_suffix) {
    std::vector<Row> rows = commonRows();
    const std::string o = out(tool + output_suffix);
    auto row = [&](const std::string& name, const std::string& input, Expect e,
                   std::vector<std::string> keys, const std::string& output = "") {
      const std::string dst = output.empty() ? o : output;
      keys.push_back(fs::path(input).filename().string());
      rows.push_back({name, quote(input) + " " + quote(dst), e, keys, dst});
    };
    // "valid points": the organizer's beam-layout estimate needs a few hundred points.
    const std::vector<std::string> invalid{"no finite", "no valid",  "nan",   "finite",
                                           "invalid",   "no points", "empty", "valid points",
                                           "infinite",  "no return"};
    row("good sequence (control)", in("seq_good"), Expect::kPass, {});
    row("missing input", in("does_not_exist"), Expect::kFail,
        {"does not exist", "no such", "not found", "cannot open"});
    row("empty folder", in("seq_no_frames"), Expect::kFail,
        {"no frames", "no scans", "empty", "no .pcd", "no pcd"});
    row("empty PCD files", in("seq_empty"), Expect::kFail, {"empty", "no frames"});
    row("non-PCD frames", in("seq_not_a_pcd"), Expect::kFail,
        {"pcd", "header", "malformed", "could not read", "not a"});
    row("truncated PCD frames", in("seq_truncated"), Expect::kFail,
        {"truncated", "malformed", "could not read", "short"});
    row("PCD without x/y/z", in("seq_no_xyz"), Expect::kFail, {"'x'", "x y z", "x/y/z", "field"});
    row("all-NaN frames", in("seq_all_nan"), Expect::kFail, invalid);
    row("NaN/Inf frames", in("seq_inf"), Expect::kFail, invalid);
    row("single-point frames", in("seq_single"), Expect::kEither, invalid);
    row("duplicate-point frames", in("seq_duplicates"), Expect::kEither, invalid);
    row("huge coordinates", in("seq_huge"), Expect::kEither,
        {"range", "huge", "field of view", "finite", "no point", "invalid", "valid points"});
    row("non-empty output folder", in("seq_good"), Expect::kFail,
        {"not empty", "exists", "--overwrite"}, dir_ + "/existing_out");
    row("output below a regular file", in("seq_good"), Expect::kFail,
        {"cannot create", "not a directory", "could not create", "failed to create", "a_file"},
        in("a_file") + "/out");
    if (file_inputs) {
      const std::string f = out(tool + "_single.pcd");
      auto frow = [&](const std::string& name, const std::string& input, Expect e,
                      std::vector<std::string> keys, const std::string& output = "") {
        const std::string dst = output.empty() ? f : output;
        keys.push_back(fs::path(input).filename().string());
        rows.push_back({name, quote(input) + " " + quote(dst), e, keys, dst});
      };
      frow("good file (control)", good_frame_, Expect::kPass, {});
      frow("missing file", in("does_not_exist.pcd"), Expect::kFail, {"does not exist", "no such"});
      frow("empty file", in("empty.pcd"), Expect::kFail, {"empty", "header", "could not read"});
      frow("non-PCD file", in("not_a_pcd.pcd"), Expect::kFail,
           {"pcd", "header", "malformed", "could not read"});
      frow("truncated PCD", in("truncated.pcd"), Expect::kFail,
           {"truncated", "malformed", "could not read"});
      frow("PCD without x/y/z", in("no_xyz.pcd"), Expect::kFail, {"'x'", "field"});
      frow("PCD with 0 points", in("header_only.pcd"), Expect::kFail, invalid);
      frow("all-NaN PCD", in("all_nan.pcd"), Expect::kFail, invalid);
      frow("NaN/Inf PCD", in("inf.pcd"), Expect::kFail, invalid);
      frow("single point", in("single.pcd"), Expect::kEither, invalid);
      frow("duplicate points", in("duplicates.pcd"), Expect::kEither, invalid);
      frow("huge coordinates", in("huge.pcd"), Expect::kEither,
           {"range", "huge", "field of view", "finite", "no point", "invalid", "valid points"});
      frow("existing output file", good_frame_, Expect::kFail, {"exists", "--overwrite"},
           dir_ + "/existing_file.pcd");
    }
    return rows;
  }

  /** Rows on poses.txt / times.txt, for tools that read them. */
  static std::vector<Row> sideFileRows(const std::string& tool, const std::string& output) {
    auto row = [&](const std::string& name, const std::string& seq, Expect e,
                   std::vector<std::string> keys) {
      return Row{name, quote(in(seq)) + " " + quote(output), e, std::move(keys), output};
    };
    return {
        row("poses.txt shorter than the frames", "seq_poses_short", Expect::kFail,
            {"poses", "pose"}),
        row("poses.txt with 11 numbers", "seq_poses_malformed", Expect::kFail, {"poses.txt", "12"}),
        row("poses.txt with NaN", "seq_poses_nan", Expect::kFail, {"poses.txt", "nan", "finite"}),
        row("times.txt longer than the frames", "seq_times_long", Expect::kFail, {"times", "time"}),
        row("non-monotonic times.txt", "seq_times_nonmonotonic", Expect::kFail,
            {"monoton", "increas", "times.txt"}),
        row("times.txt with text", "seq_times_garbage", Expect::kFail, {"times.txt", "number"}),
        // A blind frame (no return): a warning, its tracks coast, the run goes on (issue #27).
        row("one all-NaN frame among good ones", "seq_nan_frame", Expect::kPass, {}),
        // A malformed frame stays an error naming it (see Detect for --skip-bad-frames).
        row("one truncated frame among good ones", "seq_truncated_frame", Expect::kFail,
            {"000002.pcd"}),
    };
  }

  static std::string dir_;
  static std::string good_frame_;
};

std::string BadInputs::dir_;
std::string BadInputs::good_frame_;

#define SKIP_UNLESS_BUILT(tool) \
  if (!toolBuilt(tool))         \
  GTEST_SKIP() << toolPath(tool) << " is not built; build it to run its bad-input rows"

TEST_F(BadInputs, HelpIsNotAnError) {
  int checked = 0;
  for (const char* tool : {"detect", "ground", "segment", "organize", "register", "simulate",
                           "eval", "eval_segmentation", "ego_motion", "viewer", "corpus"}) {
    if (!toolBuilt(tool)) continue;
    SCOPED_TRACE(tool);
    const RunResult r = run(tool, "-h");
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_NE(lower(r.out + r.err).find("usage"), std::string::npos);
    ++checked;
  }
  if (checked == 0) GTEST_SKIP() << "no pcl_movers_* tool is built";
}

TEST_F(BadInputs, Detect) {
  SKIP_UNLESS_BUILT("detect");
  auto rows = scanRows("detect", false, "_out");
  for (auto& r : sideFileRows("detect", out("detect_out"))) rows.push_back(r);
  rows.push_back({"bad --rate",
                  quote(in("seq_good")) + " " + quote(out("detect_out")) + " --rate -5",
                  Expect::kFail,
                  {"rate"},
                  out("detect_out")});
  const std::string o = quote(out("detect_out"));
  rows.push_back({"truncated frame with --skip-bad-frames",
                  quote(in("seq_truncated_frame")) + " " + o + " --skip-bad-frames",
                  Expect::kPass,
                  {},
                  out("detect_out")});
  rows.push_back({"--resume without an earlier run",
                  quote(in("seq_good")) + " " + o + " --resume",
                  Expect::kFail,
                  {"--resume", "summary.json"},
                  out("detect_out")});
  rows.push_back({"--resume with --overwrite",
                  quote(in("seq_good")) + " " + o + " --resume --overwrite",
                  Expect::kFail,
                  {"--resume"},
                  out("detect_out")});
  rows.push_back({"--stop-after-frames 0",
                  quote(in("seq_good")) + " " + o + " --stop-after-frames 0",
                  Expect::kFail,
                  {"--stop-after-frames"},
                  out("detect_out")});
  rows.push_back({"missing --config",
                  quote(in("seq_good")) + " " + quote(out("detect_out")) + " --config " +
                      quote(in("nope.cfg")),
                  Expect::kFail,
                  {"nope.cfg"},
                  out("detect_out")});
  check("detect", rows);
}

// Determinism: the same input and parameters give a byte-identical tracks.csv (no dependence on
// thread timing, allocation addresses or unordered containers).
TEST_F(BadInputs, DetectIsDeterministic) {
  SKIP_UNLESS_BUILT("detect");
  std::string tracks[2];
  for (int k = 0; k < 2; ++k) {
    const std::string o = out("determinism_" + std::to_string(k));
    const RunResult r = run("detect", quote(in("seq_good")) + " " + quote(o));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    tracks[k] = readFile(o + "/tracks.csv");
  }
  EXPECT_GT(std::count(tracks[0].begin(), tracks[0].end(), '\n'), 1) << "no track rows at all";
  EXPECT_EQ(tracks[0], tracks[1]);
}

// Regression (found by this matrix, also in test/fuzz/corpus_pcd/regression_huge_coordinates.pcd):
// coordinates near FLT_MAX overflow r = sqrt(x² + y²) to inf; GroundPlaneFilter then cast inf to
// int for its ring lookup and indexed far outside its table (SIGSEGV in pcl_movers_ground and
// pcl_movers_segment). Such points are finite, so they must simply fall in the outermost ring.
TEST(BadInputsInProcess, GroundPlaneFilterSurvivesHugeCoordinates) {
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (int k = 0; k < 200; ++k)  // a patch of ground, so the filter has work to do
    cloud->push_back(
        pcl::PointXYZ(4.f + 0.1f * float(k % 20), -1.f + 0.2f * float(k / 20), -1.73f));
  cloud->push_back(pcl::PointXYZ(3e37f, 3e37f, -1e35f));
  cloud->push_back(pcl::PointXYZ(-3e37f, 3e37f, 0.f));
  cloud->push_back(pcl::PointXYZ(1e30f, -2e30f, 1e30f));
  pcl_movers::GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(cloud);
  pcl::Indices non_ground;
  filter.filter(non_ground);
  // Still a working filter: the patch is (mostly) ground, the three huge points are not.
  EXPECT_GE(non_ground.size(), 3u);
  EXPECT_LT(non_ground.size(), cloud->size());
}

// Regression (found by fuzz_pcd_pipeline, test/fuzz/corpus_pcd/regression_no_type_line.pcd): a PCD
// whose TYPE line is corrupted reads as 0 points, and readScan then ran pcl::fromPCLPointCloud2
// on the empty blob, which takes &cloud[0] of an empty vector (undefined behaviour, reported by
// UBSan in the sanitizer build). An empty result must be an InputError or an empty cloud.
TEST(BadInputsInProcess, ReadScanOfPcdWithCorruptTypeLine) {
  char tmpl[] = "/tmp/pcl_movers_corrupt_type_XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const std::string path = std::string(tmpl) + "/corrupt.pcd";
  writeFile(path,
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nHEIGTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
            "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n8 0 -0.4\n-19 0 -1.7\n");
  pcl::PointCloud<pcl::PointXYZ> cloud;
  try {
    pcl_movers::io::readScan(path, cloud);
    EXPECT_TRUE(cloud.empty());
  } catch (const pcl_movers::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("corrupt.pcd"), std::string::npos) << e.what();
  }
  fs::remove_all(tmpl);
}

// Found by fuzz_pcd_pipeline in the CI sanitizer job
// (test/fuzz/corpus_pcd/regression_header_claims_terabytes.pcd): pcl::PCDReader::readHeader
// allocates POINTS × point_step bytes before it reads any data, so a 190-byte file claiming
// 371 million points of 4 kB asked for 1.5 TB (ASan abort; std::bad_alloc escaping, or a real
// multi-GB allocation for smaller claims, in a plain build). readScan must refuse it up front.
TEST(BadInputsInProcess, ReadScanRefusesHeaderClaimingMoreDataThanTheFile) {
  const std::string path = std::string(PCL_MOVERS_SOURCE_DIR) +
                           "/test/fuzz/corpus_pcd/regression_header_claims_terabytes.pcd";
  pcl::PointCloud<pcl::PointXYZ> cloud;
  try {
    pcl_movers::io::readScan(path, cloud);
    ADD_FAILURE() << "a header claiming 1.5 TB of data in a tiny file was accepted";
  } catch (const pcl_movers::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("regression_header_claims_terabytes.pcd:10:"), std::string::npos) << what;
    EXPECT_NE(what.find("claims 371042315 points"), std::string::npos) << what;
  }
}

// The same check, per data format, must not refuse real files: PCL writes ascii, binary and
// binary_compressed; each reads back whole, and the same file with its POINTS/WIDTH inflated
// ten-fold is refused (binary: the bytes are not there; ascii: not enough text for the values;
// compressed: beyond LZF's largest expansion only for a much bigger claim, so ×1000 there).
TEST(BadInputsInProcess, ReadScanClaimedSizeCheckPerDataFormat) {
  char tmpl[] = "/tmp/pcl_movers_claimed_size_XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  for (int k = 0; k < 500; ++k)
    cloud.push_back(pcl::PointXYZI(0.01f * k, 5.f - 0.02f * k, -1.5f + 0.001f * k, float(k % 7)));
  auto inflate = [](std::string text, unsigned factor) {
    for (const char* key : {"WIDTH ", "POINTS "}) {
      const std::size_t at = text.find(std::string("\n") + key) + 1 + std::strlen(key);
      const std::size_t end = text.find('\n', at);
      const unsigned long n = std::stoul(text.substr(at, end - at));
      text.replace(at, end - at, std::to_string(n * factor));
    }
    return text;
  };
  struct Format {
    const char* name;
    int (*save)(const std::string&, const pcl::PointCloud<pcl::PointXYZI>&);
    unsigned inflation;
  };
  const Format formats[] = {
      {"ascii",
       [](const std::string& p, const pcl::PointCloud<pcl::PointXYZI>& c) {
         return pcl::io::savePCDFileASCII(p, c);
       },
       10},
      {"binary",
       [](const std::string& p, const pcl::PointCloud<pcl::PointXYZI>& c) {
         return pcl::io::savePCDFileBinary(p, c);
       },
       10},
      {"binary_compressed",
       [](const std::string& p, const pcl::PointCloud<pcl::PointXYZI>& c) {
         return pcl::io::savePCDFileBinaryCompressed(p, c);
       },
       1000},
  };
  for (const Format& f : formats) {
    SCOPED_TRACE(f.name);
    const std::string good = std::string(tmpl) + "/" + f.name + ".pcd";
    ASSERT_EQ(f.save(good, cloud), 0);
    pcl::PointCloud<pcl::PointXYZI> back;
    pcl_movers::io::readScan(good, back);
    EXPECT_EQ(back.size(), cloud.size());
    const std::string bad = std::string(tmpl) + "/" + f.name + "_inflated.pcd";
    writeFile(bad, inflate(readFile(good), f.inflation));
    try {
      pcl_movers::io::readScan(bad, back);
      ADD_FAILURE() << "inflated header accepted";
    } catch (const pcl_movers::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("header claims"), std::string::npos) << e.what();
    }
  }
  fs::remove_all(tmpl);
}

// Found by fuzz_pcd_pipeline in the CI sanitizer job: a PCD whose points have huge elevations made
// the beam estimator's Hough binning cast ~1e28 to int (undefined behaviour, src/sensor_model.cpp).
// In the sanitizer build UBSan aborts here without the fix; in any build the estimate must either
// succeed or refuse with InputError.
TEST(BadInputsInProcess, SensorModelEstimateSurvivesHugeOffsets) {
  const std::string path = std::string(PCL_MOVERS_SOURCE_DIR) +
                           "/test/fuzz/corpus_pcd/regression_beam_estimate_huge_offset.pcd";
  pcl::PointCloud<pcl::PointXYZ> cloud;
  pcl_movers::io::readScan(path, cloud);
  ASSERT_GE(cloud.size(), 200u) << "the regression input must reach the beam estimator";
  try {
    const pcl_movers::SensorModel model = pcl_movers::SensorModel::estimate(cloud);
    EXPECT_GT(model.rows(), 0);
  } catch (const pcl_movers::InputError& e) {
    EXPECT_FALSE(std::string(e.what()).empty());
  }
}

TEST_F(BadInputs, Ground) {
  SKIP_UNLESS_BUILT("ground");
  check("ground", scanRows("ground", true, "_out"));
}

TEST_F(BadInputs, Segment) {
  SKIP_UNLESS_BUILT("segment");
  check("segment", scanRows("segment", true, "_out"));
}

TEST_F(BadInputs, Organize) {
  SKIP_UNLESS_BUILT("organize");
  check("organize", scanRows("organize", true, "_out"));
}

TEST_F(BadInputs, OrganizeCapture) {
  SKIP_UNLESS_BUILT("organize");
  const std::string o = out("capture_out");
  auto row = [&](const std::string& name, const std::string& args, Expect e,
                 std::vector<std::string> keys, const std::string& output = "") {
    const std::string dst = output.empty() ? o : output;
    return Row{name, args + " " + quote(dst), e, std::move(keys), dst};
  };
  const std::string pcap = "--pcap " + quote(in("good.pcap"));
  check(
      "organize",
      {
          row("good capture (control)", pcap, Expect::kPass, {}),
          row("good capture, sensor given (control)", pcap + " --sensor vlp16", Expect::kPass, {}),
          row("missing capture", "--pcap " + quote(in("missing.pcap")), Expect::kFail,
              {"missing.pcap: does not exist"}),
          row("not a pcap", "--pcap " + quote(in("not_a_capture.pcap")), Expect::kFail,
              {"not_a_capture.pcap: not a pcap"}),
          row("a PCD given as capture", "--pcap " + quote(good_frame_), Expect::kFail,
              {"000000.pcd: not a pcap"}),
          row("no full sweep", "--pcap " + quote(in("short.pcap")), Expect::kFail,
              {"short.pcap: no full sweep"}),
          row("unknown sensor", pcap + " --sensor hdl999", Expect::kFail,
              {"unknown velodyne sensor 'hdl999'"}),
          row("wrong sensor", pcap + " --sensor hdl32", Expect::kFail,
              {"good.pcap: is a vlp-16 capture"}),
          row("hdl64 without calibration", pcap + " --sensor hdl64", Expect::kFail, {"--calib"}),
          row("missing calibration", pcap + " --sensor hdl64 --calib " + quote(in("missing.xml")),
              Expect::kFail, {"missing.xml"}),
          row("calibration not XML", pcap + " --sensor hdl64 --calib " + quote(in("garbage.yaml")),
              Expect::kFail, {"garbage.yaml"}),
          row("non-empty output folder", pcap, Expect::kFail,
              {"not empty", "exists", "--overwrite"}, dir_ + "/existing_out"),
          row("output below a regular file", pcap, Expect::kFail,
              {"cannot", "not a directory", "a_file"}, in("a_file") + "/capture"),
      });
}

TEST_F(BadInputs, EgoMotion) {
  SKIP_UNLESS_BUILT("ego_motion");
  std::vector<Row> rows = commonRows();
  const std::string o = out("ego_poses.txt");
  auto row = [&](const std::string& name, const std::string& seq, Expect e,
                 std::vector<std::string> keys, const std::string& output = "") {
    const std::string dst = output.empty() ? o : output;
    rows.push_back({name, quote(seq) + " " + quote(dst), e, keys, dst});
  };
  row("good sequence (control)", in("seq_good"), Expect::kPass, {});
  row("missing sequence", in("does_not_exist"), Expect::kFail, {"does not exist", "no such"});
  row("empty folder", in("seq_no_frames"), Expect::kFail, {"no frames", "empty", "no scans"});
  row("truncated frames", in("seq_truncated"), Expect::kFail, {"truncated", "could not read"});
  row("non-PCD frames", in("seq_not_a_pcd"), Expect::kFail, {"pcd", "header", "could not read"});
  row("all-NaN frames", in("seq_all_nan"), Expect::kFail,
      {"no finite", "no valid", "nan", "points", "empty"});
  row("huge coordinates", in("seq_huge"), Expect::kEither, {"points", "range", "finite"});
  row("existing output file", in("seq_good"), Expect::kFail, {"exists", "--overwrite"},
      dir_ + "/existing_file.pcd");
  row("output below a regular file", in("seq_good"), Expect::kFail,
      {"cannot", "not a directory", "a_file"}, in("a_file") + "/poses.txt");
  check("ego_motion", rows);
}

TEST_F(BadInputs, Simulate) {
  SKIP_UNLESS_BUILT("simulate");
  std::vector<Row> rows = commonRows();
  const std::string o = out("sim_out");
  auto row = [&](const std::string& name, const std::string& scenario, Expect e,
                 std::vector<std::string> keys, const std::string& output = "") {
    const std::string dst = output.empty() ? o : output;
    rows.push_back({name, quote(scenario) + " " + quote(dst), e, keys, dst});
  };
  row("good scenario (control)", in("small.yaml"), Expect::kPass, {});
  row("missing scenario", in("does_not_exist.yaml"), Expect::kFail,
      {"does not exist", "no such", "cannot open", "cannot read"});
  row("empty scenario", in("empty.yaml"), Expect::kEither, {"empty", "empty.yaml"});
  row("binary garbage", in("garbage.yaml"), Expect::kFail, {"garbage.yaml"});
  row("unknown key", in("unknown_key.yaml"), Expect::kFail, {"wheels"});
  row("negative size", in("negative.yaml"), Expect::kFail, {"size", "negative", "positive"});
  row("malformed syntax", in("bad_syntax.yaml"), Expect::kFail, {"bad_syntax.yaml:"});
  row("zero frames", in("zero_frames.yaml"), Expect::kFail, {"frames"});
  row("non-empty output folder", in("small.yaml"), Expect::kFail,
      {"not empty", "exists", "--overwrite"}, dir_ + "/existing_out");
  row("output below a regular file", in("small.yaml"), Expect::kFail,
      {"cannot", "not a directory", "a_file"}, in("a_file") + "/sim");
  rows.push_back({"--frames 0",
                  quote(in("small.yaml")) + " " + quote(o) + " --frames 0",
                  Expect::kFail,
                  {"--frames"},
                  o});
  rows.push_back({"unknown --sensor",
                  quote(in("small.yaml")) + " " + quote(o) + " --sensor hdl999",
                  Expect::kFail,
                  {"hdl999"},
                  o});
  rows.push_back({"generated scene (control)",
                  "--family urban --seed 2 --frames 2 " + quote(o),
                  Expect::kPass,
                  {},
                  o});
  rows.push_back(
      {"unknown --family", "--family motorway " + quote(o), Expect::kFail, {"motorway"}, o});
  rows.push_back(
      {"--pcap (control)",
       quote(in("small.yaml")) + " " + quote(o) + " --pcap " + quote(out("sim_capture.pcap")),
       Expect::kPass,
       {},
       o});
  rows.push_back({"--pcap for a sensor without packets",
                  quote(in("small.yaml")) + " " + quote(o) + " --sensor os1_64 --pcap " +
                      quote(out("sim_capture_os1.pcap")),
                  Expect::kFail,
                  {"'os1_64' has no velodyne packet format"},
                  o});
  rows.push_back(
      {"--pcap onto an existing file",
       quote(in("small.yaml")) + " " + quote(o) + " --pcap " + quote(dir_ + "/existing_file.pcd"),
       Expect::kFail,
       {"existing_file.pcd: exists"},
       o});
  rows.push_back({"--family with a scenario file too",
                  "--family urban " + quote(in("small.yaml")) + " " + quote(o),
                  Expect::kFail,
                  {"positional"},
                  o});
  check("simulate", rows);
}

TEST_F(BadInputs, Corpus) {
  SKIP_UNLESS_BUILT("corpus");
  const std::string o = out("corpus_out");
  std::vector<Row> rows = {
      {"no output folder", "", Expect::kFail, {"output folder"}, ""},
      {"unknown --split", quote(o) + " --split half", Expect::kFail, {"--split"}, o},
      {"unknown family", quote(o) + " --families motorway", Expect::kFail, {"motorway"}, o},
      {"unknown mode", quote(o) + " --modes icp", Expect::kFail, {"icp"}, o},
      {"--seeds 0", quote(o) + " --seeds 0", Expect::kFail, {"--seeds"}, o},
      {"--detect not a program",
       quote(o) + " --detect " + quote(in("small.yaml")),
       Expect::kFail,
       {"small.yaml"},
       o},
      {"output is a file", quote(in("small.yaml")), Expect::kFail, {"not a folder"}, ""},
  };
  check("corpus", rows);
}

TEST_F(BadInputs, Eval) {
  SKIP_UNLESS_BUILT("eval");
  std::vector<Row> rows = commonRows();
  const std::string objects = in("seq_good/objects.txt");
  auto row = [&](const std::string& name, const std::string& args, Expect e,
                 std::vector<std::string> keys, const std::string& output = "") {
    rows.push_back({name, args, e, keys, output});
  };
  row("good files (control)", quote(objects) + " " + quote(in("tracks.csv")), Expect::kPass, {});
  row("missing tracks", quote(objects) + " " + quote(in("nope.csv")), Expect::kFail, {"nope.csv"});
  row("missing objects", quote(in("nope.txt")) + " " + quote(in("tracks.csv")), Expect::kFail,
      {"nope.txt"});
  row("empty objects", quote(in("empty.pcd")) + " " + quote(in("tracks.csv")), Expect::kFail,
      {"empty", "no ground-truth", "objects"});
  row("tracks with a wrong header", quote(objects) + " " + quote(in("tracks_bad_header.csv")),
      Expect::kFail, {"header", "tracks_bad_header.csv"});
  row("tracks with text in numbers", quote(objects) + " " + quote(in("tracks_garbage.csv")),
      Expect::kFail, {"tracks_garbage.csv"});
  row("tracks with NaN", quote(objects) + " " + quote(in("tracks_nan.csv")), Expect::kFail,
      {"tracks_nan.csv", "nan", "finite"});
  row("PCD given as tracks", quote(objects) + " " + quote(good_frame_), Expect::kFail,
      {"header", "000000.pcd"});
  row("existing --json",
      quote(objects) + " " + quote(in("tracks.csv")) + " --json " +
          quote(dir_ + "/existing_file.pcd"),
      Expect::kFail, {"exists", "--overwrite"}, dir_ + "/existing_file.pcd");
  row("negative --sector-deg", quote(objects) + " " + quote(in("tracks.csv")) + " --sector-deg -10",
      Expect::kFail, {"sector"});
  check("eval", rows);
}

TEST_F(BadInputs, Register) {
  SKIP_UNLESS_BUILT("register");
  std::vector<Row> rows = commonRows();
  auto row = [&](const std::string& name, const std::string& a, const std::string& b, Expect e,
                 std::vector<std::string> keys) {
    keys.push_back(fs::path(a == good_frame_ ? b : a).filename().string());
    rows.push_back({name, quote(a) + " " + quote(b), e, keys, ""});
  };
  row("good pair (control)", good_frame_, good_frame_, Expect::kPass, {});
  row("missing target", good_frame_, in("does_not_exist.pcd"), Expect::kFail, {"does not exist"});
  row("empty source", in("empty.pcd"), good_frame_, Expect::kFail, {"empty", "could not read"});
  row("non-PCD", in("not_a_pcd.pcd"), good_frame_, Expect::kFail, {"pcd", "could not read"});
  row("truncated", good_frame_, in("truncated.pcd"), Expect::kFail, {"truncated"});
  row("no x/y/z", in("no_xyz.pcd"), good_frame_, Expect::kFail, {"'x'", "field"});
  row("all NaN", in("all_nan.pcd"), good_frame_, Expect::kFail,
      {"no finite", "nan", "no valid", "empty"});
  row("NaN/Inf", good_frame_, in("inf.pcd"), Expect::kFail,
      {"no finite", "nan", "no valid", "empty"});
  row("single point", in("single.pcd"), in("single.pcd"), Expect::kEither, {"points", "too few"});
  row("duplicate points", in("duplicates.pcd"), in("duplicates.pcd"), Expect::kEither, {"points"});
  row("huge coordinates", in("huge.pcd"), good_frame_, Expect::kEither,
      {"range", "huge", "finite", "points"});
  check("register", rows);
}

TEST_F(BadInputs, EvalSegmentation) {
  SKIP_UNLESS_BUILT("eval_segmentation");
  std::vector<Row> rows = commonRows();
  rows.erase(rows.begin() + 1);  // without arguments it evaluates the default data set
  rows.push_back({"missing --sequence",
                  "--sequence " + quote(in("does_not_exist")),
                  Expect::kFail,
                  {"does_not_exist", "does not exist"}});
  rows.push_back({"bad --frames", "--frames abc", Expect::kFail, {"--frames"}});
  rows.push_back({"negative --depth-ratio", "--depth-ratio -1", Expect::kFail, {"--depth-ratio"}});
  check("eval_segmentation", rows);
}

TEST_F(BadInputs, Viewer) {
  SKIP_UNLESS_BUILT("viewer");
  std::vector<Row> rows = commonRows();
  rows.erase(rows.begin() + 1);  // no arguments
  const std::string shots = out("shots");
  auto row = [&](const std::string& name, const std::string& seq, Expect e,
                 std::vector<std::string> keys, const std::string& extra = "") {
    rows.push_back(
        {name, quote(seq) + " --screenshot-dir " + quote(shots) + extra, e, keys, shots});
  };
  row("missing sequence", in("does_not_exist"), Expect::kFail, {"does not exist", "no such"});
  row("empty folder", in("seq_no_frames"), Expect::kFail, {"no frames", "empty", "no scans"});
  row("truncated frames", in("seq_truncated"), Expect::kFail, {"truncated", "could not read"});
  row("non-PCD frames", in("seq_not_a_pcd"), Expect::kFail, {"pcd", "could not read"});
  row("missing --detections", in("seq_good"), Expect::kFail, {"nope_dir", "tracks.csv"},
      " --detections " + quote(in("nope_dir")));
  row("bad --frames", in("seq_good"), Expect::kFail, {"--frames", "frames"}, " --frames 9:2");
  rows.push_back({"non-empty screenshot dir",
                  quote(in("seq_good")) + " --screenshot-dir " + quote(dir_ + "/existing_out"),
                  Expect::kFail,
                  {"not empty", "exists", "--overwrite"},
                  dir_ + "/existing_out"});
  check("viewer", rows);
}

}  // namespace
