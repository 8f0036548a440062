/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/free_space_map.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pcl_movers {

void FreeSpaceMap::setResolution(double azimuth_deg, double elevation_deg) {
  if (!(azimuth_deg > 0.01 && azimuth_deg <= 10 && elevation_deg > 0.01 && elevation_deg <= 10))
    throw std::invalid_argument(
        "FreeSpaceMap::setResolution: cell sizes must be in (0.01, 10] deg");
  az_res_deg_ = static_cast<float>(azimuth_deg);
  el_res_deg_ = static_cast<float>(elevation_deg);
  cols_ = static_cast<int>(std::ceil(360.0f / az_res_deg_));
  rows_ = static_cast<int>(std::ceil((max_el_deg_ - min_el_deg_) / el_res_deg_));
  scans_.clear();  // stored images have the old layout
  indexBeamRows();
  indexGroundRows();
}

void FreeSpaceMap::computeCells(const float* xs, const float* ys, const float* zs, std::size_t n,
                                int* cells, float* ranges) const {
  // Selects only, so that GCC and Clang vectorize the loop (this file is built with
  // -fno-math-errno -fno-trapping-math: no errno for the square roots, arithmetic may be
  // evaluated for lanes whose result is then discarded). One condition per select and every value
  // a float: GCC does not vectorize a select whose mask combines float and int comparisons.
  // SSE2, four points at a time, takes addScan() on a KITTI frame from 3.9 to 2.2 ms; GCC 12
  // does not vectorize this loop in an AVX2 clone ("control flow in loop").
  const float min_el = min_el_deg_, inv_el = 1.0f / el_res_deg_, inv_az = 1.0f / az_res_deg_;
  const float rows = static_cast<float>(rows_), cols = static_cast<float>(cols_);
  // floor(v) = int(v + kOffset) - kOffset for v > -kOffset: a truncation, which vectorizes
  // without SSE4.1's round instruction.
  constexpr float kOffset = 1024.0f;
  for (std::size_t i = 0; i < n; ++i) {
    const float x = xs[i], y = ys[i], z = zs[i];
    const float rxy = std::sqrt(x * x + y * y);
    const float r = std::sqrt(rxy * rxy + z * z);
    const float el = (detail::fastAtan2Deg(z, rxy) - min_el) * inv_el;
    const float az = (detail::fastAtan2Deg(y, x) + 180.0f) * inv_az;
    // Valid: r in [0.5 m, FLT_MAX] (NaN compares false). Invalid points get row -2 and column 0,
    // safe values for the conversions to int.
    float fr = r >= 0.5f ? el : -2.0f;
    fr = r <= std::numeric_limits<float>::max() ? fr : -2.0f;
    const float fc = fr >= -1.0f ? az : 0.0f;
    const float row = static_cast<float>(static_cast<int>(fr + kOffset)) - kOffset;
    float col = static_cast<float>(static_cast<int>(fc + kOffset)) - kOffset;
    col = col >= cols ? col - cols : (col < 0.0f ? col + cols : col);
    // Cell indices stay below 2^24: exact in a float.
    float cell = row >= 0.0f ? row * cols + col : -1.0f;
    cell = row < rows ? cell : -1.0f;
    cells[i] = static_cast<int>(cell);
    ranges[i] = r;
  }
}

void FreeSpaceMap::clearRange(Scan& s) const {
  const auto rows = static_cast<std::size_t>(rows_), cols = static_cast<std::size_t>(cols_);
  if (s.range.size() != rows * cols || s.sampled_rows.size() != rows) {
    s.range.assign(rows * cols, 0.0f);
    return;
  }
  for (std::size_t r = 0; r < rows; ++r)  // every return stored was in a sampled row
    if (s.sampled_rows[r])
      std::fill_n(s.range.begin() + static_cast<std::ptrdiff_t>(r * cols), cols, 0.0f);
}

void FreeSpaceMap::fillDropouts(Scan& s) const {
  // A ray that returned nothing between two that returned at about the same range is a dropout
  // (a dark or grazing spot, a lost packet), not something closer than the sensor's minimum
  // range: that silences a run of rays. It is given the nearer of its neighbours' ranges, the
  // surface it most likely missed, so that it neither vetoes its windows as a lost return nor
  // opens a gap in that surface.
  const auto cols = static_cast<std::size_t>(cols_);
  for (std::size_t r = 0; r < s.sampled_rows.size(); ++r) {
    if (!s.sampled_rows[r]) continue;
    float* row = s.range.data() + r * cols;
    for (std::size_t c = 0; c < cols; ++c) {
      if (row[c] != 0.0f) continue;
      const float left = row[c == 0 ? cols - 1 : c - 1], right = row[c + 1 == cols ? 0 : c + 1];
      const float nearer = std::min(left, right);
      if (nearer > 0.0f && std::abs(left - right) <= static_cast<float>(margin(nearer)))
        row[c] = nearer;
    }
  }
}

void FreeSpaceMap::coverColumns(Scan& s) const {
  // Walks the columns once from a covered one, so that a gap across the azimuth seam is measured
  // whole; a scan without any return covers nothing.
  const auto it = std::find(s.covered_cols.begin(), s.covered_cols.end(), 1);
  if (it == s.covered_cols.end()) return;
  const int start = static_cast<int>(it - s.covered_cols.begin());
  const int max_gap = static_cast<int>(std::floor(kMaxCoverageGapDeg / az_res_deg_));
  int last = start;  // the last column with a return, unwrapped
  for (int k = start + 1; k <= start + cols_; ++k) {
    if (!s.covered_cols[static_cast<std::size_t>(wrapCol(k))]) continue;
    if (k - last - 1 <= max_gap)
      for (int g = last + 1; g < k; ++g) s.covered_cols[static_cast<std::size_t>(wrapCol(g))] = 1;
    last = k;
  }
}

void FreeSpaceMap::addBlindScan() {
  if (scans_.size() >= static_cast<std::size_t>(history_)) scans_.pop_back();
  scans_.emplace_front();
  indexBeamRows();
}

bool FreeSpaceMap::passesOverGround(float sin_elevation) const {
  return sensor_height_ <= 0 || -sin_elevation * no_return_range_ <= sensor_height_;
}

bool FreeSpaceMap::rowPassesOverGround(int row) const {
  if (sensor_height_ <= 0) return true;  // geometry unknown: no ray is known to be lost
  const double el = (min_el_deg_ + (row + 1) * el_res_deg_) * M_PI / 180.0;  // its highest ray
  return passesOverGround(static_cast<float>(std::sin(el)));
}

void FreeSpaceMap::indexGroundRows() {
  over_ground_rows_.resize(static_cast<std::size_t>(rows_));
  for (int r = 0; r < rows_; ++r)
    over_ground_rows_[static_cast<std::size_t>(r)] = rowPassesOverGround(r) ? 1 : 0;
  versionWindowRows();
}

void FreeSpaceMap::indexBeamRows() {
  const auto rows = static_cast<std::size_t>(rows_);
  beam_rows_.assign(rows, 0);
  for (const Scan& scan : scans_)
    for (std::size_t r = 0; r < scan.sampled_rows.size() && r < rows; ++r)
      beam_rows_[r] |= scan.sampled_rows[r];
  beam_below_.assign(rows, -1);
  beam_above_.assign(rows, rows_);
  int last = -1;
  for (int r = 0; r < rows_; ++r) {
    beam_below_[static_cast<std::size_t>(r)] = last;
    if (beam_rows_[static_cast<std::size_t>(r)]) last = r;
  }
  last = rows_;
  for (int r = rows_ - 1; r >= 0; --r) {
    beam_above_[static_cast<std::size_t>(r)] = last;
    if (beam_rows_[static_cast<std::size_t>(r)]) last = r;
  }
  versionWindowRows();
}

void FreeSpaceMap::versionWindowRows(bool all) {
  const auto rows = static_cast<std::size_t>(rows_);
  if (beam_rows_.size() != rows || over_ground_rows_.size() != rows) {
    // Mid-way through setResolution(): the next index call versions the rows; judgePoint()
    // reads the scans directly until then.
    window_rows_.clear();
    row_version_.clear();
    return;
  }
  if (window_rows_.size() != rows || row_version_.size() != rows) {
    window_rows_.assign(rows, WindowRows());
    row_version_.assign(rows, 0);
    all = true;
  }
  for (int r = 0; r < rows_; ++r) {
    WindowRows w;
    windowRows(r, w.lo, w.hi);
    // A window wider than the masks (a setWindow() of more than 25 rows) is never trusted.
    const bool fits = w.hi - w.lo < 64;
    for (int k = w.lo; k <= w.hi; ++k) {
      const bool beam = beam_rows_[static_cast<std::size_t>(k)] != 0;
      w.beam = w.beam || beam;
      if (!fits) continue;
      const auto bit = std::uint64_t{1} << (k - w.lo);
      if (beam) w.beams |= bit;
      if (!over_ground_rows_[static_cast<std::size_t>(k)]) w.steep |= bit;
    }
    auto& stored = window_rows_[static_cast<std::size_t>(r)];
    if (all || !fits || !(w == stored) || row_version_[static_cast<std::size_t>(r)] == 0) {
      stored = w;
      row_version_[static_cast<std::size_t>(r)] = next_version_++;
    }
  }
}

void FreeSpaceMap::windowRows(int row, int& lo, int& hi) const {
  lo = row - win_rows_;
  hi = row + win_rows_;
  if (row >= 0 && row < rows_ && static_cast<std::size_t>(rows_) == beam_below_.size()) {
    const int below = beam_below_[static_cast<std::size_t>(row)];
    const int above = beam_above_[static_cast<std::size_t>(row)];
    if (below >= 0 && row - below <= kMaxBeamGapRows) lo = std::min(lo, below);
    if (above < rows_ && above - row <= kMaxBeamGapRows) hi = std::max(hi, above);
  }
  lo = std::max(lo, 0);
  hi = std::min(hi, rows_ - 1);
}

void FreeSpaceMap::scanWindow(const Scan& s, int row, int col, float& nearest, bool& beam,
                              bool& lost) const {
  // Nearest return over the window: a ray that passed just beside an edge never counts.
  nearest = 0.0f;
  beam = false;  // one of the window's rows is a beam of the sensor
  lost = false;  // a beam cell there should have returned (the ground) but did not
  int lo = 0, hi = -1;
  windowRows(row, lo, hi);
  for (int r = lo; r <= hi; ++r) {
    if (!beam_rows_[static_cast<std::size_t>(r)]) continue;
    beam = true;
    const bool steep = !over_ground_rows_[static_cast<std::size_t>(r)];
    for (int dc = -win_cols_; dc <= win_cols_; ++dc) {
      const int c = wrapCol(col + dc);
      const float v = s.range[static_cast<std::size_t>(r) * cols_ + c];
      if (v > 0.0f && (nearest == 0.0f || v < nearest)) nearest = v;
      lost = lost || (v == 0.0f && steep);
    }
  }
}

float FreeSpaceMap::windowCell(const Scan& s, int row, int col) const {
  const auto r = static_cast<std::size_t>(row);
  const std::size_t cell = r * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(col);
  const std::size_t block =
      r * static_cast<std::size_t>(poolBlocksPerRow()) + static_cast<std::size_t>(col / kPoolCols);
  // Allocated on the first judgement against this scan's memory (addScan() reuses the oldest
  // scan's, and sets every block unbuilt).
  if (s.pooled.size() != s.range.size()) s.pooled.resize(s.range.size());
  if (s.pooled_version[block] != row_version_[r]) {
    poolBlock(s, row, col - col % kPoolCols);
    s.pooled_version[block] = row_version_[r];
  }
  return s.pooled[cell];
}

void FreeSpaceMap::poolBlock(const Scan& s, int row, int first_col) const {
  constexpr float kNone = std::numeric_limits<float>::infinity();
  const int end_col = std::min(first_col + kPoolCols, cols_);
  // Pooled in a local block, not in the image: the compiler keeps it in registers (the image
  // might alias the scan's ranges, so every pass would load and store it).
  alignas(64) float pool[kPoolCols];
  std::fill(pool, pool + kPoolCols, kNone);
  const int w = win_cols_;
  // Blocks at the azimuth seam (and the last, short one) wrap their column index; the others
  // use a loop of kPoolCols without the wrap test, which vectorizes.
  const bool wraps = first_col - w < 0 || first_col + kPoolCols + w > cols_;
  const WindowRows& window = window_rows_[static_cast<std::size_t>(row)];
  for (int k = window.lo; k <= window.hi; ++k) {
    if (!beam_rows_[static_cast<std::size_t>(k)]) continue;
    const float silent = over_ground_rows_[static_cast<std::size_t>(k)] ? kNone : -1.0f;
    const float* in = s.range.data() + static_cast<std::size_t>(k) * cols_;
    for (int dc = -w; dc <= w; ++dc) {
      if (wraps) {
        for (int c = first_col; c < end_col; ++c) {
          const float v = in[wrapCol(c + dc)];
          pool[c - first_col] = std::min(pool[c - first_col], v > 0.0f ? v : silent);
        }
      } else {
        const float* src = in + first_col + dc;
        for (int c = 0; c < kPoolCols; ++c) {
          const float v = src[c];
          pool[c] = std::min(pool[c], v > 0.0f ? v : silent);
        }
      }
    }
  }
  std::copy(pool, pool + (end_col - first_col),
            s.pooled.data() + static_cast<std::size_t>(row) * cols_ + first_col);
}

void FreeSpaceMap::poolScan(Scan& s) {
  const auto rows = static_cast<std::size_t>(rows_), cols = static_cast<std::size_t>(cols_);
  if (row_version_.size() != rows || s.range.size() != rows * cols) return;  // built on use
  constexpr float kNone = std::numeric_limits<float>::infinity();
  const int w = win_cols_;
  // Pass 1: per beam row, the min over each cell's window columns of its returns (a silent ray
  // counting -1 in a steep row, +inf in another).
  row_minima_.resize(rows * cols);
  for (std::size_t k = 0; k < rows; ++k) {
    if (!beam_rows_[k]) continue;
    const float silent = over_ground_rows_[k] ? kNone : -1.0f;
    const float* in = s.range.data() + k * cols;
    float* out = row_minima_.data() + k * cols;
    const auto mapped = [&](int c) {
      const float v = in[wrapCol(c)];
      return v > 0.0f ? v : silent;
    };
    const int middle_begin = std::min(w, cols_), middle_end = std::max(middle_begin, cols_ - w);
    // The columns next to the azimuth seam wrap; the middle ones use a loop that vectorizes.
    for (int c = 0; c < cols_; c = c + 1 == middle_begin ? middle_end : c + 1) {
      float m = kNone;
      for (int dc = -w; dc <= w; ++dc) m = std::min(m, mapped(c + dc));
      out[c] = m;
    }
    std::fill(out + middle_begin, out + middle_end, kNone);
    for (int dc = -w; dc <= w; ++dc)
      for (int c = middle_begin; c < middle_end; ++c) {
        const float v = in[c + dc];
        out[c] = std::min(out[c], v > 0.0f ? v : silent);
      }
  }
  // Pass 2: per row, the min over its window's beam rows. A row whose window holds no beam is
  // never read (sightAt() knows it unknown from its WindowRows) and is left as it is: over half
  // the rows of a 64-beam sensor's image, and this pass is bound by the memory it writes.
  s.pooled.resize(rows * cols);
  for (std::size_t r = 0; r < rows; ++r) {
    const WindowRows& window = window_rows_[r];
    if (!window.beam) continue;
    float* out = s.pooled.data() + r * cols;
    bool first = true;
    for (int k = window.lo; k <= window.hi; ++k) {
      if (!beam_rows_[static_cast<std::size_t>(k)]) continue;
      const float* in = row_minima_.data() + static_cast<std::size_t>(k) * cols;
      if (first)
        std::copy(in, in + cols, out);
      else
        for (std::size_t c = 0; c < cols; ++c) out[c] = std::min(out[c], in[c]);
      first = false;
    }
  }
  const auto per_row = static_cast<std::size_t>(poolBlocksPerRow());
  for (std::size_t r = 0; r < rows; ++r)
    std::fill_n(s.pooled_version.begin() + static_cast<std::ptrdiff_t>(r * per_row), per_row,
                row_version_[r]);
}

void FreeSpaceMap::locate(const Scan& s, const Eigen::Vector3f* world_points, std::size_t n,
                          float* zs, float* ds, int* rows, int* cols) const {
  // Selects only, and every value a float, so that the second loop vectorizes (see
  // computeCells()). The cells are computed as cellRow() and cellCol() compute them, with the
  // division and an exact floor (truncation, less one where that rounded up), so that a point's
  // cell does not depend on how it was judged.
  const float min_el = min_el_deg_, el_res = el_res_deg_, az_res = az_res_deg_;
  const float n_cols = static_cast<float>(cols_);
  constexpr std::size_t kChunk = 64;
  alignas(64) float xs[kChunk], ys[kChunk];
  for (std::size_t first = 0; first < n; first += kChunk) {
    const std::size_t m = std::min(kChunk, n - first);
    float* z_out = zs + first;
    for (std::size_t i = 0; i < m; ++i) {
      const Eigen::Vector3f q = s.world_to_sensor * world_points[first + i];
      xs[i] = q.x();
      ys[i] = q.y();
      z_out[i] = q.z();
    }
    for (std::size_t i = 0; i < m; ++i) {
      const float x = xs[i], y = ys[i], z = z_out[i];
      const float rxy = std::sqrt(x * x + y * y);
      const float d = std::sqrt(rxy * rxy + z * z);
      float el = (detail::fastAtan2Deg(z, rxy) - min_el) / el_res;
      float az = (detail::fastAtan2Deg(y, x) + 180.0f) / az_res;
      // Outside (0.5 m, FLT_MAX] (sightAt() does not judge those): row -2 and column 0, safe
      // values for the conversions to int.
      el = d > 0.5f ? el : -2.0f;
      el = d <= std::numeric_limits<float>::max() ? el : -2.0f;
      az = d > 0.5f ? az : 0.0f;
      az = d <= std::numeric_limits<float>::max() ? az : 0.0f;
      const float el_trunc = static_cast<float>(static_cast<int>(el));
      const float az_trunc = static_cast<float>(static_cast<int>(az));
      const float row = el_trunc > el ? el_trunc - 1.0f : el_trunc;
      float col = az_trunc > az ? az_trunc - 1.0f : az_trunc;
      col = col >= n_cols ? col - n_cols : (col < 0.0f ? col + n_cols : col);
      ds[first + i] = d;
      rows[first + i] = static_cast<int>(row);
      cols[first + i] = static_cast<int>(col);
    }
  }
}

FreeSpaceMap::Sight FreeSpaceMap::judgePoint(const Scan& s, const Eigen::Vector3f& w,
                                             WindowRead read) const {
  float z = 0.0f, d = 0.0f;
  int row = 0, col = 0;
  locate(s, &w, 1, &z, &d, &row, &col);
  return sightAt(s, z, d, row, col, read);
}

void FreeSpaceMap::judgePoints(const Scan& s, const Eigen::Vector3f* world_points, std::size_t n,
                               Sight* sights) const {
  constexpr std::size_t kBlock = 256;
  alignas(64) float zs[kBlock], ds[kBlock];
  alignas(64) int rows[kBlock], cols[kBlock];
  for (std::size_t first = 0; first < n; first += kBlock) {
    const std::size_t m = std::min(kBlock, n - first);
    locate(s, world_points + first, m, zs, ds, rows, cols);
    // The pooled cells of a scan 1.5 s old are out of the caches: fetched ahead of their use.
    constexpr std::size_t kAhead = 16;
    const bool pooled = s.pooled.size() == s.range.size();
    for (std::size_t i = 0; i < m; ++i) {
      const std::size_t j = i + kAhead;
      if (pooled && j < m && rows[j] >= 0 && rows[j] < rows_)
        __builtin_prefetch(s.pooled.data() + static_cast<std::size_t>(rows[j]) * cols_ + cols[j]);
      sights[first + i] = sightAt(s, zs[i], ds[i], rows[i], cols[i]);
    }
  }
}

FreeSpaceMap::Sight FreeSpaceMap::sightAt(const Scan& s, float z, float d, int row, int col,
                                          WindowRead read) const {
  if (!(d > 0.5f && d <= std::numeric_limits<float>::max())) return Sight::kUnknown;
  float nearest = 0.0f;
  bool beam = false, lost = false;
  if (read == WindowRead::kPooled && row >= 0 && row < rows_ &&
      static_cast<std::size_t>(rows_) == row_version_.size()) {
    beam = window_rows_[static_cast<std::size_t>(row)].beam;
    if (!beam) return Sight::kUnknown;  // nothing returned around there, no beam cast (below)
    const float v = windowCell(s, row, col);
    lost = v < 0.0f;
    nearest = v < std::numeric_limits<float>::infinity() && !lost ? v : 0.0f;
  } else {
    scanWindow(s, row, col, nearest, beam, lost);
  }
  // A lost return may have been something closer than the sensor's minimum range, right in
  // front of the point: what the other rays saw says nothing then.
  if (lost) return Sight::kUnknown;
  const auto margin = static_cast<float>(this->margin(d));
  if (nearest == 0.0f) {
    // Nothing returned around there: unknown, unless the direction points down and a beam was
    // cast there (see setNoReturnRange()). Not within the sensor's minimum range of that scan
    // either: a return closer than the shortest one reported would not have been reported (a van
    // beside the path, closer than a 3 m minimum range, was silent and "seen through").
    // Nor outside the sensor's horizontal field of view, where no ray was cast at all (a
    // forward ladar: the part of a passing truck beside it was "seen through").
    if (!(z < 0.0f && beam && passesOverGround(z / d) && d > s.min_range + margin &&
          no_return_range_ > 0 && col >= 0 && col < cols_ &&
          s.covered_cols.size() == static_cast<std::size_t>(cols_) &&
          s.covered_cols[static_cast<std::size_t>(col)]))
      return Sight::kUnknown;
    // Seen empty up to the no-return range only: nothing is known beyond it.
    return no_return_range_ > d + margin ? Sight::kThrough : Sight::kBefore;
  }
  if (nearest > d + margin) return Sight::kThrough;
  return nearest >= d - margin ? Sight::kAt : Sight::kBefore;
}

const FreeSpaceMap::Scan* FreeSpaceMap::scanWithReturns(int frames_ago) const {
  if (frames_ago < 0 || frames_ago >= static_cast<int>(scans_.size())) return nullptr;
  const Scan& s = scans_[static_cast<std::size_t>(frames_ago)];
  return s.range.empty() ? nullptr : &s;  // a blind frame saw nothing
}

FreeSpaceMap::Evidence FreeSpaceMap::test(const std::vector<Eigen::Vector3f>& world_points,
                                          int frames_ago) const {
  Evidence e;
  const Scan* s = scanWithReturns(frames_ago);
  if (!s) return e;
  // A chunk at a time on the stack: the tracker tests every track every frame.
  constexpr std::size_t kChunk = 256;
  Sight sights[kChunk];
  for (std::size_t first = 0; first < world_points.size(); first += kChunk) {
    const std::size_t m = std::min(kChunk, world_points.size() - first);
    judgePoints(*s, world_points.data() + first, m, sights);
    for (std::size_t i = 0; i < m; ++i) {
      if (sights[i] == Sight::kUnknown) continue;
      ++e.tested;
      if (sights[i] == Sight::kThrough) ++e.seen_through;
    }
  }
  return e;
}

FreeSpaceMap::Sight FreeSpaceMap::judge(const Eigen::Vector3f& world_point, int frames_ago) const {
  const Scan* s = scanWithReturns(frames_ago);
  return s ? judgePoint(*s, world_point) : Sight::kUnknown;
}

void FreeSpaceMap::judge(const std::vector<Eigen::Vector3f>& world_points, int frames_ago,
                         std::vector<Sight>& sights) const {
  sights.assign(world_points.size(), Sight::kUnknown);
  const Scan* s = scanWithReturns(frames_ago);
  if (!s) return;
  judgePoints(*s, world_points.data(), world_points.size(), sights.data());
}

}  // namespace pcl_movers
