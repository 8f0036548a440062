/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/swept_edges.h>

#include <string>

namespace pcl_movers {

/** \brief How MoverTracker registers a cluster with a track's accumulated model
 * (BhattacharyaRegistration; `registration.*` keys of DetectorParameters). */
struct RegistrationParameters {
  /// Density grid cell size in x/y [m] and in z [m], and grid size in cells: the paper's 29×29×7
  /// grid grown in x/y (below), and 3 slices of 0.94 m instead of 7 — the paper's own speed-up
  /// ("reducing vertical resolution to three slices gave a good speedup while maintaining good
  /// robustness"). 0.3 m × 41 cells = 12.3 m: the grid must hold the longest mover (an 8 m truck)
  /// from wherever its centre lies, and a model stays centred on the centroid of its first view,
  /// which for a truck first seen from behind is its rear face: so the grid reaches most of a truck
  /// length either way. At 0.2 m × 29 (5.8 m) a truck's model was truncated and its reference point
  /// slid (open truck velocity error 1.05 → 0.29 m/s); at 0.3 m × 29 (8.7 m) the trucks of the
  /// scene corpus still registered slow as the sensor passed their sides (tune split, truck
  /// velocity RMS 1.25 → 1.02 m/s with 41 cells, all targets 0.712 → 0.673; 37 and 51 cells alike).
  double resolution = 0.3;
  double resolution_z = 0.94;
  int cells_xy = 41;
  int cells_z = 3;

  /// Gaussian σ per metre of range and its lower bound [m]. 0.003: one HDL-64E azimuth step
  /// (0.0029 rad at 2200 columns), the horizontal spacing of the samples, as the paper's σ
  /// "proportional to the sampling density" asks. At 0.01 (before) a car at 80 m was blurred
  /// over σ = 0.8 m, three times its sample spacing: velocity RMS open / urban / wooded 0.208 /
  /// 0.326 / 0.245 m/s, now 0.129 / 0.298 / 0.155 (docs/design_history.md).
  double sigma_per_metre = 0.003;
  double min_sigma = 0.1;

  /// Yaw layers of the registration (1 = translation only; the paper used 3-5).
  int yaw_samples = 1;

  /// Turning movers (registration mode): when a mover's candidate does not match its model
  /// confidently (B < stop_similarity), it is registered again with this many yaw
  /// layers, turn_yaw_step_deg apart (1 = off); the turned match is taken when its B is higher
  /// by more than turn_min_gain. The yaw found stays with the track (later views are turned by
  /// it onto the model) and turns the track's velocity with the object's heading.
  int turn_yaw_samples = 7;
  double turn_yaw_step_deg = 5.0;
  double turn_min_gain = 0.05;

  /// A registered candidate is only an update when its Bhattacharyya similarity reaches this
  /// (low B = occlusion or wrong object).
  double min_similarity = 0.35;

  /// Clusters are evenly subsampled to at most this many points for registration.
  int max_points = 100;

  /// Search radius of the registration for a track seen only once, around its centroid shift [m].
  double young_search_radius = 0.8;

  /// Half-life of the accumulated object model [frames].
  double model_half_life = 4.0;

  /// A track's gated candidates are registered nearest centroid first; once one reaches this
  /// similarity the farther ones are skipped (cost control; > 1 registers them all, the paper's).
  double stop_similarity = 0.8;

  /** \brief Calls `f(key, member, description)` for every setting. */
  template <typename F>
  void forEachParameter(F&& f) {
    f("resolution", resolution, "density grid cell size in x/y [m]");
    f("turn_yaw_samples", turn_yaw_samples,
      "yaw layers of a mover's second registration when the first fails (1 = off)");
    f("min_similarity", min_similarity, "min Bhattacharyya similarity of an update");
    f("model_half_life", model_half_life, "half-life of the accumulated model [frames]");
  }

