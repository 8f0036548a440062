/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/surface_density.h>
#include <pcl_movers/impl/surface_density.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace pcl_movers {

namespace {

/** erf by linear interpolation in a table of std::erf at steps of 1/512 over [0, 5] (error
 * ≤ h²/8·max|erf''| ≈ 5e-7 absolute, below the float resolution of the cell weights; erf(5) is
 * 1 - 1.5e-12). No exp per call: the density build calls it ~15 times per point and it was, as
 * the previous rational approximation with one exp, a third of a 5-yaw registration's time. */
class ErfTable {
 public:
  static constexpr int kPerUnit = 512;
  static constexpr float kMax = 5.f;
  ErfTable() {
    float v[kSize + 1];
    for (int i = 0; i <= kSize; ++i)
      v[i] = static_cast<float>(std::erf(static_cast<double>(i) / kPerUnit));
    // Each entry holds the value and the step to the next one, side by side: one 8-byte load
    // per lookup instead of two scattered ones (the steps are the same float differences the
    // interpolation would compute, so the results do not change).
    for (int i = 0; i < kSize; ++i) {
      vd_[2 * i] = v[i];
      vd_[2 * i + 1] = v[i + 1] - v[i];
    }
  }
  float operator()(float x) const {
    const float ax = std::abs(x) * kPerUnit;
    float y = 1.f;
    if (ax < kMax * kPerUnit) {
      const int i = static_cast<int>(ax);
      const float f = ax - static_cast<float>(i);
      y = vd_[2 * i] + f * vd_[2 * i + 1];
    }
    return x < 0.f ? -y : y;
  }
#ifdef __SSE2__
  /** operator() on four values at once, with the same float operations (bit-identical). */
  __m128 eval4(__m128 x) const {
    const __m128 sign = _mm_set1_ps(-0.f);
    const __m128 ax = _mm_mul_ps(_mm_andnot_ps(sign, x), _mm_set1_ps(static_cast<float>(kPerUnit)));
    const __m128 inside = _mm_cmplt_ps(ax, _mm_set1_ps(kMax * kPerUnit));
    // Indices outside the table (and NaN) read entry 0; their result is replaced by 1 below.
    const __m128i i = _mm_and_si128(_mm_cvttps_epi32(ax), _mm_castps_si128(inside));
    alignas(16) int idx[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(idx), i);
    const auto pair = [this](int k) {
      return reinterpret_cast<const __m64*>(vd_ + 2 * static_cast<std::ptrdiff_t>(k));
    };
    const __m128 p01 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), pair(idx[0])), pair(idx[1]));
    const __m128 p23 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), pair(idx[2])), pair(idx[3]));
    const __m128 a = _mm_shuffle_ps(p01, p23, _MM_SHUFFLE(2, 0, 2, 0));
    const __m128 d = _mm_shuffle_ps(p01, p23, _MM_SHUFFLE(3, 1, 3, 1));
    const __m128 f = _mm_sub_ps(ax, _mm_cvtepi32_ps(i));
    __m128 y = _mm_add_ps(a, _mm_mul_ps(f, d));
    y = _mm_or_ps(_mm_and_ps(inside, y), _mm_andnot_ps(inside, _mm_set1_ps(1.f)));
    return _mm_xor_ps(y, _mm_and_ps(_mm_cmplt_ps(x, _mm_setzero_ps()), sign));
  }
#endif

 private:
  static constexpr int kSize = static_cast<int>(kMax) * kPerUnit + 1;
  alignas(16) float vd_[2 * kSize];
};

// At namespace scope (built before main()): a function-local static would cost a guard check on
// every one of the ~10^4 calls per registration.
const ErfTable g_erf_table;

inline float fastErf(float x) {
  return g_erf_table(x);
}

/** Weights of a 1D Gaussian (mean `mean`, σ `sigma`) integrated over the cells [first, last] of an
 * axis whose cell 0 starts at `origin`, cell size `cell`. The window is ±3σ (at least the cell
 * holding the mean) and the weights are renormalised over the whole window *before* clipping to
 * the grid, so a Gaussian inside the grid has mass exactly 1 while mass outside is lost. */
