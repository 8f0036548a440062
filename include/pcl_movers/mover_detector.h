/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/free_space_map.h>
#include <pcl_movers/io/tracks.h>
#include <pcl_movers/motion_split.h>
#include <pcl_movers/mover_tracker.h>
#include <pcl_movers/range_image_region_growing.h>  // declarations only, for CellLabels
#include <pcl_movers/sensor_model.h>

#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace pcl_movers {

// The other stage classes are only held by pointer here, so that this header stays light.
template <typename PointT>
class GroundPlaneFilter;
template <typename PointT>
class RangeImageOrganizer;

/** \brief The whole mover-detection pipeline for one frame (DESIGN.md "The pipeline"):
 * organize (when the scan is not organized yet) → GroundPlaneFilter → RangeImageRegionGrowing →
 * world frame (the frame's pose) → MoverTracker.
 *
 * \code
 * pcl_movers::MoverDetector<pcl::PointXYZI> detector;
 * detector.setParameters(params);
 * for (std::size_t i = 0; i < reader.size(); ++i) {
 *   reader.read(i, *scan);
 *   pcl_movers::MoverDetector<pcl::PointXYZI>::FrameResult result;
 *   detector.process(scan, reader.pose(i), reader.time(i), int(i), result);
 *   rows.insert(rows.end(), result.rows.begin(), result.rows.end());
 * }
 * \endcode
 *
 * Each call returns, for every cluster with a track, its io::TrackRow (as written to tracks.csv),
 * the indices of its points in the organized sensor-frame cloud, and per-point labels of that
 * cloud (ground / static / mover and the track id) for labelled output. getTimings() gives the
 * milliseconds each stage took on the last frame.
 */
template <typename PointT>
class MoverDetector {
 public:
  using PointCloud = pcl::PointCloud<PointT>;
  using PointCloudPtr = typename PointCloud::Ptr;
  using PointCloudConstPtr = typename PointCloud::ConstPtr;
  using Ptr = pcl::shared_ptr<MoverDetector<PointT>>;
  using ConstPtr = pcl::shared_ptr<const MoverDetector<PointT>>;

  /** \brief Per-point class in FrameResult::labels. */
  enum Label : std::uint8_t {
    kUnlabelled = 0,  ///< invalid (NaN), or an object point not in any tracked cluster
    kGround = 1,
    kStatic = 2,  ///< in a tracked cluster that is not a mover
    kMover = 3
  };

  /** \brief Names of the stages in getTimings(), in order. */
  static const std::vector<std::string>& stageNames();

  /** \brief Everything one frame produced. */
  struct FrameResult {
    int frame = 0;
    double time = 0;
    /** One row per cluster with a track (tracks.csv rows of this frame); a mover that is a part
     * of a larger mover (its track born as the larger one's fragment) reports that mover's
     * velocity. */
    std::vector<io::TrackRow> rows;
    /** Points of rows[i] in `organized`. */
    std::vector<pcl::PointIndices> cluster_indices;
    /** The organized sensor-frame scan the indices and labels refer to. */
    PointCloudConstPtr organized;
    /** Per point of `organized`: Label, and the track id (-1 when none): its row's, or, for the
     * points of a mover's fragment (findMoverFragments()), kMover and the mover's. */
    std::vector<std::uint8_t> labels;
    std::vector<int> track_ids;
    /** Per point of `organized`: the index of the input scan's point it holds, -1 for an empty
     * cell; empty when the input was organized already (point i is then input point i). Writes
     * per-point results back in the input's order. */
    std::vector<int> input_indices;
    /** Number of clusters the segmentation produced (before size filtering). */
    int clusters = 0;
    /** A frame without observations: no finite return, or (sensor "auto") too few returns to
     * estimate the beam layout from. No rows, `organized` is empty, the tracks coasted. */
    bool blind = false;
    std::string blind_reason;  ///< why the frame is blind ("no return", ...); empty otherwise
  };

  /** \brief Fewest finite returns of a scan the beam layout is estimated from (sensor "auto");
   * a scan with fewer is a blind frame while no layout is known, not an error. */
  static constexpr long kMinReturnsToEstimate = 2000;

  MoverDetector() = default;

  /** \brief All stage parameters; validated here (throws InputError). Resets the tracker. */
  void setParameters(const DetectorParameters& parameters);
  const DetectorParameters& getParameters() const { return parameters_; }

  /** \brief Sensor layout for organizing unorganized scans (default: parameters' `sensor`
   * preset; "auto" estimates it from the first unorganized scan with enough returns and uses the
   * preset it recognizes, if any: see SensorModel::recognize()). Organized scans keep their own
   * rows and columns. */
  void setSensorModel(const SensorModel& model) {
    sensor_model_ = model;
    has_sensor_model_ = true;
    organizer_.object.reset();  // its lookups were built for the old model
  }
  const SensorModel& getSensorModel() const { return sensor_model_; }
  /** \brief With sensor "auto": the layout estimated from the first usable unorganized scan
   * (SensorModel::estimate()), of which getSensorModel() is the recognized preset, if any
   * (SensorModel::recognize()); no rows before that scan or with another sensor. */
  const SensorModel& getEstimatedSensorModel() const { return estimated_model_; }

