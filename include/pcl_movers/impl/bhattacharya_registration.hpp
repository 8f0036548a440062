/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/bhattacharya_registration.h>

#include <pcl/common/transforms.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

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

/** \brief One source density (one yaw layer) on a tight grid of the target's lattice. */
struct SourceLayer {
  SurfaceDensity density{1, 1, 1, 0.2f, 0.4f};
  int ox = 0, oy = 0, oz = 0;  ///< target-lattice index of the tight grid's cell (0, 0, 0)
  std::vector<int> nonzero;    ///< indices of the cells with sqrt(ρ) > 0
  /** The non-zero cells again, per source row (y, z) in index order, for correlateDirect():
   * row r holds cells row_begin[r] .. row_begin[r + 1] - 1 of cell_x / cell_v (x index and
   * sqrt(ρ)); rows without mass are left out. */
  std::vector<int> row_y, row_z, row_begin, cell_x;
  std::vector<float> cell_v;
};

/** \brief Where the returns of occluders hide what lies behind them, seen from one sensor: the
 * smallest occluder range per bin of azimuth (0.12°) × elevation (0.3°), each return also
 * covering the neighbouring bins (the gaps between beams and azimuth steps). Defined in
 * src/bhattacharya_registration.cpp. */
class ShadowImage {
 public:
  void build(const std::vector<Eigen::Vector3f>& occluders, const Eigen::Vector3f& sensor);
  /** \brief True when an occluder return lies in p's direction more than `margin` m closer
   * to the sensor than p. */
  bool shadowed(const Eigen::Vector3f& p, float margin = 0.3f) const;
  bool empty() const { return range_.empty(); }

 private:
  Eigen::Vector3f sensor_ = Eigen::Vector3f::Zero();
  float az0_ = 0.f, el0_ = 0.f;
  int naz_ = 0, nel_ = 0;
  std::vector<float> range_;
};

/** \brief Everything align() reuses between calls: point buffers, source layers, score arrays,
 * the density built from a target cloud, FFT plans and the target's cached spectra. */
struct BhattacharyaWorkspace {
  std::vector<Eigen::Vector3f> points, turned;
  std::vector<float> sigmas;
  // The source's Gaussians after merging (setMergeFraction()): what the layers are built from.
  std::vector<Eigen::Vector3f> gauss_points;
  std::vector<float> gauss_sigmas_xy, gauss_sigmas_z, gauss_weights;
  // Same for a target cloud's density.
  std::vector<Eigen::Vector3f> target_points, target_gauss_points;
  std::vector<float> target_sigmas, target_sigmas_xy, target_sigmas_z, target_weights;
  std::vector<SourceLayer> layers;
  // The source's Gaussians prepared on the target's vertical lattice, for the z shift
  // prepared_shift (a search on a new target or z shift prepares again).
  SurfaceDensity::PreparedGaussians prepared;
  float prepared_shift = 0.f;
  SourceLayer refine[3];
  // Coarse-to-fine search (setCoarseToFine()): the binned middle layer and target, and the
  // fine-target revision the binned target was made from.
  SourceLayer coarse_source, coarse_target;
  std::uint64_t coarse_target_of = 0;
  std::vector<float> coarse_scores;
  std::vector<float> scores, block, local;
  std::vector<char> built;  // yaw layers built in this search (coarse to fine builds on demand)
  // Occlusion pass (setSourceOccluders() / setTargetOccluders()).
  ShadowImage source_shadow, target_shadow;
  std::vector<char> source_keep;
  std::vector<Eigen::Vector3f> culled_points;
  std::vector<float> culled_sigmas;
  SurfaceDensity culled_target{1, 1, 1, 0.2f, 0.4f};
  // Density of the target cloud (when no target density is set) and what it was built from.
  SurfaceDensity own_target{1, 1, 1, 0.2f, 0.4f};
  bool own_target_valid = false;
  const void* own_target_cloud = nullptr;
  std::vector<float> own_target_key;
  // FFT state (defined in src/bhattacharya_registration.cpp, opaque here).
  struct Fft;
  std::shared_ptr<Fft> fft;
};

/** \brief Builds `layer` from points already moved (guess, yaw, shift) on the lattice of
 * `target`, clipped to the cells that can overlap the target for shifts of ±nr (±nrz) cells. */
void buildSourceLayer(SourceLayer& layer, const std::vector<Eigen::Vector3f>& points,
                      const std::vector<float>& sigmas, const SurfaceDensity& target, int nr,
                      int nrz);
/** \brief Same for Gaussians with σ per axis group and weights (SurfaceDensity::mergeGaussians()
 * output; empty `weights`: equal masses). */
