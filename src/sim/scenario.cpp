/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/sensor_model.h>
#include <pcl_movers/sim/scenario.h>
#include <pcl_movers/sim/yaml_lite.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace pcl_movers {
namespace sim {

// ------------------------------------------------------------------ Trajectory

Trajectory::Trajectory(const TrajectorySpec& spec, double horizon) {
  const std::size_t n = static_cast<std::size_t>(std::ceil(std::max(horizon, 0.0) / kStep)) + 2;
  samples_.reserve(n);
  turn_rates_.reserve(n);
  accels_.reserve(n);
  State s;
  s.position = spec.start;
  s.heading = spec.heading;
  s.speed = spec.speed;
  std::size_t seg = 0;
  double seg_start = 0, seg_start_speed = spec.speed;
  // After the last segment the motion goes on as in it (forwards or reversing).
  const bool final_reverse = !spec.segments.empty() && spec.segments.back().reverse;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = double(k) * kStep;
    while (seg < spec.segments.size() && t >= seg_start + spec.segments[seg].duration - 1e-9) {
      seg_start_speed = spec.segments[seg].speed >= 0 ? spec.segments[seg].speed : seg_start_speed;
      seg_start += spec.segments[seg].duration;
      ++seg;
    }
    double turn = 0, accel = 0;
    if (seg < spec.segments.size()) {
      const TrajectorySegment& g = spec.segments[seg];
      turn = g.turn_rate;
      const double target = g.speed >= 0 ? g.speed : seg_start_speed;
      accel = (target - seg_start_speed) / g.duration;
      // Re-anchor the speed to the segment's ramp to avoid drift from repeated additions.
      s.speed = seg_start_speed + accel * (t - seg_start);
      s.reverse = g.reverse;
    } else {
      s.speed = seg_start_speed;
      s.reverse = final_reverse;
    }
    samples_.push_back(s);
    turn_rates_.push_back(turn);
    accels_.push_back(accel);
    s = step(s, kStep, turn, accel);
  }
}

Trajectory::State Trajectory::step(const State& s, double dt, double turn, double accel) {
  // Midpoint step: heading is exact (constant rate), speed exact (linear ramp).
  const double mid_heading = s.heading + 0.5 * dt * turn + (s.reverse ? M_PI : 0.0);
  const double mid_speed = std::max(0.0, s.speed + 0.5 * dt * accel);
  State out = s;
  out.position += dt * mid_speed * Eigen::Vector2d(std::cos(mid_heading), std::sin(mid_heading));
  out.heading = s.heading + dt * turn;
  out.speed = std::max(0.0, s.speed + dt * accel);
  return out;
}

Trajectory::State Trajectory::at(double t) const {
  if (samples_.empty()) return State();
  t = std::max(t, 0.0);
  std::size_t k = static_cast<std::size_t>(std::floor(t / kStep));
  double turn = 0, accel = 0;
  if (k >= samples_.size())
    k = samples_.size() - 1;
  else {
    turn = turn_rates_[k];
    accel = accels_[k];
  }
  if (k == samples_.size() - 1) {
    turn = 0;
    accel = 0;
  }
  return step(samples_[k], t - double(k) * kStep, turn, accel);
}

// ------------------------------------------------------------------ parsing

const std::vector<std::string>& objectTypes() {
  static const std::vector<std::string> types = {"car",  "van",  "truck", "person", "cyclist",
                                                 "tree", "pole", "brush", "wall",   "building"};
  return types;
}

Eigen::Vector3d bodySize(const ObjectSpec& spec) {
  Eigen::Vector3d size = spec.size;
  Eigen::Vector3d fallback = Eigen::Vector3d::Zero();
  if (spec.type == "car") fallback = {4.4, 1.8, 1.5};
  if (spec.type == "van") fallback = {5.0, 2.0, 2.2};
  if (spec.type == "truck") fallback = {8.0, 2.5, 3.4};
  if (spec.type == "person") fallback = {0.6, 0.6, 1.75};
  if (spec.type == "cyclist") fallback = {1.8, 0.6, 1.75};
  for (int k = 0; k < 3; ++k)
    if (!(size[k] > 0)) size[k] = fallback[k];
  return size;
}

namespace {

constexpr double kDeg = M_PI / 180.0;

/** A mapping being read: remembers which keys were used so unknown keys can be reported with
 * their line, and builds "movers[2].size" style paths for messages. */
class Fields {
 public:
  Fields(const YamlNode& node, std::string path, const std::string& file)
      : node_(node), path_(std::move(path)), file_(file) {
    if (!node.isMap())
      throw InputError(file_, node.line, where() + "expected a mapping of 'key: value' lines");
  }

