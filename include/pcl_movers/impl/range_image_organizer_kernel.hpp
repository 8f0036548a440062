/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * The 8-lane kernel of RangeImageOrganizer, included by range_image_organizer.hpp for AVX2 (CPUs
 * with AVX-512 run range_image_organizer_kernel16.hpp) with these macros set:
 * PCL_MOVERS_ORGANIZER_KERNEL (function name), PCL_MOVERS_ORGANIZER_SELECT (name of its lane-select
 * helper), and PCL_MOVERS_ORGANIZER_KERNEL_ATTRIBUTES (target and, for GCC, no fused multiply-add:
 * the results must match the scalar reference bit for bit). No include guard on purpose.
 */

/** \brief Lane-wise mask ? a : b. */
PCL_MOVERS_ORGANIZER_KERNEL_ATTRIBUTES inline __m256 PCL_MOVERS_ORGANIZER_SELECT(__m256 mask,
                                                                                 __m256 a,
                                                                                 __m256 b) {
  return _mm256_or_ps(_mm256_and_ps(mask, a), _mm256_andnot_ps(mask, b));
}

/** \brief organizerKernel eight points at a time, for CPUs with AVX2 (chosen at run time: the
 * library is built for plain x86-64). Same operations, same order, no FMA: identical results.
 * `m` must be a multiple of 8.
 *
 * Rows: scanners deliver their points beam after beam (KITTI) or in runs of one beam, so eight
 * consecutive points nearly always share the row of the point before them. When the mid-lines are
 * ordered (c.ordered_mid_lines), that row r is confirmed for all eight lanes at once by comparing
 * t with mid-lines r-1 and r (the same float expressions organizerResolveRows evaluates); only
 * when a lane is outside the table or in another row are the row table and the mid-lines
 * gathered, which cost nearly half of the kernel's time on KITTI frames. Both ways give the
 * number of mid-lines above t, so the rows are those of the scalar reference whatever the input
 * order (input in another order only loses the shortcut). */
