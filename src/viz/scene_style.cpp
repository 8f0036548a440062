/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/viz/scene_style.h>
#include <pcl_movers/viz/impl/scene_style.hpp>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace pcl_movers {
namespace viz {
namespace {

Color hsv(double h_deg, double s, double v) {
  const double c = v * s;
  const double hp = std::fmod(h_deg, 360.0) / 60.0;
  const double x = c * (1.0 - std::abs(std::fmod(hp, 2.0) - 1.0));
  double r = 0, g = 0, b = 0;
  if (hp < 1)
    r = c, g = x;
  else if (hp < 2)
    r = x, g = c;
  else if (hp < 3)
    g = c, b = x;
  else if (hp < 4)
    g = x, b = c;
  else if (hp < 5)
    r = x, b = c;
  else
    r = c, b = x;
  const double m = v - c;
  auto to8 = [](double u) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(u, 0.0, 1.0) * 255));
  };
  return {to8(r + m), to8(g + m), to8(b + m)};
}

/** Strict non-negative integer parse (no sign, no trailing text). */
bool parseIndex(const std::string& s, std::size_t& value) {
  if (s.empty() || s.size() > 12) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  value = static_cast<std::size_t>(std::stoull(s));
  return true;
}

}  // namespace

Color trackColor(int track_id) {
  // Hues 90°..260° (green, cyan, blue) stepped by the golden angle so consecutive ids
  // differ clearly; red/orange/yellow are reserved for movers and the selection, magenta for
  // ground truth.
  const double golden = 0.6180339887498949;
  const double u = std::fmod(std::abs(static_cast<double>(track_id)) * golden, 1.0);
  const double hue = 90.0 + 170.0 * u;
  const double value = (track_id % 2 == 0) ? 0.95 : 0.78;
  return hsv(hue, 0.65, value);
}

OrientedBox OrientedBox::fromTrack(const io::TrackRow& row) {
  OrientedBox box;
  box.center = Eigen::Vector3d(row.x, row.y, row.z);
  box.length = row.length;
  box.width = row.width;
  box.height = row.height;
  box.yaw = row.yaw;
  return box;
}

OrientedBox OrientedBox::fromGroundTruth(const io::GroundTruthObject& object) {
  OrientedBox box;
  box.center = object.center;
  box.length = object.length;
  box.width = object.width;
  box.height = object.height;
  box.yaw = object.yaw;
  return box;
}

std::array<Eigen::Vector3d, 8> OrientedBox::corners() const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double hl = 0.5 * length, hw = 0.5 * width, hh = 0.5 * height;
  const double sx[4] = {-hl, hl, hl, -hl};
  const double sy[4] = {-hw, -hw, hw, hw};
  std::array<Eigen::Vector3d, 8> out;
  for (int k = 0; k < 4; ++k) {
    const double x = center.x() + c * sx[k] - s * sy[k];
    const double y = center.y() + s * sx[k] + c * sy[k];
    out[k] = Eigen::Vector3d(x, y, center.z() - hh);
    out[k + 4] = Eigen::Vector3d(x, y, center.z() + hh);
  }
  return out;
}

bool OrientedBox::contains(const Eigen::Vector3d& p, double margin) const {
  const Eigen::Vector3d d = p - center;
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double u = c * d.x() + s * d.y();   // along the box length
  const double v = -s * d.x() + c * d.y();  // along the width
  return std::abs(u) <= 0.5 * length + margin && std::abs(v) <= 0.5 * width + margin &&
         std::abs(d.z()) <= 0.5 * height + margin;
}

void LineSet::addSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Color& color) {
  segments.push_back({a.cast<float>(), b.cast<float>(), color});
}

void LineSet::addBox(const OrientedBox& box, const Color& color) {
  const auto c = box.corners();
  for (int k = 0; k < 4; ++k) {
    addSegment(c[k], c[(k + 1) % 4], color);          // bottom
    addSegment(c[k + 4], c[(k + 1) % 4 + 4], color);  // top
    addSegment(c[k], c[k + 4], color);                // vertical
  }
}

