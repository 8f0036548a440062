/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/ground_plane_filter.h>

#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_perpendicular_plane.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pcl_movers {
namespace detail {

/** \brief A monotone stand-in for atan2 in [0, 4) ("diamond angle"): sectors are cut on it to
 * avoid one atan2 per point; equal pseudo-angle sectors differ from equal-angle ones by at most
 * a factor ~1.4 in width, which is harmless for ground cells. */
inline float diamondAngle(float dx, float dy) {
  if (dy >= 0.f) return dx >= 0.f ? dy / (dx + dy) : 1.f - dx / (-dx + dy);
  return dx < 0.f ? 2.f - dy / (-dx - dy) : 3.f + dx / (dx - dy);
}

/** \brief Unit direction (x, y) of diamond angle t in [0, 4). */
inline Eigen::Vector2f diamondDirection(float t) {
  Eigen::Vector2f v;
  if (t < 1.f)
    v = {1.f - t, t};
  else if (t < 2.f)
    v = {1.f - t, 2.f - t};
  else if (t < 3.f)
    v = {t - 3.f, 2.f - t};
  else
    v = {t - 3.f, t - 4.f};
  return v.normalized();
}

}  // namespace detail

template <typename PointT>
GroundPlaneFilter<PointT>::GroundPlaneFilter(bool extract_removed_indices)
    : pcl::FilterIndices<PointT>(extract_removed_indices) {
  filter_name_ = "GroundPlaneFilter";
}

template <typename PointT>
int GroundPlaneFilter<PointT>::ringOf(float r) const {
  // upper_bound - 1: the last edge <= r; edges start at 0 so the result is >= 0.
  const auto it = std::upper_bound(ring_edges_.begin(), ring_edges_.end(), r);
  return static_cast<int>(it - ring_edges_.begin()) - 1;
}

template <typename PointT>
bool GroundPlaneFilter<PointT>::fitPlane(const pcl::Indices& candidates, const Plane& prior,
                                         float band, const Eigen::Vector2f& centre,
                                         SacModelPtr& model,
                                         pcl::RandomSampleConsensus<PointT>& ransac,
                                         Plane& fitted) {
  // RANSAC on an evenly strided subsample: the inlier ratio is high, so a few dozen points and
  // iterations find the plane; the refit below uses every inlier of the subsample.
  const std::size_t stride =
      (candidates.size() + static_cast<std::size_t>(max_samples_) - 1) / max_samples_;
  if (!sample_) sample_.reset(new pcl::Indices);
  sample_->clear();
  for (std::size_t j = 0; j < candidates.size(); j += stride) sample_->push_back(candidates[j]);
  model->setIndices(sample_);
  if (!ransac.computeModel()) return false;
  ransac.getInliers(inliers_);
  Eigen::VectorXf coefficients;
  ransac.getModelCoefficients(coefficients);
  const pcl::Indices& inliers = inliers_;
  if (inliers.size() < 6) return false;  // too few to refit (PCL needs more than 3)
  Eigen::VectorXf refined;
  model->optimizeModelCoefficients(inliers, coefficients, refined);
  Eigen::Vector3f normal = refined.head<3>();
  const float norm = normal.norm();
  if (!(norm > 0.f) || !std::isfinite(refined[3])) return false;
  float d = refined[3] / norm;
  normal /= norm;
  if (normal.z() < 0.f) {
    normal = -normal;
    d = -d;
  }
  // The least-squares refit is not bound by the tilt limit: check again.
  if (normal.z() < std::cos(max_tilt_)) return false;
  // Inliers on one scan line (a narrow radial extent) fix the height but not the slope along
  // the range direction: keep the prior's orientation, take only the height from the fit.
  const Eigen::Vector3f origin = input_->sensor_origin_.template head<3>();
  float r_min = std::numeric_limits<float>::max(), r_max = 0.f;
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  for (const auto i : inliers) {
    const Eigen::Vector3f p = (*input_)[i].getVector3fMap();
    const float r = (p - origin).template head<2>().norm();
    r_min = std::min(r_min, r);
    r_max = std::max(r_max, r);
    mean += p;
  }
  mean /= static_cast<float>(inliers.size());
  if (r_max - r_min < 1.0f) {
    normal = prior.normal;
    d = -normal.dot(mean);
  }
  fitted.normal = normal;
  fitted.d = d;
  // Continuity with the prior at the cell centre: a jump larger than a kerb or a slope change
  // means the fit locked onto something else (a car bonnet, a low wall).
  auto zAt = [&centre](const Plane& pl) {
    return -(pl.d + pl.normal.x() * centre.x() + pl.normal.y() * centre.y()) / pl.normal.z();
  };
  return std::abs(zAt(fitted) - zAt(prior)) <= band;
}

