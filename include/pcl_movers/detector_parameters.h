/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>
#include <pcl_movers/ground_parameters.h>
#include <pcl_movers/parameter_io.h>
#include <pcl_movers/segmentation_parameters.h>
#include <pcl_movers/tracker_parameters.h>

#include <pcl/console/print.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace pcl_movers {

/** \brief Every setting of the mover-detection pipeline: one struct per stage, each with its
 * defaults, read by the stage's class, its tool and the pipeline alike.
 *
 * MoverDetector and MoverTracker read it; `pcl_movers_detect -h` prints it (through
 * forEachParameter(), so the help can never drift from the defaults) and `--config FILE` /
 * `--<key> VALUE` set it. Keys are `stage.member` (`ground.distance`, `track.gate_sigmas`);
 * sensor and deskew, which concern the input, have none. The flat keys of earlier versions
 * (`ground_distance`, `mover_speed`) are still read, see legacyKeys().
 */
struct DetectorParameters {
  /// Beam layout used to organize unorganized scans: auto (estimated from the first scan with
  /// enough returns; a known preset's calibration when its beams are recognized, see
  /// SensorModel::recognize()), or a preset: hdl64, hdl32, vlp16, os1_64, ladar2d. Organized scans
  /// keep their own rows and columns.
  std::string sensor = "auto";
  /// De-skewing of scans whose PCD carries per-point times (`time`, `t`, `timestamp`): each point
  /// moved into the sensor frame at the frame time by the ego motion interpolated between this
  /// frame's pose and the previous one's (ScanDeskewer). auto = when the frames carry times and
  /// the poses are known, on = required (an error otherwise), off = never. Off by default: the
  /// tracker still takes every cluster at the frame time, and de-skewed movers then sit up to
  /// 0.1 s · their speed from where the frame time has them (generated highway scenes: false
  /// alarms 0.03 -> 0.63 per frame; docs/reliability.md, "De-skewing").
  std::string deskew = "off";

  GroundParameters ground;              ///< ground.*: GroundPlaneFilter
  SegmentationParameters segment;       ///< segment.*: RangeImageRegionGrowing
  RegistrationParameters registration;  ///< registration.*: a cluster against a track's model
  TrackParameters track;                ///< track.*: association, Kalman filter, lifecycle
  DecisionParameters decision;          ///< decision.*: which tracks are movers
  FreeSpaceParameters free_space;       ///< free_space.*: the free-space evidence

  /** \brief Calls `f(key, member, description)` for every parameter (double, int, bool or
   * string), with `key` a std::string "stage.member". */
  template <typename F>
  void forEachParameter(F&& f);
  template <typename F>
  void forEachParameter(F&& f) const {
    const_cast<DetectorParameters*>(this)->forEachParameter(f);
  }
  /** \brief Calls `f(key, member, description)` for every constant of the stages' rules: values
   * measured once and fixed (the stage structs say why), members but not keys. A config line
   * that sets one to its value is ignored with a warning, to any other value is an error. */
  template <typename F>
  void forEachConstant(F&& f);
  template <typename F>
  void forEachConstant(F&& f) const {
    const_cast<DetectorParameters*>(this)->forEachConstant(f);
  }

  /** \brief Calls `g(prefix, stage)` for every stage struct, in key order ("ground", ground). */
  template <typename G>
  void forEachStage(G&& g);

