/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/ground_parameters.h>

#include <pcl/filters/filter_indices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <vector>

namespace pcl_movers {

/** \brief Removes the ground of a spinning-LiDAR scan with local, roughly horizontal planes
 * (Morris et al., section 4: "a local, roughly horizontal, planar model is used to fit ground
 * points").
 *
 * The ground around the sensor is cut into polar cells: `getNumSectors()` equal azimuth sectors
 * times rings whose radial size grows with range (`setRingEdges()`), because a spinning LiDAR's
 * point density falls with the square of range — near cells would otherwise hold thousands of
 * points and far ones a handful. In every cell a plane is fitted by RANSAC (the hypotheses of
 * pcl::SampleConsensusModelPerpendicularPlane: planes within `getMaxTilt()` of horizontal; the
 * adaptive stop of pcl::RandomSampleConsensus at probability 0.99) on an evenly strided subsample
 * of at most `getMaxSamples()` points, then a least-squares refit on the inliers. The RANSAC is
 * written out on flat coordinate arrays rather than run through PCL's classes: the per-hypothesis
 * overhead of those (model object, angle via acos, OpenMP critical sections) was half the
 * filter's time on 512 small cells per frame. Cells are processed from the sensor outwards; each
 * cell only considers points near the plane of its inner neighbour (the "prior"), so a car roof or
 * a table-top cannot be mistaken for the road, and a cell whose fit fails (too few points, too
 * steep, a jump of more than `getMaxStep()` from the prior) inherits the prior. The innermost ring
 * starts from a horizontal plane `getSensorHeight()` below the input's `sensor_origin_`. Every
 * point of a cell is then classified by its distance to the cell's plane: ground when it is
 * within `getDistanceThreshold()`. (Calling everything below the plane ground was tried and cost
 * ~4 points of precision on SemanticKITTI: planes that sit a little high near walls and bushes then
 * swallow their lower parts.)
 *
 * **Local-slope test (organized inputs only).** A plane-distance test alone calls everything
 * within the threshold ground, including the lowest few centimetres of bushes, hedges, grass
 * tufts and wall bases, which dominate its false positives on SemanticKITTI. The range image
 * tells them apart cheaply: along a column (one azimuth, consecutive beams) ground rises slowly
 * with horizontal distance, while vegetation and walls rise steeply. A point that passed the
 * distance test is rejected when the rise to the point of the beam just above or below it,
 * minus `getRangeNoise()`, exceeds tan(`getMaxLocalSlope()`) times their horizontal distance —
 * the angle criterion of Bogoslavskyi & Stachniss' depth_clustering ground labelling, made
 * noise-aware because near the sensor consecutive beams hit the road only ~0.1 m apart and
 * 2 cm of range noise would otherwise look like a 10° slope. Neighbours further than
 * `getLocalSlopeBand()` from their plane are objects standing on the ground and are ignored, so
 * the road at the foot of a car or wall stays ground. Heights are measured from each point's own
 * cell plane, so slopes and rolling terrain are not mistaken for steep rises; a kerb costs at most
 * the one beam that hits its face.
 *
 * Because each cell has its own plane and planes are chained ring to ring, slopes, kerbs, ramps and
 * rolling terrain are followed; the cloud need not be organized (the cells are built from x, y).
 *
 * PCL semantics (as pcl::PassThrough / pcl::ExtractIndices):
 *  - `filter(output)` returns the **non-ground** points (what the mover pipeline needs next);
 *    `setNegative(true)` returns the **ground** points instead.
 *  - `setKeepOrganized(true)` keeps the input's width/height and replaces filtered-out points by
 * the user filter value (NaN by default).
 *  - Points with a non-finite coordinate are neither ground nor non-ground: they are removed in
 *    both modes (and reported by getRemovedIndices()).
 *  - `getRemovedIndices()` works when the filter was built with `extract_removed_indices = true`.
 *  - Only the points in `indices_` (setIndices) are considered.
 *
 * Sampling is deterministic: every cell draws its RANSAC samples from a fixed seed derived from
 * the cell's number, so the same input gives the same output.
 */
template <typename PointT>
class GroundPlaneFilter : public pcl::FilterIndices<PointT> {
 protected:
  using PointCloud = typename pcl::FilterIndices<PointT>::PointCloud;
  using pcl::FilterIndices<PointT>::negative_;
  using pcl::FilterIndices<PointT>::keep_organized_;
  using pcl::FilterIndices<PointT>::user_filter_value_;
  using pcl::Filter<PointT>::filter_name_;
  using pcl::Filter<PointT>::extract_removed_indices_;
  using pcl::Filter<PointT>::removed_indices_;
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;

