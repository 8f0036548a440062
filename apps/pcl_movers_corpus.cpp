/*
 * pcl_movers_corpus OUT — the scene corpus: generates (or reuses) the scenes of a split, runs
 * pcl_movers_detect on each in every tracker mode, in parallel, scores them and writes a Markdown
 * report by family, sensor, class and speed band.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/corpus_report.h>
#include <pcl_movers/eval/mos_metrics.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/tracks.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scene_families.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>

#include "tool_utils.h"

extern char** environ;

namespace fs = std::filesystem;
using pcl_movers::InputError;
using pcl_movers::eval::CorpusRun;

namespace {

/** Command-line options. Defaults live here only; the help text is generated from them. */
struct Options {
  std::string split = "check";  ///< tune, check or all
  int seeds = 12;               ///< seeds 1..N per family (odd: tune, even: check)
  std::string families;         ///< comma-separated; "" = every family
  int frames = pcl_movers::sim::SceneOptions().frames;
  std::string modes = "registration,centroid";
  int jobs = 0;             ///< 0 = every core
  std::string detect;       ///< "" = pcl_movers_detect beside this tool
  std::string detect_args;  ///< extra arguments for every pcl_movers_detect run
  std::string report;       ///< "" = OUT/report-<split>.md
  std::string title;        ///< "" = "Scene corpus, <split> split"
};

pcl_movers::tools::OptionTable optionTable() {
  const Options d;
  const int scenes = d.seeds * int(pcl_movers::sim::sceneFamilies().size());
  return pcl_movers::tools::OptionTable(
      {{"--split", "NAME", "tune, check or all", d.split},
       {"--seeds", "N", "seeds per family, 1..N",
        std::to_string(d.seeds) + ": " + std::to_string(scenes) + " scenes in all"},
       {"--families", "A,B", "only these families", "all"},
       {"--frames", "N", "frames per scene", std::to_string(d.frames)},
       {"--modes", "A,B", "tracker modes, --mode of pcl_movers_detect", d.modes},
       {"--jobs", "N", "scenes in parallel", "the number of cores"},
       {"--detect", "PATH", "the pcl_movers_detect to run", "the one beside this tool"},
       {"--detect-args", "\"..\"", "extra arguments for every detection, e.g. \"--config my.cfg\""},
       {"--report", "FILE", "the report's path", "OUT/report-SPLIT.md"},
       {"--title", "TEXT",
        "the report's heading; with --split all the check split's report\ncomes first",
        "\"Scene corpus, SPLIT split\""}});
}

void printHelp(const char* name) {
  std::string families;
  for (const auto& f : pcl_movers::sim::sceneFamilies())
    families += (families.empty() ? "" : ", ") + f;
  std::printf(
      "Usage: %s OUT [options]\n\n"
      "Evaluates mover detection on the scene corpus: the simulator's scene families (%s)\n"
      "with seeds 1..N each. Odd seeds are the tune split, even seeds the check split: choose\n"
      "parameters on tune, report check, never tune on it. Seeds 2k-1 and 2k share the sensor\n"
      "hdl64, hdl32, vlp16, os1_64 or ladar2d (k mod 5), so both splits hold every sensor.\n\n"
      "Writes into OUT (created; reused by later runs):\n"
      "  scenes/FAMILY-SEED/        the sequences with ground truth (simulated once; again when\n"
      "                             the scene's scenario, its sensor's layout or the simulator's\n"
      "                             output version changes; delete them after changing the\n"
      "                             simulator without raising that version)\n"
      "  runs/MODE/FAMILY-SEED/     pcl_movers_detect's output with --point-labels (replaced on\n"
      "                             every run); labels/ scored against the scene's labels/ as\n"
      "                             SemanticKITTI-MOS: the moving-point IoU\n"
      "  report-SPLIT.md            the report: overall, by family, sensor, class, speed band,\n"
      "                             the worst targets and why they were missed\n"
      "  results-SPLIT.jsonl        one line per run with every target's scores\n\n"
      "Options (-h, --help: this help):\n%s",
      name, families.c_str(), optionTable().help().c_str());
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) items.push_back(item);
  return items;
}