  /** \brief Calls `f(key, member, description)` for every constant of this stage's rules:
   * values measured once and fixed, not settings (docs/design.md, "Settings"). They stay
   * members so that the unit tests of a rule, and library users studying it, can vary them. */
  template <typename F>
  void forEachConstant(F&& f) {
    f("resolution_z", resolution_z, "density grid cell size in z [m]");
    f("cells_xy", cells_xy, "density grid cells in x and y");
    f("cells_z", cells_z, "density grid cells in z");
    f("sigma_per_metre", sigma_per_metre, "Gaussian sigma per metre of range");
    f("min_sigma", min_sigma, "lower bound of the Gaussian sigma [m]");
    f("yaw_samples", yaw_samples, "yaw layers of the registration (1 = translation only)");
    f("turn_yaw_step_deg", turn_yaw_step_deg, "step between those yaw layers [deg]");
    f("turn_min_gain", turn_min_gain, "B gain a turned match needs over the unturned one");
    f("max_points", max_points, "subsample clusters to this many points");
    f("young_search_radius", young_search_radius, "search radius for tracks seen once [m]");
    f("stop_similarity", stop_similarity,
      "skip farther candidates of a track after a registration this good");
  }
};

/** \brief Association, motion estimation and track lifecycle of MoverTracker (`track.*`
 * keys of DetectorParameters). */
struct TrackParameters {
  /// Clusters further than this from the sensor are ignored [m] (too sparse to register).
  double max_range = 80.0;

  /// Association mode: registration (the paper's) or centroid (the paper's "simplest approach").
  std::string mode = "registration";

  /// σ of the white-noise acceleration of the constant-velocity Kalman filter [m/s²].
  double acceleration_noise = 3.0;

  /// Hard acceleration limit: updates implying more are rejected [m/s²].
  double acceleration_limit = 12.0;

  /// σ of a registered position measurement [m].
  double registration_sigma = 0.1;

  /// σ of a centroid position measurement [m] (centroids move with the viewpoint).
  double centroid_sigma = 0.3;

  /// Position σ grows with range: σ = max(base σ, this · range) [m per m of range].
  double measurement_sigma_per_metre = 0.01;

  /// Reported velocity (registration mode): 1 = from a second filter on the registered positions
  /// (the tracking filter keeps the range-scaled σ) whose σ, while the track is young (fewer
  /// than manoeuvre_window registered positions) or manoeuvring (a quadratic through its last
  /// manoeuvre_window registered positions has an acceleration above manoeuvre_sigmas times its
  /// σ) and the registration is confident (B >= registration.stop_similarity), is the scatter of
  /// the track's last positions about their line (at least registration_sigma), else the
  /// range-scaled σ; 0 = the tracking filter's velocity.
  bool sigma_from_scatter = true;

  /// Registered positions of the manoeuvre test (see sigma_from_scatter).
  int manoeuvre_window = 15;

  /// Significance of the acceleration of the manoeuvre test [σ].
  double manoeuvre_sigmas = 4.0;

  /// Static tracks (slow, established, one still candidate) are registered every this many
  /// frames only; 1 = every frame (the paper's).
  int static_refresh_frames = 4;

  /// Largest centroid shift [m] of such a candidate from the track's last update (not its last
  /// still frame, so that slow motion adds up) that counts as "still".
  double static_shift = 0.15;

  /// Such a track's nearest cluster is only taken unregistered when every other cluster's
  /// centroid is farther than this from the track's last update's centroid [m] (2 = two gate
  /// margins, the earlier rule: one cluster within 2 m). Closer neighbours (parked cars in a row,
  /// bushes) are no ambiguity for a cluster that stayed within static_shift and kept its size.
  double static_clearance = 1.0;

  /// Velocity σ of a newborn track [m/s] (its velocity is unknown).
  double initial_velocity_sigma = 6.0;

  /// Gate: Mahalanobis distance bound of candidate centroids (chi²(2) 99 % ≈ 3.03).
  double gate_sigmas = 3.0;

  /// Extra gate radius for centroid shifts from changing views [m].
  double gate_margin = 1.0;

  /// Largest gate radius [m].
  double max_gate_radius = 4.0;

  /// Frames a track may go without an update (occlusion) before it is deleted.
  int max_missed_frames = 5;

  /// Upper bound on the number of live tracks (new clusters are not tracked beyond it).
  int max_tracks = 2000;

