/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/point_cloud.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <vector>

namespace pcl_movers {

/** \brief Remembers what the last few scans saw *through*, to tell movers from static objects.
 *
 * A scan is stored as a coarse spherical range image in its own sensor frame (nearest return per
 * cell, every finite point including ground) together with its pose. A world point `q` was **seen
 * through** by a stored scan when that scan's rays around the direction of `q` all ended clearly
 * beyond `q`: the space `q` occupies now was empty then. For a static opaque object this cannot
 * happen whatever the registration or segmentation error: the ray from any viewpoint to a point of
 * its surface meets the object at or before that point. A moving object, on the other hand, always
 * occupies space that was seen empty earlier (approaching or crossing), or leaves space that is
 * seen through now (receding: test its earlier points against the current scan).
 *
 * Conservative by construction: the nearest range over a small window of cells around the direction
 * is compared (edges, thin poles and mixed pixels never count), empty cells (no return) are
 * unknown, and the margin grows with range (beam divergence, pose error, sparse far sampling).
 */
class FreeSpaceMap {
 public:
  using Ptr = std::shared_ptr<FreeSpaceMap>;
  using ConstPtr = std::shared_ptr<const FreeSpaceMap>;

  FreeSpaceMap() = default;

  /** \brief Number of scans kept (the current one plus `history - 1` earlier ones). */
  void setHistory(int history) { history_ = history < 1 ? 1 : history; }
  int getHistory() const { return history_; }
  /** \brief Angular cell sizes of the stored range images [deg]. */
  void setResolution(double azimuth_deg, double elevation_deg);
  double getAzimuthResolution() const { return az_res_deg_; }
  double getElevationResolution() const { return el_res_deg_; }
  /** \brief A point is seen through when the nearest stored range around its direction exceeds
   * its distance by max(margin, margin_per_metre · distance) [m]. */
  void setMargin(double margin, double margin_per_metre) {
    margin_ = margin;
    margin_per_metre_ = margin_per_metre;
  }
  double getMargin() const { return margin_; }
  double getMarginPerMetre() const { return margin_per_metre_; }
  /** \brief The range margin [m] at `distance` [m]: max(margin, margin_per_metre · distance). */
  double margin(double distance) const { return std::max(margin_, margin_per_metre_ * distance); }
  /** \brief A direction below the stored scan's sensor (z < 0 in its frame) whose whole window
   * returned nothing, although one of the window's rows is a beam (some stored scan has a return
   * in it), counts as seen empty up to this range [m]; 0, the default:
   * such a direction is unknown and not tested. See DetectorParameters::free_space_no_return for
   * why only downward directions. */
  void setNoReturnRange(double range) {
    no_return_range_ = range > 0 ? range : 0;
    indexGroundRows();
  }
  double getNoReturnRange() const { return no_return_range_; }
  /** \brief Height of the sensor above the ground [m] for the no-return rule: only a ray that
   * would meet the ground beyond the no-return range counts, and a point whose window holds a
   * steeper ray that returned nothing is not tested at all. A steeper ray should have returned
   * from the ground, so its silence means a return dropped, absorbed or closer than the sensor's
   * minimum range (a parked van passed at 2 m: its side was inside a VLP-16's 2 m minimum range
   * and the silent rays made it "seen through"). 0, the default: every downward ray counts. */
  void setSensorHeight(double height) {
    sensor_height_ = height > 0 ? height : 0;
    indexGroundRows();
  }
  double getSensorHeight() const { return sensor_height_; }
  /** \brief Half-size of the cell window compared around a direction (rows, columns). */
  void setWindow(int rows, int cols) {
    win_rows_ = rows < 0 ? 0 : rows;
    win_cols_ = cols < 0 ? 0 : cols;
    versionWindowRows(true);
  }

  /** \brief Pool each scan's windows whole when it is added, for users that judge points all
   * over each scan (the detector's motion-aware segmentation judges every cluster), instead of a
   * block of cells at a time on first use (default), which suits judging around a few objects:
   * a whole scan costs about as much as the blocks that a tracker's tests need. */
  void setPoolOnAdd(bool pool_on_add) { pool_on_add_ = pool_on_add; }
  bool getPoolOnAdd() const { return pool_on_add_; }