  /** \brief Sets `key` (`stage.member`; '-' for '_' also works; a legacy flat key is mapped)
   * from text; throws InputError("where: ...") for an unknown key or an invalid value. */
  void set(const std::string& key, const std::string& value, const std::string& where);
  /** \brief Reads `key = value` lines ('#' comments and blank lines allowed); unknown keys and
   * malformed lines throw InputError with file:line. */
  void readConfig(const std::string& path);
  /** \brief Checks ranges (positive sizes etc.); throws InputError naming the key. */
  void validate() const;
  /** \brief All keys (settings, not constants), for the tool's argument checking. */
  std::vector<std::string> keys() const;
  /** \brief `key = value` lines (a config file the tool can read back). */
  std::string toConfig() const;
  /** \brief A JSON object with every parameter. */
  std::string toJson() const;
  /** \brief The flat keys of earlier versions and the key each is now (ground_distance ->
   * ground.distance), for configs and command lines written before the stages had structs. */
  static const std::vector<std::pair<std::string, std::string>>& legacyKeys();
  /** \brief The current key of `key` (snake_case): itself, or what legacyKeys() maps it to. */
  static std::string canonicalKey(const std::string& key);
};

// --------------------------------------------------------------------------- implementation
namespace detail {
/** \brief `f` behind the stage prefix: called as `f("prefix.key", member, doc)` by a stage's
 * forEachParameter() or forEachConstant(), which pass `key`. */
template <typename F>
auto prefixed(const char* prefix, F& f) {
  return [prefix, &f](const char* key, auto& member, const char* doc) {
    f(std::string(prefix) + "." + key, member, doc);
  };
}
}  // namespace detail

template <typename G>
void DetectorParameters::forEachStage(G&& g) {
  g("ground", ground);
  g("segment", segment);
  g("registration", registration);
  g("track", track);
  g("decision", decision);
  g("free_space", free_space);
}

template <typename F>
void DetectorParameters::forEachParameter(F&& f) {
  f(std::string("sensor"), sensor,
    "layout of unorganized scans: auto, hdl64, hdl32, vlp16, os1_64, ladar2d");
  f(std::string("deskew"), deskew, "per-point-time de-skewing with the ego motion: auto, on, off");
  forEachStage([&](const char* prefix, auto& stage) {
    stage.forEachParameter(detail::prefixed(prefix, f));
  });
}

template <typename F>
void DetectorParameters::forEachConstant(F&& f) {
  forEachStage(
      [&](const char* prefix, auto& stage) { stage.forEachConstant(detail::prefixed(prefix, f)); });
}

