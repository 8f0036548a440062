/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/bhattacharya_registration.h>
#include <pcl_movers/impl/bhattacharya_registration.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <memory>
#include <vector>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace pcl_movers {
namespace detail {

void refinePeak(int dims, const bool* active, const std::function<float(const int*)>& sample,
                float* offsets, float* value) {
  std::vector<int> act;
  for (int d = 0; d < dims; ++d) {
    offsets[d] = 0.f;
    if (active[d]) act.push_back(d);
  }
  std::vector<int> o(static_cast<std::size_t>(dims), 0);
  const float centre = sample(o.data());
  *value = centre;
  const int k = static_cast<int>(act.size());
  if (k == 0) return;

  // Full quadratic f(u) = c + gᵀu + ½ uᵀHu, least squares over the 3^k neighbourhood: captures
  // the tilt of a peak between yaw layers and translations, which independent parabolas miss.
  int count = 1;
  for (int i = 0; i < k; ++i) count *= 3;
  const int terms = 1 + k + k * (k + 1) / 2;
  Eigen::MatrixXd a(count, terms);
  Eigen::VectorXd b(count);
  for (int s = 0; s < count; ++s) {
    int rem = s;
    std::vector<double> u(static_cast<std::size_t>(k));
    for (int i = 0; i < k; ++i) {
      const int ui = rem % 3 - 1;
      rem /= 3;
      u[static_cast<std::size_t>(i)] = ui;
      o[static_cast<std::size_t>(act[static_cast<std::size_t>(i)])] = ui;
    }
    int c = 0;
    a(s, c++) = 1.0;
    for (int i = 0; i < k; ++i) a(s, c++) = u[static_cast<std::size_t>(i)];
    for (int i = 0; i < k; ++i)
      for (int j = i; j < k; ++j)
        a(s, c++) = u[static_cast<std::size_t>(i)] * u[static_cast<std::size_t>(j)];
    b(s) = sample(o.data());
  }
  const Eigen::VectorXd coef = a.colPivHouseholderQr().solve(b);
  Eigen::VectorXd g(k);
  Eigen::MatrixXd h(k, k);
  int c = 1;
  for (int i = 0; i < k; ++i) g(i) = coef(c++);
  for (int i = 0; i < k; ++i)
    for (int j = i; j < k; ++j) {
      const double q = coef(c++);
      if (i == j)
        h(i, i) = 2.0 * q;
      else
        h(i, j) = h(j, i) = q;
    }
  Eigen::LLT<Eigen::MatrixXd> neg(-h);
  if (neg.info() == Eigen::Success) {
    const Eigen::VectorXd u = neg.solve(g);  // -H u = g  →  u = -H⁻¹ g
    if (u.allFinite() && u.cwiseAbs().maxCoeff() <= 1.0) {
      for (int i = 0; i < k; ++i)
        offsets[act[static_cast<std::size_t>(i)]] = static_cast<float>(u(i));
      *value = static_cast<float>(coef(0) + g.dot(u) + 0.5 * u.dot(h * u));
      return;
    }
  }
  // Fallback: one parabola per dimension through (-1, 0, +1).
  std::fill(o.begin(), o.end(), 0);
  float gain = 0.f;
  for (int d : act) {
    o[static_cast<std::size_t>(d)] = -1;
    const float fm = sample(o.data());
    o[static_cast<std::size_t>(d)] = 1;
    const float fp = sample(o.data());
    o[static_cast<std::size_t>(d)] = 0;
    const float curv = fm - 2.f * centre + fp;
    if (curv < 0.f) {
      const float u = std::min(std::max(0.5f * (fm - fp) / curv, -0.5f), 0.5f);
      offsets[d] = u;
      gain += 0.5f * (fp - fm) * u + 0.5f * curv * u * u;
    }
  }
  *value = centre + gain;
}

namespace {
/** The workspace of the last registration object destroyed on this thread. Creating one object
 * per pair (as ICP/NDT users do, and the benchmarks) would otherwise allocate and free the
 * buffers, FFT plans and target caches on every align(); freeing ~100 kB also makes glibc
 * return the heap top to the kernel (brk, TLB flushes), which cost as much as the search. */
thread_local std::shared_ptr<BhattacharyaWorkspace> t_spare_workspace;
}  // namespace

std::shared_ptr<BhattacharyaWorkspace> acquireWorkspace() {
  std::shared_ptr<BhattacharyaWorkspace> w = std::move(t_spare_workspace);
  t_spare_workspace.reset();
  if (!w) return std::make_shared<BhattacharyaWorkspace>();
  // The content caches belong to the previous object: a new object could get the same target
  // cloud address. (The FFT's target spectra are keyed by SurfaceDensity::revision(), unique in
  // the process, and stay valid.)
  w->own_target_valid = false;
  w->own_target_cloud = nullptr;
  w->own_target_key.clear();
  return w;
}

void releaseWorkspace(std::shared_ptr<BhattacharyaWorkspace>& work) {
  if (work && work.use_count() == 1) t_spare_workspace = std::move(work);
  work.reset();
}

namespace {
constexpr float kShadowAzBin = 0.12f * 3.14159265f / 180.f;
constexpr float kShadowElBin = 0.3f * 3.14159265f / 180.f;
constexpr float kTwoPi = 6.28318531f;
}  // namespace

void ShadowImage::build(const std::vector<Eigen::Vector3f>& occluders,
                        const Eigen::Vector3f& sensor) {
  sensor_ = sensor;
  range_.clear();
  naz_ = nel_ = 0;
  if (occluders.empty()) return;
  // Azimuths relative to the first return's, so that an image straddling ±π stays contiguous.
  const Eigen::Vector3f r0 = occluders.front() - sensor;
  const float ref = std::atan2(r0.y(), r0.x());
  float amin = std::numeric_limits<float>::max(), amax = -amin, emin = amin, emax = -amin;
  std::vector<Eigen::Vector3f> aer;  // relative azimuth, elevation, range
  aer.reserve(occluders.size());
  for (const auto& q : occluders) {
    const Eigen::Vector3f r = q - sensor;
    const float range = r.norm();
    if (!(range > 0.f) || !std::isfinite(range)) continue;
    float az = std::atan2(r.y(), r.x()) - ref;
    if (az > 0.5f * kTwoPi) az -= kTwoPi;
    if (az < -0.5f * kTwoPi) az += kTwoPi;
    const float el = std::asin(std::min(1.f, std::max(-1.f, r.z() / range)));
    aer.emplace_back(az, el, range);
    amin = std::min(amin, az);
    amax = std::max(amax, az);
    emin = std::min(emin, el);
    emax = std::max(emax, el);
  }
  if (aer.empty()) return;
  // One bin of margin on each side for the dilation below.
  az0_ = ref + amin - kShadowAzBin;
  el0_ = emin - kShadowElBin;
  naz_ = static_cast<int>(std::min((amax - amin) / kShadowAzBin, 4000.f)) + 3;
  nel_ = static_cast<int>(std::min((emax - emin) / kShadowElBin, 400.f)) + 3;
  range_.assign(static_cast<std::size_t>(naz_) * nel_, std::numeric_limits<float>::infinity());
  for (const auto& v : aer) {
    const int ia = static_cast<int>((v.x() - amin) / kShadowAzBin) + 1;
    const int ie = static_cast<int>((v.y() - emin) / kShadowElBin) + 1;
    for (int e = std::max(0, ie - 1); e <= std::min(nel_ - 1, ie + 1); ++e)
      for (int a = std::max(0, ia - 1); a <= std::min(naz_ - 1, ia + 1); ++a) {
        float& r = range_[static_cast<std::size_t>(e) * naz_ + a];
        r = std::min(r, v.z());
      }
  }
}

bool ShadowImage::shadowed(const Eigen::Vector3f& p, float margin) const {
  if (range_.empty()) return false;
  const Eigen::Vector3f r = p - sensor_;
  const float range = r.norm();
  if (!(range > 0.f) || !std::isfinite(range)) return false;
  float az = std::atan2(r.y(), r.x()) - az0_;
  while (az < 0.f) az += kTwoPi;
  while (az >= kTwoPi) az -= kTwoPi;
  const float el = std::asin(std::min(1.f, std::max(-1.f, r.z() / range))) - el0_;
  if (el < 0.f) return false;
  const float fa = az / kShadowAzBin, fe = el / kShadowElBin;
  if (fa >= static_cast<float>(naz_) || fe >= static_cast<float>(nel_)) return false;
  const float occ = range_[static_cast<std::size_t>(fe) * naz_ + static_cast<std::size_t>(fa)];
  return occ < range - margin;
}

void buildSourceLayer(SourceLayer& layer, const std::vector<Eigen::Vector3f>& points,
                      const std::vector<float>& sigmas, const SurfaceDensity& target, int nr,
                      int nrz) {
  static const std::vector<float> kNoWeights;
  buildSourceLayer(layer, points, sigmas, sigmas, kNoWeights, target, nr, nrz);
}

namespace {
/** The non-zero cells of a freshly computed layer density, as lists (see SourceLayer). */
void indexNonZero(SourceLayer& layer) {
  const SurfaceDensity& d = layer.density;
  const int sx = d.getNx(), sy = d.getNy(), sz = d.getNz();
  const std::size_t cells = static_cast<std::size_t>(sx) * sy * sz;
  const std::size_t rows = static_cast<std::size_t>(sy) * sz;
  // Sized for the worst case and trimmed at the end: writes by index, no push_back per cell
  // (the capacity stays between calls, so this allocates nothing once warm).
  layer.nonzero.resize(cells);
  layer.cell_x.resize(cells);
  layer.cell_v.resize(cells);
  layer.row_y.resize(rows);
  layer.row_z.resize(rows);
  layer.row_begin.resize(rows + 1);
  int* nz_idx = layer.nonzero.data();
  int* cx = layer.cell_x.data();
  float* cv = layer.cell_v.data();
  const float* sq = d.sqrtValues().data();
  int n = 0, r = 0;
  for (int z = 0, i = 0; z < sz; ++z)
    for (int y = 0; y < sy; ++y) {
      const int before = n;
      for (int x = 0; x < sx; ++x, ++i) {
        const float v = sq[i];
        nz_idx[n] = i;
        cx[n] = x;
        cv[n] = v;
        n += v > 0.f;  // branch-free: the slot is overwritten unless the cell has mass
      }
      if (n == before) continue;
      layer.row_y[static_cast<std::size_t>(r)] = y;
      layer.row_z[static_cast<std::size_t>(r)] = z;
      layer.row_begin[static_cast<std::size_t>(r)] = before;
      ++r;
    }
  layer.row_begin[static_cast<std::size_t>(r)] = n;
  layer.nonzero.resize(static_cast<std::size_t>(n));
  layer.cell_x.resize(static_cast<std::size_t>(n));
  layer.cell_v.resize(static_cast<std::size_t>(n));
  layer.row_y.resize(static_cast<std::size_t>(r));
  layer.row_z.resize(static_cast<std::size_t>(r));
  layer.row_begin.resize(static_cast<std::size_t>(r) + 1);
}

void clearLayer(SourceLayer& layer) {
  layer.density.clear();
  layer.ox = layer.oy = layer.oz = 0;
  layer.nonzero.clear();
  layer.row_y.clear();
  layer.row_z.clear();
  layer.row_begin.assign(1, 0);
  layer.cell_x.clear();
  layer.cell_v.clear();
}
}  // namespace

void buildSourceLayer(SourceLayer& layer, const std::vector<Eigen::Vector3f>& points,
                      const std::vector<float>& sigmas_xy, const std::vector<float>& sigmas_z,
                      const std::vector<float>& weights, const SurfaceDensity& target, int nr,
                      int nrz) {
  const int nx = target.getNx(), ny = target.getNy(), nz = target.getNz();
  const float res = target.getResolution(), res_z = target.getResolutionZ();
  const Eigen::Vector3f tlo =
      target.getCentre() - 0.5f * Eigen::Vector3f(nx * res, ny * res, nz * res_z);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f hi = -lo;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f reach(3.f * sigmas_xy[i], 3.f * sigmas_xy[i], 3.f * sigmas_z[i]);
    lo = lo.cwiseMin(points[i] - reach);
    hi = hi.cwiseMax(points[i] + reach);
  }
  // Cells of the target lattice covered by the Gaussians, clipped to those that can overlap
  // the target for some searched shift (the rest never contributes).
  auto cellRange = [](float a, float b, float origin, float cell, int lo_lim, int hi_lim,
                      int& first, int& last) {
    const float fa = std::floor((a - origin) / cell), fb = std::floor((b - origin) / cell);
    first = static_cast<int>(std::max(fa, static_cast<float>(lo_lim)));
    last = static_cast<int>(std::min(fb, static_cast<float>(hi_lim)));
  };
  int ax, bx, ay, by, az, bz;
  cellRange(lo.x(), hi.x(), tlo.x(), res, -nr, nx - 1 + nr, ax, bx);
  cellRange(lo.y(), hi.y(), tlo.y(), res, -nr, ny - 1 + nr, ay, by);
  cellRange(lo.z(), hi.z(), tlo.z(), res_z, -nrz, nz - 1 + nrz, az, bz);
  if (points.empty() || bx < ax || by < ay || bz < az) {
    clearLayer(layer);
    return;
  }
  const int sx = bx - ax + 1, sy = by - ay + 1, sz = bz - az + 1;
  SurfaceDensity& d = layer.density;
  if (d.getNx() != sx || d.getNy() != sy || d.getNz() != sz) d.setGridSize(sx, sy, sz);
  d.setResolution(res);
  d.setResolutionZ(res_z);
  layer.ox = ax;
  layer.oy = ay;
  layer.oz = az;
  // Lower corner of the tight grid = lower corner of target cell (ax, ay, az).
  const Eigen::Vector3f centre =
      tlo +
      Eigen::Vector3f((ax + 0.5f * sx) * res, (ay + 0.5f * sy) * res, (az + 0.5f * sz) * res_z);
  d.computeFromGaussians(points, sigmas_xy, sigmas_z, weights, centre);
  indexNonZero(layer);
}