  const YamlNode* get(const std::string& key) {
    used_.insert(key);
    const YamlNode* n = node_.find(key);
    return (n && n->kind == YamlNode::Kind::Null) ? nullptr : n;
  }
  const YamlNode& require(const std::string& key) {
    const YamlNode* n = get(key);
    if (!n) throw InputError(file_, node_.line, where() + "missing required key '" + key + "'");
    return *n;
  }
  std::string keyPath(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }

  double number(const YamlNode& n, const std::string& key) const {
    if (!n.isScalar() || n.quoted)
      throw InputError(file_, n.line, "'" + keyPath(key) + "': expected a number");
    return parseNumber(n.scalar, n.line, key);
  }
  double parseNumber(const std::string& s, std::size_t line, const std::string& key) const {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v))
      throw InputError(file_, line,
                       "'" + keyPath(key) + "': expected a finite number, got '" + s + "'");
    return v;
  }
  double number(const std::string& key, double fallback) {
    const YamlNode* n = get(key);
    return n ? number(*n, key) : fallback;
  }
  double positive(const std::string& key, double fallback, bool allow_zero = false) {
    const YamlNode* n = get(key);
    if (!n) return fallback;
    const double v = number(*n, key);
    if (v < 0 || (!allow_zero && v == 0))
      throw InputError(file_, n->line,
                       "'" + keyPath(key) + "': must be " + (allow_zero ? "≥ 0" : "positive") +
                           ", got " + n->scalar);
    return v;
  }
  bool flag(const std::string& key, bool fallback) {
    const YamlNode* n = get(key);
    if (!n) return fallback;
    if (n->isScalar() && !n->quoted) {
      if (n->scalar == "true" || n->scalar == "1") return true;
      if (n->scalar == "false" || n->scalar == "0") return false;
    }
    throw InputError(file_, n->line, "'" + keyPath(key) + "': expected true or false");
  }
  std::string text(const std::string& key, const std::string& fallback) {
    const YamlNode* n = get(key);
    if (!n) return fallback;
    if (!n->isScalar())
      throw InputError(file_, n->line, "'" + keyPath(key) + "': expected a single value");
    return n->scalar;
  }
  std::vector<double> vector(const YamlNode& n, const std::string& key, std::size_t count) const {
    if (!n.isSequence() || n.sequence.size() != count)
      throw InputError(file_, n.line,
                       "'" + keyPath(key) + "': expected a list of " + std::to_string(count) +
                           " numbers like [1.0, 2.0" + (count > 2 ? ", ..." : "") + "]");
    std::vector<double> v;
    for (const YamlNode& e : n.sequence) v.push_back(number(e, key));
    return v;
  }
  Eigen::Vector2d vector2(const std::string& key, const Eigen::Vector2d& fallback) {
    const YamlNode* n = get(key);
    if (!n) return fallback;
    const auto v = vector(*n, key, 2);
    return {v[0], v[1]};
  }
  Eigen::Vector2d requireVector2(const std::string& key) {
    const auto v = vector(require(key), key, 2);
    return {v[0], v[1]};
  }

  /** Throws on keys never asked for. */
  void finish() const {
    for (const auto& kv : node_.map) {
      if (used_.count(kv.first)) continue;
      std::string known;
      for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
      throw InputError(file_, kv.second.line,
                       where() + "unknown key '" + kv.first + "' (known here: " + known + ")");
    }
  }
  std::string where() const { return path_.empty() ? std::string() : "'" + path_ + "': "; }
  const YamlNode& node() const { return node_; }
  const std::string& file() const { return file_; }

 private:
  const YamlNode& node_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> used_;
};

std::string itemPath(const std::string& list, std::size_t i) {
  return list + "[" + std::to_string(i) + "]";
}

TrajectorySpec readTrajectory(Fields& f, bool mover) {
  TrajectorySpec t;
  t.start = f.requireVector2(mover ? "start" : "position");
  t.heading = f.number(mover ? "heading" : "yaw", 0.0) * kDeg;
  if (!mover) return t;
  t.speed = f.positive("speed", 0.0, true);
  if (const YamlNode* segs = f.get("segments")) {
    if (!segs->isSequence())
      throw InputError(f.file(), segs->line,
                       "'" + f.keyPath("segments") + "': expected a list of segments");
    for (std::size_t i = 0; i < segs->sequence.size(); ++i) {
      Fields s(segs->sequence[i], itemPath(f.keyPath("segments"), i), f.file());
      TrajectorySegment g;
      const YamlNode& d = s.require("duration");
      g.duration = s.number(d, "duration");
      if (!(g.duration > 0))
        throw InputError(f.file(), d.line,
                         "'" + s.keyPath("duration") + "': must be positive, got " + d.scalar);
      g.speed = s.positive("speed", -1.0, true);
      g.turn_rate = s.number("turn_rate", 0.0) * kDeg;
      g.reverse = s.flag("reverse", false);
      s.finish();
      t.segments.push_back(g);
    }
  }
  return t;
}

