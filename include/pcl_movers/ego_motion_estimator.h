/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <deque>
#include <unordered_map>
#include <vector>

namespace pcl_movers {
namespace detail {

/** \brief Points hashed into cubic cells, for nearest-neighbour and radius queries no further than
 * one cell. Used instead of pcl::KdTreeFLANN because FLANN opens an OpenMP region per query, which
 * cost more than the searches themselves (over half the run time, and far worse on a loaded
 * machine), and because a hash grid is built in linear time when the map changes. */
class PointHashGrid {
 public:
  void build(const std::vector<Eigen::Vector3f>& points, float cell) {
    points_ = &points;
    cell_ = cell;
    cells_.clear();
    cells_.reserve(points.size() / 4 + 1);
    for (std::size_t i = 0; i < points.size(); ++i)
      cells_[key(points[i])].push_back(static_cast<int>(i));
  }
  /** \brief Index of the nearest point within `max_dist` (<= the cell size), or -1. */
  int nearest(const Eigen::Vector3f& q, float max_dist, float& best_d2) const {
    best_d2 = max_dist * max_dist;
    int best = -1;
    forNeighbourCells(q, [&](const std::vector<int>& ids) {
      for (int i : ids) {
        const float d2 = ((*points_)[i] - q).squaredNorm();
        if (d2 <= best_d2) {
          best_d2 = d2;
          best = i;
        }
      }
    });
    return best;
  }
  /** \brief Indices of the points within `radius` (<= the cell size). */
  void radius(const Eigen::Vector3f& q, float radius, std::vector<int>& out) const {
    out.clear();
    const float r2 = radius * radius;
    forNeighbourCells(q, [&](const std::vector<int>& ids) {
      for (int i : ids)
        if (((*points_)[i] - q).squaredNorm() <= r2) out.push_back(i);
    });
  }

 private:
  static std::int64_t pack(std::int64_t x, std::int64_t y, std::int64_t z) {
    // 21 bits per axis: +-1M cells, i.e. +-500 km at 0.5 m.
    return ((x & 0x1FFFFF) << 42) | ((y & 0x1FFFFF) << 21) | (z & 0x1FFFFF);
  }
  std::int64_t key(const Eigen::Vector3f& p) const {
    return pack(static_cast<std::int64_t>(std::floor(p.x() / cell_)),
                static_cast<std::int64_t>(std::floor(p.y() / cell_)),
                static_cast<std::int64_t>(std::floor(p.z() / cell_)));
  }
  template <typename F>
  void forNeighbourCells(const Eigen::Vector3f& q, F&& f) const {
    const std::int64_t cx = static_cast<std::int64_t>(std::floor(q.x() / cell_)),
                       cy = static_cast<std::int64_t>(std::floor(q.y() / cell_)),
                       cz = static_cast<std::int64_t>(std::floor(q.z() / cell_));
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(pack(cx + dx, cy + dy, cz + dz));
          if (it != cells_.end()) f(it->second);
        }
  }

  const std::vector<Eigen::Vector3f>* points_ = nullptr;
  float cell_ = 1.f;
  std::unordered_map<std::int64_t, std::vector<int>> cells_;
};

}  // namespace detail