void LineSet::addArrow(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Color& color) {
  const Eigen::Vector3d d = to - from;
  const double len = d.norm();
  if (len < 0.01) return;
  addSegment(from, to, color);
  const Eigen::Vector3d dir = d / len;
  // Head strokes lie in the horizontal plane (movers move horizontally, and both camera presets
  // look at that plane from above); a vertical arrow gets its strokes in the x-z plane instead.
  Eigen::Vector3d side = dir.cross(Eigen::Vector3d::UnitZ());
  if (side.norm() < 1e-6) side = Eigen::Vector3d::UnitX();
  side.normalize();
  const double head = std::min(0.35 * len, 1.0);
  addSegment(to, to - head * dir + 0.5 * head * side, color);
  addSegment(to, to - head * dir - 0.5 * head * side, color);
}

void LineSet::addPolyline(const std::vector<Eigen::Vector3d>& points, const Color& color) {
  for (std::size_t i = 1; i < points.size(); ++i) addSegment(points[i - 1], points[i], color);
}

CameraPreset parseCameraPreset(const std::string& name, bool allow_free) {
  if (name == "chase") return CameraPreset::Chase;
  if (name == "bird") return CameraPreset::Bird;
  if (allow_free && name == "free") return CameraPreset::Free;
  throw InputError("--camera: unknown camera '" + name + "' (use chase or bird" +
                   (allow_free ? std::string(" or free") : std::string()) + ")");
}

const char* cameraPresetName(CameraPreset preset) {
  switch (preset) {
    case CameraPreset::Chase:
      return "chase";
    case CameraPreset::Bird:
      return "bird";
    case CameraPreset::Free:
      return "free";
  }
  return "chase";
}

CameraView cameraView(CameraPreset preset) {
  CameraView view;
  if (preset == CameraPreset::Bird) {
    // Straight down onto the area ahead of the ego vehicle (x up in the image, y to the left),
    // high enough to see ~15 m behind to ~45 m ahead.
    view.position = Eigen::Vector3d(14.0, 0.0, 70.0);
    view.focal = Eigen::Vector3d(14.0, 0.0, -1.7);
    view.up = Eigen::Vector3d::UnitX();
    view.fov_y_deg = 45.0;
  } else {
    // Behind and above the ego vehicle, looking along +x at a point on the road ahead.
    view.position = Eigen::Vector3d(-9.0, 0.0, 7.0);
    view.focal = Eigen::Vector3d(16.0, 0.0, -1.7);
    view.up = Eigen::Vector3d::UnitZ();
    view.fov_y_deg = 45.0;
  }
  return view;
}

std::optional<Eigen::Vector2d> projectToPixel(const CameraView& camera, const Eigen::Vector3d& p,
                                              int width, int height) {
  if (width <= 0 || height <= 0) return std::nullopt;
  // The same look-at frame VTK builds: forward to the focal point, up orthogonalised.
  const Eigen::Vector3d forward = (camera.focal - camera.position).normalized();
  Eigen::Vector3d right = forward.cross(camera.up);
  if (right.norm() < 1e-12) return std::nullopt;
  right.normalize();
  const Eigen::Vector3d up = right.cross(forward);
  const Eigen::Vector3d d = p - camera.position;
  const double depth = d.dot(forward);
  if (depth <= 1e-6) return std::nullopt;
  const double t = std::tan(0.5 * camera.fov_y_deg * M_PI / 180.0);
  const double aspect = static_cast<double>(width) / height;
  const double x_ndc = d.dot(right) / depth / (t * aspect);
  const double y_ndc = d.dot(up) / depth / t;
  if (std::abs(x_ndc) > 1.0 || std::abs(y_ndc) > 1.0) return std::nullopt;
  return Eigen::Vector2d(0.5 * (x_ndc + 1.0) * width, 0.5 * (1.0 - y_ndc) * height);
}

