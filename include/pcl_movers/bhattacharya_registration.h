/*
 * Object-to-object registration by maximising the Bhattacharyya similarity of surface densities,
 * after Morris, Colonna, Haley, "Ladar-based mover detection from moving vehicles", section 5.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/surface_density.h>

#include <pcl/registration/registration.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

namespace pcl_movers {

namespace detail {
struct BhattacharyaWorkspace;
/** \brief A workspace for a new registration object: the one the last object destroyed on this
 * thread left behind (its buffers and FFT plans already sized), or a new one. */
std::shared_ptr<BhattacharyaWorkspace> acquireWorkspace();
/** \brief Keeps `work` (if no copy of its object still uses it) for the next object created on
 * this thread: a registration per object pair then costs no heap traffic once warm. */
void releaseWorkspace(std::shared_ptr<BhattacharyaWorkspace>& work);
}  // namespace detail

/** \brief The Bhattacharyya similarity B over the searched motions of the last align().
 *
 * values[(yaw · ny + iy) · nx + ix] is B for the source translated by
 * ((ix - (nx-1)/2)·resolution, (iy - (ny-1)/2)·resolution) from the guess and turned by yaws[yaw]
 * about its centroid. With z search on, each value is the best over the searched z shifts.
 * Yaw layers other than the middle one are only evaluated near the peak (0 elsewhere) unless
 * BhattacharyaRegistration::setFullYawWindow() is set.
 */
struct SimilaritySurface {
  int nx = 0, ny = 0;
  float resolution = 0.f;     ///< translation step between samples [m]
  std::vector<float> yaws;    ///< yaw of each layer [rad]
  std::vector<float> values;  ///< B per sample, see above
  float at(int ix, int iy, int yaw_layer = 0) const {
    return values[(static_cast<std::size_t>(yaw_layer) * ny + iy) * nx + ix];
  }
  bool empty() const { return values.empty(); }
};

/** \brief Registration of coarsely sampled LiDAR objects by the Bhattacharyya similarity of their
 * surface densities (see SurfaceDensity), a drop-in for pcl::IterativeClosestPoint or
 * pcl::NormalDistributionsTransform on object-to-object problems.
 *
 * Motion model: a horizontal translation (plus optionally z) and a yaw about the vertical axis,
 * which is what ground vehicles and people do. For every yaw layer the (guess-transformed, turned)
 * source density is correlated with the target density for all translations in a square window
 * of ± search radius around the guess at once (paper eq. 3: B_D = sqrt(ρ_source) ⋆ sqrt(ρ_target)),
 * so there are no local minima inside the window. The peak is refined by a quadratic fit of log B
 * over its 3×3 (×3 yaw layers) neighbourhood.
 *
 * \code
 * pcl_movers::BhattacharyaRegistration<pcl::PointXYZ, pcl::PointXYZ> reg;
 * reg.setInputSource(object_now);      // points in world coordinates
 * reg.setInputTarget(object_before);
 * reg.setSearchRadius(2.0f);           // metres around the guess
 * reg.align(aligned, predicted_motion_inverse);
 * if (reg.hasConverged() && reg.getSimilarity() > 0.5) use(reg.getFinalTransformation());
 * \endcode
 *
 * getFinalTransformation() maps the source onto the target as in PCL: x ↦ t + R_z(ψ)(x - c) + c
 * applied after the guess, c being the centroid of the guess-transformed source.
 *
 * hasConverged() is false when the peak lies on the edge of the translation window (the true
 * motion may lie outside it), when B is below setMinSimilarity(), or when source or target have
 * fewer than two finite points; getFinalTransformation() is then the guess.
 *
 * The sensor origin (range → σ of each point) defaults to each cloud's `sensor_origin_`; set it
 * with setSensorOrigin() when the clouds are in a world frame whose origin is not the sensor.
 */
