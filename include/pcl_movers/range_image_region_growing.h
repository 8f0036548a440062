/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/segmentation_parameters.h>

#include <pcl/PointIndices.h>
#include <pcl/pcl_base.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace pcl_movers {

/** \brief Clusters an organized scan by region growing in angle-depth space (Morris et al.,
 * section 4: "contiguous region building").
 *
 * The organized cloud is the range image: rows are beams, columns azimuth steps. Each valid cell
 * (finite x, y, z and, when setIndices() was used, listed there) joins its 8 neighbours when their
 * ranges r_a, r_b (distance from `sensor_origin_`) satisfy
 *
 *     |r_a - r_b| <= max(k * min(r_a, r_b), d_min)
 *
 * with k = `getDepthThresholdFactor()` — the paper's threshold proportional to depth, because the
 * spacing between neighbouring samples grows with range — and a small absolute floor
 * d_min = `getMinDepthThreshold()` for the few points very close to the sensor. For 360° sensors
 * the first and last column are neighbours (`setWrapAround(true)`, the default), so an object
 * straddling azimuth ±180° is one cluster.
 *
 * Addition to the paper's rule (documented, off with `setMaxGap(0)`): real range images have empty
 * cells inside objects (dark car windows and tyres return nothing, the organizer leaves holes where
 * two returns fell in one cell, removed ground leaves gaps at the foot of objects). When the
 * immediate neighbour in one of the 8 directions is empty, the search continues up to
 * `getMaxGap()` more cells in that direction and applies the same depth rule to the first valid
 * cell it meets.
 *
 * Second addition (off with `setBridgeLength(0)`): along a row the search goes further, past
 * empty cells *and past nearer cells*, up to `getBridgeLength()` metres of azimuth at the cell's
 * range (the columns are taken to span 360°, as in RangeImageOrganizer's images); the first cell
 * that is not nearer joins when it passes the depth rule and its point lies within
 * `getBridgeLength()` in 3D. A pole or a sign in front of a car, or a dark window run of a near
 * car, otherwise cuts it in two (SemanticKITTI 00 frames 0-2: 4 of the 6 lost objects); a farther
 * cell ends the search, so a gap that shows background between two objects is never bridged.
 *
 * Implementation: one pass over the image with a flat-array union-find (4 forward directions per
 * cell, the other 4 are covered by symmetry), then one pass to collect clusters: O(N), no kd-tree.
 *
 * Errors: on an unorganized input (height 1 or width*height != size) segment() prints a PCL_ERROR
 * and returns an empty cluster list; empty or all-NaN clouds give an empty list without error.
 * Clusters are sorted by size, largest first (as pcl::EuclideanClusterExtraction); the indices of a
 * cluster are in increasing (row-major) order.
 */
template <typename PointT>
class RangeImageRegionGrowing : public pcl::PCLBase<PointT> {
 protected:
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::fake_indices_;
  using pcl::PCLBase<PointT>::initCompute;
  using pcl::PCLBase<PointT>::deinitCompute;

 public:
  using PointCloud = pcl::PointCloud<PointT>;
  using Ptr = pcl::shared_ptr<RangeImageRegionGrowing<PointT>>;
  using ConstPtr = pcl::shared_ptr<const RangeImageRegionGrowing<PointT>>;

  /** \brief The settings start from SegmentationParameters' defaults. */
  RangeImageRegionGrowing() { setParameters(SegmentationParameters()); }

  /** \brief Sets every setting SegmentationParameters holds. */
  void setParameters(const SegmentationParameters& p) {
    depth_threshold_factor_ = static_cast<float>(p.depth_ratio);
    min_depth_threshold_ = static_cast<float>(p.depth_min);
    max_gap_ = p.max_gap;
    bridge_length_ = static_cast<float>(p.row_bridge);
    min_cluster_size_ = p.min_cluster_points;
  }
  /** \brief The settings SegmentationParameters holds, as they are now. */
  SegmentationParameters getParameters() const {
    SegmentationParameters p;
    p.depth_ratio = depth_threshold_factor_;
    p.depth_min = min_depth_threshold_;
    p.max_gap = max_gap_;
    p.row_bridge = bridge_length_;
    p.min_cluster_points = min_cluster_size_;
    return p;
  }

  /** \brief k in d_T = k · range (at k = 0.05 and 10 m, neighbours up to 0.5 m apart in depth
   * join). */
  void setDepthThresholdFactor(float k) { depth_threshold_factor_ = k; }
  float getDepthThresholdFactor() const { return depth_threshold_factor_; }

  /** \brief Absolute floor of the depth threshold [m]. */
  void setMinDepthThreshold(float d) { min_depth_threshold_ = d; }
  float getMinDepthThreshold() const { return min_depth_threshold_; }

  /** \brief Whether the last and first column are neighbours (default true, 360° sensors). */
  void setWrapAround(bool wrap) { wrap_around_ = wrap; }
  bool getWrapAround() const { return wrap_around_; }

  /** \brief Per cell of the last segment()'s range image (row-major): its range from the sensor
   * origin, negative for cells that took no part (no point, or not in the indices). */
  const std::vector<float>& getCellRanges() const { return range_; }

  /** \brief Empty cells bridged in each direction (0 = the paper's strict 8-neighbour rule). */
  void setMaxGap(int gap) { max_gap_ = gap; }
  int getMaxGap() const { return max_gap_; }

  /** \brief Longest gap [m] bridged along a row (0 = off; 0.5 is the usual Euclidean clustering
   * tolerance on KITTI): see the class description. */
  void setBridgeLength(float metres) { bridge_length_ = metres; }
  float getBridgeLength() const { return bridge_length_; }

