/*
 * pcl_movers_eval — scores a tracks.csv against objects.txt with the paper's metrics
 * (DESIGN.md "Metrics"): hit % per target, false alarms per frame, detection delay, RMS velocity
 * error. Prints a Markdown table; optionally a PNG bar chart (like the paper's Figure 8) and JSON.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/detection_metrics.h>
#include <pcl_movers/eval/kitti_dont_care.h>
#include <pcl_movers/eval/mos_metrics.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/tracks.h>

#include <pcl/console/parse.h>
#include <pcl/console/print.h>

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "tool_utils.h"

namespace fs = std::filesystem;
using pcl_movers::InputError;

namespace {

/** KITTI files a --sequence folder may hold; their DontCare regions are then used by default. */
const char* const kSequenceLabels = "labels_kitti_tracking.txt";
const char* const kSequenceCalib = "calib.txt";

struct Options {
  pcl_movers::eval::DetectionMetricsParams metrics;
  std::string dont_care_path;
  std::string calib_path;
  bool no_dont_care = false;
  std::string poses_path;
  std::string times_path;
  std::string sequence;
  std::string png_path;
  std::string json_path;
  std::string title = "HIT % PER TARGET";
  bool overwrite = false;
};

pcl_movers::tools::OptionTable optionTable() {
  using pcl_movers::tools::str;
  const Options d;
  return pcl_movers::tools::OptionTable(
      {{"--sector-deg", "D", "half-width of the scored sector around +x [deg]; 180 = all around",
        str(d.metrics.sector_deg)},
       {"--min-points", "N", "points a target needs to be visible",
        std::to_string(d.metrics.min_points)},
       {"--grow", "M", "growth of the box length and width [m]", str(d.metrics.grow_xy)},
       {"--grow-z", "M", "growth of the box height [m]", str(d.metrics.grow_z)},
       {"--frames", "N",
        "sequence length for false alarms per frame (default: the sequence's\nlength with "
        "--sequence, else the number of distinct frames in\nOBJECTS and TRACKS, which can only "
        "undercount)"},
       {"--sequence", "DIR",
        std::string("sequence folder: its length, poses.txt and times.txt are used, and\nwhen it "
                    "holds ") +
            kSequenceLabels + " and " + kSequenceCalib +
            ", their DontCare\nregions (as --dont-care and --calib; said on stderr)"},
       {"--dont-care",
        "FILE",
        "KITTI tracking label file: a mover row whose centroid projects into a\nDontCare box of "
        "its frame, and lies in no labelled box, is ignored\n(neither hit nor false alarm, as in "
        "KITTI's benchmark); needs --calib",
        "",
        {"--dontcare"}},
       {"--calib", "FILE", "KITTI calib file (P2, R0_rect, Tr_velo_cam) for --dont-care"},
       {"--no-dont-care",
        "",
        "count the rows in DontCare regions as false alarms",
        d.no_dont_care ? "counted" : "ignored when available",
        {"--no-dontcare"}},
       {"--poses", "FILE", "sensor->world poses (KITTI format) for velocity vectors"},
       {"--times", "FILE", "timestamps per frame", "10 Hz"},
       {"--png", "FILE", "write a hit-% per target bar chart"},
       {"--title", "TEXT", "chart title", "\"" + d.title + "\""},
       {"--json", "FILE", "write the scores as JSON"},
       {"--overwrite", "", "replace existing --png/--json files"},
       {"--mos", "", "score per-point labels: GT_LABELS PRED_LABELS instead of OBJECTS TRACKS"}});
}