struct AxisWeights {
  int first = 0;  // first grid cell with a weight
  int count = 0;  // number of cells with a weight (0: the Gaussian misses the grid)
  float* w = inline_w;
  // Windows of up to 127 cells (σ up to ~20 cells) need no heap: the vector's resize and its
  // zero fill cost as much as the erf evaluations.
  float inline_w[128];
  std::vector<float> heap_w;
  AxisWeights() = default;
  AxisWeights(const AxisWeights&) = delete;
  AxisWeights& operator=(const AxisWeights&) = delete;
  /** Room for n values in w. */
  void reserve(int n) {
    if (n <= 128) {
      w = inline_w;
    } else {
      heap_w.resize(static_cast<std::size_t>(n));
      w = heap_w.data();
    }
  }
};

void axisWeights(float mean, float sigma, float origin, float cell, int n, AxisWeights& out) {
  out.count = 0;
  out.first = 0;
  const float u = (mean - origin) / cell;  // position in cells
  const float reach = 3.f * sigma / cell;
  // The window bounds stay in float until they are known to overlap the grid: a point far away
  // (or a huge σ) gives bounds no int can hold (found by fuzz_pcd_pipeline).
  const float lo = std::floor(u - reach);
  const float hi = std::floor(u + reach);
  if (!std::isfinite(lo) || !std::isfinite(hi) || hi < 0.f || lo > static_cast<float>(n - 1))
    return;
  const float inv = 1.f / (std::sqrt(2.f) * sigma);
  const int first = static_cast<int>(std::max(lo, 0.f));
  const int last = static_cast<int>(std::min(hi, static_cast<float>(n - 1)));
  out.first = first;
  if (last < first) return;
  // erf at the cell boundaries first .. last + 1, written into w (one more than the cells).
  const int count = last - first + 2;
  out.reserve(count + 3);  // the four-wide loop may write up to three values past the end
  float* e = out.w;
  int k = 0;
#ifdef __SSE2__
  {
    const __m128 vc = _mm_set1_ps(cell), vo = _mm_set1_ps(origin), vm = _mm_set1_ps(mean),
                 vi = _mm_set1_ps(inv);
    for (; k < count; k += 4) {
      const __m128 fi =
          _mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(first + k), _mm_setr_epi32(0, 1, 2, 3)));
      const __m128 x = _mm_mul_ps(_mm_sub_ps(_mm_add_ps(_mm_mul_ps(fi, vc), vo), vm), vi);
      _mm_storeu_ps(e + k, g_erf_table.eval4(x));
    }
  }
#endif
  for (; k < count; ++k)
    e[k] = fastErf((static_cast<float>(first + k) * cell + origin - mean) * inv);
  // Mass of the whole window, to normalise: the per-cell weights are differences of erf, so their
  // sum telescopes to the two window ends, which are boundaries evaluated above unless the
  // window is clipped by the grid (the same expressions: identical values).
  const float e_lo =
      lo == static_cast<float>(first) ? e[0] : fastErf((lo * cell + origin - mean) * inv);
  const float e_hi = hi == static_cast<float>(last)
                         ? e[last - first + 1]
                         : fastErf(((hi + 1.f) * cell + origin - mean) * inv);
  const float total = 0.5f * (e_hi - e_lo);
  if (!(total > 0.f)) return;
  for (int k = 0; k <= last - first; ++k) e[k] = 0.5f * (e[k + 1] - e[k]) / total;
  out.count = last - first + 1;
}

}  // namespace

std::uint64_t SurfaceDensity::nextRevision() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

void SurfaceDensity::resize(int nx, int ny, int nz) {
  if (nx < 1 || ny < 1 || nz < 1)
    throw std::invalid_argument("SurfaceDensity: grid size must be at least 1x1x1, got " +
                                std::to_string(nx) + "x" + std::to_string(ny) + "x" +
                                std::to_string(nz));
  nx_ = nx;
  ny_ = ny;
  nz_ = nz;
  data_.assign(static_cast<std::size_t>(nx) * ny * nz, 0.f);
  sqrt_.assign(data_.size(), 0.f);
  mass_ = 0.f;
  revision_ = nextRevision();
}

void SurfaceDensity::clear() {
  std::fill(data_.begin(), data_.end(), 0.f);
  std::fill(sqrt_.begin(), sqrt_.end(), 0.f);
  mass_ = 0.f;
  revision_ = nextRevision();
}