  /// 1 = at a track's third registered update its Kalman filter restarts from the least-squares
  /// line through its three positions (see MoverTracker), and a track whose first views were
  /// occluded (their positions slide while the object emerges) restarts again from the line
  /// through its first three unoccluded views (urban velocity RMS 0.357 -> 0.326 m/s); 0 = the
  /// filter runs on from birth.
  bool velocity_fit_init = true;

  /// 1 = a confirmed mover whose gated candidate failed registration (low B) keeps that cluster
  /// as its output row without an update, instead of the cluster starting a new track.
  bool hold_confirmed = true;

  /// Occlusion-aware measurements (0 = off): a cluster side (range image columns) counts as
  /// occluded when at least this fraction of its boundary cells is bounded by a nearer object
  /// point (RangeImageRegionGrowing::occludedSides()). The extent there is not the object's and
  /// changes while it emerges or hides, so its registered position slides: the reported-velocity
  /// filter skips such measurements (occluded_skip) or gives them the range-scaled σ, and early
  /// confirmation waits for an unoccluded view. 0.45 of 0.3 / 0.45 / 0.6 tried: at 0.3 the KITTI
  /// van and cyclist were flagged often enough to coast through real speed changes.
  double occluded_fraction = 0.45;

  /// Registered updates of occluded views the reported-velocity filter skips in a row while the
  /// track's velocity is known (from decision.min_age unoccluded views, or inherited on
  /// re-acquisition); later ones are taken with the range-scaled σ. The first update after a
  /// skipped run moves the filter's position to the measurement and keeps its velocity (and
  /// that velocity's σ from before the run): the slide has moved the reference point on the
  /// object, an offset that must not become a velocity. 0 = never skip.
  int occluded_skip = 10;

  /// Merged clusters (0 = off; registration mode): a cluster claimed by two or more established
  /// tracks (each with at least 4 of its points within split_claim_distance of the track's last
  /// view moved by its prediction), one a confirmed mover and the others confirmed or static,
  /// whose position lines differ by at least split_min_speed_difference and gate_sigmas times
  /// their σ is split between them (MoverTracker::splitMergedClusters()): two urban walkers
  /// passing each other were one cluster for 7 frames, one track carried the merged view with a
  /// velocity 0.5 m/s off and the other track died. Fragments of one object move alike and stay
  /// merged. Split parts count as occluded (their shared side is not the object's extent).
  bool split_merged = true;
  double split_claim_distance = 0.4;
  double split_min_speed_difference = 1.0;

  /// Re-acquisition after occlusion (0 = off; registration mode): a track born on a cluster near
  /// the predicted extent of a mover lost in the last frames (coasting) starts with that mover's
  /// velocity (σ `reacquire_velocity_sigma` [m/s]) instead of zero, and skips the line-fit restart
  /// of velocity_fit_init: its first positions slide while the object emerges from behind the
  /// occluder that hid it. An occluded cluster also inherits from a confirmed mover that is still
  /// tracked and moving (the front of a car emerging past a trunk while its track keeps the rear).
  bool reacquire_velocity = true;
  double reacquire_velocity_sigma = 1.0;

  /// Positions of growing and shrinking views from the edge the free space confirms
  /// (sweptEdgeShift(); registration mode, with the free-space map): where a view's extent along
  /// its length changed since the previous frame, the registered displacement along that axis is
  /// replaced by the move of the only edge that swept through space seen empty, and the view is
  /// not treated as occluded. Without it the registration's flat optimum lets a vehicle that
  /// emerges from or hides behind an occluder slide towards its prediction. Extents are those of
  /// the whole cluster. Tune split: vel. RMS 0.482 -> 0.438 m/s (highway 0.605 -> 0.558, trail
  /// 0.571 -> 0.421: trucks), hit 76.9 -> 76.8 %, false alarms 0.026 -> 0.025 (docs/design.md).
  bool swept_edges = true;
  SweptEdgesParameters swept;

