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

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#endif

namespace pcl_movers {

namespace detail {

/** \brief atan2 to within 2e-6 rad (a column of a 2200-column image is 2.9e-3 rad) at a third of
 * the cost of std::atan2, which was a third of the organizer's time. Odd minimax polynomial of
 * atan on [0, 1] plus octant folding. */
inline float fastAtan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float mx = std::max(ax, ay), mn = std::min(ax, ay);
  const float a = mn / (mx > 0.f ? mx : 1.f);  // 0 at the origin; no branch around the division
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

/** \brief Sentinel of RangeImageOrganizer's row table: the cell holds more than two rows. */
constexpr std::uint16_t kTableAmbiguous = 0xFFFF;
/** \brief Points per block of the organizer's vectorized first pass (its scratch stays in L1). */
constexpr std::size_t kOrganizerBlock = 256;

/** \brief Constants of the organizer's per-point pass (organizerKernel). */
struct OrganizerKernelParams {
  float max_range2, min_range2;
  float upper_limit, upper_offset, lower_limit, lower_offset;  ///< field of view in t = z/ρ
  float mean_offset, g_min, g_scale, g_bins, w_scale, w_bins;  ///< row table (g, w) cells
  float azimuth_max, columns_per_radian, columns;
  bool full_revolution;
  /// Row table (padded by one entry) and mid-lines: rows are resolved where the table is unique.
  const std::uint16_t* row_table;
  const float* mid_a;
  const float* mid_h;
  /// The mid-lines are strictly ordered over the whole table (0 <= w < w_bins / w_scale), so a
  /// point in the table lies in row r exactly when it is below mid-line r-1 and not below
  /// mid-line r. Lets the AVX2 kernel confirm the previous row with two comparisons instead of
  /// three gathers (false: always look the row up).
  bool ordered_mid_lines = false;
};

/** \brief Row of each point from the table cell: the cell's top row, one lower when t is below
 * that row's mid-line; -1 where the table has no unique answer (the caller searches). */
inline void organizerResolveRows(const OrganizerKernelParams& c, std::size_t begin, std::size_t m,
                                 const float* ws, const float* ts, const int* table_cell,
                                 int* rows) {
  for (std::size_t k = begin; k < m; ++k) {
    const std::uint16_t entry = table_cell[k] >= 0 ? c.row_table[table_cell[k]] : kTableAmbiguous;
    rows[k] = entry == kTableAmbiguous
                  ? -1
                  : int(entry) + (ts[k] < c.mid_a[entry] + c.mid_h[entry] * ws[k] ? 1 : 0);
  }
}

/** \brief The per-point arithmetic of RangeImageOrganizer for `m` points given as arrays x, y, z:
 * w = 1/ρ, t = z/ρ, status (0 placed, 1 not finite, 2 outside range or view), the row-table cell
 * (-1: search instead), and column·2 + (1 when the azimuth leans to the next column). Plain
 * scalar reference; organizerKernel is the same arithmetic four points at a time. */
inline void organizerKernelScalar(const OrganizerKernelParams& c, const float* xs, const float* ys,
                                  const float* zs, std::size_t m, float* ws, float* ts, int* status,
                                  int* table_cell, int* column_code, int* rows) {
  for (std::size_t k = 0; k < m; ++k) {
    const float x = xs[k], y = ys[k], z = zs[k];
    // x - x is 0 for finite x, NaN for NaN and ±Inf.
    const bool finite = ((x - x) + (y - y) + (z - z)) == 0.f;
    const float rho2 = x * x + y * y;
    const float range2 = rho2 + z * z;
    const bool in_range = range2 <= c.max_range2 && range2 >= c.min_range2 && rho2 > 0.f;
    const float w = 1.f / std::sqrt(rho2);
    const float t = z * w;
    const bool in_beams =
        t <= c.upper_limit + c.upper_offset * w && t >= c.lower_limit + c.lower_offset * w;
    // Table cell; NaN and out-of-table values compare false and go to the search (-1).
    const float gf = (t - c.mean_offset * w - c.g_min) * c.g_scale;
    const float wf = w * c.w_scale;
    const bool in_table = gf >= 0.f && gf < c.g_bins && wf >= 0.f && wf < c.w_bins;
    const float gi = float(int(in_table ? gf : 0.f)), wi = float(int(in_table ? wf : 0.f));
    table_cell[k] = in_table ? int(wi * c.g_bins + gi) : -1;
    // Column: azimuth decreases with the column index (SensorModel).
    float f = (c.azimuth_max - fastAtan2(y, x)) * c.columns_per_radian;
    if (c.full_revolution) {
      f = f < 0.f ? f + c.columns : f;
      f = f >= c.columns ? f - c.columns : f;
    }
    const bool in_fov = f >= 0.f && f < c.columns;
    const float fc = in_fov ? f : 0.f;
    const int column = int(fc);  // < columns, since fc < columns
    column_code[k] = column * 2 + ((fc - float(column)) >= 0.5f ? 1 : 0);
    ws[k] = w;
    ts[k] = t;
    status[k] = !finite ? 1 : ((in_range && in_beams && in_fov) ? 0 : 2);
  }
  organizerResolveRows(c, 0, m, ws, ts, table_cell, rows);
}

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define PCL_MOVERS_ORGANIZER_AVX2 1
/** \brief Function attributes of the vectorized kernels: the instruction set, and for GCC no
 * contraction of a multiply and an add into one fused operation (AVX-512 has FMA, which rounds
 * once instead of twice: the results would differ from the scalar reference). */
#if defined(__clang__)
#define PCL_MOVERS_ORGANIZER_NO_CONTRACT
#else
#define PCL_MOVERS_ORGANIZER_NO_CONTRACT , optimize("fp-contract=off")
#endif
#define PCL_MOVERS_ORGANIZER_KERNEL organizerKernelAvx2
#define PCL_MOVERS_ORGANIZER_SELECT organizerSelectAvx2
#define PCL_MOVERS_ORGANIZER_KERNEL_ATTRIBUTES \
  __attribute__((target("avx2") PCL_MOVERS_ORGANIZER_NO_CONTRACT))
#include <pcl_movers/impl/range_image_organizer_kernel.hpp>
#undef PCL_MOVERS_ORGANIZER_KERNEL
#undef PCL_MOVERS_ORGANIZER_SELECT
#undef PCL_MOVERS_ORGANIZER_KERNEL_ATTRIBUTES
#undef PCL_MOVERS_ORGANIZER_NO_CONTRACT
}  // namespace detail
}  // namespace pcl_movers
// GCC 12 reports the undefined pass-through operand of its own AVX-512 intrinsics as maybe
// uninitialized once they are inlined (GCC bug 105593, fixed in 13).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <pcl_movers/impl/range_image_organizer_kernel16.hpp>
#pragma GCC diagnostic pop
#else
#include <pcl_movers/impl/range_image_organizer_kernel16.hpp>
#endif
namespace pcl_movers {
namespace detail {

/** \brief True when the CPU runs AVX2 (checked once). */
inline bool organizerHasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}

/** \brief True when the CPU runs AVX-512F (checked once). */
inline bool organizerHasAvx512() {
  static const bool has = __builtin_cpu_supports("avx512f");
  return has;
}
#endif

/** \brief organizerKernelScalar on arrays: 16 points at a time with AVX-512F when the CPU has it
 * and `m` is a multiple of 16, 8 with AVX2 when `m` is a multiple of 8, otherwise four points at
 * a time with SSE2 (every x86-64 CPU has it; the compiler cannot vectorize the scalar loop itself
 * because of sqrt's errno). The results are identical: the same IEEE operations in the same
 * order. `m` must be a multiple of 4 (pad the arrays). Falls back to the scalar loop elsewhere. */
inline void organizerKernel(const OrganizerKernelParams& c, const float* xs, const float* ys,
                            const float* zs, std::size_t m, float* ws, float* ts, int* status,
                            int* table_cell, int* column_code, int* rows) {
#if defined(PCL_MOVERS_ORGANIZER_AVX2)
  if (organizerHasAvx512() && m % 16 == 0) {
    organizerKernelAvx512x16<0>(c, xs, ys, zs, m, ws, ts, status, table_cell, column_code, rows);
    return;
  }
  if (organizerHasAvx2() && m % 8 == 0) {
    organizerKernelAvx2(c, xs, ys, zs, m, ws, ts, status, table_cell, column_code, rows);
    return;
  }
#endif
#if defined(__SSE2__) || defined(_M_X64)
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.f), half = _mm_set1_ps(0.5f);
  const __m128 sign = _mm_set1_ps(-0.f);
  const __m128 max_range2 = _mm_set1_ps(c.max_range2), min_range2 = _mm_set1_ps(c.min_range2);
  const __m128 upper_limit = _mm_set1_ps(c.upper_limit), upper_offset = _mm_set1_ps(c.upper_offset);
  const __m128 lower_limit = _mm_set1_ps(c.lower_limit), lower_offset = _mm_set1_ps(c.lower_offset);
  const __m128 mean_offset = _mm_set1_ps(c.mean_offset), g_min = _mm_set1_ps(c.g_min);
  const __m128 g_scale = _mm_set1_ps(c.g_scale), g_bins = _mm_set1_ps(c.g_bins);
  const __m128 w_scale = _mm_set1_ps(c.w_scale), w_bins = _mm_set1_ps(c.w_bins);
  const __m128 azimuth_max = _mm_set1_ps(c.azimuth_max);
  const __m128 columns_per_radian = _mm_set1_ps(c.columns_per_radian);
  const __m128 columns = _mm_set1_ps(c.columns);
  const __m128 full = c.full_revolution ? _mm_castsi128_ps(_mm_set1_epi32(-1)) : zero;
  auto select = [](__m128 mask, __m128 a, __m128 b) {
    return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
  };
  for (std::size_t k = 0; k < m; k += 4) {
    const __m128 x = _mm_loadu_ps(xs + k), y = _mm_loadu_ps(ys + k), z = _mm_loadu_ps(zs + k);
    const __m128 finite = _mm_cmpeq_ps(
        _mm_add_ps(_mm_add_ps(_mm_sub_ps(x, x), _mm_sub_ps(y, y)), _mm_sub_ps(z, z)), zero);
    const __m128 rho2 = _mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y));
    const __m128 range2 = _mm_add_ps(rho2, _mm_mul_ps(z, z));
    const __m128 in_range =
        _mm_and_ps(_mm_and_ps(_mm_cmple_ps(range2, max_range2), _mm_cmpge_ps(range2, min_range2)),
                   _mm_cmpgt_ps(rho2, zero));
    const __m128 w = _mm_div_ps(one, _mm_sqrt_ps(rho2));
    const __m128 t = _mm_mul_ps(z, w);
    const __m128 in_beams =
        _mm_and_ps(_mm_cmple_ps(t, _mm_add_ps(upper_limit, _mm_mul_ps(upper_offset, w))),
                   _mm_cmpge_ps(t, _mm_add_ps(lower_limit, _mm_mul_ps(lower_offset, w))));
    const __m128 gf =
        _mm_mul_ps(_mm_sub_ps(_mm_sub_ps(t, _mm_mul_ps(mean_offset, w)), g_min), g_scale);
    const __m128 wf = _mm_mul_ps(w, w_scale);
    const __m128 in_table =
        _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(gf, zero), _mm_cmplt_ps(gf, g_bins)),
                   _mm_and_ps(_mm_cmpge_ps(wf, zero), _mm_cmplt_ps(wf, w_bins)));
    const __m128 gi = _mm_cvtepi32_ps(_mm_cvttps_epi32(_mm_and_ps(in_table, gf)));
    const __m128 wi = _mm_cvtepi32_ps(_mm_cvttps_epi32(_mm_and_ps(in_table, wf)));
    const __m128i cell = _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(wi, g_bins), gi));
    _mm_storeu_si128(
        reinterpret_cast<__m128i*>(table_cell + k),
        _mm_or_si128(_mm_and_si128(_mm_castps_si128(in_table), cell),
                     _mm_andnot_si128(_mm_castps_si128(in_table), _mm_set1_epi32(-1))));
    // fastAtan2, lane-wise.
    const __m128 ax = _mm_andnot_ps(sign, x), ay = _mm_andnot_ps(sign, y);
    const __m128 mx = _mm_max_ps(ax, ay), mn = _mm_min_ps(ax, ay);
    const __m128 a = _mm_div_ps(mn, select(_mm_cmpgt_ps(mx, zero), mx, one));
    const __m128 s = _mm_mul_ps(a, a);
    __m128 r = _mm_add_ps(_mm_mul_ps(_mm_set1_ps(-0.01172120f), s), _mm_set1_ps(0.05265332f));
    r = _mm_sub_ps(_mm_mul_ps(r, s), _mm_set1_ps(0.11643287f));
    r = _mm_add_ps(_mm_mul_ps(r, s), _mm_set1_ps(0.19354346f));
    r = _mm_sub_ps(_mm_mul_ps(r, s), _mm_set1_ps(0.33262347f));
    r = _mm_add_ps(_mm_mul_ps(r, s), _mm_set1_ps(0.99997726f));
    r = _mm_mul_ps(r, a);
    r = select(_mm_cmpgt_ps(ay, ax), _mm_sub_ps(_mm_set1_ps(1.57079637f), r), r);
    r = select(_mm_cmplt_ps(x, zero), _mm_sub_ps(_mm_set1_ps(3.14159274f), r), r);
    r = select(_mm_cmplt_ps(y, zero), _mm_xor_ps(r, sign), r);
    __m128 f = _mm_mul_ps(_mm_sub_ps(azimuth_max, r), columns_per_radian);
    f = select(_mm_and_ps(full, _mm_cmplt_ps(f, zero)), _mm_add_ps(f, columns), f);
    f = select(_mm_and_ps(full, _mm_cmpge_ps(f, columns)), _mm_sub_ps(f, columns), f);
    const __m128 in_fov = _mm_and_ps(_mm_cmpge_ps(f, zero), _mm_cmplt_ps(f, columns));
    const __m128 fc = _mm_and_ps(in_fov, f);
    const __m128i column = _mm_cvttps_epi32(fc);
    const __m128 lean = _mm_cmpge_ps(_mm_sub_ps(fc, _mm_cvtepi32_ps(column)), half);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(column_code + k),
                     _mm_add_epi32(_mm_slli_epi32(column, 1),
                                   _mm_and_si128(_mm_castps_si128(lean), _mm_set1_epi32(1))));
    _mm_storeu_ps(ws + k, w);
    _mm_storeu_ps(ts + k, t);
    const __m128i ok = _mm_castps_si128(_mm_and_ps(_mm_and_ps(in_range, in_beams), in_fov));
    const __m128i fin = _mm_castps_si128(finite);
    // finite ? (ok ? 0 : 2) : 1
    const __m128i st = _mm_or_si128(_mm_andnot_si128(fin, _mm_set1_epi32(1)),
                                    _mm_and_si128(fin, _mm_andnot_si128(ok, _mm_set1_epi32(2))));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(status + k), st);
  }
  organizerResolveRows(c, 0, m, ws, ts, table_cell, rows);
