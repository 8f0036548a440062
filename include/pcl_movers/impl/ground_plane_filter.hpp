/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/ground_plane_filter.h>

#include <pcl/common/eigen.h>

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
  setParameters(GroundParameters());
}

template <typename PointT>
void GroundPlaneFilter<PointT>::setParameters(const GroundParameters& p) {
  constexpr double kRadPerDeg = M_PI / 180.0;
  distance_threshold_ = static_cast<float>(p.distance);
  max_tilt_ = static_cast<float>(p.max_slope_deg * kRadPerDeg);
  sensor_height_ = static_cast<float>(p.sensor_height);
  num_sectors_ = p.sectors;
  local_slope_check_ = p.local_slope;
  max_local_slope_ = static_cast<float>(p.local_slope_deg * kRadPerDeg);
  range_noise_ = static_cast<float>(p.range_noise);
  local_slope_band_ = static_cast<float>(p.slope_band);
}

template <typename PointT>
GroundParameters GroundPlaneFilter<PointT>::getParameters() const {
  constexpr double kDegPerRad = 180.0 / M_PI;
  GroundParameters p;
  p.distance = distance_threshold_;
  p.max_slope_deg = max_tilt_ * kDegPerRad;
  p.sensor_height = sensor_height_;
  p.sectors = num_sectors_;
  p.local_slope = local_slope_check_;
  p.local_slope_deg = max_local_slope_ * kDegPerRad;
  p.range_noise = range_noise_;
  p.slope_band = local_slope_band_;
  return p;
}

template <typename PointT>
int GroundPlaneFilter<PointT>::ringOf(float r) const {
  // upper_bound - 1: the last edge <= r; edges start at 0 so the result is >= 0.
  const auto it = std::upper_bound(ring_edges_.begin(), ring_edges_.end(), r);
  return static_cast<int>(it - ring_edges_.begin()) - 1;
}

template <typename PointT>
float GroundPlaneFilter<PointT>::cellDepth(int ring) const {
  // The outermost ring is open-ended: count it as deep as the one inside it.
  const int rings = static_cast<int>(ring_edges_.size());
  if (ring + 1 < rings) return ring_edges_[ring + 1] - ring_edges_[ring];
  return ring > 0 ? ring_edges_[ring] - ring_edges_[ring - 1]
                  : std::numeric_limits<float>::infinity();
}

