/*
 * Surface density of one object: a mixture of 3D Gaussians (one per point) discretized to a grid,
 * after Morris, Colonna, Haley, "Ladar-based mover detection from moving vehicles", section 5.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/pcl_macros.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pcl_movers {

/** \brief The discretized surface density ρ_DS of one object (paper eq. 1 and 3).
 *
 * A regular 3D grid of nx × ny × nz cells, cell size `resolution` in x/y and `resolution_z` in z,
 * whose centre (the middle of the middle cell for odd sizes) sits on the world point `centre`.
 * compute() places one Gaussian per point with σ = max(min_sigma, sigma_per_metre · range), range
 * being the point's distance from the sensor: the paper's "covariance proportional to the sampling
 * density". Each Gaussian carries mass 1/n and is integrated exactly over the cells (separable
 * erf differences, truncated at ±3σ), so the grid sums to 1 when the object lies inside it; mass
 * falling outside the grid is lost, which keeps the Bhattacharyya similarity
 * B = Σ sqrt(ρ_a)·sqrt(ρ_b) in [0,1].
 *
 * Models follow their objects by moving the grid, not the data: translate() shifts `centre` and
 * the content moves with it exactly (an object-centred frame). shifted() is the other option, it
 * resamples the content by a world offset while the grid stays put (linear interpolation between
 * cells, so it blurs slightly for fractional offsets).
 *
 * Cell (ix, iy, iz) has its centre at
 * centre + ((ix - (nx-1)/2)·resolution, (iy - (ny-1)/2)·resolution, (iz - (nz-1)/2)·resolution_z);
 * values are stored x fastest: index = (iz·ny + iy)·nx + ix.
 */
class SurfaceDensity {
 public:
  using Ptr = pcl::shared_ptr<SurfaceDensity>;
  using ConstPtr = pcl::shared_ptr<const SurfaceDensity>;

  /** \brief The paper's 29×29×7 grid with 0.2 m cells in x/y and 0.4 m in z (5.8 × 5.8 × 2.8 m). */
  SurfaceDensity() { resize(29, 29, 7); }
  SurfaceDensity(int nx, int ny, int nz, float resolution, float resolution_z)
      : resolution_(resolution), resolution_z_(resolution_z) {
    resize(nx, ny, nz);
  }

  /** \brief Sets the grid size in cells (each ≥ 1) and clears the content. */
  void setGridSize(int nx, int ny, int nz) { resize(nx, ny, nz); }
  int getNx() const { return nx_; }
  int getNy() const { return ny_; }
  int getNz() const { return nz_; }
  std::size_t size() const { return data_.size(); }

  /** \brief Cell size in x and y [m]. */
  void setResolution(float resolution) { resolution_ = resolution; }
  float getResolution() const { return resolution_; }
  /** \brief Cell size in z [m]; large values give the paper's "reduced vertical resolution". */
  void setResolutionZ(float resolution_z) { resolution_z_ = resolution_z; }
  float getResolutionZ() const { return resolution_z_; }

  /** \brief σ per metre of range from the sensor (default 0.003: the best registration results
   * on the simulated pairs, docs/registration.md; the HDL-64E beam spacing is ~0.007 rad
   * vertically, 0.003 rad horizontally). */
  void setSigmaPerMetre(float sigma_per_metre) { sigma_per_metre_ = sigma_per_metre; }
  float getSigmaPerMetre() const { return sigma_per_metre_; }
  /** \brief Lower bound on σ [m] (default 0.1): keeps near points from becoming spikes. */
  void setMinSigma(float min_sigma) { min_sigma_ = min_sigma; }
  float getMinSigma() const { return min_sigma_; }

  /** \brief Identifies the content (values and grid size): a new value, unique in the process,
   * after every change of the values; copies share it with their original (same content).
   * Moving the grid (translate(), setCentre()) keeps it. Lets users cache what they derive from
   * the values (BhattacharyaRegistration caches the target's spectra and non-zero cells). */
  std::uint64_t revision() const { return revision_; }

  /** \brief World point at the middle of the grid. */
  void setCentre(const Eigen::Vector3f& centre) { centre_ = centre; }
  const Eigen::Vector3f& getCentre() const { return centre_; }