FrameRange parseFrameRange(const std::string& text, std::size_t frames) {
  const std::string where = "--frames " + text;
  if (frames == 0) throw InputError(where + ": the sequence has no frames");
  FrameRange range{0, frames - 1};
  const auto colon = text.find(':');
  bool ok = true;
  if (colon == std::string::npos) {
    ok = parseIndex(text, range.first);
    range.last = range.first;
  } else {
    const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
    if (a.empty() && b.empty()) ok = false;
    if (!a.empty()) ok = ok && parseIndex(a, range.first);
    if (!b.empty()) ok = ok && parseIndex(b, range.last);
  }
  if (!ok)
    throw InputError(where + ": expected A:B, A:, :B or A with frame numbers counted from 0");
  if (range.first > range.last)
    throw InputError(where + ": first frame " + std::to_string(range.first) +
                     " is after last frame " + std::to_string(range.last));
  if (range.last >= frames)
    throw InputError(where + ": frame " + std::to_string(range.last) +
                     " is out of range, the sequence has " + std::to_string(frames) +
                     " frames (0-" + std::to_string(frames - 1) + ")");
  return range;
}

std::pair<int, int> parseImageSize(const std::string& text) {
  const auto x = text.find_first_of("xX");
  std::size_t w = 0, h = 0;
  if (x == std::string::npos || !parseIndex(text.substr(0, x), w) ||
      !parseIndex(text.substr(x + 1), h))
    throw InputError("--size " + text + ": expected WIDTHxHEIGHT in pixels, e.g. 1280x720");
  if (w < 16 || h < 16 || w > 8192 || h > 8192)
    throw InputError("--size " + text + ": width and height must be between 16 and 8192 pixels");
  return {static_cast<int>(w), static_cast<int>(h)};
}

TrackIndex::TrackIndex(std::vector<io::TrackRow> rows) : rows_(std::move(rows)) {
  for (const auto& r : rows_) {
    by_frame_[r.frame].push_back(r);
    by_track_[r.track_id].push_back(r);
  }
  for (auto& [f, v] : by_frame_)
    std::sort(v.begin(), v.end(),
              [](const io::TrackRow& a, const io::TrackRow& b) { return a.track_id < b.track_id; });
  for (auto& [t, v] : by_track_)
    std::stable_sort(v.begin(), v.end(), [](const io::TrackRow& a, const io::TrackRow& b) {
      return a.frame < b.frame;
    });
}

const std::vector<io::TrackRow>& TrackIndex::frame(int frame) const {
  static const std::vector<io::TrackRow> kNone;
  auto it = by_frame_.find(frame);
  return it == by_frame_.end() ? kNone : it->second;
}

int TrackIndex::lastFrame() const {
  return by_frame_.empty() ? -1 : by_frame_.rbegin()->first;
}

std::vector<Eigen::Vector3d> TrackIndex::trail(int track_id, int frame, int length,
                                               const Eigen::Isometry3d& world_to_sensor) const {
  std::vector<Eigen::Vector3d> out;
  auto it = by_track_.find(track_id);
  if (it == by_track_.end() || length <= 0) return out;
  for (const auto& r : it->second)
    if (r.frame <= frame && r.frame > frame - length)
      out.push_back(world_to_sensor * Eigen::Vector3d(r.wx, r.wy, r.wz));
  return out;
}

std::vector<Eigen::Vector3d> TrackIndex::sensorTrail(int track_id, int frame, int length) const {
  std::vector<Eigen::Vector3d> out;
  auto it = by_track_.find(track_id);
  if (it == by_track_.end() || length <= 0) return out;
  for (const auto& r : it->second)
    if (r.frame <= frame && r.frame > frame - length) out.emplace_back(r.x, r.y, r.z);
  return out;
}