  /** \brief Calls `f(key, member, description)` for every setting. */
  template <typename F>
  void forEachParameter(F&& f) {
    f("max_range", max_range, "clusters further than this are ignored [m]");
    f("mode", mode, "association: registration or centroid");
    f("acceleration_noise", acceleration_noise, "Kalman white-noise acceleration sigma [m/s^2]");
    f("sigma_from_scatter", sigma_from_scatter,
      "1 = reported velocity from a filter with sigma from the track's scatter");
    f("gate_sigmas", gate_sigmas, "gate: Mahalanobis bound");
    f("max_missed_frames", max_missed_frames, "frames a track coasts before deletion");
    f("velocity_fit_init", velocity_fit_init,
      "1 = restart the Kalman filter from a line fit at the 3rd registered update");
    f("hold_confirmed", hold_confirmed, "1 = confirmed movers keep low-B clusters (no update)");
    f("occluded_fraction", occluded_fraction,
      "min fraction of a cluster side's boundary next to a nearer object to call it occluded  (0 = "
      "off)");
    f("split_merged", split_merged, "1 = split clusters claimed by tracks that move differently");
    f("reacquire_velocity", reacquire_velocity,
      "1 = a track born where a coasting mover is predicted starts with its velocity");
    f("swept_edges", swept_edges,
      "1 = a growing or shrinking view's position from the edge whose move the free space "
      "confirms");
  }

  /** \brief Calls `f(key, member, description)` for every constant of this stage's rules:
   * values measured once and fixed, not settings (docs/design.md, "Settings"). They stay
   * members so that the unit tests of a rule, and library users studying it, can vary them. */
  template <typename F>
  void forEachConstant(F&& f) {
    f("acceleration_limit", acceleration_limit,
      "updates implying more acceleration are rejected [m/s^2]");
    f("registration_sigma", registration_sigma, "sigma of a registered position [m]");
    f("centroid_sigma", centroid_sigma, "sigma of a centroid position [m]");
    f("measurement_sigma_per_metre", measurement_sigma_per_metre,
      "position sigma per metre of range");
    f("manoeuvre_window", manoeuvre_window, "registered positions of the manoeuvre test");
    f("manoeuvre_sigmas", manoeuvre_sigmas, "manoeuvre: acceleration significance [sigma]");
    f("static_refresh_frames", static_refresh_frames,
      "register still static tracks every N frames");
    f("static_shift", static_shift,
      "max centroid shift of a still static track since its last update [m]");
    f("static_clearance", static_clearance,
      "other clusters this close make a still static track register [m]");
    f("initial_velocity_sigma", initial_velocity_sigma, "velocity sigma of a new track [m/s]");
    f("gate_margin", gate_margin, "gate: extra radius for centroid shifts [m]");
    f("max_gate_radius", max_gate_radius, "gate: largest radius [m]");
    f("max_tracks", max_tracks, "cap on live tracks");
    f("occluded_skip", occluded_skip,
      "occluded registered updates in a row the reported velocity coasts through");
    f("split_claim_distance", split_claim_distance,
      "max distance of a claimed point from the track's predicted view [m]");
    f("split_min_speed_difference", split_min_speed_difference,
      "min velocity difference of tracks whose shared cluster is split [m/s]");
    f("reacquire_velocity_sigma", reacquire_velocity_sigma,
      "velocity sigma of such a re-acquired track [m/s]");
    f("swept_min_change", swept.min_change,
      "swept edges: min change of a view's extent along its length [m]");
    f("swept_min_elongation", swept.min_elongation,
      "swept edges: min ratio of a view's length to its width (standard deviations)");
    f("swept_min_points", swept.min_points, "swept edges: min judged points of a swept strip");
    f("swept_min_fraction", swept.min_fraction,
      "swept edges: min fraction of a strip's judged points seen through");
  }
};

/** \brief The mover decision of MoverTracker: which tracks are reported as movers
 * (`decision.*` keys of DetectorParameters; each decision's reason is a MoverReason). */
struct DecisionParameters {
  /// Only clusters up to this long [m] and tall [m] can be movers and are registered; larger
  /// ones (buildings, walls, hedges) are tracked by centroid and always static.
  double max_length = 12.0;
  double max_height = 4.5;

  /// Clusters lower than this are not movers [m] (kerbs, ground clutter). The tracker compares the
  /// tallest view of a track (a van seen from straight behind can show a lower cluster).
  double min_height = 0.8;

  /// Speed above which a track counts as moving [m/s].
  double speed = 1.2;

  /// A speed only counts as fast when it is also this many standard deviations above zero.
  double speed_sigmas = 2.0;