template <typename PointT>
void GroundPlaneFilter<PointT>::applyFilter(pcl::Indices& indices) {
  indices.clear();
  removed_indices_->clear();
  cell_planes_.clear();
  cell_fitted_.clear();

  bool edges_ok = !ring_edges_.empty() && ring_edges_.front() == 0.f;
  for (std::size_t i = 1; i < ring_edges_.size(); ++i)
    edges_ok = edges_ok && ring_edges_[i] > ring_edges_[i - 1];
  if (!edges_ok || num_sectors_ < 1 || !(distance_threshold_ > 0.f) || !(fit_threshold_ > 0.f) ||
      !(max_tilt_ >= 0.f) || max_samples_ < 3 || max_iterations_ < 1 ||
      !(max_local_slope_ >= 0.f) || !(range_noise_ >= 0.f) || !(local_slope_band_ >= 0.f)) {
    PCL_ERROR(
        "[pcl_movers::%s::applyFilter] Invalid parameters (ring edges must start at 0 and "
        "increase; sectors, thresholds, samples and iterations must be positive; local-slope "
        "parameters must be >= 0).\n",
        filter_name_.c_str());
    // Nothing was classified: report every point as removed so callers do not mistake an
    // error for "no ground".
    if (extract_removed_indices_) *removed_indices_ = *indices_;
    return;
  }

  const int rings = static_cast<int>(ring_edges_.size());
  const int sectors = num_sectors_;
  const int num_cells = rings * sectors;
  const Eigen::Vector3f origin = input_->sensor_origin_.template head<3>();
  const std::size_t n = indices_->size();

  // Pass 1: cell of every point (-1 = not finite), counting sort into cells.
  // Ring lookup by quarter metres instead of a binary search per point; edges that fall inside
  // a bin are resolved exactly.
  constexpr float kBinsPerMetre = 4.f;
  const int bins = static_cast<int>(ring_edges_.back() * kBinsPerMetre) + 1;
  ring_lut_.resize(bins);
  for (int b = 0; b < bins; ++b) ring_lut_[b] = ringOf(static_cast<float>(b) / kBinsPerMetre);
  auto ringFast = [&](float r) {
    // Compare in float before the cast: huge (finite) coordinates overflow r to inf, and casting
    // inf to int is undefined.
    if (!(r * kBinsPerMetre < static_cast<float>(bins))) return rings - 1;
    const int b = static_cast<int>(r * kBinsPerMetre);
    int ring = ring_lut_[b];
    while (ring + 1 < rings && r >= ring_edges_[ring + 1]) ++ring;
    return ring;
  };
  std::vector<int>& cell_of = cell_of_;
  cell_of.resize(n);
  std::vector<int>& cell_start = cell_start_;
  cell_start.assign(num_cells + 1, 0);
  const float sector_scale = static_cast<float>(sectors) / 4.f;
  for (std::size_t k = 0; k < n; ++k) {
    const PointT& p = (*input_)[(*indices_)[k]];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      cell_of[k] = -1;
      continue;
    }
    const float dx = p.x - origin.x(), dy = p.y - origin.y();
    const float r = std::sqrt(dx * dx + dy * dy);
    const int ring = ringFast(r);
    // r = inf (overflow on huge coordinates) would make the diamond angle NaN: sector 0 then.
    const int sector =
        r > 0.f && std::isfinite(r)
            ? std::min(static_cast<int>(detail::diamondAngle(dx, dy) * sector_scale), sectors - 1)
            : 0;
    const int cell = ring * sectors + sector;
    cell_of[k] = cell;
    ++cell_start[cell + 1];
  }
  for (int c = 0; c < num_cells; ++c) cell_start[c + 1] += cell_start[c];
  std::vector<int>& cell_points = cell_points_;
  cell_points.resize(cell_start[num_cells]);
  // A cell-ordered copy of the coordinates: the per-cell loops below then read memory
  // sequentially instead of jumping around the cloud (that was the filter's main cost).
  cell_xyz_.resize(cell_points.size());
  {
    std::vector<int>& fill = cell_fill_;
    fill.assign(cell_start.begin(), cell_start.end() - 1);
    for (std::size_t k = 0; k < n; ++k)
      if (cell_of[k] >= 0) {
        const int j = fill[cell_of[k]]++;
        cell_points[j] = (*indices_)[k];
        cell_xyz_[j] = (*input_)[(*indices_)[k]].getVector3fMap();
      }
  }

  // Pass 2: planes, ring by ring from the sensor outwards, each cell seeded by its inner neighbour.
  cell_planes_.assign(num_cells, Plane());
  cell_fitted_.assign(num_cells, 0);
  std::vector<Eigen::Vector2f> sector_dirs(sectors);
  for (int s = 0; s < sectors; ++s)
    sector_dirs[s] = detail::diamondDirection((static_cast<float>(s) + 0.5f) / sector_scale);
  auto ringCentre = [&](int ring) {
    if (ring + 1 < rings) return 0.5f * (ring_edges_[ring] + ring_edges_[ring + 1]);
    return ring_edges_[ring] +
           0.5f * (ring_edges_[ring] - (ring > 0 ? ring_edges_[ring - 1] : 0.f));
  };

  // Built on an empty index list: the cloud constructor would fill (and copy) an index per point
  // of the frame, only for fitPlane to replace them with the cell's subsample. A fresh model per
  // call keeps the fixed seed, so every frame's RANSAC draws are reproducible.
  SacModelPtr model(new SacModel(input_, pcl::Indices(), /*random=*/false));
  model->setAxis(Eigen::Vector3f::UnitZ());
  model->setEpsAngle(max_tilt_);
  pcl::RandomSampleConsensus<PointT> ransac(model, fit_threshold_);
  ransac.setMaxIterations(max_iterations_);
  ransac.setProbability(0.99);

  Plane start;
  start.normal = Eigen::Vector3f::UnitZ();
  start.d = -(origin.z() - sensor_height_);
  pcl::Indices candidates;
  std::vector<int> positions;  // of the candidates in cell_xyz_

  for (int ring = 0; ring < rings; ++ring) {
    const float centre_r = ringCentre(ring);
    const float prior_r = ring > 0 ? ringCentre(ring - 1) : 0.f;
    const float band = max_step_ + max_slope_change_ * (centre_r - prior_r);
    for (int s = 0; s < sectors; ++s) {
      const int cell = ring * sectors + s;
      const Plane& prior = ring > 0 ? cell_planes_[cell - sectors] : start;
      cell_planes_[cell] = prior;
      const int count = cell_start[cell + 1] - cell_start[cell];
      if (count < min_points_per_cell_) continue;

      // Only points near the prior can be this cell's ground: keeps roofs and walls out.
      candidates.clear();
      positions.clear();
      for (int j = cell_start[cell]; j < cell_start[cell + 1]; ++j)
        if (std::abs(prior.height(cell_xyz_[j])) < band) {
          candidates.push_back(cell_points[j]);
          positions.push_back(j);
        }
      if (static_cast<int>(candidates.size()) < min_points_per_cell_) continue;
      const Eigen::Vector2f c2 = origin.head<2>() + centre_r * sector_dirs[s];
      Plane fitted;
      bool ok = false;
      // A plane floating above real ground (the horizontal slice through a car's body, a bonnet,
      // a hedge top) leaves points clearly below it: drop it and everything above, fit again.
      for (int attempt = 0; attempt < 3; ++attempt) {
        if (static_cast<int>(candidates.size()) < min_points_per_cell_) break;
        if (!fitPlane(candidates, prior, band, c2, model, ransac, fitted)) break;
        std::size_t below = 0;
        for (const auto j : positions) below += fitted.height(cell_xyz_[j]) < -2.f * fit_threshold_;
        if (below < std::max<std::size_t>(min_points_per_cell_ / 2, candidates.size() / 20)) {
          ok = true;
          break;
        }
        std::size_t kept = 0;
        for (std::size_t m = 0; m < positions.size(); ++m)
          if (fitted.height(cell_xyz_[positions[m]]) < -fit_threshold_) {
            candidates[kept] = candidates[m];
            positions[kept++] = positions[m];
          }
        candidates.resize(kept);
        positions.resize(kept);
      }
      if (!ok) continue;
      cell_planes_[cell] = fitted;
      cell_fitted_[cell] = 1;
    }
  }

  // Pass 3: height of every point above its cell's plane, then classify in input order so the
  // output keeps the input's point order.
  const bool organized = input_->height > 1 &&
                         static_cast<std::size_t>(input_->width) * input_->height == input_->size();
  const bool slope_check = local_slope_check_ && organized;
  // In cell order: one plane per run of points and the coordinates read sequentially.
  height_.assign(input_->size(), std::numeric_limits<float>::quiet_NaN());
  for (int c = 0; c < num_cells; ++c) {
    const Plane& plane = cell_planes_[c];
    for (int j = cell_start[c]; j < cell_start[c + 1]; ++j)
      height_[cell_points[j]] = plane.height(cell_xyz_[j]);
  }
  const int width = static_cast<int>(input_->width);
  const int image_size = static_cast<int>(input_->size());
  const float tan_slope = std::tan(std::min(max_local_slope_, 1.5707f));
  const float tan2_slope = tan_slope * tan_slope;
  // Steep rise between a ground candidate and its column neighbours (see the class description).
  auto steep = [&](int idx) {
    const float h = height_[idx];
    const Eigen::Vector3f p = (*input_)[idx].getVector3fMap();
    for (const int dr : {-1, 1}) {
      // The row above / below exists iff its index stays inside the image (width * rows
      // points): no integer division per candidate to find the row.
      const int j = idx + dr * width;
      if (j < 0 || j >= image_size) continue;
      const float hj = height_[j];
      if (!(std::abs(hj) <= local_slope_band_)) continue;  // NaN, or an object on the ground
      const float rise = std::abs(hj - h) - range_noise_;
      if (rise <= 0.f) continue;
      const Eigen::Vector3f q = (*input_)[j].getVector3fMap();
      // rise > tan(slope) * horizontal distance, squared (both sides >= 0): no square root.
      if (rise * rise > tan2_slope * (q - p).template head<2>().squaredNorm()) return true;
    }
    return false;
  };
  // Steep flags of the ground candidates; a flag counts only when a row neighbour (same beam,
  // next azimuth) is flagged too: vegetation and wall bases are rough over several columns, while
  // range noise on the road flags isolated points.
  if (slope_check) {
    steep_.assign(input_->size(), 0);
    for (std::size_t k = 0; k < n; ++k) {
      const int idx = (*indices_)[k];
      if (cell_of[k] >= 0 && std::abs(height_[idx]) < distance_threshold_) steep_[idx] = steep(idx);
    }
  }
  auto rejected = [&](int idx) {
    if (!steep_[idx]) return false;
    const int col = idx % width;
    const int left = col > 0 ? idx - 1 : idx + width - 1;
    const int right = col + 1 < width ? idx + 1 : idx - width + 1;
    return steep_[left] || steep_[right];
  };
  indices.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const int idx = (*indices_)[k];
    if (cell_of[k] < 0) {
      if (extract_removed_indices_) removed_indices_->push_back(idx);
      continue;
    }
    const bool ground =
        std::abs(height_[idx]) < distance_threshold_ && !(slope_check && rejected(idx));
    if (ground == negative_)
      indices.push_back(idx);
    else if (extract_removed_indices_)
      removed_indices_->push_back(idx);
  }
}

}  // namespace pcl_movers

#define PCL_MOVERS_INSTANTIATE_GroundPlaneFilter(T) template class pcl_movers::GroundPlaneFilter<T>;
