/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/sensor_model.h>

#include <pcl/pcl_base.h>
#include <pcl/point_cloud.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pcl_movers {

/** \brief Turns an unorganized scan of a scanning LiDAR into an organized cloud (a range image):
 * row = beam (top to bottom), column = azimuth (see SensorModel for the column convention), NaN
 * points in empty cells.
 *
 * Each point goes to the beam that best explains it (elevation and the beam's vertical offset,
 * SensorModel::rowOfPoint) and to the column of its azimuth. When two points fall in one cell the
 * second one takes a free horizontally adjacent cell on the side its azimuth leans to (sensors like
 * KITTI's HDL-64E sometimes fire twice within one column); when that is taken too the nearer point
 * keeps the cell, as a single-return range image would, and the other is counted as displaced.
 *
 * Already organized input (height > 1) is passed through unchanged. The mapping both ways is kept
 * so per-cell results can be written back in the input's order: getIndexImage() gives the input
 * index of each cell, getCellOfPoint() the cell of each input point.
 *
 * Bad input throws InputError from organize(): empty cloud, no finite point, no point inside the
 * sensor's field of view, no sensor model when estimation is off; `output` is then left as it was.
 * NaN/Inf points are skipped and counted (getInvalidCount()).
 *
 * Keep one organizer for a whole sequence: the row/column lookups of the model and all buffers
 * are kept from frame to frame (rebuilt only when the model or the width change). The per-point
 * arithmetic runs 4 points at a time (SSE2), 8 with AVX2 or 16 with AVX-512F when the CPU has it
 * (chosen at run time); all give the results of the scalar code bit for bit. With AVX-512 and no
 * indices, 16- and 32-byte points (PointXYZ, PointXYZI) are read in place, without a copy. Input
 * that comes beam after beam, as scanners record it, is fastest: the AVX2/AVX-512 code then
 * confirms the previous point's row instead of looking each row up (any other order gives the
 * same cells).
 *
 * \code
 * pcl_movers::RangeImageOrganizer<pcl::PointXYZI> organizer;
 * organizer.setInputCloud(scan);
 * organizer.setSensorModel(pcl_movers::SensorModel::hdl64());
 * pcl::PointCloud<pcl::PointXYZI> image;
 * organizer.organize(image);  // image.height == 64
 * \endcode
 */
template <typename PointT>
class RangeImageOrganizer : public pcl::PCLBase<PointT> {
 public:
  using PointCloud = pcl::PointCloud<PointT>;
  using Ptr = pcl::shared_ptr<RangeImageOrganizer<PointT>>;
  using ConstPtr = pcl::shared_ptr<const RangeImageOrganizer<PointT>>;

  RangeImageOrganizer() = default;

  /** \brief The beam layout to use; without one the layout is estimated from each input (see
   * setEstimateSensorModel). */
  void setSensorModel(const SensorModel& model);
  /** \brief The model set, or the one estimated by the last organize(). */
  const SensorModel& getSensorModel() const { return model_; }
  bool hasSensorModel() const { return has_model_; }
  /** \brief Forgets the model set, so the next organize() estimates one (if allowed). */
  void clearSensorModel();

  /** \brief Estimate the beam layout from the input (SensorModel::estimate) when no model is set
   * (default true). */
  void setEstimateSensorModel(bool estimate) { estimate_model_ = estimate; }
  bool getEstimateSensorModel() const { return estimate_model_; }

  /** \brief Azimuth columns of the output; 0 (default) keeps the model's. */
  void setColumns(int columns) { columns_ = columns < 0 ? 0 : columns; }
  int getColumns() const { return columns_; }

  /** \brief Points further than this [m] from the sensor are left out; 0 (default) = no limit. */
  void setMaxRange(float max_range) { max_range_ = max_range; }
  float getMaxRange() const { return max_range_; }
  /** \brief Points nearer than this [m] are left out (the vehicle itself); default 0. */
  void setMinRange(float min_range) { min_range_ = min_range; }
  float getMinRange() const { return min_range_; }

  /** \brief Let a point whose cell is taken use a free adjacent column (default true). */
  void setUseFreeNeighbour(bool use) { use_free_neighbour_ = use; }
  bool getUseFreeNeighbour() const { return use_free_neighbour_; }

  /** \brief Organizes the input (honouring setIndices) into `output`. Throws InputError. */
  void organize(PointCloud& output);

