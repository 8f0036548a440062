/*
 * pcl_movers_detect on real-recording situations (issue #27), run as a user runs it — a separate
 * process on a simulated sequence: blind and malformed frames (--skip-bad-frames), interruption by
 * SIGINT/SIGTERM (tracks.csv keeps every complete frame, summary.json says so, exit 128 + signal)
 * and --resume (byte-identical to an uninterrupted run, labelled clouds included).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/point_labels.h>
#include <pcl_movers/io/tracks.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "test_util.h"

namespace fs = std::filesystem;

namespace {

using test_util::readFile;
using test_util::writeFile;

std::string toolPath() {
  return PCL_MOVERS_BINARY_DIR "/apps/pcl_movers_detect";
}

struct ToolRun {
  int exit_code = -1;
  std::string err;
};

/** Starts `tool` with `args` (stderr to `err_path`, stdout to `out_path`); returns its pid. */
pid_t startTool(const std::string& tool, const std::vector<std::string>& args,
                const std::string& err_path, const std::string& out_path = "/dev/null") {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv{const_cast<char*>(tool.c_str())};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (!freopen(err_path.c_str(), "w", stderr) || !freopen(out_path.c_str(), "w", stdout))
      _exit(126);
    execv(tool.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

/** Starts pcl_movers_detect with `args` (stderr to `err_path`); returns the child's pid. */
pid_t start(const std::vector<std::string>& args, const std::string& err_path) {
  return startTool(toolPath(), args, err_path);
}

ToolRun finish(pid_t pid, const std::string& err_path) {
  int status = 0;
  waitpid(pid, &status, 0);
  ToolRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 1000 + WTERMSIG(status);
  r.err = readFile(err_path);
  return r;
}

ToolRun detect(const std::vector<std::string>& args, const std::string& dir) {
  const std::string err = dir + "/stderr.txt";
  return finish(start(args, err), err);
}

/** Rows of tracks.csv (without the header) of frames < `frames`. */
std::string rowsBefore(const std::string& tracks, long frames) {
  std::istringstream in(tracks);
  std::string line, out;
  std::getline(in, line);
  while (std::getline(in, line))
    if (std::atol(line.c_str()) < frames) out += line + "\n";
  return out;
}

long jsonNumber(const std::string& text, const std::string& key) {
  const std::size_t at = text.find("\"" + key + "\": ");
  return at == std::string::npos ? -1000 : std::atol(text.c_str() + at + key.size() + 4);
}

class DetectTool : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/pcl_movers_detect_tool_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    // A VLP-16 on a car at 5 m/s, an oncoming car and a crossing person: movers to track.
    const auto scenario = pcl_movers::sim::parseScenario(
        "name: detect_tool\nseed: 5\nframes: 30\nrate_hz: 10\n"
        "sensor: {preset: vlp16, height: 1.73, max_range: 60, min_range: 2.0}\n"
        "terrain: {type: plane, height: 0}\n"
        "ego: {start: [0, 0], heading: 0, speed: 5}\n"
        "movers:\n  - {type: car, start: [30, 3], heading: 180, speed: 6}\n"
        "  - {type: person, start: [12, -6], heading: 90, speed: 1.4}\n"
        "statics:\n  - {type: car, position: [14, -5], yaw: 0}\n"
        "  - {type: tree, position: [8, 8], height: 6, radius: 2}\n",
        "detect_tool.yaml");
    if (!fs::exists(toolPath())) return;  // each test skips, naming the tool
    pcl_movers::sim::LidarSimulator simulator(scenario);
    pcl_movers::sim::writeSequence(simulator, dir_ + "/seq", false);
    // The reference: an uninterrupted run.
    const ToolRun r =
        detect({dir_ + "/seq", dir_ + "/ref", "--labelled-clouds", "--point-labels"}, dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    reference_ = readFile(dir_ + "/ref/tracks.csv");
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  void SetUp() override {
    if (!fs::exists(toolPath())) GTEST_SKIP() << toolPath() << " is not built";
  }

  /** Labelled clouds of `out` equal the reference's, byte for byte. */
  static void expectSameLabelled(const std::string& out) {
    std::size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir_ + "/ref/labelled")) {
      const std::string name = e.path().filename().string();
      EXPECT_EQ(readFile(e.path().string()), readFile(out + "/labelled/" + name)) << name;
      ++n;
    }
    EXPECT_EQ(n, 31u);  // 30 clouds and run_key.txt (the same run key: the same run)
    std::size_t m = 0;
    for (const auto& e : fs::directory_iterator(out + "/labelled")) m += e.is_regular_file();
    EXPECT_EQ(m, n) << "extra files in " << out << "/labelled";
  }

  static std::string dir_;
  static std::string reference_;
};