template <typename PointSource, typename PointTarget, typename Scalar = float>
class BhattacharyaRegistration : public pcl::Registration<PointSource, PointTarget, Scalar> {
 public:
  using Base = pcl::Registration<PointSource, PointTarget, Scalar>;
  using typename Base::Matrix4;
  using PointCloudSource = typename Base::PointCloudSource;
  using PointCloudSourcePtr = typename PointCloudSource::Ptr;
  using PointCloudSourceConstPtr = typename PointCloudSource::ConstPtr;
  using PointCloudTarget = typename Base::PointCloudTarget;
  using PointCloudTargetConstPtr = typename PointCloudTarget::ConstPtr;

  using Ptr = pcl::shared_ptr<BhattacharyaRegistration<PointSource, PointTarget, Scalar>>;
  using ConstPtr =
      pcl::shared_ptr<const BhattacharyaRegistration<PointSource, PointTarget, Scalar>>;

  BhattacharyaRegistration();
  ~BhattacharyaRegistration() override { detail::releaseWorkspace(work_); }

  /** \brief Unlike the base class, an empty cloud is accepted; align() then reports
   * hasConverged() == false instead of silently reusing the previous cloud. */
  void setInputSource(const PointCloudSourceConstPtr& cloud) override;
  void setInputTarget(const PointCloudTargetConstPtr& cloud) override;

  /** \brief Same as pcl::Registration::align() (which this hides): copies the source to
   * `output`, runs computeTransformation() and leaves `output` moved by the final transformation.
   * Redefined because the base version cannot be compiled for mixed point types in PCL 1.13 (its
   * initCompute() hands a source-typed kd-tree to a target-typed correspondence estimator); this
   * one needs no kd-tree at all. Calls through a pcl::Registration pointer still work for equal
   * point types. */
  void align(PointCloudSource& output) { align(output, Matrix4::Identity()); }
  void align(PointCloudSource& output, const Matrix4& guess);

  /** \brief Registers against an accumulated model instead of a target cloud: the grid (size,
   * resolutions, centre) is the model's, and the grid setters below are ignored while it is set.
   * If no target cloud has been given, a one-point placeholder at the model centre is installed
   * so that pcl::Registration::align() runs. Pass nullptr to go back to target clouds. */
  void setTargetDensity(const SurfaceDensity::ConstPtr& density);
  SurfaceDensity::ConstPtr getTargetDensity() const { return target_density_; }

  /** \brief Density of the source after the final transformation, on the target's grid (the
   * target density's grid, or the grid built around the target cloud): ready for
   * SurfaceDensity::accumulate() into a model. Null before the first align() or after a failure
   * with an empty source. */
  SurfaceDensity::ConstPtr getSourceDensity() const { return source_density_; }

  /** \brief Whether align() also builds getSourceDensity() (default false: a drop-in
   * registration has no use for it, and it is a full-grid rasterisation, about 6 % of a 5-yaw
   * registration). Model accumulation switches it on (docs/registration.md); a caller that
   * registers many candidates and accumulates only the few it keeps (MoverTracker) leaves it off
   * and builds those views itself from getFinalTransformation(). While off, getSourceDensity()
   * is null after align(). */
  void setComputeSourceDensity(bool compute) { compute_source_density_ = compute; }
  bool getComputeSourceDensity() const { return compute_source_density_; }

  /** \brief B at the optimum of the last align(), in [0,1] (1 for identical densities). */
  float getSimilarity() const { return similarity_; }

  /** \brief B over all searched translations × yaw layers of the last align() (paper Fig. 6). */
  const SimilaritySurface& getSimilaritySurface() const { return surface_; }

  /** \brief Half width of the square translation window around the guess [m] (default 2). */
  void setSearchRadius(float radius) { search_radius_ = radius; }
  float getSearchRadius() const { return search_radius_; }

  /** \brief Cell size in x and y [m] (default 0.2); also the translation step of the search. */
  void setResolution(float resolution) { resolution_ = resolution; }
  float getResolution() const { return resolution_; }

