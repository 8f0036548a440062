/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/bhattacharya_registration.h>
#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/free_space_map.h>
#include <pcl_movers/kalman_filter_cv.h>
#include <pcl_movers/observation.h>
#include <pcl_movers/surface_density.h>

#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace pcl_movers {
/** \brief The last few values a track keeps (positions, votes, views), oldest first.
 *
 * A vector with pop_front(), not a std::deque: a deque allocates even when it is moved from, and
 * its move may throw, so std::vector<Track> copied every track (all its views and points) each
 * time it grew, and every birth and deletion allocated a dozen times (about 8 M instructions a
 * KITTI frame). The windows hold at most a few dozen values: shifting them is cheap. */
template <typename T>
class Fifo : public std::vector<T> {
 public:
  void pop_front() { this->erase(this->begin()); }
};

/** \brief The test of the mover decision that settled a track's last update, in the order
 * MoverTracker tests them: why an object is, or is not, a mover (tracks.csv `reason`). */
enum class MoverReason : std::uint8_t {
  kNew,           ///< seen once: no motion measured yet
  kLarge,         ///< larger than any mover: static structure, tracked by its centroid
  kYoung,         ///< fewer than mover_min_age updates and its motion not yet beyond doubt
  kLow,           ///< lower than min_mover_height in every view
  kNoMotion,      ///< neither fast motion (speed votes) nor sustained slow motion
  kNoFreeSpace,   ///< moves, but too few of its views fall in space earlier scans saw empty
  kFast,          ///< mover: speed votes and free-space evidence
  kWellMeasured,  ///< mover while young: its displacement beyond doubt and seen through
  kSustained,     ///< mover: sustained slow motion (slow_window) and free-space evidence
  kLatched        ///< mover: confirmed by mover_window decisions in a row (mover_latch)
};

/** \brief The name of a reason as tracks.csv writes it: new, large, young, low, no_motion,
 * no_free_space, fast, well_measured, sustained, latched. */
inline const char* moverReasonName(MoverReason reason) {
  static const char* const names[] = {"new",       "large",         "young", "low",
                                      "no_motion", "no_free_space", "fast",  "well_measured",
                                      "sustained", "latched"};
  return names[static_cast<int>(reason)];
}