void printHelp(const char* argv0) {
  const Options d;
  std::printf(
      "Usage: %s OBJECTS TRACKS [options]\n"
      "       %s --mos GT_LABELS PRED_LABELS [--json FILE] [--overwrite]\n"
      "  Scores mover detections (tracks.csv of pcl_movers_detect) against ground truth\n"
      "  (objects.txt) with the metrics of DESIGN.md and prints a Markdown table.\n\n"
      "  A target is a ground-truth track with moving = 1, visible in a frame with >= "
      "--min-points\n"
      "  points and its centre within the scored sector. Hit: a mover row of that frame has its\n"
      "  sensor-frame centroid inside the target's box grown by --grow in length and width.\n"
      "  False alarm: a mover row in the sector inside no target's grown box (rows on parked,\n"
      "  non-moving objects are false alarms). Delay: frames from first visibility to first hit.\n"
      "  Velocity error on hits: with poses, |v_xy(row) - v_xy(ground truth)| where the ground\n"
      "  truth is a line fit of the world box centres over +-%d frames; without poses,\n"
      "  | |v_xy(row)| - speed_mps |.\n"
      "  Extra (not the DESIGN metric, labelled as such): hit %% over only the frames where the\n"
      "  target's speed_mps is >= %g m/s, since a target that stands still is no mover then.\n\n"
      "  --mos: moving-object segmentation scored as SemanticKITTI-MOS does, on SemanticKITTI\n"
      "  .label files (class in the low 16 bits): every GT_LABELS/NAME.label against\n"
      "  PRED_LABELS/NAME.label (pcl_movers_detect --point-labels; a folder holding labels/, e.g.\n"
      "  a sequence or detect's OUT, stands for that labels/). Moving = classes 251-259, static =\n"
      "  every other class; points whose ground-truth class is 0 (unlabeled) or 1 (outlier) are\n"
      "  not scored. Moving IoU = TP / (TP + FP + FN) over all points of all frames (a prediction\n"
      "  of 0 on a scored point is an FN), static IoU likewise; then per-frame counts. A\n"
      "  prediction missing for a ground-truth frame, or with another point count, is an error.\n\n"
      "Options (-h, --help: this help):\n%s",
      argv0, argv0, d.metrics.velocity_half_window, d.metrics.moving_speed,
      optionTable().help().c_str());
}

using pcl_movers::tools::parseNumber;

int parseCount(const std::string& flag, const std::string& text, int min_value) {
  const double v = parseNumber(flag, text);
  if (v != std::floor(v) || v < min_value || v > 1e9)
    throw InputError(flag + ": expected an integer >= " + std::to_string(min_value) + ", got '" +
                     text + "'");
  return static_cast<int>(v);
}

/** Refuses to replace user files silently; checked before any work so nothing is half done. */
void checkOutput(const std::string& path, bool overwrite) {
  if (path.empty()) return;
  if (fs::exists(path) && !overwrite)
    throw InputError(path + ": exists; pass --overwrite to replace it");
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent))
    throw InputError(path + ": folder " + parent.string() + " does not exist");
}

/** Writes via a temporary file and a rename, so an error never leaves a half-written file. */
template <typename Writer>
void writeAtomically(const std::string& path, Writer&& write) {
  const std::string tmp = path + ".tmp-pcl_movers_eval";
  try {
    write(tmp);
    fs::rename(tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

void writeText(const std::string& path, const std::string& text) {
  writeAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp);
    out << text;
    out.close();
    if (!out) throw InputError(path + ": cannot write");
  });
}