void prepareSource(SurfaceDensity::PreparedGaussians& prepared,
                   const std::vector<Eigen::Vector3f>& points, const std::vector<float>& sigmas_xy,
                   const std::vector<float>& sigmas_z, const std::vector<float>& weights,
                   const SurfaceDensity& target, int nrz, float z_shift) {
  const float res_z = target.getResolutionZ();
  // Lattice cell 0 of the target; a shift of the points is a shift of the lattice the other way.
  const float z0 = target.getCentre().z() - 0.5f * static_cast<float>(target.getNz()) * res_z;
  SurfaceDensity::prepareGaussians(points, sigmas_xy, sigmas_z, weights, target.getResolution(),
                                   res_z, z0 - z_shift, -nrz, target.getNz() - 1 + nrz, prepared);
}

void buildSourceLayer(SourceLayer& layer, const std::vector<Eigen::Vector3f>& points,
                      const SurfaceDensity::PreparedGaussians& prepared,
                      const SurfaceDensity& target, int nr, int nrz) {
  const int nx = target.getNx(), ny = target.getNy(), nz = target.getNz();
  const float res = target.getResolution(), res_z = target.getResolutionZ();
  const float tx = target.getCentre().x() - 0.5f * static_cast<float>(nx) * res;
  const float ty = target.getCentre().y() - 0.5f * static_cast<float>(ny) * res;
  const float inv_res = 1.f / res;
  // Horizontal reach in cells of the target lattice (the ±3σ windows), vertical from the
  // preparation.
  float lx = std::numeric_limits<float>::max(), ly = lx, hx = -lx, hy = -lx;
  for (std::size_t k = 0; k < prepared.index.size(); ++k) {
    const Eigen::Vector3f& p = points[static_cast<std::size_t>(prepared.index[k])];
    const float u = (p.x() - tx) * inv_res, v = (p.y() - ty) * inv_res, r = prepared.reach_xy[k];
    lx = std::min(lx, u - r);
    hx = std::max(hx, u + r);
    ly = std::min(ly, v - r);
    hy = std::max(hy, v + r);
  }
  const int az = std::max(prepared.z_min, -nrz), bz = std::min(prepared.z_max, nz - 1 + nrz);
  auto clip = [](float a, float b, int lo_lim, int hi_lim, int& first, int& last) {
    first = static_cast<int>(std::max(std::floor(a), static_cast<float>(lo_lim)));
    last = static_cast<int>(std::min(std::floor(b), static_cast<float>(hi_lim)));
  };
  int ax = 0, bx = -1, ay = 0, by = -1;
  if (!prepared.empty()) {
    clip(lx, hx, -nr, nx - 1 + nr, ax, bx);
    clip(ly, hy, -nr, ny - 1 + nr, ay, by);
  }
  if (prepared.empty() || bx < ax || by < ay || bz < az) {
    clearLayer(layer);
    return;
  }
  const int sx = bx - ax + 1, sy = by - ay + 1, sz = bz - az + 1;
  SurfaceDensity& d = layer.density;
  if (d.getNx() != sx || d.getNy() != sy || d.getNz() != sz) d.setGridSize(sx, sy, sz);
  d.setResolution(res);
  d.setResolutionZ(res_z);
  layer.ox = ax;
  layer.oy = ay;
  layer.oz = az;
  const Eigen::Vector3f centre(tx + (static_cast<float>(ax) + 0.5f * sx) * res,
                               ty + (static_cast<float>(ay) + 0.5f * sy) * res,
                               prepared.z0 + (static_cast<float>(az) + 0.5f * sz) * res_z);
  d.computeFromPrepared(prepared, points, centre);
  indexNonZero(layer);
}