/** \brief Tracks every object cluster of a LiDAR sequence and decides which are movers
 * (Morris et al., section 6).
 *
 * Each frame, update() receives the clusters of one scan in the **world** frame. Every track
 * (static objects too) carries a constant-velocity KalmanFilterCV on its horizontal position and,
 * in the default registration mode, an accumulated SurfaceDensity model:
 *
 *  1. predict all tracks to the frame time;
 *  2. gate: a cluster is a candidate of a track when its centroid lies within
 *     `gate_sigmas`·σ (innovation covariance) + ½·`acceleration_limit`·dt² + `gate_margin` of the
 *     predicted centroid (predicted reference point + the centroid offset of the last update),
 *     at most `max_gate_radius` (the acceleration limit bounds the search);
 *  3. registration mode: each candidate is registered with BhattacharyaRegistration against the
 *     track's model, the search window centred on the prediction and as wide as the gate; its
 *     similarity B is the association score and B < `min_similarity` is not an update (occlusion
 *     or wrong object). Centroid mode (the paper's "simplest approach", for comparison): the
 *     measurement is the cluster centroid and the score is minus the centroid distance;
 *  4. pairs are assigned greedily, best score first, one cluster per track and one track per
 *     cluster; the Kalman filter is updated with the measured position; the registered view is
 *     accumulated into the model with a half-life of `model_half_life` frames;
 *  5. unmatched tracks coast (prediction only) and are deleted after `max_missed_frames`; a
 *     confirmed mover holds a cluster near its prediction that failed to register, and after
 *     `max_missed_frames` such frames restarts its model from it when the held clusters moved
 *     along its path (reanchorTrack()); unmatched clusters start new tracks (at most
 *     `max_tracks` live tracks);
 *  6. mover decision: speed > `mover_speed` (and > `mover_speed_sigmas` times its own standard
 *     deviation, so young or far tracks with vague velocities wait) in `mover_votes` of the last
 *     `mover_window` updates,
 *     at least `mover_min_age` updates, the tallest view at least `min_mover_height`, the net
 *     displacement of the measurements over the
 *     window at least `displacement_ratio`·`mover_speed`·elapsed time (a filter velocity inflated
 *     by a few noisy measurements does not survive this check), and — when a FreeSpaceMap is set —
 *     free-space evidence (tests run on every fast update from the third on, in parallel with
 *     the speed votes): at least `free_space_min_fraction` of the object's points lie in space
 *     an earlier scan saw through, or its earlier points lie in space the current scan sees
 *     through (FreeSpaceMap). Static objects cannot produce this evidence, whatever their
 *     registration or segmentation errors, so it rejects the centroid-shift and registration-slip
 *     false alarms the kinematic rules let through;
 *     Early confirmation (`confirm_false_rate`): a track whose last update registered well
 *     (B ≥ `confirm_min_similarity`, ≥ `confirm_min_points` points) and whose window's line fit
 *     rejects "velocity = 0" in an F-test at that false-positive rate (σ from the scatter, at
 *     least `confirm_sigma_floor`) while being faster than `mover_speed` skips the vote count
 *     and the minimum age, and needs `confirm_free_space_votes` free-space tests;
 *  7. latching (`mover_latch`): a track decided mover in `mover_window` consecutive updates stays
 *     a mover while its track lives (a car waiting at a light, a pedestrian pausing), unless it
 *     becomes a large structure.
 *
 * Before update(), splitMergedClusters() cuts clusters that hold two established tracks moving
 * differently (walkers passing each other) along their predicted views; MoverDetector does so
 * every frame (`split_merged`).
 *
 * The registered measurement is the track's reference point: the model grid is centred where the
 * object was first seen and the registration maps each new view onto it, so the measured position
 * is that reference point moved by the registered motion. It does not shift when a different part
 * of the object is seen, which is the point of registering instead of using centroids.
 *
 * Cost control (documented design choice, `static_refresh_frames`): an established, slow,
 * non-mover track whose single gated candidate's centroid moved less than `static_shift` is
 * registered only every `static_refresh_frames` frames; in between it is marked seen without a
 * Kalman update (its velocity is near zero anyway). Any centroid jump, ambiguity or speed-up
 * brings registration back at once. `static_refresh_frames = 1` registers every track every frame,
 * as in the paper.
 *
 * Practical limits (documented design choices): clusters longer than `max_mover_length` or taller
 * than `max_mover_height` (buildings, walls, hedges, tree rows) are tracked by centroid only and
 * are never movers — registering them would be expensive and their centroids move with the view;
 * clusters lower than `min_mover_height` are never movers. Tracks and models are bounded: each
 * track owns one fixed-size grid, tracks die after `max_missed_frames` and their number is capped.
 */
template <typename PointT>
class MoverTracker {
 public:
  using PointCloud = pcl::PointCloud<PointT>;
  using PointCloudPtr = typename PointCloud::Ptr;
  using PointCloudConstPtr = typename PointCloud::ConstPtr;
  using Ptr = pcl::shared_ptr<MoverTracker<PointT>>;
  using ConstPtr = pcl::shared_ptr<const MoverTracker<PointT>>;

  /** \brief Geometry of one cluster in the world frame. */
  struct ClusterFeatures {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    double length = 0, width = 0, height = 0;  ///< oriented box in the horizontal plane, z extent
    double yaw = 0;                            ///< heading of the box's long side [rad], world
    double min_z = 0, max_z = 0;
    int points = 0;
    bool large = false;  ///< longer/taller than any mover: tracked by centroid, never a mover
    /// A side of the cluster is bounded by a nearer object (see update()): its extent there is
    /// not the object's, and its measured position can slide while it emerges or hides.
    bool occluded = false;
    /// What the object stands on (world z): the lowest point of a nearer object hiding its lower
    /// part (a parked car below a walker's head), else the ground under it; NaN = unknown.
    double floor_z = std::numeric_limits<double>::quiet_NaN();
  };

