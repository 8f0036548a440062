/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/sensor_model.h>
#include <pcl_movers/impl/sensor_model.hpp>

#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <utility>

namespace pcl_movers {

namespace {

constexpr float kDeg = float(M_PI / 180.0);

/** Elevations of `count` beams evenly spaced from `top` to `bottom` (degrees, inclusive). */
std::vector<float> evenlySpaced(float top_deg, float bottom_deg, int count) {
  std::vector<float> elevations(count);
  for (int i = 0; i < count; ++i) {
    const float t = count > 1 ? float(i) / float(count - 1) : 0.f;
    elevations[i] = (top_deg + t * (bottom_deg - top_deg)) * kDeg;
  }
  return elevations;
}

}  // namespace

SensorModel::SensorModel(std::vector<float> elevations, int columns, float azimuth_min,
                         float azimuth_max, std::string name)
    : name_(std::move(name)),
      elevations_(std::move(elevations)),
      columns_(columns),
      azimuth_min_(azimuth_min),
      azimuth_max_(azimuth_max) {
  if (elevations_.empty()) throw InputError("SensorModel '" + name_ + "': no beam elevations");
  for (const float e : elevations_)
    if (!std::isfinite(e) || std::abs(e) >= float(M_PI / 2))
      throw InputError("SensorModel '" + name_ + "': beam elevation out of (-90°, 90°)");
  if (columns_ <= 0) throw InputError("SensorModel '" + name_ + "': columns must be positive");
  if (!std::isfinite(azimuth_min_) || !std::isfinite(azimuth_max_) ||
      !(azimuth_max_ > azimuth_min_) || azimuth_max_ - azimuth_min_ > float(2 * M_PI) + 1e-4f)
    throw InputError("SensorModel '" + name_ + "': azimuth range must satisfy min < max, <= 2π");
  // Rows are top to bottom: the highest beam is row 0 like the top row of an image.
  std::sort(elevations_.begin(), elevations_.end(), std::greater<float>());
  vertical_offsets_.assign(elevations_.size(), 0.f);
}

void SensorModel::setVerticalOffsets(std::vector<float> offsets) {
  if (offsets.size() != elevations_.size())
    throw InputError("SensorModel '" + name_ + "': " + std::to_string(offsets.size()) +
                     " vertical offsets for " + std::to_string(elevations_.size()) + " beams");
  for (const float h : offsets)
    if (!std::isfinite(h) || std::abs(h) > 10.f)
      throw InputError("SensorModel '" + name_ + "': vertical offset not finite or above 10 m");
  vertical_offsets_ = std::move(offsets);
}

int SensorModel::rowOfPoint(float rho, float z) const {
  const int n = rows();
  if (n == 0 || !std::isfinite(rho) || !std::isfinite(z) || !(rho > 0.f)) return -1;
  if (n == 1) return rowOf(std::atan2(z - vertical_offsets_[0], rho));
  // In t = z/ρ each beam is the line t_k(w) = tan θ_k + h_k·w of w = 1/ρ, and the lines keep their
  // order for any ρ: walk from the offset-free guess to the beam with the nearest line.
  const float w = 1.f / rho, t = z * w;
  auto predicted = [&](int k) { return std::tan(elevations_[k]) + vertical_offsets_[k] * w; };
  float mean_offset = 0.f;
  for (const float h : vertical_offsets_) mean_offset += h;
  mean_offset /= float(n);
  int row = rowOf(std::atan2(z - mean_offset, rho));
  if (row < 0) row = t > predicted(0) ? 0 : n - 1;
  while (row > 0 && std::abs(t - predicted(row - 1)) < std::abs(t - predicted(row))) --row;
  while (row < n - 1 && std::abs(t - predicted(row + 1)) < std::abs(t - predicted(row))) ++row;
  // Beyond the outermost beams by more than half their spacing: not a point of this sensor.
  if (row == 0 && t - predicted(0) > 0.5f * (predicted(0) - predicted(1))) return -1;
  if (row == n - 1 && predicted(n - 1) - t > 0.5f * (predicted(n - 2) - predicted(n - 1)))
    return -1;
  return row;
}

SensorModel SensorModel::hdl64() {
  // KITTI's HDL-64E is two blocks of 32 lasers, upper ~+2° to -8.7° (~1/3° apart), lower ~-9° to
  // -25° (~1/2° apart), but the individual lasers are not evenly spaced and sit 0.21 m (upper) and
  // 0.12 m (lower) above the sensor origin, so near points appear up to a few degrees above their
  // beam. The table was fitted per laser (z = ρ·tan θ + h, residuals < 0.01°) on the scan-order
  // rings of four frames of two KITTI drives; the fits agreed to 0.002°.
  static const float kElevationDeg[64] = {
      1.937f,   1.574f,   1.305f,   0.872f,   0.579f,   0.181f,   -0.089f,  -0.452f,
      -0.803f,  -1.201f,  -1.494f,  -1.833f,  -2.208f,  -2.547f,  -2.874f,  -3.236f,
      -3.539f,  -3.936f,  -4.216f,  -4.588f,  -4.914f,  -5.251f,  -5.611f,  -5.958f,
      -6.329f,  -6.676f,  -6.999f,  -7.287f,  -7.679f,  -8.058f,  -8.311f,  -8.711f,
      -9.026f,  -9.573f,  -10.062f, -10.470f, -10.957f, -11.599f, -12.115f, -12.562f,
      -13.041f, -13.485f, -14.048f, -14.598f, -15.189f, -15.657f, -16.177f, -16.554f,
      -17.187f, -17.730f, -18.323f, -18.797f, -19.320f, -19.735f, -20.222f, -20.788f,
      -21.317f, -21.935f, -22.438f, -22.858f, -23.322f, -23.972f, -24.506f, -24.996f};
  static const float kOffset[64] = {
      0.2091f, 0.2087f, 0.2083f, 0.2077f, 0.2073f, 0.2068f, 0.2065f, 0.2060f, 0.2056f, 0.2051f,
      0.2048f, 0.2044f, 0.2039f, 0.2036f, 0.2032f, 0.2028f, 0.2025f, 0.2021f, 0.2018f, 0.2015f,
      0.2011f, 0.2008f, 0.2005f, 0.2001f, 0.1998f, 0.1995f, 0.1992f, 0.1990f, 0.1986f, 0.1984f,
      0.1982f, 0.1978f, 0.1258f, 0.1254f, 0.1250f, 0.1247f, 0.1244f, 0.1239f, 0.1235f, 0.1232f,
      0.1230f, 0.1226f, 0.1222f, 0.1218f, 0.1215f, 0.1212f, 0.1210f, 0.1207f, 0.1203f, 0.1200f,
      0.1196f, 0.1194f, 0.1190f, 0.1187f, 0.1185f, 0.1183f, 0.1178f, 0.1176f, 0.1174f, 0.1173f,
      0.1169f, 0.1167f, 0.1163f, 0.1157f};
  std::vector<float> elevations(64);
  for (int i = 0; i < 64; ++i) elevations[i] = kElevationDeg[i] * kDeg;
  SensorModel model(std::move(elevations), 2200, -float(M_PI), float(M_PI), "hdl64");
  // The table is already top to bottom, so the offsets line up with the sorted rows.
  model.setVerticalOffsets(std::vector<float>(kOffset, kOffset + 64));
  return model;
}

SensorModel SensorModel::hdl32() {
  // The vertical angles of the HDL-32E user's manual (Velodyne 63-9113, "Laser firing sequence"),
  // the table VeloView, PCL's HDLGrabber and the ROS velodyne driver decode its packets with (the
  // sensor does not send them). They are 4/3° apart rounded to 0.01°: an even spacing from
  // +10.67° to -30.67° differs from them by up to 0.007°, which moves a 100 m return by 1.2 cm.
  static const float kElevationDeg[32] = {
      10.67f,  9.33f,   8.f,     6.67f,   5.33f,   4.f,     2.67f,   1.33f,
      0.f,     -1.33f,  -2.67f,  -4.f,    -5.33f,  -6.67f,  -8.f,    -9.33f,
      -10.67f, -12.f,   -13.33f, -14.67f, -16.f,   -17.33f, -18.67f, -20.f,
      -21.33f, -22.67f, -24.f,   -25.33f, -26.67f, -28.f,   -29.33f, -30.67f};
  std::vector<float> elevations(32);
  for (int i = 0; i < 32; ++i) elevations[i] = kElevationDeg[i] * kDeg;
  return SensorModel(std::move(elevations), 2048, -float(M_PI), float(M_PI), "hdl32");
}

SensorModel SensorModel::vlp16() {
  return SensorModel(evenlySpaced(15.f, -15.f, 16), 1800, -float(M_PI), float(M_PI), "vlp16");
}

SensorModel SensorModel::os1_64() {
  return SensorModel(evenlySpaced(16.6f, -16.6f, 64), 2048, -float(M_PI), float(M_PI), "os1_64");
}

SensorModel SensorModel::ladar2d() {
  // A forward-looking ladar on a ground vehicle: 90° wide, 30° tall, tilted down so most of the
  // field of view sees the ground ahead and objects on it. 60 rows of 0.5° (cell centres).
  return SensorModel(evenlySpaced(10.f - 0.25f, -20.f + 0.25f, 60), 360, -float(M_PI / 4),
                     float(M_PI / 4), "ladar2d");
}

SensorModel SensorModel::fromName(const std::string& name) {
  if (name == "hdl64") return hdl64();
  if (name == "hdl32") return hdl32();
  if (name == "vlp16") return vlp16();
  if (name == "os1_64") return os1_64();
  if (name == "ladar2d") return ladar2d();
  throw InputError("unknown sensor preset '" + name +
                   "' (known: hdl64, hdl32, vlp16, os1_64, ladar2d)");
}

namespace {
/** Elevation [rad] at which beam k of `m` sees points `rho` metres away (offsets included). */
double elevationAt(const SensorModel& m, int k, double rho) {
  const double h = m.verticalOffsets().empty() ? 0.0 : m.verticalOffsets()[std::size_t(k)];
  return std::atan(std::tan(double(m.elevations()[std::size_t(k)])) + h / rho);
}

/** Whether every beam of `b` is a beam of `a`, each its own (see SensorModel::recognize()). */
bool beamsOf(const SensorModel& a, const SensorModel& b) {
  const int n = a.rows(), m = b.rows();
  if (n < 2 || m < 2 || 2 * m < n || m > n || a.isFullRevolution() != b.isFullRevolution())
    return false;
  int previous = -1;
  for (int k = 0; k < m; ++k) {
    int match = -1;
    for (int j = previous + 1; j < n && match < 0; ++j) {
      bool close = true;
      for (const double rho : {5.0, 50.0}) {
        const double e = elevationAt(a, j, rho);
        double spacing = std::numeric_limits<double>::max();
        if (j > 0) spacing = std::min(spacing, elevationAt(a, j - 1, rho) - e);
        if (j + 1 < n) spacing = std::min(spacing, e - elevationAt(a, j + 1, rho));
        close = close && std::abs(elevationAt(b, k, rho) - e) <= 0.25 * spacing;
      }
      if (close) match = j;
    }
    if (match < 0) return false;
    previous = match;
  }
  return true;
}
}  // namespace

SensorModel SensorModel::recognize(const SensorModel& estimated) {
  for (const char* name : {"hdl64", "hdl32", "vlp16", "os1_64"}) {
    SensorModel preset = fromName(name);
    if (!beamsOf(preset, estimated)) continue;
    if (std::abs(estimated.columns() - preset.columns()) > 0.05 * preset.columns())
      preset.setColumns(estimated.columns());
    return preset;
  }
  return estimated;
}

bool SensorModel::isFullRevolution() const {
  return std::abs((azimuth_max_ - azimuth_min_) - float(2 * M_PI)) < 1e-4f;
}

int SensorModel::rowOf(float elevation) const {
  const int n = rows();
  if (n == 0 || !std::isfinite(elevation)) return -1;
  if (n == 1) {
    // A single beam has no spacing: accept anything within a degree.
    return std::abs(elevation - elevations_[0]) <= kDeg ? 0 : -1;
  }
  // Outside the outermost beams: accept up to half the outermost spacing.
  if (elevation >= elevations_.front()) {
    const float half = 0.5f * (elevations_[0] - elevations_[1]);
    return elevation - elevations_.front() <= half ? 0 : -1;
  }
  if (elevation <= elevations_.back()) {
    const float half = 0.5f * (elevations_[n - 2] - elevations_[n - 1]);
    return elevations_.back() - elevation <= half ? n - 1 : -1;
  }
  // Descending order: first beam strictly below `elevation`.
  const auto it = std::upper_bound(elevations_.begin(), elevations_.end(), elevation,
                                   [](float value, float beam) { return value > beam; });
  const int below = int(it - elevations_.begin());
  const int above = below - 1;
  return (elevations_[above] - elevation) <= (elevation - elevations_[below]) ? above : below;
}

int SensorModel::columnOf(float azimuth) const {
  if (columns_ <= 0 || !std::isfinite(azimuth)) return -1;
  const float span = azimuth_max_ - azimuth_min_;
  float offset = azimuth_max_ - azimuth;  // grows with the column index
  if (isFullRevolution()) {
    offset = std::fmod(offset, span);
    if (offset < 0.f) offset += span;
  } else if (offset < 0.f || offset > span) {
    return -1;
  }
  const int column = int(offset / span * float(columns_));
  return std::min(std::max(column, 0), columns_ - 1);
}

}  // namespace pcl_movers