std::optional<Eigen::Isometry3d> fitSensorPose(const std::vector<io::TrackRow>& frame_rows) {
  const int n = static_cast<int>(frame_rows.size());
  if (n < 3) return std::nullopt;
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (int i = 0; i < n; ++i) {
    const auto& r = frame_rows[static_cast<std::size_t>(i)];
    src.col(i) = Eigen::Vector3d(r.x, r.y, r.z);
    dst.col(i) = Eigen::Vector3d(r.wx, r.wy, r.wz);
  }
  // Collinear (or coincident) centroids leave the rotation about that line undetermined.
  const Eigen::Matrix3Xd centred = src.colwise() - src.rowwise().mean();
  Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(centred);
  if (svd.singularValues()(1) < 0.5) return std::nullopt;
  const Eigen::Matrix4d m = Eigen::umeyama(src, dst, false);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.matrix() = m;
  // Rows of inconsistent frames (bad file) would give a meaningless pose; require a tight fit.
  const double rms = std::sqrt(((pose * src) - dst).colwise().squaredNorm().mean());
  if (!(rms < 0.5)) return std::nullopt;
  return pose;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> velocityArrow(const io::TrackRow& row,
                                                          const Eigen::Isometry3d& sensor_to_world,
                                                          double seconds) {
  const Eigen::Vector3d from(row.x, row.y, row.z);
  const Eigen::Vector3d v_world(row.vx, row.vy, 0.0);
  const Eigen::Vector3d v_sensor = sensor_to_world.linear().transpose() * v_world;
  return {from, from + seconds * v_sensor};
}

int nextSelectedTrack(const std::vector<io::TrackRow>& frame_rows, int current) {
  if (frame_rows.empty()) return -1;
  std::vector<std::pair<int, int>> order;  // (0 for movers / 1 for others, id)
  for (const auto& r : frame_rows) order.emplace_back(r.mover ? 0 : 1, r.track_id);
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < order.size(); ++i)
    if (order[i].second == current) return order[(i + 1) % order.size()].second;
  return order.front().second;
}

std::string overlayText(std::size_t frame, std::size_t frames, double time, int movers,
                        const io::TrackRow* selected, const std::string& extra, long long file) {
  char line[256], file_text[40] = "";
  if (file >= 0) std::snprintf(file_text, sizeof(file_text), " (file %06lld)", file);
  std::snprintf(line, sizeof(line), "frame %zu/%zu%s   t = %.2f s   movers: %d", frame,
                frames > 0 ? frames - 1 : 0, file_text, time, movers);
  std::string text = line;
  if (selected) {
    std::snprintf(line, sizeof(line), "\ntrack %d%s: %.1f m/s (%.0f km/h), B = %.2f, %d points",
                  selected->track_id, selected->mover ? " (mover)" : "", selected->speed,
                  selected->speed * 3.6, selected->similarity, selected->points);
    text += line;
  }
  if (!extra.empty()) text += "\n" + extra;
  return text;
}

#ifndef PCL_NO_PRECOMPILE
template std::vector<bool> estimateGroundMask<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&,
                                                             double, double);
template std::vector<bool> estimateGroundMask<pcl::PointXYZI>(
    const pcl::PointCloud<pcl::PointXYZI>&, double, double);
template PointLabels labelPointsFromTracks<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&,
                                                          const std::vector<bool>&,
                                                          const std::vector<io::TrackRow>&, double,
                                                          double);
template PointLabels labelPointsFromTracks<pcl::PointXYZI>(const pcl::PointCloud<pcl::PointXYZI>&,
                                                           const std::vector<bool>&,
                                                           const std::vector<io::TrackRow>&, double,
                                                           double);
template std::vector<OrientedBox> fitTrackBoxes<pcl::PointXYZ>(
    const pcl::PointCloud<pcl::PointXYZ>&, const PointLabels&, const std::vector<io::TrackRow>&);
template std::vector<OrientedBox> fitTrackBoxes<pcl::PointXYZI>(
    const pcl::PointCloud<pcl::PointXYZI>&, const PointLabels&, const std::vector<io::TrackRow>&);
template std::vector<Color> colorPoints<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&,
                                                       const PointLabels&, const std::vector<int>&,
                                                       const SceneStyle&);
template std::vector<Color> colorPoints<pcl::PointXYZI>(const pcl::PointCloud<pcl::PointXYZI>&,
                                                        const PointLabels&, const std::vector<int>&,
                                                        const SceneStyle&);
#endif

}  // namespace viz
}  // namespace pcl_movers
