/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <vector>

namespace pcl_movers {
namespace detail {

/** \brief Open-addressing hash table from a packed voxel key to an int, for the estimator's
 * voxel maps. Replaces std::unordered_map (one heap node per entry, a pointer chase per
 * lookup): lookups are the inner loop of the registration and this table resolves most of them
 * in one cache line. Entries are never erased (the callers keep empty voxels and rebuild). */
class VoxelHashIndex {
 public:
  static constexpr std::int64_t kEmpty = std::numeric_limits<std::int64_t>::min();

  /** \brief Empties the table, sized for about `expected` entries. */
  void clear(std::size_t expected = 0) {
    std::size_t cap = 16;
    while (cap < 2 * expected + 2) cap *= 2;
    keys_.assign(cap, kEmpty);
    values_.assign(cap, -1);
    mask_ = cap - 1;
    size_ = 0;
  }
  /** \brief The value stored for `key`, or -1. */
  int find(std::int64_t key) const {
    if (keys_.empty()) return -1;
    for (std::size_t i = slot(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return values_[i];
      if (keys_[i] == kEmpty) return -1;
    }
  }
  /** \brief Stores `value` for `key` unless the key is present; returns the stored value. */
  int insert(std::int64_t key, int value) {
    if (keys_.empty() || 2 * (size_ + 1) > keys_.size()) grow();
    for (std::size_t i = slot(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return values_[i];
      if (keys_[i] == kEmpty) {
        keys_[i] = key;
        values_[i] = value;
        ++size_;
        return value;
      }
    }
  }
  std::size_t size() const { return size_; }

  /** \brief Packs integer voxel coordinates, 21 bits each (+-1M voxels: +-1000 km at 1 m). */
  static std::int64_t pack(std::int64_t x, std::int64_t y, std::int64_t z) {
    return ((x & 0x1FFFFF) << 42) | ((y & 0x1FFFFF) << 21) | (z & 0x1FFFFF);
  }

 private:
  std::size_t slot(std::int64_t key) const {
    // Fibonacci hashing: the packed keys of neighbouring voxels differ in few, low bits.
    return static_cast<std::size_t>((static_cast<std::uint64_t>(key) * 0x9E3779B97F4A7C15ull) >>
                                    17) &
           mask_;
  }
  void grow() {
    std::vector<std::int64_t> keys;
    std::vector<int> values;
    keys.swap(keys_);
    values.swap(values_);
    clear(std::max<std::size_t>(16, keys.size()));
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) insert(keys[i], values[i]);
  }

  std::vector<std::int64_t> keys_;
  std::vector<int> values_;
  std::size_t mask_ = 0;
  std::size_t size_ = 0;
};

/** \brief Zeroth, first and second moments of the points in a voxel: enough to add and remove
 * whole scans from a map exactly, and to fit a plane at any time. */
struct VoxelMoments {
  double n = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();  ///< sum of p p^T
};

}  // namespace detail

/** \brief Estimates the sensor's pose from the scans themselves, for sequences recorded without
 * an INS (no poses.txt, no VIEWPOINT). The paper had an INS; this replaces it by LiDAR odometry.
 *
 * Each scan is cropped to [`getMinRange()`, `getMaxRange()`] (the near cut removes the ego
 * vehicle, the far cut sparse returns) and summarised in one pass by the moments (count, mean,
 * scatter) of its points in cubic voxels of `getVoxelSize()`. The voxel means are the points
 * registered; the map is the sum of the voxel moments of the last `getLocalMapSize()` keyframes
 * in world coordinates, from which every map voxel gets a plane (mean and normal, kept only where
 * the points are planar). Registration is point-to-plane ICP of the scan's voxel means against
 * those planes: a coarse phase (nearest plane among the 27 surrounding voxels, wide gate, no
 * trimming) and a fine phase (the plane of the voxel a point falls in: one table lookup). Adding
 * and dropping keyframes adds and subtracts their moments, so the map follows the sensor at the
 * cost of one scan's voxels, and nothing is searched in a tree. Registering to several past
 * scans instead of only the previous one keeps the error from growing with every frame while the
 * vehicle crawls. The initial guess is a constant-velocity prediction.
 *
 * Robustness to movers (the very objects this library looks for) comes from three things:
 * correspondences with a point-to-plane residual above `getMaxCorrespondenceDistance()` are
 * dropped, the worst `1 - getTrimRatio()` of the remaining residuals are ignored in every fine
 * iteration (trimmed ICP), and the rest are weighted with a Cauchy kernel of scale
 * `getKernelScale()`. Moving objects are a small part of a street scene, so they end up in the
 * trimmed tail.
 *
 * With `setPlanarMotion(true)` only x, y and yaw are estimated (z, roll and pitch keep their
 * predicted values), which suits vehicles on flat ground and removes the weakly observed degrees
 * of freedom.
 *
 * World = sensor frame of the first scan; `estimate()` returns the sensor→world pose in the same
 * convention as poses.txt.
 */
template <typename PointT>
class EgoMotionEstimator {
 public:
  using Ptr = pcl::shared_ptr<EgoMotionEstimator<PointT>>;
  using ConstPtr = pcl::shared_ptr<const EgoMotionEstimator<PointT>>;
  using PointCloud = pcl::PointCloud<PointT>;