  /** \brief One track. Positions and velocities are in the world frame. */
  struct Track {
    int id = 0;
    KalmanFilterCV filter;
    double z = 0;          ///< height of the reference point (from the last measurement)
    double last_time = 0;  ///< time of the last update
    int hits = 0;          ///< updates so far
    /// Born with the velocity of a coasting mover it re-acquires (see reacquire_velocity).
    bool reacquired = false;
    /// The velocity inherited at birth (reacquired tracks), kept apart from the filter, whose
    /// velocity follows the centroids of the partial views until the track gets its model.
    Eigen::Vector2d inherited_velocity = Eigen::Vector2d::Zero();
    int occluded_run = 0;  ///< consecutive registered updates of occluded views
    /// Centroid (x, y) and time of the first cluster held since the last update (holdClusters);
    /// time NaN while no cluster is held.
    Eigen::Vector3d held_from = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    /// Yaw [rad] that turns the track's current views onto its model (turn_yaw_samples).
    double model_yaw = 0;
    /// Consecutive occluded updates the velocity filter skipped (occluded_skip).
    int skipped_run = 0;
    /// Velocity covariance of the velocity filter when the skipped run began.
    Eigen::Matrix2d skip_velocity_covariance = Eigen::Matrix2d::Zero();
    int unoccluded_updates = 0;  ///< registered updates of unoccluded views so far
    /// A view of the track was occluded (birth included): its velocity_fit_init line may hold
    /// sliding positions.
    bool seen_occluded = false;
    /// (x, y, time) of the first run of kUnoccludedFitPositions consecutive registered
    /// unoccluded positions (shorter while it is being collected).
    Fifo<Eigen::Vector3d> unoccluded_positions;
    int age = 0;                             ///< frames since birth
    int missed = 0;                          ///< consecutive frames without update
    bool mover = false;                      ///< mover decision after the last update
    MoverReason reason = MoverReason::kNew;  ///< the test that settled `mover`
    bool large = false;                      ///< static structure tracked by centroid
    double similarity = 0;     ///< B of the last update (0 in centroid mode / at birth)
    ClusterFeatures features;  ///< geometry of the last cluster assigned
    /// Cluster centroid minus measured reference point at the last update (x, y): the reference
    /// point stays where the object was first seen while the visible part (and so the centroid)
    /// changes with the view, so candidates are gated against the predicted *centroid*.
    Eigen::Vector2d centroid_offset = Eigen::Vector2d::Zero();
    /// Tallest (not large) view of the object so far [m]: the height test of the mover decision
    /// uses it, as a van seen from straight behind can show a lower cluster than its height.
    double max_height = 0;
    /// The same with views hidden from below measured down to what hides them (standingHeight()).
    double max_standing_height = 0;
    /// Longest (not large) view of the object so far [m]: how far from the last visible part
    /// another part of it can reappear (see reacquire_velocity).
    double max_length = 0;
    Fifo<char> fast;                ///< speed > mover_speed after each of the last updates
    Fifo<Eigen::Vector3d> history;  ///< (x, y, time) of the last measurements
    /// (x, y, time) of the measurements of the last slow_window seconds (sustainedMotion()).
    Fifo<Eigen::Vector3d> long_history;
    /// (x, y, time) of the last registered measurements (manoeuvre_window of them), for the
    /// manoeuvre test of registeredSigma().
    Fifo<Eigen::Vector3d> registered;
    /// Reported velocity (registration mode): a second constant-velocity filter on the registered
    /// positions whose σ follows the registrations (registeredSigma()), while `filter`, which
    /// gates, searches and decides, keeps the conservative range-scaled σ. Uninitialized until
    /// the first registered update (or with measurement_sigma_from_scatter = 0).
    KalmanFilterCV velocity_filter;
    /// The velocity reported for the track: velocity_filter's once initialized, else filter's.
    Eigen::Vector2d reportedVelocity() const {
      return velocity_filter.isInitialized() ? velocity_filter.velocity() : filter.velocity();
    }
    SurfaceDensity::Ptr model;   ///< accumulated surface density (registration mode)
    int since_registration = 0;  ///< cheap (unregistered) frames since the last registration
    bool confirmed = false;      ///< latched mover (see mover_latch)
    int mover_run = 0;           ///< consecutive updates decided mover (latched after mover_window)
    double free_space = 0;       ///< free-space evidence of the last test (fraction seen through)
    Fifo<char> free_votes;       ///< free-space test passed, for each of the last tests
    /// World points of the last updates (subsampled), oldest first, for the free-space test.
    Fifo<std::vector<Eigen::Vector3f>> past_points;
    /// World points of the last update's view (at most kLastViewPoints), for
    /// splitMergedClusters().
    std::vector<Eigen::Vector3f> last_view;
    /// last_view of the last free_space.long_lag updates, oldest first: the receding test of
    /// sustained slow motion (slowFreeSpaceEvidence()).
    Fifo<std::vector<Eigen::Vector3f>> past_views;
  };
  static_assert(std::is_nothrow_move_constructible<Track>::value,
                "std::vector<Track> must move its tracks when it grows, not copy them (see Fifo)");
  static constexpr std::size_t kLastViewPoints = 64;
  /// Unoccluded registered positions the filters restart from (see velocity_fit_init).
  static constexpr int kUnoccludedFitPositions = 3;
  /// Smallest part splitMergedClusters() cuts off, and tracks (see update()).
  static constexpr int kMinSplitPoints = 4;