/** \brief Estimates the sensor's pose from the scans themselves, for sequences recorded without
 * an INS (no poses.txt, no VIEWPOINT). The paper had an INS; this replaces it by LiDAR odometry.
 *
 * Each scan is cropped to [`getMinRange()`, `getMaxRange()`] (the near cut removes the ego
 * vehicle, the far cut sparse returns), downsampled with a voxel grid of `getVoxelSize()`, given
 * normals from its own neighbourhood, and registered to a **local map** — the last
 * `getLocalMapSize()` keyframes in world coordinates — with point-to-plane ICP, first coarse
 * (wide gate, no trimming) and then fine. Registering to
 * several past scans instead of only the previous one keeps the error from growing with every
 * frame while the vehicle crawls. The initial guess is a constant-velocity prediction.
 *
 * Robustness to movers (the very objects this library looks for) comes from three things:
 * correspondences further than `getMaxCorrespondenceDistance()` are dropped, the worst
 * `1 - getTrimRatio()` of the remaining residuals are ignored in every iteration (trimmed ICP),
 * and the rest are weighted with a Cauchy kernel of scale `getKernelScale()`. Moving objects are a
 * small part of a street scene, so they end up in the trimmed tail.
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
   * usable points keeps the constant-velocity prediction (and getLastFitness() reports 0
   * correspondences) rather than failing the whole sequence. */
  Eigen::Isometry3d estimate(const PointCloud& scan);

  /** \brief A frame without a scan (a blind frame: no return at all): returns its pose predicted
   * with the constant-velocity motion (the last pose without it), and leaves the map unchanged.
   * Before the first scan it returns the identity and the next scan still defines the world. */
  Eigen::Isometry3d coast();

  /** \brief Forgets the map and the motion; the next scan becomes the world origin. */
  void reset();

  /** \brief Voxel grid leaf of the registered scans [m] (default 0.5). */
  void setVoxelSize(float size) { voxel_size_ = size; }
  float getVoxelSize() const { return voxel_size_; }

  /** \brief Points nearer than this are dropped (ego vehicle) [m] (default 3). */
  void setMinRange(float range) { min_range_ = range; }
  float getMinRange() const { return min_range_; }

  /** \brief Points further than this are dropped [m] (default 60). */
  void setMaxRange(float range) { max_range_ = range; }
  float getMaxRange() const { return max_range_; }

  /** \brief Largest point-to-map distance of a correspondence in the first iteration [m]
   * (default 1.5); it shrinks to a third of this over the iterations. */
  void setMaxCorrespondenceDistance(float distance) { max_correspondence_distance_ = distance; }
  float getMaxCorrespondenceDistance() const { return max_correspondence_distance_; }

  /** \brief Fraction of correspondences kept (the smallest residuals) (default 0.8). */
  void setTrimRatio(float ratio) { trim_ratio_ = ratio; }
  float getTrimRatio() const { return trim_ratio_; }

  /** \brief Scale of the Cauchy weights of the residuals [m] (default 0.2). */
  void setKernelScale(float scale) { kernel_scale_ = scale; }
  float getKernelScale() const { return kernel_scale_; }

  /** \brief Most scan points registered per frame; the downsampled scan is strided down to this
   * (default 4000, 0 = all). */
  void setMaxSourcePoints(int n) { max_source_points_ = n; }
  int getMaxSourcePoints() const { return max_source_points_; }

  /** \brief ICP iterations per scan, split between a coarse and a fine phase (default 30). */
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

  /** \brief Neighbours used for each point's normal (default 10). */
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
  /** \brief A downsampled scan with per-point unit normals (NaN normal = not planar enough). */
  struct Keyframe {
    std::vector<Eigen::Vector3f> points;   ///< world frame
    std::vector<Eigen::Vector3f> normals;  ///< world frame
  };

  /** \brief Crop and downsample; in the sensor frame. */
  void preprocess(const PointCloud& scan, std::vector<Eigen::Vector3f>& points) const;
  /** \brief Unit normals by PCA of each point's neighbours (NaN where not planar). */
  void computeNormals(const std::vector<Eigen::Vector3f>& points,
                      std::vector<Eigen::Vector3f>& normals) const;
  /** \brief Point-to-plane ICP of `points` against the map, starting from `pose`. */
  bool registerToMap(const std::vector<Eigen::Vector3f>& points, Eigen::Isometry3d& pose);
  /** \brief Appends a keyframe and rebuilds the map's search tree. */
  void addKeyframe(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& pose);

  float voxel_size_ = 0.5f;
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
  int normal_neighbours_ = 10;
  bool vertical_ground_normals_ = false;

  std::deque<Keyframe> keyframes_;
  std::vector<Eigen::Vector3f> map_points_;   ///< world frame, one per voxel
  std::vector<Eigen::Vector3f> map_normals_;  ///< world frame
  detail::PointHashGrid map_grid_;
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