/** Whitespace-separated words (no quoting: detect's options take no spaces). */
std::vector<std::string> words(const std::string& text) {
  std::vector<std::string> w;
  std::istringstream in(text);
  for (std::string s; in >> s;) w.push_back(s);
  return w;
}

int parseCount(const std::string& flag, const std::string& text, int lo, int hi) {
  const double v = pcl_movers::tools::parseNumber(flag, text);
  if (v != std::floor(v) || v < lo || v > hi)
    throw InputError(flag + ": expected an integer in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "], got '" + text + "'");
  return int(v);
}

Options parseOptions(const pcl_movers::tools::Arguments& args) {
  Options opt;
  std::string v;
  if (args.get("--split", opt.split) && opt.split != "tune" && opt.split != "check" &&
      opt.split != "all")
    throw InputError("--split: expected tune, check or all, got '" + opt.split + "'");
  if (args.get("--seeds", v)) opt.seeds = parseCount("--seeds", v, 1, 100000);
  if (args.get("--frames", v)) opt.frames = parseCount("--frames", v, 1, 1000000);
  if (args.get("--jobs", v)) opt.jobs = parseCount("--jobs", v, 1, 1024);
  args.get("--families", opt.families);
  args.get("--modes", opt.modes);
  args.get("--detect", opt.detect);
  args.get("--detect-args", opt.detect_args);
  args.get("--report", opt.report);
  args.get("--title", opt.title);
  for (const auto& f : splitList(opt.families)) pcl_movers::sim::generateScene(f, 1, {1, 10.0});
  for (const auto& m : splitList(opt.modes))
    if (m != "registration" && m != "centroid")
      throw InputError("--modes: unknown mode '" + m + "' (registration, centroid)");
  if (splitList(opt.modes).empty()) throw InputError("--modes: no mode given");
  return opt;
}

struct Scene {
  std::string family;
  std::uint64_t seed = 0;
  std::string name() const { return family + "-" + std::to_string(seed); }
};