  EgoMotionEstimator() = default;

  /** \brief Registers the next scan (sensor frame) and returns its sensor→world pose. The first
   * scan after construction or reset() defines the world frame (identity). A scan with too few
   * usable points in range keeps the constant-velocity prediction (and getLastCorrespondences()
   * reports 0) rather than failing the whole sequence.
   * \throws pcl_movers::InputError if the scan has no finite point at all (empty or all NaN):
   * that is a broken input, not a hard scene; the estimator's state is left unchanged. */
  Eigen::Isometry3d estimate(const PointCloud& scan);

  /** \brief Forgets the map and the motion; the next scan becomes the world origin. */
  void reset();

  /** \brief Edge of the voxels in which scans are summarised and map planes fitted [m]
   * (default 1.0). */
  void setVoxelSize(float size) { voxel_size_ = size; }
  float getVoxelSize() const { return voxel_size_; }

  /** \brief Points nearer than this are dropped (ego vehicle) [m] (default 3). */
  void setMinRange(float range) { min_range_ = range; }
  float getMinRange() const { return min_range_; }

  /** \brief Points further than this are dropped [m] (default 60). */
  void setMaxRange(float range) { max_range_ = range; }
  float getMaxRange() const { return max_range_; }

  /** \brief Largest point-to-plane residual (and, in the coarse phase, point to plane-centre
   * distance) of a correspondence [m] (default 1.5); the fine phase shrinks it to a third of
   * this over its iterations. */
  void setMaxCorrespondenceDistance(float distance) { max_correspondence_distance_ = distance; }
  float getMaxCorrespondenceDistance() const { return max_correspondence_distance_; }

  /** \brief Fraction of correspondences kept (the smallest residuals) (default 0.8). */
  void setTrimRatio(float ratio) { trim_ratio_ = ratio; }
  float getTrimRatio() const { return trim_ratio_; }

  /** \brief Scale of the Cauchy weights of the residuals [m] (default 0.2). */
  void setKernelScale(float scale) { kernel_scale_ = scale; }
  float getKernelScale() const { return kernel_scale_; }

  /** \brief Most voxel means registered per frame in the fine phase; more are strided down to
   * this (default 4000, 0 = all). The coarse phase uses a quarter of them. */
  void setMaxSourcePoints(int n) { max_source_points_ = n; }
  int getMaxSourcePoints() const { return max_source_points_; }

  /** \brief Most ICP iterations per scan, coarse and fine phases together (default 30); both
   * phases end early once an update is below getTransformationEpsilon(). */
  void setMaximumIterations(int iterations) { max_iterations_ = iterations; }
  int getMaximumIterations() const { return max_iterations_; }

  /** \brief Stop when an update is smaller than this [m and rad] (default 1e-4). */
  void setTransformationEpsilon(double epsilon) { transformation_epsilon_ = epsilon; }
  double getTransformationEpsilon() const { return transformation_epsilon_; }

  /** \brief Keyframes kept in the local map (default 8). */
  void setLocalMapSize(int keyframes) { local_map_size_ = keyframes; }
  int getLocalMapSize() const { return local_map_size_; }

  /** \brief A scan becomes a keyframe after moving this far from the last keyframe [m]
   * (default 1.0) or turning `getKeyframeAngle()`. */
  void setKeyframeDistance(double distance) { keyframe_distance_ = distance; }
  double getKeyframeDistance() const { return keyframe_distance_; }

  /** \brief Turn that makes a new keyframe [rad] (default 5°). */
  void setKeyframeAngle(double angle) { keyframe_angle_ = angle; }
  double getKeyframeAngle() const { return keyframe_angle_; }

  /** \brief Estimate only x, y and yaw (default false). */
  void setPlanarMotion(bool planar) { planar_motion_ = planar; }
  bool getPlanarMotion() const { return planar_motion_; }

