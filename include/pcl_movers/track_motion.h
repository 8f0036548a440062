/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/kalman_filter_cv.h>
#include <pcl_movers/line_fit.h>
#include <pcl_movers/track.h>

#include <Eigen/Core>

namespace pcl_movers {

/** \brief Motion estimation of a track (MoverTracker): its two constant-velocity Kalman
 * filters and what keeps them honest.
 *
 * `Track::filter` gates, searches and decides, with the conservative range-scaled σ of every
 * measurement; `Track::velocity_filter` is the velocity reported, on the registered positions
 * only, with σ from their own scatter while the track is young or manoeuvring
 * (registeredSigma()). Around the Kalman updates: the velocities turn with a registration that
 * found the object turned (turn()); a track's second view outside its velocity prior's gate
 * starts it fast (startsFast()); established tracks' velocities change no faster than
 * track.acceleration_limit; occluded views, whose registered positions slide with their visible
 * part, are skipped by the reported velocity for up to track.occluded_skip updates; and at the
 * third registration, or the third unoccluded one after occluded views, the filters restart from
 * the line through those positions (refit(), track.velocity_fit_init). Reads the `track.*`
 * settings and decision.window / decision.min_age of DetectorParameters. */
class TrackMotion {
 public:
  /// Unoccluded registered positions the filters restart from (see track.velocity_fit_init).
  static constexpr int kUnoccludedFitPositions = 3;

  void setParameters(const DetectorParameters& parameters) { parameters_ = parameters; }
  const DetectorParameters& getParameters() const { return parameters_; }

  /** \brief Turns both filters' velocities with the object's heading before a registered update:
   * `registration_yaw` is the yaw of the registration mapping this view onto the model, and the
   * object turned by minus its change since the last one (Track::model_yaw). */
  void turn(Track& track, double registration_yaw) const;
  /** \brief Updates the track's filters with a measured `position` (world; registered: the
   * reference point, else the centroid) at `time`, the view `occluded` or not, registered with
   * `similarity` at `range` [m] from the sensor. Call before the track records the update
   * (Track::last_time is the previous update's). \return the measurement's σ [m]. */
  double measure(Track& track, const Eigen::Vector3d& position, bool registered, bool occluded,
                 double similarity, double range, double time) const;
  /** \brief After the track recorded the update (hits, history): restarts the filters from the
   * line through its first registered or first unoccluded positions (track.velocity_fit_init). */
  void refit(Track& track, const Eigen::Vector3d& position, bool registered, bool occluded,
             double meas_sigma, double time) const;

  /** \brief σ [m] of a registered position `measurement` of `track` at `time` (this measurement
   * is the newest of track.registered): the prior max(registration_sigma,
   * measurement_sigma_per_metre · `range`), or, when the registration's B (`similarity`) is
   * confident and the track young or manoeuvring (see
   * DetectorParameters::measurement_sigma_from_scatter), the scatter of its recent positions
   * (this one included) about their line, at least registration_sigma. `occluded` views (a side
   * bounded by a nearer object) keep the prior. */
  double registeredSigma(const Track& track, const Eigen::Vector3d& measurement, double similarity,
                         bool occluded, double time, double range) const;

  /** \brief Turns the velocity of `filter` (and its covariance) by `angle` [rad]. */
  static void rotateVelocity(KalmanFilterCV& filter, double angle);

  /** \brief Restarts the track's filters (tracking, and velocity once initialized) from the
   * line `fit` of its positions, with that line's covariance; nothing when it is not valid. */
  static void restartFromLine(Track& track, const LineFit& fit, double time);

  /** \brief Clamps the velocity change of `filter` since `v_before` to `limit` [m/s]. */
  static void limitAcceleration(KalmanFilterCV& filter, const Eigen::Vector2d& v_before,
                                double limit);

  /** \brief Records a registered position of `track` (after its tracking filter took it) and
   * updates the track's velocity_filter with it; `since` [s] is the time since the last update.
   * `reanchor`: the first update after skipped occluded views moves the filter's position to
   * the measurement and keeps its velocity (see track.occluded_skip). */
  void updateVelocityFilter(Track& track, const Eigen::Vector3d& measurement, double similarity,
                            bool occluded, double time, double range, double since,
                            bool reanchor = false) const;

  /** \brief At a track's second view, outside its velocity prior's gate: restarts the filter
   * from the two views (position `measured`, velocity their difference / `since`) and returns
   * true; else false (the caller updates the filter as usual). */
  bool startsFast(Track& t, const Eigen::Vector2d& measured, const Eigen::Matrix2d& meas_cov,
                  double since) const;

 private:
  DetectorParameters parameters_;
};

}  // namespace pcl_movers