PCL_MOVERS_ORGANIZER_KERNEL_ATTRIBUTES inline void PCL_MOVERS_ORGANIZER_KERNEL(
    const OrganizerKernelParams& c, const float* xs, const float* ys, const float* zs,
    std::size_t m, float* ws, float* ts, int* status, int* table_cell, int* column_code,
    int* rows) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.f), half = _mm256_set1_ps(0.5f);
  const __m256 sign = _mm256_set1_ps(-0.f);
  const __m256 max_range2 = _mm256_set1_ps(c.max_range2), min_range2 = _mm256_set1_ps(c.min_range2);
  const __m256 upper_limit = _mm256_set1_ps(c.upper_limit),
               upper_offset = _mm256_set1_ps(c.upper_offset);
  const __m256 lower_limit = _mm256_set1_ps(c.lower_limit),
               lower_offset = _mm256_set1_ps(c.lower_offset);
  const __m256 mean_offset = _mm256_set1_ps(c.mean_offset), g_min = _mm256_set1_ps(c.g_min);
  const __m256 g_scale = _mm256_set1_ps(c.g_scale), g_bins = _mm256_set1_ps(c.g_bins);
  const __m256 w_scale = _mm256_set1_ps(c.w_scale), w_bins = _mm256_set1_ps(c.w_bins);
  const __m256 azimuth_max = _mm256_set1_ps(c.azimuth_max);
  const __m256 columns_per_radian = _mm256_set1_ps(c.columns_per_radian);
  const __m256 columns = _mm256_set1_ps(c.columns);
  const __m256 full = c.full_revolution ? _mm256_castsi256_ps(_mm256_set1_epi32(-1)) : zero;
  // Row of the previous eight points' last lane (-1: none) and its two mid-lines; above row 0
  // there is no mid-line (+inf never fails the comparison for a finite t).
  int previous_row = -1;
  __m256 upper_a = zero, upper_h = zero, lower_a = zero, lower_h = zero;
  for (std::size_t k = 0; k < m; k += 8) {
    const __m256 x = _mm256_loadu_ps(xs + k), y = _mm256_loadu_ps(ys + k),
                 z = _mm256_loadu_ps(zs + k);
    const __m256 finite = _mm256_cmp_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_sub_ps(x, x), _mm256_sub_ps(y, y)), _mm256_sub_ps(z, z)),
        zero, _CMP_EQ_OQ);
    const __m256 rho2 = _mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y));
    const __m256 range2 = _mm256_add_ps(rho2, _mm256_mul_ps(z, z));
    const __m256 in_range =
        _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(range2, max_range2, _CMP_LE_OQ),
                                    _mm256_cmp_ps(range2, min_range2, _CMP_GE_OQ)),
                      _mm256_cmp_ps(rho2, zero, _CMP_GT_OQ));
    const __m256 w = _mm256_div_ps(one, _mm256_sqrt_ps(rho2));
    const __m256 t = _mm256_mul_ps(z, w);
    const __m256 in_beams = _mm256_and_ps(
        _mm256_cmp_ps(t, _mm256_add_ps(upper_limit, _mm256_mul_ps(upper_offset, w)), _CMP_LE_OQ),
        _mm256_cmp_ps(t, _mm256_add_ps(lower_limit, _mm256_mul_ps(lower_offset, w)), _CMP_GE_OQ));
    const __m256 gf = _mm256_mul_ps(
        _mm256_sub_ps(_mm256_sub_ps(t, _mm256_mul_ps(mean_offset, w)), g_min), g_scale);
    const __m256 wf = _mm256_mul_ps(w, w_scale);
    const __m256 in_table = _mm256_and_ps(
        _mm256_and_ps(_mm256_cmp_ps(gf, zero, _CMP_GE_OQ), _mm256_cmp_ps(gf, g_bins, _CMP_LT_OQ)),
        _mm256_and_ps(_mm256_cmp_ps(wf, zero, _CMP_GE_OQ), _mm256_cmp_ps(wf, w_bins, _CMP_LT_OQ)));
    const __m256 gi = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(_mm256_and_ps(in_table, gf)));
    const __m256 wi = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(_mm256_and_ps(in_table, wf)));
    const __m256i cell = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(wi, g_bins), gi));
    _mm256_storeu_si256(
        reinterpret_cast<__m256i*>(table_cell + k),
        _mm256_or_si256(_mm256_and_si256(_mm256_castps_si256(in_table), cell),
                        _mm256_andnot_si256(_mm256_castps_si256(in_table), _mm256_set1_epi32(-1))));
    bool same_row = false;
    if (previous_row >= 0) {
      // All eight in the table (where the mid-lines are ordered), below mid-line r-1 and not
      // below mid-line r. NaN lanes fail both comparisons.
      const __m256 below_upper =
          _mm256_cmp_ps(t, _mm256_add_ps(upper_a, _mm256_mul_ps(upper_h, w)), _CMP_LT_OQ);
      const __m256 above_lower =
          _mm256_cmp_ps(t, _mm256_add_ps(lower_a, _mm256_mul_ps(lower_h, w)), _CMP_GE_OQ);
      same_row = _mm256_movemask_ps(
                     _mm256_and_ps(in_table, _mm256_and_ps(below_upper, above_lower))) == 0xFF;
    }
    if (same_row) {
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(rows + k), _mm256_set1_epi32(previous_row));
    } else {
      // organizerResolveRows with gathers: the 16-bit entry read as the low half of 32 bits (the
      // table has a padding entry), then the mid-line of the entry's row.
      const __m256i table_mask = _mm256_castps_si256(in_table);
      const __m256i cell_index = _mm256_and_si256(table_mask, cell);
      const __m256i raw = _mm256_mask_i32gather_epi32(_mm256_set1_epi32(-1),
                                                      reinterpret_cast<const int*>(c.row_table),
                                                      cell_index, table_mask, 2);
      const __m256i entry = _mm256_and_si256(raw, _mm256_set1_epi32(0xFFFF));
      const __m256i ambiguous = _mm256_cmpeq_epi32(entry, _mm256_set1_epi32(0xFFFF));
      const __m256i row_index = _mm256_andnot_si256(ambiguous, entry);
      const __m256 mid_a = _mm256_i32gather_ps(c.mid_a, row_index, 4);
      const __m256 mid_h = _mm256_i32gather_ps(c.mid_h, row_index, 4);
      const __m256 below =
          _mm256_cmp_ps(t, _mm256_add_ps(mid_a, _mm256_mul_ps(mid_h, w)), _CMP_LT_OQ);
      const __m256i row = _mm256_sub_epi32(row_index, _mm256_castps_si256(below));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(rows + k),
                          _mm256_or_si256(ambiguous, _mm256_andnot_si256(ambiguous, row)));
      const int last = rows[k + 7];
      if (c.ordered_mid_lines && last >= 0 && last != previous_row) {
        previous_row = last;
        const float inf = std::numeric_limits<float>::infinity();
        upper_a = _mm256_set1_ps(last > 0 ? c.mid_a[last - 1] : inf);
        upper_h = _mm256_set1_ps(last > 0 ? c.mid_h[last - 1] : 0.f);
        lower_a = _mm256_set1_ps(c.mid_a[last]);
        lower_h = _mm256_set1_ps(c.mid_h[last]);
      }
    }
    // fastAtan2, lane-wise.
    const __m256 ax = _mm256_andnot_ps(sign, x), ay = _mm256_andnot_ps(sign, y);
    const __m256 mx = _mm256_max_ps(ax, ay), mn = _mm256_min_ps(ax, ay);
    const __m256 a = _mm256_div_ps(
        mn, PCL_MOVERS_ORGANIZER_SELECT(_mm256_cmp_ps(mx, zero, _CMP_GT_OQ), mx, one));
    const __m256 s = _mm256_mul_ps(a, a);
    __m256 r =
        _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(-0.01172120f), s), _mm256_set1_ps(0.05265332f));
    r = _mm256_sub_ps(_mm256_mul_ps(r, s), _mm256_set1_ps(0.11643287f));
    r = _mm256_add_ps(_mm256_mul_ps(r, s), _mm256_set1_ps(0.19354346f));
    r = _mm256_sub_ps(_mm256_mul_ps(r, s), _mm256_set1_ps(0.33262347f));
    r = _mm256_add_ps(_mm256_mul_ps(r, s), _mm256_set1_ps(0.99997726f));
    r = _mm256_mul_ps(r, a);
    r = PCL_MOVERS_ORGANIZER_SELECT(_mm256_cmp_ps(ay, ax, _CMP_GT_OQ),
                                    _mm256_sub_ps(_mm256_set1_ps(1.57079637f), r), r);
    r = PCL_MOVERS_ORGANIZER_SELECT(_mm256_cmp_ps(x, zero, _CMP_LT_OQ),
                                    _mm256_sub_ps(_mm256_set1_ps(3.14159274f), r), r);
    r = PCL_MOVERS_ORGANIZER_SELECT(_mm256_cmp_ps(y, zero, _CMP_LT_OQ), _mm256_xor_ps(r, sign), r);
    __m256 f = _mm256_mul_ps(_mm256_sub_ps(azimuth_max, r), columns_per_radian);
    f = PCL_MOVERS_ORGANIZER_SELECT(_mm256_and_ps(full, _mm256_cmp_ps(f, zero, _CMP_LT_OQ)),
                                    _mm256_add_ps(f, columns), f);
    f = PCL_MOVERS_ORGANIZER_SELECT(_mm256_and_ps(full, _mm256_cmp_ps(f, columns, _CMP_GE_OQ)),
                                    _mm256_sub_ps(f, columns), f);
    const __m256 in_fov =
        _mm256_and_ps(_mm256_cmp_ps(f, zero, _CMP_GE_OQ), _mm256_cmp_ps(f, columns, _CMP_LT_OQ));
    const __m256 fc = _mm256_and_ps(in_fov, f);
    const __m256i column = _mm256_cvttps_epi32(fc);
    const __m256 lean =
        _mm256_cmp_ps(_mm256_sub_ps(fc, _mm256_cvtepi32_ps(column)), half, _CMP_GE_OQ);
    _mm256_storeu_si256(
        reinterpret_cast<__m256i*>(column_code + k),
        _mm256_add_epi32(_mm256_slli_epi32(column, 1),
                         _mm256_and_si256(_mm256_castps_si256(lean), _mm256_set1_epi32(1))));
    _mm256_storeu_ps(ws + k, w);
    _mm256_storeu_ps(ts + k, t);
    const __m256i ok =
        _mm256_castps_si256(_mm256_and_ps(_mm256_and_ps(in_range, in_beams), in_fov));
    const __m256i fin = _mm256_castps_si256(finite);
    // finite ? (ok ? 0 : 2) : 1
    const __m256i st =
        _mm256_or_si256(_mm256_andnot_si256(fin, _mm256_set1_epi32(1)),
                        _mm256_and_si256(fin, _mm256_andnot_si256(ok, _mm256_set1_epi32(2))));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(status + k), st);
  }
}
