/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/track_motion.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pcl_movers {

void TrackMotion::turn(Track& t, double registration_yaw) const {
  // A registration over yaw layers found the object turned (turn_yaw_samples): a vehicle's
  // velocity turns with its heading, so both filters' velocities turn with it before the
  // update (the object turned by minus the change of the yaw that maps views onto the model).
  const double turned = -std::remainder(registration_yaw - t.model_yaw, 2 * M_PI);
  t.model_yaw = registration_yaw;
  if (turned != 0) {
    rotateVelocity(t.filter, turned);
    if (t.velocity_filter.isInitialized()) rotateVelocity(t.velocity_filter, turned);
  }
}

double TrackMotion::measure(Track& t, const Eigen::Vector3d& position, bool registered,
                            bool occluded, double similarity, double range, double time) const {
  const auto& p = parameters_;
  // Far objects are sampled coarsely and their densities are wide: their positions are less
  // certain, which keeps a few noisy far measurements from producing a confident velocity.
  const double meas_sigma =
      std::max(registered ? p.track.registration_sigma : p.track.centroid_sigma,
               p.track.measurement_sigma_per_metre * range);
  const Eigen::Vector2d v_before = t.filter.velocity();
  const double since = std::max(1e-3, time - t.last_time);
  const Eigen::Matrix2d meas_cov = Eigen::Matrix2d::Identity() * meas_sigma * meas_sigma;
  if (!(registered && startsFast(t, position.head<2>(), meas_cov, since)))
    t.filter.update(position.head<2>(), meas_cov);
  // Acceleration limit on established tracks: the filter's velocity may not change faster than a
  // vehicle can accelerate (a single bad measurement cannot make a static object a mover).
  if (t.hits >= p.decision.min_age)
    limitAcceleration(t.filter, v_before, p.track.acceleration_limit * since);
  // An occluded view's registered position slides with its visible part (hiding: towards the
  // occluder, emerging: away from it, both towards "no motion"), so while the track's velocity
  // is known from unoccluded views (or inherited on re-acquisition) the reported velocity
  // coasts through up to occluded_skip such updates instead of following the slide.
  const bool velocity_known = t.velocity_filter.isInitialized() &&
                              (t.unoccluded_updates >= p.decision.min_age || t.reacquired);
  const bool skip_occluded =
      registered && occluded && velocity_known && t.occluded_run < p.track.occluded_skip;
  if (registered) {
    t.occluded_run = occluded ? t.occluded_run + 1 : 0;
    if (!occluded) ++t.unoccluded_updates;
  }
  if (registered && !skip_occluded) {
    updateVelocityFilter(t, position, similarity, occluded, time, range, since, t.skipped_run > 0);
    t.skipped_run = 0;
  } else if (skip_occluded) {
    if (t.skipped_run++ == 0)
      t.skip_velocity_covariance = t.velocity_filter.getCovariance().bottomRightCorner<2, 2>();
  }
  return meas_sigma;
}

void TrackMotion::refit(Track& t, const Eigen::Vector3d& position, bool registered, bool occluded,
                        double meas_sigma, double time) const {
  const auto& p = parameters_;
  // The first run of kUnoccludedFitPositions consecutive unoccluded registered positions.
  bool unoccluded_fit_ready = false;
  if (registered && static_cast<int>(t.unoccluded_positions.size()) < kUnoccludedFitPositions) {
    if (occluded) {
      t.unoccluded_positions.clear();
    } else {
      t.unoccluded_positions.emplace_back(position.x(), position.y(), time);
      unoccluded_fit_ready =
          static_cast<int>(t.unoccluded_positions.size()) == kUnoccludedFitPositions;
    }
  }
  if (p.track.velocity_fit_init && registered && t.hits == 3 && !t.reacquired) {
    // A young track's Kalman velocity converges slowly: its birth position carries
    // registration_sigma while later positions carry the range-scaled σ, so the filter stays
    // anchored on the birth position (a car at 80 m took 10+ frames). At the third
    // registration the filter restarts from the least-squares line through the three
    // positions, with that line's covariance (σ as in the updates, or the scatter if larger).
    restartFromLine(t, fitVelocity(t.history, meas_sigma), time);
  } else if (p.track.velocity_fit_init && unoccluded_fit_ready && t.seen_occluded &&
             !t.reacquired && t.unoccluded_updates == kUnoccludedFitPositions) {
    // That line went through occluded views, whose positions slide with the visible part
    // towards "no motion" (urban car 4 emerging past a building corner at 8 m/s: 3.0 m/s from
    // the line, then 7 frames to reach 6.7 m/s, where it coasted through the next occlusion).
    // The third unoccluded view restarts the filters from the line through the unoccluded
    // positions alone.
    restartFromLine(t, fitVelocity(t.unoccluded_positions, meas_sigma), time);
  }
  if (occluded) t.seen_occluded = true;
}

void TrackMotion::rotateVelocity(KalmanFilterCV& filter, double angle) {
  const Eigen::Matrix2d r = Eigen::Rotation2Dd(angle).matrix();
  auto state = filter.getState();
  state.tail<2>() = r * state.tail<2>();
  filter.setState(state);
  Eigen::Matrix4d turn = Eigen::Matrix4d::Identity();
  turn.bottomRightCorner<2, 2>() = r;
  filter.setCovariance(turn * filter.getCovariance() * turn.transpose());
}

void TrackMotion::restartFromLine(Track& track, const LineFit& fit, double time) {
  if (!fit.valid) return;
  const double stt = fit.time_spread;
  const Eigen::Vector2d& v = fit.velocity;
  const double s2 = fit.sigma_v * fit.sigma_v * stt;  // σ² of one position
  const double dt_now = time - fit.mean_time;
  KalmanFilterCV::State state;
  state.head<2>() = fit.mean_position + v * dt_now;
  state.tail<2>() = v;
  KalmanFilterCV::Covariance cov = KalmanFilterCV::Covariance::Zero();
  const double var_p = s2 * (1.0 / static_cast<double>(fit.positions) + dt_now * dt_now / stt);
  const double var_v = s2 / stt, cov_pv = s2 * dt_now / stt;
  for (int a = 0; a < 2; ++a) {
    cov(a, a) = var_p;
    cov(a + 2, a + 2) = var_v;
    cov(a, a + 2) = cov(a + 2, a) = cov_pv;
  }
  track.filter.setState(state);
  track.filter.setCovariance(cov);
  if (track.velocity_filter.isInitialized()) track.velocity_filter = track.filter;
}

void TrackMotion::limitAcceleration(KalmanFilterCV& filter, const Eigen::Vector2d& v_before,
                                    double limit) {
  Eigen::Vector2d dv = filter.velocity() - v_before;
  if (!(dv.norm() > limit)) return;
  dv *= limit / dv.norm();
  auto state = filter.getState();
  state.tail<2>() = v_before + dv;
  filter.setState(state);
}

bool TrackMotion::startsFast(Track& t, const Eigen::Vector2d& measured,
                             const Eigen::Matrix2d& meas_cov, double since) const {
  if (t.hits != 1 || t.reacquired) return false;
  // A track's second view: its velocity prior (initial_velocity_sigma) is that of most objects,
  // at rest or walking. A view that prior cannot explain (outside its gate) is of a fast object:
  // the track starts from the velocity of its two views instead, as a diffuse prior would give.
  const Eigen::Vector2d shift = measured - t.filter.position();
  const Eigen::Matrix2d S = t.filter.innovationCovariance(meas_cov);
  const double gate = parameters_.track.gate_sigmas;
  if (!(shift.dot(S.ldlt().solve(shift)) > gate * gate)) return false;
  const double sigma = std::sqrt(meas_cov(0, 0));
  t.filter.initialize(measured, meas_cov, shift / since, std::sqrt(2.0) * sigma / since);
  return true;
}

void TrackMotion::updateVelocityFilter(Track& track, const Eigen::Vector3d& measurement,
                                       double similarity, bool occluded, double time, double range,
                                       double since, bool reanchor) const {
  const auto& p = parameters_;
  if (reanchor && track.velocity_filter.isInitialized()) {
    // The skipped views' registered positions slid with the visible part (an emerging car's
    // grew backwards by 3.5 m: it registered at 4.8 m/s for 7), so the object's reference point
    // now sits somewhere else on it. That offset is a position error, not a velocity: taken as a
    // measurement it turned the velocity the filter had coasted on (7.0 m/s, right) into 4.4,
    // which took 12 frames to recover. The filter moves to the measurement and keeps its
    // velocity; the positions before the skip, measured with the old offset, leave the
    // manoeuvre fit.
    track.registered.clear();
    track.registered.emplace_back(measurement.x(), measurement.y(), time);
    KalmanFilterCV::State state = track.velocity_filter.getState();
    state.head<2>() = measurement.head<2>();
    KalmanFilterCV::Covariance cov = track.velocity_filter.getCovariance();
    const double sigma = registeredSigma(track, measurement, similarity, occluded, time, range);
    cov.topLeftCorner<2, 2>() = Eigen::Matrix2d::Identity() * sigma * sigma;
    cov.topRightCorner<2, 2>().setZero();
    cov.bottomLeftCorner<2, 2>().setZero();
    cov.bottomRightCorner<2, 2>() = track.skip_velocity_covariance;
    track.velocity_filter.setState(state);
    track.velocity_filter.setCovariance(cov);
    return;
  }
  track.registered.emplace_back(measurement.x(), measurement.y(), time);
  while (static_cast<int>(track.registered.size()) > p.track.manoeuvre_window)
    track.registered.pop_front();
  if (!p.track.sigma_from_scatter) return;
  // The first registered update starts it from the tracking filter (which has just taken the
  // same measurement); so do the restarts of the tracking filter (see velocity_fit_init).
  if (!track.velocity_filter.isInitialized()) {
    track.velocity_filter = track.filter;
    return;
  }
  const double sigma = registeredSigma(track, measurement, similarity, occluded, time, range);
  const Eigen::Vector2d v_before = track.velocity_filter.velocity();
  // The acceleration limit bounds how fast the object's velocity can change, but an update also
  // corrects the estimate's own error, which the filter knows: a young track's estimate may be
  // off by several m/s (urban car 4 reported 3.7 m/s for 8, its registered point having slid
  // while the car emerged, and the limit held it there for half a second). So the change may
  // reach gate_sigmas times the predicted velocity σ; only a correction beyond both is a bad
  // measurement.
  const double sigma_v =
      std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(
                                  track.velocity_filter.getCovariance().bottomRightCorner<2, 2>(),
                                  Eigen::EigenvaluesOnly)
                                  .eigenvalues()
                                  .maxCoeff()));
  track.velocity_filter.update(measurement.head<2>(), Eigen::Matrix2d::Identity() * sigma * sigma);
  if (track.hits >= p.decision.min_age)
    limitAcceleration(track.velocity_filter, v_before,
                      std::max(p.track.acceleration_limit * since, p.track.gate_sigmas * sigma_v));
}

