/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/kalman_filter_cv.h>
#include <pcl_movers/surface_density.h>

#include <Eigen/Core>
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
  kYoung,         ///< fewer than decision.min_age updates and its motion not yet beyond doubt
  kLow,           ///< lower than decision.min_height in every view
  kNoMotion,      ///< neither fast motion (speed votes) nor sustained slow motion
  kNoFreeSpace,   ///< moves, but too few of its views fall in space earlier scans saw empty
  kFast,          ///< mover: speed votes and free-space evidence
  kWellMeasured,  ///< mover while young: its displacement beyond doubt and seen through
  kSustained,     ///< mover: sustained slow motion (slow_window) and free-space evidence
  kFreeSpace,  ///< mover: most of its view fills space seen empty (MoverDecision::fillsFreeSpace)
  kLatched     ///< mover: confirmed by decision.window decisions in a row (decision.latch)
};

/** \brief The name of a reason as tracks.csv writes it: new, large, young, low, no_motion,
 * no_free_space, fast, well_measured, sustained, free_space, latched. */
inline const char* moverReasonName(MoverReason reason) {
  static const char* const names[] = {"new",       "large",         "young",  "low",
                                      "no_motion", "no_free_space", "fast",   "well_measured",
                                      "sustained", "free_space",    "latched"};
  return names[static_cast<int>(reason)];
}

/** \brief Geometry of one cluster in the world frame. */
struct ClusterFeatures {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double length = 0, width = 0, height = 0;  ///< oriented box in the horizontal plane, z extent
  double yaw = 0;                            ///< heading of the box's long side [rad], world
  double min_z = 0, max_z = 0;
  int points = 0;
  bool large = false;  ///< longer/taller than any mover: tracked by centroid, never a mover
  /// A side of the cluster is bounded by a nearer object (Observation::occluded): its extent there
  /// is not the object's, and its measured position can slide while it emerges or hides.
  bool occluded = false;
  /// What the object stands on (world z): the lowest point of a nearer object hiding its lower
  /// part (a parked car below a walker's head), else the ground under it; NaN = unknown.
  double floor_z = std::numeric_limits<double>::quiet_NaN();
  /// How rough its surface is in the range image [m] (Observation::roughness); NaN = unknown.
  double roughness = std::numeric_limits<double>::quiet_NaN();
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
  double similarity = 0;                   ///< B of the last update (0 in centroid mode / at birth)
  ClusterFeatures features;                ///< geometry of the last cluster assigned
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
  /// Id of the mover whose fragment (findMoverFragments()) the track's first cluster was, or -1:
  /// the track follows a part of that mover (MoverTracker::recordBirthOwners()).
  int born_part_of = -1;
  Fifo<char> fast;                ///< speed > decision.speed after each of the last updates
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
  SurfaceDensity::Ptr model;  ///< accumulated surface density (registration mode)
  /// Centroid of the cluster of the last update (still frames excluded): a still frame needs
  /// the cluster within track.static_shift of it (findStillClusters()).
  Eigen::Vector3d measured_centroid = Eigen::Vector3d::Zero();
  int since_registration = 0;  ///< cheap (unregistered) frames since the last registration
  bool confirmed = false;      ///< latched mover (see decision.latch)
  int mover_run = 0;      ///< consecutive updates decided mover (latched after decision.window)
  double free_space = 0;  ///< free-space evidence of the last test (fraction seen through)
  Fifo<char> free_votes;  ///< free-space test passed, for each of the last tests
  /// ClusterFeatures::roughness of the last decision.window updates' views.
  Fifo<float> roughness;
  /// World points of the last updates (subsampled), oldest first, for the free-space test.
  Fifo<std::vector<Eigen::Vector3f>> past_points;
  /// World points of the last update's view (at most kLastViewPoints), for
  /// splitMergedClusters().
  std::vector<Eigen::Vector3f> last_view;
  /// Every world point of the last update's view (track.swept_edges): the extents of a view
  /// must be measured on the whole cluster, a sample's extremes wander.
  std::vector<Eigen::Vector3f> full_view;
  /// last_view of the last free_space.long_lag updates, oldest first: the receding test of
  /// sustained slow motion (slowFreeSpaceEvidence()).
  Fifo<std::vector<Eigen::Vector3f>> past_views;
};
static_assert(std::is_nothrow_move_constructible<Track>::value,
              "std::vector<Track> must move its tracks when it grows, not copy them (see Fifo)");

}  // namespace pcl_movers