namespace pcl_movers {
namespace detail {

namespace {

/** Histogram bin of value x (bin width `width` from `lo`), or -1 outside [0, bins). Checked in
 * double before the cast: a huge or non-finite coordinate would make the float-to-int conversion
 * undefined (found by fuzz_pcd_pipeline). x in (-width, 0) truncates to bin 0, as int() did. */
int binOf(double x, double lo, double width, int bins) {
  const double b = (x - lo) / width;
  return (b > -1.0 && b < bins) ? int(b) : -1;
}

/** Index of the beam line t_k(w) = a_k + h_k·w nearest to (w, t), starting the walk at `row`;
 * the lines are ordered (a descending) and do not cross for w > 0. */
int nearestBeam(const std::vector<double>& a, const std::vector<double>& h, float w, float t,
                int row) {
  const int n = int(a.size());
  auto d = [&](int k) { return std::abs(double(t) - a[k] - h[k] * w); };
  while (row > 0 && d(row - 1) < d(row)) --row;
  while (row < n - 1 && d(row + 1) < d(row)) ++row;
  return row;
}

// Histogram of t (or t - h·w) shared by the steps of estimateBeams.
constexpr double kBin = 0.0003, kTMin = -1.2, kTMax = 1.2;
const int kBins = int((kTMax - kTMin) / kBin);
constexpr int kOffsets = 81;
double offsetOf(int j) {
  return 0.01 * (j - kOffsets / 2);
}
// The offset is chosen per band of ~2° of t (the two blocks of an HDL-64E sit at different
// heights). Measured on KITTI: 120 bins find all 64 beams to 0.006°; 90 and 180 bins miss the beam
// next to the block boundary, whose band then mixes both blocks.
constexpr int kBand = 120;
/** A subsample is plenty for the histograms: a beam still gets hundreds of points. */
std::size_t subsampleStride(std::size_t n) {
  return std::max<std::size_t>(1, n / 40000);
}

/** Index (offsetOf) of the vertical offset of each band of kBand bins of t: the one whose
 * histogram of the band's points is most concentrated (largest sum of squares). */
std::vector<int> bandOffsets(const std::vector<float>& w, const std::vector<float>& t,
                             std::size_t stride) {
  const std::size_t n = w.size();
  const int bins = kBins;
  const int bands = (bins + kBand - 1) / kBand;
  std::vector<int> band_offset(bands, kOffsets / 2);
  std::vector<bool> confident(bands, false);
  // Band membership is fixed by the uncorrected t, so each band is judged on the same points for
  // every offset.
  std::vector<std::vector<std::size_t>> members(bands);
  for (std::size_t i = 0; i < n; i += stride) {
    const int b = binOf(t[i], kTMin, kBin, bins);
    if (b >= 0 && b < bins) members[b / kBand].push_back(i);
  }
  std::vector<int> counts(bins, 0);
  for (int band = 0; band < bands; ++band) {
    if (members[band].size() < 20) continue;
    std::vector<double> score(kOffsets, 0.0);
    for (int j = 0; j < kOffsets; ++j) {
      const double h = offsetOf(j);
      double squares = 0.0;
      for (const std::size_t i : members[band]) {
        const int b = binOf(t[i] - h * w[i], kTMin, kBin, bins);
        if (b < 0 || b >= bins) continue;
        squares += 2.0 * counts[b] + 1.0;
        ++counts[b];
      }
      for (const std::size_t i : members[band]) {
        const int b = binOf(t[i] - h * w[i], kTMin, kBin, bins);
        if (b >= 0 && b < bins) counts[b] = 0;
      }
      score[std::size_t(j)] = squares;
    }
    const double best_squares = *std::max_element(score.begin(), score.end());
    const double worst_squares = *std::min_element(score.begin(), score.end());
    // Of the offsets as sharp as the best (within 1 %), the one nearest 0: a beam ring seen at one
    // range (flat ground) is equally sharp for a range of offsets, and the first of them (-0.01 to
    // -0.04 m) made the simulator's HDL-32E, whose beams have no offset, lose and split beams.
    for (int d = 0; d <= kOffsets / 2; ++d) {
      const int lo = kOffsets / 2 - d, hi = kOffsets / 2 + d;
      if (score[std::size_t(lo)] >= 0.99 * best_squares) {
        band_offset[band] = lo;
        break;
      }
      if (score[std::size_t(hi)] >= 0.99 * best_squares) {
        band_offset[band] = hi;
        break;
      }
    }
    // Beams hit at one range only (flat ground) are equally sharp for any offset: such a band
    // says nothing about the offset and borrows it from the nearest band that does.
    confident[band] = worst_squares < 0.8 * best_squares;
  }
  for (int band = 0; band < bands; ++band) {
    if (confident[band]) continue;
    int chosen = -1;
    for (int d = 1; d < bands && chosen < 0; ++d) {
      if (band + d < bands && confident[band + d])
        chosen = band + d;
      else if (band - d >= 0 && confident[band - d])
        chosen = band - d;
    }
    band_offset[band] = chosen >= 0 ? band_offset[chosen] : kOffsets / 2;
  }
  return band_offset;
}

/** The layout from (w, t) pairs: the Hough transform, the peaks and the refit. */
SensorModel estimateFromLines(const std::vector<float>& w, const std::vector<float>& t,
                              int num_beams, int columns) {
  const std::size_t n = w.size();
  // Hough transform of the lines t = a + h·w: for each candidate offset h a histogram of t - h·w
  // in bins of 0.0003 (~0.017° near the horizon). A beam makes a sharp peak at its own h and
  // smeared ones elsewhere (near points shift by h/ρ), so h is chosen per elevation band
  // (bandOffsets).
  const int bins = kBins;
  const std::size_t stride = subsampleStride(n);
  std::vector<double> raw(bins), accumulator(std::size_t(kOffsets) * bins, 0.0);
  for (int j = 0; j < kOffsets; ++j) {
    const double h = offsetOf(j);
    std::fill(raw.begin(), raw.end(), 0.0);
    for (std::size_t i = 0; i < n; i += stride) {
      const int b = binOf(t[i] - h * w[i], kTMin, kBin, bins);
      if (b >= 0 && b < bins) raw[b] += 1.0;
    }
    double* row = &accumulator[std::size_t(j) * bins];
    for (int b = 2; b + 2 < bins; ++b)
      row[b] = (raw[b - 2] + 2 * raw[b - 1] + 3 * raw[b] + 2 * raw[b + 1] + raw[b + 2]) / 9.0;
  }
  auto at = [&](int j, int b) { return accumulator[std::size_t(j) * bins + b]; };
  const std::vector<int> band_offset = bandOffsets(w, t, stride);
  double peak_max = 0.0;
  for (int b = 0; b < bins; ++b) peak_max = std::max(peak_max, at(band_offset[b / kBand], b));
  // A beam is a narrow peak; clutter is broad: a candidate must stand clearly above the histogram
  // a few bins away (real beams are >= 17 bins apart).
  constexpr int kShoulder = 6;
  std::vector<double> best_offset(bins, 0.0);
  std::vector<std::pair<double, int>> candidates;  // (height, bin)
  for (int b = kShoulder; b + kShoulder < bins; ++b) {
    const int j = band_offset[b / kBand];
    const double v = at(j, b);
    if (v < std::max(2.0, 0.01 * peak_max)) continue;
    if (!(v > at(j, b - 1) && v >= at(j, b + 1))) continue;
    if (v < 2.0 * std::max(at(j, b - kShoulder), at(j, b + kShoulder))) continue;
    candidates.emplace_back(v, b);
    best_offset[b] = offsetOf(j);
  }
  std::sort(candidates.begin(), candidates.end(), std::greater<>());
  // Beams closer than ~0.12° would not be separable by any real sensor: keep the higher peak.
  constexpr int kMinSeparationBins = 7;
  std::vector<std::pair<double, int>> peaks;
  for (const auto& c : candidates) {
    bool separate = true;
    for (const auto& p : peaks)
      if (std::abs(p.second - c.second) < kMinSeparationBins) separate = false;
    if (separate) peaks.push_back(c);
  }
  if (num_beams > 0) {
    if (int(peaks.size()) < num_beams)
      throw InputError("SensorModel::estimate: found only " + std::to_string(peaks.size()) +
                       " beams, expected " + std::to_string(num_beams));
    peaks.resize(num_beams);
  } else if (!peaks.empty()) {
    // Side lobes and clutter make much smaller peaks than beams. Not too small, though: an upward
    // beam in an open scene sees only the odd tree or car (a simulated 40-beam sensor's 15 upper
    // beams had 0.1-0.25 of the median peak, and dropping them cost the detection most of its
    // movers); the peaks must also be narrow and separate (above).
    std::vector<double> heights;
    for (const auto& p : peaks) heights.push_back(p.first);
    std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end(),
                     std::greater<>());
    const double median = heights[heights.size() / 2];
    peaks.erase(std::remove_if(peaks.begin(), peaks.end(),
                               [&](const auto& p) { return p.first < 0.1 * median; }),
                peaks.end());
  }
  if (peaks.empty()) throw InputError("SensorModel::estimate: no beam structure in the cloud");
  std::sort(peaks.begin(), peaks.end(),
            [](const auto& p, const auto& q) { return p.second > q.second; });
  const int beams = int(peaks.size());
  std::vector<double> a(beams), h(beams), prior(beams);
  for (int k = 0; k < beams; ++k) {
    a[k] = kTMin + (peaks[k].second + 0.5) * kBin;
    h[k] = prior[k] = best_offset[peaks[k].second];
  }
  double mean_offset = 0.0;
  for (const double v : h) mean_offset += v / beams;

