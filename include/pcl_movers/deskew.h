/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

namespace pcl_movers {

/** \brief A sensor→world pose at a time [s]; `valid` = false when it is not known. */
struct StampedPose {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  double time = 0;
  bool valid = false;
};

/** \brief Motion of the sensor from `frame.time` to `frame.time + dt`, in the sensor frame at
 * `frame.time`, at the constant velocity given by the two poses (`other` before or after `frame`):
 * the translation scaled linearly, the rotation slerped (its angle scaled about its axis). */
Eigen::Isometry3d sweepMotion(const StampedPose& frame, const StampedPose& other, double dt);

/** \brief De-skews a scan taken by a sensor turning while it moves.
 *
 * Point i of `cloud` (sensor frame) was measured `times[i]` seconds after `frame.time` (the time
 * of the pose, the start of the sweep); it is moved into the sensor frame at `frame.time` by the
 * ego motion up to its time (sweepMotion()), so a sweep taken from a vehicle driving 20 m/s is no
 * longer torn by up to 2 m at its seam. The objects' own motion during the sweep is not
 * corrected. NaN points stay NaN; the organized structure is kept.
 * \return false (cloud unchanged) when `times` is empty; throws InputError when the sizes differ
 *   or the two poses have the same time. */
template <typename PointT>
bool deskewScan(pcl::PointCloud<PointT>& cloud, const std::vector<float>& times,
                const StampedPose& frame, const StampedPose& other);

/** \brief De-skewing of a sequence's frames as `pcl_movers_detect` applies it (detector parameter
 * `deskew`): "auto" de-skews the frames whose PCD carries per-point times (io::readPointTimes)
 * when the poses are known; "on" requires both (InputError naming the file otherwise); "off"
 * never reads the times. Counts what it did for summary.json. */
class ScanDeskewer {
 public:
  /** \brief Throws InputError for a mode other than auto, on, off. */
  explicit ScanDeskewer(const std::string& mode = "auto");

  /** \brief De-skews `cloud`, read from `path`, with its pose `frame` and a neighbouring one
   * `other` (the previous frame's; the next one's at the first frame; invalid when the poses are
   * estimated from the scans). \return whether the scan was de-skewed. */
  bool apply(const std::string& path, pcl::PointCloud<pcl::PointXYZI>& cloud,
             const StampedPose& frame, const StampedPose& other);

  const std::string& getMode() const { return mode_; }
  /** \brief Frames de-skewed so far. */
  std::size_t getDeskewedFrames() const { return deskewed_; }
  /** \brief {"mode", "time_field" (of the last frame with times, "" if none), "frames" (de-skewed),
   * "without_times", "without_poses"} as a JSON object. */
  std::string toJson() const;

 private:
  std::string mode_;
  std::string field_;
  std::size_t deskewed_ = 0;
  std::size_t without_times_ = 0;
  std::size_t without_poses_ = 0;
};

}  // namespace pcl_movers
