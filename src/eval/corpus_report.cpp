/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/corpus_report.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <set>
#include <sstream>

namespace pcl_movers {
namespace eval {

namespace {

/** Sums of one group of targets and runs in one mode. */
struct Tally {
  std::set<std::string> scenes;
  int targets = 0;
  int never_detected = 0;
  double hit_sum = 0;
  std::vector<int> delays;
  double velocity_squares = 0;
  int velocity_samples = 0;
  int frames = 0;
  int false_alarms = 0;
  bool has_false_alarms = false;  ///< false for groups of targets (class, speed band)
  MosCounts mos;                  ///< moving-point counts of the group's runs
  bool has_mos = false;

  void addTarget(const TargetScore& t) {
    ++targets;
    hit_sum += double(t.hits) / t.visible_frames;
    if (t.hits == 0) ++never_detected;
    if (t.delay >= 0) delays.push_back(t.delay);
    if (t.velocity_samples > 0 && std::isfinite(t.rms_velocity_error)) {
      velocity_squares += t.rms_velocity_error * t.rms_velocity_error * t.velocity_samples;
      velocity_samples += t.velocity_samples;
    }
  }
  void addRun(const CorpusRun& run) {
    scenes.insert(run.scene());
    frames += run.frames;
    false_alarms += run.score.false_alarms;
    has_false_alarms = true;
    if (run.has_mos) {
      mos += run.mos;
      has_mos = true;
    }
  }
  double movingIouPercent() const { return has_mos ? 100.0 * mos.movingIou() : NAN; }
  double hitPercent() const { return targets > 0 ? 100.0 * hit_sum / targets : NAN; }
  double medianDelay() const {
    if (delays.empty()) return NAN;
    std::vector<int> d = delays;
    std::sort(d.begin(), d.end());
    const std::size_t n = d.size();
    return n % 2 ? d[n / 2] : 0.5 * (d[n / 2 - 1] + d[n / 2]);
  }
  double velocityRms() const {
    return velocity_samples > 0 ? std::sqrt(velocity_squares / velocity_samples) : NAN;
  }
  double falseAlarmsPerFrame() const { return frames > 0 ? double(false_alarms) / frames : NAN; }
};

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "–";
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, v);
  return text;
}

bool visible(const TargetScore& t) {
  return t.visible_frames > 0;
}

std::vector<std::string> modesOf(const std::vector<CorpusRun>& runs) {
  std::vector<std::string> modes;
  for (const CorpusRun& r : runs)
    if (std::find(modes.begin(), modes.end(), r.mode) == modes.end()) modes.push_back(r.mode);
  return modes;
}

using RunKey = std::function<std::string(const CorpusRun&)>;
using TargetKey = std::function<std::string(const CorpusRun&, const TargetScore&)>;

/** One table: a row per key (in `order`, then any others sorted), a column group per mode. With
 * a run key the false alarms of the group's runs are counted; with only a target key not. */
std::string groupTable(const std::vector<CorpusRun>& runs, const std::string& heading,
                       const std::vector<std::string>& order, const RunKey& run_key,
                       const TargetKey& target_key) {
  const std::vector<std::string> modes = modesOf(runs);
  std::map<std::string, std::map<std::string, Tally>> tallies;  // key → mode → tally
  for (const CorpusRun& run : runs) {
    if (run_key) tallies[run_key(run)][run.mode].addRun(run);
    for (const TargetScore& t : run.score.targets)
      if (visible(t)) {
        Tally& tally = tallies[target_key(run, t)][run.mode];
        tally.addTarget(t);
        tally.scenes.insert(run.scene());
      }
  }
  std::vector<std::string> keys;
  for (const std::string& k : order)
    if (tallies.count(k)) keys.push_back(k);
  for (const auto& kv : tallies)
    if (std::find(keys.begin(), keys.end(), kv.first) == keys.end()) keys.push_back(kv.first);

  std::ostringstream out;
  out << "| " << heading << " | scenes | targets";
  for (std::size_t m = 0; m < modes.size(); ++m) {
    const std::string p = m == 0 ? "" : modes[m] + ": ";
    out << " | " << p << "hit %"
        << (run_key ? " | " + p + "FA / frame | " + p + "moving IoU %" : "");
    if (m == 0) out << " | median delay | never hit";
    out << " | " << p << "vel. RMS [m/s]";
  }
  out << " |\n|---|---:|---:";
  for (std::size_t m = 0; m < modes.size(); ++m)
    out << "|---:" << (run_key ? "|---:|---:" : "") << (m == 0 ? "|---:|---:" : "") << "|---:";
  out << "|\n";
  for (const std::string& k : keys) {
    const auto& by_mode = tallies[k];
    const Tally& first = by_mode.count(modes[0]) ? by_mode.at(modes[0]) : Tally();
    out << "| " << k << " | " << first.scenes.size() << " | " << first.targets;
    for (std::size_t m = 0; m < modes.size(); ++m) {
      const auto it = by_mode.find(modes[m]);
      const Tally t = it == by_mode.end() ? Tally() : it->second;
      out << " | " << fixed(t.hitPercent(), 1);
      if (run_key)
        out << " | " << fixed(t.falseAlarmsPerFrame(), 3) << " | "
            << fixed(t.movingIouPercent(), 1);
      if (m == 0) out << " | " << fixed(t.medianDelay(), 1) << " | " << t.never_detected;
      out << " | " << fixed(t.velocityRms(), 3);
    }
    out << " |\n";
  }
  return out.str();
}

std::vector<std::string> speedBands() {
  return {"< 1 m/s", "1-2 m/s", "2-5 m/s", "5-15 m/s", "> 15 m/s"};
}

std::string worstTargets(const std::vector<CorpusRun>& runs, const CorpusReportOptions& options) {
  const std::string mode = modesOf(runs).front();
  struct Row {
    const CorpusRun* run;
    const TargetScore* target;
  };
  std::vector<Row> rows;
  for (const CorpusRun& run : runs)
    if (run.mode == mode)
      for (const TargetScore& t : run.score.targets)
        if (visible(t)) rows.push_back({&run, &t});
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    const double ha = a.target->hitRate(), hb = b.target->hitRate();
    if (ha != hb) return ha < hb;
    if (a.target->visible_frames != b.target->visible_frames)
      return a.target->visible_frames > b.target->visible_frames;
    if (a.run->scene() != b.run->scene()) return a.run->scene() < b.run->scene();
    return a.target->track_id < b.target->track_id;
  });
  if (int(rows.size()) > options.worst) rows.resize(std::size_t(options.worst));
  std::ostringstream out;
  out << "| scene | sensor | target | class | speed [m/s] | visible | hit % | delay | why |\n"
      << "|---|---|---:|---|---:|---:|---:|---:|---|\n";
  for (const Row& r : rows) {
    const TargetScore& t = *r.target;
    out << "| " << r.run->scene() << " | " << r.run->sensor << " | " << t.track_id << " | "
        << t.type << " | " << fixed(t.median_speed, 1) << " | " << t.visible_frames << " | "
        << fixed(100.0 * t.hitRate(), 1) << " | " << (t.delay >= 0 ? std::to_string(t.delay) : "–")
        << " | " << missReason(t, r.run->ok, options.late_frames) << " |\n";
  }
  return out.str();
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char text[64];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

}  // namespace

