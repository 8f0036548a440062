/*
 * Object-to-object registration pairs with known motion, for tests and the registration benchmark:
 * simulated (a small self-contained ray-caster of boxes and cylinders seen by a 64-beam sensor)
 * and real (objects cut from a labelled KITTI tracking sequence with their boxes).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <random>
#include <string>
#include <vector>

namespace pcl_movers {
namespace eval {

/** \brief A solid for the ray-caster: an oriented box (size length × width × height, yaw about z)
 * or a vertical cylinder (radius = width / 2). `centre` is the middle of the solid. Solids with the
 * same `object` id form one object. */
struct SimShape {
  enum Kind { Box, Cylinder };
  Kind kind = Box;
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();
  float length = 1.f, width = 1.f, height = 1.f, yaw = 0.f;
  int object = 0;
};

/** \brief Ray-casts a 64-beam spinning sensor (HDL-64E-like: elevations +2° … -24.9°, azimuth step
 * 0.18°, range noise `noise_sigma`) at `sensor` against `shapes` and a ground plane z = 0, and
 * returns the hits on object `object` only (everything else occludes). Only azimuths near the
 * object are cast. `azimuth_phase` ∈ [0,1) shifts the azimuth sampling (different sampling per
 * frame). The cloud's sensor_origin_ is set to `sensor`. */
pcl::PointCloud<pcl::PointXYZ> rayCastObject(const std::vector<SimShape>& shapes, int object,
                                             const Eigen::Vector3f& sensor, float azimuth_phase,
                                             float noise_sigma, std::mt19937& rng);

/** \brief One registration problem: find the transform mapping `source` onto `target`. */
struct RegistrationPair {
  pcl::PointCloud<pcl::PointXYZ>::Ptr source, target;   ///< world frame, sensor_origin_ set
  Eigen::Matrix4f truth = Eigen::Matrix4f::Identity();  ///< source → target
  Eigen::Vector3f reference = Eigen::Vector3f::Zero();  ///< object centre in the source (errors)
  std::string label;                                    ///< class / description
  float range = 0.f;                                    ///< distance of the object [m]
  /** Returns of other objects in the two scans (simulated pairs: the occluder's; empty when
   * there is none), for BhattacharyaRegistration::setSourceOccluders()/setTargetOccluders(). */
  pcl::PointCloud<pcl::PointXYZ>::Ptr source_occluders, target_occluders;
};

/** \brief Simulated pairs: vehicles (two boxes) and people (two cylinders) at 10-60 m, object
 * motion up to 2 m with yaw change up to `max_yaw_deg`, sensor motion up to 1.5 m, a static
 * occluder in ~40 % of the pairs. Pairs with fewer than `min_points` points in either frame are
 * redrawn. */
std::vector<RegistrationPair> makeSimulatedPairs(std::size_t count, unsigned seed,
                                                 float max_yaw_deg = 15.f, int min_points = 10);

/** \brief Pairs of different objects (vehicle vs person, vehicles of different shapes, vehicle vs
 * wall or pole), target cloud centred on the source's position: for the ROC of B as an absolute
 * match score. `truth` is the centroid alignment. */
std::vector<RegistrationPair> makeSimulatedDifferentPairs(std::size_t count, unsigned seed,
                                                          int min_points = 10);

/** \brief Real pairs from a KITTI tracking folder (frames/, poses.txt, objects.txt): for each track
 * in `track_ids` and each frame gap in `gaps`, frames f and f+gap (f advancing by `stride`); points
 * inside the labelled box grown by `grow` m in length and width, above box bottom + `ground_cut`
 * m, taken to the world frame with poses.txt. Truth is the box motion (centre and yaw) from
 * frame f+gap (source) to frame f (target). Pairs with < `min_points` in either frame are dropped.
 * Throws pcl_movers::InputError when files are missing. */
std::vector<RegistrationPair> loadKittiPairs(const std::string& folder,
                                             const std::vector<int>& track_ids,
                                             const std::vector<int>& gaps, int stride = 1,
                                             float grow = 0.3f, float ground_cut = 0.2f,
                                             int min_points = 30);

/** \brief Real different-object pairs from the same data: object A of frame f as source against
 * object B ≠ A of frame f+gap as target, B's cloud moved so its centroid lies on A's. */
std::vector<RegistrationPair> loadKittiDifferentPairs(const std::string& folder,
                                                      const std::vector<int>& track_ids, int gap,
                                                      int stride = 2, float grow = 0.3f,
                                                      float ground_cut = 0.2f, int min_points = 30);

/** \brief Error of an estimate at the reference point: |T·ref - truth·ref| (horizontal + vertical).
 */
float translationError(const Eigen::Matrix4f& estimate, const RegistrationPair& pair);
/** \brief |yaw(estimate) - yaw(truth)| [rad], wrapped to [0, π]. */
float yawError(const Eigen::Matrix4f& estimate, const RegistrationPair& pair);

/** \brief The initial guess used by the benchmark: the true translation of the reference point
 * plus a horizontal offset of `offset` m in direction `angle`, and no rotation. */
Eigen::Matrix4f perturbedGuess(const RegistrationPair& pair, float offset, float angle);

/** \brief Area under the ROC curve of `positives` scoring above `negatives` (ties count half). */
double rocAuc(const std::vector<float>& positives, const std::vector<float>& negatives);

}  // namespace eval
}  // namespace pcl_movers
