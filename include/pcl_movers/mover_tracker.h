/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/bhattacharya_registration.h>
#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/free_space_map.h>
#include <pcl_movers/kalman_filter_cv.h>
#include <pcl_movers/line_fit.h>
#include <pcl_movers/mover_decision.h>
#include <pcl_movers/observation.h>
#include <pcl_movers/surface_density.h>
#include <pcl_movers/swept_edges.h>
#include <pcl_movers/track.h>
#include <pcl_movers/track_motion.h>

#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace pcl_movers {
/** \brief Tracks every object cluster of a LiDAR sequence and decides which are movers
 * (Morris et al., section 6).
 *
 * Each frame, update() receives the clusters of one scan in the **world** frame. Every track
 * (static objects too) carries a constant-velocity KalmanFilterCV on its horizontal position and,
 * in the default registration mode, an accumulated SurfaceDensity model:
 *
 *  1. predict all tracks to the frame time;
 *  2. gate: a cluster is a candidate of a track when its centroid lies within
 *     `track.gate_sigmas`·σ (innovation covariance) + ½·`track.acceleration_limit`·dt²
 *     + `track.gate_margin` of the predicted centroid (predicted reference point + the
 *     centroid offset of the last update), at most `track.max_gate_radius` (the acceleration
 *     limit bounds the search);
 *  3. registration mode: each candidate is registered with BhattacharyaRegistration against the
 *     track's model, the search window centred on the prediction and as wide as the gate; its
 *     similarity B is the association score and B < `registration.min_similarity` is not an
 *     update (occlusion or wrong object). Centroid mode (the paper's "simplest approach", for
 *     comparison): the measurement is the cluster centroid and the score is minus the centroid
 *     distance;
 *  4. pairs are assigned greedily, best score first, one cluster per track and one track per
 *     cluster; the Kalman filter is updated with the measured position; the registered view is
 *     accumulated into the model with a half-life of `registration.model_half_life` frames;
 *  5. unmatched tracks coast (prediction only) and are deleted after `track.max_missed_frames`; a
 *     confirmed mover holds a cluster near its prediction that failed to register, and after
 *     `track.max_missed_frames` such frames restarts its model from it when the held clusters
 *     moved along its path (reanchorTrack()); unmatched clusters start new tracks (at most
 *     `track.max_tracks` live tracks);
 *  6. mover decision (MoverDecision, after every update): named tests in order, the first one
 *     failed is the reason written per row — large, latched, young (< `decision.min_age` updates
 *     unless the motion is beyond doubt), low (never `decision.min_height` tall), no_motion
 *     (neither speed votes nor sustained slow motion), no_free_space (too few views in space an
 *     earlier scan saw through, FreeSpaceMap: no static object can give that evidence);
 *  7. latching (`decision.latch`): a track decided mover in `decision.window` consecutive updates
 *     stays a mover while its track lives (a car waiting at a light, a pedestrian pausing), unless
 *     it becomes a large structure.
 *
 * Before update(), splitMergedClusters() cuts clusters that hold two established tracks moving
 * differently (walkers passing each other) along their predicted views; MoverDetector does so
 * every frame (`track.split_merged`).
 *
 * The registered measurement is the track's reference point: the model grid is centred where the
 * object was first seen and the registration maps each new view onto it, so the measured position
 * is that reference point moved by the registered motion. It does not shift when a different part
 * of the object is seen, which is the point of registering instead of using centroids.
 *
 * Cost control (documented design choice, `track.static_refresh_frames`): an established, slow,
 * non-mover track whose single gated candidate's centroid lies within `track.static_shift` of its
 * last update's is registered only every `track.static_refresh_frames` frames; in between it is
 * marked seen without a Kalman update (its velocity is near zero anyway). Any centroid jump,
 * ambiguity or speed-up brings registration back at once. `track.static_refresh_frames` = 1
 * registers every track every frame, as in the paper.
 *
 * Practical limits (documented design choices): clusters longer than `decision.max_length` or
 * taller than `decision.max_height` (buildings, walls, hedges, tree rows) are tracked by centroid
 * only and are never movers — registering them would be expensive and their centroids move with the
 * view; clusters lower than `decision.min_height` are never movers. Tracks and models are bounded:
 * each track owns one fixed-size grid, tracks die after `track.max_missed_frames` and their number
 * is capped.
 */