std::string speedBand(double speed) {
  const std::vector<std::string> bands = speedBands();
  if (!(speed >= 1)) return bands[0];
  if (speed < 2) return bands[1];
  if (speed < 5) return bands[2];
  if (speed <= 15) return bands[3];
  return bands[4];
}

std::string missReason(const TargetScore& t, bool run_ok, int late_frames) {
  if (!run_ok) return "run failed";
  if (t.hits == 0 && t.tracked_frames == 0) return "never its own object";
  if (t.hits == 0) {
    // The decision test its rows failed most often (frames without any row aside).
    const std::pair<const std::string, int>* most = nullptr;
    for (const auto& m : t.missed_by_reason)
      if (m.first != "no row" && (!most || m.second > most->second)) most = &m;
    return most ? "tracked, never a mover: " + most->first : "tracked, never a mover";
  }
  if (t.delay > late_frames) return "late (" + std::to_string(t.delay) + " frames)";
  return t.hitRate() < 0.5 ? "intermittent"
                           : "missed " + std::to_string(t.visible_frames - t.hits) + " frames";
}

namespace {

/** Missed visible frames of `mode` by reason (TargetScore::missed_by_reason), per family. */
std::string missedByReasonTable(const std::vector<CorpusRun>& runs, const std::string& mode) {
  std::map<std::string, std::map<std::string, int>> by_family;  // family -> reason -> frames
  std::set<std::string> reasons;
  for (const CorpusRun& r : runs) {
    if (r.mode != mode) continue;
    for (const TargetScore& t : r.score.targets)
      for (const auto& m : t.missed_by_reason) {
        by_family[r.family][m.first] += m.second;
        by_family["all"][m.first] += m.second;
        reasons.insert(m.first);
      }
  }
  if (reasons.empty()) return "No missed frame.\n";
  // "no row" first, then the decision's tests in their order, then any other.
  std::vector<std::string> columns;
  for (const char* r : {"no row", "new", "large", "young", "low", "no_motion", "no_free_space"})
    if (reasons.erase(r)) columns.push_back(r);
  columns.insert(columns.end(), reasons.begin(), reasons.end());
  std::ostringstream out;
  out << "| family | missed frames |";
  for (const auto& c : columns) out << " " << c << " |";
  out << "\n|---|---:|";
  for (std::size_t k = 0; k < columns.size(); ++k) out << "---:|";
  out << "\n";
  for (const char* family : {"highway", "urban", "parking", "open", "trail", "all"}) {
    const auto it = by_family.find(family);
    if (it == by_family.end()) continue;
    int total = 0;
    for (const auto& m : it->second) total += m.second;
    out << "| " << family << " | " << total << " |";
    for (const auto& c : columns) {
      const auto f = it->second.find(c);
      out << " " << fixed(100.0 * (f == it->second.end() ? 0 : f->second) / total, 1) << " |";
    }
    out << "\n";
  }
  return out.str();
}

}  // namespace