template <typename PointT>
bool GroundPlaneFilter<PointT>::fitPlane(const std::vector<int>& positions, const Plane& prior,
                                         float band, const Eigen::Vector2f& centre,
                                         std::uint32_t seed, Plane& fitted) {
  // RANSAC on an evenly strided subsample: the inlier ratio is high, so a few dozen points and
  // iterations find the plane; the refit below uses every inlier of the subsample. The subsample
  // is copied into three flat arrays so the inlier count of a hypothesis is one vectorizable loop
  // (pcl::RandomSampleConsensus with SampleConsensusModelPerpendicularPlane did the same work at
  // ~5x the cost: a shared model object, acos per hypothesis, OpenMP critical sections).
  const std::size_t stride =
      (positions.size() + static_cast<std::size_t>(max_samples_) - 1) / max_samples_;
  sample_x_.clear();
  sample_y_.clear();
  sample_z_.clear();
  for (std::size_t j = 0; j < positions.size(); j += stride) {
    const Eigen::Vector3f& p = cell_xyz_[positions[j]];
    sample_x_.push_back(p.x());
    sample_y_.push_back(p.y());
    sample_z_.push_back(p.z());
  }
  const int m = static_cast<int>(sample_x_.size());
  if (m < 3) return false;
  const float* sx = sample_x_.data();
  const float* sy = sample_y_.data();
  const float* sz = sample_z_.data();
  const float threshold = fit_threshold_;
  const float cos_tilt = std::cos(max_tilt_);
  auto countInliers = [&](const Eigen::Vector4f& c) {
    int count = 0;
    for (int j = 0; j < m; ++j)
      count += std::abs(c[0] * sx[j] + c[1] * sy[j] + c[2] * sz[j] + c[3]) < threshold;
    return count;
  };
  // A fixed seed per cell (not per frame): the same cell points always give the same plane,
  // whatever the other cells hold.
  std::uint32_t state = seed * 2654435761u + 0x9e3779b9u;
  auto draw = [&state, m]() {
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return static_cast<int>((static_cast<std::uint64_t>(state) * static_cast<std::uint32_t>(m)) >>
                            32);
  };
  // Adaptive stop as pcl::RandomSampleConsensus: enough hypotheses for probability 0.99 of one
  // outlier-free sample at the best inlier ratio seen so far, capped by getMaxIterations().
  const double log_miss = std::log(1.0 - 0.99);
  double needed = max_iterations_;
  Eigen::Vector4f best(0.f, 0.f, 1.f, 0.f);
  int best_count = 0;
  for (int it = 0; it < max_iterations_ && it < needed; ++it) {
    const int a = draw();
    int b = draw(), c = draw();
    if (b == a) b = (b + 1) % m;
    while (c == a || c == b) c = (c + 1) % m;
    const Eigen::Vector3f pa(sx[a], sy[a], sz[a]);
    Eigen::Vector3f normal = (Eigen::Vector3f(sx[b], sy[b], sz[b]) - pa)
                                 .cross(Eigen::Vector3f(sx[c], sy[c], sz[c]) - pa);
    const float norm = normal.norm();
    if (!(norm > 1e-6f)) continue;  // collinear sample
    normal /= norm;
    // The perpendicular-plane constraint: steeper than getMaxTilt() is no ground hypothesis.
    if (std::abs(normal.z()) < cos_tilt) continue;
    const Eigen::Vector4f model(normal.x(), normal.y(), normal.z(), -normal.dot(pa));
    const int count = countInliers(model);
    if (count > best_count) {
      best_count = count;
      best = model;
      const double w = static_cast<double>(count) / m;
      const double p_clean = std::max(1e-12, std::min(1.0 - 1e-12, 1.0 - w * w * w));
      needed = log_miss / std::log(p_clean);
    }
  }
  if (best_count < 6) return false;  // too few to refit
  // Least-squares refit on the inliers (the smallest-eigenvalue direction of their covariance).
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  const Eigen::Vector3f origin = input_->sensor_origin_.template head<3>();
  float r2_min = std::numeric_limits<float>::max(), r2_max = 0.f;
  for (int j = 0; j < m; ++j)
    if (std::abs(best[0] * sx[j] + best[1] * sy[j] + best[2] * sz[j] + best[3]) < threshold) {
      mean += Eigen::Vector3f(sx[j], sy[j], sz[j]);
      const float dx = sx[j] - origin.x(), dy = sy[j] - origin.y();
      const float r2 = dx * dx + dy * dy;
      r2_min = std::min(r2_min, r2);
      r2_max = std::max(r2_max, r2);
    }
  mean /= static_cast<float>(best_count);
  Eigen::Matrix3f covariance = Eigen::Matrix3f::Zero();
  for (int j = 0; j < m; ++j)
    if (std::abs(best[0] * sx[j] + best[1] * sy[j] + best[2] * sz[j] + best[3]) < threshold) {
      const Eigen::Vector3f q = Eigen::Vector3f(sx[j], sy[j], sz[j]) - mean;
      covariance.noalias() += q * q.transpose();
    }
  float eigen_value;
  Eigen::Vector3f normal;
  pcl::eigen33(covariance, eigen_value, normal);
  const float norm = normal.norm();
  if (!(norm > 0.f) || !normal.allFinite()) return false;
  normal /= norm;
  if (normal.z() < 0.f) normal = -normal;
  float d = -normal.dot(mean);
  // The least-squares refit is not bound by the tilt limit: check again.
  if (normal.z() < cos_tilt) return false;
  // Inliers on one scan line (a narrow radial extent) fix the height but not the slope along
  // the range direction: keep the prior's orientation, take only the height from the fit.
  if (std::sqrt(r2_max) - std::sqrt(r2_min) < 1.0f) {
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
float GroundPlaneFilter<PointT>::estimateSensorHeight(const Eigen::Vector3f& origin) {
  // Depths below the sensor of the points within kNearRange, in kBin steps: near the sensor the
  // ground holds most returns of any sensor that looks down (a spinning LiDAR's lower beams, a
  // tilted 2-D ladar), in one thin layer, while walls, cars and people spread over many layers.
  // kNearRange reaches a VLP-16's lowest beams mounted 2.5 m high (they meet the ground 9-17 m
  // out). The ground is the deepest dense 0.3 m layer (three bins, see below), its median depth
  // the height.
  constexpr float kNearRange = 15.f, kBin = 0.1f, kMaxDepth = 5.f;
  constexpr int kBins = static_cast<int>(kMaxDepth / kBin);
  depth_bins_.assign(kBins, 0);
  const int rings = static_cast<int>(ring_edges_.size());
  int last = 0;  // cells [0, last) are the rings within kNearRange
  for (int ring = 0; ring < rings && ring_edges_[ring] < kNearRange; ++ring)
    last = (ring + 1) * num_sectors_;
  const int end = cell_start_[last];
  // The bin of a return, -1 for none; checked as an int (depth / kBin rounds up to kBins just
  // below kMaxDepth), and computed the same way in both passes.
  auto binOf = [&](const Eigen::Vector3f& p) {
    const float depth = origin.z() - p.z();
    const float dx = p.x() - origin.x(), dy = p.y() - origin.y();
    const int bin = depth > 0.f && depth < kMaxDepth ? static_cast<int>(depth / kBin) : -1;
    return bin < kBins && dx * dx + dy * dy < kNearRange * kNearRange ? bin : -1;
  };
  for (int j = 0; j < end; ++j) {
    const int bin = binOf(cell_xyz_[j]);
    if (bin >= 0) ++depth_bins_[bin];
  }
  auto layer = [this](int b) { return depth_bins_[b - 1] + depth_bins_[b] + depth_bins_[b + 1]; };
  int best_count = 0;
  for (int b = 1; b + 1 < kBins; ++b) best_count = std::max(best_count, layer(b));
  // Too few returns to tell (a blind frame, a sensor that does not look down): the last
  // estimate, or KITTI's mounting height before the first.
  if (best_count < min_points_per_cell_) return used_sensor_height_;
  // Nothing lies under the ground: of the dense layers (at least an eighth of the densest) take
  // the deepest, at its peak. In a car park the roofs and bonnets within 15 m can outnumber the
  // ground four to one; what lies below the ground (multipath, a ditch) is sparse.
  int best = kBins - 2;
  while (best > 1 && 8 * layer(best) < best_count) --best;
  while (best > 1 && layer(best - 1) > layer(best)) --best;
  depths_.clear();
  for (int j = 0; j < end; ++j)
    if (std::abs(binOf(cell_xyz_[j]) - best) <= 1) depths_.push_back(origin.z() - cell_xyz_[j].z());
  auto middle = depths_.begin() + depths_.size() / 2;
  std::nth_element(depths_.begin(), middle, depths_.end());
  return *middle;
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
      !(max_local_slope_ >= 0.f) || !(range_noise_ >= 0.f) || !(local_slope_band_ >= 0.f) ||
      !(curved_cell_depth_ >= 0.f)) {
    PCL_ERROR(
        "[pcl_movers::%s::applyFilter] Invalid parameters (ring edges must start at 0 and "
        "increase; sectors, thresholds, samples and iterations must be positive; local-slope "
        "parameters and the curved-cell depth must be >= 0).\n",
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

  used_sensor_height_ = sensor_height_ > 0.f ? sensor_height_ : estimateSensorHeight(origin);
  Plane start;
  start.normal = Eigen::Vector3f::UnitZ();
  start.d = -(origin.z() - used_sensor_height_);
  std::vector<int>& positions = positions_;  // of the candidates in cell_xyz_

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
      // Written unconditionally, kept by advancing the count: no branch per point.
      positions.resize(count);
      std::size_t kept_near = 0;
      for (int j = cell_start[cell]; j < cell_start[cell + 1]; ++j) {
        positions[kept_near] = j;
        kept_near += std::abs(prior.height(cell_xyz_[j])) < band;
      }
      positions.resize(kept_near);
      if (static_cast<int>(positions.size()) < min_points_per_cell_) continue;
      const Eigen::Vector2f c2 = origin.head<2>() + centre_r * sector_dirs[s];
      Plane fitted, floating;
      bool ok = false;
      // A plane floating above real ground (the horizontal slice through a car's body, a bonnet,
      // a hedge top) leaves points clearly below it: drop it and everything above, fit again.
      // In a deep cell (getCurvedCellDepth()) the lower fit must also leave fewer of the cell's
      // candidates below it than the plane it replaces, or it is no lower and the earlier plane
      // is kept: there the points below a plane are often the lowest stretches of its two or
      // three scan lines on curved ground (rolling terrain, a crest, the vehicle pitching), and
      // a plane through them alone tilts or rises elsewhere (simulated open scene, a 68-82 m
      // cell: 132 of its 169 candidates were then left 0.5-1.3 m below the plane).
      const bool deep = cellDepth(ring) >= curved_cell_depth_;
      if (deep) candidates_.assign(positions.begin(), positions.end());
      auto belowCandidates = [&](const Plane& plane) {
        std::size_t below = 0;
        for (const auto j : candidates_)
          below += plane.height(cell_xyz_[j]) < -2.f * fit_threshold_;
        return below;
      };
      std::size_t floating_below = 0;
      for (int attempt = 0; attempt < 3; ++attempt) {
        if (static_cast<int>(positions.size()) < min_points_per_cell_) break;
        const auto seed = static_cast<std::uint32_t>(cell * 4 + attempt);
        if (!fitPlane(positions, prior, band, c2, seed, fitted)) break;
        const std::size_t all_below = deep ? belowCandidates(fitted) : 0;
        if (deep && attempt > 0 && all_below >= floating_below) {
          fitted = floating;
          ok = true;
          break;
        }
        std::size_t below = 0;
        for (const auto j : positions) below += fitted.height(cell_xyz_[j]) < -2.f * fit_threshold_;
        if (below < std::max<std::size_t>(min_points_per_cell_ / 2, positions.size() / 20)) {
          ok = true;
          break;
        }
        floating = fitted;
        floating_below = all_below;
        std::size_t kept = 0;
        for (std::size_t m = 0; m < positions.size(); ++m)
          if (fitted.height(cell_xyz_[positions[m]]) < -fit_threshold_)
            positions[kept++] = positions[m];
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
  const float tan_slope = std::tan(std::min(max_local_slope_, 1.5707f));
  const float tan2_slope = tan_slope * tan_slope;
  // Steep rise between a ground candidate and its column neighbours (see the class description).
  // Neighbour j is steep when it is near its plane (|h_j| <= band: not NaN, not an object on the
  // ground) and its rise, minus the noise, exceeds tan(slope) times the horizontal distance
  // (squared, both sides >= 0: no square root). Evaluated without branches: NaN heights make the
  // comparisons false, and the outcomes along a row are too irregular to predict.
  const float band = local_slope_band_;
  const float noise = range_noise_;
  auto steepTo = [&](int j, float h, float px, float py) {
    const float hj = height_[j];
    const float rise = std::abs(hj - h) - noise;
    const float dx = (*input_)[j].x - px, dy = (*input_)[j].y - py;
    return (std::abs(hj) <= band) & (rise > 0.f) & (rise * rise > tan2_slope * (dx * dx + dy * dy));
  };
  // Steep flags of the ground candidates; a flag counts only when a row neighbour (same beam,
  // next azimuth) is flagged too: vegetation and wall bases are rough over several columns, while
  // range noise on the road flags isolated points.
  // The candidates are the cells with |height| < threshold: height_ is NaN for every cell that is
  // not in indices_ or not finite, so one pass over the image finds them without reading
  // indices_ or cell_of.
  if (slope_check) {
    steep_.assign(input_->size(), 0);
    const int rows = static_cast<int>(input_->height);
    for (int row = 0; row < rows; ++row) {
      const bool up = row > 0, down = row + 1 < rows;
      for (int idx = row * width; idx < (row + 1) * width; ++idx) {
        const float h = height_[idx];
        if (!(std::abs(h) < distance_threshold_)) continue;
        const float px = (*input_)[idx].x, py = (*input_)[idx].y;
        bool s = false;
        if (up) s |= steepTo(idx - width, h, px, py);
        if (down) s |= steepTo(idx + width, h, px, py);
        steep_[idx] = s;
      }
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
