/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/eval/kitti_dont_care.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/tracks.h>

#include <Eigen/Geometry>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace pcl_movers {
namespace eval {

/** \brief Parameters of the detection scoring (DESIGN.md "Metrics"). Defaults are the KITTI ones.
 */
struct DetectionMetricsParams {
  /** \brief Half-width of the scored sector around +x [deg]: 40 for KITTI labels (camera field of
   * view), 180 for fully labelled (simulated) scenes. */
  double sector_deg = 40.0;
  /** \brief A target is visible in a frame only with at least this many scan points in its box. */
  int min_points = 10;
  /** \brief Growth of the target box in length and in width [m] (total, half on each side) before
   * a detection centroid is tested against it. */
  double grow_xy = 1.0;
  /** \brief Growth of the box height [m]; DESIGN grows length and width only. */
  double grow_z = 0.0;
  /** \brief Number of frames of the sequence for false alarms per frame; 0 = the number of distinct
   * frames that appear in objects.txt or tracks.csv (which can only undercount, so the rate is
   * never flattered). */
  int frames = 0;
  /** \brief Half-window [frames] of the least-squares line fit used to derive ground-truth world
   * velocities from box centres when poses are given (labelled box centres jitter by a few cm;
   * a plain two-frame difference would turn that into tenths of m/s). */
  int velocity_half_window = 2;
  /** \brief Extra variant, NOT the DESIGN metric (reported next to it): hit rates over the
   * visible frames in which the target's own speed (objects.txt `speed_mps`) is at least this
   * [m/s]. DESIGN counts every visible frame of a track whose moving flag is 1, including frames
   * where it stands still (the open scene's van waits ~40 frames before driving off), which no
   * detector of motion can hit before it has seen the object move. */
  double moving_speed = 0.5;
  /** \brief KITTI DontCare regions (none by default). A `mover` row in the sector that lies in no
   * target's grown box and no labelled object's box, and whose centroid projects into a DontCare
   * box of its frame, is ignored: neither a hit nor a false alarm (DetectionScore::
   * dont_care_ignored). As in KITTI's devkit, rows are matched to the labelled objects first, so a
   * DontCare box that overlaps a target in the image never takes a hit away. */
  std::shared_ptr<const DontCareRegions> dont_care;
};

/** \brief Per-target result. */
struct TargetScore {
  int track_id = 0;
  std::string type;
  int visible_frames = 0;
  int hits = 0;
  int first_visible = -1;  ///< frame, -1 when never visible
  int first_hit = -1;      ///< frame, -1 when never hit
  /** \brief First frame in which a `mover` row lies in the target's grown box, counting every
   * labelled frame of the target (outside the scored sector and under min_points too); -1 when
   * never. Not a DESIGN metric: it tells whether a target was reported at all, e.g. KITTI's
   * pedestrian, labelled for 6 frames of which only the first 4 fall inside the ±40° sector. */
  int first_reported = -1;
  /** \brief Whether the first_reported frame was a visible (scored) one. */
  bool first_reported_visible = false;
  /** \brief first_hit - first_visible [frames]; -1 when never hit. */
  int delay = -1;
  /** \brief RMS velocity error over hits with a ground-truth velocity [m/s]; NaN when none. */
  double rms_velocity_error = std::numeric_limits<double>::quiet_NaN();
  int velocity_samples = 0;
  /** \brief Extra variant (see DetectionMetricsParams::moving_speed): visible frames with the
   * target's speed >= moving_speed, and the hits among them. */
  int moving_frames = 0;
  int moving_hits = 0;
  /** \brief Diagnostic: visible frames in which some row of tracks.csv, mover or not, has its
   * centroid in the target's grown box (the target was segmented and tracked as an object). */
  int tracked_frames = 0;
  /** \brief Diagnostic: first visible frame counted in tracked_frames; -1 when never. */
  int first_tracked = -1;
  /** \brief Diagnostic: the visible frames without a hit, by why: the tracks.csv `reason` of the
   * row in the grown box nearest its centre (the mover decision's test that row failed;
   * "unknown" for files without the column), or "no row" when no row is in the box. */
  std::map<std::string, int> missed_by_reason;
  /** \brief Median of the target's objects.txt `speed_mps` over its visible frames [m/s]; NaN
   * when never visible. */
  double median_speed = std::numeric_limits<double>::quiet_NaN();
  double movingHitRate() const {
    return moving_frames > 0 ? double(moving_hits) / moving_frames
                             : std::numeric_limits<double>::quiet_NaN();
  }
  double hitRate() const {
    return visible_frames > 0 ? double(hits) / visible_frames
                              : std::numeric_limits<double>::quiet_NaN();
  }
};

/** \brief The members of a JSON object for TargetScore::missed_by_reason: `"reason": count, ...`
 * (sorted by reason, without the braces). */
std::string formatReasonCounts(const std::map<std::string, int>& counts);

/** \brief Whole-run result. */
struct DetectionScore {
  std::vector<TargetScore> targets;  ///< sorted by track id
  int frames = 0;                    ///< frames used for the false alarm rate
  int false_alarms = 0;
  int mover_rows_in_sector = 0;
  /** \brief False alarms that matched a non-moving ground-truth object (e.g. a parked car declared
   * a mover); they are false alarms too, counted here for diagnosis. */
  int false_alarms_on_static_objects = 0;
  /** \brief Whether DontCare regions were applied (DetectionMetricsParams::dont_care). */
  bool dont_care_used = false;
  /** \brief Mover rows in the sector ignored because they project into a DontCare box (and
   * match no labelled object); included in mover_rows_in_sector, not in false_alarms. */
  int dont_care_ignored = 0;
  double mean_hit_rate = std::numeric_limits<double>::quiet_NaN();    ///< over visible targets
  double pooled_hit_rate = std::numeric_limits<double>::quiet_NaN();  ///< all hits / all visible
  /** \brief Extra variant, not the DESIGN metric: mean over targets of movingHitRate(). */
  double mean_moving_hit_rate = std::numeric_limits<double>::quiet_NaN();
  double moving_speed = 0.5;  ///< the threshold used for the extra variant [m/s]
  double false_alarms_per_frame = 0;
  double median_delay = std::numeric_limits<double>::quiet_NaN();  ///< over detected targets
  int targets_never_detected = 0;  ///< visible targets without any hit (excluded from the median)
  double rms_velocity_error = std::numeric_limits<double>::quiet_NaN();  ///< pooled over hits
  int velocity_samples = 0;
  /** \brief "world velocity (poses)" or "speed (objects.txt speed_mps)". */
  std::string velocity_mode;
};

/** \brief Scores mover detections against ground truth exactly as DESIGN.md defines it.
 *
 * - target: a ground-truth track with `moving` = 1; visible in a frame when it has at least
 *   `min_points` points and its box centre lies in the scored sector (|atan2(cy, cx)| <= sector).
 * - hit: some `mover` row of that frame has its sensor-frame centroid inside the target's box
 *   grown by `grow_xy` in length and width. Hit rate = hits / visible frames.
 * - false alarm: a `mover` row whose centroid is in the scored sector and lies in no target's grown
 *   box of that frame (whether that target is visible or not). A row on a non-moving ground-truth
 *   object is a false alarm: a parked car reported as moving is exactly the error to count.
 * - delay: frames from the first visible frame to the first hit.
 * - velocity error, on hits (the hitting row nearest the box centre): when `poses` (sensor→world,
 *   one per frame index) are given, |(vx, vy) - v_gt| with v_gt the horizontal world velocity of
 *   the box centre (line fit over +-velocity_half_window frames, times from `times` or 10 Hz);
 *   otherwise | |(vx, vy)| - speed_mps |, which needs no poses but ignores heading errors.
 * - with `params.dont_care`, a row that would be a false alarm (in the sector, in no labelled box)
 *   and projects into a DontCare box of its frame is ignored instead (KITTI's benchmark).
 *
 * \param times seconds per frame index; empty = 10 Hz.
 * Throws InputError when a frame index has no pose/time. */
DetectionScore scoreDetections(const std::vector<io::GroundTruthObject>& objects,
                               const std::vector<io::TrackRow>& tracks,
                               const DetectionMetricsParams& params = DetectionMetricsParams(),
                               const std::vector<Eigen::Isometry3d>& poses = {},
                               const std::vector<double>& times = {});

/** \brief The Markdown table: one row per target, then the totals. */
std::string formatMarkdown(const DetectionScore& score);
/** \brief The same as a JSON object. */
std::string formatJson(const DetectionScore& score);

/** \brief Draws a hit-% per target bar chart (like the paper's Figure 8) into an RGB image,
 * row 0 = top. Labels use a built-in 5x7 pixel font, so no font or display is needed. */
void drawHitChart(const DetectionScore& score, const std::string& title, int& width, int& height,
                  std::vector<unsigned char>& rgb);

}  // namespace eval
}  // namespace pcl_movers
