/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/eval/mos_metrics.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace pcl_movers {
namespace eval {

namespace {

double iou(std::uint64_t tp, std::uint64_t fp, std::uint64_t fn) {
  const std::uint64_t sum = tp + fp + fn;
  return sum > 0 ? double(tp) / double(sum) : NAN;
}

std::string percent(double v) {
  if (!std::isfinite(v)) return "–";
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f", 100.0 * v);
  return text;
}

std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/** The `*.label` files of a folder, sorted by number. */
std::vector<std::string> labelFiles(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file(ec) && e.path().extension() == ".label")
      files.push_back(e.path().string());
  if (ec) throw InputError(dir, 0, "cannot list: " + ec.message());
  io::sortNumerically(files);
  return files;
}

}  // namespace

double MosCounts::movingIou() const {
  return iou(tp(), fp(), fn());
}

double MosCounts::staticIou() const {
  return iou(static_as_static, moving_as_static, static_as_moving + static_as_none);
}

MosCounts& MosCounts::operator+=(const MosCounts& o) {
  moving_as_moving += o.moving_as_moving;
  moving_as_static += o.moving_as_static;
  moving_as_none += o.moving_as_none;
  static_as_moving += o.static_as_moving;
  static_as_static += o.static_as_static;
  static_as_none += o.static_as_none;
  unscored += o.unscored;
  return *this;
}

MosCounts scoreMosFrame(const std::vector<std::uint32_t>& truth,
                        const std::vector<std::uint32_t>& prediction,
                        const std::string& prediction_name) {
  const bool none = prediction.empty();
  if (!none && prediction.size() != truth.size())
    throw InputError(prediction_name, 0,
                     std::to_string(prediction.size()) + " points, but the ground truth has " +
                         std::to_string(truth.size()));
  MosCounts c;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const std::uint16_t gt = io::labelClass(truth[k]);
    if (isUnscoredClass(gt)) {
      ++c.unscored;
      continue;
    }
    const std::uint16_t pr = none ? 0 : io::labelClass(prediction[k]);
    const bool gt_moving = isMovingClass(gt);
    if (pr == 0)
      ++(gt_moving ? c.moving_as_none : c.static_as_none);
    else if (isMovingClass(pr))
      ++(gt_moving ? c.moving_as_moving : c.static_as_moving);
    else
      ++(gt_moving ? c.moving_as_static : c.static_as_static);
  }
  return c;
}

MosScore scoreMosFolders(const std::string& truth_dir, const std::string& prediction_dir) {
  for (const std::string& dir : {truth_dir, prediction_dir})
    if (!dir.empty() && !fs::is_directory(dir)) throw InputError(dir, 0, "no such folder");
  const std::vector<std::string> truth_files = labelFiles(truth_dir);
  if (truth_files.empty()) throw InputError(truth_dir, 0, "no .label files (ground truth)");
  MosScore score;
  std::vector<std::string> truth_names;
  for (const std::string& path : truth_files) {
    const std::string name = fs::path(path).filename().string();
    truth_names.push_back(name);
    std::vector<std::uint32_t> prediction;
    std::string prediction_path;
    if (!prediction_dir.empty()) {
      prediction_path = (fs::path(prediction_dir) / name).string();
      if (!fs::is_regular_file(prediction_path))
        throw InputError(prediction_path, 0,
                         "missing: the ground truth has " + path + " (a frame not predicted)");
      prediction = io::readLabels(prediction_path);
    }
    const std::vector<std::uint32_t> truth = io::readLabels(path);
    // An empty prediction file for an empty frame is fine; for a frame with points it is not.
    if (!prediction_dir.empty() && prediction.size() != truth.size())
      throw InputError(prediction_path, 0,
                       std::to_string(prediction.size()) + " points, but the ground truth " + path +
                           " has " + std::to_string(truth.size()));
    MosFrame frame;
    frame.name = fs::path(path).stem().string();
    frame.counts = scoreMosFrame(truth, prediction, prediction_path);
    score.total += frame.counts;
    score.frames.push_back(frame);
  }
  if (!prediction_dir.empty())
    for (const std::string& path : labelFiles(prediction_dir))
      if (std::find(truth_names.begin(), truth_names.end(), fs::path(path).filename().string()) ==
          truth_names.end())
        score.unmatched_predictions.push_back(path);
  return score;
}