  /** \brief Runs the pipeline on one scan (sensor frame) with its sensor→world pose.
   * World poses may be geo-referenced (UTM-sized translations): the detector works relative to
   * its origin (getOrigin()) and the rows' world columns add it back in double precision.
   * A scan without a finite point (empty, all NaN) or, while the beam layout is still to be
   * estimated (sensor "auto"), with fewer than kMinReturnsToEstimate is a blind frame
   * (FrameResult::blind): the tracks coast to `time` and no row is returned. Throws InputError
   * when the scan cannot be organized (no beam structure, no point in the sensor's view). */
  void process(const PointCloudConstPtr& scan, const Eigen::Isometry3d& world_pose, double time,
               int frame, FrameResult& result);

  /** \brief World position [m] that every single-precision quantity of the detector (world
   * clusters, the tracker's tracks and models, the free-space map) is relative to: the
   * translation of the first pose given to process() after construction, setParameters() or
   * reset(), unless set with setOrigin(). Tracker positions (getTracker()) plus this origin are
   * world positions. */
  const Eigen::Vector3d& getOrigin() const { return origin_; }
  /** \brief Fixes the origin before the first frame (e.g. a map's origin); process() then keeps
   * it instead of taking the first pose's translation. */
  void setOrigin(const Eigen::Vector3d& origin) {
    origin_ = origin;
    has_origin_ = true;
  }

  /** \brief (stage, milliseconds) of the last process(): organize, ground, segment, transform,
   * track, total. */
  const std::vector<std::pair<std::string, double>>& getTimings() const { return timings_; }

  const MoverTracker<PointT>& getTracker() const { return tracker_; }

  /** \brief The ground stage of process(): indices of the non-ground points of `organized`,
   * with the current parameters. Public so that benchmarks and tools reproduce the tracker's input
   * exactly instead of re-configuring the stages by hand. Not const: it runs the detector's own
   * GroundPlaneFilter, whose work buffers are kept from frame to frame. */
  pcl::IndicesPtr removeGround(const PointCloudConstPtr& organized);

  /** \brief The segmentation stage of process(): clusters of `objects` (indices into
   * `organized`), with the current parameters (the detector's own RangeImageRegionGrowing, as
   * removeGround()). */
  std::vector<pcl::PointIndices> segmentObjects(const PointCloudConstPtr& organized,
                                                const pcl::IndicesPtr& objects);

  /** \brief The transform stage of process(): the points of `clusters` moved by `pose` into
   * `world` (only cluster points), and each cluster's indices into `world`. */
  static void clustersToWorld(const PointCloud& organized,
                              const std::vector<pcl::PointIndices>& clusters,
                              const Eigen::Isometry3d& pose, PointCloud& world,
                              std::vector<pcl::PointIndices>& world_clusters);

  /** \brief Lowers each cluster's floor (Observation::floor_z; NaN = none) to the ground under
   * it: the median over its points of (world z − height above the ground filter's cell plane).
   * A car seen by one or two beams of a sparse sensor shows a 0.1-0.5 m slice, yet its top
   * stands 1.5 m above the ground under it: that is what the mover height test asks. */
  void groundFloors(const PointCloud& world, const std::vector<pcl::PointIndices>& clusters,
                    std::vector<Observation>& observations);

  /** \brief Motion-aware segmentation (free_space.split; MotionSplitter): splits the clusters
   * joining a part seen through by the scan free_space.long_lag frames ago to a surface it saw
   * where it is, and remaps `world_clusters` to the new clusters (`world` keeps its points).
   * Needs the current scan in the free-space map. */
  void splitMovingParts(const PointCloud& organized, const Eigen::Isometry3d& pose,
                        std::vector<pcl::PointIndices>& clusters, const PointCloud& world,
                        std::vector<pcl::PointIndices>& world_clusters);

  /** \brief Forgets all tracks and the origin (start of a new sequence). */
  void reset() {
    tracker_.reset();
    free_space_.clear();
    origin_.setZero();
    has_origin_ = false;
  }

 protected:
  /** \brief `world_pose` relative to the origin (taken from it when none is set yet). */
  Eigen::Isometry3d localPose(const Eigen::Isometry3d& world_pose);

  /** \brief Why `scan` is a blind frame, or "" when it can be processed; estimates the beam
   * layout from it when that is still to be done (sensor "auto"). */
  std::string blindReason(const PointCloudConstPtr& scan);
  /** \brief A blind frame: the tracks coast to `time`, the free-space map counts the frame. */
  void coast(const Eigen::Isometry3d& pose, double time, FrameResult& result);

  /** \brief Organizes `scan` into a range image (copy when it is already organized). */
  PointCloudConstPtr organize(const PointCloudConstPtr& scan);