  // Refit each beam's line t = a + h·w on the points nearest to it. The ridge term keeps h at the
  // common offset when a beam's points all lie at one range (e.g. flat ground), where a and h
  // cannot be told apart.
  for (int iteration = 0; iteration < 4 && beams > 1; ++iteration) {
    std::vector<double> s(beams), sw(beams), st(beams), sww(beams), swt(beams);
    for (std::size_t i = 0; i < n; ++i) {
      // Start near the answer: the beam whose line at this w is just below t.
      const double guess = t[i] - mean_offset * w[i];
      int row = int(std::upper_bound(a.begin(), a.end(), guess, std::greater<>()) - a.begin());
      row = nearestBeam(a, h, w[i], t[i], std::min(row, beams - 1));
      const double d = t[i] - a[row] - h[row] * w[i];
      const double spacing =
          row == 0 ? a[0] - a[1] : (row == beams - 1 ? a[row - 1] - a[row] : a[row - 1] - a[row]);
      if (std::abs(d) > 0.5 * spacing) continue;
      s[row] += 1;
      sw[row] += w[i];
      st[row] += t[i];
      sww[row] += double(w[i]) * w[i];
      swt[row] += double(w[i]) * t[i];
    }
    for (int k = 0; k < beams; ++k) {
      if (s[k] < 10) continue;
      const double lambda = s[k] * 1e-5;
      const double m00 = s[k], m01 = sw[k], m11 = sww[k] + lambda;
      const double r0 = st[k], r1 = swt[k] + lambda * prior[k];
      const double det = m00 * m11 - m01 * m01;
      if (!(det > 0)) continue;
      a[k] = (r0 * m11 - m01 * r1) / det;
      h[k] = (m00 * r1 - m01 * r0) / det;
    }
    // Keep the rows ordered if a poorly supported beam moved past a neighbour.
    std::vector<int> order(beams);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int i, int j) { return a[i] > a[j]; });
    std::vector<double> a2(beams), h2(beams), prior2(beams);
    for (int k = 0; k < beams; ++k) {
      a2[k] = a[order[k]];
      h2[k] = h[order[k]];
      prior2[k] = prior[order[k]];
    }
    a.swap(a2);
    h.swap(h2);
    prior.swap(prior2);
  }
  std::vector<float> elevations(beams), offsets(beams);
  for (int k = 0; k < beams; ++k) {
    elevations[k] = float(std::atan(a[k]));
    offsets[k] = float(h[k]);
  }
  SensorModel model(elevations, columns > 0 ? columns : 2048, -float(M_PI), float(M_PI),
                    "estimated");
  model.setVerticalOffsets(offsets);
  return model;
}