  /** \brief Input index of each cell (row-major, rows × columns), -1 for empty cells. */
  const std::vector<int>& getIndexImage() const { return index_image_; }
  /** \brief Cell (row * columns + column) of each input point, -1 when it has none (invalid,
   * outside the field of view or range limits, not in the indices, or displaced). */
  const std::vector<int>& getCellOfPoint() const { return cell_of_point_; }
  /** \brief Points that lost their cell to a nearer point. */
  std::size_t getDisplacedCount() const { return displaced_; }
  /** \brief Points placed in an adjacent free column because their own cell was taken. */
  std::size_t getShiftedCount() const { return shifted_; }
  /** \brief NaN/Inf points skipped. */
  std::size_t getInvalidCount() const { return invalid_; }
  /** \brief Points outside the beams, the azimuth field of view or the range limits. */
  std::size_t getOutOfViewCount() const { return out_of_view_; }
  /** \brief True when the last input was already organized and was passed through. */
  bool wasPassThrough() const { return pass_through_; }
  /** \brief Whether the last output's first and last columns are neighbours (its columns close a
   * full turn): the sensor model's field of view, or for organized input passed through, the
   * median azimuth step between its columns times its width (a forward-looking sensor's image
   * covers a part of the turn only). */
  bool isFullTurn() const { return full_turn_; }
  /** \brief Whether the columns of an organized image close a full turn (see isFullTurn()). */
  static bool columnsCloseFullTurn(const PointCloud& image);

 protected:
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::use_indices_;
  using pcl::PCLBase<PointT>::fake_indices_;
  using pcl::PCLBase<PointT>::initCompute;
  using pcl::PCLBase<PointT>::deinitCompute;

  /** \brief Precomputes the row and column lookups of `model_` for `columns` columns. */
  void prepareLookup(int columns);
  /** \brief Row of the beam line nearest to (w = 1/ρ, t = z/ρ) by bisection over the lines
   * half-way between neighbouring beams (no table; used where the table is ambiguous). */
  inline int rowBySearch(float w, float t) const;
  /** \brief Places the points `begin`..`end` of the loop over the input (or its indices). */
  void placeBlock(std::size_t begin, std::size_t end);
  void passThrough(PointCloud& output);

  SensorModel model_;
  bool has_model_ = false;
  bool estimate_model_ = true;
  int columns_ = 0;
  float max_range_ = 0.f;
  float min_range_ = 0.f;
  bool use_free_neighbour_ = true;

  std::vector<int> index_image_;
  std::vector<int> cell_of_point_;
  PointCloud image_;  ///< scratch output for organize(*input), swapped into place
  std::size_t displaced_ = 0, shifted_ = 0, invalid_ = 0, out_of_view_ = 0, placed_ = 0;
  bool pass_through_ = false;
  bool full_turn_ = true;

  // Lookups of the current model, rebuilt only when the model or the column count change (a
  // caller organizes one frame after the other with the same sensor).
  bool lookup_ready_ = false;
  // Row of a point: beam k is the line t = tan θ_k + h_k·w of (w = 1/ρ, t = z/ρ); the row is the
  // number of mid-lines (half-way between beams k and k+1: t = mid_a_k + mid_h_k·w) above t. A 2D
  // table over (g = t - mean offset·w, w) gives for each cell the top row r of the at most two
  // rows the cell holds; one comparison with mid-line r finishes the job (kTableAmbiguous: search).
  std::vector<float> mid_a_, mid_h_;
  std::vector<std::uint16_t> row_table_;
  float mean_offset_ = 0.f, table_g_min_ = 0.f, table_g_scale_ = 0.f, table_w_scale_ = 0.f;
  int table_g_bins_ = 0, table_w_bins_ = 0;
  bool ordered_mid_lines_ = false;  // mid-lines keep their order over the table (see the kernel)
  float upper_limit_ = 0.f, lower_limit_ = 0.f;  // half a spacing outside the outer beams, in t
  float upper_offset_ = 0.f, lower_offset_ = 0.f;
  float azimuth_max_ = 0.f, columns_per_radian_ = 0.f;
  int output_columns_ = 0;
  bool full_revolution_ = true;
  // Per-block scratch of the vectorized first pass (structure of arrays).
  std::vector<float> block_x_, block_y_, block_z_, block_w_, block_t_;
  std::vector<int> block_status_, block_table_, block_column_, block_row_;
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/range_image_organizer.hpp>
#endif