  /** \brief Adds the scan to the free-space map and hands the map to the tracker; false (and no
   * map) when the free-space test is off. */
  bool addToFreeSpaceMap(const PointCloud& organized, const Eigen::Isometry3d& pose);
  /** \brief The tracker's observations of `clusters` (sensor frame; `world_clusters` are the same
   * clusters in `world`): their points and what the range image and the ground filter say of
   * them, whether a side is occluded and what they stand on. */
  std::vector<Observation> describeClusters(const PointCloud& organized,
                                            const pcl::Indices& objects,
                                            const std::vector<pcl::PointIndices>& clusters,
                                            const Eigen::Isometry3d& pose, const PointCloud& world,
                                            std::vector<pcl::PointIndices> world_clusters);
  /** \brief Splits the clusters that hold two tracks moving differently
   * (MoverTracker::splitMergedClusters()), the sensor-frame clusters and the observations alike. */
  void splitMergedClusters(const PointCloud& world, double time,
                           std::vector<pcl::PointIndices>& clusters,
                           std::vector<Observation>& observations);
  /** \brief Per cluster, the mover cluster it is a fragment of (findMoverFragments()), or -1; a
   * mover's cluster is one when its track was born as that mover's fragment. Records the owners
   * of the tracks born this frame (MoverTracker::recordBirthOwners()). */
  std::vector<int> assignFragments(const PointCloud& organized,
                                   const std::vector<pcl::PointIndices>& clusters, double pose_yaw);
  /** \brief The frame's labels, track ids and rows from the tracker's cluster results; `owner`
   * is assignFragments()'. */
  void writeOutputs(const PointCloud& organized, const pcl::Indices& objects,
                    const std::vector<pcl::PointIndices>& clusters, const std::vector<int>& owner,
                    const Eigen::Isometry3d& pose, FrameResult& result) const;
  /** \brief Labels the points of each mover's fragments with the mover; a fragment that is a
   * mover of its own keeps its points and row, but the row reports the mover's velocity. */
  void labelMoverFragments(const std::vector<pcl::PointIndices>& clusters,
                           const std::vector<int>& owner, FrameResult& result) const;
  /** \brief The sensor's yaw in the world [rad]. */
  static double poseYaw(const Eigen::Isometry3d& pose) {
    return std::atan2(pose.linear()(1, 0), pose.linear()(0, 0));
  }
  /** \brief The tracks.csv row of one tracked cluster; `world_to_sensor` and `pose_yaw` (the
   * sensor's yaw in the world) are the frame's, computed once for all its rows. */
  io::TrackRow trackRow(const typename MoverTracker<PointT>::ClusterResult& cluster,
                        const Eigen::Isometry3d& world_to_sensor, double pose_yaw, int frame,
                        double time) const;

  /** \brief A stage object kept between frames so that its work buffers (and the organizer's
   * lookup tables) are reused instead of reallocated every frame. Created on first use; a copy of
   * the detector starts without one, so two detectors never share buffers. */
  template <typename T>
  struct StageObject {
    std::shared_ptr<T> object;
    StageObject() = default;
    StageObject(const StageObject&) {}
    StageObject& operator=(const StageObject&) {
      object.reset();
      return *this;
    }
    StageObject(StageObject&&) noexcept = default;
    StageObject& operator=(StageObject&&) noexcept = default;
    ~StageObject() = default;
  };

  DetectorParameters parameters_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  ///< see getOrigin()
  bool has_origin_ = false;
  SensorModel sensor_model_;
  SensorModel estimated_model_;  ///< see getEstimatedSensorModel()
  bool has_sensor_model_ = false;
  MoverTracker<PointT> tracker_;
  FreeSpaceMap free_space_;                   ///< recent scans for the tracker's free-space test
  std::vector<std::uint8_t> occluded_sides_;  ///< describeClusters()' work buffer
  /// Cell labels of the last frame's range image, shared by occludedSides() and occluderFloors()
  typename RangeImageRegionGrowing<PointT>::CellLabels cell_labels_;
  std::vector<float> roughness_;     ///< per cluster: clusterRoughness()
  std::vector<int> floors_;          ///< per cluster: lowest point of a nearer object below, or -1
  std::vector<float> ground_under_;  ///< groundFloors()' work buffer, kept between frames
  MotionSplitter splitter_;          ///< splitMovingParts()' splitter and its buffers
  std::vector<Eigen::Vector3f> split_points_;  ///< splitMovingParts(): world points to judge
  StageObject<RangeImageOrganizer<PointT>> organizer_;
  /// Whether the last range image's first and last columns are neighbours (organize()).
  bool full_turn_ = true;
  StageObject<GroundPlaneFilter<PointT>> ground_;
  StageObject<RangeImageRegionGrowing<PointT>> segmenter_;
  StageObject<PointCloud> organized_buffer_;  ///< the last range image, reused when released
  std::vector<int> input_indices_;            ///< input index of each cell of the last range image
  std::vector<std::pair<std::string, double>> timings_;
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/mover_detector.hpp>
#endif