void SurfaceDensity::updateSqrt() {
  // Every change of the values ends here: a new revision for caches keyed on the content.
  revision_ = nextRevision();
  sqrt_.resize(data_.size());
  const std::size_t n = data_.size();
  const float* d = data_.data();
  float* q = sqrt_.data();
  std::size_t i = 0;
  double mass = 0.0;
#ifdef __SSE2__
  // Four cells per step: sqrtps rounds exactly as std::sqrt (which the compiler keeps scalar for
  // errno), and the mass goes to four double sums instead of one serial chain of additions
  // (the two loops were a tenth of a registration's time).
  __m128d m01 = _mm_setzero_pd(), m23 = _mm_setzero_pd();
  for (; i + 4 <= n; i += 4) {
    const __m128 v = _mm_loadu_ps(d + i);
    _mm_storeu_ps(q + i, _mm_sqrt_ps(v));
    m01 = _mm_add_pd(m01, _mm_cvtps_pd(v));
    m23 = _mm_add_pd(m23, _mm_cvtps_pd(_mm_movehl_ps(v, v)));
  }
  double part[2];
  _mm_storeu_pd(part, _mm_add_pd(m01, m23));
  mass = part[0] + part[1];
#endif
  for (; i < n; ++i) {
    q[i] = std::sqrt(d[i]);
    mass += d[i];
  }
  mass_ = static_cast<float>(mass);
}