void checkType(const std::string& type, const YamlNode& n, const std::string& path,
               const std::string& file, const std::vector<std::string>& allowed) {
  if (std::find(allowed.begin(), allowed.end(), type) == allowed.end()) {
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    throw InputError(file, n.line,
                     "'" + path + "': unknown type '" + type + "' (one of " + list + ")");
  }
}

ObjectSpec readObject(const YamlNode& node, const std::string& path, const std::string& file,
                      bool mover) {
  Fields f(node, path, file);
  ObjectSpec o;
  o.mover = mover;
  o.line = node.line;
  const YamlNode& type_node = f.require("type");
  o.type = f.text("type", "");
  static const std::vector<std::string> mover_types = {"car", "van", "truck", "person", "cyclist"};
  checkType(o.type, type_node, f.keyPath("type"), file, mover ? mover_types : objectTypes());
  o.trajectory = readTrajectory(f, mover);
  const bool boxy = o.type == "wall" || o.type == "building";
  if (const YamlNode* s = f.get("size")) {
    const auto v = f.vector(*s, "size", 3);
    for (double x : v)
      if (!(x > 0))
        throw InputError(file, s->line, "'" + f.keyPath("size") + "': sizes must be positive");
    o.size = {v[0], v[1], v[2]};
  } else if (boxy) {
    f.require("size");
  }
  if (o.type == "tree" || o.type == "pole" || o.type == "brush") {
    o.size.z() = f.positive("height", 0.0);
    o.radius = f.positive("radius", 0.0);
  }
  if (o.type == "tree") {
    o.trunk_radius = f.positive("trunk_radius", 0.0);
    o.trunk_height = f.positive("trunk_height", 0.0);
  }
  f.finish();
  return o;
}

}  // namespace