  /** \brief Start each registration from a constant-velocity prediction (default true). */
  void setConstantVelocity(bool enabled) { constant_velocity_ = enabled; }
  bool getConstantVelocity() const { return constant_velocity_; }

  /** \brief Treat map normals within ~18 deg of vertical as exactly vertical, so that the
   * ground constrains only z, roll and pitch (default false: on rolling terrain the sloping
   * ground is what fixes x and y). */
  void setVerticalGroundNormals(bool enabled) { vertical_ground_normals_ = enabled; }
  bool getVerticalGroundNormals() const { return vertical_ground_normals_; }

  /** \brief Fewest points a voxel needs to be registered (scan) or to get a plane (map)
   * (default 5: a plane from fewer is mostly noise). */
  void setNormalNeighbours(int k) { normal_neighbours_ = k; }
  int getNormalNeighbours() const { return normal_neighbours_; }

  /** \brief RMS point-to-plane residual of the kept correspondences of the last scan [m]. */
  double getLastFitness() const { return last_fitness_; }
  /** \brief Number of correspondences used in the last iteration of the last scan. */
  int getLastCorrespondences() const { return last_correspondences_; }
  /** \brief ICP iterations of the last scan. */
  int getLastIterations() const { return last_iterations_; }
  /** \brief Motion of the last scan relative to the previous one (previous sensor frame). */
  const Eigen::Isometry3d& getLastMotion() const { return motion_; }
  /** \brief Scans processed since reset(). */
  std::size_t getFrameCount() const { return frames_; }

 protected:
  /** \brief A scan voxel, sensor frame: moments, and the point registered (one of its points
   * drawn at random). */
  struct ScanVoxel {
    detail::VoxelMoments moments;
    Eigen::Vector3f sample = Eigen::Vector3f::Zero();
  };
  /** \brief A map voxel: summed moments of the keyframes and the plane fitted to them. */
  struct MapVoxel {
    detail::VoxelMoments moments;
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< plane normal, or line direction
    bool planar = false;                               ///< has a usable plane or line
    bool linear = false;  ///< a line (pole, trunk), matched point-to-line
    bool dirty = true;    ///< moments changed since the plane was fitted
  };
  /** \brief What one keyframe added to the map (world frame), to subtract it again. */
  struct Keyframe {
    std::vector<std::int64_t> keys;
    std::vector<detail::VoxelMoments> moments;
  };

  /** \brief Crops the scan and fills scan_voxels_ (sensor frame); returns the finite points. */
  std::size_t summarise(const PointCloud& scan);
  /** \brief Point-to-plane ICP of the scan voxel means against the map, starting from `pose`. */
  bool registerToMap(Eigen::Isometry3d& pose);
  /** \brief Adds the scan's voxels at `pose` to the map, dropping the oldest keyframe if the map
   * is full. */
  void addKeyframe(const Eigen::Isometry3d& pose);
  /** \brief The map voxel with a valid plane for `key`, or null; fits the plane if stale. */
  const MapVoxel* plane(std::int64_t key);
  /** \brief Voxel key of a point at `voxel_size_`. */
  std::int64_t keyOf(const Eigen::Vector3f& p, Eigen::Vector3i* cell = nullptr) const;

  float voxel_size_ = 1.0f;
  float min_range_ = 3.0f;
  float max_range_ = 60.0f;
  float max_correspondence_distance_ = 1.5f;
  float trim_ratio_ = 0.8f;
  float kernel_scale_ = 0.2f;
  int max_iterations_ = 30;
  int max_source_points_ = 4000;
  double transformation_epsilon_ = 1e-4;
  int local_map_size_ = 8;
  double keyframe_distance_ = 1.0;
  double keyframe_angle_ = 5.0 * M_PI / 180.0;
  bool planar_motion_ = false;
  bool constant_velocity_ = true;
  int normal_neighbours_ = 5;
  bool vertical_ground_normals_ = false;

  std::vector<ScanVoxel> scan_voxels_;  ///< the current scan, sensor frame
  detail::VoxelHashIndex scan_index_;
  std::deque<Keyframe> keyframes_;
  std::vector<MapVoxel> map_voxels_;  ///< world frame; empty voxels stay until compaction
  detail::VoxelHashIndex map_index_;
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d motion_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d keyframe_pose_ = Eigen::Isometry3d::Identity();
  std::size_t frames_ = 0;
  double last_fitness_ = 0.0;
  int last_correspondences_ = 0;
  int last_iterations_ = 0;
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/ego_motion_estimator.hpp>
#endif