  /** \brief Adds a scan (points in the sensor frame, NaN allowed) taken at `pose` (sensor→world).
   * The oldest scan is forgotten when more than `history` are stored. */
  template <typename PointT>
  void addScan(const pcl::PointCloud<PointT>& scan, const Eigen::Isometry3d& pose);

  /** \brief Adds a frame without a scan (a blind frame: no return at all), so that `frames_ago`
   * keeps counting frames; tests against it find nothing (an empty Evidence). */
  void addBlindScan();

  /** \brief Where the sensor was (world frame) for the scan stored `frames_ago` scans back;
   * NaN when that scan is not stored. */
  Eigen::Vector3f sensorPosition(int frames_ago = 0) const {
    if (frames_ago < 0 || frames_ago >= static_cast<int>(scans_.size()))
      return Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    return scans_[static_cast<std::size_t>(frames_ago)].world_to_sensor.inverse().translation();
  }

  /** \brief Scans stored (≤ history). Index 0 is the latest. */
  int size() const { return static_cast<int>(scans_.size()); }

  /** \brief Result of a query. */
  struct Evidence {
    int tested = 0;        ///< points whose direction had at least one return in the window
    int seen_through = 0;  ///< of those, points lying in space the scan saw empty
    double fraction() const { return tested > 0 ? static_cast<double>(seen_through) / tested : 0; }
  };

  /** \brief Tests world points against the scan stored `frames_ago` scans back (0 = latest).
   * Returns an empty Evidence when that scan is not stored. */
  Evidence test(const std::vector<Eigen::Vector3f>& world_points, int frames_ago) const;

  /** \brief What a stored scan saw along the direction of a point. */
  enum class Sight : std::uint8_t {
    kUnknown,  ///< not tested: no return around there, a lost return, or no such scan
    kThrough,  ///< its rays ended clearly beyond the point: the point's space was empty then
    kAt,       ///< its nearest return was at the point's distance (within the margin): occupied
    kBefore,   ///< its nearest return was clearly nearer: the point was hidden then
  };
  /** \brief Per point, what the scan stored `frames_ago` scans back saw along its direction
   * (sights[i] for world_points[i]); test() counts kThrough among the points that are not
   * kUnknown. */
  void judge(const std::vector<Eigen::Vector3f>& world_points, int frames_ago,
             std::vector<Sight>& sights) const;
  /** \brief judge() of one point (kUnknown when that scan is not stored). */
  Sight judge(const Eigen::Vector3f& world_point, int frames_ago) const;

  /** \brief Forgets all scans. */
  void clear() {
    scans_.clear();
    indexBeamRows();
  }

