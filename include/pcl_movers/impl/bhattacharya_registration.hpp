/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/bhattacharya_registration.h>

#include <pcl/common/transforms.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace pcl_movers {

namespace detail {

/** \brief Refines a peak of a sampled function by a quadratic fit on the 3^k neighbourhood
 * (k = active dimensions, those where the peak is not on the border). `sample(offsets)` returns
 * the value at integer offsets (each in {-1,0,1} for active dims, 0 otherwise). Returns the
 * sub-sample offset per dimension (|offset| ≤ 1) and the fitted peak value. Falls back to
 * independent 1D parabolas when the full fit is not a proper maximum. Defined in
 * src/bhattacharya_registration.cpp. */
void refinePeak(int dims, const bool* active, const std::function<float(const int*)>& sample,
                float* offsets, float* value);

}  // namespace detail

template <typename PointSource, typename PointTarget, typename Scalar>
BhattacharyaRegistration<PointSource, PointTarget, Scalar>::BhattacharyaRegistration() {
  reg_name_ = "BhattacharyaRegistration";
  // No kd-tree is ever needed: stop pcl::Registration::initCompute() from building one.
  this->force_no_recompute_ = true;
  this->force_no_recompute_reciprocal_ = true;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::setInputSource(
    const PointCloudSourceConstPtr& cloud) {
  this->source_cloud_updated_ = true;
  pcl::PCLBase<PointSource>::setInputCloud(cloud);
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::setInputTarget(
    const PointCloudTargetConstPtr& cloud) {
  target_ = cloud;
  this->target_cloud_updated_ = true;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::setTargetDensity(
    const SurfaceDensity::ConstPtr& density) {
  target_density_ = density;
  if (density && !target_) {
    auto placeholder = pcl::make_shared<PointCloudTarget>();
    PointTarget p;
    p.x = density->getCentre().x();
    p.y = density->getCentre().y();
    p.z = density->getCentre().z();
    placeholder->push_back(p);
    target_ = placeholder;
  }
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::align(PointCloudSource& output,
                                                                       const Matrix4& guess) {
  converged_ = false;
  similarity_ = 0.f;
  if (!target_) {
    PCL_ERROR("[pcl_movers::%s::align] No input target dataset was given!\n", reg_name_.c_str());
    return;
  }
  if (!pcl::PCLBase<PointSource>::initCompute()) return;
  output.resize(indices_->size());
  output.header = input_->header;
  if (indices_->size() != input_->size()) {
    output.width = static_cast<std::uint32_t>(indices_->size());
    output.height = 1;
  } else {
    output.width = input_->width;
    output.height = input_->height;
  }
  output.is_dense = input_->is_dense;
  output.sensor_origin_ = input_->sensor_origin_;
  output.sensor_orientation_ = input_->sensor_orientation_;
  for (std::size_t i = 0; i < indices_->size(); ++i) output[i] = (*input_)[(*indices_)[i]];
  final_transformation_ = transformation_ = previous_transformation_ = Matrix4::Identity();
  computeTransformation(output, guess);
  this->deinitCompute();
}

template <typename PointSource, typename PointTarget, typename Scalar>
bool BhattacharyaRegistration<PointSource, PointTarget, Scalar>::buildTargetDensity(
    SurfaceDensity& target) const {
  if (target_density_) {
    target = *target_density_;
    return !target.empty();
  }
  if (!target_) return false;
  const Eigen::Vector3f origin =
      use_sensor_origin_ ? sensor_origin_ : target_->sensor_origin_.template head<3>();
  // Grid centred on the middle of the target's bounding box (not its centroid, which leans
  // towards the sensor because only the near faces are sampled): the object fits best that way.
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f hi = -lo;
  std::size_t n = 0;
  for (const auto& p : target_->points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const Eigen::Vector3f v(p.x, p.y, p.z);
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
    ++n;
  }
  if (n < 2) return false;
  const Eigen::Vector3f centroid = 0.5f * (lo + hi);
  target.setGridSize(nx_, ny_, nz_);
  target.setResolution(resolution_);
  target.setResolutionZ(grid_height_ / static_cast<float>(nz_));
  target.setSigmaPerMetre(sigma_per_metre_);
  target.setMinSigma(min_sigma_);
  target.compute(*target_, origin, centroid);
  return !target.empty();
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::computeTransformation(
    PointCloudSource& output, const Matrix4& guess) {
  converged_ = false;
  similarity_ = 0.f;
  surface_ = SimilaritySurface();
  source_density_.reset();
  const Eigen::Matrix4f guess_f = guess.template cast<float>();
  final_transformation_ = transformation_ = guess;

  auto finish = [&]() {
    if (output.size() > 0) pcl::transformPointCloud(output, output, final_transformation_);
  };
  if (!(resolution_ > 0.f) || !(search_radius_ > 0.f) || nx_ < 1 || ny_ < 1 || nz_ < 1 ||
      !(grid_height_ > 0.f) || yaw_samples_ < 1) {
    PCL_ERROR("[pcl_movers::%s] invalid parameters (resolution, radius, grid or yaw samples)\n",
              reg_name_.c_str());
    finish();
    return;
  }

  // ---- target density (the "model")
  SurfaceDensity target;
  if (!buildTargetDensity(target)) {
    finish();
    return;
  }
  const int nx = target.getNx(), ny = target.getNy(), nz = target.getNz();
  const float res = target.getResolution(), res_z = target.getResolutionZ();

  // ---- source points after the guess; σ from the untransformed ranges
  const Eigen::Vector3f src_origin =
      use_sensor_origin_ ? sensor_origin_ : input_->sensor_origin_.template head<3>();
  std::vector<Eigen::Vector3f> points;
  std::vector<float> sigmas;
  points.reserve(indices_->size());
  sigmas.reserve(indices_->size());
  const Eigen::Matrix3f guess_r = guess_f.template topLeftCorner<3, 3>();
  const Eigen::Vector3f guess_t = guess_f.template topRightCorner<3, 1>();
  for (const auto idx : *indices_) {
    const auto& p = (*input_)[idx];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const Eigen::Vector3f v(p.x, p.y, p.z);
    points.push_back(guess_r * v + guess_t);
    sigmas.push_back(std::max(min_sigma_, sigma_per_metre_ * (v - src_origin).norm()));
  }
  if (points.size() < 2) {
    finish();
    return;
  }
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<float>(points.size());

  // ---- search window: translations of ±nr cells (±nrz in z) around the guess
  const int nr = std::max(1, static_cast<int>(std::ceil(search_radius_ / res - 1e-4f)));
  const int nrz =
      search_z_ ? std::max(1, static_cast<int>(std::ceil(search_radius_z_ / res_z - 1e-4f))) : 0;
  const int wx = 2 * nr + 1, wz = 2 * nrz + 1;
  const int layers = yaw_samples_ % 2 == 1 ? yaw_samples_ : yaw_samples_ + 1;
  // The source density lives on the target's lattice padded by the window, so every shifted
  // source cell that overlaps the target grid is available.
  SurfaceDensity padded(nx + 2 * nr, ny + 2 * nr, nz + 2 * nrz, res, res_z);
  const int pnx = nx + 2 * nr, pny = ny + 2 * nr;

  // Non-zero target cells: the correlation only needs those (objects are surfaces, so most of
  // the grid is empty).
  const std::vector<float>& st = target.sqrtValues();
  std::vector<int> nz_cells;
  nz_cells.reserve(st.size());
  for (int i = 0; i < static_cast<int>(st.size()); ++i)
    if (st[i] > 1e-7f) nz_cells.push_back(i);

  // scores[((l * wz + ez) * wx + ey) * wx + ex], e = nr - d (d = translation in cells);
  // -1 marks a translation not evaluated.
  std::vector<float> scores(static_cast<std::size_t>(layers) * wz * wx * wx, -1.f);
  std::vector<std::vector<float>> layer_sqrt(static_cast<std::size_t>(layers));
  std::vector<Eigen::Vector3f> turned(points.size());
  auto buildLayer = [&](int l) {
    const float yaw = (l - (layers - 1) / 2) * yaw_step_;
    const Eigen::Matrix3f rz = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    for (std::size_t i = 0; i < points.size(); ++i)
      turned[i] = rz * (points[i] - centroid) + centroid;
    padded.computeFromPoints(turned, sigmas, target.getCentre());
    layer_sqrt[static_cast<std::size_t>(l)] = padded.sqrtValues();
  };
  // B(d) = Σ_i sqrtT[i] · sqrtP[i + nr - d] over a block of translations (all z shifts); with
  // e = nr - d the inner loop runs forward over a contiguous row of the padded grid. Direct
  // summation over the non-zero target cells only.
  std::vector<float> block;
  auto correlate = [&](int l, int ex0, int ex1, int ey0, int ey1) {
    ex0 = std::max(ex0, 0);
    ey0 = std::max(ey0, 0);
    ex1 = std::min(ex1, wx - 1);
    ey1 = std::min(ey1, wx - 1);
    if (ex1 < ex0 || ey1 < ey0) return;
    const int bw = ex1 - ex0 + 1, bh = ey1 - ey0 + 1;
    block.assign(static_cast<std::size_t>(wz) * bh * bw, 0.f);
    const std::vector<float>& sp = layer_sqrt[static_cast<std::size_t>(l)];
    for (const int cell : nz_cells) {
      const int ix = cell % nx;
      const int iy = (cell / nx) % ny;
      const int iz = cell / (nx * ny);
      const float v = st[static_cast<std::size_t>(cell)];
      for (int ez = 0; ez < wz; ++ez) {
        const int pz = iz + ez;
        for (int ey = ey0; ey <= ey1; ++ey) {
          const float* prow = &sp[(static_cast<std::size_t>(pz) * pny + (iy + ey)) * pnx +
                                  static_cast<std::size_t>(ix + ex0)];
          float* orow = &block[(static_cast<std::size_t>(ez) * bh + (ey - ey0)) * bw];
          for (int k = 0; k < bw; ++k) orow[k] += v * prow[k];
        }
      }
    }
    for (int ez = 0; ez < wz; ++ez)
      for (int ey = ey0; ey <= ey1; ++ey)
        for (int ex = ex0; ex <= ex1; ++ex)
          scores[((static_cast<std::size_t>(l) * wz + ez) * wx + ey) * wx + ex] =
              block[(static_cast<std::size_t>(ez) * bh + (ey - ey0)) * bw + (ex - ex0)];
  };
  auto at = [&](int l, int ez, int ey, int ex) {
    return scores[((static_cast<std::size_t>(l) * wz + ez) * wx + ey) * wx + ex];
  };
  int bl = 0, bez = 0, bey = 0, bex = 0;
  float best = -1.f;
  auto findBest = [&]() {
    best = -1.f;
    for (int l = 0; l < layers; ++l)
      for (int ez = 0; ez < wz; ++ez)
        for (int ey = 0; ey < wx; ++ey)
          for (int ex = 0; ex < wx; ++ex)
            if (at(l, ez, ey, ex) > best) {
              best = at(l, ez, ey, ex);
              bl = l;
              bez = ez;
              bey = ey;
              bex = ex;
            }
  };

  // The whole window at the guess's yaw. The other yaw layers turn the source about its own
  // centroid, which moves the peak little, so they are evaluated in a ±kLocal-cell block around
  // the middle layer's peak (unless setFullYawWindow()), then grown by hill climbing until the
  // best sample's neighbourhood is fully known. This makes yaw layers cost a fraction of a full
  // correlation each.
  const int mid = (layers - 1) / 2;
  for (int l = 0; l < layers; ++l) buildLayer(l);
  correlate(mid, 0, wx - 1, 0, wx - 1);
  findBest();
  constexpr int kLocal = 4;
  for (int l = 0; l < layers; ++l) {
    if (l == mid) continue;
    if (full_yaw_window_)
      correlate(l, 0, wx - 1, 0, wx - 1);
    else
      correlate(l, bex - kLocal, bex + kLocal, bey - kLocal, bey + kLocal);
  }
  findBest();
  for (int iter = 0; iter < 4 * wx; ++iter) {
    bool grew = false;
    for (int l = std::max(0, bl - 1); l <= std::min(layers - 1, bl + 1); ++l)
      for (int ey = std::max(0, bey - 1); ey <= std::min(wx - 1, bey + 1); ++ey)
        for (int ex = std::max(0, bex - 1); ex <= std::min(wx - 1, bex + 1); ++ex)
          if (at(l, 0, ey, ex) < 0.f) {
            correlate(l, ex - 2, ex + 2, ey - 2, ey + 2);
            grew = true;
          }
    if (!grew) break;
    findBest();
  }

  // Similarity surface for callers (max over z shifts), indexed by translation d = e - nr... in
  // increasing d, i.e. ix = nr + d = 2nr - e.
  surface_.nx = wx;
  surface_.ny = wx;
  surface_.resolution = res;
  surface_.yaws.resize(static_cast<std::size_t>(layers));
  surface_.values.assign(static_cast<std::size_t>(layers) * wx * wx, 0.f);
  for (int l = 0; l < layers; ++l) {
    surface_.yaws[static_cast<std::size_t>(l)] = (l - (layers - 1) / 2) * yaw_step_;
    for (int ey = 0; ey < wx; ++ey)
      for (int ex = 0; ex < wx; ++ex) {
        float m = 0.f;
        for (int ez = 0; ez < wz; ++ez) m = std::max(m, at(l, ez, ey, ex));
        surface_.values[(static_cast<std::size_t>(l) * wx + (wx - 1 - ey)) * wx + (wx - 1 - ex)] =
            std::min(std::max(m, 0.f), 1.f);
      }
  }

  const bool on_edge = bex == 0 || bex == wx - 1 || bey == 0 || bey == wx - 1 ||
                       (nrz > 0 && (bez == 0 || bez == wz - 1));

  // ---- sub-sample refinement (dims: x, y, z, yaw)
  const bool active[4] = {bex > 0 && bex<wx - 1, bey> 0 && bey<wx - 1, nrz> 0 && bez > 0 &&
                          bez<wz - 1, layers> 1 && bl > 0 && bl < layers - 1};
  float offs[4] = {0.f, 0.f, 0.f, 0.f};
  float value = best;
  detail::refinePeak(
      4, active, [&](const int* o) { return at(bl + o[3], bez + o[2], bey + o[1], bex + o[0]); },
      offs, &value);
  value = std::min(std::max(value, best), 1.f);

  const float dx = static_cast<float>(nr - bex) - offs[0];
  const float dy = static_cast<float>(nr - bey) - offs[1];
  const float dz = static_cast<float>(nrz - bez) - offs[2];
  const float yaw = (static_cast<float>(bl - (layers - 1) / 2) + offs[3]) * yaw_step_;

  Eigen::Affine3f motion = Eigen::Translation3f(Eigen::Vector3f(dx * res, dy * res, dz * res_z)) *
                           Eigen::Translation3f(centroid) *
                           Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()) *
                           Eigen::Translation3f(-centroid);
  const Eigen::Matrix4f final_f = motion.matrix() * guess_f;
  final_transformation_ = transformation_ = final_f.template cast<Scalar>();

  similarity_ = std::max(0.f, value);
  converged_ = !on_edge && similarity_ >= min_similarity_;

  // Source density on the target grid after the final motion, for model accumulation.
  {
    const Eigen::Matrix3f r = motion.linear();
    const Eigen::Vector3f t = motion.translation();
    for (std::size_t i = 0; i < points.size(); ++i) turned[i] = r * points[i] + t;
    auto sd = pcl::make_shared<SurfaceDensity>(target);
    sd->computeFromPoints(turned, sigmas, target.getCentre());
    source_density_ = sd;
  }
  finish();
}

}  // namespace pcl_movers