std::string formatCorpusReport(const std::vector<CorpusRun>& runs,
                               const CorpusReportOptions& options) {
  std::ostringstream out;
  if (runs.empty()) return "## " + options.title + "\n\nNo runs.\n";
  const std::vector<std::string> modes = modesOf(runs);
  std::set<std::string> scenes;
  int frames = 0, blind = 0;
  for (const CorpusRun& r : runs)
    if (r.mode == modes[0]) {
      scenes.insert(r.scene());
      frames += r.frames;
      blind += r.blind_frames;
    }
  out << "## " << options.title << "\n\n"
      << scenes.size() << " scenes, " << frames << " frames (" << blind << " of them blind), "
      << "modes: ";
  for (std::size_t m = 0; m < modes.size(); ++m) out << (m ? ", " : "") << modes[m];
  out << ". ";
  if (!options.command.empty()) out << "Made by `" << options.command << "` ";
  out << "in " << fixed(options.wall_seconds / 60.0, 1) << " min on " << options.cores << " cores ("
      << fixed(options.generate_seconds / 60.0, 1)
      << " min of worker time simulating scenes that were not cached).\n\n"
      << "Hit % is the mean over targets of each target's hits / visible frames; FA / frame the "
         "false alarms over all frames; median delay over targets hit at least once; vel. RMS "
         "pooled over hits. Moving IoU is the moving-point IoU of pcl_movers_detect "
         "--point-labels against the scenes' point labels, scored as SemanticKITTI-MOS does: "
         "TP / (TP + FP + FN) over every point of the group's frames (moving = moving in that "
         "frame). The first mode's columns come first; the others are prefixed.\n\n";

  const RunKey all = [](const CorpusRun&) { return std::string("all"); };
  const TargetKey all_t = [](const CorpusRun&, const TargetScore&) { return std::string("all"); };
  out << "### Overall\n\n" << groupTable(runs, "", {}, all, all_t) << "\n";

  const RunKey family = [](const CorpusRun& r) { return r.family; };
  out << "### By family\n\n"
      << groupTable(runs, "family", {"highway", "urban", "parking", "open", "trail"}, family,
                    [](const CorpusRun& r, const TargetScore&) { return r.family; })
      << "\n";
  const RunKey sensor = [](const CorpusRun& r) { return r.sensor; };
  out << "### By sensor\n\n"
      << groupTable(runs, "sensor", {"hdl64", "hdl32", "vlp16", "os1_64", "ladar2d"}, sensor,
                    [](const CorpusRun& r, const TargetScore&) { return r.sensor; })
      << "\n";
  out << "### By class (false alarms belong to no class)\n\n"
      << groupTable(runs, "class", {"Car", "Van", "Truck", "Pedestrian", "Cyclist"}, nullptr,
                    [](const CorpusRun&, const TargetScore& t) { return t.type; })
      << "\n";
  out << "### By speed band (the target's median speed while visible)\n\n"
      << groupTable(
             runs, "speed", speedBands(), nullptr,
             [](const CorpusRun&, const TargetScore& t) { return speedBand(t.median_speed); })
      << "\n";
  out << "### Why visible frames were missed (" << modes[0] << ")\n\n"
      << "Each visible frame without a hit, by the tracks.csv `reason` of the row in the "
         "target's box nearest its centre (the mover decision's test that row failed, "
         "docs/design.md), or *no row* when no tracked row is in the box (segmentation joined the "
         "target to something, or it was not tracked); % of the missed frames.\n\n"
      << missedByReasonTable(runs, modes[0]) << "\n";
  out << "### The " << options.worst << " worst targets (" << modes[0] << ")\n\n"
      << "Why: *never its own object* = no tracked row in its box in any visible frame "
         "(segmentation joined it to something, or it was never tracked); *tracked, never a "
         "mover: REASON*, the decision test its rows failed most often; *late* = first hit more "
         "than "
      << options.late_frames << " frames after it became visible; *intermittent* = hit in time "
      << "but in under half of its frames.\n\n"
      << worstTargets(runs, options) << "\n";
  std::ostringstream failed;
  for (const CorpusRun& r : runs)
    if (!r.ok) failed << "| " << r.scene() << " | " << r.mode << " | " << r.error << " |\n";
  if (!failed.str().empty())
    out << "### Failed runs (their targets count as missed)\n\n| scene | mode | error |\n"
        << "|---|---|---|\n"
        << failed.str() << "\n";
  return out.str();
}