namespace {
/** The target's square roots with `pad` zero cells before and after every x row: the direct sum
 * then needs no per-cell test of the shifts that leave the target (their products are exact
 * zeros, which leave a sum of non-negative terms unchanged bit for bit). Rebuilt when the
 * target's content (SurfaceDensity::revision(), unique in the process) or the padding changes. */
struct PaddedTarget {
  std::uint64_t revision = 0;
  int pad = -1, stride = 0;
  std::vector<float> v;
};

const float* paddedRows(const SurfaceDensity& target, int pad, int& stride) {
  // Two entries: the coarse-to-fine search alternates between the target and its binned copy.
  thread_local PaddedTarget cache[2];
  thread_local int last_used = 0;
  int slot = cache[0].revision == target.revision() ? 0 : 1;
  if (cache[slot].revision != target.revision()) slot = 1 - last_used;
  last_used = slot;
  PaddedTarget& p = cache[slot];
  const int nx = target.getNx(), ny = target.getNy(), nz = target.getNz();
  if (p.revision != target.revision() || p.pad < pad) {
    // Round up: windows of a few sizes alternate (layers, blocks, refinement).
    p.pad = std::max(pad, (pad + 15) / 16 * 16);
    p.stride = nx + 2 * p.pad;
    p.v.assign(static_cast<std::size_t>(p.stride) * ny * nz, 0.f);
    const float* t = target.sqrtValues().data();
    for (int r = 0; r < ny * nz; ++r)
      std::copy(t + static_cast<std::size_t>(r) * nx, t + static_cast<std::size_t>(r + 1) * nx,
                p.v.begin() + static_cast<std::ptrdiff_t>(r) * p.stride + p.pad);
    p.revision = target.revision();
  }
  stride = p.stride;
  return p.v.data() + p.pad;
}
}  // namespace