std::string DetectTool::dir_;
std::string DetectTool::reference_;

}  // namespace

// --stop-after-frames N (hidden, for tests) stops exactly as SIGINT does after N frames; --resume
// then finishes the run with outputs byte-identical to the uninterrupted one.
TEST_F(DetectTool, InterruptThenResumeEqualsUninterruptedRun) {
  ASSERT_GT(std::count(reference_.begin(), reference_.end(), '\n'), 40) << "too few rows";
  const std::string out = dir_ + "/stopped";
  ToolRun r = detect(
      {dir_ + "/seq", out, "--labelled-clouds", "--point-labels", "--stop-after-frames", "12"},
      dir_);
  EXPECT_EQ(r.exit_code, 130) << r.err;
  EXPECT_NE(r.err.find("--resume"), std::string::npos) << r.err;
  const std::string summary = readFile(out + "/summary.json");
  EXPECT_NE(summary.find("\"interrupted\": true"), std::string::npos) << summary;
  EXPECT_EQ(jsonNumber(summary, "last_complete_frame"), 11) << summary;
  // Every complete frame is there, and nothing after it.
  const std::string partial = readFile(out + "/tracks.csv");
  EXPECT_EQ(rowsBefore(partial, 1000), rowsBefore(reference_, 12));
  EXPECT_FALSE(rowsBefore(partial, 1000).empty());

  // Another run's folder (other parameters) is refused, and left as it was.
  r = detect({dir_ + "/seq", out, "--labelled-clouds", "--point-labels", "--resume",
              "--decision.speed", "2.5"},
             dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("different run"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(out + "/tracks.csv"), partial);

  r = detect({dir_ + "/seq", out, "--labelled-clouds", "--resume"}, dir_);
  EXPECT_NE(r.exit_code, 0) << "resumed without the --point-labels of the interrupted run";
  EXPECT_NE(r.err.find("different run"), std::string::npos) << r.err;
  r = detect({dir_ + "/seq", out, "--labelled-clouds", "--point-labels", "--resume"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(readFile(out + "/tracks.csv"), reference_);
  expectSameLabelled(out);
  for (const char* name : {"000000.label", "000011.label", "000012.label", "000029.label"})
    EXPECT_EQ(readFile(out + "/labels/" + name), readFile(dir_ + "/ref/labels/" + name)) << name;
  const std::string done = readFile(out + "/summary.json");
  EXPECT_NE(done.find("\"interrupted\": false"), std::string::npos) << done;
  EXPECT_EQ(jsonNumber(done, "resumed_from_frame"), 12) << done;
  // A finished run has nothing to resume.
  r = detect({dir_ + "/seq", out, "--labelled-clouds", "--point-labels", "--resume"}, dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("finished"), std::string::npos) << r.err;
}

// --resume refuses rows on disk that the run does not give (the input changed, a file was edited).
TEST_F(DetectTool, ResumeRefusesRowsItDoesNotReproduce) {
  const std::string out = dir_ + "/edited";
  ToolRun r = detect({dir_ + "/seq", out, "--stop-after-frames", "10"}, dir_);
  ASSERT_EQ(r.exit_code, 130) << r.err;
  std::string tracks = readFile(out + "/tracks.csv");
  const std::size_t comma = tracks.find(',', tracks.find('\n') + 1);  // first row's time
  ASSERT_NE(comma, std::string::npos);
  tracks.insert(comma + 1, "9");
  writeFile(out + "/tracks.csv", tracks);
  r = detect({dir_ + "/seq", out, "--resume"}, dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("tracks.csv"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(out + "/tracks.csv"), tracks) << "a failed resume changed tracks.csv";
}

// Real signals, sent while the tool runs: it finishes its current frame, keeps every complete
// frame and exits with 128 + the signal; SIGINT's folder is then resumed to the reference.
TEST_F(DetectTool, SigintAndSigtermLeaveCompleteFramesAndResume) {
  for (const int sig : {SIGTERM, SIGINT}) {
    SCOPED_TRACE(sig == SIGINT ? "SIGINT" : "SIGTERM");
    const std::string out = dir_ + (sig == SIGINT ? "/sigint" : "/sigterm");
    const std::string err = dir_ + "/signal_stderr.txt";
    // The reference's options: its labelled/run_key.txt is compared too.
    const pid_t pid = start({dir_ + "/seq", out, "--labelled-clouds", "--point-labels"}, err);
    // As soon as the first frame is written (30 frames to go: the run cannot be over yet).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline && !fs::exists(out + "/labelled/000000.pcd"))
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    kill(pid, sig);
    const ToolRun r = finish(pid, err);
    ASSERT_EQ(r.exit_code, 128 + sig) << r.err;
    const std::string summary = readFile(out + "/summary.json");
    EXPECT_NE(summary.find("\"interrupted\": true"), std::string::npos) << summary;
    const long done = jsonNumber(summary, "frames_done");
    EXPECT_GE(done, 1);
    EXPECT_LT(done, 30);
    EXPECT_EQ(rowsBefore(readFile(out + "/tracks.csv"), 1000), rowsBefore(reference_, done));
    if (sig != SIGINT) continue;
    const ToolRun resumed =
        detect({dir_ + "/seq", out, "--labelled-clouds", "--point-labels", "--resume"}, dir_);
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    EXPECT_EQ(readFile(out + "/tracks.csv"), reference_);
    expectSameLabelled(out);
  }
}

// Blind frames (no return at all: an all-NaN organized scan, a PCD with no point) are warned
// about, listed in summary.json, and the run goes on; a truncated frame is an error naming it,
// unless --skip-bad-frames, which warns, counts it and treats it as blind.
TEST_F(DetectTool, BlindAndBadFrames) {
  const std::string seq = dir_ + "/seq_blind";
  fs::create_directories(seq);
  fs::copy(dir_ + "/seq/frames", seq + "/frames");
  fs::copy_file(dir_ + "/seq/poses.txt", seq + "/poses.txt");
  fs::copy_file(dir_ + "/seq/times.txt", seq + "/times.txt");
  const std::string header =
      "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n";
  std::string nan_frame =
      header + "WIDTH 4\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 8\n" + "DATA ascii\n";
  for (int k = 0; k < 8; ++k) nan_frame += "nan nan nan 0\n";
  writeFile(seq + "/frames/000010.pcd", nan_frame);
  writeFile(seq + "/frames/000011.pcd",
            header + "WIDTH 0\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA ascii\n");
  const std::string frame14 = readFile(seq + "/frames/000014.pcd");
  writeFile(seq + "/frames/000014.pcd", frame14.substr(0, frame14.size() / 2));

  ToolRun r = detect({seq, dir_ + "/blind_strict"}, dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("000014.pcd"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ + "/blind_strict")) << "a failed run left its output";

  r = detect({seq, dir_ + "/blind", "--skip-bad-frames", "--point-labels"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Point labels of blind and bad frames: all 0, as many as the input's points (a bad frame's
  // header count), none for a frame without points.
  pcl::PCLPointCloud2 full;
  ASSERT_EQ(pcl::io::loadPCDFile(dir_ + "/seq/frames/000014.pcd", full), 0);
  for (const auto& [name, points] : std::vector<std::pair<std::string, std::size_t>>{
           {"000010", 8}, {"000011", 0}, {"000014", std::size_t(full.width) * full.height}}) {
    const std::string labels = readFile(dir_ + "/blind/labels/" + name + ".label");
    EXPECT_EQ(labels.size(), 4 * points) << name;
    EXPECT_EQ(labels, std::string(4 * points, '\0')) << name << ": not all 0";
  }
  EXPECT_NE(readFile(dir_ + "/blind/labels/000015.label"),
            std::string(4 * std::size_t(full.width) * full.height, '\0'));
  for (const char* name : {"000010.pcd", "000011.pcd", "000014.pcd"})
    EXPECT_NE(r.err.find(name), std::string::npos) << "no warning naming " << name << ":\n"
                                                   << r.err;
  const std::string summary = readFile(dir_ + "/blind/summary.json");
  EXPECT_NE(summary.find("\"blind_frames\": [10, 11]"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"bad_frames\": [14]"), std::string::npos) << summary;
  EXPECT_EQ(jsonNumber(summary, "blind_frame_count"), 2);
  EXPECT_EQ(jsonNumber(summary, "bad_frame_count"), 1);
  const std::string tracks = readFile(dir_ + "/blind/tracks.csv");
  // Untouched before the gap; rows after it.
  EXPECT_EQ(rowsBefore(tracks, 10), rowsBefore(reference_, 10));
  EXPECT_GT(tracks.size(), rowsBefore(tracks, 15).size() + 100);
  for (const char* frame : {"\n10,", "\n11,", "\n14,"})
    EXPECT_EQ(tracks.find(frame), std::string::npos) << "a row in blind frame" << frame;
}

// ------------------------------------------------------------------ outputs that line up (#29)
namespace {

/** The first `n` frames of the fixture's sequence as a flat folder of PCDs numbered from `first`,
 * unorganized, with fields x y z intensity ring (uint16) time (float), a NaN point first; poses in
 * `poses_out` (not in the folder), times.txt in it. */
void writeNumberedSequence(const std::string& src, const std::string& seq, int first, int n,
                           const std::string& poses_out) {
  fs::create_directories(seq);
  std::istringstream poses(readFile(src + "/poses.txt")), times(readFile(src + "/times.txt"));
  std::string poses_text, times_text, line;
  for (int k = 0; k < n && std::getline(poses, line); ++k) poses_text += line + "\n";
  for (int k = 0; k < n && std::getline(times, line); ++k) times_text += line + "\n";
  writeFile(poses_out, poses_text);
  writeFile(seq + "/times.txt", times_text);
  for (int k = 0; k < n; ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "/frames/%06d.pcd", k);
    pcl::PointCloud<pcl::PointXYZI> in;
    ASSERT_EQ(pcl::io::loadPCDFile(src + name, in), 0) << name;
    pcl::PCLPointCloud2 blob;
    const char* names[6] = {"x", "y", "z", "intensity", "ring", "time"};
    const std::uint8_t types[6] = {7, 7, 7, 7, pcl::PCLPointField::UINT16, 7};
    const std::uint32_t offsets[6] = {0, 4, 8, 12, 16, 20};
    for (int f = 0; f < 6; ++f) {
      pcl::PCLPointField field;
      field.name = names[f];
      field.offset = offsets[f];
      field.datatype = types[f];
      field.count = 1;
      blob.fields.push_back(field);
    }
    blob.point_step = 24;
    blob.height = 1;
    blob.width = static_cast<std::uint32_t>(in.size() + 1);
    blob.row_step = blob.point_step * blob.width;
    blob.is_dense = false;
    blob.data.assign(blob.width * blob.point_step, 0);
    for (std::size_t j = 0; j <= in.size(); ++j) {
      const float nan = std::numeric_limits<float>::quiet_NaN();
      const float v[4] = {j ? in[j - 1].x : nan, j ? in[j - 1].y : nan, j ? in[j - 1].z : nan,
                          j ? in[j - 1].intensity : 0.f};
      const std::uint16_t ring = static_cast<std::uint16_t>(j % 16);
      const float time = 1e-6f * static_cast<float>(j);
      std::uint8_t* d = &blob.data[j * blob.point_step];
      std::memcpy(d, v, 16);
      std::memcpy(d + 16, &ring, 2);
      std::memcpy(d + 20, &time, 4);
    }
    std::snprintf(name, sizeof(name), "/%06d.pcd", first + k);
    ASSERT_EQ(pcl::PCDWriter().writeBinary(seq + name, blob), 0);
  }
}

/** Byte offset of field `name` in `blob`, or -1. */
int fieldOffset(const pcl::PCLPointCloud2& blob, const std::string& name) {
  for (const auto& f : blob.fields)
    if (f.name == name) return static_cast<int>(f.offset);
  return -1;
}

/** Parsed tracks.json through python3's json module: "frame file time [mover ids] [all ids]" a
 * line, or "" when python3 is missing. */
std::string tracksJsonSummary(const std::string& path) {
  const std::string cmd =
      "python3 -c 'import json,sys\n"
      "for f in json.load(open(sys.argv[1])):\n"
      "  print(f[\"frame\"], f[\"file\"], \"%.3f\" % f[\"time\"], sorted(m[\"track_id\"] for m in "
      "f[\"movers\"]), sorted(f[\"track_ids\"]), all(len(m[\"center\"]) == 3 and "
      "len(m[\"size\"]) == 3 and len(m[\"velocity\"]) == 2 and 0 <= m[\"similarity\"] <= 1 "
      "for m in f[\"movers\"]))' " +
      path + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return "";
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof(buf), pipe)) out.append(buf, n);
  return pclose(pipe) == 0 ? out : "python3 failed: " + out;
}

/** The same summary from tracks.csv rows, for frames 0..frames-1. */
std::string tracksCsvSummary(const std::string& csv, int frames, int first_file) {
  std::map<int, std::vector<int>> movers, ids;
  std::map<int, std::string> times;
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) c.push_back(cell);
    const int frame = std::stoi(c[0]);
    times[frame] = c[2];
    ids[frame].push_back(std::stoi(c[3]));
    if (c[4] == "1") movers[frame].push_back(std::stoi(c[3]));
  }
  auto list = [](std::vector<int> v) {
    std::sort(v.begin(), v.end());
    std::string s = "[";
    for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + std::to_string(v[k]);
    return s + "]";
  };
  std::string out;
  for (int f = 0; f < frames; ++f)
    out += std::to_string(f) + " " + std::to_string(first_file + f) + " " +
           (times.count(f) ? times[f] : "?") + " " + list(movers[f]) + " " + list(ids[f]) +
           " True\n";
  return out;
}

}  // namespace

// Files 000040..49: tracks.csv says frame 0-9 and file 40-49, labelled clouds are 000040..49.pcd
// with every input point (a NaN one too) in the input's order and fields, tracks.json agrees.
TEST_F(DetectTool, FileNumbersPerPointAlignmentAndTracksJson) {
  const std::string seq = dir_ + "/seq40", out = dir_ + "/out40";
  writeNumberedSequence(dir_ + "/seq", seq, 40, 10, dir_ + "/poses40.txt");
  ToolRun r = detect({seq, out, "--labelled-clouds", "--poses", dir_ + "/poses40.txt"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const std::string csv = readFile(out + "/tracks.csv");
  ASSERT_EQ(csv.rfind("frame,file,time,track_id,", 0), 0u) << csv.substr(0, 80);
  std::istringstream rows(csv);
  std::string line;
  std::getline(rows, line);
  std::map<int, std::map<int, bool>> tracks_of_frame;  // frame -> track id -> mover
  while (std::getline(rows, line)) {
    int frame = -1, track = -1, mover = -1;
    long long file = -1;
    double time = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%lld,%lf,%d,%d", &frame, &file, &time, &track, &mover),
              5)
        << line;
    EXPECT_EQ(file, frame + 40) << line;
    tracks_of_frame[frame][track] = mover == 1;
  }
  ASSERT_FALSE(tracks_of_frame.empty());

  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(out + "/labelled"))
    if (e.path().extension() == ".pcd") names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  ASSERT_EQ(names.size(), 10u);
  // The run that wrote them, for pcl_movers_viewer's check: summary.json's run_key.
  std::string stamp = readFile(out + "/labelled/run_key.txt");
  ASSERT_FALSE(stamp.empty());
  stamp.pop_back();
  EXPECT_NE(readFile(out + "/summary.json").find("\"run_key\": \"" + stamp + "\""),
            std::string::npos);
  EXPECT_EQ(names.front(), "000040.pcd");
  EXPECT_EQ(names.back(), "000049.pcd");

  std::size_t movers = 0;
  for (int k = 0; k < 10; ++k) {
    pcl::PCLPointCloud2 in, lab;
    const std::string name = names[k];
    ASSERT_EQ(pcl::io::loadPCDFile(seq + "/" + name, in), 0);
    ASSERT_EQ(pcl::io::loadPCDFile(out + "/labelled/" + name, lab), 0);
    ASSERT_EQ(lab.width * lab.height, in.width * in.height) << name;
    for (const char* f : {"x", "y", "z", "intensity", "ring", "time", "label", "track"})
      ASSERT_GE(fieldOffset(lab, f), 0) << name << " has no field " << f;
    const int label_at = fieldOffset(lab, "label"), track_at = fieldOffset(lab, "track");
    for (std::size_t j = 0; j < in.width; ++j) {
      const std::uint8_t* a = &in.data[j * in.point_step];
      const std::uint8_t* b = &lab.data[j * lab.point_step];
      for (const char* f : {"x", "y", "z", "intensity", "ring", "time"})
        ASSERT_EQ(std::memcmp(a + fieldOffset(in, f), b + fieldOffset(lab, f), 4), 0)
            << name << " point " << j << " field " << f;
      std::uint32_t label = 0;
      std::int32_t track = 0;
      std::memcpy(&label, b + label_at, 4);
      std::memcpy(&track, b + track_at, 4);
      ASSERT_LE(label, 3u);
      if (j == 0) EXPECT_EQ(label, 0u) << "the NaN point is unlabelled";
      if (track >= 0) {
        ASSERT_TRUE(tracks_of_frame[k].count(track)) << name << ": track " << track;
        EXPECT_EQ(label == 3u, tracks_of_frame[k][track]) << name << ": track " << track;
      }
      movers += label == 3u;
    }
  }
  EXPECT_GT(movers, 0u) << "no mover point in any labelled cloud";

  const std::string json = tracksJsonSummary(out + "/tracks.json");
  if (json.empty()) GTEST_SKIP() << "python3 is missing: tracks.json not parsed";
  EXPECT_EQ(json, tracksCsvSummary(csv, 10, 40));

  // --resume after an interruption ends with the same tracks.csv, tracks.json and clouds.
  r = detect({seq, out + "_int", "--labelled-clouds", "--poses", dir_ + "/poses40.txt",
              "--stop-after-frames", "4"},
             dir_);
  ASSERT_EQ(r.exit_code, 130) << r.err;
  r = detect({seq, out + "_int", "--labelled-clouds", "--poses", dir_ + "/poses40.txt", "--resume"},
             dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(readFile(out + "_int/tracks.csv"), csv);
  EXPECT_EQ(readFile(out + "_int/tracks.json"), readFile(out + "/tracks.json"));
  EXPECT_EQ(readFile(out + "_int/labelled/000047.pcd"), readFile(out + "/labelled/000047.pcd"));
}

// --overwrite removes what the tool wrote (labelled clouds of the earlier, longer run included)
// and nothing else; a bad poses.txt does not stop --estimate-poses; a file for SEQ is named.
TEST_F(DetectTool, OverwriteClearsOnlyItsOwnOutputs) {
  const std::string seq = dir_ + "/seq_ow", out = dir_ + "/out_ow";
  writeNumberedSequence(dir_ + "/seq", seq, 0, 8, seq + "/poses.txt");
  ToolRun r = detect({seq, out, "--labelled-clouds", "--point-labels"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(out + "/labelled/000007.pcd"));
  ASSERT_TRUE(fs::exists(out + "/labels/000007.label"));
  writeFile(out + "/notes.txt", "mine\n");
  writeFile(out + "/labelled/readme.txt", "mine too\n");
  writeFile(out + "/labels/readme.txt", "mine as well\n");

  fs::remove(seq + "/000007.pcd");
  fs::remove(seq + "/000006.pcd");
  writeFile(seq + "/poses.txt", "not a pose\n");
  writeFile(seq + "/times.txt", "0\n0.1\n0.2\n0.3\n0.4\n0.5\n");
  r = detect({seq, out, "--estimate-poses"}, dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--overwrite"), std::string::npos) << r.err;
  r = detect({seq, out, "--estimate-poses", "--overwrite"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(readFile(out + "/notes.txt"), "mine\n");
  EXPECT_EQ(readFile(out + "/labelled/readme.txt"), "mine too\n");
  EXPECT_FALSE(fs::exists(out + "/labelled/000000.pcd")) << "an earlier run's cloud is left";
  EXPECT_FALSE(fs::exists(out + "/labelled/000007.pcd")) << "an earlier run's cloud is left";
  EXPECT_EQ(readFile(out + "/labels/readme.txt"), "mine as well\n");
  EXPECT_FALSE(fs::exists(out + "/labels/000000.label")) << "an earlier run's labels are left";
  EXPECT_FALSE(fs::exists(out + "/labels/000007.label")) << "an earlier run's labels are left";
  EXPECT_NE(readFile(out + "/summary.json").find("\"pose_source\": \"estimated\""),
            std::string::npos);
  EXPECT_EQ(rowsBefore(readFile(out + "/tracks.csv"), 100),
            rowsBefore(readFile(out + "/tracks.csv"), 6));

  r = detect({seq + "/000001.pcd", dir_ + "/out_file"}, dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(seq + "/000001.pcd"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("sequence folder"), std::string::npos) << r.err;
}

// ------------------------------------------------------------------ per-point moving labels (#26)
namespace {

std::string evalToolPath() {
  return PCL_MOVERS_BINARY_DIR "/apps/pcl_movers_eval";
}

/** pcl_movers_eval with `args`; its stdout in `out`. */
ToolRun evalTool(const std::vector<std::string>& args, const std::string& dir, std::string& out) {
  const std::string err = dir + "/eval_stderr.txt", stdout_path = dir + "/eval_stdout.txt";
  const ToolRun r = finish(startTool(evalToolPath(), args, err, stdout_path), err);
  out = readFile(stdout_path);
  return r;
}

/** The rows of tracks.csv by frame and track id. */
std::map<int, std::map<int, pcl_movers::io::TrackRow>> rowsByFrame(const std::string& path) {
  std::map<int, std::map<int, pcl_movers::io::TrackRow>> rows;
  for (const auto& r : pcl_movers::io::readTracks(path)) rows[r.frame][r.track_id] = r;
  return rows;
}

/** Checks frame `frame`'s point labels against its labelled cloud (same run) point by point: a
 * mover point (label 3) has the moving class of its track's box and the track id; any other
 * return 9; a point without a return (non-finite, or at range 0) 0. Counts mover points and
 * returns the labelled cloud left unlabelled (0: not kept by the range image or in no tracked
 * cluster). */
void checkPointLabels(const std::string& labels_path, const std::string& labelled_path,
                      const std::map<int, pcl_movers::io::TrackRow>& rows, std::size_t& movers,
                      std::size_t& unlabelled_returns) {
  const auto labels = pcl_movers::io::readLabels(labels_path);
  pcl::PCLPointCloud2 lab;
  ASSERT_EQ(pcl::io::loadPCDFile(labelled_path, lab), 0);
  ASSERT_EQ(labels.size(), std::size_t(lab.width) * lab.height) << labels_path;
  const int x_at = fieldOffset(lab, "x"), label_at = fieldOffset(lab, "label"),
            track_at = fieldOffset(lab, "track");
  for (std::size_t j = 0; j < labels.size(); ++j) {
    const std::uint8_t* d = &lab.data[j * lab.point_step];
    float xyz[3];
    std::uint32_t label = 0;
    std::int32_t track = 0;
    std::memcpy(xyz, d + x_at, 12);
    std::memcpy(&label, d + label_at, 4);
    std::memcpy(&track, d + track_at, 4);
    const bool has_return = std::isfinite(xyz[0]) && std::isfinite(xyz[1]) &&
                            std::isfinite(xyz[2]) && (xyz[0] || xyz[1] || xyz[2]);
    const std::uint16_t cls = pcl_movers::io::labelClass(labels[j]);
    const std::uint16_t instance = pcl_movers::io::labelInstance(labels[j]);
    if (!has_return) {
      ASSERT_EQ(labels[j], 0u) << labels_path << " point " << j << ": no return";
    } else if (label == 3) {
      ASSERT_TRUE(rows.count(track)) << labels_path << " point " << j << ": track " << track;
      const auto& row = rows.at(track);
      ASSERT_TRUE(row.mover);
      ASSERT_EQ(cls, pcl_movers::io::moverClassFromBox(row.length, row.width, row.height))
          << labels_path << " point " << j;
      ASSERT_EQ(instance, std::uint16_t(track)) << labels_path << " point " << j;
      ++movers;
    } else {
      ASSERT_EQ(labels[j], 9u) << labels_path << " point " << j << ": label " << label;
      unlabelled_returns += label == 0;
    }
  }
}

}  // namespace

// Organized input (the simulator's, as its labels/ is): OUT/labels/NAME.label has a label per cell
// in row-major order, 0 exactly where the simulator has none (no return); mover points carry their
// class and track; pcl_movers_eval --mos scores them, and names a mismatched or missing file.
TEST_F(DetectTool, PointLabelsOrganizedAndMosEval) {
  const auto rows = rowsByFrame(dir_ + "/ref/tracks.csv");
  std::size_t movers = 0, unlabelled = 0;
  for (int k = 0; k < 30; ++k) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d", k);
    const auto truth = pcl_movers::io::readLabels(dir_ + "/seq/labels/" + name + ".label");
    const auto labels = pcl_movers::io::readLabels(dir_ + "/ref/labels/" + name + ".label");
    ASSERT_EQ(labels.size(), truth.size()) << name;
    for (std::size_t j = 0; j < truth.size(); ++j)
      ASSERT_EQ(labels[j] == 0, truth[j] == 0) << name << " point " << j;
    const auto it = rows.find(k);
    checkPointLabels(dir_ + "/ref/labels/" + name + ".label",
                     dir_ + "/ref/labelled/" + name + ".pcd",
                     it == rows.end() ? std::map<int, pcl_movers::io::TrackRow>() : it->second,
                     movers, unlabelled);
  }
  EXPECT_GT(movers, 200u) << "too few mover points";

  if (!fs::exists(evalToolPath())) GTEST_SKIP() << evalToolPath() << " is not built";
  std::string out;
  ToolRun r = evalTool({"--mos", dir_ + "/seq", dir_ + "/ref"}, dir_, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(out.find("| moving | "), std::string::npos) << out;
  EXPECT_NE(out.find("30 frames"), std::string::npos) << out;
  // The moving car and the walking person are found in part at least.
  EXPECT_EQ(out.find("| moving | 0.0 |"), std::string::npos) << out;

  const std::string pred = dir_ + "/mos_pred";
  fs::copy(dir_ + "/ref/labels", pred);
  const std::string third = readFile(pred + "/000003.label");
  writeFile(pred + "/000003.label", third.substr(0, third.size() - 4));
  r = evalTool({"--mos", dir_ + "/seq/labels", pred}, dir_, out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(pred + "/000003.label"), std::string::npos) << r.err;
  fs::remove(pred + "/000003.label");
  r = evalTool({"--mos", dir_ + "/seq/labels", pred}, dir_, out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(pred + "/000003.label"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("missing"), std::string::npos) << r.err;
}

// Unorganized input with a NaN point, a point at range 0, one very near and duplicated points
// (twice in one range-image cell: the range image keeps one): a label per input point in the
// input's order; the points the range image did not keep are 9 (return) or 0 (none).
TEST_F(DetectTool, PointLabelsUnorganized) {
  const std::string seq = dir_ + "/seq_unorg", out = dir_ + "/out_unorg";
  fs::create_directories(seq);
  std::istringstream poses(readFile(dir_ + "/seq/poses.txt")),
      times(readFile(dir_ + "/seq/times.txt"));
  std::string poses_text, times_text, line;
  for (int k = 0; k < 10 && std::getline(poses, line); ++k) poses_text += line + "\n";
  for (int k = 0; k < 10 && std::getline(times, line); ++k) times_text += line + "\n";
  writeFile(seq + "/poses.txt", poses_text);
  writeFile(seq + "/times.txt", times_text);
  std::vector<std::size_t> sizes;
  for (int k = 0; k < 10; ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.pcd", k);
    pcl::PointCloud<pcl::PointXYZI> in, cloud;
    ASSERT_EQ(pcl::io::loadPCDFile(dir_ + "/seq/frames/" + name, in), 0);
    pcl::PointXYZI p;
    p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
    p.intensity = 0;
    cloud.push_back(p);  // 0: no return
    p.x = p.y = p.z = 0;
    cloud.push_back(p);  // 1: range 0, no return
    p.x = 0.3f, p.y = 0.1f, p.z = 0.05f;
    cloud.push_back(p);  // 2: a return nearer than the range image keeps
    std::size_t finite = 0;
    for (const auto& q : in) {
      if (!std::isfinite(q.x)) continue;
      cloud.push_back(q);
      if (++finite % 5 == 0) {  // its twin, 2 cm further along the same ray
        pcl::PointXYZI t = q;
        const float s = 1.f + 0.02f / std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
        t.x *= s, t.y *= s, t.z *= s;
        cloud.push_back(t);
      }
    }
    cloud.width = static_cast<std::uint32_t>(cloud.size());
    cloud.height = 1;
    cloud.is_dense = false;
    sizes.push_back(cloud.size());
    ASSERT_EQ(pcl::io::savePCDFileBinary(seq + "/" + name, cloud), 0);
  }
  const ToolRun r =
      detect({seq, out, "--labelled-clouds", "--point-labels", "--sensor", "vlp16"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = rowsByFrame(out + "/tracks.csv");
  std::size_t movers = 0, unlabelled = 0;
  for (int k = 0; k < 10; ++k) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d", k);
    const auto labels = pcl_movers::io::readLabels(out + "/labels/" + name + ".label");
    ASSERT_EQ(labels.size(), sizes[k]) << name;
    EXPECT_EQ(labels[0], 0u) << name;
    EXPECT_EQ(labels[1], 0u) << name;
    EXPECT_EQ(labels[2], 9u) << name;
    const auto it = rows.find(k);
    checkPointLabels(out + "/labels/" + name + ".label", out + "/labelled/" + name + ".pcd",
                     it == rows.end() ? std::map<int, pcl_movers::io::TrackRow>() : it->second,
                     movers, unlabelled);
  }
  EXPECT_GT(movers, 50u) << "too few mover points";
  EXPECT_GT(unlabelled, 10u * sizes[0] / 12) << "the twins the range image dropped are not 9";
}
