/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>
#include <pcl_movers/range_image_organizer.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace pcl_movers {

namespace detail {

/** \brief atan2 to within 2e-6 rad (a column of a 2200-column image is 2.9e-3 rad) at a third of
 * the cost of std::atan2, which was a third of the organizer's time. Odd minimax polynomial of
 * atan on [0, 1] plus octant folding. */
inline float fastAtan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float mx = std::max(ax, ay), mn = std::min(ax, ay);
  const float a = mx > 0.f ? mn / mx : 0.f;
  const float s = a * a;
  float r = (((((-0.01172120f * s + 0.05265332f) * s - 0.11643287f) * s + 0.19354346f) * s -
              0.33262347f) *
                 s +
             0.99997726f) *
            a;
  if (ay > ax) r = 1.57079637f - r;
  if (x < 0.f) r = 3.14159274f - r;
  return y < 0.f ? -r : r;
}

}  // namespace detail

template <typename PointT>
void RangeImageOrganizer<PointT>::setSensorModel(const SensorModel& model) {
  if (model.rows() == 0 || model.columns() <= 0)
    throw InputError("RangeImageOrganizer: sensor model '" + model.name() +
                     "' has no beams or no columns");
  model_ = model;
  has_model_ = true;
}

template <typename PointT>
void RangeImageOrganizer<PointT>::clearSensorModel() {
  model_ = SensorModel();
  has_model_ = false;
}

template <typename PointT>
void RangeImageOrganizer<PointT>::prepareLookup(int columns) {
  const int n = model_.rows();
  tan_elevation_.resize(n);
  offset_ = model_.verticalOffsets();
  mean_offset_ = 0.f;
  for (int k = 0; k < n; ++k) {
    tan_elevation_[k] = std::tan(model_.elevations()[k]);
    mean_offset_ += offset_[k] / float(n);
  }
  // Half a beam spacing beyond the outer beams still belongs to them (as SensorModel::rowOf);
  // a single beam accepts one degree either way.
  const float one_degree = float(M_PI / 180.0);
  const float upper_half = n > 1 ? 0.5f * (tan_elevation_[0] - tan_elevation_[1]) : one_degree;
  const float lower_half =
      n > 1 ? 0.5f * (tan_elevation_[n - 2] - tan_elevation_[n - 1]) : one_degree;
  upper_limit_ = tan_elevation_[0] + upper_half;
  lower_limit_ = tan_elevation_[n - 1] - lower_half;
  upper_offset_ = offset_[0];
  lower_offset_ = offset_[n - 1];
  // The table only has to land within a couple of rows of the answer; the walk in rowOf() does
  // the rest exactly. Cells much finer than the tightest beam spacing keep the walk to ~1 step.
  const float margin = 4.f * std::max(upper_half, lower_half) + 0.5f;
  table_min_ = lower_limit_ - margin;
  const float table_max = upper_limit_ + margin;
  const int size = 16384;
  table_scale_ = float(size) / (table_max - table_min_);
  row_table_.resize(size);
  int row = n - 1;
  for (int i = 0; i < size; ++i) {
    const float g = table_min_ + (float(i) + 0.5f) / table_scale_;
    while (row > 0 && std::abs(g - tan_elevation_[row - 1]) <= std::abs(g - tan_elevation_[row]))
      --row;
    row_table_[i] = row;
  }
  output_columns_ = columns;
  full_revolution_ = model_.isFullRevolution();
  azimuth_max_ = model_.azimuthMax();
  columns_per_radian_ = float(columns) / (model_.azimuthMax() - model_.azimuthMin());
}

template <typename PointT>
inline int RangeImageOrganizer<PointT>::rowOf(float inv_rho, float z) const {
  const float t = z * inv_rho;
  // Outside the outer beams' lines (each with its own offset) by more than half a spacing.
  if (t > upper_limit_ + upper_offset_ * inv_rho || t < lower_limit_ + lower_offset_ * inv_rho)
    return -1;
  const float g = t - mean_offset_ * inv_rho;
  int i = int((g - table_min_) * table_scale_);
  i = std::min(std::max(i, 0), int(row_table_.size()) - 1);
  int row = row_table_[i];
  // Each beam is the line t = tan θ_k + h_k / ρ; the lines keep their order, so the nearest one
  // is reached by walking downhill. (Walking only towards the point's side was measured slower:
  // that side is a coin flip for the branch predictor, while here both loops usually stop at once.)
  const int n = int(tan_elevation_.size());
  auto distance = [&](int k) { return std::abs(t - tan_elevation_[k] - offset_[k] * inv_rho); };
  float d = distance(row);
  while (row > 0) {
    const float up = distance(row - 1);
    if (!(up < d)) break;
    d = up;
    --row;
  }
  while (row < n - 1) {
    const float down = distance(row + 1);
    if (!(down < d)) break;
    d = down;
    ++row;
  }
  return row;
}

template <typename PointT>
void RangeImageOrganizer<PointT>::passThrough(PointCloud& output) {
  if (&output != input_.get()) output = *input_;
  const std::size_t size = input_->size();
  index_image_.assign(size, -1);
  cell_of_point_.assign(size, -1);
  std::vector<char> selected(size, fake_indices_ ? 1 : 0);
  if (!fake_indices_)
    for (const auto i : *indices_)
      if (i >= 0 && std::size_t(i) < size) selected[i] = 1;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < size; ++i) {
    const auto& p = (*input_)[i];
    const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    if (!finite) ++invalid_;
    if (finite && selected[i]) {
      index_image_[i] = int(i);
      cell_of_point_[i] = int(i);
    } else {
      // Not ours to keep: blank it so the cell reads as empty, like the unorganized path.
      output[i].x = output[i].y = output[i].z = nan;
    }
  }
  output.is_dense = false;
}