void writePng(const std::string& path, const pcl_movers::eval::DetectionScore& score,
              const std::string& title) {
  int w = 0, h = 0;
  std::vector<unsigned char> rgb;
  pcl_movers::eval::drawHitChart(score, title, w, h, rgb);
  vtkNew<vtkImageData> image;
  image->SetDimensions(w, h, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* dst = static_cast<unsigned char*>(image->GetScalarPointer());
  // VTK images start at the bottom row; the chart starts at the top.
  for (int y = 0; y < h; ++y)
    std::copy(rgb.begin() + std::size_t(h - 1 - y) * w * 3,
              rgb.begin() + std::size_t(h - y) * w * 3, dst + std::size_t(y) * w * 3);
  writeAtomically(path, [&](const std::string& tmp) {
    vtkNew<vtkPNGWriter> writer;
    writer->SetFileName(tmp.c_str());
    writer->SetInputData(image);
    writer->Write();
    if (writer->GetErrorCode() != 0 || !fs::exists(tmp) || fs::file_size(tmp) == 0)
      throw InputError(path + ": cannot write PNG");
  });
}

/** The DontCare regions to apply: --dont-care/--calib, else the --sequence folder's KITTI files;
 * none with --no-dont-care. */
std::shared_ptr<const pcl_movers::eval::DontCareRegions> loadDontCare(const Options& opt) {
  const bool given = !opt.dont_care_path.empty() || !opt.calib_path.empty();
  if (opt.no_dont_care) {
    if (given) throw InputError("--no-dont-care contradicts --dont-care/--calib");
    return nullptr;
  }
  if (given && (opt.dont_care_path.empty() || opt.calib_path.empty()))
    throw InputError(opt.dont_care_path.empty() ? "--calib needs --dont-care LABELS"
                                                : "--dont-care needs --calib CALIB");
  std::string labels = opt.dont_care_path, calib = opt.calib_path;
  if (!given && !opt.sequence.empty()) {
    const fs::path dir(opt.sequence);
    if (!fs::is_regular_file(dir / kSequenceLabels) || !fs::is_regular_file(dir / kSequenceCalib))
      return nullptr;
    labels = (dir / kSequenceLabels).string();
    calib = (dir / kSequenceCalib).string();
  }
  if (labels.empty()) return nullptr;
  for (const auto& p : {labels, calib})
    if (!fs::is_regular_file(p)) throw InputError(p + ": no such file");
  auto regions = std::make_shared<const pcl_movers::eval::DontCareRegions>(
      pcl_movers::eval::DontCareRegions::fromFiles(labels, calib));
  pcl::console::print_info(
      stderr, "DontCare: %zu KITTI DontCare boxes from %s (calib %s); rows there are ignored%s\n",
      regions->size(), labels.c_str(), calib.c_str(),
      given ? "" : " (--no-dont-care to count them)");
  return regions;
}

/** A labels folder: DIR itself, or DIR/labels when DIR holds no .label file but that folder. */
std::string labelsFolder(const std::string& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir + ": no such folder");
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".label") return dir;
  if (fs::is_directory(fs::path(dir) / "labels")) return (fs::path(dir) / "labels").string();
  return dir;
}

/** --mos GT PRED: moving-point IoU of per-point labels. */
int runMos(const pcl_movers::tools::Arguments& args) {
  const auto& positional = args.positional;
  if (positional.size() != 2)
    throw InputError("--mos expects GT_LABELS and PRED_LABELS folders, got " +
                     std::to_string(positional.size()) + " argument(s); see -h");
  for (const char* flag :
       {"--sector-deg", "--min-points", "--grow", "--grow-z", "--frames", "--sequence", "--poses",
        "--times", "--png", "--title", "--dont-care", "--calib", "--no-dont-care"})
    if (args.has(flag))
      throw InputError(std::string(flag) + " is for scoring tracks; --mos takes --json only");
  std::string json_path;
  args.get("--json", json_path);
  checkOutput(json_path, args.has("--overwrite"));
  const std::string truth = labelsFolder(positional[0]), prediction = labelsFolder(positional[1]);
  const auto score = pcl_movers::eval::scoreMosFolders(truth, prediction);
  std::cout << "Moving-object segmentation: " << prediction << " against " << truth << "\n\n"
            << pcl_movers::eval::formatMosMarkdown(score) << std::flush;
  if (!json_path.empty()) {
    writeText(json_path, pcl_movers::eval::formatMosJson(score));
    pcl::console::print_info("wrote %s\n", json_path.c_str());
  }
  return 0;
}