void correlateDirect(const SurfaceDensity& target, const SourceLayer& src, int dx0, int dx1,
                     int dy0, int dy1, int dz0, int dz1, float* out) {
  const int bw = dx1 - dx0 + 1, bh = dy1 - dy0 + 1, bd = dz1 - dz0 + 1;
  std::fill(out, out + static_cast<std::size_t>(bw) * bh * bd, 0.f);
  const int rows = static_cast<int>(src.row_y.size());
  if (rows == 0 || bw < 1) return;
  const int nx = target.getNx(), ny = target.getNy(), nz = target.getNz();
  // x reach of the shifted source cells, beyond the target on either side.
  const int sx = src.density.getNx();
  const int pad = std::max(0, std::max(-(src.ox + dx0), src.ox + sx - 1 + dx1 - (nx - 1)));
  int stride = 0;
  const float* t = paddedRows(target, pad, stride);
  const int* cx = src.cell_x.data();
  const float* cv = src.cell_v.data();
  // Row by row of the source: the shifts (dy, dz) that land inside the target are the same for
  // the whole row; each output row then takes the row's cells as a dot product per shift dx,
  // kept in registers (four shifts at a time). Every output still receives the source cells in
  // index order, so the sums are those of the cell-by-cell scatter, bit for bit.
  for (int r = 0; r < rows; ++r) {
    const int jy = src.row_y[static_cast<std::size_t>(r)] + src.oy;
    const int jz = src.row_z[static_cast<std::size_t>(r)] + src.oz;
    const int c0 = src.row_begin[static_cast<std::size_t>(r)];
    const int c1 = src.row_begin[static_cast<std::size_t>(r) + 1];
    const int ez0 = std::max(dz0, -jz), ez1 = std::min(dz1, nz - 1 - jz);
    const int ey0 = std::max(dy0, -jy), ey1 = std::min(dy1, ny - 1 - jy);
    for (int dz = ez0; dz <= ez1; ++dz)
      for (int dy = ey0; dy <= ey1; ++dy) {
        // trow[x] = target at x + ox + dx0 (x may reach into the padding).
        const float* trow =
            t + (static_cast<std::size_t>(jz + dz) * ny + (jy + dy)) * stride + src.ox + dx0;
        float* orow = out + (static_cast<std::size_t>(dz - dz0) * bh + (dy - dy0)) * bw;
        int k = 0;
#ifdef __SSE2__
        // Sixteen shifts at a time: four independent sums hide the latency of the additions.
        for (; k + 16 <= bw; k += 16) {
          __m128 a0 = _mm_loadu_ps(orow + k), a1 = _mm_loadu_ps(orow + k + 4),
                 a2 = _mm_loadu_ps(orow + k + 8), a3 = _mm_loadu_ps(orow + k + 12);
          for (int c = c0; c < c1; ++c) {
            const __m128 v = _mm_set1_ps(cv[c]);
            const float* tk = trow + cx[c] + k;
            a0 = _mm_add_ps(a0, _mm_mul_ps(v, _mm_loadu_ps(tk)));
            a1 = _mm_add_ps(a1, _mm_mul_ps(v, _mm_loadu_ps(tk + 4)));
            a2 = _mm_add_ps(a2, _mm_mul_ps(v, _mm_loadu_ps(tk + 8)));
            a3 = _mm_add_ps(a3, _mm_mul_ps(v, _mm_loadu_ps(tk + 12)));
          }
          _mm_storeu_ps(orow + k, a0);
          _mm_storeu_ps(orow + k + 4, a1);
          _mm_storeu_ps(orow + k + 8, a2);
          _mm_storeu_ps(orow + k + 12, a3);
        }
        for (; k + 4 <= bw; k += 4) {
          __m128 acc = _mm_loadu_ps(orow + k);
          for (int c = c0; c < c1; ++c)
            acc = _mm_add_ps(acc, _mm_mul_ps(_mm_set1_ps(cv[c]), _mm_loadu_ps(trow + cx[c] + k)));
          _mm_storeu_ps(orow + k, acc);
        }
#endif
        for (; k < bw; ++k) {
          float acc = orow[k];
          for (int c = c0; c < c1; ++c) acc += cv[c] * trow[cx[c] + k];
          orow[k] = acc;
        }
      }
  }
}