/** Sector of an azimuth [rad] among `sectors` equal ones over the full turn. */
int sectorOf(float azimuth, int sectors) {
  const double f = (double(azimuth) + M_PI) / (2 * M_PI) * sectors;
  return f >= 0.0 && f < sectors ? int(f) : (f < 0.0 ? 0 : sectors - 1);
}

/** A point moved by d [m] along its ray to w = 1/ρ was fired at ρ - d: its w and t = z/ρ were
 * those divided by 1 - d·w (kept positive for the rare point nearer than d). */
double unmoveScale(double d, double w) {
  return std::max(0.2, 1.0 - d * w);
}

/** The radial displacement of a motion-corrected scan as a function of azimuth φ: a point fired a
 * fraction u of the turn after the scan's seam was moved by the sensor's travel between its
 * firing and the scan's reference time, (V·(u - u_ref))·(cos φ, sin φ) along its ray, i.e.
 * (a·u + c)·cos φ + (b·u + d)·sin φ with the seam, a, b, c, d fitted to the sectors. */
struct MotionDisplacement {
  double seam = -M_PI, a = 0.0, b = 0.0, c = 0.0, d = 0.0;
  bool isZero() const { return a == 0.0 && b == 0.0 && c == 0.0 && d == 0.0; }
  double at(double phi) const {
    double u = (phi - seam) / (2 * M_PI);
    u -= std::floor(u);
    return (a * u + c) * std::cos(phi) + (b * u + d) * std::sin(phi);
  }
};