inline const std::vector<std::pair<std::string, std::string>>& DetectorParameters::legacyKeys() {
  static const std::vector<std::pair<std::string, std::string>> keys{
      {"sensor_height", "ground.sensor_height"},
      {"ground_distance", "ground.distance"},
      {"ground_max_slope_deg", "ground.max_slope_deg"},
      {"ground_local_slope", "ground.local_slope"},
      {"depth_ratio", "segment.depth_ratio"},
      {"depth_min", "segment.depth_min"},
      {"max_gap", "segment.max_gap"},
      {"row_bridge", "segment.row_bridge"},
      {"min_cluster_points", "segment.min_cluster_points"},
      {"max_range", "track.max_range"},
      {"density_resolution", "registration.resolution"},
      {"density_resolution_z", "registration.resolution_z"},
      {"density_cells_xy", "registration.cells_xy"},
      {"density_cells_z", "registration.cells_z"},
      {"sigma_per_metre", "registration.sigma_per_metre"},
      {"min_sigma", "registration.min_sigma"},
      {"yaw_samples", "registration.yaw_samples"},
      {"turn_yaw_samples", "registration.turn_yaw_samples"},
      {"turn_yaw_step_deg", "registration.turn_yaw_step_deg"},
      {"turn_min_gain", "registration.turn_min_gain"},
      {"min_similarity", "registration.min_similarity"},
      {"max_registration_points", "registration.max_points"},
      {"young_search_radius", "registration.young_search_radius"},
      {"model_half_life", "registration.model_half_life"},
      {"registration_stop_similarity", "registration.stop_similarity"},
      {"mode", "track.mode"},
      {"acceleration_noise", "track.acceleration_noise"},
      {"acceleration_limit", "track.acceleration_limit"},
      {"registration_sigma", "track.registration_sigma"},
      {"centroid_sigma", "track.centroid_sigma"},
      {"measurement_sigma_per_metre", "track.measurement_sigma_per_metre"},
      {"measurement_sigma_from_scatter", "track.sigma_from_scatter"},
      {"manoeuvre_window", "track.manoeuvre_window"},
      {"manoeuvre_sigmas", "track.manoeuvre_sigmas"},
      {"static_refresh_frames", "track.static_refresh_frames"},
      {"static_shift", "track.static_shift"},
      {"static_clearance", "track.static_clearance"},
      {"initial_velocity_sigma", "track.initial_velocity_sigma"},
      {"gate_sigmas", "track.gate_sigmas"},
      {"gate_margin", "track.gate_margin"},
      {"max_gate_radius", "track.max_gate_radius"},
      {"max_missed_frames", "track.max_missed_frames"},
      {"max_tracks", "track.max_tracks"},
      {"velocity_fit_init", "track.velocity_fit_init"},
      {"occluded_fraction", "track.occluded_fraction"},
      {"occluded_skip", "track.occluded_skip"},
      {"split_merged", "track.split_merged"},
      {"split_claim_distance", "track.split_claim_distance"},
      {"split_min_speed_difference", "track.split_min_speed_difference"},
      {"reacquire_velocity", "track.reacquire_velocity"},
      {"reacquire_velocity_sigma", "track.reacquire_velocity_sigma"},
      {"hold_confirmed", "track.hold_confirmed"},
      {"max_mover_length", "decision.max_length"},
      {"max_mover_height", "decision.max_height"},
      {"min_mover_height", "decision.min_height"},
      {"mover_speed", "decision.speed"},
      {"mover_speed_sigmas", "decision.speed_sigmas"},
      {"fast_from_fit", "decision.fast_from_fit"},
      {"slow_window", "decision.slow_window"},
      {"slow_speed", "decision.slow_speed"},
      {"mover_window", "decision.window"},
      {"mover_votes", "decision.votes"},
      {"mover_min_age", "decision.min_age"},
      {"displacement_ratio", "decision.displacement_ratio"},
      {"confirm_false_rate", "decision.confirm_false_rate"},
      {"confirm_sigma_floor", "decision.confirm_sigma_floor"},
      {"confirm_min_similarity", "decision.confirm_min_similarity"},
      {"confirm_min_points", "decision.confirm_min_points"},
      {"confirm_free_space_votes", "decision.confirm_free_space_votes"},
      {"mover_latch", "decision.latch"},
      {"standing_height_from_occluder", "decision.standing_height"},
      {"decision.standing_height_from_occluder", "decision.standing_height"},
      {"free_space_lag", "free_space.lag"},
      {"free_space_long_lag", "free_space.long_lag"},
      {"free_space_long_min_fraction", "free_space.long_min_fraction"},
      {"free_space_min_fraction", "free_space.min_fraction"},
      {"free_space_min_points", "free_space.min_points"},
      {"free_space_votes", "free_space.votes"},
      {"free_space_margin", "free_space.margin"},
      {"free_space_margin_per_metre", "free_space.margin_per_metre"},
      {"free_space_no_return", "free_space.no_return"},
  };
  return keys;
}

inline std::string DetectorParameters::canonicalKey(const std::string& key) {
  std::string snake = key;  // the command line's spelling, ground.max-slope-deg, is accepted too
  for (char& c : snake)
    if (c == '-') c = '_';
  for (const auto& legacy : legacyKeys())
    if (legacy.first == snake) return legacy.second;
  return snake;
}