#else
  organizerKernelScalar(c, xs, ys, zs, m, ws, ts, status, table_cell, column_code, rows);
#endif
}

}  // namespace detail

template <typename PointT>
void RangeImageOrganizer<PointT>::setSensorModel(const SensorModel& model) {
  if (model.rows() == 0 || model.columns() <= 0)
    throw InputError("RangeImageOrganizer: sensor model '" + model.name() +
                     "' has no beams or no columns");
  model_ = model;
  has_model_ = true;
  lookup_ready_ = false;
}

template <typename PointT>
void RangeImageOrganizer<PointT>::clearSensorModel() {
  model_ = SensorModel();
  has_model_ = false;
  lookup_ready_ = false;
}

template <typename PointT>
void RangeImageOrganizer<PointT>::prepareLookup(int columns) {
  const int n = model_.rows();
  std::vector<float> tan_elevation(n);
  const std::vector<float>& offset = model_.verticalOffsets();
  mean_offset_ = 0.f;
  for (int k = 0; k < n; ++k) {
    tan_elevation[k] = std::tan(model_.elevations()[k]);
    mean_offset_ += offset[k] / float(n);
  }
  // Half a beam spacing beyond the outer beams still belongs to them (as SensorModel::rowOf);
  // a single beam accepts one degree either way.
  const float one_degree = float(M_PI / 180.0);
  const float upper_half = n > 1 ? 0.5f * (tan_elevation[0] - tan_elevation[1]) : one_degree;
  const float lower_half =
      n > 1 ? 0.5f * (tan_elevation[n - 2] - tan_elevation[n - 1]) : one_degree;
  upper_limit_ = tan_elevation[0] + upper_half;
  lower_limit_ = tan_elevation[n - 1] - lower_half;
  upper_offset_ = offset[0];
  lower_offset_ = offset[n - 1];

  // Mid-lines between neighbouring beams; the last one is -inf so row n-1 never moves down.
  mid_a_.assign(n, -std::numeric_limits<float>::infinity());
  mid_h_.assign(n, 0.f);
  float min_spacing = std::numeric_limits<float>::infinity(), max_slope = 0.f;
  for (int k = 0; k + 1 < n; ++k) {
    mid_a_[k] = 0.5f * (tan_elevation[k] + tan_elevation[k + 1]);
    mid_h_[k] = 0.5f * (offset[k] + offset[k + 1]);
    min_spacing = std::min(min_spacing, tan_elevation[k] - tan_elevation[k + 1]);
    max_slope = std::max(max_slope, std::abs(mid_h_[k] - mean_offset_));
  }
  if (!std::isfinite(min_spacing) || !(min_spacing > 0.f)) min_spacing = one_degree;

  // Table over g = t - mean offset·w (the mid-lines are nearly parallel in g) and w = 1/ρ up to
  // 1/(1 m): cells a quarter of the tightest spacing tall and 1/32 m⁻¹ wide, where the mid-lines
  // drift by max_slope/32, usually hold one mid-line at most. Points nearer than 1 m, or in the
  // few cells with two mid-lines, are bisected.
  constexpr float kTableMaxW = 1.f;
  table_w_bins_ = 32;
  table_w_scale_ = float(table_w_bins_) / kTableMaxW;
  const float margin = max_slope * kTableMaxW + std::max(upper_half, lower_half);
  table_g_min_ = lower_limit_ - margin;
  const float g_max = upper_limit_ + margin;
  const float g_cell = std::max(0.25f * min_spacing, (g_max - table_g_min_) / float(1 << 15));
  table_g_bins_ = int(std::ceil((g_max - table_g_min_) / g_cell));
  table_g_scale_ = float(table_g_bins_) / (g_max - table_g_min_);
  // One padding entry: the vectorized lookup reads 32 bits at 16-bit entries.
  row_table_.assign(std::size_t(table_g_bins_) * std::size_t(table_w_bins_) + 1,
                    detail::kTableAmbiguous);
  if (n < int(detail::kTableAmbiguous)) {
    for (int j = 0; j < table_w_bins_; ++j) {
      // Corners widened by 1 % of a cell: a point rounded into a neighbouring cell is covered.
      const float w0 = std::max(0.f, (float(j) - 0.01f) / table_w_scale_);
      const float w1 = (float(j) + 1.01f) / table_w_scale_;
      for (int i = 0; i < table_g_bins_; ++i) {
        const float g0 = table_g_min_ + (float(i) - 0.01f) / table_g_scale_;
        const float g1 = table_g_min_ + (float(i) + 1.01f) / table_g_scale_;
        // Rows grow as t falls: the top row is at the highest corner, the bottom one at the
        // lowest (regions between straight mid-lines: the extremes are at corners).
        int lo = n, hi = -1;
        for (const float w : {w0, w1})
          for (const float g : {g0, g1}) {
            const int r = rowBySearch(w, g + mean_offset_ * w);
            lo = std::min(lo, r);
            hi = std::max(hi, r);
          }
        if (hi - lo <= 1)
          row_table_[std::size_t(j) * std::size_t(table_g_bins_) + std::size_t(i)] =
              std::uint16_t(lo);
      }
    }
  }
  // The kernel may confirm a row from mid-lines r-1 and r alone when the mid-lines keep their
  // order over the table's w range (straight lines: checking both ends is enough), with a margin
  // far above float rounding (1e-5 against values below ~10, ulp ~1e-6).
  ordered_mid_lines_ = true;
  for (int k = 0; k + 2 < n; ++k)
    for (const double w : {0.0, double(kTableMaxW)})
      if (!(double(mid_a_[k]) + double(mid_h_[k]) * w >
            double(mid_a_[k + 1]) + double(mid_h_[k + 1]) * w + 1e-5))
        ordered_mid_lines_ = false;
  output_columns_ = columns;
  full_revolution_ = model_.isFullRevolution();
  azimuth_max_ = model_.azimuthMax();
  columns_per_radian_ = float(columns) / (model_.azimuthMax() - model_.azimuthMin());
  lookup_ready_ = true;
}