namespace {
int floorDiv2(int v) {
  return v >= 0 ? v / 2 : -((1 - v) / 2);
}
}  // namespace

void binLayer(const SurfaceDensity& fine, int ox, int oy, int oz, SourceLayer& coarse) {
  const int fx = fine.getNx(), fy = fine.getNy(), fz = fine.getNz();
  const int cx0 = floorDiv2(ox), cy0 = floorDiv2(oy);
  const int cnx = floorDiv2(ox + fx - 1) - cx0 + 1, cny = floorDiv2(oy + fy - 1) - cy0 + 1;
  SurfaceDensity& d = coarse.density;
  if (d.getNx() != cnx || d.getNy() != cny || d.getNz() != fz) d.setGridSize(cnx, cny, fz);
  d.setResolution(2.f * fine.getResolution());
  d.setResolutionZ(fine.getResolutionZ());
  thread_local std::vector<float> sum;
  sum.assign(static_cast<std::size_t>(cnx) * cny * fz, 0.f);
  const std::vector<float>& v = fine.values();
  for (int z = 0, i = 0; z < fz; ++z)
    for (int y = 0; y < fy; ++y) {
      float* row =
          sum.data() + (static_cast<std::size_t>(z) * cny + (floorDiv2(oy + y) - cy0)) * cnx;
      for (int x = 0; x < fx; ++x, ++i)
        row[floorDiv2(ox + x) - cx0] += v[static_cast<std::size_t>(i)];
    }
  d.setValues(sum);
  coarse.ox = cx0;
  coarse.oy = cy0;
  coarse.oz = oz;
  indexNonZero(coarse);
}