  /// 1 = the speed vote of a registered update uses the least-squares line through the measured
  /// positions of the window (σ from their scatter about it, at least track.registration_sigma); 0
  /// = the Kalman velocity and its covariance (σ from track.measurement_sigma_per_metre · range),
  /// which centroid updates always use.
  bool fast_from_fit = true;

  /// A track is a mover when its speed exceeded speed in votes of its last
  /// window updates, it has at least min_age updates, and the displacement of its
  /// measurements over the window is consistent with that speed.
  /// Sustained slow motion (0 = off): a track whose positions over the last slow_window seconds
  /// (five at least) lie on a line faster than slow_speed and at most speed, significantly so
  /// (the F-test of confirm_false_rate, σ from the scatter about the line, at least
  /// track.registration_sigma), counts as moving although it gets no speed votes. A walker
  /// at 0.6 m/s covers 0.9 m in 1.5 s, while registration wobble of a parked car does not lie on
  /// a line; the free-space (slowFreeSpaceEvidence()) and height tests still apply. Tune split:
  /// 1.0 s 0.040 FA/frame, 1.5 s 66.6 % hit 0.033, 2.0 s 66.2 % 0.032.
  double slow_window = 1.5;
  double slow_speed = 0.4;
  int window = 5;
  int votes = 3;
  int min_age = 4;

  /// Displacement check: net measured displacement over the window must be at least this
  /// fraction of speed × elapsed time.
  double displacement_ratio = 0.6;

  /// Early confirmation of well-measured motion (0 = off): a registered track whose measured
  /// positions determine its velocity beyond doubt need not wait for votes of window
  /// votes and min_age updates. Its window's least-squares line (σ from the scatter of the
  /// positions about it, at least confirm_sigma_floor) must be faster than speed and pass an
  /// F-test of "velocity = 0" at this false-positive rate: |v|² / (2 σ_v²) ≥ F(2, 2(n-2)) quantile,
  /// i.e. |v| / σ_v ≥ 44.7 / 11.1 / 7.3 / 6.1 at 3 / 4 / 5 / 6 positions. The displacement and
  /// height tests still apply, and confirm_free_space_votes free-space tests must have passed.
  double confirm_false_rate = 0.001;

  /// Lower bound on the position σ of that test [m]: registration errors are not only white noise
  /// (the sub-cell fit's median error is ~0.02 m), so a line through 3-4 nearly collinear positions
  /// is not credited with a vanishing σ.
  double confirm_sigma_floor = 0.02;

  /// Only tracks whose last update registered with at least this similarity and had at least this
  /// many points are confirmed early (sparse or poorly matched views keep the M-of-N rule: their
  /// registrations can jump between partial views consistently enough to look like a line; with
  /// no B bound a simulated wooded shrub was confirmed). 0.8 is a confident match, as
  /// registration.stop_similarity; 12 points keeps the 8-11-point clusters
  /// segment.min_cluster_points admits on the vote rule.
  double confirm_min_similarity = 0.8;
  int confirm_min_points = 12;

  /// Free-space tests that must have passed for an early confirmation (free_space.votes otherwise).
  int confirm_free_space_votes = 1;

  /// Once confirmed, a track stays a mover while it is tracked (1) or is re-decided every update
  /// (0).
  bool latch = true;

  /// 1 = a view's height, for the min_height test, is measured from what the object stands on:
  /// the ground under it (the ground filter's plane there: a car seen by one or two beams of a
  /// sparse sensor shows a 0.1 m slice whose top stands 1.2 m above the road) or, when a nearer
  /// object hides its lower part (RangeImageRegionGrowing::occluderFloors(): at least half its
  /// bottom cells have a nearer object right below), that object's lowest point (a walker seen
  /// only above a parked car shows a 0.3 m head and shoulders); 0 = its visible extent.
  bool standing_height = true;

