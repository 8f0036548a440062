/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief Sort file names by the number they contain ("2.pcd" before "10.pcd"), then by name. */
void sortNumerically(std::vector<std::string>& paths);

/** \brief Reads one scan: binary/ASCII PCD (must have x, y, z) or KITTI `.bin` (float32 x y z r).
 * For PCDs the cloud keeps its width/height (organized or not), `sensor_origin_` and
 * `sensor_orientation_`. Throws InputError naming the file on a missing, truncated or malformed
 * file. Works for pcl::PointXYZ and pcl::PointXYZI (intensity = KITTI reflectance, 0 when absent).
 */
template <typename PointT>
void readScan(const std::string& path, pcl::PointCloud<PointT>& cloud);

/** \brief Reads a KITTI pose file: one row-major 3x4 matrix (12 numbers) per line.
 * Throws InputError with file and line on a malformed row. */
std::vector<Eigen::Isometry3d> readPoses(const std::string& path);
/** \brief Writes poses in the KITTI format read by readPoses(). */
void writePoses(const std::string& path, const std::vector<Eigen::Isometry3d>& poses);
/** \brief Reads one timestamp (seconds) per line. */
std::vector<double> readTimes(const std::string& path);
void writeTimes(const std::string& path, const std::vector<double>& times);

/** \brief A sequence folder as `DESIGN.md` defines it.
 *
 * Frames come from `frames/ *.pcd`, else `*.pcd` in the folder itself, else KITTI `velodyne/
 * *.bin`, sorted numerically. Poses: `poses.txt` (sensor→world, KITTI 3x4), else a non-identity PCD
 * VIEWPOINT of the first frame means every frame's VIEWPOINT is its pose, else none (estimate
 * them). Times: `times.txt`, else frame index / rate. All counts are checked at open(); errors
 * throw InputError naming the file and line.
 */
class SequenceReader {
 public:
  SequenceReader() = default;
  explicit SequenceReader(const std::string& folder, double rate_hz = 10.0) {
    open(folder, rate_hz);
  }

  /** \brief Scans the folder and reads poses/times; throws InputError. */
  void open(const std::string& folder, double rate_hz = 10.0);

  std::size_t size() const { return frame_paths_.size(); }
  bool empty() const { return frame_paths_.empty(); }
  const std::string& folder() const { return folder_; }
  const std::vector<std::string>& framePaths() const { return frame_paths_; }
  /** \brief Frame names without extension ("000042"), used to name outputs. */
  std::string frameName(std::size_t i) const;

  /** \brief Whether poses came from poses.txt or the PCD VIEWPOINTs. */
  bool hasPoses() const { return !poses_.empty(); }
  /** \brief "poses.txt", "viewpoint" or "none". */
  const std::string& poseSource() const { return pose_source_; }
  /** \brief Sensor→world pose of frame i (identity when the sequence has none). */
  Eigen::Isometry3d pose(std::size_t i) const;
  const std::vector<Eigen::Isometry3d>& poses() const { return poses_; }

  bool hasTimes() const { return has_times_; }
  double time(std::size_t i) const { return times_.at(i); }
  const std::vector<double>& times() const { return times_; }

  /** \brief Path of objects.txt (ground truth) if the folder has one, else "". */
  std::string objectsPath() const;
  /** \brief Path of the SemanticKITTI-style label file of frame i if present, else "". */
  std::string labelPath(std::size_t i) const;

  /** \brief Reads frame i in the sensor frame (see readScan). */
  template <typename PointT>
  void read(std::size_t i, pcl::PointCloud<PointT>& cloud) const {
    readScan(frame_paths_.at(i), cloud);
  }

 private:
  std::string folder_;
  std::vector<std::string> frame_paths_;
  std::vector<Eigen::Isometry3d> poses_;
  std::string pose_source_ = "none";
  std::vector<double> times_;
  bool has_times_ = false;
};

/** \brief Writes a sequence folder: `frames/NNNNNN.pcd` (binary), `poses.txt`, `times.txt`.
 *
 * Refuses (InputError) a folder that exists and is not empty unless `overwrite` is set, so nothing
 * the user has is replaced silently.
 */
class SequenceWriter {
 public:
  explicit SequenceWriter(const std::string& folder, bool overwrite = false);

  /** \brief Writes frames/NNNNNN.pcd (index zero-padded to 6 digits). Returns the path. */
  template <typename PointT>
  std::string writeFrame(std::size_t index, const pcl::PointCloud<PointT>& cloud) const;
  void writePoses(const std::vector<Eigen::Isometry3d>& poses) const;
  void writeTimes(const std::vector<double>& times) const;
  const std::string& folder() const { return folder_; }
  std::string framesFolder() const { return folder_ + "/frames"; }

 private:
  std::string folder_;
};

/** \brief True when `folder` does not exist or is an empty directory. */
bool isMissingOrEmptyDirectory(const std::string& folder);

/** \brief Creates `folder` for output. Throws InputError when it exists, is not empty and
 * `overwrite` is false, or when it cannot be created/written. */
void prepareOutputDirectory(const std::string& folder, bool overwrite);

}  // namespace io
}  // namespace pcl_movers