  /** \brief A cluster of the frame after splitMergedClusters(): the input cluster it comes from
   * and the positions, in that cluster's index list, of its points. */
  struct ClusterPart {
    int cluster = -1;
    std::vector<int> positions;
  };

  /** \brief What happened to one input cluster in the last update(). */
  struct ClusterResult {
    int track_id = -1;  ///< -1: not tracked (too small, or the track cap was reached)
    bool mover = false;
    MoverReason reason = MoverReason::kNew;  ///< why it is, or is not, a mover
    double similarity = 0;
    Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  ///< world [m/s]
    ClusterFeatures features;
  };

  MoverTracker() = default;
  /** \brief A copy owns copies of the tracks' models, so that the copy and the original can both
   * keep tracking (sharing them, each would accumulate its views into the other's models). Work
   * buffers are not copied. */
  MoverTracker(const MoverTracker& other);
  MoverTracker& operator=(const MoverTracker& other);
  MoverTracker(MoverTracker&&) = default;
  MoverTracker& operator=(MoverTracker&&) = default;
  ~MoverTracker() = default;

  /** \brief Uses the tracker and registration entries of `parameters` (validated by the caller). */
  void setParameters(const DetectorParameters& parameters) { parameters_ = parameters; }
  const DetectorParameters& getParameters() const { return parameters_; }

  /** \brief Processes one frame.
   * \param cloud points in the world frame (may be organized with NaN; only the observations'
   * points are read) \param observations this frame's object clusters (Observation: indices into
   * `cloud`, occlusion, split part, floor) \param sensor_origin sensor position in the world
   * frame (ranges → density σ) \param time frame time [s], increasing */
  void update(const PointCloudConstPtr& cloud, const std::vector<Observation>& observations,
              const Eigen::Vector3d& sensor_origin, double time);
  /** \brief update() for plain clusters (nothing known besides their points). */
  void update(const PointCloudConstPtr& cloud, const std::vector<pcl::PointIndices>& clusters,
              const Eigen::Vector3d& sensor_origin, double time) {
    update(cloud, observationsOf(clusters), sensor_origin, time);
  }

  /** \brief Splits the clusters that hold the predicted objects of two or more established tracks
   * moving differently (two walkers passing each other, a cyclist beside a parked car): region
   * growing joins objects that touch, and a merged cluster would update one track with both
   * objects' points while the other coasts and dies. Call before update() with the same frame
   * time. A track (established, seen in the last 3 frames) claims a cluster when at least
   * kMinSplitPoints of its points lie within split_claim_distance of the track's last view moved
   * by its predicted motion; a cluster claimed by a confirmed mover and another confirmed or
   * static track whose position lines differ by split_min_speed_difference and gate_sigmas
   * times their σ is split, each point going to the claimer whose moved view is nearest.
   * \return empty when nothing was split (the clusters stand as they are), else one part per
   * output cluster, in order: unsplit clusters whole, split ones as several parts. */
  std::vector<ClusterPart> splitMergedClusters(const PointCloud& cloud,
                                               const std::vector<Observation>& observations,
                                               double time) const;
  /** \brief The clusters `parts` (from splitMergedClusters()) describe, cut from `clusters` — or
   * from any list parallel to it (MoverDetector cuts its world and sensor-frame lists alike). */
  static std::vector<pcl::PointIndices> applyParts(const std::vector<ClusterPart>& parts,
                                                   const std::vector<pcl::PointIndices>& clusters);
  /** \brief The observations `parts` describe, cut from `observations`: a whole one as it was,
   * a part cut from one marked Observation::split_part (and occluded), on the whole's floor. */
  static std::vector<Observation> applyParts(const std::vector<ClusterPart>& parts,
                                             const std::vector<Observation>& observations);