  /** \brief Calls `f(key, member, description)` for every setting. */
  template <typename F>
  void forEachParameter(F&& f) {
    f("min_height", min_height, "lower clusters are never movers [m]");
    f("speed", speed, "speed threshold of a mover [m/s]");
    f("speed_sigmas", speed_sigmas, "fast only if speed > this * its sigma");
    f("slow_window", slow_window, "window of the sustained-slow-motion test [s] (0 = off)");
    f("window", window, "mover decision window N [updates]");
    f("votes", votes, "fast updates M of the last N needed");
    f("min_age", min_age, "min updates of a mover track K");
    f("displacement_ratio", displacement_ratio, "min net displacement / (mover_speed * time)");
    f("confirm_false_rate", confirm_false_rate,
      "early confirmation: F-test false-positive rate of velocity = 0 (0 = off)");
    f("latch", latch, "1 = a confirmed mover stays a mover while tracked");
    f("standing_height", standing_height,
      "1 = a view's height is measured from the ground under it or a nearer object hiding its "
      "lower part");
  }

  /** \brief Calls `f(key, member, description)` for every constant of this stage's rules:
   * values measured once and fixed, not settings (docs/design.md, "Settings"). They stay
   * members so that the unit tests of a rule, and library users studying it, can vary them. */
  template <typename F>
  void forEachConstant(F&& f) {
    f("max_length", max_length, "longer clusters are static, tracked by centroid [m]");
    f("max_height", max_height, "taller clusters are static, tracked by centroid [m]");
    f("fast_from_fit", fast_from_fit,
      "1 = speed votes from a line fit of the measured positions, 0 = Kalman velocity");
    f("slow_speed", slow_speed, "min speed of sustained slow motion [m/s]");
    f("confirm_sigma_floor", confirm_sigma_floor, "early confirmation: min position sigma [m]");
    f("confirm_min_similarity", confirm_min_similarity, "early confirmation: min B of the update");
    f("confirm_min_points", confirm_min_points, "early confirmation: min points of the cluster");
    f("confirm_free_space_votes", confirm_free_space_votes,
      "early confirmation: passed free-space tests needed");
  }
};

/** \brief The free-space evidence of the mover decision (FreeSpaceMap; `free_space.*`
 * keys of DetectorParameters). */
struct FreeSpaceParameters {
  /// Free-space test (FreeSpaceMap): a mover must occupy space the scan lag frames ago
  /// saw through, or have left space the current scan sees through (0 = test off). 5 frames at
  /// 10 Hz: a target at decision.speed has moved 0.6 m, twice the near margin. In a sequence's
  /// first frames, before that many earlier scans exist, the oldest one is tested.
  int lag = 5;

  /// A second, longer lag tried when the lag test fails (0 = off): a slow mover
  /// approaching far away (a pedestrian walking towards the sensor at 50 m) moves less in
  /// lag frames than the range-scaled margin (1.3 m at 50 m), so only an older scan
  /// can have seen its space empty. Static objects give no evidence at any lag.
  int long_lag = 15;

  /// Fraction of the points the long_lag test needs: a mover has moved three times
  /// further by then and is mostly seen through (urban walker at 50 m: 70-100 %), while the
  /// spurious evidence of a static object (foliage gaps, a changed viewpoint) does not grow with
  /// the lag (a KITTI bush: 32 %).
  double long_min_fraction = 0.5;

  /// Motion shows at a lag when the object covers this many margins (below) at its range in
  /// that time: lag was chosen so that a target at decision.speed moves twice the near margin.
  /// A fast-voted track that does not at lag (a walker at 1.3 m/s 30 m away: 0.65 m against a
  /// 0.6 m margin) is also tested at long_lag, as slow motion is, once its registered positions
  /// lie on a line (MoverDecision::shortLagTooShort). Tune split: hit 71.5 -> 72.3 % (urban
  /// 76.4 -> 78.3, parking 61.5 -> 63.2), median delay 8 -> 6.5 frames, false alarms 0.041 ->
  /// 0.042 per frame; 0 = off.
  double lag_margins = 2.0;

  /// A view whose surface is rougher than this [m] (clusterRoughness(): the median range step
  /// between its range-image neighbours) is porous, foliage, and gives no free-space vote: rays
  /// pass through foliage whether it moves or not. Sensor noise gives steps of a few
  /// centimetres, a tree's canopy tenths of a metre (simulated corpus: walkers and cars 0.04 m,
  /// trees 0.36-0.53 m). 0 = off.
  double porous_roughness = 0.2;