std::string formatMosMarkdown(const MosScore& score) {
  const MosCounts& t = score.total;
  std::ostringstream out;
  out << "| class | IoU % | TP | FP | FN | ground-truth points |\n"
      << "|---|---:|---:|---:|---:|---:|\n"
      << "| moving | " << percent(t.movingIou()) << " | " << t.tp() << " | " << t.fp() << " | "
      << t.fn() << " | " << t.movingTruth() << " |\n"
      << "| static | " << percent(t.staticIou()) << " | " << t.static_as_static << " | "
      << t.moving_as_static << " | " << t.static_as_moving + t.static_as_none << " | "
      << t.staticTruth() << " |\n\n";
  std::size_t with_truth = 0, with_prediction = 0, missed = 0, false_only = 0;
  std::vector<double> ious, moving_points;
  for (const MosFrame& f : score.frames) {
    const MosCounts& c = f.counts;
    with_truth += c.movingTruth() > 0;
    with_prediction += c.movingPredicted() > 0;
    missed += c.movingTruth() > 0 && c.tp() == 0;
    false_only += c.movingTruth() == 0 && c.movingPredicted() > 0;
    if (std::isfinite(c.movingIou())) ious.push_back(c.movingIou());
    if (c.movingTruth() > 0) moving_points.push_back(double(c.movingTruth()));
  }
  char line[512];
  std::snprintf(line, sizeof(line),
                "%zu frames, %llu scored points (%llu not scored: ground-truth class 0 or 1). "
                "Moving in the ground truth: %zu frames (median %s points there); predicted "
                "moving: %zu frames. Frames with moving points none of which was found: %zu; "
                "frames predicting moving points where nothing moves: %zu. Per-frame moving IoU "
                "(frames with moving truth or prediction): median %s %%.\n",
                score.frames.size(), static_cast<unsigned long long>(t.scored()),
                static_cast<unsigned long long>(t.unscored), with_truth,
                moving_points.empty() ? "–" : std::to_string(long(median(moving_points))).c_str(),
                with_prediction, missed, false_only, percent(median(ious)).c_str());
  out << line;
  if (!score.unmatched_predictions.empty())
    out << "\n"
        << score.unmatched_predictions.size()
        << " prediction file(s) without ground truth, not scored (first: "
        << score.unmatched_predictions.front() << ").\n";
  return out.str();
}

std::string formatMosJson(const MosScore& score) {
  auto counts = [](const MosCounts& c) {
    std::ostringstream js;
    js << "\"tp\": " << c.tp() << ", \"fp\": " << c.fp() << ", \"fn\": " << c.fn()
       << ", \"moving_iou\": " << jsonNumber(c.movingIou())
       << ", \"static_iou\": " << jsonNumber(c.staticIou())
       << ", \"moving_truth\": " << c.movingTruth() << ", \"static_truth\": " << c.staticTruth()
       << ", \"moving_as_static\": " << c.moving_as_static
       << ", \"moving_as_none\": " << c.moving_as_none
       << ", \"static_as_none\": " << c.static_as_none << ", \"unscored\": " << c.unscored;
    return js.str();
  };
  std::ostringstream js;
  js << "{" << counts(score.total) << ", \"frames\": [";
  for (std::size_t k = 0; k < score.frames.size(); ++k)
    js << (k ? ",\n  " : "\n  ") << "{\"name\": " << jsonString(score.frames[k].name) << ", "
       << counts(score.frames[k].counts) << "}";
  js << "\n]}\n";
  return js.str();
}

}  // namespace eval
}  // namespace pcl_movers