void buildSourceLayer(SourceLayer& layer, const std::vector<Eigen::Vector3f>& points,
                      const std::vector<float>& sigmas_xy, const std::vector<float>& sigmas_z,
                      const std::vector<float>& weights, const SurfaceDensity& target, int nr,
                      int nrz);

/** \brief `prepared` ← the Gaussians prepared (SurfaceDensity::prepareGaussians()) on the
 * target's vertical lattice, clipped to the cells reached by shifts of ±nrz cells, for points
 * moved up by z_shift [m]. */
void prepareSource(SurfaceDensity::PreparedGaussians& prepared,
                   const std::vector<Eigen::Vector3f>& points, const std::vector<float>& sigmas_xy,
                   const std::vector<float>& sigmas_z, const std::vector<float>& weights,
                   const SurfaceDensity& target, int nrz, float z_shift);
/** \brief buildSourceLayer() from prepared Gaussians at the horizontal positions of `points`
 * (indexed as when prepared): two axes per Gaussian instead of three. */
void buildSourceLayer(SourceLayer& layer, const std::vector<Eigen::Vector3f>& points,
                      const SurfaceDensity::PreparedGaussians& prepared,
                      const SurfaceDensity& target, int nr, int nrz);

/** \brief `coarse` ← the density `fine` (whose cell (0, 0, 0) is cell (ox, oy, oz) of a lattice)
 * summed over 2 × 2 horizontal blocks of that lattice (cells 2X, 2X + 1), square roots taken
 * after summing: the same object at twice the cell size. Its cell (0, 0, 0) is cell
 * (⌊ox/2⌋, ⌊oy/2⌋, oz) of the binned lattice, so a shift by D binned cells is one of 2D cells. */
void binLayer(const SurfaceDensity& fine, int ox, int oy, int oz, SourceLayer& coarse);

/** \brief B(d) = Σ_j sqrt(S[j])·sqrt(T[j + o + d]) for d in [dx0,dx1]×[dy0,dy1]×[dz0,dz1],
 * summed directly over the non-zero source cells; out[((dz-dz0)·h + dy-dy0)·w + dx-dx0]. */
void correlateDirect(const SurfaceDensity& target, const SourceLayer& src, int dx0, int dx1,
                     int dy0, int dy1, int dz0, int dz1, float* out);

/** \brief Same over the whole window d ∈ [-nr,nr]² × [-nrz,nrz] by FFT (per-slice spectra,
 * summed over slices before one inverse transform per z shift); the target's spectra are cached
 * in `work` by SurfaceDensity::revision(). */
void correlateFft(BhattacharyaWorkspace& work, const SurfaceDensity& target, const SourceLayer& src,
                  int nr, int nrz, float* out);

/** \brief Cost-model estimates (same unit, ~ns on the machine measured) of the two paths. */
double directCost(const SurfaceDensity& target, const SourceLayer& src, int nr, int nrz);
double fftCost(const BhattacharyaWorkspace& work, const SurfaceDensity& target,
               const SourceLayer& src, int nr, int nrz);

}  // namespace detail