inline void DetectorParameters::set(const std::string& key, const std::string& value,
                                    const std::string& where) {
  const std::string canonical = canonicalKey(key);
  bool found = false;
  forEachParameter([&](const std::string& k, auto& member, const char*) {
    if (canonical == k) {
      detail::parseValue(detail::trim(value), member, key, where);
      found = true;
    }
  });
  if (found) return;
  // A constant (a key of earlier versions): its own value is harmless, any other is not what
  // this version runs with.
  forEachConstant([&](const std::string& k, const auto& member, const char*) {
    if (canonical != k) return;
    found = true;
    auto given = member;
    detail::parseValue(detail::trim(value), given, key, where);
    const std::string fixed = detail::formatValue(member);
    if (detail::formatValue(given) != fixed)
      throw InputError(where + ": '" + key + "' is no longer a setting: its rule uses " + fixed +
                       " (docs/design.md, Settings)");
    PCL_WARN("%s: '%s' is no longer a setting (fixed at %s); ignored\n", where.c_str(), key.c_str(),
             fixed.c_str());
  });
  if (!found) throw InputError(where + ": unknown parameter '" + key + "'");
}

inline void DetectorParameters::readConfig(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open config file");
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    line = detail::trim(line);
    if (line.empty()) continue;
    const auto eq = line.find('=');
    const std::string where = path + ":" + std::to_string(number);
    if (eq == std::string::npos) throw InputError(path, number, "expected 'key = value'");
    const std::string key = detail::trim(line.substr(0, eq));
    std::string snake = key;
    for (char& c : snake)
      if (c == '-') c = '_';
    const std::string canonical = canonicalKey(key);
    if (canonical != snake)
      PCL_WARN("%s: '%s' is a key of earlier versions, use '%s'\n", where.c_str(), key.c_str(),
               canonical.c_str());
    set(key, line.substr(eq + 1), where);
  }
}