int run(int argc, char** argv) {
  const auto args = optionTable().parse(argc, argv);
  const auto& positional = args.positional;
  if (args.has("--mos")) return runMos(args);
  if (positional.size() != 2)
    throw InputError("expected OBJECTS and TRACKS, got " + std::to_string(positional.size()) +
                     " file argument(s); see -h");

  Options opt;
  std::string value;
  if (args.get("--sector-deg", value)) {
    opt.metrics.sector_deg = parseNumber("--sector-deg", value);
    if (!(opt.metrics.sector_deg > 0 && opt.metrics.sector_deg <= 180))
      throw InputError("--sector-deg: must be in (0, 180], got '" + value + "'");
  }
  if (args.get("--min-points", value))
    opt.metrics.min_points = parseCount("--min-points", value, 0);
  if (args.get("--grow", value)) {
    opt.metrics.grow_xy = parseNumber("--grow", value);
    if (opt.metrics.grow_xy < 0) throw InputError("--grow: must be >= 0, got '" + value + "'");
  }
  if (args.get("--grow-z", value)) {
    opt.metrics.grow_z = parseNumber("--grow-z", value);
    if (opt.metrics.grow_z < 0) throw InputError("--grow-z: must be >= 0, got '" + value + "'");
  }
  if (args.get("--frames", value)) opt.metrics.frames = parseCount("--frames", value, 1);
  args.get("--sequence", opt.sequence);
  args.get("--poses", opt.poses_path);
  args.get("--times", opt.times_path);
  args.get("--png", opt.png_path);
  args.get("--json", opt.json_path);
  args.get("--title", opt.title);
  args.get("--dont-care", opt.dont_care_path);
  args.get("--calib", opt.calib_path);
  opt.no_dont_care = args.has("--no-dont-care");
  opt.overwrite = args.has("--overwrite");

  checkOutput(opt.png_path, opt.overwrite);
  checkOutput(opt.json_path, opt.overwrite);
  if (!opt.png_path.empty() && opt.png_path == opt.json_path)
    throw InputError("--png and --json name the same file: " + opt.png_path);

  for (const auto& p : positional)
    if (!fs::is_regular_file(p)) throw InputError(p + ": no such file");
  const auto objects = pcl_movers::io::readObjects(positional[0]);
  const auto tracks = pcl_movers::io::readTracks(positional[1]);
  if (objects.empty())
    throw InputError(positional[0] + ": no ground-truth objects; nothing to score against");

  std::vector<Eigen::Isometry3d> poses;
  std::vector<double> times;
  if (!opt.sequence.empty()) {
    pcl_movers::io::SequenceReader seq(opt.sequence);
    if (seq.empty()) throw InputError(opt.sequence + ": no frames in the sequence folder");
    if (opt.metrics.frames == 0) opt.metrics.frames = static_cast<int>(seq.size());
    if (seq.hasPoses()) poses = seq.poses();
    if (seq.hasTimes()) times = seq.times();
  }
  if (!opt.poses_path.empty()) poses = pcl_movers::io::readPoses(opt.poses_path);
  if (!opt.times_path.empty()) times = pcl_movers::io::readTimes(opt.times_path);

  // Frames referenced by the inputs must exist in the poses/times given, else the run is
  // inconsistent (wrong sequence); say which file is short instead of scoring garbage.
  int max_frame = -1;
  for (const auto& o : objects) max_frame = std::max(max_frame, o.frame);
  for (const auto& r : tracks) max_frame = std::max(max_frame, r.frame);
  const std::string poses_name = opt.poses_path.empty() ? opt.sequence + "/poses" : opt.poses_path;
  const std::string times_name = opt.times_path.empty() ? opt.sequence + "/times" : opt.times_path;
  if (!poses.empty() && max_frame >= static_cast<int>(poses.size()))
    throw InputError(poses_name + ": " + std::to_string(poses.size()) +
                     " poses, but the inputs reach frame " + std::to_string(max_frame));
  if (!times.empty() && max_frame >= static_cast<int>(times.size()))
    throw InputError(times_name + ": " + std::to_string(times.size()) +
                     " times, but the inputs reach frame " + std::to_string(max_frame));
  if (opt.metrics.frames > 0 && max_frame >= opt.metrics.frames)
    throw InputError("--frames " + std::to_string(opt.metrics.frames) +
                     " is fewer than the frames in the inputs (up to " + std::to_string(max_frame) +
                     ")");

  opt.metrics.dont_care = loadDontCare(opt);
  const auto score = pcl_movers::eval::scoreDetections(objects, tracks, opt.metrics, poses, times);
  std::cout << pcl_movers::eval::formatMarkdown(score) << std::flush;
  if (!opt.json_path.empty()) {
    writeText(opt.json_path, pcl_movers::eval::formatJson(score));
    pcl::console::print_info("wrote %s\n", opt.json_path.c_str());
  }
  if (!opt.png_path.empty()) {
    writePng(opt.png_path, score, opt.title);
    pcl::console::print_info("wrote %s\n", opt.png_path.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  return pcl_movers::tools::runTool("pcl_movers_eval", [&] { return run(argc, argv); });
}