  /** \brief Scans for the free-space test (see DetectorParameters::free_space_lag); the map must
   * already hold the current frame's scan when update() is called. nullptr (default) disables the
   * test. Not owned. */
  void setFreeSpaceMap(const FreeSpaceMap* map) { free_space_map_ = map; }
  const FreeSpaceMap* getFreeSpaceMap() const { return free_space_map_; }

  /** \brief Per input cluster of the last update(), in input order. */
  const std::vector<ClusterResult>& getClusterResults() const { return results_; }
  /** \brief Live tracks (updated or coasting). */
  const std::vector<Track>& getTracks() const { return tracks_; }
  /** \brief The track with this id, or nullptr. */
  const Track* findTrack(int id) const;
  /** \brief Number of registrations run in the last update() (for profiling). */
  int getRegistrationCount() const { return registrations_; }
  /** \brief Total number of tracks ever started. */
  int getTracksStarted() const { return next_id_; }

  /** \brief Least-squares line through measured positions (x, y, time), see fitVelocity(). */
  struct LineFit {
    bool valid = false;  ///< false with fewer than 3 positions or no time span
    Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  ///< slope of the line [m/s]
    /// σ of the velocity per axis: `sigma` / sqrt(`time_spread`); infinite when not valid.
    double sigma_v = std::numeric_limits<double>::infinity();
    /// σ of one position about the line per axis (the scatter, at least the floor) [m].
    double sigma = std::numeric_limits<double>::infinity();
    Eigen::Vector2d mean_position = Eigen::Vector2d::Zero();  ///< centre of the line
    double mean_time = 0;                                     ///< time of mean_position [s]
    double time_spread = 0;                                   ///< Σ (t - mean_time)² [s²]
    std::size_t positions = 0;
  };

  /** \brief Least-squares line through measured positions (x, y, time): its velocity, the
   * velocity's σ (per axis) from the scatter of the positions about the line (at least
   * `min_sigma`), and the means and spread a caller needs to restart a filter from the line. */
  static LineFit fitVelocity(const std::vector<Eigen::Vector3d>& history, double min_sigma);

  /** \brief The |v| / σ_v a line fit of `positions` positions must reach for "velocity = 0" to be
   * rejected at `false_rate`: with σ estimated from the scatter (2 (n - 2) degrees of freedom,
   * σ_v as LineFit::sigma_v), |v|² / (2 σ_v²) of a static object follows F(2, 2 (n - 2)), whose
   * quantile has the closed form ν/2 · (false_rate^(-2/ν) - 1). Infinite below 3 positions. */
  static double speedSignificanceRatio(std::size_t positions, double false_rate);

  /** \brief Least-squares quadratic through measured positions (x, y, time), see
   * fitAcceleration(). */
  struct QuadraticFit {
    bool valid = false;  ///< false with fewer than 4 positions or a degenerate time spread
    Eigen::Vector2d acceleration = Eigen::Vector2d::Zero();  ///< second derivative [m/s²]
    /// σ of the acceleration per axis, from `sigma`; infinite when not valid.
    double sigma_a = std::numeric_limits<double>::infinity();
    /// σ of one position about the quadratic per axis (the scatter, at least the floor) [m].
    double sigma = std::numeric_limits<double>::infinity();
  };

  /** \brief Least-squares quadratic `p + v·τ + a·τ²/2` through measured positions (x, y, time):
   * its acceleration and the acceleration's σ (per axis) from the scatter of the positions about
   * the quadratic (at least `min_sigma`). */
  static QuadraticFit fitAcceleration(const std::vector<Eigen::Vector3d>& positions,
                                      double min_sigma);

