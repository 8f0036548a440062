/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief Sort file names by the number they contain ("2.pcd" before "10.pcd"), then by name. */
void sortNumerically(std::vector<std::string>& paths);

/** \brief Reads one scan: binary/ASCII PCD or PLY (must have x, y, z; PLY through
 * pcl::PLYReader) or KITTI `.bin` (float32 x y z r).
 * For PCDs the cloud keeps its width/height (organized or not), `sensor_origin_` and
 * `sensor_orientation_`. Throws InputError naming the file on a missing, truncated or malformed
 * file. Works for pcl::PointXYZ and pcl::PointXYZI (intensity = KITTI reflectance, 0 when absent).
 */
template <typename PointT>
void readScan(const std::string& path, pcl::PointCloud<PointT>& cloud);

/** \brief Reads one scan with every field of the file, in the file's point order (a KITTI
 * `.bin` gives x y z intensity). Throws InputError naming the file, as readScan(). */
void readScanBlob(const std::string& path, pcl::PCLPointCloud2& blob);

/** \brief True for the scan files a sequence may hold: `.pcd`, `.bin`, `.ply`. */
bool isScanFile(const std::string& path);

/** \brief The last run of digits in the file name's stem ("scan_000040.bin" → 40), -1 if none. */
long long frameNumber(const std::string& path);

/** \brief Formats of a pose file (`--poses-format`). */
enum class PoseFormat {
  kitti,        ///< 12 numbers a line: row-major 3x4 sensor→world pose, one per frame
  tum,          ///< `timestamp x y z qx qy qz qw` a line, `#` comments; matched by time
  kitti_camera  ///< KITTI odometry camera-0 poses; velodyne pose = Tr⁻¹ · P_cam · Tr (calib.txt)
};
/** \brief "kitti", "tum" or "kitti-camera"; throws InputError naming --poses-format. */
PoseFormat parsePoseFormat(const std::string& name);

/** \brief A pose with its timestamp (TUM trajectories). */
struct StampedPose {
  double time;
  Eigen::Isometry3d pose;
};
/** \brief Reads a TUM trajectory (`timestamp x y z qx qy qz qw`, `#` comments); timestamps must
 * increase. Throws InputError with file and line. */
std::vector<StampedPose> readTumPoses(const std::string& path);
/** \brief The `Tr:` row (velodyne→camera 0) of a KITTI odometry calib.txt (also
 * `Tr_velo_to_cam:`). Throws InputError naming the file. */
Eigen::Isometry3d readKittiCalibTr(const std::string& path);
/** \brief Velodyne poses from camera poses: Tr⁻¹ · P_cam · Tr. */
std::vector<Eigen::Isometry3d> cameraToVelodynePoses(const std::vector<Eigen::Isometry3d>& cam,
                                                     const Eigen::Isometry3d& tr);
/** \brief The pose at each of `times`: interpolated (linear, slerp) between the two stamped poses
 * around it, or the nearest one at the ends. Throws InputError naming `path`, the frame and the
 * nearest pose time when no pose is within `tolerance` seconds of a frame. */
std::vector<Eigen::Isometry3d> posesAtTimes(const std::vector<StampedPose>& stamped,
                                            const std::vector<double>& times,
                                            const std::string& path, double tolerance);

/** \brief Reads a KITTI pose file: one row-major 3x4 matrix (12 numbers) per line.
 * Throws InputError with file and line on a malformed row. */
std::vector<Eigen::Isometry3d> readPoses(const std::string& path);
/** \brief Writes poses in the KITTI format read by readPoses(). */
void writePoses(const std::string& path, const std::vector<Eigen::Isometry3d>& poses);
/** \brief Reads one timestamp (seconds) per line. */
std::vector<double> readTimes(const std::string& path);
/** \brief Writes one timestamp (seconds) per line: with 6 decimals (µs), or with `exact` the
 * shortest decimals that read back (readTimes()) to the same double. */
void writeTimes(const std::string& path, const std::vector<double>& times, bool exact = false);

/** \brief How SequenceReader::open() finds times and poses. */
struct SequenceOptions {
  double rate_hz = 10.0;                        ///< frame rate when there is no times.txt
  std::string poses_path;                       ///< a pose file; "" = the folder's poses.txt
  PoseFormat poses_format = PoseFormat::kitti;  ///< format of `poses_path`
  std::string calib_path;                       ///< KITTI calib.txt for PoseFormat::kitti_camera
  bool load_poses = true;  ///< false: no pose file is read (the caller estimates them)
};

/** \brief A sequence folder as `DESIGN.md` defines it.
 *
 * Frames are the scans (`.pcd`, `.bin` or `.ply`, one format) of `frames/`, else of the folder
 * itself, else of `velodyne/`, sorted numerically; a folder mixing formats is an error saying
 * what it holds. Poses: SequenceOptions::poses_path in its format, else `poses.txt`
 * (sensor→world, KITTI 3x4), else a non-identity PCD VIEWPOINT of the first frame means every
 * frame's VIEWPOINT is its pose, else none (estimate them). Times: `times.txt`, else frame index
 * / rate. All counts are checked at open(); errors throw InputError naming the file and line.
 */
class SequenceReader {
 public:
  SequenceReader() = default;
  explicit SequenceReader(const std::string& folder, double rate_hz = 10.0) {
    open(folder, rate_hz);
  }

  explicit SequenceReader(const std::string& folder, const SequenceOptions& options) {
    open(folder, options);
  }

  /** \brief Scans the folder and reads poses/times; throws InputError. */
  void open(const std::string& folder, double rate_hz = 10.0);
  void open(const std::string& folder, const SequenceOptions& options);

  std::size_t size() const { return frame_paths_.size(); }
  bool empty() const { return frame_paths_.empty(); }
  const std::string& folder() const { return folder_; }
  const std::vector<std::string>& framePaths() const { return frame_paths_; }
  /** \brief Frame names without extension ("000042"), used to name outputs. */
  std::string frameName(std::size_t i) const;
  /** \brief The number in frame i's file name (000040.bin → 40), i when it has none. Outputs
   * (tracks.csv `file`, labelled clouds) use it so they line up with the input files. */
  long long frameNumber(std::size_t i) const;

  /** \brief Whether poses came from poses.txt or the PCD VIEWPOINTs. */
  bool hasPoses() const { return !poses_.empty(); }
  /** \brief "poses.txt", "viewpoint", "none" or "FILE (format)" for SequenceOptions::poses_path. */
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
  void loadTimes(double rate_hz);
  void loadPoses(const SequenceOptions& options);
  void loadPoseFile(const SequenceOptions& options);
  void checkPoseCount(const std::string& path) const;

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
  /** \brief Writes frames/NNNNNN.pcd with a per-point float `time` field after x y z intensity
   * (`times`: one per point, seconds after the frame's time in times.txt, NaN allowed), as the
   * Velodyne driver writes it and readPointTimes() reads it. Throws InputError when the sizes
   * differ. Returns the path. */
  std::string writeFrame(std::size_t index, const pcl::PointCloud<pcl::PointXYZI>& cloud,
                         const std::vector<float>& times) const;
  void writePoses(const std::vector<Eigen::Isometry3d>& poses) const;
  /** \brief Writes times.txt (see io::writeTimes()). */
  void writeTimes(const std::vector<double>& times, bool exact = false) const;
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