/** FFT plans, buffers and the cached spectra of the last target. 2-D transforms of the
 * horizontal slices: real rows (half spectrum, H = N/2+1 bins) then complex columns. */
struct BhattacharyaWorkspace::Fft {
  Eigen::FFT<float> fft;
  std::uint64_t target_revision = 0;
  int target_n = 0;
  std::vector<std::complex<float>> target_spectra;  // nz × N × H
  std::vector<char> target_used;                    // slice has mass
  std::vector<std::complex<float>> source_spectra, acc, col_in, col_out;
  std::vector<float> row;
  Fft() {
    fft.SetFlag(Eigen::FFT<float>::HalfSpectrum);
    fft.SetFlag(Eigen::FFT<float>::Unscaled);
  }
  /** spectrum (N × H) of the w × h slice `v` (row stride w) zero-padded to N × N. */
  void forward(const float* v, int w, int h, int n, std::complex<float>* spectrum) {
    const int hb = n / 2 + 1;
    row.assign(static_cast<std::size_t>(n), 0.f);
    std::fill(spectrum, spectrum + static_cast<std::size_t>(n) * hb, std::complex<float>(0.f));
    for (int y = 0; y < h; ++y) {
      std::copy(v + static_cast<std::size_t>(y) * w, v + static_cast<std::size_t>(y + 1) * w,
                row.begin());
      fft.fwd(spectrum + static_cast<std::size_t>(y) * hb, row.data(), n);
    }
    col_in.resize(static_cast<std::size_t>(n));
    col_out.resize(static_cast<std::size_t>(n));
    for (int c = 0; c < hb; ++c) {
      for (int y = 0; y < n; ++y) col_in[static_cast<std::size_t>(y)] = spectrum[y * hb + c];
      fft.fwd(col_out.data(), col_in.data(), n);
      for (int y = 0; y < n; ++y) spectrum[y * hb + c] = col_out[static_cast<std::size_t>(y)];
    }
  }
};

