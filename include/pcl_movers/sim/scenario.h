/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace pcl_movers {
namespace sim {

/** \brief One piece of a planar trajectory: for `duration` seconds the speed ramps linearly to
 * `speed` (so stopping is `speed: 0`, starting again a later segment with `speed: 5`) while the
 * heading changes at `turn_rate`. */
struct TrajectorySegment {
  double duration = 0;   ///< [s], > 0
  double speed = -1;     ///< speed at the end of the segment [m/s]; < 0 keeps the current speed
  double turn_rate = 0;  ///< [rad/s], positive = left (counter-clockwise seen from above)
  /** \brief Drive backwards: the body keeps its heading and moves the other way (a car
   * reversing out of a parking slot). The turn rate still turns the body. */
  bool reverse = false;
};

/** \brief Start state plus segments; after the last segment the motion continues straight at the
 * final speed. A static object is a trajectory with speed 0 and no segments. */
struct TrajectorySpec {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();  ///< world x, y [m]
  double heading = 0;                               ///< [rad], 0 = +x
  double speed = 0;                                 ///< initial speed [m/s]
  std::vector<TrajectorySegment> segments;
};

/** \brief A planar trajectory integrated once (10 ms steps, exact heading, midpoint position), so
 * that sampling any time is cheap and every run gives the same numbers. */
class Trajectory {
 public:
  struct State {
    Eigen::Vector2d position = Eigen::Vector2d::Zero();
    double heading = 0;  ///< where the body points [rad]
    double speed = 0;    ///< along the heading, or against it while reversing [m/s]
    bool reverse = false;
  };
  Trajectory() = default;
  /** \param horizon seconds to integrate (sampling later times extrapolates straight). */
  Trajectory(const TrajectorySpec& spec, double horizon);
  State at(double t) const;

 private:
  static constexpr double kStep = 0.01;
  /** State after `dt` seconds at a constant turn rate and acceleration. */
  static State step(const State& s, double dt, double turn, double accel);
  std::vector<State> samples_;
  std::vector<double> turn_rates_;  // turn rate and acceleration in force after each sample
  std::vector<double> accels_;
};

/** \brief Sensor settings of a scenario (`sensor:` block). */
struct SensorSpec {
  std::string preset = "hdl64";  ///< SensorModel::fromName name
  double height = 1.73;          ///< sensor origin above the terrain under the ego vehicle [m]
  double max_range = 80.0;       ///< returns beyond are NaN [m]
  double min_range = 1.0;        ///< returns closer are NaN [m]
  double range_noise = 0.02;     ///< Gaussian range noise sigma [m]
  double dropout = 0.0;          ///< probability that a return is lost, [0, 1)
  /** \brief "instant": the whole scan at the frame time; "rolling": each azimuth column at its
   * own time within the frame period, as a spinning sensor takes it (LidarSimulator::columnTime).
   */
  std::string sweep = "instant";
};

/** \brief Ground surface (`terrain:` block). Height h(x, y) = height + slope·(x, y) plus, for
 * "rolling", two octaves of sinusoidal hills of `amplitude` and `wavelength`. */
struct TerrainSpec {
  std::string type = "plane";  ///< plane, slope, rolling
  double height = 0.0;
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();  ///< dz/dx, dz/dy
  double amplitude = 0.0;                           ///< rolling: peak height of the hills [m]
  double wavelength = 40.0;                         ///< rolling: hill spacing [m]
  std::string surface = "terrain";  ///< label of ground off the roads: terrain, sidewalk, ...
  double road_width = 0.0;          ///< width of a road along the ego path (0 = none) [m]
};

/** \brief An extra road (`roads:`): a polyline of given width labelled road. */
struct RoadSpec {
  std::vector<Eigen::Vector2d> points;
  double width = 7.0;
};

/** \brief One scene object: a mover (`movers:`) or a static object (`statics:`).
 * Types: car, van, truck, person, cyclist (vehicles and people), tree, pole, brush, wall,
 * building. Sizes not given take the type's defaults (see data/scenarios/README.md). */
struct ObjectSpec {
  std::string type;
  bool mover = false;
  TrajectorySpec trajectory;  ///< statics: start = position, heading = yaw, speed 0
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< length, width, height (0 = default)
  double radius = 0;        ///< pole/brush radius, tree crown radius (0 = default)
  double trunk_radius = 0;  ///< tree (0 = default)
  double trunk_height = 0;  ///< tree: height where the crown starts (0 = default)
  std::size_t line = 0;     ///< line in the scenario file, for messages
};

/** \brief Randomly placed objects (`clutter:`): `count` objects of `type` in `region`
 * [xmin, xmax, ymin, ymax], sizes jittered, kept off roads and mover/ego paths. */
struct ClutterSpec {
  std::string type;
  int count = 0;
  Eigen::Vector4d region = Eigen::Vector4d::Zero();
  double min_spacing = 2.0;
  std::size_t line = 0;
};

/** \brief A parsed scenario file. See data/scenarios/README.md for the format. */
struct Scenario {
  std::string name = "scenario";
  std::string path;  ///< file it was read from ("" when built in code)
  std::uint64_t seed = 1;
  int frames = 100;
  double rate_hz = 10.0;
  SensorSpec sensor;
  TerrainSpec terrain;
  std::vector<RoadSpec> roads;
  TrajectorySpec ego;
  std::vector<ObjectSpec> objects;
  std::vector<ClutterSpec> clutter;
  /** \brief Frames with no return at all (a covered sensor, a dropped batch of packets): their
   * scans are all NaN, their objects have 0 points. Sorted, unique. */
  std::vector<int> blind_frames;
};

/** \brief Reads and validates a scenario file. Throws InputError "file:line: reason" naming the
 * key on unknown keys, missing required fields, wrong types, negative sizes or malformed syntax. */
Scenario loadScenario(const std::string& path);
/** \brief Same from text; `file_name` is used in error messages. */
Scenario parseScenario(const std::string& text, const std::string& file_name);

/** \brief Object types a scenario may use. */
const std::vector<std::string>& objectTypes();

/** \brief Length, width and height [m] of a car, van, truck, person or cyclist: each of the
 * spec's sizes where it gives one, else its type's default (the body LidarSimulator builds).
 * Other types: the spec's size as given. */
Eigen::Vector3d bodySize(const ObjectSpec& spec);

}  // namespace sim
}  // namespace pcl_movers