  /** \brief Clusters with fewer points are dropped. */
  void setMinClusterSize(int n) { min_cluster_size_ = n; }
  int getMinClusterSize() const { return min_cluster_size_; }

  /** \brief Clusters with more points are dropped (default: no limit). */
  void setMaxClusterSize(int n) { max_cluster_size_ = n; }
  int getMaxClusterSize() const { return max_cluster_size_; }

  /** \brief Segments the input into clusters (see the class description for errors). The
   * previous content of `clusters` is replaced; its index vectors are reused, so passing the
   * same vector frame after frame avoids reallocating them. */
  void segment(std::vector<pcl::PointIndices>& clusters);

  /** \brief Bits of occludedSides(): the cluster's extent along that image side is cut by a
   * nearer object. */
  enum OccludedSide : std::uint8_t { kOccludedLeft = 1, kOccludedRight = 2 };

  /** \brief What each cell of a range image holds, for occludedSides() and occluderFloors():
   * kEmptyCell (no point), kGroundCell (a point not in the objects), kObjectCell (an object point
   * in no cluster), else the index of the cluster holding the cell. Computed once per frame by
   * cellLabels(), it serves both (the detector calls them back to back on the same image). */
  struct CellLabels {
    std::vector<int> label;
  };
  static constexpr int kEmptyCell = -2, kGroundCell = -3, kObjectCell = -1;

  /** \brief Fills `labels` for the range image, its non-ground points `objects` and the clusters
   * of segment(); the vector's memory is reused from call to call. */
  static void cellLabels(const PointCloud& organized, const pcl::Indices& objects,
                         const std::vector<pcl::PointIndices>& clusters, CellLabels& labels);

  /** \brief Which sides (columns) of each cluster are bounded by a nearer object, so that the
   * visible extent there is not the object's (it continues behind the occluder, and grows or
   * shrinks as the object emerges or hides).
   *
   * A cell of cluster c is a left (right) boundary cell when the first valid cell to its left
   * (right) in its row, skipping up to `max_gap` empty cells, is not in c. The boundary is
   * occluded there when that cell is an object point (listed in `objects`) nearer than the
   * boundary cell by more than the depth rule's threshold max(k · range, d_min) — the cell that
   * ended the cluster is a closer surface, not background. A side is flagged when at least
   * `min_fraction` of its boundary cells are occluded (a stray nearer point, like a leaf, does not
   * flag it). Ranges are measured from the origin (the organized scan is in the sensor frame).
   * \param[in] organized range image (rows = beams, columns = azimuth)
   * \param[in] objects indices of the non-ground points (occluders are taken from these)
   * \param[in] clusters the clusters of segment()
   * \param[in] k, d_min depth rule of the segmentation
   * \param[in] max_gap empty cells skipped, as in the segmentation
   * \param[in] wrap_around whether the first and last column are neighbours
   * \param[in] min_fraction fraction of a side's boundary cells that must be occluded
   * \param[out] sides per cluster, a combination of OccludedSide bits */
  static void occludedSides(const PointCloud& organized, const pcl::Indices& objects,
                            const std::vector<pcl::PointIndices>& clusters, float k, float d_min,
                            int max_gap, bool wrap_around, float min_fraction,
                            std::vector<std::uint8_t>& sides);
  /** \brief occludedSides() on labels computed by cellLabels() for the same image and clusters. */
  static void occludedSides(const PointCloud& organized, const CellLabels& labels,
                            const std::vector<pcl::PointIndices>& clusters, float k, float d_min,
                            int max_gap, bool wrap_around, float min_fraction,
                            std::vector<std::uint8_t>& sides);

  /** \brief For each cluster hidden from below by a nearer object (a walker's head and shoulders
   * seen above a parked car), the index of the lowest point of that object, else -1.
   *
   * A cluster's bottom cells are its lowest cell in each of its columns. Below one, the first
   * valid cell down the column (skipping up to `max_gap` empty cells) hides the cluster's lower
   * part when it is an object point (in `objects`) nearer by more than max(k · range, d_min), as
   * occludedSides() tests along rows. When at least `min_fraction` of the bottom cells are hidden
   * so, the cluster's floor is the lowest point (smallest z) of the objects hiding it: of their
   * whole clusters where they belong to one, else of the hiding cells themselves. */
  static void occluderFloors(const PointCloud& organized, const pcl::Indices& objects,
                             const std::vector<pcl::PointIndices>& clusters, float k, float d_min,
                             int max_gap, float min_fraction, std::vector<int>& floors);
  /** \brief occluderFloors() on labels computed by cellLabels() for the same image and clusters. */
  static void occluderFloors(const PointCloud& organized, const CellLabels& labels,
                             const std::vector<pcl::PointIndices>& clusters, float k, float d_min,
                             int max_gap, float min_fraction, std::vector<int>& floors);

 protected:
  /** \brief Root of the set holding i, with path halving. */
  int findRoot(int i);

  float depth_threshold_factor_;  // these five: SegmentationParameters' defaults
  float min_depth_threshold_;
  bool wrap_around_ = true;
  int max_gap_;
  float bridge_length_;
  int min_cluster_size_;
  int max_cluster_size_ = std::numeric_limits<int>::max();

  // Work buffers kept between calls so a sequence of frames does not reallocate.
  std::vector<float> range_;      ///< per cell: range, < 0 when the cell does not take part
  std::vector<float> threshold_;  ///< per valid cell: max(k * range, floor)
  std::vector<int> parent_;       ///< union-find forest over the cells
  std::vector<int> set_of_, set_sizes_, set_order_, set_output_;  ///< cluster collection
  std::vector<pcl::index_t*> cursor_;  ///< per output cluster: next index to write
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/range_image_region_growing.hpp>
#endif
