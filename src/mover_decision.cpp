/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/mover_decision.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pcl_movers {

void MoverDecision::voteFast(Track& t, bool registered) const {
  const auto& p = parameters_;
  if (p.decision.fast_from_fit && registered) {
    // Fast only when a straight line fits the measured positions of the window with a speed
    // above the threshold and well above its uncertainty, the uncertainty taken from the
    // scatter of the positions about that line (at least the measurement σ). The Kalman
    // velocity's σ rests on an assumed σ = measurement_sigma_per_metre·range: a pedestrian at
    // 40 m registered to a few cm (urban) never cleared it (σ_v ≈ 0.65 m/s at 1.3 m/s) and was
    // confirmed 20 frames late. The scatter credits precise registrations and still withholds
    // the vote from noisy ones. Centroid measurements (centroid mode, large structures) keep the
    // Kalman test: with their 0.3 m σ floor a 6-position line cannot tell a walker (σ_v 0.7
    // m/s), where the filter's longer memory can (centroid-mode walkers were lost).
    const double floor = p.track.registration_sigma;
    const LineFit fit = fitVelocity(t.history, floor);
    const double speed = fit.velocity.norm();
    t.fast.push_back(fit.valid && speed > p.decision.speed &&
                     speed > p.decision.speed_sigmas * fit.sigma_v);
  } else {
    // Fast only when the speed is above the threshold and well above its own uncertainty.
    const Eigen::Vector2d v = t.filter.velocity();
    const double speed = v.norm();
    double sigma_v = 0;
    if (speed > 0)
      sigma_v =
          std::sqrt(std::max(0.0, v.dot(t.filter.getCovariance().bottomRightCorner<2, 2>() * v)) /
                    (speed * speed));
    t.fast.push_back(speed > p.decision.speed && speed > p.decision.speed_sigmas * sigma_v ? 1 : 0);
  }
  while (static_cast<int>(t.fast.size()) > p.decision.window) t.fast.pop_front();
}

double MoverDecision::medianRoughness(const Track& track) {
  // The value of rank size / 2 by counting, without a copy to sort: the window holds a few
  // values, and this runs for every decided track every frame.
  const auto& r = track.roughness;
  const std::size_t rank = r.size() / 2;
  for (const float v : r) {
    std::size_t below = 0, equal = 0;
    for (const float w : r) {
      below += w < v;
      equal += w == v;
    }
    if (below <= rank && rank < below + equal) return v;
  }
  return std::numeric_limits<double>::quiet_NaN();  // no view with a known roughness
}

void MoverDecision::decide(Track& track, const std::vector<Eigen::Vector3f>& points,
                           const std::vector<Track>& tracks) const {
  const auto& p = parameters_;
  const int run = track.mover_run;
  track.mover = false;
  track.reason = MoverReason::kLarge;
  if (track.large) return;
  if (track.confirmed && p.decision.latch) {
    track.mover = true;
    track.reason = MoverReason::kLatched;
    return;
  }
  track.mover_run = 0;  // restored below when this update passes every test
  // Free-space evidence is collected from the first fast update on, while the speed votes
  // accumulate, instead of only once every kinematic test has passed: the two are independent,
  // and waiting for one before starting the other delayed every confirmation by 1-2 frames.
  // From the third update only: at the second, the velocity rests on the first association of a
  // newborn track, whose birth cluster is often merged or partial (KITTI 0000: a track born on a
  // merged cluster collected two votes at updates 2-3 and latched as a false alarm).
  bool free_now = false;  // this update's view passed the free-space test
  const bool slow_now = sustainedMotion(track);
  const bool fast_now = !track.fast.empty() && track.fast.back();
  // Rays pass through foliage whether it moves or not: a porous object's free space says nothing
  // (on the tune split most of trail's false alarms were trees whose registration slid). Judged
  // on the median of its last decision.window views: a bush's roughness flickers around the bound
  // from view to view (paper wooded scene: the false alarms came back on its smoother views),
  // and a solid object may show one rough view (a forward ladar's car at 70 m, 0.3 m between
  // cells: 0.11-0.35 m from view to view; the roughest of the window cost it 16 hits).
  if (std::isfinite(track.features.roughness))
    track.roughness.push_back(static_cast<float>(track.features.roughness));
  while (static_cast<int>(track.roughness.size()) > p.decision.window) track.roughness.pop_front();
  const bool porous =
      p.free_space.porous_roughness > 0 && medianRoughness(track) > p.free_space.porous_roughness;
  if (track.hits >= 3 && (fast_now || slow_now)) {
    // Evidence on the time scale of the motion: the short lag for fast motion, the long one for a
    // sustained line (slow, or far away, where the short lag's displacement is within the
    // range-scaled margin: a walker at 50 m moves 0.7 m in 0.5 s against a 1.0 m margin).
    // Fast motion that the short lag cannot show at the track's range is tested at the long
    // lag as well, as slow motion is (a walker at 1.3 m/s 30 m away: 0.65 m in 0.5 s against a
    // 0.6 m margin, and it waited for a 1.5 s line before).
    free_now = !porous && ((fast_now && freeSpaceEvidence(track, points)) ||
                           ((slow_now || (fast_now && shortLagTooShort(track))) &&
                            slowFreeSpaceEvidence(track, points)));
    track.free_votes.push_back(free_now ? 1 : 0);
    while (static_cast<int>(track.free_votes.size()) > p.decision.window)
      track.free_votes.pop_front();
  }
  // Motion determined beyond doubt by the positions so far skips the vote count and the minimum
  // age, which only exist to average out noisy velocities (see wellMeasuredMotion()).
  // Only while the track is young (up to its first full window, decision.window + 1 positions): the
  // early rule stands in for history a track does not have yet, not for the vote count of an
  // established one (KITTI 0000: a parked car whose registration slipped by ~1 m over 3 s after
  // 20 still updates passed the significance test). And the free-space evidence must come from
  // this update's view: tests stay in free_votes for up to decision.window fast updates, which can
  // be seconds apart, while the significance test concerns the motion of the last few frames.
  const bool well_measured = track.hits <= p.decision.window + 1 &&
                             (free_now || !free_space_map_ || p.free_space.lag <= 0) &&
                             wellMeasuredMotion(track);
  track.reason = MoverReason::kYoung;
  if (!well_measured && track.hits < p.decision.min_age) return;
  // The tallest view counts: a cluster's height changes with the view (a van seen from straight
  // behind showed 0.7-0.9 m and its decision flickered around decision.min_height).
  // A lower view counts from what it stands on (standingHeight(): the ground under it, or the
  // object hiding it from below), unless a moving object is beside it: then it is more likely
  // that object's own upper part, cut off by its nearer lower body (urban cars, the KITTI van: such
  // fragments became movers with the velocity of their sliding centroid).
  const bool seen_standing_only = track.max_height < p.decision.min_height;
  track.reason = MoverReason::kLow;
  if (seen_standing_only &&
      (track.max_standing_height < p.decision.min_height || besideMover(track, tracks)))
    return;
  const bool fast = fastMotion(track, seen_standing_only, well_measured);
  // One test can be fooled (a cluster that briefly included something else, a mixed edge);
  // free_space.votes tests with evidence are needed, within the last decision.window tests.
  int free_votes = 0;
  for (const char f : track.free_votes) free_votes += f;
  const int free_needed = well_measured
                              ? std::min(p.decision.confirm_free_space_votes, p.free_space.votes)
                              : p.free_space.votes;
  const bool moves = fast || slow_now;
  const bool seen_through = !free_space_map_ || p.free_space.lag <= 0 || free_votes >= free_needed;
  if (moves && seen_through) {
    track.reason = !fast                                              ? MoverReason::kSustained
                   : well_measured && track.hits < p.decision.min_age ? MoverReason::kWellMeasured
                                                                      : MoverReason::kFast;
  } else if ((fast_now || slow_now) && fillsFreeSpace(track, points)) {
    // Both kinds of evidence from this update alone: its speed vote (or sustained line) and
    // most of its view in space seen empty, in place of the vote counts that average noisy
    // ones over the window (which lag a walker slowing down or a car whose young velocity
    // is still converging).
    track.reason = MoverReason::kFreeSpace;
  } else {
    track.reason = moves ? MoverReason::kNoFreeSpace : MoverReason::kNoMotion;
    return;
  }
  track.mover = true;
  // Latch only after a steady run of positive decisions: a brief false confirmation (a cluster
  // that jumped to another object) must not become a mover for the rest of the track's life.
  track.mover_run = run + 1;
  if (track.mover_run >= p.decision.window) track.confirmed = true;
}

bool MoverDecision::significantLine(const std::vector<Eigen::Vector3d>& positions, double min_sigma,
                                    double min_speed, double max_speed) const {
  const LineFit fit = fitVelocity(positions, min_sigma);
  if (!fit.valid) return false;
  const double speed = fit.velocity.norm();
  return speed > min_speed && speed <= max_speed &&
         speed >= speedSignificanceRatio(fit.positions, parameters_.decision.confirm_false_rate) *
                      fit.sigma_v;
}

bool MoverDecision::wellMeasuredMotion(const Track& track) const {
  const auto& p = parameters_;
  if (!(p.decision.confirm_false_rate > 0) || track.large || !track.model) return false;
  // B is 0 for centroid updates, so they never qualify; the current view must be a good match of
  // a well-sampled object (earlier positions' quality shows in the scatter about the line).
  if (track.similarity < p.decision.confirm_min_similarity ||
      track.features.points < p.decision.confirm_min_points)
    return false;
  // A view cut by a nearer object is placed by its visible part, which slides while the object
  // emerges or hides: its line can be straight and wrong.
  if (track.features.occluded) return false;
  return significantLine(track.history, p.decision.confirm_sigma_floor, p.decision.speed);
}

bool MoverDecision::fastMotion(const Track& track, bool seen_standing_only,
                               bool well_measured) const {
  const auto& p = parameters_;
  int votes = 0;
  for (const char f : track.fast) votes += f;
  if (!well_measured && votes < p.decision.votes) return false;
  // Measured only down to what hides it, a track needs every speed vote of a full window: small
  // fragments above parked cars in a real street (KITTI city, 20-50 points, 0.1-0.3 m tall)
  // moved with their centroids' jumps and passed decision.votes of them.
  if (seen_standing_only &&
      (static_cast<int>(track.fast.size()) < p.decision.window || votes < p.decision.window))
    return false;
  const auto& first = track.history.front();
  const auto& last = track.history.back();
  const double elapsed = last.z() - first.z();
  if (elapsed <= 0) return false;
  const double displacement = (last.head<2>() - first.head<2>()).norm();
  return displacement >= p.decision.displacement_ratio * p.decision.speed * elapsed;
}

bool MoverDecision::sustainedMotion(const Track& track) const {
  const auto& p = parameters_;
  // Registered positions only (a model exists): the centroids of partial views slide as the view
  // changes, steadily enough over seconds to look like slow motion (a 0.1 m tall fragment beside
  // the ego in KITTI city at 0.9 m/s).
  // Five positions at least (6 degrees of freedom for the scatter): a slow track is registered
  // only every static_refresh_frames frames while its centroid barely moves (cheap frames).
  if (!(p.decision.slow_window > 0) || track.large || !track.model || track.long_history.size() < 5)
    return false;
  // Slow means up to decision.speed: a faster line is the speed votes' to judge (fastMotion()).
  // A stretch of wall beside a highway registers sliding along with the sensor, on a straight
  // line at its speed, and passed as sustained motion (tune split: 19 false alarms in one
  // highway scene). Below that speed the line needs no minimum span, only its five positions:
  // the F-test's bound grows as they get fewer, and a walker at 1 m/s waited 1.1 s for the
  // window to fill (tune split: a quarter of the missed walker frames, `no_motion`).
  return significantLine(track.long_history, p.track.registration_sigma, p.decision.slow_speed,
                         p.decision.speed);
}

bool MoverDecision::freeSpaceEvidence(Track& track,
                                      const std::vector<Eigen::Vector3f>& points) const {
  const auto& p = parameters_;
  track.free_space = 0;
  if (!free_space_map_ || p.free_space.lag <= 0) return true;  // test disabled
  // (a) approaching / crossing: the object now fills space an earlier scan saw empty. In the
  // first frames of a sequence fewer than free_space.lag earlier scans exist, and the oldest one
  // is used: a static object gives no evidence at any lag, and a mover that has moved less than
  // the margin since gives none either, so only clearly moving objects are confirmed before the
  // lag has passed (open truck, seen from frame 0: confirmed at frame 5 before, when the first
  // lag-5 scan exists).
  const FreeSpaceMap::Evidence ahead = shortLagEvidence(points);
  // (b) receding: the object's earlier surface is now seen through by the current scan.
  FreeSpaceMap::Evidence behind;
  // The oldest stored view is used once and dropped: each vote tests a different earlier view,
  // so one early view with stray points (mixed pixels at an edge) cannot vote repeatedly.
  if (track.past_points.size() > 1) {
    behind = free_space_map_->test(track.past_points.front(), 0);
    track.past_points.pop_front();
  }
  track.free_space = std::max(seenThroughFraction(ahead), seenThroughFraction(behind));
  return track.free_space >= p.free_space.min_fraction;
}

bool MoverDecision::slowFreeSpaceEvidence(Track& track,
                                          const std::vector<Eigen::Vector3f>& points) const {
  const auto& p = parameters_;
  track.free_space = 0;
  if (!free_space_map_ || p.free_space.lag <= 0) return true;  // test disabled
  const int lag =
      std::min(std::max(p.free_space.long_lag, p.free_space.lag), free_space_map_->size() - 1);
  if (lag < 1) return false;
  // (a) approaching or crossing, as in freeSpaceEvidence(), against the scan lag frames back;
  // (b) receding: the view of up to long_lag updates back is seen through by the current scan.
  // A walker moving away along the ray fills only space its own earlier body hid, so only (b)
  // can show it (a group walking away at 1.3 m/s 30 m ahead: no evidence from (a) in 100 frames).
  const auto ahead = free_space_map_->test(points, lag);
  // Its fraction is taken over the whole earlier view, not only over the points the current
  // scan could judge: most of a receding walker's earlier view lies in front of it now and is
  // judged, while a view of which the current scan judges only a few points (a parked car
  // passed at 2 m, mostly out of the beams) says little.
  double behind = 0;
  if (static_cast<int>(track.past_views.size()) >= p.free_space.lag) {
    const auto& view = track.past_views.front();
    const auto e = free_space_map_->test(view, 0);
    if (e.seen_through >= p.free_space.min_points)
      behind = static_cast<double>(e.seen_through) / static_cast<double>(view.size());
  }
  track.free_space = std::max(seenThroughFraction(ahead), behind);
  return track.free_space >= p.free_space.long_min_fraction;
}

bool MoverDecision::fillsFreeSpace(const Track& track,
                                   const std::vector<Eigen::Vector3f>& points) const {
  const auto& p = parameters_;
  if (!free_space_map_ || p.free_space.lag <= 0 || !(p.free_space.alone_fraction > 0) ||
      points.empty())
    return false;
  // Not before the age at which the vote counts may pass (a younger track's view is often a
  // merged or partial birth cluster, and its velocity still converging); not on foliage, which
  // is seen through whether it moves or not: as one view decides here, none of the window's
  // views may be porous (a bush's roughness flickers about the bound, and its median passes on
  // a run of smoother views); not on a view cut by a nearer object (its position slides with its
  // visible part); and not on a track never seen at a mover's height: the rising view of a
  // parked car entering a high-mounted sensor's lowest beams as it is passed fills space the
  // beams passed over before (tune split without this test: parking false alarms 0.037 -> 0.056
  // per frame, os1_64 0.035 -> 0.057).
  // Registered tracks only, as the other shortcuts past the vote counts (wellMeasured(),
  // sustained motion): a centroid track's speed vote slides with its partial views, and with this
  // rule centroid mode gained false alarms (KITTI 0000-a 0.143 -> 0.169 per frame).
  if (!track.model || track.hits < p.decision.min_age || track.features.occluded ||
      track.max_height < p.decision.min_height)
    return false;
  const bool porous = p.free_space.porous_roughness > 0 &&
                      std::any_of(track.roughness.begin(), track.roughness.end(),
                                  [&](float r) { return r > p.free_space.porous_roughness; });
  if (porous) return false;
  // With no stored scan to test against, the Evidence is empty and its fraction 0.
  return seenThroughFraction(shortLagEvidence(points)) >= p.free_space.alone_fraction;
}

FreeSpaceMap::Evidence MoverDecision::shortLagEvidence(
    const std::vector<Eigen::Vector3f>& points) const {
  const int lag = std::min(parameters_.free_space.lag, free_space_map_->size() - 1);
  return lag >= 1 ? free_space_map_->test(points, lag) : FreeSpaceMap::Evidence();
}

double MoverDecision::seenThroughFraction(const FreeSpaceMap::Evidence& evidence) const {
  return evidence.seen_through >= parameters_.free_space.min_points ? evidence.fraction() : 0.0;
}

bool MoverDecision::shortLagTooShort(const Track& track) const {
  const auto& p = parameters_;
  if (!free_space_map_ || !track.model || track.long_history.size() < 5) return false;
  const Eigen::Vector3f sensor = free_space_map_->sensorPosition(0);
  if (!sensor.allFinite()) return false;
  const double frame_period = (track.history.back().z() - track.history.front().z()) /
                              static_cast<double>(track.history.size() - 1);
  const double range = (track.filter.position() - sensor.head<2>().cast<double>()).norm();
  const double margin = free_space_map_->margin(range);
  if (!(track.filter.speed() * p.free_space.lag * frame_period < p.free_space.lag_margins * margin))
    return false;
  // The registered positions so far lie on a line, as sustainedMotion() asks of slow motion but
  // over the positions there are: foliage whose registration slides in jumps votes fast, and the
  // long lag sees through its gaps (tune split, trail: 0.078 false alarms per frame without this
  // test, 0.071 with it, 0.067 without the long lag).
  return significantLine(track.long_history, p.track.registration_sigma, p.decision.slow_speed);
}

double MoverDecision::standingHeight(const ClusterFeatures& f) const {
  // Measured from what the object stands on (ClusterFeatures::floor_z): the ground under it
  // (a sparse sensor's one or two beams across a car), or the lowest point of a nearer object
  // hiding its lower part (a walker's head above a parked car).
  if (!parameters_.decision.standing_height || !std::isfinite(f.floor_z)) return f.height;
  return std::max(f.height, f.max_z - std::min(f.min_z, f.floor_z));
}

bool MoverDecision::besideMover(const Track& track, const std::vector<Track>& tracks) const {
  const Eigen::Vector2d at = track.filter.position();
  for (const Track& u : tracks) {
    // Moving, confirmed or not yet: the two are decided in the same update, in either order.
    const bool moving =
        u.mover || u.confirmed || u.filter.velocity().norm() > parameters_.decision.speed;
    if (u.id == track.id || u.large || !moving) continue;
    if ((u.filter.position() - at).norm() < 0.5 * u.max_length + parameters_.track.gate_margin)
      return true;
  }
  return false;
}

}  // namespace pcl_movers