  /** \brief Builds the density of `cloud` on a grid centred at `centre`. NaN/Inf points are
   * skipped; an empty cloud gives an all-zero grid (total mass 0). */
  template <typename PointT>
  void compute(const pcl::PointCloud<PointT>& cloud, const Eigen::Vector3f& sensor_origin,
               const Eigen::Vector3f& centre);

  /** \brief Same, with explicit per-point σ [m] (σ.size() == points.size()); points with a
   * non-finite coordinate or σ ≤ 0 are skipped. The core the templated compute() calls. */
  void computeFromPoints(const std::vector<Eigen::Vector3f>& points,
                         const std::vector<float>& sigmas, const Eigen::Vector3f& centre);

  /** \brief The general core: Gaussian i at points[i] with σ sigmas_xy[i] in x and y and
   * sigmas_z[i] in z, carrying mass weights[i] / Σ weights (1/n each when `weights` is empty).
   * Gaussians with a non-finite coordinate, σ ≤ 0 or weight ≤ 0 are skipped. Takes what
   * mergeGaussians() produces. */
  void computeFromGaussians(const std::vector<Eigen::Vector3f>& points,
                            const std::vector<float>& sigmas_xy, const std::vector<float>& sigmas_z,
                            const std::vector<float>& weights, const Eigen::Vector3f& centre);

  /** \brief Merges the points of each cube of edge `cell` [m] (a lattice fixed in the frame of
   * the points) into one Gaussian with the same mass, mean and second moments: weight = number
   * of points, mean = their mean, σ_z² = mean σ² + variance in z, σ_xy² = mean σ² + mean of the
   * variances in x and y (isotropic in x/y, so turning about z keeps it exact). The density
   * changes only by the fourth moments, O((cell/σ)⁴) relative: with cell ≤ σ a near object's
   * hundreds of points become a fraction as many Gaussians at no visible cost (see
   * BhattacharyaRegistration::setMergeFraction()). Invalid points (non-finite or σ ≤ 0) are
   * dropped; the output order is that of each cube's first point (deterministic). cell ≤ 0
   * copies the points as they are. */
  static void mergeGaussians(const std::vector<Eigen::Vector3f>& points,
                             const std::vector<float>& sigmas, float cell,
                             std::vector<Eigen::Vector3f>& out_points,
                             std::vector<float>& out_sigmas_xy, std::vector<float>& out_sigmas_z,
                             std::vector<float>& out_weights);

  /** \brief Gaussians prepared for repeated rasterisation while only their horizontal positions
   * change (the yaw layers and shifts of a registration): per Gaussian the horizontal constants
   * and the vertical cell weights (times its mass) are computed once by prepareGaussians(), so
   * computeFromPrepared() evaluates two axes per Gaussian instead of three. */
  struct PreparedGaussians {
    float resolution = 0.f;       ///< horizontal cell size the constants are for [m]
    float resolution_z = 0.f;     ///< vertical cell size [m]
    float z0 = 0.f;               ///< lower bound of vertical lattice cell 0 [m]
    int z_min = 0, z_max = -1;    ///< lattice z cells holding any weight
    std::vector<int> index;       ///< input position of each prepared Gaussian
    std::vector<float> a_xy;      ///< resolution / (√2 σ_xy)
    std::vector<float> reach_xy;  ///< 3 σ_xy / resolution (the ±3σ window)
    std::vector<int> z_first;     ///< lattice z cell of the first vertical weight
    std::vector<int> z_begin;     ///< weights of Gaussian k: wz[z_begin[k] .. z_begin[k + 1])
    std::vector<float> wz;        ///< vertical weights × normalised mass
    bool empty() const { return index.empty(); }
  };

  /** \brief Prepares the (valid) Gaussians of computeFromGaussians() for a vertical lattice of
   * cells `resolution_z` whose cell 0 starts at height z0, its weights clipped to the lattice
   * cells [z_lo, z_hi]; `resolution` is the horizontal cell size of the grids it will be
   * rasterised into. Only the z coordinates of `points` are used. */
  static void prepareGaussians(const std::vector<Eigen::Vector3f>& points,
                               const std::vector<float>& sigmas_xy,
                               const std::vector<float>& sigmas_z,
                               const std::vector<float>& weights, float resolution,
                               float resolution_z, float z0, int z_lo, int z_hi,
                               PreparedGaussians& out);