Scenario parseScenario(const std::string& text, const std::string& file) {
  const YamlNode root = parseYaml(text, file);
  Fields top(root, "", file);
  Scenario sc;
  sc.path = file;
  sc.name = top.text("name", "scenario");
  if (const YamlNode* s = top.get("seed")) {
    const double v = top.number(*s, "seed");
    if (v < 0 || v != std::floor(v) || v > 9.0e15)
      throw InputError(file, s->line, "'seed': expected a non-negative integer");
    sc.seed = static_cast<std::uint64_t>(v);
  }
  if (const YamlNode* n = top.get("frames")) {
    const double v = top.number(*n, "frames");
    if (v < 1 || v != std::floor(v) || v > 1e6)
      throw InputError(file, n->line, "'frames': expected a positive integer");
    sc.frames = static_cast<int>(v);
  }
  sc.rate_hz = top.positive("rate_hz", 10.0);

  if (const YamlNode* n = top.get("sensor")) {
    Fields f(*n, "sensor", file);
    sc.sensor.preset = f.text("preset", sc.sensor.preset);
    try {
      SensorModel::fromName(sc.sensor.preset);
    } catch (const InputError& e) {
      throw InputError(file, f.get("preset")->line, std::string("'sensor.preset': ") + e.what());
    }
    sc.sensor.height = f.positive("height", sc.sensor.height);
    sc.sensor.max_range = f.positive("max_range", sc.sensor.max_range);
    sc.sensor.min_range = f.positive("min_range", sc.sensor.min_range, true);
    sc.sensor.range_noise = f.positive("range_noise", sc.sensor.range_noise, true);
    sc.sensor.dropout = f.positive("dropout", sc.sensor.dropout, true);
    if (sc.sensor.dropout >= 1.0)
      throw InputError(file, f.get("dropout")->line, "'sensor.dropout': must be below 1");
    if (sc.sensor.min_range >= sc.sensor.max_range)
      throw InputError(file, n->line, "'sensor': min_range must be below max_range");
    sc.sensor.sweep = f.text("sweep", sc.sensor.sweep);
    if (sc.sensor.sweep != "instant" && sc.sensor.sweep != "rolling")
      throw InputError(
          file, f.get("sweep")->line,
          "'sensor.sweep': unknown sweep '" + sc.sensor.sweep + "' (instant, rolling)");
    f.finish();
  }

  if (const YamlNode* n = top.get("terrain")) {
    Fields f(*n, "terrain", file);
    TerrainSpec& t = sc.terrain;
    t.type = f.text("type", t.type);
    if (t.type != "plane" && t.type != "slope" && t.type != "rolling")
      throw InputError(file, f.get("type")->line,
                       "'terrain.type': unknown type '" + t.type + "' (plane, slope, rolling)");
    t.height = f.number("height", 0.0);
    if (t.type != "plane") t.slope = f.vector2("slope", t.slope);
    if (t.type == "slope" && !f.get("slope"))
      throw InputError(file, n->line, "'terrain': missing required key 'slope' for type slope");
    if (t.type == "rolling") {
      t.amplitude = f.positive("amplitude", 0.5, true);
      t.wavelength = f.positive("wavelength", t.wavelength);
    }
    if (t.slope.norm() > 0.5)
      throw InputError(file, f.get("slope")->line, "'terrain.slope': steeper than 0.5 (27°)");
    t.surface = f.text("surface", t.surface);
    if (t.surface != "terrain" && t.surface != "road" && t.surface != "sidewalk" &&
        t.surface != "parking" && t.surface != "other-ground")
      throw InputError(file, f.get("surface")->line,
                       "'terrain.surface': unknown '" + t.surface +
                           "' (terrain, road, sidewalk, parking, other-ground)");
    t.road_width = f.positive("road_width", 0.0, true);
    f.finish();
  }

  if (const YamlNode* n = top.get("roads")) {
    if (!n->isSequence()) throw InputError(file, n->line, "'roads': expected a list");
    for (std::size_t i = 0; i < n->sequence.size(); ++i) {
      Fields f(n->sequence[i], itemPath("roads", i), file);
      RoadSpec r;
      const YamlNode& pts = f.require("points");
      if (!pts.isSequence() || pts.sequence.size() < 2)
        throw InputError(file, pts.line,
                         "'" + f.keyPath("points") + "': expected a list of ≥ 2 [x, y] points");
      for (const YamlNode& p : pts.sequence) {
        const auto v = f.vector(p, "points", 2);
        r.points.emplace_back(v[0], v[1]);
      }
      r.width = f.positive("width", r.width);
      f.finish();
      sc.roads.push_back(r);
    }
  }

  {
    Fields f(top.require("ego"), "ego", file);
    sc.ego = readTrajectory(f, true);
    f.finish();
  }

  for (const char* list : {"movers", "statics"}) {
    const YamlNode* n = top.get(list);
    if (!n) continue;
    if (!n->isSequence())
      throw InputError(file, n->line, std::string("'") + list + "': expected a list of objects");
    for (std::size_t i = 0; i < n->sequence.size(); ++i)
      sc.objects.push_back(
          readObject(n->sequence[i], itemPath(list, i), file, std::string(list) == "movers"));
  }

  if (const YamlNode* n = top.get("clutter")) {
    if (!n->isSequence()) throw InputError(file, n->line, "'clutter': expected a list");
    for (std::size_t i = 0; i < n->sequence.size(); ++i) {
      Fields f(n->sequence[i], itemPath("clutter", i), file);
      ClutterSpec c;
      c.line = n->sequence[i].line;
      const YamlNode& type_node = f.require("type");
      c.type = f.text("type", "");
      checkType(c.type, type_node, f.keyPath("type"), file,
                {"tree", "pole", "brush", "car", "person"});
      const YamlNode& count = f.require("count");
      const double cv = f.number(count, "count");
      if (cv < 0 || cv != std::floor(cv) || cv > 100000)
        throw InputError(file, count.line, "'" + f.keyPath("count") + "': expected an integer ≥ 0");
      c.count = static_cast<int>(cv);
      const YamlNode& region = f.require("region");
      const auto r = f.vector(region, "region", 4);
      if (!(r[1] > r[0] && r[3] > r[2]))
        throw InputError(file, region.line,
                         "'" + f.keyPath("region") + "': expected [xmin, xmax, ymin, ymax]");
      c.region = {r[0], r[1], r[2], r[3]};
      c.min_spacing = f.positive("min_spacing", c.min_spacing, true);
      f.finish();
      sc.clutter.push_back(c);
    }
  }
  if (const YamlNode* n = top.get("blind_frames")) {
    if (!n->isSequence()) throw InputError(file, n->line, "'blind_frames': expected a list");
    for (const YamlNode& e : n->sequence) {
      const double v = top.number(e, "blind_frames");
      if (v < 0 || v != std::floor(v) || v >= sc.frames)
        throw InputError(file, e.line,
                         "'blind_frames': expected frame numbers in [0, " +
                             std::to_string(sc.frames - 1) + "], got " + e.scalar);
      sc.blind_frames.push_back(static_cast<int>(v));
    }
    std::sort(sc.blind_frames.begin(), sc.blind_frames.end());
    sc.blind_frames.erase(std::unique(sc.blind_frames.begin(), sc.blind_frames.end()),
                          sc.blind_frames.end());
  }
  top.finish();
  return sc;
}

Scenario loadScenario(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open scenario file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, "cannot read scenario file");
  return parseScenario(text.str(), path);
}

}  // namespace sim
}  // namespace pcl_movers