template <typename PointSource, typename PointTarget, typename Scalar>
BhattacharyaRegistration<PointSource, PointTarget, Scalar>::BhattacharyaRegistration() {
  reg_name_ = "BhattacharyaRegistration";
  // No kd-tree is ever needed: stop pcl::Registration::initCompute() from building one.
  this->force_no_recompute_ = true;
  this->force_no_recompute_reciprocal_ = true;
  work_ = detail::acquireWorkspace();
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
const SurfaceDensity* BhattacharyaRegistration<PointSource, PointTarget, Scalar>::targetDensity() {
  if (target_density_) return target_density_->empty() ? nullptr : target_density_.get();
  if (!target_) return nullptr;
  detail::BhattacharyaWorkspace& w = *work_;
  const Eigen::Vector3f origin =
      use_sensor_origin_ ? sensor_origin_ : target_->sensor_origin_.template head<3>();
  const std::vector<float> key = {static_cast<float>(nx_),
                                  static_cast<float>(ny_),
                                  static_cast<float>(nz_),
                                  resolution_,
                                  grid_height_,
                                  sigma_per_metre_,
                                  min_sigma_,
                                  origin.x(),
                                  origin.y(),
                                  origin.z(),
                                  static_cast<float>(target_->size())};
  // The same target cloud registered against many sources (or the same call repeated) reuses
  // its density; setInputTarget() always invalidates it.
  if (w.own_target_valid && !this->target_cloud_updated_ && w.own_target_cloud == target_.get() &&
      w.own_target_key == key)
    return w.own_target.empty() ? nullptr : &w.own_target;
  this->target_cloud_updated_ = false;
  w.own_target_cloud = target_.get();
  w.own_target_key = key;
  w.own_target_valid = true;
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
  SurfaceDensity& target = w.own_target;
  if (n < 2) {
    target.clear();
    return nullptr;
  }
  if (target.getNx() != nx_ || target.getNy() != ny_ || target.getNz() != nz_)
    target.setGridSize(nx_, ny_, nz_);
  target.setResolution(resolution_);
  target.setResolutionZ(grid_height_ / static_cast<float>(nz_));
  target.setSigmaPerMetre(sigma_per_metre_);
  target.setMinSigma(min_sigma_);
  w.target_points.clear();
  w.target_sigmas.clear();
  for (const auto& p : target_->points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const Eigen::Vector3f v(p.x, p.y, p.z);
    w.target_points.push_back(v);
    w.target_sigmas.push_back(target.sigmaAtRange((v - origin).norm()));
  }
  buildDensity(target, w.target_points, w.target_sigmas, Eigen::Vector3f(0.5f * (lo + hi)));
  return target.empty() ? nullptr : &target;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::computeTransformation(
    PointCloudSource& output, const Matrix4& guess) {
  search(guess, search_radius_, nullptr, nullptr);
  if ((source_occluders_ && !source_occluders_->empty()) ||
      (target_occluders_ && !target_occluders_->empty())) {
    // The culling depends on the estimate: repeat while it still moves.
    for (int pass = 0; pass < kOcclusionPasses && converged_; ++pass) {
      const Matrix4 before = final_transformation_;
      occlusionPass();
      if ((final_transformation_.template topRightCorner<3, 1>() -
           before.template topRightCorner<3, 1>())
              .norm() < Scalar(0.01))
        break;
    }
  }
  if (output.size() > 0) pcl::transformPointCloud(output, output, final_transformation_);
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::occlusionPass() {
  detail::BhattacharyaWorkspace& w = *work_;
  const Eigen::Matrix4f est = final_transformation_.template cast<float>();
  const Eigen::Matrix4f est_inv = est.inverse();
  if (!est_inv.allFinite()) return;
  const Eigen::Vector3f src_origin =
      use_sensor_origin_ ? sensor_origin_ : input_->sensor_origin_.template head<3>();
  const Eigen::Vector3f tgt_origin =
      use_sensor_origin_ ? sensor_origin_ : target_->sensor_origin_.template head<3>();
  // Shadows of each scan's occluders, seen from that scan's sensor.
  auto shadows = [](detail::ShadowImage& image, const auto& cloud, const Eigen::Vector3f& origin) {
    std::vector<Eigen::Vector3f> pts;
    if (cloud)
      for (const auto& p : cloud->points)
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
          pts.emplace_back(p.x, p.y, p.z);
    image.build(pts, origin);
  };
  shadows(w.target_shadow, target_occluders_, tgt_origin);
  shadows(w.source_shadow, source_occluders_, src_origin);
  // Source points that the target's occluders would hide at the estimated motion, and target
  // points that the source's occluders would hide: left out so that both views show the same
  // parts of the object.
  std::size_t culled = 0, kept_src = 0;
  w.source_keep.assign(indices_->size(), 1);
  for (std::size_t k = 0; k < indices_->size(); ++k) {
    const auto& p = (*input_)[(*indices_)[k]];
    // Also the source's own points in the (dilated) shadow of its occluders: their twins in the
    // target are culled by the same test, so both views end at the same edge.
    const Eigen::Vector4f v = est * Eigen::Vector4f(p.x, p.y, p.z, 1.f);
    if (v.allFinite() && (w.target_shadow.shadowed(v.template head<3>()) ||
                          w.source_shadow.shadowed(Eigen::Vector3f(p.x, p.y, p.z)))) {
      w.source_keep[k] = 0;
      ++culled;
    } else {
      ++kept_src;
    }
  }
  const SurfaceDensity* target_override = nullptr;
  if (!target_density_ && !(w.source_shadow.empty() && w.target_shadow.empty())) {
    std::vector<Eigen::Vector3f>& pts = w.culled_points;
    std::vector<float>& sig = w.culled_sigmas;
    pts.clear();
    sig.clear();
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f hi = -lo;
    for (const auto& p : target_->points) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
      const Eigen::Vector3f v(p.x, p.y, p.z);
      const Eigen::Vector4f back = est_inv * Eigen::Vector4f(p.x, p.y, p.z, 1.f);
      if (w.source_shadow.shadowed(back.template head<3>()) || w.target_shadow.shadowed(v)) {
        ++culled;
        continue;
      }
      pts.push_back(v);
      sig.push_back(std::max(min_sigma_, sigma_per_metre_ * (v - tgt_origin).norm()));
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    if (pts.size() < 2) return;
    if (culled > 0) {
      SurfaceDensity& t = w.culled_target;
      t.setGridSize(nx_, ny_, nz_);
      t.setResolution(resolution_);
      t.setResolutionZ(grid_height_ / static_cast<float>(nz_));
      t.setSigmaPerMetre(sigma_per_metre_);
      t.setMinSigma(min_sigma_);
      buildDensity(t, pts, sig, Eigen::Vector3f(0.5f * (lo + hi)));
      if (t.empty()) return;
      target_override = &t;
    }
  }
  if (culled == 0 || kept_src < 2) return;
  // A local search from the first estimate on the views reduced to their common visible part;
  // the first result stands when this one does not converge.
  const Matrix4 first = final_transformation_;
  const float first_similarity = similarity_;
  SimilaritySurface first_surface = surface_;
  SurfaceDensity::Ptr first_density = source_density_;
  search(first, std::min(search_radius_, kOcclusionRadius), &w.source_keep, target_override);
  if (!converged_) {
    final_transformation_ = transformation_ = first;
    similarity_ = first_similarity;
    surface_ = std::move(first_surface);
    source_density_ = first_density;
    converged_ = true;
  }
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::buildDensity(
    SurfaceDensity& density, const std::vector<Eigen::Vector3f>& points,
    const std::vector<float>& sigmas, const Eigen::Vector3f& centre) {
  detail::BhattacharyaWorkspace& w = *work_;
  SurfaceDensity::mergeGaussians(points, sigmas, merge_fraction_ * min_sigma_,
                                 w.target_gauss_points, w.target_sigmas_xy, w.target_sigmas_z,
                                 w.target_weights);
  density.computeFromGaussians(w.target_gauss_points, w.target_sigmas_xy, w.target_sigmas_z,
                               w.target_weights, centre);
}

template <typename PointSource, typename PointTarget, typename Scalar>
void BhattacharyaRegistration<PointSource, PointTarget, Scalar>::search(
    const Matrix4& guess, float radius, const std::vector<char>* source_keep,
    const SurfaceDensity* target_override) {
  converged_ = false;
  similarity_ = 0.f;
  surface_.nx = surface_.ny = 0;
  surface_.yaws.clear();
  surface_.values.clear();
  const Eigen::Matrix4f guess_f = guess.template cast<float>();
  final_transformation_ = transformation_ = guess;
  bool keep_source_density = false;

  auto finish = [&]() {
    if (!keep_source_density) source_density_.reset();
  };
  if (!(resolution_ > 0.f) || !(radius > 0.f) || nx_ < 1 || ny_ < 1 || nz_ < 1 ||
      !(grid_height_ > 0.f) || yaw_samples_ < 1 || !std::isfinite(radius) ||
      radius / resolution_ > 1000.f) {
    PCL_ERROR("[pcl_movers::%s] invalid parameters (resolution, radius, grid or yaw samples)\n",
              reg_name_.c_str());
    finish();
    return;
  }
  if (!guess_f.allFinite()) {
    PCL_ERROR("[pcl_movers::%s] the initial guess is not finite\n", reg_name_.c_str());
    finish();
    return;
  }
  detail::BhattacharyaWorkspace& w = *work_;

  // ---- target density (the "model")
  const SurfaceDensity* target_ptr = target_override ? target_override : targetDensity();
  if (!target_ptr) {
    finish();
    return;
  }
  const SurfaceDensity& target = *target_ptr;
  const float res = target.getResolution(), res_z = target.getResolutionZ();

  // ---- source points after the guess; σ from the untransformed ranges
  const Eigen::Vector3f src_origin =
      use_sensor_origin_ ? sensor_origin_ : input_->sensor_origin_.template head<3>();
  std::vector<Eigen::Vector3f>& points = w.points;
  std::vector<float>& sigmas = w.sigmas;
  points.clear();
  sigmas.clear();
  const Eigen::Matrix3f guess_r = guess_f.template topLeftCorner<3, 3>();
  const Eigen::Vector3f guess_t = guess_f.template topRightCorner<3, 1>();
  for (std::size_t k = 0; k < indices_->size(); ++k) {
    if (source_keep && !(*source_keep)[k]) continue;
    const auto& p = (*input_)[(*indices_)[k]];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const Eigen::Vector3f v(p.x, p.y, p.z);
    const float sigma = std::max(min_sigma_, sigma_per_metre_ * (v - src_origin).norm());
    if (!(sigma > 0.f) || !std::isfinite(sigma)) continue;
    points.push_back(guess_r * v + guess_t);
    sigmas.push_back(sigma);
  }
  if (points.size() < 2) {
    finish();
    return;
  }
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<float>(points.size());
  // The Gaussians every source density below is built from: the points merged per cube of
  // merge fraction · min σ (moment-matched, see SurfaceDensity::mergeGaussians()), once per
  // search instead of once per yaw layer and refinement step.
  std::vector<Eigen::Vector3f>& gauss = w.gauss_points;
  SurfaceDensity::mergeGaussians(points, sigmas, merge_fraction_ * min_sigma_, gauss,
                                 w.gauss_sigmas_xy, w.gauss_sigmas_z, w.gauss_weights);
  std::vector<Eigen::Vector3f>& turned = w.turned;
  turned.resize(gauss.size());
  int nrz_prepare = 0;
  // Rotations about z and horizontal shifts leave every Gaussian's vertical cell weights as
  // they are: they are computed once per search (and z shift), each layer below only evaluates
  // the two horizontal axes.
  bool prepared_valid = false;
  auto buildLayer = [&](detail::SourceLayer& layer, int r, int rz, float z_shift) {
    if (!prepared_valid || z_shift != w.prepared_shift) {
      detail::prepareSource(w.prepared, gauss, w.gauss_sigmas_xy, w.gauss_sigmas_z, w.gauss_weights,
                            target, nrz_prepare, z_shift);
      w.prepared_shift = z_shift;
      prepared_valid = true;
    }
    detail::buildSourceLayer(layer, turned, w.prepared, target, r, rz);
  };

  // ---- search window: translations d of ±nr cells (±nrz in z) around the guess
  const int nr = std::max(1, static_cast<int>(std::ceil(radius / res - 1e-4f)));
  const int nrz =
      search_z_ ? std::max(1, static_cast<int>(std::ceil(search_radius_z_ / res_z - 1e-4f))) : 0;
  const int wx = 2 * nr + 1, wz = 2 * nrz + 1;
  nrz_prepare = nrz;
  const int layers = yaw_samples_ % 2 == 1 ? yaw_samples_ : yaw_samples_ + 1;
  const int mid = (layers - 1) / 2;
  if (static_cast<int>(w.layers.size()) < layers) w.layers.resize(static_cast<std::size_t>(layers));

  // Moves the source (after the guess) by yaw ψ about its centroid, then by `shift`.
  auto place = [&](float yaw, const Eigen::Vector3f& shift) {
    const Eigen::Matrix3f rz = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    for (std::size_t i = 0; i < gauss.size(); ++i)
      turned[i] = rz * (gauss[i] - centroid) + centroid + shift;
  };
  // Coarse to fine in yaw (setCoarseToFine()): only the middle layer and its two neighbours are
  // built up front; a layer further out is built when the hill climbing below first reaches it
  // (the best sample lies on its neighbour layer), which is what a unimodal B(yaw) needs.
  const bool coarse_to_fine = coarse_to_fine_ && !full_yaw_window_ &&
                              correlation_method_ != CorrelationMethod::FFT &&
                              nr >= kCoarseMinRadius;
  const bool lazy_layers = coarse_to_fine;
  std::vector<char>& built = w.built;
  built.assign(static_cast<std::size_t>(layers), 0);
  auto ensureLayer = [&](int l) {
    if (built[static_cast<std::size_t>(l)]) return;
    place(static_cast<float>(l - mid) * yaw_step_, Eigen::Vector3f::Zero());
    buildLayer(w.layers[static_cast<std::size_t>(l)], nr, nrz, 0.f);
    built[static_cast<std::size_t>(l)] = 1;
  };
  for (int l = 0; l < layers; ++l)
    if (!lazy_layers || std::abs(l - mid) <= 1) ensureLayer(l);

  // scores[((l·wz + dz+nrz)·wx + dy+nr)·wx + dx+nr] = B(d) of layer l; -1: not evaluated.
  std::vector<float>& scores = w.scores;
  scores.assign(static_cast<std::size_t>(layers) * wz * wx * wx, -1.f);
  auto at = [&](int l, int dz, int dy, int dx) -> float& {
    return scores[((static_cast<std::size_t>(l) * wz + (dz + nrz)) * wx + (dy + nr)) * wx +
                  (dx + nr)];
  };
  // The best sample so far (the first in index order among equals, as a scan would find it),
  // kept up to date by correlateBlock(); findBest() rescans after the FFT wrote a window.
  int bl = 0, bdz = 0, bdy = 0, bdx = 0;
  float best = -1.f;
  std::size_t best_index = 0;
  auto correlateBlock = [&](int l, int dx0, int dx1, int dy0, int dy1) {
    dx0 = std::max(dx0, -nr);
    dy0 = std::max(dy0, -nr);
    dx1 = std::min(dx1, nr);
    dy1 = std::min(dy1, nr);
    if (dx1 < dx0 || dy1 < dy0) return;
    ensureLayer(l);
    const int bw = dx1 - dx0 + 1, bh = dy1 - dy0 + 1;
    w.block.assign(static_cast<std::size_t>(wz) * bh * bw, 0.f);
    detail::correlateDirect(target, w.layers[static_cast<std::size_t>(l)], dx0, dx1, dy0, dy1, -nrz,
                            nrz, w.block.data());
    for (int dz = -nrz; dz <= nrz; ++dz)
      for (int dy = dy0; dy <= dy1; ++dy)
        for (int dx = dx0; dx <= dx1; ++dx) {
          const float v =
              w.block[(static_cast<std::size_t>(dz + nrz) * bh + (dy - dy0)) * bw + (dx - dx0)];
          float& slot = at(l, dz, dy, dx);
          slot = v;
          const std::size_t index = static_cast<std::size_t>(&slot - scores.data());
          if (v > best || (v == best && index < best_index)) {
            best = v;
            best_index = index;
            bl = l;
            bdz = dz;
            bdy = dy;
            bdx = dx;
          }
        }
  };
  // The whole window of the middle layer: direct sum or FFT, whichever the cost model says is
  // cheaper (or as forced by setCorrelationMethod()).
  if (coarse_to_fine) {
    // Coarse to fine: the whole window at even shifts on 2×2-binned densities (a quarter of the
    // cells, a quarter of the shifts), then full resolution in a ±2-cell block around each of
    // the best few coarse maxima (a binned peak can be a runner-up: the blocks decide).
    last_method_ = CorrelationMethod::Direct;
    if (w.coarse_target_of != target.revision()) {
      detail::binLayer(target, 0, 0, 0, w.coarse_target);
      w.coarse_target_of = target.revision();
    }
    const detail::SourceLayer& ml = w.layers[static_cast<std::size_t>(mid)];
    detail::binLayer(ml.density, ml.ox, ml.oy, ml.oz, w.coarse_source);
    const int cr = nr / 2, cw = 2 * cr + 1;
    std::vector<float>& cs = w.coarse_scores;
    cs.assign(static_cast<std::size_t>(wz) * cw * cw, 0.f);
    detail::correlateDirect(w.coarse_target.density, w.coarse_source, -cr, cr, -cr, cr, -nrz, nrz,
                            cs.data());
    // Best over z shifts, then the local maxima (3×3) in decreasing order.
    for (int dz = 1; dz < wz; ++dz)
      for (int i = 0; i < cw * cw; ++i)
        cs[static_cast<std::size_t>(i)] = std::max(cs[static_cast<std::size_t>(i)],
                                                   cs[static_cast<std::size_t>(dz) * cw * cw + i]);
    struct Peak {
      float value;
      int x, y;
    };
    Peak peaks[kCoarsePeaks];
    int found = 0;
    for (int y = 0; y < cw; ++y)
      for (int x = 0; x < cw; ++x) {
        const float v = cs[static_cast<std::size_t>(y) * cw + x];
        if (!(v > 0.f)) continue;
        bool is_max = true;
        for (int ny = std::max(0, y - 1); ny <= std::min(cw - 1, y + 1) && is_max; ++ny)
          for (int nx = std::max(0, x - 1); nx <= std::min(cw - 1, x + 1); ++nx) {
            const float u = cs[static_cast<std::size_t>(ny) * cw + nx];
            // Ties go to the first in scan order: deterministic plateaus.
            if (u > v || (u == v && ny * cw + nx < y * cw + x)) {
              is_max = false;
              break;
            }
          }
        if (!is_max) continue;
        int k = std::min(found, kCoarsePeaks - 1);
        if (found == kCoarsePeaks && !(v > peaks[k].value)) continue;
        for (; k > 0 && v > peaks[k - 1].value; --k) peaks[k] = peaks[k - 1];
        peaks[k] = {v, x - cr, y - cr};
        found = std::min(found + 1, kCoarsePeaks);
      }
    for (int k = 0; k < found; ++k)
      correlateBlock(mid, 2 * peaks[k].x - 2, 2 * peaks[k].x + 2, 2 * peaks[k].y - 2,
                     2 * peaks[k].y + 2);
    if (found == 0) correlateBlock(mid, -2, 2, -2, 2);  // no overlap anywhere: B = 0 at the guess
  } else {
    const detail::SourceLayer& ml = w.layers[static_cast<std::size_t>(mid)];
    bool use_fft = correlation_method_ == CorrelationMethod::FFT;
    if (correlation_method_ == CorrelationMethod::Auto)
      use_fft = detail::fftCost(w, target, ml, nr, nrz) < detail::directCost(target, ml, nr, nrz);
    last_method_ = use_fft ? CorrelationMethod::FFT : CorrelationMethod::Direct;
    if (use_fft)
      detail::correlateFft(w, target, ml, nr, nrz, &at(mid, -nrz, -nr, -nr));
    else
      correlateBlock(mid, -nr, nr, -nr, nr);
  }
  auto findBest = [&]() {
    best = -1.f;
    best_index = 0;
    for (int l = 0; l < layers; ++l)
      for (int dz = -nrz; dz <= nrz; ++dz)
        for (int dy = -nr; dy <= nr; ++dy)
          for (int dx = -nr; dx <= nr; ++dx)
            if (at(l, dz, dy, dx) > best) {
              best = at(l, dz, dy, dx);
              best_index = static_cast<std::size_t>(&at(l, dz, dy, dx) - scores.data());
              bl = l;
              bdz = dz;
              bdy = dy;
              bdx = dx;
            }
  };
  if (last_method_ == CorrelationMethod::FFT) findBest();
  // The other yaw layers turn the source about its own centroid, which moves the peak little,
  // so they are evaluated in a ±kLocal-cell block around the middle layer's peak (unless
  // setFullYawWindow()), then grown by hill climbing until the best sample's neighbourhood is
  // fully known.
  // Coarse to fine: ±2 cells, the hill climbing below grows the blocks where the peak leads.
  const int kLocal = coarse_to_fine ? 2 : 4;
  const int mdx = bdx, mdy = bdy;  // the middle layer's peak (bdx, bdy follow the best below)
  for (int l = 0; l < layers; ++l) {
    if (l == mid || (lazy_layers && std::abs(l - mid) > 1)) continue;
    if (full_yaw_window_) {
      if (last_method_ == CorrelationMethod::FFT)
        detail::correlateFft(w, target, w.layers[static_cast<std::size_t>(l)], nr, nrz,
                             &at(l, -nrz, -nr, -nr));
      else
        correlateBlock(l, -nr, nr, -nr, nr);
    } else {
      correlateBlock(l, mdx - kLocal, mdx + kLocal, mdy - kLocal, mdy + kLocal);
    }
  }
  if (last_method_ == CorrelationMethod::FFT) findBest();
  for (int iter = 0; iter < 4 * wx; ++iter) {
    bool grew = false;
    const int cl = bl, cy = bdy, cx = bdx;  // this round's best
    for (int l = std::max(0, cl - 1); l <= std::min(layers - 1, cl + 1); ++l)
      for (int dy = std::max(-nr, cy - 1); dy <= std::min(nr, cy + 1); ++dy)
        for (int dx = std::max(-nr, cx - 1); dx <= std::min(nr, cx + 1); ++dx)
          if (at(l, -nrz, dy, dx) < 0.f) {
            correlateBlock(l, dx - 2, dx + 2, dy - 2, dy + 2);
            grew = true;
          }
    if (!grew) break;
    if (last_method_ == CorrelationMethod::FFT) findBest();
  }

  // Similarity surface for callers (max over z shifts), ix = nr + dx.
  surface_.nx = wx;
  surface_.ny = wx;
  surface_.resolution = res;
  surface_.yaws.resize(static_cast<std::size_t>(layers));
  surface_.values.resize(static_cast<std::size_t>(layers) * wx * wx);
  // A flat loop per layer (the z planes of a layer are consecutive in `scores`): at 5 layers of
  // 33 × 33 it is a few microseconds, where the indexed one was 5 % of a registration.
  const std::size_t plane = static_cast<std::size_t>(wx) * wx;
  for (int l = 0; l < layers; ++l) {
    surface_.yaws[static_cast<std::size_t>(l)] = static_cast<float>(l - mid) * yaw_step_;
    float* out = surface_.values.data() + static_cast<std::size_t>(l) * plane;
    const float* in = scores.data() + static_cast<std::size_t>(l) * wz * plane;
    for (std::size_t i = 0; i < plane; ++i) out[i] = std::min(std::max(in[i], 0.f), 1.f);
    for (int z = 1; z < wz; ++z) {
      const float* layer_z = in + static_cast<std::size_t>(z) * plane;
      for (std::size_t i = 0; i < plane; ++i)
        out[i] = std::max(out[i], std::min(std::max(layer_z[i], 0.f), 1.f));
    }
  }

  const bool on_edge = bdx == -nr || bdx == nr || bdy == -nr || bdy == nr ||
                       (nrz > 0 && (bdz == -nrz || bdz == nrz));

  // ---- sub-sample refinement (dims: x, y, z, yaw)
  // This first fit is made on log B: near its top B is close to a Gaussian of the offset (for
  // two Gaussians of σ it is exp(-d²/8σ²)), which a quadratic in log B follows exactly wherever
  // the samples fall on it, where a quadratic in B on samples off the top is biased (near
  // objects: σ = half a cell). The re-centring below fits on samples symmetric about the peak,
  // where the quadratic in B is unbiased, and stays on B (on log B it lost the track of a van
  // passing the sensor on KITTI city-22; docs/design_history.md).
  auto logB = [](float b) { return std::log(std::max(b, kLogFloor)); };
  const bool active[4] = {bdx > -nr && bdx<nr, bdy> - nr && bdy<nr, nrz> 0 && bdz > -nrz &&
                          bdz<nrz, layers> 1 && bl > 0 && bl < layers - 1};
  float offs[4] = {0.f, 0.f, 0.f, 0.f};
  float value = best;
  detail::refinePeak(
      4, active,
      [&](const int* o) { return logB(at(bl + o[3], bdz + o[2], bdy + o[1], bdx + o[0])); }, offs,
      &value);
  value = std::min(std::max(std::exp(value), best), 1.f);
  float dx = static_cast<float>(bdx) + offs[0];
  float dy = static_cast<float>(bdy) + offs[1];
  float dz = static_cast<float>(bdz) + offs[2];
  float yaw = (static_cast<float>(bl - mid) + offs[3]) * yaw_step_;

  // ---- sub-cell re-centring: rebuild the source at the fitted motion and fit the samples
  // around it again (symmetric samples; see setSubCellIterations()).
  const int rl = layers > 1 ? 3 : 1;
  const int rz = nrz > 0 ? 1 : 0;
  for (int it = 0; it < sub_cell_iterations_ && !on_edge; ++it) {
    w.local.assign(static_cast<std::size_t>(rl) * (2 * rz + 1) * 9, 0.f);
    for (int k = 0; k < rl; ++k) {
      place(yaw + static_cast<float>(k - (rl - 1) / 2) * yaw_step_,
            Eigen::Vector3f(dx * res, dy * res, dz * res_z));
      buildLayer(w.refine[k], 1, rz, dz * res_z);
      detail::correlateDirect(target, w.refine[k], -1, 1, -1, 1, -rz, rz,
                              &w.local[static_cast<std::size_t>(k) * (2 * rz + 1) * 9]);
    }
    const bool act[4] = {true, true, rz > 0, rl > 1};
    float u[4] = {0.f, 0.f, 0.f, 0.f};
    float v = 0.f;
    detail::refinePeak(
        4, act,
        [&](const int* o) {
          return w
              .local[((static_cast<std::size_t>(o[3] + (rl - 1) / 2) * (2 * rz + 1) + (o[2] + rz)) *
                          3 +
                      (o[1] + 1)) *
                         3 +
                     (o[0] + 1)];
        },
        u, &v);
    dx += u[0];
    dy += u[1];
    dz += u[2];
    yaw += u[3] * yaw_step_;
    // As for the coarse fit: the fitted top is never below the best sample.
    const float centre_sample =
        w.local[((static_cast<std::size_t>((rl - 1) / 2) * (2 * rz + 1) + rz) * 3 + 1) * 3 + 1];
    value = std::min(std::max(v, centre_sample), 1.f);
    if (std::max(std::max(std::abs(u[0]), std::abs(u[1])),
                 std::max(std::abs(u[2]), std::abs(u[3]))) < kRecentreTolerance)
      break;
  }

  Eigen::Affine3f motion = Eigen::Translation3f(Eigen::Vector3f(dx * res, dy * res, dz * res_z)) *
                           Eigen::Translation3f(centroid) *
                           Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()) *
                           Eigen::Translation3f(-centroid);
  const Eigen::Matrix4f final_f = motion.matrix() * guess_f;
  final_transformation_ = transformation_ = final_f.template cast<Scalar>();

  similarity_ = std::max(0.f, value);
  converged_ = !on_edge && similarity_ >= min_similarity_;

  // Source density on the target grid after the final motion, for model accumulation. The
  // object is reused while nobody else holds it: no allocation per call.
  if (compute_source_density_) {
    const Eigen::Matrix3f r = motion.linear();
    const Eigen::Vector3f t = motion.translation();
    for (std::size_t i = 0; i < gauss.size(); ++i) turned[i] = r * gauss[i] + t;
    if (!source_density_ || source_density_.use_count() > 1)
      source_density_ = pcl::make_shared<SurfaceDensity>(target);
    SurfaceDensity& sd = *source_density_;
    if (sd.getNx() != target.getNx() || sd.getNy() != target.getNy() ||
        sd.getNz() != target.getNz())
      sd.setGridSize(target.getNx(), target.getNy(), target.getNz());
    sd.setResolution(res);
    sd.setResolutionZ(res_z);
    sd.setSigmaPerMetre(target.getSigmaPerMetre());
    sd.setMinSigma(target.getMinSigma());
    const float z_shift = dz * res_z;
    if (!prepared_valid || z_shift != w.prepared_shift) {
      detail::prepareSource(w.prepared, gauss, w.gauss_sigmas_xy, w.gauss_sigmas_z, w.gauss_weights,
                            target, nrz, z_shift);
      w.prepared_shift = z_shift;
    }
    sd.computeFromPrepared(w.prepared, turned, target.getCentre());
    keep_source_density = true;
  }
  finish();
}

}  // namespace pcl_movers