  /** \brief Density grid size in cells (default the paper's 29 × 29 × 7). */
  void setGridSize(int nx, int ny, int nz) {
    nx_ = nx;
    ny_ = ny;
    nz_ = nz;
  }
  int getGridNx() const { return nx_; }
  int getGridNy() const { return ny_; }
  int getGridNz() const { return nz_; }

  /** \brief Height covered by the grid [m] (default 2.8); the vertical cell size is
   * height / nz. */
  void setGridHeight(float height) { grid_height_ = height; }
  float getGridHeight() const { return grid_height_; }

  /** \brief Number of horizontal slices (the grid's nz) at unchanged grid height: the paper's
   * reduced vertical resolution, e.g. 3. */
  void setVerticalSlices(int slices) { nz_ = slices; }
  int getVerticalSlices() const { return nz_; }

  /** \brief Number of yaw layers (odd; 1 = translation only, the default) and their spacing
   * [rad] (default 5°). Layers are centred on the guess's yaw. */
  void setYawSamples(int samples) { yaw_samples_ = samples; }
  int getYawSamples() const { return yaw_samples_; }
  void setYawStep(float step) { yaw_step_ = step; }
  float getYawStep() const { return yaw_step_; }

  /** \brief Correlate every yaw layer over the whole translation window (default false: only
   * the middle layer covers the whole window; the others are evaluated around its peak and
   * grown by hill climbing, several times faster with the same result when the turn does not
   * move the peak by more than a few cells, which it cannot since layers turn about the source
   * centroid). */
  void setFullYawWindow(bool full) { full_yaw_window_ = full; }
  bool getFullYawWindow() const { return full_yaw_window_; }

  /** \brief Coarse-to-fine translation search (default true): the middle yaw layer is
   * searched over the whole window on 2 × 2-binned densities (0.4 m cells for the default
   * 0.2 m) at every second shift, then at full resolution in ±2-cell blocks around the best
   * three coarse maxima, and grown by hill climbing like the other layers. About a tenth of the
   * multiply-adds of the full window; the optimum is the full search's unless the binned surface
   * ranks the true peak below three others (see docs/registration.md). Yaw layers beyond the
   * middle one's neighbours are only built when the hill climbing reaches them, which can miss
   * a better yaw when B(yaw) has two maxima (0.5 % of simulated pairs). Not used when
   * setFullYawWindow() is set, the FFT is forced, or the window is under ±6 cells. false: the
   * exact full-window search. getSimilaritySurface() then holds 0 where nothing was evaluated. */
  void setCoarseToFine(bool coarse_to_fine) { coarse_to_fine_ = coarse_to_fine; }
  bool getCoarseToFine() const { return coarse_to_fine_; }

  /** \brief How the similarity over the whole translation window is computed: `Auto` (the
   * default) picks the cheaper of the two by a cost model measured on this code (see
   * docs/registration.md); `Direct` sums over the non-zero source cells; `FFT` multiplies
   * spectra (Eigen's FFT module, kissfft), the target's spectra being cached per content. Both
   * give the same surface up to float rounding. */
  enum class CorrelationMethod { Auto, Direct, FFT };
  void setCorrelationMethod(CorrelationMethod method) { correlation_method_ = method; }
  CorrelationMethod getCorrelationMethod() const { return correlation_method_; }
  /** \brief The method the last align() used for the whole window (Direct or FFT). */
  CorrelationMethod getLastCorrelationMethod() const { return last_method_; }

  /** \brief Sub-cell re-centring passes (default 2). After the quadratic fit (of log B), the source
   * density is rebuilt at the fitted (fractional) motion and the 3×3 (×3 yaw) neighbourhood is
   * evaluated and fitted again, so the fit is made on samples symmetric about the peak. A fit on
   * samples at an arbitrary sub-cell phase is biased by up to ~0.15 m on the sharp, ridge-shaped
   * peaks of near vehicles (0.2 m cells); 0 switches it off (the paper's single fit). A pass
   * whose correction is under kRecentreTolerance (cells, yaw steps) ends the re-centring. */
  void setSubCellIterations(int iterations) { sub_cell_iterations_ = iterations; }
  int getSubCellIterations() const { return sub_cell_iterations_; }

