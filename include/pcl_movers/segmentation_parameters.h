/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/parameter_io.h>

#include <string>

namespace pcl_movers {

/** \brief The settings of range-image segmentation (RangeImageRegionGrowing), with their
 * defaults: the one source of them for the class, `pcl_movers_segment`,
 * `pcl_movers_eval_segmentation` and the detector (`segment.*` keys of DetectorParameters). */
struct SegmentationParameters {
  /// Region growing joins range-image neighbours whose depth differs by less than
  /// depth_ratio · range (the paper's d_T proportional to depth). 0.05: at 0.03, which splits
  /// SemanticKITTI's objects from each other more often (merged 32.9 -> 22.4 %), the tune split
  /// of the scene corpus had more fragments and false alarms (0.032 -> 0.054 per frame; hit rate
  /// 67.1 -> 69.3 %).
  double depth_ratio = 0.05;

  /// Lower bound on that depth threshold [m] (near objects).
  double depth_min = 0.1;

  /// Empty range-image cells bridged by region growing in each direction (0 = strict 8-neighbour).
  int max_gap = 2;

  /// Longest gap bridged along a range-image row past empty and nearer cells [m]
  /// (RangeImageRegionGrowing::setBridgeLength; 0 = off). Off: 0.5 recovers more SemanticKITTI
  /// objects (92.9 -> 96.5 %) but lowered the mean hit rate on simulated urban by 1.6 points (a
  /// cyclist joined to its surroundings), and KITTI 0000 did not change.
  double row_bridge = 0.0;

  /// Clusters with fewer points are ignored (noise, too small to track). 8, two under the 10 box
  /// points of a scored target (docs/design_history.md): the ground filter takes a far walker's
  /// feet, so a 10-12-point pedestrian at 45-60 m left 8-10-point clusters, and at 10 its track was
  /// born or lost every other frame (open pedestrian 5 confirmed 18 frames after it became visible,
  /// 7 at 8).
  int min_cluster_points = 8;

  /// A cluster touching a mover's in the range image and lying within the mover's box grown by
  /// this much [m] is a part of the mover that region growing split off at a range step (a car's
  /// wheels, a walker's legs): its points are labelled moving with it (findMoverFragments). The
  /// box is one view's, and the view often misses an edge of the object that a fragment shows.
  /// 0.5, chosen on the scene corpus's tune split: moving-point IoU 84.3 / 84.7 / 85.0 % with
  /// 0.25 / 0.5 / 1.0 m, the parking family 77.7 / 78.4 / 78.0 %.
  double fragment_margin = 0.5;

  /** \brief Throws InputError naming the first setting out of its range; `prefix` names the
   * settings ("--" for a tool's options, "parameter segment." for the detector's keys). */
  void validate(const std::string& prefix) const {
    auto fail = [&](const char* key, const char* rule) {
      throw InputError(detail::parameterName(prefix, key) + " must be " + rule);
    };
    if (!(depth_ratio > 0)) fail("depth_ratio", "> 0");
    if (!(depth_min >= 0)) fail("depth_min", ">= 0");
    if (max_gap < 0 || max_gap > 64) fail("max_gap", "in 0..64");
    if (!(row_bridge >= 0)) fail("row_bridge", ">= 0");
    if (min_cluster_points < 1) fail("min_cluster_points", ">= 1");
    if (!(fragment_margin >= 0)) fail("fragment_margin", ">= 0");
  }

  /** \brief Calls `f(key, member, description)` for every setting. */
  template <typename F>
  void forEachParameter(F&& f) {
    f("depth_ratio", depth_ratio, "region growing depth threshold d_T / range");
    f("depth_min", depth_min, "lower bound of d_T [m]");
    f("max_gap", max_gap, "empty range-image cells bridged by region growing");
    f("min_cluster_points", min_cluster_points, "clusters with fewer points are ignored");
  }

  /** \brief Calls `f(key, member, description)` for every constant of this stage's rules:
   * values measured once and fixed, not settings (docs/design.md, "Settings"). They stay
   * members so that the unit tests of a rule, and library users studying it, can vary them. */
  template <typename F>
  void forEachConstant(F&& f) {
    f("row_bridge", row_bridge, "gap bridged along a row past empty and nearer cells [m], 0 = off");
    f("fragment_margin", fragment_margin,
      "a mover's fragment lies within its box grown by this much [m]");
  }
};

}  // namespace pcl_movers