  /** \brief Forgets all tracks. */
  void reset();

  /** \brief Geometry of a set of points (centroid, oriented box from the horizontal principal
   * axes). */
  static ClusterFeatures computeFeatures(const PointCloud& cloud, const pcl::Indices& indices);

 protected:
  struct Candidate {
    PointCloudPtr points;  ///< the cluster's points (built lazily in registration mode)
    ClusterFeatures features;
    bool usable = false;  ///< enough points to track
  };
  struct Match {
    double score = 0;
    std::size_t track = 0, cluster = 0;
    Eigen::Vector3d measurement = Eigen::Vector3d::Zero();
    double similarity = 0;
    /// Registered motion (cluster → model), from which the view accumulated into the model is
    /// built once the match is assigned (most registered pairs are not).
    Eigen::Matrix<float, 4, 4, Eigen::DontAlign> transform =
        Eigen::Matrix<float, 4, 4, Eigen::DontAlign>::Identity();
    bool registered = false;
    bool cheap = false;  ///< static track seen without registration
  };

  /** \brief Where a track looks for its object this frame (association). */
  struct TrackGate {
    std::size_t track = 0;
    Eigen::Vector2d predicted = Eigen::Vector2d::Zero();  ///< predicted reference point
    double prior_search = 0;  ///< the velocity prior's gate radius (without margin) [m]
    double search = 0;        ///< radius searched (prior_search, or further for a young track)
    /// (centroid distance to the predicted centroid, cluster) of the candidates in the gate.
    std::vector<std::pair<double, std::size_t>> candidates;
  };

  /** \brief What the steps of one update() share. */
  struct Frame {
    const PointCloud& cloud;                       ///< the clusters' points, world frame
    const std::vector<Observation>& observations;  ///< this frame's clusters
    Eigen::Vector3d sensor_origin;                 ///< world frame
    double time;                                   ///< frame time [s]
    double dt;                                     ///< since the last frame [s]
    bool use_registration;                         ///< registration mode (else centroid)
    float model_weight;  ///< SurfaceDensity::halfLifeWeight() of model_half_life
  };
  /** \brief One frame's association: every gated (track, cluster) pair with its score, best
   * first, and per track the nearest cluster a confirmed mover could hold (hold_confirmed). */
  struct Association {
    std::vector<Match> matches;
    std::vector<double> held_distance;
    std::vector<int> held_cluster;  ///< -1: none
  };