std::string formatCorpusJson(const std::vector<CorpusRun>& runs) {
  std::ostringstream out;
  for (const CorpusRun& r : runs) {
    out << "{\"scene\": " << jsonString(r.scene()) << ", \"family\": " << jsonString(r.family)
        << ", \"seed\": " << r.seed << ", \"sensor\": " << jsonString(r.sensor)
        << ", \"mode\": " << jsonString(r.mode) << ", \"ok\": " << (r.ok ? "true" : "false")
        << ", \"error\": " << jsonString(r.error) << ", \"frames\": " << r.frames
        << ", \"blind_frames\": " << r.blind_frames << ", \"seconds\": " << jsonNumber(r.seconds)
        << ", \"false_alarms\": " << r.score.false_alarms;
    if (r.has_mos)
      out << ", \"mos\": {\"tp\": " << r.mos.tp() << ", \"fp\": " << r.mos.fp()
          << ", \"fn\": " << r.mos.fn() << ", \"moving_iou\": " << jsonNumber(r.mos.movingIou())
          << ", \"static_iou\": " << jsonNumber(r.mos.staticIou()) << "}";
    out << ", \"targets\": [";
    bool first = true;
    for (const TargetScore& t : r.score.targets) {
      if (!visible(t)) continue;
      out << (first ? "" : ", ") << "{\"id\": " << t.track_id
          << ", \"class\": " << jsonString(t.type) << ", \"visible\": " << t.visible_frames
          << ", \"hits\": " << t.hits << ", \"delay\": " << t.delay
          << ", \"tracked\": " << t.tracked_frames << ", \"speed\": " << jsonNumber(t.median_speed)
          << ", \"vel_rms\": " << jsonNumber(t.rms_velocity_error)
          << ", \"vel_n\": " << t.velocity_samples << ", \"missed_by_reason\": {"
          << formatReasonCounts(t.missed_by_reason) << "}}";
      first = false;
    }
    out << "]}\n";
  }
  return out.str();
}

}  // namespace eval
}  // namespace pcl_movers
