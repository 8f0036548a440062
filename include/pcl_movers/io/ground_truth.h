/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief One row of objects.txt (ground truth), in the sensor frame of its frame:
 * `frame track_id class cx cy cz length width height yaw moving speed_mps n_points`. */
struct GroundTruthObject {
  int frame = 0;
  int track_id = 0;
  std::string type;  ///< class name: Car, Van, Pedestrian, Cyclist, ...
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< box centre, sensor frame [m]
  double length = 0, width = 0, height = 0;          ///< box size [m] (length along yaw)
  double yaw = 0;                                    ///< box heading about z [rad]
  bool moving = false;                               ///< the track's median world speed > 0.5 m/s
  double speed = 0;                                  ///< world speed in this frame [m/s]
  int n_points = 0;                                  ///< scan points inside the box

  /** \brief Whether sensor-frame point p lies inside the box grown by `grow_xy` in length and width
   * (total, i.e. grow/2 on each side) and `grow_z` in height. */
  bool contains(const Eigen::Vector3d& p, double grow_xy = 0.0, double grow_z = 0.0) const;
};

/** \brief Reads objects.txt ('#' comment lines skipped). Throws InputError with file and line. */
std::vector<GroundTruthObject> readObjects(const std::string& path);
/** \brief Writes objects.txt with the standard header comment. */
void writeObjects(const std::string& path, const std::vector<GroundTruthObject>& objects);

/** \brief SemanticKITTI point labels: class in the low 16 bits, instance in the high 16. */
std::vector<std::uint32_t> readLabels(const std::string& path);
void writeLabels(const std::string& path, const std::vector<std::uint32_t>& labels);
inline std::uint16_t labelClass(std::uint32_t label) {
  return label & 0xFFFFu;
}
inline std::uint16_t labelInstance(std::uint32_t label) {
  return label >> 16;
}
inline std::uint32_t makeLabel(std::uint16_t cls, std::uint16_t instance) {
  return (static_cast<std::uint32_t>(instance) << 16) | cls;
}

/** \brief SemanticKITTI classes the project uses. */
namespace semantic {
constexpr std::uint16_t kUnlabeled = 0, kOutlier = 1, kCar = 10, kBicycle = 11, kTruck = 18,
                        kOtherVehicle = 20, kPerson = 30, kBicyclist = 31, kRoad = 40,
                        kParking = 44, kSidewalk = 48, kOtherGround = 49, kBuilding = 50,
                        kFence = 51, kVegetation = 70, kTrunk = 71, kTerrain = 72, kPole = 80,
                        kTrafficSign = 81, kMovingCar = 252, kMovingPerson = 254;
/** \brief The simulator labels an object's points with a moving class (252 moving-car, 253
 * moving-bicyclist, 254 moving-person, 258 moving-truck) only in the frames where its world speed
 * exceeds this [m/s], as SemanticKITTI-MOS's ground truth: moving = moving in that frame. Parked
 * cars, standing people and movers while they stop keep their static class (10, 30, ...). (The
 * objects.txt flag `moving` is per track: its median speed > 0.5 m/s.) Label version 2; version 1
 * labelled every frame of a track by that flag. */
constexpr double kMovingLabelSpeed = 0.1;
/** \brief road, parking, sidewalk, other-ground, terrain. */
inline bool isGround(std::uint16_t c) {
  return c == kRoad || c == kParking || c == kSidewalk || c == kOtherGround || c == kTerrain;
}
}  // namespace semantic

}  // namespace io
}  // namespace pcl_movers
