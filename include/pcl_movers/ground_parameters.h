/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/parameter_io.h>

#include <string>

namespace pcl_movers {

/** \brief The settings of ground removal (GroundPlaneFilter), with their defaults: the one source
 * of them for the filter, `pcl_movers_ground`, `pcl_movers_segment`,
 * `pcl_movers_eval_segmentation` and the detector (`ground.*` keys of DetectorParameters).
 *
 * The defaults were chosen for mover detection on the tune split of the scene corpus
 * (docs/design.md, decision log): 0.1 m with the local-slope test kept every point of a person's
 * or car's lower 0.25 m that the 0.25 m plane-only test called ground (moving-point IoU 77.1 ->
 * 81.2 %, hit rate 67.1 -> 67.2 %, false alarms 0.032 -> 0.035 per frame); a 10° plane tilt
 * instead of 15° gave urban scenes 0.11 false alarms per frame instead of 0.02.
 */
struct GroundParameters {
  /// Height of the sensor above the ground under it [m] (KITTI's HDL-64E: 1.73); the innermost
  /// cells start from a horizontal plane this far below the cloud's sensor origin. 0: estimated
  /// from each scan (the deepest dense layer of returns within 15 m below the sensor): mounting
  /// heights differ by a metre between vehicles (the corpus: 1.54-2.47 m), and a plane started
  /// 0.7 m too high on rolling terrain lost a fifth of the ground (docs/design.md, decision log).
  double sensor_height = 0.0;
  /// Points closer than this to their cell's plane are ground [m].
  double distance = 0.1;
  /// Steepest plane still taken for ground [deg]; steeper fits inherit the inner cell's plane.
  double max_slope_deg = 15.0;
  /// Equal azimuth sectors of the polar cells.
  int sectors = 32;
  /// The column local-slope test on organized (range-image) input: a point within `distance`
  /// of its plane is still not ground when the beam above or below it rises more steeply than
  /// `local_slope_deg` (the lowest centimetres of bushes, wall bases and people's feet).
  bool local_slope = true;
  /// Steepest rise to a column neighbour still ground [deg].
  double local_slope_deg = 20.0;
  /// Height noise forgiven by the local-slope test [m] (the HDL-64E's range noise).
  double range_noise = 0.02;
  /// Column neighbours further than this from their plane are objects standing on the ground and
  /// take no part in the local-slope test [m].
  double slope_band = 0.3;

  /** \brief Throws InputError naming the first setting out of its range; `prefix` names the
   * settings ("--" for a tool's options, "parameter ground." for the detector's keys). */
  void validate(const std::string& prefix) const {
    auto fail = [&](const char* key, const char* rule) {
      throw InputError(detail::parameterName(prefix, key) + " must be " + rule);
    };
    if (!(sensor_height >= 0)) fail("sensor_height", ">= 0");
    if (!(distance > 0)) fail("distance", "> 0");
    if (!(max_slope_deg >= 0 && max_slope_deg < 90)) fail("max_slope_deg", "in [0, 90)");
    if (sectors < 1 || sectors > 4096) fail("sectors", "in 1..4096");
    if (!(local_slope_deg >= 0 && local_slope_deg < 90)) fail("local_slope_deg", "in [0, 90)");
    if (!(range_noise >= 0)) fail("range_noise", ">= 0");
    if (!(slope_band >= 0)) fail("slope_band", ">= 0");
  }

  /** \brief Calls `f(key, member, description)` for every setting (the keys of the `ground.*`
   * parameters and of the tools' options). */
  template <typename F>
  void forEachParameter(F&& f) {
    f("sensor_height", sensor_height,
      "sensor height above the ground under it [m]; 0 = estimated from each scan");
    f("distance", distance, "ground if within this of its cell's plane [m]");
    f("max_slope_deg", max_slope_deg, "steepest plane taken for ground [deg]");
    f("local_slope", local_slope, "column local-slope test on organized scans");
    f("local_slope_deg", local_slope_deg, "steepest rise to a column neighbour still ground [deg]");
  }

  /** \brief Calls `f(key, member, description)` for every constant of this stage's rules:
   * values measured once and fixed, not settings (docs/design.md, "Settings"). They stay
   * members so that the unit tests of a rule, and library users studying it, can vary them. */
  template <typename F>
  void forEachConstant(F&& f) {
    f("sectors", sectors, "azimuth sectors of the polar cells");
    f("range_noise", range_noise, "height noise forgiven by the local-slope test [m]");
    f("slope_band", slope_band,
      "column neighbours further than this from their plane are ignored "
      "by the local-slope test [m]");
  }
};

}  // namespace pcl_movers