template <typename PointT>
void RangeImageOrganizer<PointT>::organize(PointCloud& output) {
  displaced_ = shifted_ = invalid_ = out_of_view_ = 0;
  pass_through_ = false;
  index_image_.clear();
  cell_of_point_.clear();
  if (!input_) throw InputError("RangeImageOrganizer: no input cloud set");
  if (input_->empty()) throw InputError("RangeImageOrganizer: the input cloud is empty");
  if (!initCompute()) throw InputError("RangeImageOrganizer: invalid input or indices");

  if (input_->height > 1) {
    pass_through_ = true;
    passThrough(output);
    deinitCompute();
    return;
  }

  if (!has_model_) {
    if (!estimate_model_) {
      deinitCompute();
      throw InputError("RangeImageOrganizer: no sensor model set and estimation is off");
    }
    try {
      model_ = SensorModel::estimate(*input_, 0, columns_);
    } catch (...) {
      deinitCompute();
      throw;
    }
  }
  const int rows = model_.rows();
  const int columns = columns_ > 0 ? columns_ : model_.columns();
  prepareLookup(columns);

  const std::size_t cells = std::size_t(rows) * std::size_t(columns);
  index_image_.assign(cells, -1);
  cell_of_point_.assign(input_->size(), -1);
  // Squared range of the point in each cell, for the nearer-return-wins rule (a member: reused).
  std::vector<float>& cell_range = cell_range_;
  cell_range.assign(cells, std::numeric_limits<float>::infinity());
  const float max_range2 =
      max_range_ > 0.f ? max_range_ * max_range_ : std::numeric_limits<float>::infinity();
  const float min_range2 = min_range_ > 0.f ? min_range_ * min_range_ : 0.f;
  const float columns_f = float(columns);

  // The image is written while the points are placed (reading the input in order, scattering into
  // the image: measured ~5 % faster than gathering from the input afterwards). It goes to a member
  // cloud reused from call to call and is swapped into `output` only on
  // success, so `output` is untouched when organize() throws and organize(*input) works too.
  PointT empty;
  empty.x = empty.y = empty.z = std::numeric_limits<float>::quiet_NaN();
  PointCloud& image = image_;
  image.points.assign(cells, empty);

  auto tryPlace = [&](int cell, int index, float range2) -> bool {
    if (index_image_[cell] < 0) {
      index_image_[cell] = index;
      cell_range[cell] = range2;
      cell_of_point_[index] = cell;
      image.points[cell] = (*input_)[index];
      return true;
    }
    return false;
  };

  for (const auto index : *indices_) {
    const PointT& p = (*input_)[index];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      ++invalid_;
      continue;
    }
    const float rho2 = p.x * p.x + p.y * p.y;
    const float range2 = rho2 + p.z * p.z;
    if (range2 > max_range2 || range2 < min_range2 || !(rho2 > 0.f)) {
      ++out_of_view_;
      continue;
    }
    const float inv_rho = 1.f / std::sqrt(rho2);
    const int row = rowOf(inv_rho, p.z);
    if (row < 0) {
      ++out_of_view_;
      continue;
    }
    float f = (azimuth_max_ - detail::fastAtan2(p.y, p.x)) * columns_per_radian_;
    if (full_revolution_) {
      if (f < 0.f) f += columns_f;
      if (f >= columns_f) f -= columns_f;
    } else if (f < 0.f || f >= columns_f) {
      ++out_of_view_;
      continue;
    }
    const int column = std::min(int(f), columns - 1);
    const int base = row * columns;
    if (tryPlace(base + column, index, range2)) continue;
    if (use_free_neighbour_) {
      // The side the azimuth leans to first: the nearer neighbour centre.
      const int step = (f - float(column)) >= 0.5f ? 1 : -1;
      bool placed = false;
      for (const int side : {step, -step}) {
        int c = column + side;
        if (full_revolution_) {
          if (c < 0) c += columns;
          if (c >= columns) c -= columns;
        } else if (c < 0 || c >= columns) {
          continue;
        }
        if (tryPlace(base + c, index, range2)) {
          placed = true;
          break;
        }
      }
      if (placed) {
        ++shifted_;
        continue;
      }
    }
    // The cell is taken: the nearer return wins, as in a single-return range image.
    const int cell = base + column;
    ++displaced_;
    if (range2 < cell_range[cell]) {
      cell_of_point_[index_image_[cell]] = -1;
      index_image_[cell] = index;
      cell_range[cell] = range2;
      cell_of_point_[index] = cell;
      image.points[cell] = p;
    }
  }

  const std::size_t placed =
      cells - std::size_t(std::count(index_image_.begin(), index_image_.end(), -1));
  if (placed == 0) {
    deinitCompute();
    if (invalid_ == indices_->size())
      throw InputError("RangeImageOrganizer: the input has no finite point");
    throw InputError("RangeImageOrganizer: no input point lies in the field of view of sensor '" +
                     model_.name() + "'");
  }

  image.header = input_->header;
  image.sensor_origin_ = input_->sensor_origin_;
  image.sensor_orientation_ = input_->sensor_orientation_;
  image.width = std::uint32_t(columns);
  image.height = std::uint32_t(rows);
  image.is_dense = false;
  output.swap(image);
  deinitCompute();
}

}  // namespace pcl_movers
