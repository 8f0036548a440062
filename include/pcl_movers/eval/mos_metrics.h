/*
 * Moving-object segmentation (MOS) scoring of per-point labels, as SemanticKITTI-MOS scores it:
 * SemanticKITTI `.label` files (class in the low 16 bits) of ground truth and prediction.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace pcl_movers {
namespace eval {

/** \brief SemanticKITTI's moving classes: 251 moving, 252 moving-car, 253 moving-bicyclist,
 * 254 moving-person, 255 moving-motorcyclist, 256 moving-on-rails, 257 moving-bus, 258
 * moving-truck, 259 moving-other-vehicle. */
inline bool isMovingClass(std::uint16_t cls) {
  return cls >= 251 && cls <= 259;
}

/** \brief Ground-truth classes that are not scored: 0 unlabeled and 1 outlier (SemanticKITTI-MOS's
 * learning map sends both to "unlabeled", which its evaluation ignores). */
inline bool isUnscoredClass(std::uint16_t cls) {
  return cls <= 1;
}

/** \brief Point counts of one or more frames, by ground truth (moving / static, points with an
 * unscored ground-truth class left out) and prediction (moving, static, or 0 = no label).
 *
 * As SemanticKITTI-MOS (semantic-kitti-api, ignore = [0]): moving IoU = TP / (TP + FP + FN) with
 * TP = moving predicted moving, FP = static predicted moving, FN = moving predicted static or 0;
 * static IoU likewise for the static class (a 0 prediction on a static point is a static FN).
 * Predictions on points whose ground truth is unscored do not count at all. */
struct MosCounts {
  std::uint64_t moving_as_moving = 0, moving_as_static = 0, moving_as_none = 0;
  std::uint64_t static_as_moving = 0, static_as_static = 0, static_as_none = 0;
  std::uint64_t unscored = 0;  ///< points whose ground-truth class is unscored

  std::uint64_t tp() const { return moving_as_moving; }
  std::uint64_t fp() const { return static_as_moving; }
  std::uint64_t fn() const { return moving_as_static + moving_as_none; }
  std::uint64_t movingTruth() const { return moving_as_moving + moving_as_static + moving_as_none; }
  std::uint64_t movingPredicted() const { return moving_as_moving + static_as_moving; }
  std::uint64_t staticTruth() const { return static_as_moving + static_as_static + static_as_none; }
  std::uint64_t scored() const { return movingTruth() + staticTruth(); }
  /** \brief TP / (TP + FP + FN) of the moving class; NaN when that sum is 0 (nothing moving in
   * the ground truth and nothing predicted moving). */
  double movingIou() const;
  /** \brief The same for the static class. */
  double staticIou() const;
  MosCounts& operator+=(const MosCounts& o);
};

/** \brief Counts of one frame. `prediction` empty means "no prediction" (every scored point an
 * FN of its class). Throws InputError naming `prediction_name` when the point counts differ. */
MosCounts scoreMosFrame(const std::vector<std::uint32_t>& truth,
                        const std::vector<std::uint32_t>& prediction,
                        const std::string& prediction_name = "prediction");

/** \brief One scored frame of a folder pair. */
struct MosFrame {
  std::string name;  ///< file name without `.label`
  MosCounts counts;
};

/** \brief All frames of a folder pair and their sum. */
struct MosScore {
  std::vector<MosFrame> frames;  ///< in the ground truth's (numeric) file order
  MosCounts total;
  std::vector<std::string> unmatched_predictions;  ///< prediction files without ground truth
};

/** \brief Scores every `*.label` of `truth_dir` against the same name in `prediction_dir`.
 * An empty `prediction_dir` scores as if nothing was predicted (a failed run). Throws InputError
 * for a missing folder, a ground-truth folder without `.label` files, a prediction missing for a
 * ground-truth frame (naming it), or differing point counts (naming the prediction file).
 * Prediction files without ground truth are listed, not scored. */
MosScore scoreMosFolders(const std::string& truth_dir, const std::string& prediction_dir);

/** \brief Markdown: the moving and static IoU with their counts, and a per-frame summary. */
std::string formatMosMarkdown(const MosScore& score);

/** \brief The score as JSON, per-frame counts included. */
std::string formatMosJson(const MosScore& score);

}  // namespace eval
}  // namespace pcl_movers