/** Least-squares fit of MotionDisplacement to the per-sector displacements, the seam at the
 * sector boundary that fits best. */
MotionDisplacement fitMotion(const std::vector<double>& sector) {
  const int sectors = int(sector.size());
  MotionDisplacement best;
  double best_error = -1.0;
  for (int k = 0; k < sectors; ++k) {
    MotionDisplacement m;
    m.seam = -M_PI + 2 * M_PI * k / sectors;
    // Normal equations of the 4 linear parameters.
    double A[4][5] = {};
    for (int s = 0; s < sectors; ++s) {
      const double phi = -M_PI + 2 * M_PI * (s + 0.5) / sectors;
      double u = (phi - m.seam) / (2 * M_PI);
      u -= std::floor(u);
      const double f[4] = {u * std::cos(phi), u * std::sin(phi), std::cos(phi), std::sin(phi)};
      for (int r = 0; r < 4; ++r) {
        for (int q = 0; q < 4; ++q) A[r][q] += f[r] * f[q];
        A[r][4] += f[r] * sector[s];
      }
    }
    for (int r = 0; r < 4; ++r) A[r][r] += 1e-9;  // all-zero sectors: the zero solution
    bool ok = true;
    for (int r = 0; r < 4 && ok; ++r) {
      int pivot = r;
      for (int q = r + 1; q < 4; ++q)
        if (std::abs(A[q][r]) > std::abs(A[pivot][r])) pivot = q;
      std::swap(A[r], A[pivot]);
      if (!(std::abs(A[r][r]) > 1e-12)) {
        ok = false;
        break;
      }
      for (int q = 0; q < 4; ++q) {
        if (q == r) continue;
        const double factor = A[q][r] / A[r][r];
        for (int col = r; col < 5; ++col) A[q][col] -= factor * A[r][col];
      }
    }
    if (!ok) continue;
    m.a = A[0][4] / A[0][0];
    m.b = A[1][4] / A[1][1];
    m.c = A[2][4] / A[2][2];
    m.d = A[3][4] / A[3][3];
    double error = 0.0;
    for (int s = 0; s < sectors; ++s) {
      const double e = m.at(-M_PI + 2 * M_PI * (s + 0.5) / sectors) - sector[s];
      error += e * e;
    }
    if (best_error < 0.0 || error < best_error) {
      best_error = error;
      best = m;
    }
  }
  return best;
}