  /** \brief computeFromGaussians() for prepared Gaussians at the horizontal positions
   * points[index[k]] (their z is ignored: the prepared vertical weights stand). The grid's
   * resolutions must be the prepared ones and its vertical cells on the prepared lattice (the
   * grid's lowest cell is the lattice cell nearest to it); same result as computeFromGaussians()
   * up to float rounding, mass outside [z_lo, z_hi] of the preparation being lost. Throws
   * std::invalid_argument on other resolutions. */
  void computeFromPrepared(const PreparedGaussians& prepared,
                           const std::vector<Eigen::Vector3f>& points,
                           const Eigen::Vector3f& centre);

  /** \brief σ the density would use for a point at `range` metres. */
  float sigmaAtRange(float range) const;

  /** \brief model ← (1 - w)·model + w·view. Both grids must have the same size and resolutions;
   * when the centres differ the view is first resampled onto this grid (shifted()). An empty
   * model (mass 0) simply takes the view. w ∈ [0,1]; use halfLifeWeight() for a decay with a
   * half-life in frames. Throws std::invalid_argument on mismatched grids. */
  void accumulate(const SurfaceDensity& view, float weight_of_new);

  /** \brief w = 1 - 0.5^(1/half_life_frames): the weight of each new view such that an old
   * view's weight halves every `half_life_frames` accumulations. */
  static float halfLifeWeight(float half_life_frames);

  /** \brief Moves the grid (and with it the content) by `offset` [m]: exact, no resampling. */
  void translate(const Eigen::Vector3f& offset) { centre_ += offset; }

  /** \brief A copy whose content is moved by `offset` [m] while the grid stays where it is
   * (trilinear resampling; mass moved outside the grid is lost). */
  SurfaceDensity shifted(const Eigen::Vector3f& offset) const;

  /** \brief Density value of a cell. */
  float at(int ix, int iy, int iz) const { return data_[index(ix, iy, iz)]; }
  /** \brief Square root of the density of a cell (what the Bhattacharyya sum uses). */
  float sqrtAt(int ix, int iy, int iz) const { return sqrt_[index(ix, iy, iz)]; }
  std::size_t index(int ix, int iy, int iz) const {
    return (static_cast<std::size_t>(iz) * ny_ + iy) * nx_ + ix;
  }
  /** \brief All values (x fastest, see class doc). */
  const std::vector<float>& values() const { return data_; }
  /** \brief Square roots of all values, kept up to date with values(). */
  const std::vector<float>& sqrtValues() const { return sqrt_; }

  /** \brief World position of a cell centre. */
  Eigen::Vector3f cellCentre(int ix, int iy, int iz) const;

  /** \brief Σ ρ over the grid: 1 when every Gaussian lies inside, less when mass fell outside.
   * Kept with the values (computed once per change, not per call: registrations ask for it on
   * every align()). */
  float totalMass() const { return mass_; }
  /** \brief True when the grid holds no mass. */
  bool empty() const { return totalMass() <= 0.f; }

  /** \brief Bhattacharyya similarity Σ sqrt(ρ_a)·sqrt(ρ_b) of two densities on identical grids
   * (sizes, resolutions and centre); in [0,1]. Throws std::invalid_argument on mismatch. */
  static float bhattacharyya(const SurfaceDensity& a, const SurfaceDensity& b);

  /** \brief Sets all values to zero. */
  void clear();

  /** \brief Replaces the content (same size as size(); negative values clamp to 0). */
  void setValues(const std::vector<float>& values);

 private:
  void resize(int nx, int ny, int nz);
  void updateSqrt();
  static std::uint64_t nextRevision();

  int nx_ = 0, ny_ = 0, nz_ = 0;
  float resolution_ = 0.2f;
  float resolution_z_ = 0.4f;
  float sigma_per_metre_ = 0.003f;
  float min_sigma_ = 0.1f;
  Eigen::Vector3f centre_ = Eigen::Vector3f::Zero();
  std::vector<float> data_;
  std::vector<float> sqrt_;
  std::uint64_t revision_ = 0;
  float mass_ = 0.f;
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/surface_density.hpp>
#endif