 protected:
  struct Scan {
    Eigen::Isometry3f world_to_sensor = Eigen::Isometry3f::Identity();
    std::vector<float> range;  ///< 0 = no return; empty for a blind frame (addBlindScan())
    /// 1 for the rows (elevations) in which some return was stored.
    std::vector<std::uint8_t> sampled_rows;
    /// 1 for the columns (azimuths) the sensor covered: those with a return, and gaps between
    /// them of up to kMaxCoverageGapDeg (see coverColumns()).
    std::vector<std::uint8_t> covered_cols;
    /// Shortest range returned [m]: nothing closer is reported by the sensor (its minimum range),
    /// so a silent ray says nothing about the space up to there.
    float min_range = 0.0f;
    /// What judgePoint() reads of this scan around each cell (see poolBlock()): built whole when
    /// the scan is added (poolScan()), and again a block of kPoolCols cells at a time, on use,
    /// where the window rows changed since; a block is valid while its pooled_version equals
    /// the map's row_version_ of its row. A cache, hence mutable: a map is used by one thread at
    /// a time.
    mutable std::vector<float> pooled;
    mutable std::vector<std::uint64_t> pooled_version;  ///< per block, row-major; 0 = not built
  };
  /** \brief cells[i] = row · cols + column of the direction of point i (sensor frame), or -1
   * (not finite, under 0.5 m, outside the rows); ranges[i] = its range. */
  void computeCells(const float* xs, const float* ys, const float* zs, std::size_t n, int* cells,
                    float* ranges) const;
  /** \brief Fills each silent cell of `s.range` whose two azimuth neighbours returned at
   * about the same range (a dropout) with the nearer of their ranges. */
  void fillDropouts(Scan& s) const;
  /** \brief Marks as covered the silent columns of `s` between two columns with returns at most
   * kMaxCoverageGapDeg apart: azimuths between a sensor's samples, or a sky-facing gap, not
   * outside its horizontal field of view. */
  void coverColumns(Scan& s) const;
  /** \brief Sets every cell of `s.range` to 0 (no return) for a new scan: only the rows that
   * the scan whose memory it reuses wrote, when the layout is the same (a sensor's beams cover
   * a fraction of the rows; the others are still clear). */
  void clearRange(Scan& s) const;
  /** \brief A ray at this elevation (its sine) stays above the ground up to the no-return range
   * (see setSensorHeight()). */
  bool passesOverGround(float sin_elevation) const;
  /** \brief passesOverGround() for the rays of a row (true without a sensor height). */
  bool rowPassesOverGround(int row) const;
  /** \brief Recomputes over_ground_rows_ (rowPassesOverGround() of every row: a sine per row,
   * not per point and window row). */
  void indexGroundRows();
  /** \brief The scan stored `frames_ago` scans back, or nullptr when it is not stored or is a
   * blind frame (nothing to judge against). */
  const Scan* scanWithReturns(int frames_ago) const;
  /** \brief How judgePoint() reads a window: from the pooled cache (windowCell()), or cell by
   * cell (scanWindow(): the definition, kept for the rows outside the image and for tests). */
  enum class WindowRead : std::uint8_t { kPooled, kDirect };
  /** \brief What scan `s` saw along the direction of world point `w` (locate() and
   * sightAt()). */
  Sight judgePoint(const Scan& s, const Eigen::Vector3f& w,
                   WindowRead read = WindowRead::kPooled) const;
  /** \brief Where world points lie in scan `s`'s frame: per point its height z, distance d
   * and cell (row, column; as cellRow() and cellCol() give them, row out of range when d is
   * not in (0.5 m, FLT_MAX]). The transform per point, the square roots, arc tangents and
   * divisions in a loop that vectorizes. */
  void locate(const Scan& s, const Eigen::Vector3f* world_points, std::size_t n, float* zs,
              float* ds, int* rows, int* cols) const;
  /** \brief What scan `s` saw along a direction located at (z, d, row, col) (locate()). */
  Sight sightAt(const Scan& s, float z, float d, int row, int col,
                WindowRead read = WindowRead::kPooled) const;
  /** \brief judgePoint() of world_points[0..n) into sights, a block of points at a time
   * (locate() together, then each point's pooled cell, fetched ahead: a scan 1.5 s old is out
   * of the caches). */
  void judgePoints(const Scan& s, const Eigen::Vector3f* world_points, std::size_t n,
                   Sight* sights) const;
  /** \brief Reads the window around cell (row, col) of scan `s` cell by cell: its nearest return
   * (0: none), whether one of its rows is a beam and whether a steep ray of it was silent. The
   * definition of what windowCell() caches. */
  void scanWindow(const Scan& s, int row, int col, float& nearest, bool& beam, bool& lost) const;
  /** \brief Cell (row, col) of `s.pooled`; its block of kPoolCols cells is built first when it
   * is stale (poolBlock()). One lookup instead of the window's 15 or more cells per judged point:
   * the split judges about 26k points per KITTI frame. */
  float windowCell(const Scan& s, int row, int col) const;
  /** \brief Builds `s.pooled` for the cells first_col..first_col + kPoolCols - 1 of `row`: per
   * cell, the min over its window's beam cells of their return, a silent steep ray counting -1
   * and another silent ray +inf (so the min is -1 when scanWindow() finds a lost return, +inf
   * when it finds nothing, else the nearest return). Blocks, not rows: most scans are queried
   * around a few objects only (the tracker's tests: ~30 points per row queried). */
  void poolBlock(const Scan& s, int row, int first_col) const;
  /** \brief Builds every block of `s.pooled` (the newest scan, after indexBeamRows()) in two
   * passes: per beam row, the min over each cell's window columns; then per row, the min of
   * those over its window's beam rows. The same values as poolBlock(), from an image still in
   * the caches, and each beam row's columns pooled once instead of once per window holding it.
   * Built on first use instead, the blocks of a scan 1.5 s old waited on memory most of the
   * time (see docs/design.md). */
  void poolScan(Scan& s);
  static constexpr int kPoolCols = 32;
  int poolBlocksPerRow() const { return (cols_ + kPoolCols - 1) / kPoolCols; }

