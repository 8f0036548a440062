/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * The 16-lane AVX-512F kernel of RangeImageOrganizer (included by range_image_organizer.hpp, only
 * for GCC/Clang on x86). The same IEEE operations in the same order as organizerKernelScalar, no
 * fused multiply-add: identical results.
 */
#pragma once

#include <immintrin.h>

#include <cstddef>
#include <limits>

namespace pcl_movers {
namespace detail {

/** \brief Target of the AVX-512F code, for GCC without contraction of a multiply and an add into
 * one fused operation (it rounds once instead of twice: the results would differ from the scalar
 * reference). */
#if defined(__clang__)
#define PCL_MOVERS_ORGANIZER_AVX512_ATTRIBUTES __attribute__((target("avx512f")))
#else
#define PCL_MOVERS_ORGANIZER_AVX512_ATTRIBUTES \
  __attribute__((target("avx512f"), optimize("fp-contract=off")))
#endif

/** \brief x, y and z of 16 points. kStride 0: from three arrays at xs, ys, zs. kStride 4 or 8:
 * straight from the points (PointXYZ: 16 bytes, PointXYZI: 32 bytes, x, y, z first), xs being the
 * first point's x. Loading the points whole and transposing them with two rounds of
 * permutes replaces the copy into arrays (the organizer's points are read once, not twice) and
 * costs the same for both point sizes (no gathers). */
template <int kStride>
PCL_MOVERS_ORGANIZER_AVX512_ATTRIBUTES inline void organizerLoad16(const float* xs, const float* ys,
                                                                   const float* zs, __m512& x,
                                                                   __m512& y, __m512& z) {
  static_assert(kStride == 0 || kStride == 4 || kStride == 8, "16 or 32-byte points only");
  if constexpr (kStride == 0) {
    x = _mm512_loadu_ps(xs);
    y = _mm512_loadu_ps(ys);
    z = _mm512_loadu_ps(zs);
  } else if constexpr (kStride == 4) {
    // Four points per register: x0..7 | y0..7 and z0..7 from each pair of registers.
    const __m512i xy = _mm512_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28, 1, 5, 9, 13, 17, 21, 25, 29);
    const __m512i zz =
        _mm512_setr_epi32(2, 6, 10, 14, 18, 22, 26, 30, 2, 6, 10, 14, 18, 22, 26, 30);
    const __m512 v0 = _mm512_loadu_ps(xs), v1 = _mm512_loadu_ps(xs + 16);
    const __m512 v2 = _mm512_loadu_ps(xs + 32), v3 = _mm512_loadu_ps(xs + 48);
    const __m512 xy01 = _mm512_permutex2var_ps(v0, xy, v1),
                 xy23 = _mm512_permutex2var_ps(v2, xy, v3);
    const __m512 z01 = _mm512_permutex2var_ps(v0, zz, v1), z23 = _mm512_permutex2var_ps(v2, zz, v3);
    x = _mm512_shuffle_f32x4(xy01, xy23, _MM_SHUFFLE(1, 0, 1, 0));
    y = _mm512_shuffle_f32x4(xy01, xy23, _MM_SHUFFLE(3, 2, 3, 2));
    z = _mm512_shuffle_f32x4(z01, z23, _MM_SHUFFLE(1, 0, 1, 0));
  } else {
    // Two points per register: x0..3 | y0..3 | z0..3 | - from each pair, then the 128-bit
    // quarters of the four results regrouped.
    const __m512i xyz = _mm512_setr_epi32(0, 8, 16, 24, 1, 9, 17, 25, 2, 10, 18, 26, 3, 11, 19, 27);
    __m512 q[4];
    for (int j = 0; j < 4; ++j)
      q[j] = _mm512_permutex2var_ps(_mm512_loadu_ps(xs + 32 * j), xyz,
                                    _mm512_loadu_ps(xs + 32 * j + 16));
    const __m512 lo01 = _mm512_shuffle_f32x4(q[0], q[1], _MM_SHUFFLE(1, 0, 1, 0));
    const __m512 lo23 = _mm512_shuffle_f32x4(q[2], q[3], _MM_SHUFFLE(1, 0, 1, 0));
    const __m512 hi01 = _mm512_shuffle_f32x4(q[0], q[1], _MM_SHUFFLE(3, 2, 3, 2));
    const __m512 hi23 = _mm512_shuffle_f32x4(q[2], q[3], _MM_SHUFFLE(3, 2, 3, 2));
    x = _mm512_shuffle_f32x4(lo01, lo23, _MM_SHUFFLE(2, 0, 2, 0));
    y = _mm512_shuffle_f32x4(lo01, lo23, _MM_SHUFFLE(3, 1, 3, 1));
    z = _mm512_shuffle_f32x4(hi01, hi23, _MM_SHUFFLE(2, 0, 2, 0));
  }
}

/** \brief organizerKernelScalar sixteen points at a time with AVX-512F (chosen at run time: the
 * library is built for plain x86-64), lane masks in mask registers. `m` must be a multiple of 16;
 * see organizerLoad16 for kStride and xs/ys/zs. Rows as in the 8-lane kernel: the previous row is
 * confirmed for all sixteen lanes with two comparisons when the mid-lines are ordered, otherwise
 * the row table and the mid-lines are gathered (same results, whatever the input order). */
template <int kStride>
PCL_MOVERS_ORGANIZER_AVX512_ATTRIBUTES inline void organizerKernelAvx512x16(
    const OrganizerKernelParams& c, const float* xs, const float* ys, const float* zs,
    std::size_t m, float* ws, float* ts, int* status, int* table_cell, int* column_code,
    int* rows) {
  const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.f), half = _mm512_set1_ps(0.5f);
  const __m512i sign = _mm512_set1_epi32(int(0x80000000u));
  const __m512i minus_one = _mm512_set1_epi32(-1), one_i = _mm512_set1_epi32(1);
  const __m512 max_range2 = _mm512_set1_ps(c.max_range2), min_range2 = _mm512_set1_ps(c.min_range2);
  const __m512 upper_limit = _mm512_set1_ps(c.upper_limit),
               upper_offset = _mm512_set1_ps(c.upper_offset);
  const __m512 lower_limit = _mm512_set1_ps(c.lower_limit),
               lower_offset = _mm512_set1_ps(c.lower_offset);
  const __m512 mean_offset = _mm512_set1_ps(c.mean_offset), g_min = _mm512_set1_ps(c.g_min);
  const __m512 g_scale = _mm512_set1_ps(c.g_scale), g_bins = _mm512_set1_ps(c.g_bins);
  const __m512 w_scale = _mm512_set1_ps(c.w_scale), w_bins = _mm512_set1_ps(c.w_bins);
  const __m512 azimuth_max = _mm512_set1_ps(c.azimuth_max);
  const __m512 columns_per_radian = _mm512_set1_ps(c.columns_per_radian);
  const __m512 columns = _mm512_set1_ps(c.columns);
  const __mmask16 full = c.full_revolution ? __mmask16(0xFFFF) : __mmask16(0);
  int previous_row = -1;
  __m512 upper_a = zero, upper_h = zero, lower_a = zero, lower_h = zero;
  for (std::size_t k = 0; k < m; k += 16) {
    __m512 x, y, z;
    if constexpr (kStride == 0)
      organizerLoad16<0>(xs + k, ys + k, zs + k, x, y, z);
    else
      organizerLoad16<kStride>(xs + k * kStride, nullptr, nullptr, x, y, z);
    const __mmask16 finite = _mm512_cmp_ps_mask(
        _mm512_add_ps(_mm512_add_ps(_mm512_sub_ps(x, x), _mm512_sub_ps(y, y)), _mm512_sub_ps(z, z)),
        zero, _CMP_EQ_OQ);
    const __m512 rho2 = _mm512_add_ps(_mm512_mul_ps(x, x), _mm512_mul_ps(y, y));
    const __m512 range2 = _mm512_add_ps(rho2, _mm512_mul_ps(z, z));
    const __mmask16 in_range = _mm512_cmp_ps_mask(range2, max_range2, _CMP_LE_OQ) &
                               _mm512_cmp_ps_mask(range2, min_range2, _CMP_GE_OQ) &
                               _mm512_cmp_ps_mask(rho2, zero, _CMP_GT_OQ);
    const __m512 w = _mm512_div_ps(one, _mm512_sqrt_ps(rho2));
    const __m512 t = _mm512_mul_ps(z, w);
    const __mmask16 in_beams =
        _mm512_cmp_ps_mask(t, _mm512_add_ps(upper_limit, _mm512_mul_ps(upper_offset, w)),
                           _CMP_LE_OQ) &
        _mm512_cmp_ps_mask(t, _mm512_add_ps(lower_limit, _mm512_mul_ps(lower_offset, w)),
                           _CMP_GE_OQ);
    const __m512 gf = _mm512_mul_ps(
        _mm512_sub_ps(_mm512_sub_ps(t, _mm512_mul_ps(mean_offset, w)), g_min), g_scale);
    const __m512 wf = _mm512_mul_ps(w, w_scale);
    const __mmask16 in_table =
        _mm512_cmp_ps_mask(gf, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(gf, g_bins, _CMP_LT_OQ) &
        _mm512_cmp_ps_mask(wf, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(wf, w_bins, _CMP_LT_OQ);
    const __m512 gi = _mm512_cvtepi32_ps(_mm512_cvttps_epi32(_mm512_maskz_mov_ps(in_table, gf)));
    const __m512 wi = _mm512_cvtepi32_ps(_mm512_cvttps_epi32(_mm512_maskz_mov_ps(in_table, wf)));
    const __m512i cell = _mm512_cvttps_epi32(_mm512_add_ps(_mm512_mul_ps(wi, g_bins), gi));
    _mm512_storeu_si512(table_cell + k, _mm512_mask_blend_epi32(in_table, minus_one, cell));
    bool same_row = false;
    if (previous_row >= 0) {
      // All sixteen in the table, below mid-line r-1 and not below mid-line r (NaN fails both).
      const __mmask16 confirmed =
          in_table &
          _mm512_cmp_ps_mask(t, _mm512_add_ps(upper_a, _mm512_mul_ps(upper_h, w)), _CMP_LT_OQ) &
          _mm512_cmp_ps_mask(t, _mm512_add_ps(lower_a, _mm512_mul_ps(lower_h, w)), _CMP_GE_OQ);
      same_row = confirmed == __mmask16(0xFFFF);
    }
    if (same_row) {
      _mm512_storeu_si512(rows + k, _mm512_set1_epi32(previous_row));
    } else {
      // organizerResolveRows with gathers: the 16-bit entry read as the low half of 32 bits (the
      // table has a padding entry), then the mid-line of the entry's row.
      const __m512i raw = _mm512_mask_i32gather_epi32(
          minus_one, in_table, _mm512_maskz_mov_epi32(in_table, cell), c.row_table, 2);
      const __m512i entry = _mm512_and_si512(raw, _mm512_set1_epi32(0xFFFF));
      const __mmask16 ambiguous = _mm512_cmpeq_epi32_mask(entry, _mm512_set1_epi32(0xFFFF));
      const __m512i row_index = _mm512_maskz_mov_epi32(__mmask16(~ambiguous), entry);
      const __m512 mid_a = _mm512_i32gather_ps(row_index, c.mid_a, 4);
      const __m512 mid_h = _mm512_i32gather_ps(row_index, c.mid_h, 4);
      const __mmask16 below =
          _mm512_cmp_ps_mask(t, _mm512_add_ps(mid_a, _mm512_mul_ps(mid_h, w)), _CMP_LT_OQ);
      const __m512i row = _mm512_mask_add_epi32(row_index, below, row_index, one_i);
      _mm512_storeu_si512(rows + k, _mm512_mask_mov_epi32(row, ambiguous, minus_one));
      const int last = rows[k + 15];
      if (c.ordered_mid_lines && last >= 0 && last != previous_row) {
        previous_row = last;
        const float inf = std::numeric_limits<float>::infinity();
        upper_a = _mm512_set1_ps(last > 0 ? c.mid_a[last - 1] : inf);
        upper_h = _mm512_set1_ps(last > 0 ? c.mid_h[last - 1] : 0.f);
        lower_a = _mm512_set1_ps(c.mid_a[last]);
        lower_h = _mm512_set1_ps(c.mid_h[last]);
      }
    }
    // fastAtan2, lane-wise.
    const __m512 ax = _mm512_abs_ps(x), ay = _mm512_abs_ps(y);
    const __m512 mx = _mm512_max_ps(ax, ay), mn = _mm512_min_ps(ax, ay);
    const __m512 a =
        _mm512_div_ps(mn, _mm512_mask_blend_ps(_mm512_cmp_ps_mask(mx, zero, _CMP_GT_OQ), one, mx));
    const __m512 s = _mm512_mul_ps(a, a);
    __m512 r =
        _mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(-0.01172120f), s), _mm512_set1_ps(0.05265332f));
    r = _mm512_sub_ps(_mm512_mul_ps(r, s), _mm512_set1_ps(0.11643287f));
    r = _mm512_add_ps(_mm512_mul_ps(r, s), _mm512_set1_ps(0.19354346f));
    r = _mm512_sub_ps(_mm512_mul_ps(r, s), _mm512_set1_ps(0.33262347f));
    r = _mm512_add_ps(_mm512_mul_ps(r, s), _mm512_set1_ps(0.99997726f));
    r = _mm512_mul_ps(r, a);
    r = _mm512_mask_sub_ps(r, _mm512_cmp_ps_mask(ay, ax, _CMP_GT_OQ), _mm512_set1_ps(1.57079637f),
                           r);
    r = _mm512_mask_sub_ps(r, _mm512_cmp_ps_mask(x, zero, _CMP_LT_OQ), _mm512_set1_ps(3.14159274f),
                           r);
    r = _mm512_castsi512_ps(_mm512_mask_xor_epi32(_mm512_castps_si512(r),
                                                  _mm512_cmp_ps_mask(y, zero, _CMP_LT_OQ),
                                                  _mm512_castps_si512(r), sign));
    __m512 f = _mm512_mul_ps(_mm512_sub_ps(azimuth_max, r), columns_per_radian);
    f = _mm512_mask_add_ps(f, full & _mm512_cmp_ps_mask(f, zero, _CMP_LT_OQ), f, columns);
    f = _mm512_mask_sub_ps(f, full & _mm512_cmp_ps_mask(f, columns, _CMP_GE_OQ), f, columns);
    const __mmask16 in_fov =
        _mm512_cmp_ps_mask(f, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(f, columns, _CMP_LT_OQ);
    const __m512 fc = _mm512_maskz_mov_ps(in_fov, f);
    const __m512i column = _mm512_cvttps_epi32(fc);
    const __mmask16 lean =
        _mm512_cmp_ps_mask(_mm512_sub_ps(fc, _mm512_cvtepi32_ps(column)), half, _CMP_GE_OQ);
    const __m512i twice = _mm512_slli_epi32(column, 1);
    _mm512_storeu_si512(column_code + k, _mm512_mask_add_epi32(twice, lean, twice, one_i));
    _mm512_storeu_ps(ws + k, w);
    _mm512_storeu_ps(ts + k, t);
    // finite ? (ok ? 0 : 2) : 1
    const __mmask16 ok = in_range & in_beams & in_fov;
    const __m512i st =
        _mm512_mask_mov_epi32(_mm512_maskz_mov_epi32(__mmask16(finite & ~ok), _mm512_set1_epi32(2)),
                              __mmask16(~finite), one_i);
    _mm512_storeu_si512(status + k, st);
  }
}

#undef PCL_MOVERS_ORGANIZER_AVX512_ATTRIBUTES

}  // namespace detail
}  // namespace pcl_movers
