/*
 * pcl_movers_detect on real-recording situations (issue #27), run as a user runs it — a separate
 * process on a simulated sequence: blind and malformed frames (--skip-bad-frames), interruption by
 * SIGINT/SIGTERM (tracks.csv keeps every complete frame, summary.json says so, exit 128 + signal)
 * and --resume (byte-identical to an uninterrupted run, labelled clouds included).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

std::string toolPath() {
  return PCL_MOVERS_BINARY_DIR "/apps/pcl_movers_detect";
}

struct ToolRun {
  int exit_code = -1;
  std::string err;
};

/** Starts the tool with `args` (stderr to `err_path`); returns the child's pid. */
pid_t start(const std::vector<std::string>& args, const std::string& err_path) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv{const_cast<char*>("pcl_movers_detect")};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (!freopen(err_path.c_str(), "w", stderr) || !freopen("/dev/null", "w", stdout)) _exit(126);
    execv(toolPath().c_str(), argv.data());
    _exit(127);
  }
  return pid;
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
    const ToolRun r = detect({dir_ + "/seq", dir_ + "/ref", "--labelled-clouds"}, dir_);
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
    EXPECT_EQ(n, 30u);
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
  ToolRun r = detect({dir_ + "/seq", out, "--labelled-clouds", "--stop-after-frames", "12"}, dir_);
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
  r = detect({dir_ + "/seq", out, "--labelled-clouds", "--resume", "--mover_speed", "2.5"}, dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("different run"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(out + "/tracks.csv"), partial);

  r = detect({dir_ + "/seq", out, "--labelled-clouds", "--resume"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(readFile(out + "/tracks.csv"), reference_);
  expectSameLabelled(out);
  const std::string done = readFile(out + "/summary.json");
  EXPECT_NE(done.find("\"interrupted\": false"), std::string::npos) << done;
  EXPECT_EQ(jsonNumber(done, "resumed_from_frame"), 12) << done;
  // A finished run has nothing to resume.
  r = detect({dir_ + "/seq", out, "--labelled-clouds", "--resume"}, dir_);
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
    const pid_t pid = start({dir_ + "/seq", out, "--labelled-clouds"}, err);
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
    const ToolRun resumed = detect({dir_ + "/seq", out, "--labelled-clouds", "--resume"}, dir_);
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

  r = detect({seq, dir_ + "/blind", "--skip-bad-frames"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
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