  /** \brief After the beam rows or the steep rows changed: gives a new version to each row whose
   * window reads other rows or other flags (every row when `all`), so that every scan rebuilds
   * that row on its next use. */
  void versionWindowRows(bool all = false);
  /** \brief Recomputes beam_rows_ (rows with a return in any stored scan: the sensor's beams)
   * and, per row, the nearest beam row below and above it. */
  void indexBeamRows();
  /** \brief Rows compared around `row`: ±win_rows and at least the nearest beam below and above
   * (within kMaxBeamGapRows), so that a sparse sensor's direction between two beams is judged by
   * both. Otherwise a point at an object's top edge, tested against an earlier scan whose
   * beam just above passed over the object and whose beam below hit it outside the window, was
   * "seen through" (VLP-16, 2° between beams: a parked van passed at 2 m was a mover). */
  void windowRows(int row, int& lo, int& hi) const;
  static constexpr int kMaxBeamGapRows = 25;
  /// Widest silent azimuth gap still inside a sensor's field of view [deg]: several times the
  /// coarsest column step of the supported sensors (the forward ladar's 0.25°, against the map's
  /// 0.2° columns).
  static constexpr float kMaxCoverageGapDeg = 2.0f;
  /** \brief The row and column of a direction: the definition that locate() computes in its
   * vectorized loop (and the tests compare it with). */
  int cellRow(float elevation_deg) const {
    return static_cast<int>(std::floor((elevation_deg - min_el_deg_) / el_res_deg_));
  }
  int cellCol(float azimuth_deg) const {
    return wrapCol(static_cast<int>(std::floor((azimuth_deg + 180.0f) / az_res_deg_)));
  }
  /** \brief Column `c` (at most one turn off the image) wrapped across the azimuth seam. */
  int wrapCol(int c) const { return c >= cols_ ? c - cols_ : (c < 0 ? c + cols_ : c); }