/** The radial displacement of a motion-corrected scan (see estimateBeams): per azimuth sector
 * (kScanSectors of them) the displacement d along the rays (unmoveScale) that best lines the
 * sector's points up with the rest of the scan, then MotionDisplacement fitted to the sectors; a
 * few rounds, each against the scan corrected by the previous round's fit. */
constexpr int kScanSectors = 32;
MotionDisplacement scanMotion(const std::vector<float>& w, const std::vector<float>& t,
                              const std::vector<float>& azimuth, std::size_t stride) {
  const std::size_t n = w.size();
  const int bins = kBins;
  const std::vector<int> band_offset = bandOffsets(w, t, stride);
  std::vector<std::vector<std::size_t>> members(kScanSectors);
  std::vector<double> offset(n, 0.0);  // of the subsampled points only
  for (std::size_t i = 0; i < n; i += stride) {
    const int b = binOf(t[i], kTMin, kBin, bins);
    if (b < 0) continue;
    offset[i] = offsetOf(band_offset[b / kBand]);
    members[sectorOf(azimuth[i], kScanSectors)].push_back(i);
  }
  // 600 points per sector are plenty to line it up (every k-th point, spread over the beams).
  constexpr std::size_t kSectorPoints = 600;
  for (auto& m : members)
    if (m.size() > kSectorPoints) {
      const std::size_t every = (m.size() + kSectorPoints - 1) / kSectorPoints;
      std::size_t kept = 0;
      for (std::size_t j = 0; j < m.size(); j += every) m[kept++] = m[j];
      m.resize(kept);
    }
  MotionDisplacement motion;
  std::vector<double> raw(bins), reference(bins);
  auto bin = [&](std::size_t i, double d) {
    return binOf((double(t[i]) - offset[i] * w[i]) / unmoveScale(d, w[i]), kTMin, kBin, bins);
  };
  constexpr int kRounds = 4;
  for (int round = 0; round < kRounds; ++round) {
    // The reference: all points with the current displacements, smoothed like the Hough
    // histograms.
    std::fill(raw.begin(), raw.end(), 0.0);
    for (int s = 0; s < kScanSectors; ++s)
      for (const std::size_t i : members[s]) {
        const int b = bin(i, motion.at(azimuth[i]));
        if (b >= 0) raw[b] += 1.0;
      }
    for (int b = 2; b + 2 < bins; ++b)
      reference[b] = (raw[b - 2] + 2 * raw[b - 1] + 3 * raw[b] + 2 * raw[b + 1] + raw[b + 2]) / 9.0;
    // First round: up to ±1.2 m in 5 cm steps (a car at 24 m/s moves 1.2 m in half a turn of a
    // 10 Hz sensor); later rounds ±25 cm in 1.25 cm steps around the fit. Tried from the centre
    // outwards: a sector whose points fit any displacement equally (e.g. all at one range) keeps
    // the centre.
    const int steps = round == 0 ? 24 : 20;
    const double step = round == 0 ? 0.05 : 0.0125;
    std::vector<double> sector(kScanSectors, 0.0);
    for (int s = 0; s < kScanSectors; ++s) {
      const double centre =
          round == 0 ? 0.0 : motion.at(-M_PI + 2 * M_PI * (s + 0.5) / kScanSectors);
      sector[s] = centre;
      if (members[s].size() < 100) continue;  // keeps the centre
      double best_score = -1.0;
      for (int k = 0; k <= 2 * steps; ++k) {
        const double d = centre + step * ((k + 1) / 2) * (k % 2 ? 1 : -1);
        double score = 0.0;
        for (const std::size_t i : members[s]) {
          const int b = bin(i, d);
          if (b >= 0) score += reference[b];
        }
        if (score > best_score) {
          best_score = score;
          sector[s] = d;
        }
      }
    }
    // A lone sector off its neighbours is noise; a step between two (the scan's seam) is kept.
    std::vector<double> filtered(kScanSectors);
    for (int s = 0; s < kScanSectors; ++s) {
      double v[3] = {sector[(s + kScanSectors - 1) % kScanSectors], sector[s],
                     sector[(s + 1) % kScanSectors]};
      std::sort(v, v + 3);
      filtered[s] = v[1];
    }
    motion = fitMotion(filtered);
    // No sector moved: a scan without motion correction (or a sensor at rest), nothing to undo.
    if (round == 0 &&
        std::all_of(filtered.begin(), filtered.end(), [](double d) { return d == 0.0; }))
      return MotionDisplacement();
  }
  return motion;
}

