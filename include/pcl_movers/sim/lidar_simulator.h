/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/sensor_model.h>
#include <pcl_movers/sim/scenario.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace pcl_movers {
namespace sim {

/** \brief Version of what the simulator writes for the same scenario (scans, labels, objects.txt).
 * Raise it with every change to that output, so that caches of simulated scenes (the corpus's
 * corpus_stamp.txt) are simulated again. 2: moving label classes only while the object moves
 * (io::semantic::kMovingLabelSpeed). */
constexpr int kSimulatorOutputVersion = 2;

/** \brief Ray-casts a Scenario into organized scans with point-wise and object ground truth.
 *
 * Every beam (row) and azimuth step (column) of the SensorModel is one ray from the sensor on the
 * moving ego vehicle. With `sensor.sweep: instant` (the default) the scan is taken at one instant
 * per frame; with `rolling` each column is taken at its own time (columnTime()), the ego pose and
 * every object evaluated then, as a spinning sensor on a moving vehicle sees the world. The
 * ego vehicle follows its planar trajectory on the terrain and is pitched/rolled by the terrain
 * slope. Objects are unions of analytic primitives (boxes, vertical cylinders, ellipsoids; foliage
 * as porous ellipsoids with an exponential free path), so coarse angular sampling changes their
 * appearance from frame to frame exactly as in the paper. Terrain is intersected analytically
 * (plane, slope) or by Lipschitz-bounded ray marching plus bisection (rolling).
 *
 * Culling: per frame each object's bounding sphere gives an azimuth interval (exact) and an
 * elevation interval (conservative); rays only test objects listed in their column, nearest first,
 * and stop once the next object cannot be nearer than the current hit.
 *
 * Randomness (range noise, dropouts, foliage penetration) comes from a counter-based hash of
 * (seed, frame, row, column, object), so output does not depend on evaluation order and the same
 * scenario and seed give byte-identical output. Clutter placement uses the seed too.
 */
class LidarSimulator {
 public:
  using Ptr = std::shared_ptr<LidarSimulator>;
  using ConstPtr = std::shared_ptr<const LidarSimulator>;

  /** \brief Builds the scene (expands clutter). Throws InputError for an unknown sensor preset. */
  explicit LidarSimulator(const Scenario& scenario);
  ~LidarSimulator();
  LidarSimulator(const LidarSimulator&) = delete;
  LidarSimulator& operator=(const LidarSimulator&) = delete;

  /** \brief Replaces the scenario's sensor (e.g. `--sensor vlp16`). */
  void setSensor(const SensorModel& sensor);
  const SensorModel& getSensor() const { return sensor_; }
  const Scenario& getScenario() const { return scenario_; }
  int getFrameCount() const { return scenario_.frames; }
  /** \brief Number of scene objects after clutter expansion (track ids 1..N in this order). */
  std::size_t getObjectCount() const;

  /** \brief Time of frame i [s] (i / rate). */
  double time(int frame) const { return double(frame) / scenario_.rate_hz; }
  /** \brief Time of column `column` relative to its frame's time [s]: 0 for an instant sweep; for
   * a rolling sweep column / (columns · rate). Columns run clockwise seen from above (azimuth
   * decreasing, as a Velodyne turns), column 0 starting behind the sensor for a 360° sensor, so
   * the frame time is the start of the sweep and the seam is behind the vehicle. */
  double columnTime(int column) const;
  /** \brief Sensor→world pose of frame i, world = the sensor frame of frame 0 (as in KITTI). */
  Eigen::Isometry3d pose(int frame) const;
  /** \brief Sensor→world pose of frame i in the scenario file's world (terrain, objects). */
  Eigen::Isometry3d worldPose(int frame) const;

  /** \brief Simulates frame `frame`.
   * \param[out] organized rows = beams top to bottom, columns = SensorModel columns; sensor frame;
   *   NaN x y z (and intensity 0) where there is no return; is_dense = false
   * \param[out] labels one SemanticKITTI label per point of `organized`, row-major (class low 16
   *   bits, track id high 16; ground instance 0; 0 where there is no return)
   * \param[out] objects ground truth for this frame, one row per object whose box centre lies
   *   within max_range of the sensor, in the sensor frame; n_points = returns labelled with it
   * \param[out] pose sensor→world pose, see pose() */
  void simulate(int frame, pcl::PointCloud<pcl::PointXYZI>& organized,
                std::vector<std::uint32_t>& labels, std::vector<io::GroundTruthObject>& objects,
                Eigen::Isometry3d& pose) const;

  /** \brief Terrain height at world (x, y) (world of the scenario file, not pose()'s frame). */
  double terrainHeight(double x, double y) const;

 private:
  struct Scene;
  Scenario scenario_;
  SensorModel sensor_;
  std::unique_ptr<Scene> scene_;
};

/** \brief Writes a whole sequence folder as DESIGN.md defines it: `frames/NNNNNN.pcd`,
 * `labels/NNNNNN.label`, `poses.txt`, `times.txt`, `objects.txt`, plus `scenario.yaml` (a copy
 * of the input when it came from a file). A rolling sweep's frames carry a per-point float
 * `time` field (seconds after the frame time, LidarSimulator::columnTime()), as the Velodyne
 * driver writes it.
 *
 * The sequence is written into a temporary sibling folder and moved into place at the end, so an
 * error leaves nothing half-written. An existing non-empty `folder` is refused (InputError) unless
 * `overwrite`, in which case its frames/ and labels/ folders and the files above are replaced.
 * \param progress called after each frame with (frames done, total); may be empty. */
void writeSequence(const LidarSimulator& simulator, const std::string& folder, bool overwrite,
                   const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace sim
}  // namespace pcl_movers