  int history_ = 8;
  float az_res_deg_ = 0.2f, el_res_deg_ = 0.2f;
  // Elevations covered: every preset sensor (HDL-64E −24.9°…+2°, OS1 ±16.6°, VLP-16 ±15°).
  float min_el_deg_ = -35.0f, max_el_deg_ = 25.0f;
  int rows_ = 300, cols_ = 1800;
  double margin_ = 0.3, margin_per_metre_ = 0.02;
  double no_return_range_ = 0;
  double sensor_height_ = 0;
  int win_rows_ = 2, win_cols_ = 1;
  bool pool_on_add_ = false;
  std::deque<Scan> scans_;
  /// Rows with a return in some stored scan (the sensor's beams: between the beams of a sparse
  /// sensor, VLP-16 2° = 10 rows apart, a cell is empty because no ray was cast there), and per
  /// row the nearest such row below / above it (-1 / rows_ when none).
  std::vector<std::uint8_t> beam_rows_;
  std::vector<int> beam_below_, beam_above_;
  /// rowPassesOverGround() per row (indexGroundRows()); all rows without a sensor height.
  std::vector<std::uint8_t> over_ground_rows_ =
      std::vector<std::uint8_t>(static_cast<std::size_t>(rows_), 1);
  /// Per row, what its window reads (versionWindowRows()): rows lo..hi, which of them are beams
  /// and which steep, as bit masks from lo (a window spans at most 2 · kMaxBeamGapRows + 1 rows).
  struct WindowRows {
    int lo = 0, hi = -1;
    bool beam = false;  ///< one of rows lo..hi is a beam
    std::uint64_t beams = 0, steep = 0;
    bool operator==(const WindowRows& o) const {
      return lo == o.lo && hi == o.hi && beam == o.beam && beams == o.beams && steep == o.steep;
    }
  };
  std::vector<WindowRows> window_rows_;
  std::vector<std::uint64_t> row_version_;  ///< per row; changes when window_rows_[row] does
  std::uint64_t next_version_ = 1;
  std::vector<float> row_minima_;  ///< poolScan(): per beam row, the min over each cell's columns
};

// ----------------------------------------------------------------------------- implementation
namespace detail {
/** \brief atan2 in degrees, |error| < 0.001° (cells are 0.2°): std::atan2 on every point of
 * every scan would cost more than the rest of the map. Branch-free. */
inline float fastAtan2Deg(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float mx = ax > ay ? ax : ay, mn = ax > ay ? ay : ax;
  // Selects, no branches: the loop of computeCells() vectorizes. atan2(0, 0) = 0.
  const float a = mn / (mx > 0.0f ? mx : 1.0f), s = a * a;
  float r =
      a * (0.99997726f +
           s * (-0.33262347f +
                s * (0.19354346f + s * (-0.11643287f + s * (0.05265332f - s * 0.01172120f)))));
  if (ay > ax) r = 1.57079637f - r;
  if (x < 0) r = 3.14159274f - r;
  if (y < 0) r = -r;
  return r * 57.2957795f;
}
}  // namespace detail

template <typename PointT>
void FreeSpaceMap::addScan(const pcl::PointCloud<PointT>& scan, const Eigen::Isometry3d& pose) {
  Scan s;
  if (scans_.size() >= static_cast<std::size_t>(history_)) {
    // Reuse the oldest image's memory.
    s = std::move(scans_.back());
    scans_.pop_back();
  }
  s.world_to_sensor = pose.inverse().cast<float>();
  clearRange(s);
  s.pooled_version.assign(static_cast<std::size_t>(rows_) * poolBlocksPerRow(), 0);  // none yet
  s.sampled_rows.assign(static_cast<std::size_t>(rows_), 0);
  s.covered_cols.assign(static_cast<std::size_t>(cols_), 0);
  s.min_range = std::numeric_limits<float>::max();
  // In blocks: the coordinates copied out of the point structs, the cells computed by a loop
  // that vectorizes (computeCells()), then the nearest range kept per cell.
  constexpr std::size_t kBlock = 512;
  alignas(64) float xs[kBlock], ys[kBlock], zs[kBlock], ranges[kBlock];
  alignas(64) int cells[kBlock];
  const std::size_t n = scan.points.size();
  for (std::size_t first = 0; first < n; first += kBlock) {
    const std::size_t m = std::min(kBlock, n - first);
    for (std::size_t i = 0; i < m; ++i) {
      const PointT& p = scan.points[first + i];
      xs[i] = p.x;
      ys[i] = p.y;
      zs[i] = p.z;
    }
    computeCells(xs, ys, zs, m, cells, ranges);
    for (std::size_t i = 0; i < m; ++i) {
      if (cells[i] < 0) continue;
      float& cell = s.range[static_cast<std::size_t>(cells[i])];
      if (cell == 0.0f || ranges[i] < cell) cell = ranges[i];
      s.sampled_rows[static_cast<std::size_t>(cells[i] / cols_)] = 1;
      s.covered_cols[static_cast<std::size_t>(cells[i] % cols_)] = 1;
      s.min_range = std::min(s.min_range, ranges[i]);
    }
  }
  fillDropouts(s);
  coverColumns(s);
  scans_.push_front(std::move(s));
  indexBeamRows();
  if (pool_on_add_) poolScan(scans_.front());
}

}  // namespace pcl_movers