inline void DetectorParameters::validate() const {
  auto positive = [](const char* key, double v) {
    if (!(v > 0)) throw InputError(std::string("parameter ") + key + " must be > 0");
  };
  ground.validate("parameter ground.");
  segment.validate("parameter segment.");
  if (deskew != "auto" && deskew != "on" && deskew != "off")
    throw InputError("parameter deskew must be auto, on or off (not '" + deskew + "')");
  positive("track.max_range", track.max_range);
  positive("registration.resolution", registration.resolution);
  positive("registration.resolution_z", registration.resolution_z);
  positive("registration.cells_xy", registration.cells_xy);
  positive("registration.cells_z", registration.cells_z);
  positive("registration.sigma_per_metre", registration.sigma_per_metre);
  positive("registration.min_sigma", registration.min_sigma);
  positive("registration.yaw_samples", registration.yaw_samples);
  positive("registration.turn_yaw_samples", registration.turn_yaw_samples);
  positive("registration.turn_yaw_step_deg", registration.turn_yaw_step_deg);
  if (!(registration.turn_min_gain >= 0 && registration.turn_min_gain <= 1))
    throw InputError("parameter registration.turn_min_gain must be in [0, 1]");
  positive("registration.model_half_life", registration.model_half_life);
  positive("registration.max_points", registration.max_points);
  positive("registration.young_search_radius", registration.young_search_radius);
  positive("track.acceleration_limit", track.acceleration_limit);
  positive("track.registration_sigma", track.registration_sigma);
  positive("track.centroid_sigma", track.centroid_sigma);
  positive("registration.stop_similarity", registration.stop_similarity);
  positive("track.initial_velocity_sigma", track.initial_velocity_sigma);
  positive("track.gate_sigmas", track.gate_sigmas);
  positive("track.max_gate_radius", track.max_gate_radius);
  positive("track.max_tracks", track.max_tracks);
  positive("decision.window", decision.window);
  positive("track.split_claim_distance", track.split_claim_distance);
  if (!(track.split_min_speed_difference >= 0))
    throw InputError("parameter track.split_min_speed_difference must be >= 0");
  positive("track.static_refresh_frames", track.static_refresh_frames);
  if (!(track.static_clearance >= 0))
    throw InputError("parameter track.static_clearance must be >= 0");
  positive("decision.votes", decision.votes);
  if (decision.votes > decision.window)
    throw InputError("parameter decision.votes must not exceed decision.window");
  if (registration.min_similarity < 0 || registration.min_similarity > 1)
    throw InputError("parameter registration.min_similarity must be in [0, 1]");
  if (free_space.lag < 0 || free_space.lag > 50)
    throw InputError("parameter free_space.lag must be in [0, 50]");
  if (free_space.long_lag < 0 || free_space.long_lag > 50)
    throw InputError("parameter free_space.long_lag must be in [0, 50]");
  if (free_space.long_min_fraction < 0 || free_space.long_min_fraction > 1)
    throw InputError("parameter free_space.long_min_fraction must be in [0, 1]");
  if (free_space.min_fraction < 0 || free_space.min_fraction > 1)
    throw InputError("parameter free_space.min_fraction must be in [0, 1]");
  if (free_space.votes < 1) throw InputError("parameter free_space.votes must be >= 1");
  if (free_space.min_points < 1) throw InputError("parameter free_space.min_points must be >= 1");
  if (free_space.margin < 0 || free_space.margin_per_metre < 0)
    throw InputError("parameters free_space.margin(_per_metre) must be >= 0");
  if (!(free_space.porous_roughness >= 0))
    throw InputError("parameter free_space.porous_roughness must be >= 0");
  if (!(free_space.lag_margins >= 0))
    throw InputError("parameter free_space.lag_margins must be >= 0");
  if (decision.confirm_false_rate < 0 || decision.confirm_false_rate >= 1)
    throw InputError("parameter decision.confirm_false_rate must be in [0, 1)");
  positive("decision.confirm_sigma_floor", decision.confirm_sigma_floor);
  if (track.occluded_fraction < 0 || track.occluded_fraction > 1)
    throw InputError("parameter track.occluded_fraction must be in [0, 1]");
  positive("track.reacquire_velocity_sigma", track.reacquire_velocity_sigma);
  if (track.occluded_skip < 0) throw InputError("parameter track.occluded_skip must be >= 0");
  if (decision.confirm_min_similarity < 0 || decision.confirm_min_similarity > 1)
    throw InputError("parameter decision.confirm_min_similarity must be in [0, 1]");
  if (decision.confirm_min_points < 1)
    throw InputError("parameter decision.confirm_min_points must be >= 1");
  if (decision.confirm_free_space_votes < 1)
    throw InputError("parameter decision.confirm_free_space_votes must be >= 1");
  if (track.manoeuvre_window < 4) throw InputError("parameter track.manoeuvre_window must be >= 4");
  positive("track.manoeuvre_sigmas", track.manoeuvre_sigmas);
  if (track.max_missed_frames < 0)
    throw InputError("parameter track.max_missed_frames must be >= 0");
  if (track.mode != "registration" && track.mode != "centroid")
    throw InputError("parameter track.mode must be 'registration' or 'centroid', not '" +
                     track.mode + "'");
}

inline std::vector<std::string> DetectorParameters::keys() const {
  std::vector<std::string> k;
  forEachParameter([&](const std::string& key, const auto&, const char*) { k.push_back(key); });
  return k;
}

inline std::string DetectorParameters::toConfig() const {
  std::string out;
  forEachParameter([&](const std::string& key, const auto& v, const char* doc) {
    out += key + " = " + detail::formatValue(v) + "  # " + doc + "\n";
  });
  out += "\n# Constants of the rules: fixed, not settings (docs/design.md, Settings).\n";
  forEachConstant([&](const std::string& key, const auto& v, const char* doc) {
    out += "# " + key + " = " + detail::formatValue(v) + "  # " + doc + "\n";
  });
  return out;
}

inline std::string DetectorParameters::toJson() const {
  std::string out = "{";
  bool first = true;
  const auto add = [&](const std::string& key, const auto& v, const char*) {
    out += std::string(first ? "" : ", ") + "\"" + key + "\": " + detail::jsonValue(v);
    first = false;
  };
  // The constants too: summary.json records every value the run used.
  forEachParameter(add);
  forEachConstant(add);
  return out + "}";
}

}  // namespace pcl_movers