namespace {

/** Smallest FFT size ≥ n that is a multiple of 4 (kissfft's fast real path) with factors 2, 3,
 * 5 only. */
int fftSize(int n) {
  for (int m = std::max(4, (n + 3) / 4 * 4);; m += 4) {
    int r = m;
    for (int f : {2, 3, 5})
      while (r % f == 0) r /= f;
    if (r == 1) return m;
  }
}

/** N such that the circular correlation equals the linear one at the searched lags. */
int fftSizeFor(const SurfaceDensity& target, const SourceLayer& src, int nr) {
  const int nx = target.getNx(), ny = target.getNy();
  const int sx = src.density.getNx(), sy = src.density.getNy();
  int need = std::max(std::max(nx, ny), std::max(sx, sy));
  need = std::max(need, std::max(nx - (src.ox - nr), src.ox + nr + sx));
  need = std::max(need, std::max(ny - (src.oy - nr), src.oy + nr + sy));
  return fftSize(need);
}

// Cost model, in nanoseconds, fitted to timings of both paths on this code (Release, one
// thread; see docs/registration.md "Direct sum or FFT"): a multiply-add of the direct sum, and
// one N×N real 2-D transform per unit of N² log2 N.
// The direct constants were halved when the direct sum went row-wise and sixteen shifts wide
// (measured/model time 0.55 over the calibration set; 0.5 picks the faster path most often).
constexpr double kDirectNsPerMac = 0.125;
constexpr double kDirectNsPerCell = 1.75;
constexpr double kFftNsPerUnit = 0.85;
constexpr double kFftNsPerProduct = 1.9;

}  // namespace

double directCost(const SurfaceDensity& target, const SourceLayer& src, int nr, int nrz) {
  // The exact number of multiply-adds: per non-zero source cell, the shifts that land inside the
  // target (O(non-zero cells), negligible next to the sum itself).
  const int nx = target.getNx(), ny = target.getNy(), nz = target.getNz();
  auto valid = [](int t0, int r, int n) {
    return std::max(0, std::min(r, n - 1 - t0) - std::max(-r, -t0) + 1);
  };
  double macs = 0.0;
  for (std::size_t r = 0; r + 1 < src.row_begin.size(); ++r) {
    const int yz = valid(src.row_y[r] + src.oy, nr, ny) * valid(src.row_z[r] + src.oz, nrz, nz);
    for (int c = src.row_begin[r]; c < src.row_begin[r + 1]; ++c)
      macs +=
          static_cast<double>(valid(src.cell_x[static_cast<std::size_t>(c)] + src.ox, nr, nx)) * yz;
  }
  return kDirectNsPerMac * macs + kDirectNsPerCell * static_cast<double>(src.nonzero.size());
}

double fftCost(const BhattacharyaWorkspace& work, const SurfaceDensity& target,
               const SourceLayer& src, int nr, int nrz) {
  if (src.nonzero.empty()) return 0.0;
  const int n = fftSizeFor(target, src, nr);
  const double unit = static_cast<double>(n) * n * std::log2(static_cast<double>(n));
  const bool cached =
      work.fft && work.fft->target_revision == target.revision() && work.fft->target_n == n;
  const double transforms = src.density.getNz() + (2.0 * nrz + 1.0) +
                            (cached ? 0.0 : static_cast<double>(target.getNz()));
  const double products =
      (2.0 * nrz + 1.0) * src.density.getNz() * static_cast<double>(n) * (n / 2 + 1);
  return kFftNsPerUnit * transforms * unit + kFftNsPerProduct * products;
}