double TrackMotion::registeredSigma(const Track& track, const Eigen::Vector3d& measurement,
                                    double similarity, bool occluded, double time,
                                    double range) const {
  const auto& p = parameters_;
  // The range-scaled σ is a bound for far, coarsely sampled objects, not what a registration
  // delivers: the registered positions of a van at 40-80 m scattered by 3-10 cm about their
  // track while σ said 0.4-0.8 m, so the filter lagged every manoeuvre by ~0.5 s (open: 1.3 m/s
  // behind an accelerating van). The track's own scatter measures it, per object and view.
  const double prior =
      std::max(p.track.registration_sigma, p.track.measurement_sigma_per_metre * range);
  if (!p.track.sigma_from_scatter) return prior;
  // A view that matched its model poorly (B below registration_stop_similarity: the object turns,
  // recedes behind trees, is partly hidden) is placed less precisely than the scatter of the
  // earlier positions says: it keeps the prior.
  if (!(similarity >= p.registration.stop_similarity)) return prior;
  // So is a view cut by a nearer object: the occluder cuts the object at the same world place in
  // consecutive scans, which pulls the registration towards no motion while the visible part grows
  // or shrinks (urban car 4 emerging behind parked cars registered at 1-4 m/s for 8).
  if (occluded) return prior;
  // But registrations also slide slowly while the view of an object changes (a car passing the
  // sensor, one emerging from behind another), and a filter that trusts every position follows
  // those slides (open truck ±1.6 m/s). The prior keeps smoothing them once the track is
  // established, unless its positions show a significant acceleration: a quadratic through the
  // last manoeuvre_window registered positions (~1 s), whose curvature a slide of a few frames
  // does not sustain.
  const bool young = static_cast<int>(track.registered.size()) < p.track.manoeuvre_window;
  if (!young) {
    const QuadraticFit quadratic = fitAcceleration(track.registered, p.track.registration_sigma);
    if (!quadratic.valid ||
        !(quadratic.acceleration.norm() > p.track.manoeuvre_sigmas * quadratic.sigma_a))
      return prior;
  }
  Fifo<Eigen::Vector3d> positions = track.history;  // at most decision.window + 1
  positions.emplace_back(measurement.x(), measurement.y(), time);
  while (static_cast<int>(positions.size()) > p.decision.window + 1) positions.pop_front();
  // Four positions leave 4 degrees of freedom for the scatter; with fewer it is a guess.
  if (positions.size() < 4) return prior;
  const LineFit fit = fitVelocity(positions, p.track.registration_sigma);
  return fit.valid ? fit.sigma : prior;
}

}  // namespace pcl_movers