template <typename PointT>
class MoverTracker {
 public:
  using PointCloud = pcl::PointCloud<PointT>;
  using PointCloudPtr = typename PointCloud::Ptr;
  using PointCloudConstPtr = typename PointCloud::ConstPtr;
  using Ptr = pcl::shared_ptr<MoverTracker<PointT>>;
  using ConstPtr = pcl::shared_ptr<const MoverTracker<PointT>>;

  using ClusterFeatures = pcl_movers::ClusterFeatures;
  using Track = pcl_movers::Track;
  using LineFit = pcl_movers::LineFit;
  static constexpr std::size_t kLastViewPoints = 64;
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
  void setParameters(const DetectorParameters& parameters) {
    parameters_ = parameters;
    motion_.setParameters(parameters);
    decision_.setParameters(parameters);
  }
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
  void setFreeSpaceMap(const FreeSpaceMap* map) { decision_.setFreeSpaceMap(map); }
  const FreeSpaceMap* getFreeSpaceMap() const { return decision_.getFreeSpaceMap(); }

  /** \brief Per input cluster of the last update(), in input order. */
  const std::vector<ClusterResult>& getClusterResults() const { return results_; }
  /** \brief Live tracks (updated or coasting). */
  const std::vector<Track>& getTracks() const { return tracks_; }
  /** \brief The track with this id, or nullptr. */
  const Track* findTrack(int id) const;
  /** \brief Records what each track born in the last update() was born on: `owner[c]` is the
   * cluster (of that update, in input order) that cluster c is a fragment of, or -1
   * (findMoverFragments()); the track of cluster c gets the owner's track id as
   * Track::born_part_of. Tracks born earlier keep theirs. */
  void recordBirthOwners(const std::vector<int>& owner);
  /** \brief Number of registrations run in the last update() (for profiling). */
  int getRegistrationCount() const { return registrations_; }
  /** \brief Total number of tracks ever started. */
  int getTracksStarted() const { return next_id_; }

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

  /** \brief A track that can claim points of a merged cluster (splitMergedClusters()):
   * established, seen in the last frames, with a view. */
  struct Claimant {
    std::size_t track = 0;
    Eigen::Vector2f shift, lo, hi;  ///< predicted motion of its view, the moved view's box
    LineFit fit;                    ///< line through its last positions (claimantsDiffer())
  };
  /** \brief The tracks that can claim points this frame, their views moved to `time`. */
  std::vector<Claimant> findClaimants(double time) const;
  /** \brief Whether two claimants move differently beyond doubt, one a confirmed mover and the
   * other confirmed or static. */
  bool claimantsDiffer(const Claimant& a, const Claimant& b) const;
  /** \brief (index into `ids`, squared distance) of the claimant among `ids` whose moved view
   * lies nearest to `q` in the horizontal plane. */
  std::pair<std::size_t, float> nearestView(const PointT& q, const std::vector<Claimant>& claimants,
                                            const std::vector<std::size_t>& ids) const;
  /** \brief The pieces of the cluster `idx` claimed by tracks that move differently (positions
   * in `idx`, each at least kMinSplitPoints), or none when it stays whole. */
  std::vector<ClusterPart> cutCluster(const PointCloud& cloud, const pcl::Indices& idx,
                                      const std::vector<Claimant>& claimants) const;

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
  /** \brief Replaces the displacement along a growing or shrinking view's length by the move
   * of the edge the free space confirms (sweptEdgeShift(), `track.swept_edges`): registered
   * matches of tracks updated by registration in the previous frame. Returns whether it did. */
  bool measureSweptEdge(const Track& t, const std::vector<Eigen::Vector3f>& view, Match& m);
  /** \brief The world points of cluster `cluster`, all of them (not the registration sample). */
  std::vector<Eigen::Vector3f> fullView(const Frame& frame, int cluster) const;
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
  MoverDecision decision_;  ///< the mover decision after each update
  TrackMotion motion_;      ///< the filters of each update
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/mover_tracker.hpp>
#endif
