/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/eval/detection_metrics.h>
#include <pcl_movers/eval/mos_metrics.h>

#include <cstdint>
#include <string>
#include <vector>

namespace pcl_movers {
namespace eval {

/** \brief One detection run of the scene corpus: a scene (family, seed, sensor) in one tracker
 * mode, scored with scoreDetections(). */
struct CorpusRun {
  std::string family;
  std::uint64_t seed = 0;
  std::string sensor;
  std::string mode;  ///< "registration" or "centroid"
  int frames = 0;
  int blind_frames = 0;
  bool ok = false;     ///< false: pcl_movers_detect failed; every target counts as missed
  std::string error;   ///< its last error line when !ok
  double seconds = 0;  ///< wall time of the detection
  DetectionScore score;
  /** Per-point moving labels (pcl_movers_detect --point-labels) scored against the scene's
   * labels as SemanticKITTI-MOS does (scoreMosFolders()); has_mos false when not scored. */
  MosCounts mos;
  bool has_mos = false;
  std::string scene() const { return family + "-" + std::to_string(seed); }
};

/** \brief Speed bands of the report [m/s]: < 1, 1-2, 2-5, 5-15, > 15. */
std::string speedBand(double speed);

/** \brief Why a target was missed or hit late, for the worst-targets table:
 * - "never its own object": no row of tracks.csv (mover or not) in its box in any visible frame:
 *   segmentation merged it into something else, or it was never tracked;
 * - "tracked, never a mover": tracked as its own object but never declared a mover, followed
 *   by ": REASON", the decision test its rows failed most often (TargetScore::missed_by_reason);
 * - "late (N frames)": first hit more than `late_frames` frames after it became visible;
 * - "intermittent": hit, in time, but in under half of its frames; else "missed N frames";
 * - "run failed" when the run did not finish. */
std::string missReason(const TargetScore& target, bool run_ok, int late_frames = 10);

/** \brief Options of the corpus report. */
struct CorpusReportOptions {
  std::string title = "Scene corpus";
  std::string command;      ///< the command line that made it, quoted in the report
  double wall_seconds = 0;  ///< the whole command (generation, detection, scoring)
  double generate_seconds = 0;
  int cores = 1;
  int worst = 20;        ///< rows of the worst-targets table
  int late_frames = 10;  ///< a first hit later than this is "late"
};

/** \brief The Markdown report: overall, per family, per sensor, per class and per speed band,
 * registration and centroid side by side; the worst targets with their scene and why they were
 * missed; failed runs. Deterministic for the same runs (only the times quoted change). */
std::string formatCorpusReport(const std::vector<CorpusRun>& runs,
                               const CorpusReportOptions& options);

/** \brief One JSON object per run (one line each) with the per-target scores, for scripts. */
std::string formatCorpusJson(const std::vector<CorpusRun>& runs);

}  // namespace eval
}  // namespace pcl_movers