template <typename PointT>
inline int RangeImageOrganizer<PointT>::rowBySearch(float w, float t) const {
  // Row = number of mid-lines above t; they are ordered for w >= 0 (beams do not cross).
  int lo = 0, hi = int(mid_a_.size()) - 1;  // the answer is in [lo, hi]
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (t < mid_a_[mid] + mid_h_[mid] * w)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

template <typename PointT>
void RangeImageOrganizer<PointT>::placeBlock(std::size_t begin, std::size_t end) {
  const std::size_t m = end - begin;
  float* bx = block_x_.data();
  float* by = block_y_.data();
  float* bz = block_z_.data();
  float* bw = block_w_.data();
  float* bt = block_t_.data();
  int* status = block_status_.data();
  int* table_cell = block_table_.data();
  int* column_code = block_column_.data();
  const PointT* in = input_->points.data();
  const auto* indices = fake_indices_ ? nullptr : indices_->data();

  detail::OrganizerKernelParams c;
  c.max_range2 =
      max_range_ > 0.f ? max_range_ * max_range_ : std::numeric_limits<float>::infinity();
  c.min_range2 = min_range_ > 0.f ? min_range_ * min_range_ : 0.f;
  c.upper_limit = upper_limit_;
  c.upper_offset = upper_offset_;
  c.lower_limit = lower_limit_;
  c.lower_offset = lower_offset_;
  c.mean_offset = mean_offset_;
  c.g_min = table_g_min_;
  c.g_scale = table_g_scale_;
  c.g_bins = float(table_g_bins_);
  c.w_scale = table_w_scale_;
  c.w_bins = float(table_w_bins_);
  c.azimuth_max = azimuth_max_;
  c.columns_per_radian = columns_per_radian_;
  c.columns = float(output_columns_);
  c.full_revolution = full_revolution_;
  c.row_table = row_table_.data();
  c.mid_a = mid_a_.data();
  c.mid_h = mid_h_.data();
  c.ordered_mid_lines = ordered_mid_lines_;
  int* rows = block_row_.data();
  // With AVX-512 the kernel reads full blocks of PointXYZ/PointXYZI-like points (x, y, z first,
  // 16 or 32 bytes) itself; otherwise the points are copied into structure-of-arrays first.
  bool done = false;
#if defined(PCL_MOVERS_ORGANIZER_AVX2)
  constexpr int kStride = int(sizeof(PointT) / sizeof(float));
  if constexpr (kStride == 4 || kStride == 8) {
    const float* first = &in[begin].x;
    if (!indices && m % 16 == 0 && detail::organizerHasAvx512() &&
        first == reinterpret_cast<const float*>(in + begin) && &in[begin].y == first + 1 &&
        &in[begin].z == first + 2) {
      detail::organizerKernelAvx512x16<kStride>(c, first, nullptr, nullptr, m, bw, bt, status,
                                                table_cell, column_code, rows);
      done = true;
    }
  }
#endif
  if (!done) {
    // Structure-of-arrays for the vectorized kernel; the padding lanes are NaN.
    const std::size_t padded = (m + 15) & ~std::size_t(15);
    for (std::size_t k = 0; k < m; ++k) {
      const PointT& p = in[indices ? std::size_t((*indices_)[begin + k]) : begin + k];
      bx[k] = p.x;
      by[k] = p.y;
      bz[k] = p.z;
    }
    for (std::size_t k = m; k < padded; ++k)
      bx[k] = by[k] = bz[k] = std::numeric_limits<float>::quiet_NaN();
    detail::organizerKernel(c, bx, by, bz, padded, bw, bt, status, table_cell, column_code, rows);
  }
  const bool full = full_revolution_;

  // Placement, in input order: the first point takes its cell, a later one a free neighbour or,
  // when nearer, the cell (a single-return range image keeps the nearest).
  const int columns = output_columns_;
  int* index_image = index_image_.data();
  int* cell_of_point = cell_of_point_.data();
  auto range2Of = [&](int index) {
    const PointT& q = in[index];
    return (q.x * q.x + q.y * q.y) + q.z * q.z;
  };
  // Counted in locals, added to the members after the loop: a member incremented through `this`
  // may alias the int stores below, so the compiler kept it in memory, and each point's increment
  // waited for the previous one's store (~12 % of the organizer's time).
  std::size_t placed = 0, shifted = 0, displaced = 0, invalid = 0, out_of_view = 0;
  for (std::size_t k = 0; k < m; ++k) {
    const int index = indices ? (*indices_)[begin + k] : int(begin + k);
    if (status[k] != 0) {
      cell_of_point[index] = -1;
      if (status[k] == 1)
        ++invalid;
      else
        ++out_of_view;
      continue;
    }

    int row = rows[k];
    if (row < 0) row = rowBySearch(bw[k], bt[k]);
    const int column = column_code[k] >> 1;
    const int base = row * columns;
    const int cell = base + column;
    if (index_image[cell] < 0) {
      index_image[cell] = index;
      cell_of_point[index] = cell;
      ++placed;
      continue;
    }
    if (use_free_neighbour_) {
      // The side the azimuth leans to first: the nearer neighbour centre.
      const int step = (column_code[k] & 1) ? 1 : -1;
      bool free_found = false;
      for (const int side : {step, -step}) {
        int c = column + side;
        if (full) {
          if (c < 0) c += columns;
          if (c >= columns) c -= columns;
        } else if (c < 0 || c >= columns) {
          continue;
        }
        if (index_image[base + c] < 0) {
          index_image[base + c] = index;
          cell_of_point[index] = base + c;
          ++placed;
          free_found = true;
          break;
        }
      }
      if (free_found) {
        ++shifted;
        continue;
      }
    }
    // The cell is taken: the nearer return wins, as in a single-return range image.
    ++displaced;
    cell_of_point[index] = -1;  // unless it wins the cell below
    const int occupant = index_image[cell];
    if (range2Of(index) < range2Of(occupant)) {
      cell_of_point[occupant] = -1;
      index_image[cell] = index;
      cell_of_point[index] = cell;
    }
  }
  placed_ += placed;
  shifted_ += shifted;
  displaced_ += displaced;
  invalid_ += invalid;
  out_of_view_ += out_of_view;
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
  full_turn_ = columnsCloseFullTurn(output);
}

template <typename PointT>
bool RangeImageOrganizer<PointT>::columnsCloseFullTurn(const PointCloud& image) {
  // The azimuth of each column's first return; the median step between columns with returns.
  const int width = static_cast<int>(image.width), height = static_cast<int>(image.height);
  std::vector<float> steps;
  int last_column = -1;
  float last_azimuth = 0.f;
  for (int c = 0; c < width; ++c) {
    for (int r = 0; r < height; ++r) {
      const auto& p = image[static_cast<std::size_t>(r) * width + c];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || (p.x == 0.f && p.y == 0.f)) continue;
      const float azimuth = std::atan2(p.y, p.x);
      if (last_column >= 0) {
        float d = azimuth - last_azimuth;
        d -= static_cast<float>(2 * M_PI) * std::round(d / static_cast<float>(2 * M_PI));
        steps.push_back(std::abs(d) / static_cast<float>(c - last_column));
      }
      last_column = c;
      last_azimuth = azimuth;
      break;
    }
  }
  if (steps.size() < 2) return true;  // nothing to tell: the detector's former assumption
  auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), middle, steps.end());
  return *middle * static_cast<float>(width) > 0.95f * static_cast<float>(2 * M_PI);
}