  /** \brief σ = max(min sigma, sigma per metre · range) of each point's Gaussian. */
  void setSigmaPerMetre(float sigma_per_metre) { sigma_per_metre_ = sigma_per_metre; }
  float getSigmaPerMetre() const { return sigma_per_metre_; }
  void setMinSigma(float min_sigma) { min_sigma_ = min_sigma; }
  float getMinSigma() const { return min_sigma_; }

  /** \brief Returns of other objects (occluders) in the source's scan, and in the target's
   * scan, in the frame of the respective cloud (e.g. the scan points in front of the object).
   * When either is set, a converged align() is followed by a second, local search (±1 m, at
   * most the search radius) on the two views reduced to what both could see: source points that
   * the target's occluders would hide at the first estimate, and target points that the source's
   * occluders would hide, are left out (a return counts as an occluder of a point when it lies in
   * the point's direction, seen from that scan's sensor, ≥ 0.3 m closer; points next to the
   * edge of their own scan's occluders go too, so that both views end at the same edge). The
   * pass is repeated (up to 5 times) while the estimate moves by ≥ 1 cm. A static occluder cuts
   * the object at the same place in both scans, which otherwise pulls the estimate towards no
   * motion. Target culling needs a target cloud (not setTargetDensity()). The first result stands
   * when the second search does not converge. nullptr (the default) switches a side off. */
  void setSourceOccluders(const PointCloudSourceConstPtr& occluders) {
    source_occluders_ = occluders;
  }
  PointCloudSourceConstPtr getSourceOccluders() const { return source_occluders_; }
  void setTargetOccluders(const PointCloudTargetConstPtr& occluders) {
    target_occluders_ = occluders;
  }
  PointCloudTargetConstPtr getTargetOccluders() const { return target_occluders_; }

  /** \brief Points (of the source, and of a target cloud) closer together than a cube of
   * fraction · min σ are merged into one moment-matched Gaussian before the densities are built
   * (SurfaceDensity::mergeGaussians()): near objects have many points per σ, and every yaw layer
   * and refinement step rasterises them all. The densities change by O(fraction⁴) relative.
   * 0 switches merging off. Default 1 (see docs/benchmarks.md). */
  void setMergeFraction(float fraction) { merge_fraction_ = fraction; }
  float getMergeFraction() const { return merge_fraction_; }

  /** \brief B below this means "no match": hasConverged() is false (default 0.2). */
  void setMinSimilarity(float min_similarity) { min_similarity_ = min_similarity; }
  float getMinSimilarity() const { return min_similarity_; }

  /** \brief Also search vertical shifts of ± setSearchRadiusZ() (default off: vehicles stay on
   * the ground and a z search costs a factor of the number of z shifts). */
  void setSearchZ(bool search_z) { search_z_ = search_z; }
  bool getSearchZ() const { return search_z_; }
  void setSearchRadiusZ(float radius_z) { search_radius_z_ = radius_z; }
  float getSearchRadiusZ() const { return search_radius_z_; }

  /** \brief Sensor position used for the ranges of both clouds' points (same frame as the
   * points). Without it each cloud's own `sensor_origin_` is used. */
  void setSensorOrigin(const Eigen::Vector3f& origin) {
    sensor_origin_ = origin;
    use_sensor_origin_ = true;
  }
  /** \brief Back to each cloud's `sensor_origin_`. */
  void clearSensorOrigin() { use_sensor_origin_ = false; }
  Eigen::Vector3f getSensorOrigin() const { return sensor_origin_; }
  bool hasSensorOrigin() const { return use_sensor_origin_; }

 protected:
  using Base::converged_;
  using Base::final_transformation_;
  using Base::indices_;
  using Base::input_;
  using Base::previous_transformation_;
  using Base::reg_name_;
  using Base::target_;
  using Base::transformation_;