  /// Fraction of a view's judged points in space the scan lag frames ago saw empty with which
  /// the view's own speed vote makes its track a mover without the vote counts
  /// (MoverDecision::fillsFreeSpace; 0 = off): most of a view, not a few mixed edge pixels, as
  /// long_min_fraction. Tune split: hit 74.4 -> 75.2 %, false alarms 0.031 -> 0.032 per frame
  /// (docs/design.md, decision log).
  double alone_fraction = 0.5;

  /// Fraction of the tested points that must be seen through, and at least this many points.
  double min_fraction = 0.2;
  int min_points = 3;

  /// Tests that must pass (among the last decision.window ones) before a track is confirmed. Tests
  /// run on every fast update from a track's third update on, in parallel with the speed votes.
  int votes = 2;

  /// Seen through = the earlier range exceeds the point's distance by max(margin,
  /// margin_per_metre · distance) [m, m/m] (range noise, pose error, beam footprint).
  double margin = 0.3;
  double margin_per_metre = 0.02;

  /// 1 = a downward direction in which an earlier scan got no return at all counts as seen
  /// empty up to track.max_range; 0 = such a direction is unknown. A downward ray passes every
  /// object standing on the ground before it reaches the ground, and the sensors this is for return
  /// from cars, people and foliage well beyond track.max_range (HDL-64E: 120 m), so a ray that
  /// returned nothing passed the object's place while it was empty. Without this, an object
  /// entering the scene at track.max_range has no evidence until it is lag frames inside, because
  /// the space it fills was last seen by rays that reached past track.max_range (urban car 1 at 80
  /// m: confirmed 2 frames later). Upward rays are left unknown: their no-returns are sky seen past
  /// porous canopy, which says nothing about the leaves the next scan hits in that direction
  /// (wooded: 31-53 false alarms per 160 frames when they counted). Only where a beam was cast
  /// (FreeSpaceMap: not between a sparse sensor's beams) and only for rays that stay above the
  /// ground (ground.sensor_height below) up to track.max_range: a steeper silent ray met something
  /// closer than the sensor's minimum range, or its return dropped (tune split: 0.887 -> 0.049
  /// false alarms per frame, parked cars passed at 2 m).
  bool no_return = true;

  /// Motion-aware segmentation (MotionSplitter): a cluster holding both points that the scan
  /// long_lag frames ago saw through and points it saw where they are is split into its moving
  /// part(s) and its static rest, so that a walker beside a wall, hedge or parked car is tracked
  /// on its own. false = clusters as region growing made them.
  bool split = true;

  /** \brief Calls `f(key, member, description)` for every setting. */
  template <typename F>
  void forEachParameter(F&& f) {
    f("lag", lag, "free-space test against the scan this many frames ago (0 = off)");
    f("long_lag", long_lag,
      "longer lag tried when the free_space_lag test fails [frames] (0 = off)");
    f("no_return", no_return,
      "1 = no return below the sensor in an earlier scan = seen empty up to max_range");
    f("split", split, "1 = split a cluster's seen-through part from its static rest");
  }

  /** \brief Calls `f(key, member, description)` for every constant of this stage's rules:
   * values measured once and fixed, not settings (docs/design.md, "Settings"). They stay
   * members so that the unit tests of a rule, and library users studying it, can vary them. */
  template <typename F>
  void forEachConstant(F&& f) {
    f("long_min_fraction", long_min_fraction, "min fraction seen through at free_space_long_lag");
    f("alone_fraction", alone_fraction,
      "fraction of a view seen through at lag that, with its speed vote, makes a mover, 0 = off");
    f("min_fraction", min_fraction, "min fraction of points seen through");
    f("min_points", min_points, "min number of points seen through");
    f("votes", votes, "passed free-space tests needed to confirm");
    f("margin", margin, "seen-through range margin [m]");
    f("margin_per_metre", margin_per_metre, "margin per metre of distance");
    f("porous_roughness", porous_roughness,
      "a view rougher than this [m] is porous and gives no free-space vote, 0 = off");
    f("lag_margins", lag_margins,
      "margins an object covers in lag frames for its motion to show (else long_lag too)");
  }
};

}  // namespace pcl_movers