template <typename PointT>
void RangeImageOrganizer<PointT>::organize(PointCloud& output) {
  displaced_ = shifted_ = invalid_ = out_of_view_ = placed_ = 0;
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
    lookup_ready_ = false;
  }
  full_turn_ = model_.isFullRevolution();
  const int rows = model_.rows();
  const int columns = columns_ > 0 ? columns_ : model_.columns();
  // The lookups depend on the model and the width only: kept from frame to frame.
  if (!lookup_ready_ || output_columns_ != columns) prepareLookup(columns);

  const std::size_t cells = std::size_t(rows) * std::size_t(columns);
  // All buffers below are members: same-size frames reuse them without allocating.
  index_image_.assign(cells, -1);
  // Without indices every point passes the placement loop, which writes its entry; with indices
  // the points left out must read -1.
  if (fake_indices_)
    cell_of_point_.resize(input_->size());
  else
    cell_of_point_.assign(input_->size(), -1);
  for (auto* block : {&block_x_, &block_y_, &block_z_, &block_w_, &block_t_})
    block->resize(detail::kOrganizerBlock);
  for (auto* block : {&block_status_, &block_table_, &block_column_, &block_row_})
    block->resize(detail::kOrganizerBlock);

  PointT empty;
  empty.x = empty.y = empty.z = std::numeric_limits<float>::quiet_NaN();
  const std::size_t count = fake_indices_ ? input_->size() : indices_->size();
  for (std::size_t begin = 0; begin < count; begin += detail::kOrganizerBlock)
    placeBlock(begin, std::min(count, begin + detail::kOrganizerBlock));

  if (placed_ == 0) {
    deinitCompute();
    if (invalid_ == count) throw InputError("RangeImageOrganizer: the input has no finite point");
    throw InputError("RangeImageOrganizer: no input point lies in the field of view of sensor '" +
                     model_.name() + "'");
  }

  // One pass writes every cell once, from the index image (no NaN fill followed by overwrites;
  // measured faster than writing the points while placing them and blanking the rest).
  // organize(*input) needs the input intact while writing: it goes through image_.
  const bool in_place = &output == input_.get();
  PointCloud& image = in_place ? image_ : output;
  image.points.resize(cells);
  {
    const PointT* in = input_->points.data();
    PointT* out = image.points.data();
    const int* index = index_image_.data();
    for (std::size_t c = 0; c < cells; ++c) out[c] = index[c] >= 0 ? in[index[c]] : empty;
  }
  image.header = input_->header;
  image.sensor_origin_ = input_->sensor_origin_;
  image.sensor_orientation_ = input_->sensor_orientation_;
  image.width = std::uint32_t(columns);
  image.height = std::uint32_t(rows);
  image.is_dense = false;
  if (in_place) output.swap(image);
  deinitCompute();
}

}  // namespace pcl_movers