  // The steps of update(), in order.
  /** \brief Moves every track's filters `dt` seconds ahead. */
  void predictTracks(double dt);
  /** \brief One candidate per cluster: its features and whether it can be tracked. */
  std::vector<Candidate> makeCandidates(const Frame& frame);
  /** \brief Per track, the cluster an established static track is seen in without registration
   * this frame (static_refresh_frames), or -1. */
  std::vector<int> findStillClusters(const Frame& frame,
                                     const std::vector<Candidate>& candidates) const;
  /** \brief Gates and scores every track against the candidates (registering where needed),
   * tracks seen in the last frame first. */
  Association associate(const Frame& frame, std::vector<Candidate>& candidates,
                        const std::vector<int>& still);
  /** \brief The gate and scores of track `ti` (the scorer by the track: scoreByCentroid(),
   * scoreStill() or scoreByRegistration()); the clusters it matched confidently are `claimed`
   * (coasting static tracks do not register those). */
  void gateTrack(std::size_t ti, const Frame& frame, std::vector<Candidate>& candidates,
                 const std::vector<int>& still, std::vector<char>& claimed,
                 Association& association);
  /** \brief Track `ti`'s prediction and search radii into `gate` (not its candidates). */
  void setGate(std::size_t ti, const Frame& frame, TrackGate& gate) const;
  /** \brief The usable candidates within the gate, in cluster order, into `gate.candidates`; a
   * candidate too low to register near a confirmed mover with a model may be held instead
   * (Association::held_cluster). */
  void gateCandidates(TrackGate& gate, const Frame& frame, const std::vector<Candidate>& candidates,
                      Association& association) const;
  // The scorers: each turns the gated candidates into scored matches. The score orders all
  // matches of the frame for the greedy assignment (a B in [0, 1] above any centroid score).
  /** \brief The simplest approach (centroid mode, tracks without a model, large structures):
   * every gated candidate, scored by minus its centroid distance. */
  void scoreByCentroid(const TrackGate& gate, const std::vector<Candidate>& candidates,
                       Association& association) const;
  /** \brief An established static track whose nearest cluster did not move
   * (findStillClusters()): that cluster, unregistered, at the track's last similarity. */
  void scoreStill(const TrackGate& gate, std::size_t still_cluster, std::vector<char>& claimed,
                  Association& association) const;
  /** \brief The paper's: each gated candidate registered onto the track's model, nearest first,
   * scored by its similarity B; a confident match stops the search. */
  void scoreByRegistration(const TrackGate& gate, const Frame& frame,
                           std::vector<Candidate>& candidates, std::vector<char>& claimed,
                           Association& association);
  /** \brief A static track seen, unregistered, in its still cluster. */
  void seeStill(Track& track, const Candidate& candidate, ClusterResult& result);
  /** \brief Updates the track of match `m` with its cluster: filters, history, model, decision. */
  void updateTrack(const Match& m, const Frame& frame, std::vector<Candidate>& candidates);
  /** \brief The speed vote of an update (fast_from_fit: from the line through the registered
   * positions; else from the Kalman velocity and its covariance). */
  void voteFast(Track& track, bool registered) const;
  /** \brief Accumulates a registered view into the track's model, or starts the model of a track
   * born too low once it is seen tall enough. */
  void updateModel(Track& track, const Match& m, const Frame& frame,
                   std::vector<Candidate>& candidates, double meas_sigma);
  /** \brief The mover decision of an update, then the views later tests need (the last view for
   * splitting merged clusters, past points for the free-space test). */
  void decideAndRemember(Track& track, const Match& m, const Frame& frame,
                         std::vector<Candidate>& candidates);
  /** \brief Confirmed movers that got no update keep a cluster nobody took near them. */
  void holdClusters(const Frame& frame, const Association& association,
                    std::vector<Candidate>& candidates, std::vector<char>& track_used,
                    std::vector<char>& cluster_used);
  /** \brief A track that held clusters for max_missed_frames restarts its model from the held
   * one (cluster `c`), its positions moved onto that view's centroid. */
  void reanchorTrack(Track& track, const Frame& frame, std::vector<Candidate>& candidates,
                     std::size_t c);
  /** \brief Whether the clusters `track` held since Track::held_from moved with its velocity
   * (within track.gate_margin): the held object is the one it follows. */
  bool heldAlongItsPath(const Track& track, const Eigen::Vector2d& centroid, double time) const;
  /** \brief Whether a view is tall enough, and not large, to register against a model or to
   * start one. */
  bool registrable(const ClusterFeatures& features) const;
  /** \brief Coasting tracks missed too long (or seen once and then missed) are deleted. */
  void dropLostTracks(const std::vector<char>& track_used);
  /** \brief A new track for every usable cluster no track took. */
  void bearTracks(const Frame& frame, std::vector<Candidate>& candidates,
                  const std::vector<char>& cluster_used);
  /** \brief The output row of a cluster given to `track`. */
  static void report(const Track& track, double similarity, ClusterResult& result);

  /** \brief Registers candidate `c` against track `t`'s model around the predicted position. Fills
   * the measurement (reference point) and similarity; false when registration found no match. */
  bool registerCandidate(const Track& track, Candidate& candidate, const Eigen::Vector2d& predicted,
                         double search_radius, const Eigen::Vector3d& sensor_origin, Match& match);

  /** \brief Builds into view_ the density of the candidate's points moved by `transform` on the
   * grid of `model` (what the registration would give as its source density). */
  void buildView(const Candidate& candidate, const Eigen::Matrix4f& transform,
                 const SurfaceDensity& model, const Eigen::Vector3d& sensor_origin);

