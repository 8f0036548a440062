/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/free_space_map.h>
#include <pcl_movers/line_fit.h>
#include <pcl_movers/track.h>

#include <Eigen/Core>
#include <limits>
#include <vector>

namespace pcl_movers {

/** \brief The mover decision of MoverTracker: after each update of a track, a fixed sequence of
 * named tests, the first one failed giving the track's MoverReason (tracks.csv `reason`).
 *
 * large → latched → young → low → no_motion → no_free_space; a track that passes is `fast`,
 * `well_measured` or `sustained` by the kinematic path that let it through. Both kinds of
 * evidence are needed: kinematic (fastMotion(), wellMeasuredMotion() or sustainedMotion()) and
 * free space (freeSpaceEvidence(), slowFreeSpaceEvidence(): the object fills space an earlier scan
 * saw through, or its earlier surface is seen through now), which no static object can give
 * whatever its registration or segmentation errors. A track that fails the vote counts is still
 * a mover, `free_space`, when this update gives both kinds at once: its speed vote or sustained
 * line, and most of its view in space seen empty (fillsFreeSpace()). Reads the `decision.*` and
 * `free_space.*` settings (and track.registration_sigma, track.gate_margin) of DetectorParameters.
 */
class MoverDecision {
 public:
  void setParameters(const DetectorParameters& parameters) { parameters_ = parameters; }
  const DetectorParameters& getParameters() const { return parameters_; }
  /** \brief Scans for the free-space tests (not owned); nullptr = the tests are off. */
  void setFreeSpaceMap(const FreeSpaceMap* map) { free_space_map_ = map; }
  const FreeSpaceMap* getFreeSpaceMap() const { return free_space_map_; }

  /** \brief The speed vote of an update (fast_from_fit: from the line through the registered
   * positions; else from the Kalman velocity and its covariance). */
  void voteFast(Track& track, bool registered) const;
  /** \brief Height of a cluster for the mover height test: its top above what it stands on
   * (ClusterFeatures::floor_z, decision.standing_height), at least its own extent. */
  double standingHeight(const ClusterFeatures& features) const;
  /** \brief Whether a moving track other than `track` (a mover, confirmed, or faster than
   * decision.speed) lies within half its longest view plus gate_margin of `track`'s position. */
  bool besideMover(const Track& track, const std::vector<Track>& tracks) const;
  /** \brief Decides whether `track` is a mover after an update (Track::mover, and the test that
   * settled it, Track::reason); `points` are the world points of the cluster just assigned (the
   * free-space tests), `tracks` all live tracks (besideMover()). */
  void decide(Track& track, const std::vector<Eigen::Vector3f>& points,
              const std::vector<Track>& tracks) const;

  /** \brief True when the track's motion is well determined enough for an early confirmation
   * (see DetectorParameters::confirm_false_rate): last update registered with a high B on enough
   * points, and the line through the window's positions faster than decision.speed and
   * significantly non-zero. */
  bool wellMeasuredMotion(const Track& track) const;
  /** \brief The median roughness (ClusterFeatures::roughness) of the track's last
   * decision.window views; porous above free_space.porous_roughness. */
  static double medianRoughness(const Track& track);
  /** \brief The track's positions over the last slow_window seconds (five at least) lie on a
   * line faster than slow_speed and at most decision.speed, beyond their scatter (F-test at
   * confirm_false_rate). */
  bool sustainedMotion(const Track& track) const;
  /** \brief Speed votes (decision.votes of the last decision.window updates faster than
   * decision.speed; all of a full window for a view seen only above what hides it) and a net
   * displacement of at least displacement_ratio of decision.speed over the window. The votes are
   * waived for wellMeasuredMotion(). */
  bool fastMotion(const Track& track, bool seen_standing_only, bool well_measured) const;

  /** \brief Free-space evidence of a track: the larger fraction of (a) its current points seen
   * through by the scan `free_space.lag` frames ago and (b) its oldest stored points seen through
   * by the current scan (that view is then dropped, so every vote tests a different view). Sets
   * track.free_space; true when it reaches free_space.min_fraction. */
  bool freeSpaceEvidence(Track& track, const std::vector<Eigen::Vector3f>& points) const;
  /** \brief Free-space evidence on the time scale of slow motion: the larger of (a) the
   * fraction of the track's current points seen through by the scan free_space.long_lag frames
   * ago (the oldest stored early in a sequence) and (b) the fraction of its view of up to
   * free_space.long_lag updates ago (Track::past_views) seen through by the current scan
   * reaches free_space.long_min_fraction. A walker at 0.6 m/s has moved 0.3 m in
   * free_space.lag frames, no more than the margin, so a pass at that lag says little; over
   * 1.5 s it has moved 0.9 m. Sets track.free_space. */
  bool slowFreeSpaceEvidence(Track& track, const std::vector<Eigen::Vector3f>& points) const;
  /** \brief This update's view shows motion by itself: the track is registered (has a model),
   * has decision.min_age updates,
   * was seen at least once decision.min_height tall, none of its last decision.window views
   * porous (free_space.porous_roughness) and this one not occluded, and
   * free_space.alone_fraction of the view's judged points (at least free_space.min_points) lie
   * in space the scan free_space.lag frames ago saw empty. decide() asks it, with this update's
   * speed vote or sustained line, of a track that fails the vote counts. */
  bool fillsFreeSpace(const Track& track, const std::vector<Eigen::Vector3f>& points) const;
  /** \brief Whether free_space.lag frames are too short to show the track's motion: at its
   * speed it covers less than twice the free-space margin at its range in that time (a walker
   * at 1.3 m/s 30 m away: 0.65 m against a 0.6 m margin), so that scan saw the object's own
   * earlier surface where it is now. */
  bool shortLagTooShort(const Track& track) const;

 private:
  /** \brief The least-squares line through `positions` (σ from their scatter, at least
   * `min_sigma`) is faster than `min_speed`, at most `max_speed`, and rejects "velocity = 0" in
   * the F-test at decision.confirm_false_rate. */
  bool significantLine(const std::vector<Eigen::Vector3d>& positions, double min_sigma,
                       double min_speed,
                       double max_speed = std::numeric_limits<double>::infinity()) const;
  /** \brief `points` tested against the scan free_space.lag frames back, or the oldest stored
   * one when fewer are stored (empty Evidence when there is none: the first frame). */
  FreeSpaceMap::Evidence shortLagEvidence(const std::vector<Eigen::Vector3f>& points) const;
  /** \brief The fraction of an Evidence's judged points seen through, 0 when fewer than
   * free_space.min_points are: a few stray points are no evidence. */
  double seenThroughFraction(const FreeSpaceMap::Evidence& evidence) const;

  DetectorParameters parameters_;
  const FreeSpaceMap* free_space_map_ = nullptr;
};

}  // namespace pcl_movers