void correlateFft(BhattacharyaWorkspace& work, const SurfaceDensity& target, const SourceLayer& src,
                  int nr, int nrz, float* out) {
  const int wx = 2 * nr + 1, wz = 2 * nrz + 1;
  std::fill(out, out + static_cast<std::size_t>(wz) * wx * wx, 0.f);
  if (src.nonzero.empty()) return;
  if (!work.fft) work.fft = std::make_shared<BhattacharyaWorkspace::Fft>();
  BhattacharyaWorkspace::Fft& f = *work.fft;
  const int nx = target.getNx(), ny = target.getNy(), nz = target.getNz();
  const int sx = src.density.getNx(), sy = src.density.getNy(), sz = src.density.getNz();
  const int n = fftSizeFor(target, src, nr);
  const int hb = n / 2 + 1;
  const std::size_t plane = static_cast<std::size_t>(n) * hb;
  // Target spectra: computed once per target content and size.
  if (f.target_revision != target.revision() || f.target_n != n) {
    f.target_spectra.resize(plane * nz);
    f.target_used.assign(static_cast<std::size_t>(nz), 0);
    const std::vector<float>& t = target.sqrtValues();
    for (int z = 0; z < nz; ++z) {
      const float* slice = t.data() + static_cast<std::size_t>(z) * nx * ny;
      bool any = false;
      for (int i = 0; i < nx * ny && !any; ++i) any = slice[i] > 0.f;
      f.target_used[static_cast<std::size_t>(z)] = any;
      if (any) f.forward(slice, nx, ny, n, f.target_spectra.data() + plane * z);
    }
    f.target_revision = target.revision();
    f.target_n = n;
  }
  f.source_spectra.resize(plane * sz);
  std::vector<char> used(static_cast<std::size_t>(sz), 0);
  const std::vector<float>& s = src.density.sqrtValues();
  for (int z = 0; z < sz; ++z) {
    const float* slice = s.data() + static_cast<std::size_t>(z) * sx * sy;
    bool any = false;
    for (int i = 0; i < sx * sy && !any; ++i) any = slice[i] > 0.f;
    used[static_cast<std::size_t>(z)] = any;
    if (any) f.forward(slice, sx, sy, n, f.source_spectra.data() + plane * z);
  }
  // c[k] = Σ_j s[j]·t[j + k] ⇔ C = conj(Ŝ)·T̂; lag k = o + d.
  f.acc.resize(plane);
  f.col_in.resize(static_cast<std::size_t>(n));
  f.col_out.resize(static_cast<std::size_t>(n));
  f.row.resize(static_cast<std::size_t>(n));
  const float scale = 1.f / (static_cast<float>(n) * static_cast<float>(n));
  for (int dz = -nrz; dz <= nrz; ++dz) {
    std::fill(f.acc.begin(), f.acc.end(), std::complex<float>(0.f));
    bool any = false;
    for (int tz = 0; tz < nz; ++tz) {
      const int jz = tz - src.oz - dz;
      if (jz < 0 || jz >= sz || !used[static_cast<std::size_t>(jz)] ||
          !f.target_used[static_cast<std::size_t>(tz)])
        continue;
      any = true;
      const std::complex<float>* a = f.source_spectra.data() + plane * jz;
      const std::complex<float>* b = f.target_spectra.data() + plane * tz;
      for (std::size_t i = 0; i < plane; ++i) f.acc[i] += std::conj(a[i]) * b[i];
    }
    if (!any) continue;
    // Inverse: complex columns, then the real rows that hold the searched lags only.
    for (int c = 0; c < hb; ++c) {
      for (int y = 0; y < n; ++y) f.col_in[static_cast<std::size_t>(y)] = f.acc[y * hb + c];
      f.fft.inv(f.col_out.data(), f.col_in.data(), n);
      for (int y = 0; y < n; ++y) f.acc[y * hb + c] = f.col_out[static_cast<std::size_t>(y)];
    }
    for (int dy = -nr; dy <= nr; ++dy) {
      const int ky = ((src.oy + dy) % n + n) % n;
      f.fft.inv(f.row.data(), f.acc.data() + static_cast<std::size_t>(ky) * hb, n);
      float* o = out + (static_cast<std::size_t>(dz + nrz) * wx + (dy + nr)) * wx;
      for (int dx = -nr; dx <= nr; ++dx) {
        const int kx = ((src.ox + dx) % n + n) % n;
        o[dx + nr] = f.row[static_cast<std::size_t>(kx)] * scale;
      }
    }
  }
}

}  // namespace detail

#ifndef PCL_NO_PRECOMPILE
template class BhattacharyaRegistration<pcl::PointXYZ, pcl::PointXYZ, float>;
template class BhattacharyaRegistration<pcl::PointXYZI, pcl::PointXYZI, float>;
template class BhattacharyaRegistration<pcl::PointXYZ, pcl::PointXYZI, float>;
template class BhattacharyaRegistration<pcl::PointXYZI, pcl::PointXYZ, float>;
#endif

}  // namespace pcl_movers