/** Azimuth columns of a spinning sensor whose beams are `model`'s: each beam fires the same
 * number of times per turn, and the points of a beam in the directions where it returned
 * anything sample that rate (sky, the car's own body and occluders only shorten the turn it
 * covers). The rate is the 90th percentile over the beams that cover at least half the
 * turn of points / covered fraction, and the columns are 2 % more (irregular firing, as KITTI's
 * HDL-64E with its extra half step every ~7 samples: 2048 columns for its ~2150 firings put 4 % of
 * the points in a cell another point already holds), rounded up to a multiple of 8. 2048 when no
 * beam covers half the turn (a narrow field of view). */
int estimateColumns(const SensorModel& model, const std::vector<float>& w,
                    const std::vector<float>& t, const std::vector<float>& azimuth) {
  constexpr int kBinsPerTurn = 360;  // 1°: several firings of any real sensor
  const int rows = model.rows();
  std::vector<std::size_t> points(std::size_t(rows), 0);
  std::vector<char> covered(std::size_t(rows) * kBinsPerTurn, 0);
  for (std::size_t i = 0; i < w.size(); ++i) {
    const float rho = 1.f / w[i];
    const int row = model.rowOfPoint(rho, t[i] * rho);
    if (row < 0) continue;
    ++points[std::size_t(row)];
    int bin = int((azimuth[i] + float(M_PI)) / float(2 * M_PI) * kBinsPerTurn);
    bin = std::min(std::max(bin, 0), kBinsPerTurn - 1);
    covered[std::size_t(row) * kBinsPerTurn + std::size_t(bin)] = 1;
  }
  std::vector<double> rates;
  for (int r = 0; r < rows; ++r) {
    const auto begin = covered.begin() + std::ptrdiff_t(r) * kBinsPerTurn;
    const double fraction = double(std::count(begin, begin + kBinsPerTurn, 1)) / kBinsPerTurn;
    if (fraction >= 0.5) rates.push_back(double(points[std::size_t(r)]) / fraction);
  }
  if (rates.empty()) return 2048;
  // Every loss (dropouts, partly covered bins at the edges of what a beam sees) lowers a beam's
  // rate, none raises it: the 90th percentile, not the median (KITTI: median ~2090, 90 % ~2145).
  const std::size_t q = rates.size() * 9 / 10;
  std::nth_element(rates.begin(), rates.begin() + std::ptrdiff_t(q), rates.end());
  const double firings = rates[q];
  return std::max(8, int(std::ceil(1.02 * firings / 8.0)) * 8);
}