std::vector<Scene> scenesOf(const Options& opt) {
  const auto families =
      opt.families.empty() ? pcl_movers::sim::sceneFamilies() : splitList(opt.families);
  std::vector<Scene> scenes;
  for (int seed = 1; seed <= opt.seeds; ++seed)
    for (const auto& f : families) {
      const std::string split = pcl_movers::sim::splitName(pcl_movers::sim::splitOf(seed));
      if (opt.split == "all" || opt.split == split) scenes.push_back({f, std::uint64_t(seed)});
    }
  return scenes;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/** What a cached scene was made from: its scenario file, the beam layout of its sensor (a
 * changed preset makes the scene stale although its scenario file is the same) and the simulator's
 * output version (sim::kSimulatorOutputVersion: e.g. a change of the labels). */
std::string sceneStamp(const pcl_movers::sim::Scenario& scenario) {
  const pcl_movers::SensorModel sensor = pcl_movers::SensorModel::fromName(scenario.sensor.preset);
  std::ostringstream stamp;
  stamp << pcl_movers::sim::toYaml(scenario)
        << "# simulator output version: " << pcl_movers::sim::kSimulatorOutputVersion << "\n"
        << "# sensor layout: " << sensor.rows() << " x " << sensor.columns() << ", elevations";
  stamp.precision(9);
  for (float e : sensor.elevations()) stamp << " " << e;
  stamp << "\n";
  return stamp.str();
}

/** Simulates the scene unless OUT/scenes holds it with the same stamp. Returns the seconds spent
 * simulating (0 when reused). */
double ensureScene(const pcl_movers::sim::Scenario& scenario, const fs::path& folder) {
  const std::string stamp = sceneStamp(scenario);
  const fs::path stamp_file = folder / "corpus_stamp.txt";
  if (fs::exists(folder / "objects.txt") && readFile(stamp_file) == stamp) return 0;
  const auto start = std::chrono::steady_clock::now();
  pcl_movers::sim::LidarSimulator simulator(scenario);
  pcl_movers::sim::writeSequence(simulator, folder.string(), true);
  std::ofstream(stamp_file) << stamp;  // last: a scene without it is simulated again
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/** Runs a program with stdout and stderr to `log`; returns its exit status (-1: not started,
 * 128 + n: killed by signal n). */
int runProgram(const std::vector<std::string>& args, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

/** The error line of a failed run's log (else its last line), for the failed-runs table. */
std::string errorLine(const fs::path& log) {
  std::istringstream in(readFile(log));
  std::string last, error;
  for (std::string line; std::getline(in, line);) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    last = line;
    if (line.find("error") != std::string::npos) error = line;
  }
  std::string shown = error.empty() ? last : error;
  std::replace(shown.begin(), shown.end(), '|', '/');
  return shown.empty() ? "no output" : shown.substr(0, 160);
}

/** Detects movers in one scene in one mode and scores the result (sector 180°: simulated scenes
 * are labelled all around). A failed run is scored as if it had reported nothing. */
CorpusRun detectAndScore(const Options& opt, const std::string& detect, const Scene& scene,
                         const pcl_movers::sim::Scenario& scenario, const fs::path& seq,
                         const std::string& mode, const fs::path& out) {
  CorpusRun run;
  run.family = scene.family;
  run.seed = scene.seed;
  run.sensor = scenario.sensor.preset;
  run.mode = mode;
  run.frames = scenario.frames;
  run.blind_frames = int(scenario.blind_frames.size());
  std::vector<std::string> args = {detect, seq.string(),  out.string(),    "--track.mode",
                                   mode,   "--overwrite", "--point-labels"};
  for (const auto& w : words(opt.detect_args)) args.push_back(w);
  fs::create_directories(out.parent_path());
  const fs::path log = out.string() + ".log";
  const auto start = std::chrono::steady_clock::now();
  const int status = runProgram(args, log);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.ok = status == 0 && fs::exists(out / "tracks.csv");
  if (!run.ok)
    run.error = status < 0 ? "cannot start " + detect
                           : "exit " + std::to_string(status) + ": " + errorLine(log);
  pcl_movers::eval::DetectionMetricsParams params;
  params.sector_deg = 180;
  params.frames = scenario.frames;
  pcl_movers::io::SequenceReader reader(seq.string());
  const auto objects = pcl_movers::io::readObjects((seq / "objects.txt").string());
  const auto tracks = run.ok ? pcl_movers::io::readTracks((out / "tracks.csv").string())
                             : std::vector<pcl_movers::io::TrackRow>();
  run.score =
      pcl_movers::eval::scoreDetections(objects, tracks, params, reader.poses(), reader.times());
  // Moving-point IoU (SemanticKITTI-MOS); a failed run predicted nothing.
  if (fs::is_directory(seq / "labels")) {
    run.mos = pcl_movers::eval::scoreMosFolders((seq / "labels").string(),
                                                run.ok ? (out / "labels").string() : "")
                  .total;
    run.has_mos = true;
  }
  return run;
}

std::string commandLine(int argc, char** argv) {
  std::string s = fs::path(argv[0]).filename().string();
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    s += " " + (a.find(' ') == std::string::npos ? a : "\"" + a + "\"");
  }
  return s;
}

void writeText(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << text;
    if (!out) throw InputError(path.string() + ": cannot write");
  }
  fs::rename(tmp, path);
}

