/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/eval/detection_metrics.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

namespace pcl_movers {
namespace eval {

namespace {

constexpr double kPi = 3.14159265358979323846;

bool inSector(double x, double y, double sector_deg) {
  return std::abs(std::atan2(y, x)) <= sector_deg * kPi / 180.0 + 1e-12;
}

double timeOf(const std::vector<double>& times, int frame) {
  if (times.empty()) return 0.1 * frame;
  if (frame < 0 || frame >= static_cast<int>(times.size()))
    throw InputError("times", 0,
                     "no timestamp for frame " + std::to_string(frame) + " (have " +
                         std::to_string(times.size()) + ")");
  return times[frame];
}

/** Least-squares slope of the horizontal world position over a window of frames. */
bool fitVelocity(const std::map<int, Eigen::Vector2d>& track, int frame, int half_window,
                 const std::vector<double>& times, Eigen::Vector2d& velocity) {
  std::vector<std::pair<double, Eigen::Vector2d>> samples;
  for (auto it = track.lower_bound(frame - half_window);
       it != track.end() && it->first <= frame + half_window; ++it)
    samples.emplace_back(timeOf(times, it->first), it->second);
  if (samples.size() < 2) return false;
  double mean_t = 0;
  Eigen::Vector2d mean_p = Eigen::Vector2d::Zero();
  for (const auto& s : samples) {
    mean_t += s.first;
    mean_p += s.second;
  }
  mean_t /= samples.size();
  mean_p /= double(samples.size());
  double stt = 0;
  Eigen::Vector2d stp = Eigen::Vector2d::Zero();
  for (const auto& s : samples) {
    stt += (s.first - mean_t) * (s.first - mean_t);
    stp += (s.first - mean_t) * (s.second - mean_p);
  }
  if (stt <= 1e-12) return false;
  velocity = stp / stt;
  return true;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string fmt(double v, int precision) {
  if (!std::isfinite(v)) return "—";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", precision, v);
  return buf;
}

std::string jsonNumber(double v, int precision = 4) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", precision, v);
  return buf;
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

using ObjectsByFrame = std::map<int, std::vector<const io::GroundTruthObject*>>;
using RowsByFrame = std::map<int, std::vector<const io::TrackRow*>>;

/** Whether some row's centroid lies in the object's grown box. */
bool anyRowIn(const io::GroundTruthObject& o, const std::vector<const io::TrackRow*>& rows,
              const DetectionMetricsParams& params) {
  for (const auto* r : rows)
    if (o.contains(Eigen::Vector3d(r->x, r->y, r->z), params.grow_xy, params.grow_z)) return true;
  return false;
}

/** The row whose centroid lies in the grown box nearest (horizontally) its centre; null if none. */
const io::TrackRow* nearestRowIn(const io::GroundTruthObject& o,
                                 const std::vector<const io::TrackRow*>& rows,
                                 const DetectionMetricsParams& params) {
  const io::TrackRow* best = nullptr;
  double best_d = std::numeric_limits<double>::infinity();
  for (const auto* r : rows) {
    const Eigen::Vector3d c(r->x, r->y, r->z);
    if (!o.contains(c, params.grow_xy, params.grow_z)) continue;
    const double d = (c - o.center).head<2>().norm();
    if (d < best_d) best_d = d, best = r;
  }
  return best;
}

/** False alarms: mover rows in the sector outside every target's grown box of their frame; those
 * in no labelled box that project into a DontCare box are ignored instead. */
void countFalseAlarms(const RowsByFrame& movers_by_frame, const ObjectsByFrame& objects_by_frame,
                      const DetectionMetricsParams& params, DetectionScore& score) {
  for (const auto& fm : movers_by_frame) {
    const auto oit = objects_by_frame.find(fm.first);
    for (const auto* r : fm.second) {
      if (!inSector(r->x, r->y, params.sector_deg)) continue;
      ++score.mover_rows_in_sector;
      const Eigen::Vector3d c(r->x, r->y, r->z);
      bool on_target = false, on_static = false;
      if (oit != objects_by_frame.end())
        for (const auto* o : oit->second) {
          if (!o->contains(c, params.grow_xy, params.grow_z)) continue;
          if (o->moving)
            on_target = true;
          else
            on_static = true;
        }
      if (on_target) continue;
      if (!on_static && params.dont_care && params.dont_care->contains(fm.first, c)) {
        ++score.dont_care_ignored;
        continue;
      }
      ++score.false_alarms;
      if (on_static) ++score.false_alarms_on_static_objects;
    }
  }
}

}  // namespace

DetectionScore scoreDetections(const std::vector<io::GroundTruthObject>& objects,
                               const std::vector<io::TrackRow>& tracks,
                               const DetectionMetricsParams& params,
                               const std::vector<Eigen::Isometry3d>& poses,
                               const std::vector<double>& times) {
  if (!(params.sector_deg > 0) || params.sector_deg > 180)
    throw InputError("sector must be in (0, 180] degrees, got " +
                     std::to_string(params.sector_deg));
  if (params.grow_xy < 0 || params.grow_z < 0) throw InputError("box growth must be >= 0");
  DetectionScore score;
  score.dont_care_used = params.dont_care != nullptr;
  const bool use_poses = !poses.empty();
  score.velocity_mode = use_poses ? "world velocity (poses)" : "speed (objects.txt speed_mps)";

  // Index everything by frame.
  ObjectsByFrame objects_by_frame;
  RowsByFrame movers_by_frame, rows_by_frame;
  std::set<int> frames;
  for (const auto& o : objects) {
    objects_by_frame[o.frame].push_back(&o);
    frames.insert(o.frame);
  }
  for (const auto& r : tracks) {
    frames.insert(r.frame);
    rows_by_frame[r.frame].push_back(&r);
    if (r.mover) movers_by_frame[r.frame].push_back(&r);
  }
  score.frames = params.frames > 0 ? params.frames : static_cast<int>(frames.size());

  // Targets: tracks flagged moving (the flag is per track, but take any row's flag to be safe).
  std::map<int, TargetScore> targets;
  for (const auto& o : objects)
    if (o.moving) {
      auto& t = targets[o.track_id];
      t.track_id = o.track_id;
      if (t.type.empty()) t.type = o.type;
    }

  // World horizontal centre of each target over time (for the reference velocity).
  std::map<int, std::map<int, Eigen::Vector2d>> world_tracks;
  if (use_poses) {
    for (const auto& o : objects) {
      if (!targets.count(o.track_id)) continue;
      if (o.frame < 0 || o.frame >= static_cast<int>(poses.size()))
        throw InputError("poses", 0,
                         "no pose for frame " + std::to_string(o.frame) + " (have " +
                             std::to_string(poses.size()) + ")");
      world_tracks[o.track_id][o.frame] = (poses[o.frame] * o.center).head<2>();
    }
  }

  std::map<int, std::vector<double>> squared_errors, visible_speeds;
  static const std::vector<const io::TrackRow*> kNone;
  for (const auto& frame_objects : objects_by_frame) {
    const int frame = frame_objects.first;
    const auto mit = movers_by_frame.find(frame);
    const auto& movers = mit == movers_by_frame.end() ? kNone : mit->second;
    const auto rit = rows_by_frame.find(frame);
    const auto& rows = rit == rows_by_frame.end() ? kNone : rit->second;
    for (const auto* o : frame_objects.second) {
      if (!o->moving) continue;
      auto& t = targets[o->track_id];
      const bool visible = o->n_points >= params.min_points &&
                           inSector(o->center.x(), o->center.y(), params.sector_deg);
      if (t.first_reported < 0 && anyRowIn(*o, movers, params)) {
        t.first_reported = frame;  // frames are visited in increasing order
        t.first_reported_visible = visible;
      }
      if (!visible) continue;
      ++t.visible_frames;
      const bool moving_now = o->speed >= params.moving_speed;
      if (moving_now) ++t.moving_frames;
      if (t.first_visible < 0) t.first_visible = frame;
      visible_speeds[o->track_id].push_back(o->speed);
      if (anyRowIn(*o, rows, params)) {
        ++t.tracked_frames;
        if (t.first_tracked < 0) t.first_tracked = frame;
      }
      // The hitting row nearest the box centre carries the velocity estimate we score.
      const io::TrackRow* best = nearestRowIn(*o, movers, params);
      if (!best) {
        const io::TrackRow* row = nearestRowIn(*o, rows, params);
        ++t.missed_by_reason[!row ? "no row" : row->reason.empty() ? "unknown" : row->reason];
        continue;
      }
      ++t.hits;
      if (moving_now) ++t.moving_hits;
      if (t.first_hit < 0) t.first_hit = frame;
      double err = std::numeric_limits<double>::quiet_NaN();
      if (use_poses) {
        Eigen::Vector2d v_gt;
        if (fitVelocity(world_tracks[o->track_id], frame, params.velocity_half_window, times, v_gt))
          err = (Eigen::Vector2d(best->vx, best->vy) - v_gt).norm();
      } else {
        err = std::abs(Eigen::Vector2d(best->vx, best->vy).norm() - o->speed);
      }
      if (std::isfinite(err)) squared_errors[o->track_id].push_back(err * err);
    }
  }

  countFalseAlarms(movers_by_frame, objects_by_frame, params, score);
  score.false_alarms_per_frame = score.frames > 0 ? double(score.false_alarms) / score.frames : 0;

  // Totals.
  std::vector<double> delays, hit_rates, moving_hit_rates, all_sq;
  int total_visible = 0, total_hits = 0;
  for (auto& kv : targets) {
    auto& t = kv.second;
    const auto& sq = squared_errors[t.track_id];
    t.median_speed = median(visible_speeds[t.track_id]);
    t.velocity_samples = static_cast<int>(sq.size());
    if (!sq.empty()) {
      double s = 0;
      for (double e : sq) s += e;
      t.rms_velocity_error = std::sqrt(s / sq.size());
      all_sq.insert(all_sq.end(), sq.begin(), sq.end());
    }
    if (t.first_hit >= 0) {
      t.delay = t.first_hit - t.first_visible;
      delays.push_back(t.delay);
    }
    if (t.moving_frames > 0) moving_hit_rates.push_back(t.movingHitRate());
    if (t.visible_frames > 0) {
      hit_rates.push_back(t.hitRate());
      if (t.hits == 0) ++score.targets_never_detected;
    }
    total_visible += t.visible_frames;
    total_hits += t.hits;
    score.targets.push_back(t);
  }
  if (!hit_rates.empty()) {
    double s = 0;
    for (double h : hit_rates) s += h;
    score.mean_hit_rate = s / hit_rates.size();
  }
  if (!moving_hit_rates.empty()) {
    double s = 0;
    for (double h : moving_hit_rates) s += h;
    score.mean_moving_hit_rate = s / moving_hit_rates.size();
  }
  score.moving_speed = params.moving_speed;
  if (total_visible > 0) score.pooled_hit_rate = double(total_hits) / total_visible;
  score.median_delay = median(delays);
  score.velocity_samples = static_cast<int>(all_sq.size());
  if (!all_sq.empty()) {
    double s = 0;
    for (double e : all_sq) s += e;
    score.rms_velocity_error = std::sqrt(s / all_sq.size());
  }
  return score;
}

std::string formatMarkdown(const DetectionScore& score) {
  std::ostringstream out;
  out << "| target | class | visible frames | hits | hit % | delay [frames] | RMS vel. err [m/s] "
         "| extra: hit % while moving ≥ "
      << fmt(score.moving_speed, 1) << " m/s (frames) | extra: first reported [frame] |\n"
      << "|---:|---|---:|---:|---:|---:|---:|---:|---|\n";
  for (const auto& t : score.targets)
    out << "| " << t.track_id << " | " << t.type << " | " << t.visible_frames << " | " << t.hits
        << " | " << fmt(100.0 * t.hitRate(), 1) << " | "
        << (t.delay >= 0 ? std::to_string(t.delay) : std::string(t.visible_frames ? "never" : "—"))
        << " | " << fmt(t.rms_velocity_error, 3) << " | " << fmt(100.0 * t.movingHitRate(), 1)
        << " (" << t.moving_frames << ") | "
        << (t.first_reported < 0 ? std::string("never")
                                 : std::to_string(t.first_reported) +
                                       (t.first_reported_visible ? "" : " (not scored there)"))
        << " |\n";
  out << "\n| total | value |\n|---|---:|\n"
      << "| targets (visible) | " << score.targets.size() << " ("
      << std::count_if(score.targets.begin(), score.targets.end(),
                       [](const TargetScore& t) { return t.visible_frames > 0; })
      << ") |\n"
      << "| mean hit % | " << fmt(100.0 * score.mean_hit_rate, 1) << " |\n"
      << "| extra (not the DESIGN metric): mean hit % over frames moving ≥ "
      << fmt(score.moving_speed, 1) << " m/s | " << fmt(100.0 * score.mean_moving_hit_rate, 1)
      << " |\n"
      << "| pooled hit % (all hits / all visible) | " << fmt(100.0 * score.pooled_hit_rate, 1)
      << " |\n"
      << "| false alarms / frame | " << fmt(score.false_alarms_per_frame, 4) << " ("
      << score.false_alarms << " in " << score.frames << " frames, "
      << score.false_alarms_on_static_objects << " on static objects"
      << (score.dont_care_used ? "; " + std::to_string(score.dont_care_ignored) +
                                     " rows in KITTI DontCare regions ignored"
                               : std::string())
      << ") |\n"
      << "| median delay [frames] | " << fmt(score.median_delay, 1) << " ("
      << score.targets_never_detected << " never detected) |\n"
      << "| RMS velocity error [m/s] | " << fmt(score.rms_velocity_error, 3) << " ("
      << score.velocity_mode << ", " << score.velocity_samples << " hits) |\n";
  return out.str();
}

std::string formatJson(const DetectionScore& score) {
  std::ostringstream out;
  out << "{\n  \"frames\": " << score.frames << ",\n  \"false_alarms\": " << score.false_alarms
      << ",\n  \"false_alarms_on_static_objects\": " << score.false_alarms_on_static_objects
      << ",\n  \"mover_rows_in_sector\": " << score.mover_rows_in_sector
      << ",\n  \"dont_care\": " << (score.dont_care_used ? "true" : "false")
      << ",\n  \"dont_care_ignored\": " << score.dont_care_ignored
      << ",\n  \"false_alarms_per_frame\": " << jsonNumber(score.false_alarms_per_frame, 5)
      << ",\n  \"mean_hit_rate\": " << jsonNumber(score.mean_hit_rate)
      << ",\n  \"pooled_hit_rate\": " << jsonNumber(score.pooled_hit_rate)
      << ",\n  \"extra_mean_moving_hit_rate\": " << jsonNumber(score.mean_moving_hit_rate)
      << ",\n  \"extra_moving_speed\": " << jsonNumber(score.moving_speed)
      << ",\n  \"median_delay\": " << jsonNumber(score.median_delay, 1)
      << ",\n  \"targets_never_detected\": " << score.targets_never_detected
      << ",\n  \"rms_velocity_error\": " << jsonNumber(score.rms_velocity_error)
      << ",\n  \"velocity_samples\": " << score.velocity_samples
      << ",\n  \"velocity_mode\": " << jsonString(score.velocity_mode) << ",\n  \"targets\": [";
  for (std::size_t i = 0; i < score.targets.size(); ++i) {
    const auto& t = score.targets[i];
    out << (i ? "," : "") << "\n    {\"id\": " << t.track_id
        << ", \"class\": " << jsonString(t.type) << ", \"visible_frames\": " << t.visible_frames
        << ", \"hits\": " << t.hits << ", \"hit_rate\": " << jsonNumber(t.hitRate())
        << ", \"first_visible\": " << t.first_visible << ", \"first_hit\": " << t.first_hit
        << ", \"delay\": " << (t.delay >= 0 ? std::to_string(t.delay) : "null")
        << ", \"rms_velocity_error\": " << jsonNumber(t.rms_velocity_error)
        << ", \"velocity_samples\": " << t.velocity_samples
        << ", \"first_reported\": " << t.first_reported
        << ", \"first_reported_visible\": " << (t.first_reported_visible ? "true" : "false")
        << ", \"tracked_frames\": " << t.tracked_frames
        << ", \"first_tracked\": " << t.first_tracked
        << ", \"median_speed\": " << jsonNumber(t.median_speed, 3)
        << ", \"extra_moving_frames\": " << t.moving_frames
        << ", \"extra_moving_hit_rate\": " << jsonNumber(t.movingHitRate())
        << ", \"missed_by_reason\": {" << formatReasonCounts(t.missed_by_reason) << "}}";
  }
  out << "\n  ]\n}\n";
  return out.str();
}

std::string formatReasonCounts(const std::map<std::string, int>& counts) {
  std::string out;
  for (const auto& c : counts)
    out += (out.empty() ? "" : ", ") + jsonString(c.first) + ": " + std::to_string(c.second);
  return out;
}

// ------------------------------------------------------------------------------------- chart
namespace {

/** 5x7 glyphs, one string of 7 rows x 5 columns ('#' = ink) per character. */
const char* glyph(char c) {
  static const std::map<char, const char*> font = {
      {'0', " ### #   ##  ### # ###  ##   # ### "}, {'1', "  #   ##    #    #    #    #   ### "},
      {'2', " ### #   #    #   #   #   #   #####"}, {'3', "#####   #   #     #     ##   # ### "},
      {'4', "   #   ##  # # #  # #####   #    # "}, {'5', "######    ####     #    ##   # ### "},
      {'6', "  ##  #   #    #### #   ##   # ### "}, {'7', "#####    #   #   #   #    #    #   "},
      {'8', " ### #   ##   # ### #   ##   # ### "}, {'9', " ### #   ##   # ####    #   #  ##  "},
      {'A', " ### #   ##   #######   ##   ##   #"}, {'B', "#### #   ##   ##### #   ##   ##### "},
      {'C', " ### #   ##    #    #    #   # ### "}, {'D', "###  #  # #   ##   ##   ##  # ###  "},
      {'E', "######    #    #### #    #    #####"}, {'F', "######    #    #### #    #    #    "},
      {'G', " ### #   ##    # ####   ##   # ####"}, {'H', "#   ##   ##   #######   ##   ##   #"},
      {'I', " ###   #    #    #    #    #   ### "}, {'J', "  ###   #    #    #    # #  #  ##  "},
      {'K', "#   ##  # # #  ##   # #  #  # #   #"}, {'L', "#    #    #    #    #    #    #####"},
      {'M', "#   ### ### # ## # ##   ##   ##   #"}, {'N', "#   ##   ###  ## # ##  ###   ##   #"},
      {'O', " ### #   ##   ##   ##   ##   # ### "}, {'P', "#### #   ##   ##### #    #    #    "},
      {'Q', " ### #   ##   ##   ## # ##  #  ## #"}, {'R', "#### #   ##   ##### # #  #  # #   #"},
      {'S', " #####    #     ###     #    ##### "}, {'T', "#####  #    #    #    #    #    #  "},
      {'U', "#   ##   ##   ##   ##   ##   # ### "}, {'V', "#   ##   ##   ##   ##   # # #   #  "},
      {'W', "#   ##   ##   ## # ## # ## # # # # "}, {'X', "#   ##   # # #   #   # # #   ##   #"},
      {'Y', "#   ##   # # #   #    #    #    #  "}, {'Z', "#####    #   #   #   #   #    #####"},
      {'%', "##   ##  #   #   #   #   #  ##   ##"}, {'.', "                          ##   ##  "},
      {'-', "                ###                "}, {':', "      ##   ##        ##   ##       "},
      {'/', "         #   #   #   #   #         "}, {'=', "          #####     #####          "},
      {'(', "   #   #   #    #    #     #     # "}, {')', " #     #     #    #    #   #   #   "},
      {',', "                     ##    #   #   "}, {'_', "                              #####"},
  };
  if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  const auto it = font.find(c);
  return it == font.end() ? nullptr : it->second;
}

struct Canvas {
  int w, h;
  std::vector<unsigned char>& rgb;
  void set(int x, int y, const unsigned char* c) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    for (int k = 0; k < 3; ++k) rgb[3 * (std::size_t(y) * w + x) + k] = c[k];
  }
  void rect(int x0, int y0, int x1, int y1, const unsigned char* c) {
    for (int y = std::min(y0, y1); y <= std::max(y0, y1); ++y)
      for (int x = std::min(x0, x1); x <= std::max(x0, x1); ++x) set(x, y, c);
  }
  /** Text with its top-left corner at (x, y), `scale` pixels per font pixel. */
  void text(int x, int y, const std::string& s, int scale, const unsigned char* c) {
    for (char ch : s) {
      const char* g = glyph(ch);
      if (g)
        for (int r = 0; r < 7; ++r)
          for (int col = 0; col < 5; ++col) {
            const std::size_t idx = std::size_t(r) * 5 + col;
            if (idx < std::char_traits<char>::length(g) && g[idx] == '#')
              rect(x + col * scale, y + r * scale, x + col * scale + scale - 1,
                   y + r * scale + scale - 1, c);
          }
      x += 6 * scale;
    }
  }
};

int textWidth(const std::string& s, int scale) {
  return static_cast<int>(s.size()) * 6 * scale;
}

}  // namespace

void drawHitChart(const DetectionScore& score, const std::string& title, int& width, int& height,
                  std::vector<unsigned char>& rgb) {
  const int n = std::max<int>(1, static_cast<int>(score.targets.size()));
  const int bar = 48, gap = 32, left = 70, right = 30, top = 60, plot_h = 300, bottom = 70;
  width = std::max(left + n * (bar + gap) + right, textWidth(title, 2) + 40);
  width = std::max(width, 480);
  height = top + plot_h + bottom;
  rgb.assign(std::size_t(width) * height * 3, 255);
  Canvas cv{width, height, rgb};
  const unsigned char black[3] = {0, 0, 0}, grid[3] = {215, 215, 215}, blue[3] = {52, 101, 164},
                      grey[3] = {150, 150, 150};
  cv.text(20, 18, title, 2, black);
  const int y0 = top + plot_h;  // y of 0 %
  for (int p = 0; p <= 100; p += 20) {
    const int y = y0 - p * plot_h / 100;
    cv.rect(left, y, width - right, y, grid);
    const std::string label = std::to_string(p);
    cv.text(left - 8 - textWidth(label, 1), y - 3, label, 1, black);
  }
  cv.text(8, top - 16, "HIT %", 1, black);
  cv.rect(left, top, left, y0, black);
  cv.rect(left, y0, width - right, y0, black);
  for (int i = 0; i < static_cast<int>(score.targets.size()); ++i) {
    const auto& t = score.targets[i];
    const int x = left + gap / 2 + i * (bar + gap);
    const double rate = t.hitRate();
    if (std::isfinite(rate)) {
      const int hgt = static_cast<int>(std::lround(rate * plot_h));
      if (hgt > 0) cv.rect(x, y0 - hgt, x + bar - 1, y0 - 1, blue);
      const std::string v = fmt(100.0 * rate, 0);
      cv.text(x + (bar - textWidth(v, 1)) / 2, y0 - hgt - 11, v, 1, black);
    } else {
      cv.text(x + (bar - textWidth("N/A", 1)) / 2, y0 - 11, "N/A", 1, grey);
    }
    const std::string id = std::to_string(t.track_id);
    cv.text(x + (bar - textWidth(id, 1)) / 2, y0 + 8, id, 1, black);
    std::string cls = t.type.substr(0, 10);
    cv.text(x + (bar - textWidth(cls, 1)) / 2, y0 + 20, cls, 1, black);
  }
  char foot[160];
  std::snprintf(foot, sizeof(foot), "MEAN HIT %s %%   FA/FRAME %s   MEDIAN DELAY %s",
                fmt(100.0 * score.mean_hit_rate, 1).c_str(),
                fmt(score.false_alarms_per_frame, 3).c_str(), fmt(score.median_delay, 1).c_str());
  cv.text(left, y0 + 44, foot, 1, black);
}

}  // namespace eval
}  // namespace pcl_movers