/** The layout from (w, t), then its columns from the azimuths when not given. */
SensorModel fitLayout(const std::vector<float>& w, const std::vector<float>& t,
                      const std::vector<float>& azimuth, int num_beams, int columns) {
  SensorModel model = estimateFromLines(w, t, num_beams, columns);
  if (columns == 0) model.setColumns(estimateColumns(model, w, t, azimuth));
  return model;
}

}  // namespace

SensorModel estimateBeams(const std::vector<float>& w, const std::vector<float>& t,
                          const std::vector<float>& azimuth, int num_beams, int columns) {
  const std::size_t n = w.size();
  if (n < 200)
    throw InputError("SensorModel::estimate: only " + std::to_string(n) +
                     " valid points beyond 2 m; need at least 200 to find the beams");
  // Scans corrected for the sensor's own motion during the turn (KITTI odometry's are) moved
  // each point along the vehicle's path by the time between its firing and the scan's reference
  // time: the two sides of the scan's seam (a full turn apart) moved in opposite directions, so
  // a beam's ground ring behind the vehicle splits into two peaks (~0.2° apart at 8.6 m/s). The
  // radial part of that displacement depends on the azimuth only: it is estimated per sector as
  // the one that best lines the sector up with the rest of the scan, and undone before the beams
  // are fitted. For scans without such a correction it comes out ~0.
  const MotionDisplacement motion = scanMotion(w, t, azimuth, subsampleStride(n));
  if (motion.isZero()) return fitLayout(w, t, azimuth, num_beams, columns);
  std::vector<float> w_fired(n), t_fired(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double scale = unmoveScale(motion.at(azimuth[i]), w[i]);
    w_fired[i] = float(w[i] / scale);
    t_fired[i] = float(t[i] / scale);
  }
  return fitLayout(w_fired, t_fired, azimuth, num_beams, columns);
}

}  // namespace detail

#ifndef PCL_NO_PRECOMPILE
template SensorModel SensorModel::estimate<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&,
                                                          int, int);
template SensorModel SensorModel::estimate<pcl::PointXYZI>(const pcl::PointCloud<pcl::PointXYZI>&,
                                                           int, int);
#endif

}  // namespace pcl_movers