  /** \brief Builds a track's first model from its birth cluster. */
  SurfaceDensity::Ptr makeModel(const Candidate& candidate,
                                const Eigen::Vector3d& sensor_origin) const;

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
   * the measurement and keeps its velocity (see occluded_skip). */
  void updateVelocityFilter(Track& track, const Eigen::Vector3d& measurement, double similarity,
                            bool occluded, double time, double range, double since,
                            bool reanchor = false) const;

  /** \brief At a track's second view, outside its velocity prior's gate: restarts the filter
   * from the two views (position `measured`, velocity their difference / `since`) and returns
   * true; else false (the caller updates the filter as usual). */
  bool startsFast(Track& t, const Eigen::Vector2d& measured, const Eigen::Matrix2d& meas_cov,
                  double since) const;
  /** \brief Height of a cluster for the mover height test: its top above what it stands on
   * (ClusterFeatures::floor_z, decision.standing_height), at least its own extent. */
  double standingHeight(const ClusterFeatures& features) const;
  /** \brief Whether a moving track other than `track` (a mover, confirmed, or faster than
   * mover_speed) lies within half its longest view plus gate_margin of `track`'s position. */
  bool besideMover(const Track& track) const;
  /** \brief Updates the mover flag of a track after an update; `points` are the world points of
   * the cluster just assigned (for the free-space test). */
  void decideMover(Track& track, const std::vector<Eigen::Vector3f>& points) const;

  /** \brief True when the track's motion is well determined enough for an early confirmation
   * (see DetectorParameters::confirm_false_rate): last update registered with a high B on enough
   * points, and the line through the window's positions faster than mover_speed and significantly
   * non-zero. */
  bool wellMeasuredMotion(const Track& track) const;
  /** \brief The track's positions over the last slow_window seconds lie on a line faster than
   * slow_speed, beyond their scatter (F-test at confirm_false_rate). */
  bool sustainedMotion(const Track& track) const;
  /** \brief Speed votes (mover_votes of the last mover_window updates faster than mover_speed;
   * all of a full window for a view seen only above what hides it) and a net displacement of at
   * least displacement_ratio of mover_speed over the window. The votes are waived for
   * wellMeasuredMotion(). */
  bool fastMotion(const Track& track, bool seen_standing_only, bool well_measured) const;

  /** \brief Free-space evidence of a track: the larger fraction of (a) its current points seen
   * through by the scan `free_space_lag` frames ago and (b) its oldest stored points seen through
   * by the current scan (that view is then dropped, so every vote tests a different view). Sets
   * track.free_space; true when it reaches free_space_min_fraction. */
  bool freeSpaceEvidence(Track& track, const std::vector<Eigen::Vector3f>& points) const;
  /** \brief Free-space evidence on the time scale of slow motion: the larger of (a) the
   * fraction of the track's current points seen through by the scan free_space_long_lag frames
   * ago (the oldest stored early in a sequence) and (b) the fraction of its view of up to
   * free_space_long_lag updates ago (Track::past_views) seen through by the current scan
   * reaches free_space_long_min_fraction. A walker at 0.6 m/s has moved 0.3 m in
   * free_space_lag frames, no more than the margin, so a pass at that lag says little; over
   * 1.5 s it has moved 0.9 m. Sets track.free_space. */
  bool slowFreeSpaceEvidence(Track& track, const std::vector<Eigen::Vector3f>& points) const;

  void ensurePoints(const PointCloud& cloud, const pcl::PointIndices& indices,
                    Candidate& candidate) const;

  DetectorParameters parameters_;
  std::vector<Track> tracks_;
  std::vector<ClusterResult> results_;
  int next_id_ = 0;
  int registrations_ = 0;
  bool has_time_ = false;
  double last_time_ = 0;
  BhattacharyaRegistration<PointT, PointT> registration_;
  /// Buffers of buildView(), reused between calls.
  SurfaceDensity view_;
  std::vector<Eigen::Vector3f> view_points_;
  std::vector<float> view_sigmas_;
  TrackGate gate_;  ///< gateTrack()'s work buffer
  /// Buffer of scoreByRegistration(): its gated candidates to register (distance, cluster).
  std::vector<std::pair<double, std::size_t>> to_register_;
  const FreeSpaceMap* free_space_map_ = nullptr;
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/mover_tracker.hpp>
#endif