  void computeTransformation(PointCloudSource& output, const Matrix4& guess) override;

  /** \brief The search of align() from `guess` over ±radius: sets the final transformation,
   * similarity, surface and source density. `source_keep` (per index of indices_) leaves source
   * points out, `target_override` replaces the target density. */
  void search(const Matrix4& guess, float radius, const std::vector<char>* source_keep,
              const SurfaceDensity* target_override);
  /** \brief The second, local search on the mutually visible parts (see setSourceOccluders()). */
  void occlusionPass();
  static constexpr float kOcclusionRadius = 1.0f;
  /** Each pass culls at the last estimate, and the views culled at an estimate short of (or
   * beyond) the motion still leave a plateau of B between it and the motion, whose middle the fit
   * takes: the error about halves per pass. 3 passes left 0.12 m of a 0.44 m first error in the
   * unit test's scene; 5 and 8 gained 15 and 16 of 2700 simulated trials over 3. */
  static constexpr int kOcclusionPasses = 5;
  /** Coarse-to-fine search: coarse maxima verified at full resolution, smallest window. */
  static constexpr int kCoarsePeaks = 3;
  static constexpr int kCoarseMinRadius = 6;
  /** Re-centring stops after a pass that moved the fit by less than this (cells or yaw steps:
   * 1 cm, 0.25 deg at the defaults). Measured on the simulated pairs of bench_registration, a
   * second pass after a smaller correction left success and median error unchanged at every
   * tolerance up to 0.1 (0.02 before: 6 % more time for the same results). */
  static constexpr float kRecentreTolerance = 0.05f;
  /** Samples below this B enter the log-B peak fit as this value (no log of 0). */
  static constexpr float kLogFloor = 1e-6f;

  /** \brief The target's density: the one set with setTargetDensity(), or the one built from
   * target_ (kept between calls while the cloud and the grid parameters stay the same). Null
   * when it is empty or the target has < 2 finite points. */
  const SurfaceDensity* targetDensity();
  /** \brief `density` ← the Gaussians of `points` merged as set by setMergeFraction(). */
  void buildDensity(SurfaceDensity& density, const std::vector<Eigen::Vector3f>& points,
                    const std::vector<float>& sigmas, const Eigen::Vector3f& centre);

  float search_radius_ = 2.0f;
  float resolution_ = 0.2f;
  int nx_ = 29, ny_ = 29, nz_ = 7;
  float grid_height_ = 2.8f;
  int yaw_samples_ = 1;
  float yaw_step_ = 0.0872664626f;  // 5 degrees
  float sigma_per_metre_ = 0.003f;
  float min_sigma_ = 0.1f;
  float min_similarity_ = 0.2f;
  float merge_fraction_ = 1.0f;
  bool search_z_ = false;
  bool full_yaw_window_ = false;
  bool coarse_to_fine_ = true;
  bool compute_source_density_ = false;
  float search_radius_z_ = 0.4f;
  Eigen::Vector3f sensor_origin_ = Eigen::Vector3f::Zero();
  bool use_sensor_origin_ = false;
  CorrelationMethod correlation_method_ = CorrelationMethod::Auto;
  CorrelationMethod last_method_ = CorrelationMethod::Direct;
  int sub_cell_iterations_ = 2;
  PointCloudSourceConstPtr source_occluders_;
  PointCloudTargetConstPtr target_occluders_;
  /** Buffers, FFT plans and the target caches reused between align() calls (no heap traffic
   * per call once warm); shared by copies of this object, and handed on to the next object
   * created on the thread when this one is destroyed (see detail::acquireWorkspace()). */
  std::shared_ptr<detail::BhattacharyaWorkspace> work_;

  SurfaceDensity::ConstPtr target_density_;
  SurfaceDensity::Ptr source_density_;
  float similarity_ = 0.f;
  SimilaritySurface surface_;
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/bhattacharya_registration.hpp>
#endif