 public:
  using Ptr = pcl::shared_ptr<GroundPlaneFilter<PointT>>;
  using ConstPtr = pcl::shared_ptr<const GroundPlaneFilter<PointT>>;

  /** \brief A plane n·p + d = 0 with n the unit upward normal (n.z > 0). */
  struct Plane {
    Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
    float d = 0.f;
    /** \brief Signed height of p above the plane [m]. */
    float height(const Eigen::Vector3f& p) const { return normal.dot(p) + d; }
  };

  /** \param extract_removed_indices set to true to be able to call getRemovedIndices().
   * The settings start from GroundParameters' defaults. */
  explicit GroundPlaneFilter(bool extract_removed_indices = false);

  /** \brief Sets every setting GroundParameters holds (the individual setters below set one). */
  void setParameters(const GroundParameters& parameters);
  /** \brief The settings GroundParameters holds, as they are now. */
  GroundParameters getParameters() const;

  /** \brief Points whose height above their cell's plane is below this are ground [m]. */
  void setDistanceThreshold(float threshold) { distance_threshold_ = threshold; }
  float getDistanceThreshold() const { return distance_threshold_; }

  /** \brief Inlier distance of the sample-consensus fit [m] (default 0.1). */
  void setFitThreshold(float threshold) { fit_threshold_ = threshold; }
  float getFitThreshold() const { return fit_threshold_; }

  /** \brief Steepest plane still taken for ground [rad]; steeper fits fall back to the prior
   * plane. */
  void setMaxTilt(float radians) { max_tilt_ = radians; }
  float getMaxTilt() const { return max_tilt_; }

  /** \brief Largest height jump [m] between a cell's plane and its prior at the cell centre
   * (default 0.5), plus `getMaxSlopeChange()` per metre between the two cell centres. */
  void setMaxStep(float step) { max_step_ = step; }
  float getMaxStep() const { return max_step_; }

  /** \brief Height change allowed per metre of distance to the prior cell (default 0.1, ~6°):
   * how much the terrain may bend between rings. */
  void setMaxSlopeChange(float slope) { max_slope_change_ = slope; }
  float getMaxSlopeChange() const { return max_slope_change_; }

  /** \brief Height of the sensor above the ground under it [m]; the innermost cells start from
   * a horizontal plane this far below `sensor_origin_`. 0 (the default): estimated from each
   * scan as the depth of the deepest dense layer of returns within 15 m below the sensor
   * (getUsedSensorHeight()), since mounting heights differ by a metre between vehicles. */
  void setSensorHeight(float height) { sensor_height_ = height; }
  float getSensorHeight() const { return sensor_height_; }
  /** \brief The sensor height the last run started from: the set one, or the estimate. */
  float getUsedSensorHeight() const { return used_sensor_height_; }

  /** \brief Number of equal azimuth sectors. */
  void setNumSectors(int sectors) { num_sectors_ = sectors; }
  int getNumSectors() const { return num_sectors_; }

  /** \brief Radial cell edges [m], increasing, starting at 0; points beyond the last edge go to the
   * outermost ring. Default {0, 6, 8, 10, 12.5, 15, 18, 21.5, 25.5, 30, 35, 41, 48, 57, 68, 82}. */
  void setRingEdges(const std::vector<float>& edges) { ring_edges_ = edges; }
  const std::vector<float>& getRingEdges() const { return ring_edges_; }

  /** \brief Radial depth [m] from which a cell's ground may curve within it (default 10, the
   * cells beyond 57 m with the default rings). In such a cell a plane that leaves points below it
   * is only replaced by the plane through those points when that one leaves fewer of the cell's
   * points below it: on rolling terrain the points below a far cell's plane are the low stretches
   * of its two or three scan lines, not the ground beneath an object's horizontal slice, and a
   * plane through them alone rises elsewhere. Infinity = every cell as a near one. */
  void setCurvedCellDepth(float depth) { curved_cell_depth_ = depth; }
  float getCurvedCellDepth() const { return curved_cell_depth_; }
  /** \brief Fewest points for a cell to get its own plane (default 12); sparser cells inherit. */
  void setMinPointsPerCell(int n) { min_points_per_cell_ = n; }
  int getMinPointsPerCell() const { return min_points_per_cell_; }

  /** \brief Most points one cell's RANSAC sees (default 64, an evenly strided subsample). */
  void setMaxSamples(int n) { max_samples_ = n; }
  int getMaxSamples() const { return max_samples_; }

  /** \brief RANSAC iteration cap per cell (default 40; the inlier ratio is high so RANSAC's own
   * adaptive stop usually ends far earlier). */
  void setMaxIterations(int n) { max_iterations_ = n; }
  int getMaxIterations() const { return max_iterations_; }