void SurfaceDensity::setValues(const std::vector<float>& values) {
  if (values.size() != data_.size())
    throw std::invalid_argument("SurfaceDensity::setValues: expected " +
                                std::to_string(data_.size()) + " values, got " +
                                std::to_string(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i)
    data_[i] = std::isfinite(values[i]) ? std::max(values[i], 0.f) : 0.f;
  updateSqrt();
}

float SurfaceDensity::sigmaAtRange(float range) const {
  return std::max(min_sigma_, sigma_per_metre_ * range);
}

Eigen::Vector3f SurfaceDensity::cellCentre(int ix, int iy, int iz) const {
  return centre_ + Eigen::Vector3f((ix - 0.5f * (nx_ - 1)) * resolution_,
                                   (iy - 0.5f * (ny_ - 1)) * resolution_,
                                   (iz - 0.5f * (nz_ - 1)) * resolution_z_);
}

void SurfaceDensity::computeFromPoints(const std::vector<Eigen::Vector3f>& points,
                                       const std::vector<float>& sigmas,
                                       const Eigen::Vector3f& centre) {
  if (points.size() != sigmas.size())
    throw std::invalid_argument("SurfaceDensity::computeFromPoints: points and sigmas differ");
  static const std::vector<float> kNoWeights;
  computeFromGaussians(points, sigmas, sigmas, kNoWeights, centre);
}

void SurfaceDensity::computeFromGaussians(const std::vector<Eigen::Vector3f>& points,
                                          const std::vector<float>& sigmas_xy,
                                          const std::vector<float>& sigmas_z,
                                          const std::vector<float>& weights,
                                          const Eigen::Vector3f& centre) {
  if (points.size() != sigmas_xy.size() || points.size() != sigmas_z.size() ||
      (!weights.empty() && weights.size() != points.size()))
    throw std::invalid_argument(
        "SurfaceDensity::computeFromGaussians: points, sigmas and weights differ in size");
  if (!(resolution_ > 0.f) || !(resolution_z_ > 0.f))
    throw std::invalid_argument("SurfaceDensity: resolutions must be positive");
  // The vertical weights on this grid's own z cells, then the horizontal pass of
  // computeFromPrepared(): one rasterisation code path for every density.
  thread_local PreparedGaussians prepared;
  const float z0 = centre.z() - 0.5f * static_cast<float>(nz_) * resolution_z_;
  prepareGaussians(points, sigmas_xy, sigmas_z, weights, resolution_, resolution_z_, z0, 0, nz_ - 1,
                   prepared);
  computeFromPrepared(prepared, points, centre);
}

namespace {
/** std::floor for |x| < 2^22 without the libm call that SSE2 code gets for it (a tenth of
 * preparedAxisWeights()): truncate, then step down where truncation rounded up. */
inline float floorSmall(float x) {
  const float t = static_cast<float>(static_cast<int>(x));
  return t > x ? t - 1.f : t;
}

/** axisWeights() for a Gaussian at u cells from the lower bound of cell 0, with a = cell / (√2 σ)
 * and reach = 3σ / cell precomputed, over cells [0, n - 1]: the same window, but the weights are
 * left unnormalised (differences of erf) and the window's mass (their normaliser) is returned in
 * `total`, for the caller to fold into its product (one division per Gaussian, not per axis). `e`
 * needs room for n + 8 values and gets zeros from the returned count up to the next multiple of
 * four. Returns the number of cells (0: the Gaussian misses). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline int
preparedAxisWeights(float u, float a, float reach, int n, int& first, float* e, float& total) {
  const float a_lo = u - reach, a_hi = u + reach;
  // Written so that NaN and infinite positions fail too.
  if (!(a_hi >= 0.f) || !(a_lo < static_cast<float>(n))) return 0;
  constexpr float kSmall = 4194304.f;  // 2^22
  const bool small = a_lo > -kSmall && a_hi < kSmall;
  const float lo = small ? floorSmall(a_lo) : std::floor(a_lo);
  const float hi = small ? floorSmall(a_hi) : std::floor(a_hi);
  first = static_cast<int>(std::max(lo, 0.f));
  const int last = static_cast<int>(std::min(hi, static_cast<float>(n - 1)));
  const int cells = last - first + 1;
  const int count = cells + 1;       // boundaries
  float e_first = 0.f, e_end = 0.f;  // erf at the first and the last boundary
  // Longer windows: the boundaries in e, then differences in place.
  auto inMemory = [&](int k) {  // boundaries before k are written already
    for (; k < count; ++k) e[k] = fastErf((static_cast<float>(first + k) - u) * a);
    e_first = e[0];
    e_end = e[cells];
    for (k = 0; k < cells; ++k) e[k] = e[k + 1] - e[k];
    for (k = cells; k < ((cells + 3) & ~3); ++k) e[k] = 0.f;
  };
#ifdef __SSE2__
  const __m128 va = _mm_set1_ps(a), vu = _mm_set1_ps(u);
  auto boundaries = [&](int k) {
    const __m128 fi =
        _mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(first + k), _mm_setr_epi32(0, 1, 2, 3)));
    return g_erf_table.eval4(_mm_mul_ps(_mm_sub_ps(fi, vu), va));
  };
  if (count <= 8) {
    // The usual window (σ up to about one cell): the boundaries stay in two registers and the
    // differences come from shuffles, without a round trip through memory.
    const __m128 v0 = boundaries(0);
    const __m128 v1 = count > 4 ? boundaries(4) : _mm_setzero_ps();
    // [e1 e2 e3 e4] and [e5 e6 e7 e7]
    const __m128 s0 =
        _mm_shuffle_ps(_mm_move_ss(v0, v1), _mm_move_ss(v0, v1), _MM_SHUFFLE(0, 3, 2, 1));
    const __m128 s1 = _mm_shuffle_ps(v1, v1, _MM_SHUFFLE(3, 3, 2, 1));
    const __m128i nc = _mm_set1_epi32(cells);
    const __m128 m0 = _mm_castsi128_ps(_mm_cmplt_epi32(_mm_setr_epi32(0, 1, 2, 3), nc));
    const __m128 m1 = _mm_castsi128_ps(_mm_cmplt_epi32(_mm_setr_epi32(4, 5, 6, 7), nc));
    _mm_storeu_ps(e, _mm_and_ps(m0, _mm_sub_ps(s0, v0)));
    _mm_storeu_ps(e + 4, _mm_and_ps(m1, _mm_sub_ps(s1, v1)));
    alignas(16) float b[8];
    _mm_store_ps(b, v0);
    _mm_store_ps(b + 4, v1);
    e_first = b[0];
    e_end = b[cells];
  } else {
    int k = 0;
    for (; k + 4 <= count; k += 4) _mm_storeu_ps(e + k, boundaries(k));
    inMemory(k);
  }
#else
  inMemory(0);
#endif
  // Mass of the whole (unclipped) window, to normalise: the weights telescope to its two ends.
  const float e_lo = lo == static_cast<float>(first) ? e_first : fastErf((lo - u) * a);
  const float e_hi = hi == static_cast<float>(last) ? e_end : fastErf((hi + 1.f - u) * a);
  total = e_hi - e_lo;
  if (!(total > 0.f)) return 0;
  return cells;
}
}  // namespace

void SurfaceDensity::prepareGaussians(const std::vector<Eigen::Vector3f>& points,
                                      const std::vector<float>& sigmas_xy,
                                      const std::vector<float>& sigmas_z,
                                      const std::vector<float>& weights, float resolution,
                                      float resolution_z, float z0, int z_lo, int z_hi,
                                      PreparedGaussians& out) {
  if (points.size() != sigmas_xy.size() || points.size() != sigmas_z.size() ||
      (!weights.empty() && weights.size() != points.size()))
    throw std::invalid_argument(
        "SurfaceDensity::prepareGaussians: points, sigmas and weights differ in size");
  if (!(resolution > 0.f) || !(resolution_z > 0.f))
    throw std::invalid_argument("SurfaceDensity: resolutions must be positive");
  out.resolution = resolution;
  out.resolution_z = resolution_z;
  out.z0 = z0;
  out.z_min = std::numeric_limits<int>::max();
  out.z_max = std::numeric_limits<int>::min();
  out.index.clear();
  out.a_xy.clear();
  out.reach_xy.clear();
  out.z_first.clear();
  out.z_begin.assign(1, 0);
  out.wz.clear();
  auto valid = [&](std::size_t i) {
    return points[i].allFinite() && sigmas_xy[i] > 0.f && std::isfinite(sigmas_xy[i]) &&
           sigmas_z[i] > 0.f && std::isfinite(sigmas_z[i]) &&
           (weights.empty() || (weights[i] > 0.f && std::isfinite(weights[i])));
  };
  double total_weight = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (valid(i)) total_weight += weights.empty() ? 1.0 : static_cast<double>(weights[i]);
  if (!(total_weight > 0.0) || z_hi < z_lo) return;
  const float unit_mass = static_cast<float>(1.0 / total_weight);
  // The lattice cells [z_lo, z_hi] as a grid of its own (cell 0 = z_lo) for axisWeights().
  const int nz = z_hi - z_lo + 1;
  const float oz = z0 + static_cast<float>(z_lo) * resolution_z;
  // Sized for every Gaussian and trimmed at the end: stores by index instead of a push_back
  // (with its capacity check) per value; the capacity stays between calls.
  const std::size_t n = points.size();
  out.index.resize(n);
  out.a_xy.resize(n);
  out.reach_xy.resize(n);
  out.z_first.resize(n);
  out.z_begin.resize(n + 1);
  out.wz.resize(n * static_cast<std::size_t>(nz));
  std::size_t m = 0, used = 0;
  const float root2 = std::sqrt(2.f);
  AxisWeights wz;
  for (std::size_t i = 0; i < n; ++i) {
    if (!valid(i)) continue;
    axisWeights(points[i].z(), sigmas_z[i], oz, resolution_z, nz, wz);
    if (wz.count == 0) continue;
    const float mass = weights.empty() ? unit_mass : unit_mass * weights[i];
    out.index[m] = static_cast<int>(i);
    out.a_xy[m] = resolution / (root2 * sigmas_xy[i]);
    out.reach_xy[m] = 3.f * sigmas_xy[i] / resolution;
    out.z_first[m] = z_lo + wz.first;
    for (int k = 0; k < wz.count; ++k) out.wz[used + static_cast<std::size_t>(k)] = mass * wz.w[k];
    used += static_cast<std::size_t>(wz.count);
    out.z_begin[m + 1] = static_cast<int>(used);
    out.z_min = std::min(out.z_min, z_lo + wz.first);
    out.z_max = std::max(out.z_max, z_lo + wz.first + wz.count - 1);
    ++m;
  }
  out.index.resize(m);
  out.a_xy.resize(m);
  out.reach_xy.resize(m);
  out.z_first.resize(m);
  out.z_begin.resize(m + 1);
  out.wz.resize(used);
}

void SurfaceDensity::computeFromPrepared(const PreparedGaussians& g,
                                         const std::vector<Eigen::Vector3f>& points,
                                         const Eigen::Vector3f& centre) {
  if (g.resolution != resolution_ || g.resolution_z != resolution_z_)
    throw std::invalid_argument(
        "SurfaceDensity::computeFromPrepared: prepared for other resolutions");
  centre_ = centre;
  std::fill(data_.begin(), data_.end(), 0.f);
  const float ox = centre.x() - 0.5f * nx_ * resolution_;
  const float oy = centre.y() - 0.5f * ny_ * resolution_;
  // Lattice index of this grid's lowest cell (a grid centred at a non-finite or absurd place
  // gets nothing: the index would not fit an int).
  const double oz_cells =
      std::round((static_cast<double>(centre.z()) - 0.5 * nz_ * resolution_z_ - g.z0) /
                 static_cast<double>(resolution_z_));
  if (!(std::abs(oz_cells) < 1e9) || !std::isfinite(ox) || !std::isfinite(oy)) {
    updateSqrt();
    return;
  }
  const int oz = static_cast<int>(oz_cells);
  const float inv_res = 1.f / resolution_;
  // Cell weights of both axes; room for the grid plus the four-wide loop's overrun.
  thread_local std::vector<float> buf;
  const std::size_t room = static_cast<std::size_t>(std::max(nx_, ny_)) + 8;
  if (buf.size() < 2 * room) buf.resize(2 * room);
  float* __restrict wx = buf.data();
  float* __restrict wy = buf.data() + room;
  for (std::size_t k = 0; k < g.index.size(); ++k) {
    // Vertical cells inside this grid.
    const int z_first = g.z_first[k] - oz;
    const int b = g.z_begin[k], e = g.z_begin[k + 1];
    const int kz0 = std::max(0, -z_first), kz1 = std::min(e - b, nz_ - z_first);
    if (kz1 <= kz0) continue;
    const Eigen::Vector3f& p = points[static_cast<std::size_t>(g.index[k])];
    int fy = 0, fx = 0;
    float total_y = 1.f, total_x = 1.f;
    const int cy =
        preparedAxisWeights((p.y() - oy) * inv_res, g.a_xy[k], g.reach_xy[k], ny_, fy, wy, total_y);
    if (cy == 0) continue;
    const int cx =
        preparedAxisWeights((p.x() - ox) * inv_res, g.a_xy[k], g.reach_xy[k], nx_, fx, wx, total_x);
    if (cx == 0) continue;
    const float scale = 1.f / (total_x * total_y);
#ifdef __SSE2__
    // Rows of four cells: the x weights come padded with zeros to a multiple of four, so the
    // cells past the Gaussian's window (further along the row, or the next row's first cells)
    // get + 0 and keep their values bit for bit. This replaces a short vector loop with a scalar
    // tail, whose branches cost more than the arithmetic for windows of 3-6 cells. A Gaussian
    // whose padding would run past the end of the grid takes the scalar loop below.
    const int cx4 = (cx + 3) & ~3;
    const std::size_t last_row = index(fx, fy + cy - 1, z_first + kz1 - 1);
    if (last_row + static_cast<std::size_t>(cx4) <= data_.size()) {
      const __m128 w0 = _mm_loadu_ps(wx), w1 = _mm_loadu_ps(wx + 4);
      for (int kz = kz0; kz < kz1; ++kz) {
        const float fz = g.wz[static_cast<std::size_t>(b + kz)] * scale;
        float* row = &data_[index(fx, fy, z_first + kz)];
        for (int ky = 0; ky < cy; ++ky, row += nx_) {
          const __m128 f = _mm_set1_ps(fz * wy[ky]);
          _mm_storeu_ps(row, _mm_add_ps(_mm_loadu_ps(row), _mm_mul_ps(f, w0)));
          if (cx4 > 4) {
            _mm_storeu_ps(row + 4, _mm_add_ps(_mm_loadu_ps(row + 4), _mm_mul_ps(f, w1)));
            for (int kx = 8; kx < cx4; kx += 4)
              _mm_storeu_ps(row + kx, _mm_add_ps(_mm_loadu_ps(row + kx),
                                                 _mm_mul_ps(f, _mm_loadu_ps(wx + kx))));
          }
        }
      }
      continue;
    }
#endif
    for (int kz = kz0; kz < kz1; ++kz) {
      const float fz = g.wz[static_cast<std::size_t>(b + kz)] * scale;
      for (int ky = 0; ky < cy; ++ky) {
        const float fzy = fz * wy[ky];
        float* __restrict row = &data_[index(fx, fy + ky, z_first + kz)];
        for (int kx = 0; kx < cx; ++kx) row[kx] += fzy * wx[kx];
      }
    }
  }
  updateSqrt();
}

void SurfaceDensity::mergeGaussians(const std::vector<Eigen::Vector3f>& points,
                                    const std::vector<float>& sigmas, float cell,
                                    std::vector<Eigen::Vector3f>& out_points,
                                    std::vector<float>& out_sigmas_xy,
                                    std::vector<float>& out_sigmas_z,
                                    std::vector<float>& out_weights) {
  if (points.size() != sigmas.size())
    throw std::invalid_argument("SurfaceDensity::mergeGaussians: points and sigmas differ");
  out_points.clear();
  out_sigmas_xy.clear();
  out_sigmas_z.clear();
  out_weights.clear();
  auto valid = [&](std::size_t i) {
    return points[i].allFinite() && sigmas[i] > 0.f && std::isfinite(sigmas[i]);
  };
  if (!(cell > 0.f) || !std::isfinite(cell)) {
    for (std::size_t i = 0; i < points.size(); ++i)
      if (valid(i)) {
        out_points.push_back(points[i]);
        out_sigmas_xy.push_back(sigmas[i]);
        out_sigmas_z.push_back(sigmas[i]);
        out_weights.push_back(1.f);
      }
    return;
  }
  // Sums per cube, in coordinates relative to the cube's corner (no cancellation in the
  // variances); an open-addressing table on the cube index, reused between calls.
  struct Acc {
    std::int64_t key;
    Eigen::Vector3f corner;
    Eigen::Vector3f sum, sum_sq;
    float sigma_sq = 0.f;
    int n = 0;
  };
  thread_local std::vector<int> table;
  thread_local std::vector<Acc> acc;
  std::size_t slots = 16;
  while (slots < 2 * points.size()) slots *= 2;
  table.assign(slots, -1);
  acc.clear();
  const float inv = 1.f / cell;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!valid(i)) continue;
    const Eigen::Vector3f q = points[i] * inv;
    const Eigen::Vector3f f(std::floor(q.x()), std::floor(q.y()), std::floor(q.z()));
    // Cube indices beyond ±2^20 (points > 100 km away at 0.1 m cubes) are kept unmerged.
    if (!(f.cwiseAbs().maxCoeff() < 1048576.f)) {
      acc.push_back({-1 - static_cast<std::int64_t>(acc.size()), points[i], Eigen::Vector3f::Zero(),
                     Eigen::Vector3f::Zero(), sigmas[i] * sigmas[i], 1});
      continue;
    }
    const std::int64_t key = ((static_cast<std::int64_t>(f.x()) + 1048576) << 42) |
                             ((static_cast<std::int64_t>(f.y()) + 1048576) << 21) |
                             (static_cast<std::int64_t>(f.z()) + 1048576);
    std::size_t h =
        static_cast<std::size_t>((static_cast<std::uint64_t>(key) * 0x9E3779B97F4A7C15ull) >> 20) &
        (slots - 1);
    while (table[h] >= 0 && acc[static_cast<std::size_t>(table[h])].key != key)
      h = (h + 1) & (slots - 1);
    if (table[h] < 0) {
      table[h] = static_cast<int>(acc.size());
      acc.push_back({key, f * cell, Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), 0.f, 0});
    }
    Acc& a = acc[static_cast<std::size_t>(table[h])];
    const Eigen::Vector3f d = points[i] - a.corner;
    a.sum += d;
    a.sum_sq += d.cwiseProduct(d);
    a.sigma_sq += sigmas[i] * sigmas[i];
    ++a.n;
  }
  out_points.reserve(acc.size());
  out_sigmas_xy.reserve(acc.size());
  out_sigmas_z.reserve(acc.size());
  out_weights.reserve(acc.size());
  for (const Acc& a : acc) {
    const float n = static_cast<float>(a.n);
    const Eigen::Vector3f mean = a.sum / n;
    const Eigen::Vector3f var = (a.sum_sq / n - mean.cwiseProduct(mean)).cwiseMax(0.f);
    const float s2 = a.sigma_sq / n;
    out_points.push_back(a.corner + mean);
    out_sigmas_xy.push_back(std::sqrt(s2 + 0.5f * (var.x() + var.y())));
    out_sigmas_z.push_back(std::sqrt(s2 + var.z()));
    out_weights.push_back(n);
  }
}

float SurfaceDensity::halfLifeWeight(float half_life_frames) {
  if (!(half_life_frames > 0.f)) return 1.f;
  return 1.f - std::pow(0.5f, 1.f / half_life_frames);
}

void SurfaceDensity::accumulate(const SurfaceDensity& view, float weight_of_new) {
  if (view.nx_ != nx_ || view.ny_ != ny_ || view.nz_ != nz_ || view.resolution_ != resolution_ ||
      view.resolution_z_ != resolution_z_)
    throw std::invalid_argument("SurfaceDensity::accumulate: grids differ in size or resolution");
  const float w = std::min(std::max(weight_of_new, 0.f), 1.f);
  const bool same_place = (view.centre_ - centre_).norm() < 1e-6f;
  const SurfaceDensity* v = &view;
  SurfaceDensity moved;
  if (!same_place) {
    // Content of `view` expressed on this grid: moving it by (view centre - our centre).
    SurfaceDensity tmp = view;
    tmp.centre_ = centre_;
    moved = tmp.shifted(view.centre_ - centre_);
    v = &moved;
  }
  if (empty()) {
    data_ = v->data_;
  } else {
    for (std::size_t i = 0; i < data_.size(); ++i)
      data_[i] = (1.f - w) * data_[i] + w * v->data_[i];
  }
  updateSqrt();
}

SurfaceDensity SurfaceDensity::shifted(const Eigen::Vector3f& offset) const {
  SurfaceDensity out = *this;
  std::fill(out.data_.begin(), out.data_.end(), 0.f);
  // Offset in cells, split into whole and fractional parts; each source cell spreads its mass to
  // the (up to) 8 cells around its moved position, so mass is conserved inside the grid.
  const float sx = offset.x() / resolution_, sy = offset.y() / resolution_,
              sz = offset.z() / resolution_z_;
  // A shift of more than the grid moves everything out (and would overflow the casts below).
  if (!(std::abs(sx) < nx_ + 1.f && std::abs(sy) < ny_ + 1.f && std::abs(sz) < nz_ + 1.f)) {
    out.updateSqrt();  // square roots, mass and revision of the now empty grid
    return out;
  }
  const int bx = static_cast<int>(std::floor(sx)), by = static_cast<int>(std::floor(sy)),
            bz = static_cast<int>(std::floor(sz));
  const float fx = sx - bx, fy = sy - by, fz = sz - bz;
  const float wxs[2] = {1.f - fx, fx}, wys[2] = {1.f - fy, fy}, wzs[2] = {1.f - fz, fz};
  for (int iz = 0; iz < nz_; ++iz)
    for (int iy = 0; iy < ny_; ++iy)
      for (int ix = 0; ix < nx_; ++ix) {
        const float v = data_[index(ix, iy, iz)];
        if (v == 0.f) continue;
        for (int a = 0; a < 2; ++a) {
          const int tz = iz + bz + a;
          if (tz < 0 || tz >= nz_ || wzs[a] == 0.f) continue;
          for (int b = 0; b < 2; ++b) {
            const int ty = iy + by + b;
            if (ty < 0 || ty >= ny_ || wys[b] == 0.f) continue;
            for (int c = 0; c < 2; ++c) {
              const int tx = ix + bx + c;
              if (tx < 0 || tx >= nx_ || wxs[c] == 0.f) continue;
              out.data_[index(tx, ty, tz)] += v * wzs[a] * wys[b] * wxs[c];
            }
          }
        }
      }
  out.updateSqrt();
  return out;
}

float SurfaceDensity::bhattacharyya(const SurfaceDensity& a, const SurfaceDensity& b) {
  if (a.nx_ != b.nx_ || a.ny_ != b.ny_ || a.nz_ != b.nz_ || a.resolution_ != b.resolution_ ||
      a.resolution_z_ != b.resolution_z_ || (a.centre_ - b.centre_).norm() > 1e-5f)
    throw std::invalid_argument("SurfaceDensity::bhattacharyya: grids differ");
  double s = 0.0;
  for (std::size_t i = 0; i < a.sqrt_.size(); ++i) s += a.sqrt_[i] * b.sqrt_[i];
  return static_cast<float>(std::min(std::max(s, 0.0), 1.0));
}

#ifndef PCL_NO_PRECOMPILE
template void SurfaceDensity::compute<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&,
                                                     const Eigen::Vector3f&,
                                                     const Eigen::Vector3f&);
template void SurfaceDensity::compute<pcl::PointXYZI>(const pcl::PointCloud<pcl::PointXYZI>&,
                                                      const Eigen::Vector3f&,
                                                      const Eigen::Vector3f&);
#endif

}  // namespace pcl_movers