int run(int argc, char** argv) {
  const auto args = optionTable().parse(argc, argv);
  const auto& positional = args.positional;
  if (positional.size() != 1)
    throw InputError("expected the output folder OUT, got " + std::to_string(positional.size()) +
                     " positional arguments; see -h");
  Options opt = parseOptions(args);
  const fs::path out = positional[0];
  if (fs::exists(out) && !fs::is_directory(out))
    throw InputError(out.string() + ": exists and is not a folder");
  std::string detect = opt.detect;
  if (detect.empty())
    detect = (fs::canonical("/proc/self/exe").parent_path() / "pcl_movers_detect").string();
  if (access(detect.c_str(), X_OK) != 0)
    throw InputError(detect + ": not an executable pcl_movers_detect (see --detect)");
  const fs::path report =
      opt.report.empty() ? out / ("report-" + opt.split + ".md") : fs::path(opt.report);
  const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
  const int jobs = opt.jobs > 0 ? opt.jobs : cores;
  const auto scenes = scenesOf(opt);
  const auto modes = splitList(opt.modes);
  fs::create_directories(out / "scenes");

  // Messages go to stderr: stdout carries the report alone.
  std::fprintf(stderr, "%zu scenes (%s split), %zu mode(s), %d in parallel → %s\n", scenes.size(),
               opt.split.c_str(), modes.size(), jobs, out.string().c_str());
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::vector<CorpusRun>> results(scenes.size());
  std::vector<std::string> errors(scenes.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::atomic<double> generate_seconds{0};
  std::mutex progress_mutex;
  pcl_movers::tools::ProgressBar bar(scenes.size(), "scenes");
  auto worker = [&]() {
    for (std::size_t i = next++; i < scenes.size(); i = next++) {
      try {
        pcl_movers::sim::SceneOptions scene_options;
        scene_options.frames = opt.frames;
        const auto scenario =
            pcl_movers::sim::generateScene(scenes[i].family, scenes[i].seed, scene_options);
        const fs::path seq = out / "scenes" / scenes[i].name();
        const double g = ensureScene(scenario, seq);
        for (double cur = generate_seconds;
             !generate_seconds.compare_exchange_weak(cur, cur + g);) {
        }
        for (const auto& mode : modes)
          results[i].push_back(detectAndScore(opt, detect, scenes[i], scenario, seq, mode,
                                              out / "runs" / mode / scenes[i].name()));
      } catch (const std::exception& e) {
        errors[i] = scenes[i].name() + ": " + e.what();
      }
      std::lock_guard<std::mutex> lock(progress_mutex);
      bar.update(++done);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < jobs; ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  bar.finish();
  for (const auto& e : errors)
    if (!e.empty()) throw InputError(e);

  std::vector<CorpusRun> runs;
  for (const auto& r : results) runs.insert(runs.end(), r.begin(), r.end());
  pcl_movers::eval::CorpusReportOptions ro;
  ro.command = commandLine(argc, argv);
  ro.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ro.generate_seconds = generate_seconds;
  ro.cores = cores;
  // Both halves: the check split first (what is reported), then the tune split, never pooled.
  std::string text;
  for (const std::string split : {"check", "tune"}) {
    if (opt.split != "all" && opt.split != split) continue;
    std::vector<CorpusRun> part;
    for (const CorpusRun& r : runs)
      if (pcl_movers::sim::splitName(pcl_movers::sim::splitOf(r.seed)) == split) part.push_back(r);
    ro.title = opt.title.empty() ? "Scene corpus, " + split + " split" : opt.title + ", " + split;
    text += pcl_movers::eval::formatCorpusReport(part, ro);
  }
  writeText(report, text);
  writeText(out / ("results-" + opt.split + ".jsonl"), pcl_movers::eval::formatCorpusJson(runs));
  std::cout << text << std::flush;
  std::fprintf(stderr, "wrote %s\n", report.string().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  return pcl_movers::tools::runTool("pcl_movers_corpus", [&] { return run(argc, argv); });
}