  /** \brief Whether to apply the local-slope test on organized inputs (ignored on unorganized
   * clouds, which have no beam neighbours: organize them first, see RangeImageOrganizer). */
  void setLocalSlopeCheck(bool check) { local_slope_check_ = check; }
  bool getLocalSlopeCheck() const { return local_slope_check_; }

  /** \brief Steepest local slope [rad] between a point and the points of the beams just above
   * and below it in its column; see the class description. */
  void setMaxLocalSlope(float radians) { max_local_slope_ = radians; }
  float getMaxLocalSlope() const { return max_local_slope_; }

  /** \brief Height noise [m] forgiven in the local-slope test: a rise counts as steep only when
   * it exceeds this plus tan(max local slope) times the horizontal distance. */
  void setRangeNoise(float noise) { range_noise_ = noise; }
  float getRangeNoise() const { return range_noise_; }

  /** \brief Column neighbours further than this [m] from their plane do not take part in the
   * local-slope test: they belong to an object standing on the ground (a wall, a car), and the
   * step up to them says nothing about the point at its foot. */
  void setLocalSlopeBand(float band) { local_slope_band_ = band; }
  float getLocalSlopeBand() const { return local_slope_band_; }

  /** \brief Plane used by each cell in the last run, ring-major (ring * sectors + sector). */
  const std::vector<Plane>& getCellPlanes() const { return cell_planes_; }
  /** \brief Whether each cell of the last run fitted its own plane (false = inherited). */
  const std::vector<std::uint8_t>& getCellFitted() const { return cell_fitted_; }
  /** \brief Per point of the last input: its height above its cell's plane [m], NaN for points
   * that were not finite. What an object standing there rises to above the ground under it,
   * however few of its lower points a sparse sensor sampled. */
  const std::vector<float>& getPointHeights() const { return height_; }

 protected:
  /** \brief Fills `indices` with the non-ground (or, when negative, ground) points. */
  void applyFilter(pcl::Indices& indices) override;

  /** \brief Fits one cell's plane to the candidate points `positions` (into the cell-ordered
   * coordinates) by RANSAC with the random sequence `seed`, then least squares; false when the
   * fit fails or is too steep or too far from `prior` (more than `band` at `centre`). */
  bool fitPlane(const std::vector<int>& positions, const Plane& prior, float band,
                const Eigen::Vector2f& centre, std::uint32_t seed, Plane& fitted);

  /** \brief The depth below `origin` of the deepest dense layer of near returns (the ground
   * under the sensor); the last estimate when the scan has too few near returns. */
  float estimateSensorHeight(const Eigen::Vector3f& origin);

  /** \brief Ring of a horizontal distance r (binary search over ring_edges_). */
  int ringOf(float r) const;
  /** \brief Radial size of a ring [m] (the open outermost one: as deep as the ring inside it). */
  float cellDepth(int ring) const;

  float distance_threshold_;  // these eight: GroundParameters' defaults
  float fit_threshold_ = 0.1f;
  float max_tilt_;
  float max_step_ = 0.5f;
  float max_slope_change_ = 0.1f;
  float sensor_height_;
  float used_sensor_height_ = 1.73f;  ///< before any estimate: KITTI's HDL-64E mounting
  int num_sectors_;
  std::vector<float> ring_edges_{0.f,   6.f,  8.f,  10.f, 12.5f, 15.f, 18.f, 21.5f,
                                 25.5f, 30.f, 35.f, 41.f, 48.f,  57.f, 68.f, 82.f};
  float curved_cell_depth_ = 10.f;
  int min_points_per_cell_ = 12;
  int max_samples_ = 64;
  int max_iterations_ = 40;
  bool local_slope_check_;
  float max_local_slope_;
  float range_noise_;
  float local_slope_band_;

  std::vector<Plane> cell_planes_;
  std::vector<std::uint8_t> cell_fitted_;
  // Work buffers kept between calls so a sequence of frames does not reallocate.
  std::vector<int> cell_of_, cell_start_, cell_fill_, cell_points_, ring_lut_;
  std::vector<Eigen::Vector3f> cell_xyz_;
  std::vector<float> height_;  ///< per point of the input: height above its plane, NaN if unused
  std::vector<std::uint8_t> steep_;  ///< per point: the local-slope test flagged it
  std::vector<int> depth_bins_;      ///< near returns per depth layer (sensor-height estimate)
  std::vector<float> depths_;        ///< depths of the densest layer's returns
  std::vector<int> positions_;       ///< candidates of the current cell (into cell_xyz_)
  std::vector<int> candidates_;      ///< the same before the floating-plane test trims them
  std::vector<float> sample_x_, sample_y_, sample_z_;  ///< RANSAC subsample, flat per axis
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/ground_plane_filter.hpp>
#endif
