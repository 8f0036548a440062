/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/sim/scene_families.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <sstream>

namespace pcl_movers {
namespace sim {

namespace {

constexpr double kDeg = M_PI / 180.0;

/** Rounds to `decimals` places the way the parser reads the printed number back. */
double rounded(double v, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, v);
  const double r = std::strtod(text, nullptr);
  return r == 0.0 ? 0.0 : r;  // no "-0"
}

/** splitmix64 draws: portable (std distributions are implementation-defined), so a family and
 * seed give the same scene on every machine. */
class Draw {
 public:
  Draw(const std::string& family, std::uint64_t seed) : state_(seed * 0x2545F4914F6CDD1Dull) {
    for (char c : family) state_ = mix((state_ ^ std::uint64_t(c)) * 0x100000001B3ull);
  }
  double uniform() {
    state_ += 0x9E3779B97F4A7C15ull;
    return double(mix(state_) >> 11) * (1.0 / 9007199254740992.0);
  }
  /** Uniform in [lo, hi], rounded to `decimals` places. */
  double uniform(double lo, double hi, int decimals = 2) {
    return rounded(lo + (hi - lo) * uniform(), decimals);
  }
  /** Uniform integer in [lo, hi]. */
  int integer(int lo, int hi) {
    return lo + std::min(hi - lo, int(uniform() * double(hi - lo + 1)));
  }
  bool chance(double p) { return uniform() < p; }
  double sign() { return chance(0.5) ? 1.0 : -1.0; }

 private:
  static std::uint64_t mix(std::uint64_t x) {
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
  }
  std::uint64_t state_;
};

/** An angle in degrees, rounded, as the parser converts it. */
double degrees(double deg) {
  return rounded(deg, 2) * kDeg;
}

TrajectorySegment segment(double duration, double speed = -1, double turn_deg = 0,
                          bool reverse = false) {
  TrajectorySegment g;
  g.duration = rounded(duration, 2);
  g.speed = speed < 0 ? -1 : rounded(speed, 2);
  g.turn_rate = degrees(turn_deg);
  g.reverse = reverse;
  return g;
}

Eigen::Vector2d direction(double heading) {
  return {std::cos(heading), std::sin(heading)};
}

/** Builds one scene: the ego drive first, then objects placed relative to it. */
class SceneBuilder {
 public:
  SceneBuilder(const std::string& family, std::uint64_t seed, const SceneOptions& options)
      : draw_(family, seed) {
    scenario_.name = family + "-" + std::to_string(seed);
    scenario_.seed = seed;
    scenario_.frames = options.frames;
    scenario_.rate_hz = options.rate_hz;
    duration_ = options.frames / options.rate_hz;
  }

  Draw& draw() { return draw_; }
  Scenario& scenario() { return scenario_; }
  double duration() const { return duration_; }

  void setEgo(const TrajectorySpec& ego) {
    scenario_.ego = normalized(ego);
    ego_path_ = Trajectory(scenario_.ego, duration_ + 1.0);
  }
  Trajectory::State egoAt(double t) const { return ego_path_.at(t); }
  /** A point `ahead` metres along and `left` metres to the left of the ego at time t. */
  Eigen::Vector2d besideEgo(double t, double ahead, double left) const {
    const Trajectory::State s = egoAt(t);
    return s.position + ahead * direction(s.heading) + left * direction(s.heading + M_PI / 2);
  }
  /** The box [xmin, xmax, ymin, ymax] around the ego drive, grown by `pad`. */
  Eigen::Vector4d egoRegion(double pad) const {
    Eigen::Vector4d r(1e9, -1e9, 1e9, -1e9);
    for (double t = 0; t <= duration_; t += 0.5) {
      const Eigen::Vector2d p = egoAt(t).position;
      r = Eigen::Vector4d(std::min(r[0], p.x()), std::max(r[1], p.x()), std::min(r[2], p.y()),
                          std::max(r[3], p.y()));
    }
    return {rounded(r[0] - pad, 1), rounded(r[1] + pad, 1), rounded(r[2] - pad, 1),
            rounded(r[3] + pad, 1)};
  }

  /** The trajectory with every number as the scenario file gives it back. */
  static TrajectorySpec normalized(TrajectorySpec spec) {
    spec.start = {rounded(spec.start.x(), 2), rounded(spec.start.y(), 2)};
    spec.heading = degrees(spec.heading / kDeg);
    spec.speed = rounded(spec.speed, 2);
    return spec;
  }

  /** Moves a mover's start so that it is at `point` at time `t` (any segments). */
  static void placeAt(TrajectorySpec& spec, double t, const Eigen::Vector2d& point) {
    TrajectorySpec at_origin = spec;
    at_origin.start = Eigen::Vector2d::Zero();
    const Eigen::Vector2d offset = Trajectory(at_origin, t + 0.1).at(t).position;
    spec.start = {rounded(point.x() - offset.x(), 2), rounded(point.y() - offset.y(), 2)};
  }

  /** Adds a mover that is at `point` at time t, or up to 3 s earlier (not before the scene's
   * start) or later if it would otherwise run into a mover added before it (footprints
   * overlapping at a frame time): solid objects do not pass through each other, and the traffic
   * drawn lane by lane did (a faster car through a slower one in its lane, a car through a walker
   * crossing its path), which no sensor can show as two objects. A mover that runs into another
   * at every such time is left out. Returns whether it was added. */
  bool addMover(const std::string& type, TrajectorySpec spec, double t,
                const Eigen::Vector2d& point) {
    ObjectSpec o;
    o.type = type;
    o.mover = true;
    spec = normalized(spec);
    for (const double delay : {0.0, 1.0, -1.0, 2.0, -2.0, 3.0, -3.0}) {
      o.trajectory = spec;
      placeAt(o.trajectory, t + delay, point);
      const Trajectory path(o.trajectory, duration_ + 1.0);
      if (runsIntoAnother(o, path)) continue;
      scenario_.objects.push_back(o);
      mover_paths_.push_back(path);
      mover_footprints_.push_back(footprint(o));
      return true;
    }
    return false;
  }

  ObjectSpec& addStatic(const std::string& type, const Eigen::Vector2d& position, double yaw_deg) {
    ObjectSpec o;
    o.type = type;
    o.trajectory.start = {rounded(position.x(), 2), rounded(position.y(), 2)};
    o.trajectory.heading = degrees(yaw_deg);
    scenario_.objects.push_back(o);
    return scenario_.objects.back();
  }

  void addBox(const std::string& type, const Eigen::Vector2d& position, double yaw_deg,
              const Eigen::Vector3d& size) {
    ObjectSpec& o = addStatic(type, position, yaw_deg);
    o.size = {rounded(size.x(), 2), rounded(size.y(), 2), rounded(size.z(), 2)};
  }

  void addClutter(const std::string& type, int count, const Eigen::Vector4d& region,
                  double min_spacing) {
    ClutterSpec c;
    c.type = type;
    c.count = count;
    c.region = region;
    c.min_spacing = min_spacing;
    scenario_.clutter.push_back(c);
  }

  /** Walking pace: 40 % slow walkers (0.55-1.2 m/s: the elderly, prams, window-shoppers). */
  double walkingSpeed() {
    return draw_.chance(0.4) ? draw_.uniform(0.55, 1.2) : draw_.uniform(1.2, 1.8);
  }

  /** A person walking along `heading` so as to be at `point` at time t, and with probability
   * `group_chance` one or two companions beside them on the `free_side` (+1 left, -1 right of the
   * walking direction), 0.7 m apart. */
  void addWalkers(double heading_deg, double speed, double t, const Eigen::Vector2d& point,
                  double group_chance, double free_side) {
    TrajectorySpec spec;
    spec.heading = degrees(heading_deg);
    spec.speed = rounded(speed, 2);
    const int people = draw_.chance(group_chance) ? draw_.integer(2, 3) : 1;
    const Eigen::Vector2d side = free_side * direction(spec.heading + M_PI / 2);
    for (int i = 0; i < people; ++i) {
      const double along = i == 0 ? 0.0 : draw_.uniform(-0.4, 0.4);
      addMover("person", spec, t, point + 0.7 * i * side + along * direction(spec.heading));
    }
  }

  /** 1-3 consecutive blind frames in half of the scenes, in the middle third. */
  void addBlindFrames() {
    if (!draw_.chance(0.5)) return;
    const int n = draw_.integer(1, 3);
    const int first = draw_.integer(scenario_.frames / 3, 2 * scenario_.frames / 3);
    for (int f = first; f < first + n && f < scenario_.frames; ++f)
      scenario_.blind_frames.push_back(f);
  }

  /** Length and width [m] of a mover's box as the simulator builds it. */
  static Eigen::Vector2d footprint(const ObjectSpec& o) { return bodySize(o).head<2>(); }

  /** True when the mover's footprint overlaps an added mover's at a frame time. */
  bool runsIntoAnother(const ObjectSpec& o, const Trajectory& path) const {
    const Eigen::Vector2d size = footprint(o);
    const double dt = 1.0 / scenario_.rate_hz;
    for (int f = 0; f < scenario_.frames; ++f) {
      const Trajectory::State s = path.at(f * dt);
      for (std::size_t i = 0; i < mover_paths_.size(); ++i)
        if (boxesOverlap(s, size, mover_paths_[i].at(f * dt), mover_footprints_[i])) return true;
    }
    return false;
  }

  /** Separating-axis test of two footprints (centre, heading; length along it, width across). */
  static bool boxesOverlap(const Trajectory::State& a, const Eigen::Vector2d& size_a,
                           const Trajectory::State& b, const Eigen::Vector2d& size_b) {
    const Eigen::Vector2d d = b.position - a.position;
    if (d.norm() > 0.5 * (size_a.norm() + size_b.norm())) return false;
    const Eigen::Vector2d axes[4] = {direction(a.heading), direction(a.heading + M_PI / 2),
                                     direction(b.heading), direction(b.heading + M_PI / 2)};
    const auto halfExtent = [](const Eigen::Vector2d& axis, double heading,
                               const Eigen::Vector2d& size) {
      return 0.5 * (size.x() * std::abs(axis.dot(direction(heading))) +
                    size.y() * std::abs(axis.dot(direction(heading + M_PI / 2))));
    };
    for (const Eigen::Vector2d& axis : axes)
      if (std::abs(axis.dot(d)) >
          halfExtent(axis, a.heading, size_a) + halfExtent(axis, b.heading, size_b))
        return false;
    return true;
  }

  void drawSensor() {
    SensorSpec& s = scenario_.sensor;
    s.preset = sensorOfSeed(scenario_.seed);
    s.height = draw_.uniform(1.5, 2.5);
    s.max_range = 80.0;
    s.min_range = 2.0;
    s.range_noise = draw_.uniform(0.01, 0.03, 3);
    s.dropout = draw_.uniform(0.0, 0.04, 3);
  }

 private:
  Draw draw_;
  Scenario scenario_;
  Trajectory ego_path_;
  std::vector<Trajectory> mover_paths_;  ///< of the movers added so far, in their order
  std::vector<Eigen::Vector2d> mover_footprints_;
  double duration_ = 15.0;
};

std::string vehicleType(Draw& d) {
  const double u = d.uniform();
  return u < 0.6 ? "car" : (u < 0.8 ? "van" : "truck");
}

// ------------------------------------------------------------------ highway
// Three lanes each way, a median barrier, shoulders; the ego at 15-30 m/s; traffic overtaking,
// being overtaken, oncoming behind the barrier and merging from the on-ramp; a stopped vehicle on
// the shoulder with a person walking beside it.
void highway(SceneBuilder& b) {
  Draw& d = b.draw();
  const double T = b.duration();
  const double lanes[3] = {-1.75, -5.25, -8.75};
  const int ego_lane = d.integer(0, 2);
  const double v = d.uniform(15, 30, 1);
  TrajectorySpec ego;
  ego.start = {0, lanes[ego_lane]};
  ego.speed = v;
  if (d.chance(0.4)) ego.segments.push_back(segment(d.uniform(3, 6), v + d.uniform(-4, 4, 1)));
  b.setEgo(ego);
  const double x_end = rounded(b.egoAt(T).position.x() + 400, 0);

  Scenario& sc = b.scenario();
  sc.terrain.type = "slope";
  sc.terrain.slope = {d.uniform(-0.02, 0.02, 3), 0.0};
  sc.terrain.surface = "terrain";
  RoadSpec ours, theirs;
  ours.points = {{-300, -5.25}, {x_end, -5.25}};
  ours.width = 14;  // three lanes and the shoulder
  theirs.points = {{-300, 6.25}, {x_end, 6.25}};
  theirs.width = 11;
  sc.roads = {ours, theirs};
  b.addBox("wall", {(x_end - 300) / 2, 0.5}, 0, {x_end + 300, 0.4, 0.9});  // median barrier

  auto other_lane = [&]() {
    int l = d.integer(0, 1);
    return lanes[l >= ego_lane ? l + 1 : l];
  };
  TrajectorySpec fwd;
  for (int i = d.integer(1, 2); i > 0; --i) {  // overtaking us
    fwd.speed = std::min(38.0, v + d.uniform(3, 8));
    const double t = d.uniform(2, T - 3);
    b.addMover(vehicleType(d), fwd, t, {b.egoAt(t).position.x() + d.uniform(-5, 15), other_lane()});
  }
  for (int i = d.integer(1, 2); i > 0; --i) {  // overtaken by us
    fwd.speed = std::max(10.0, v - d.uniform(4, 10));
    const double t = d.uniform(2, T - 3);
    b.addMover(vehicleType(d), fwd, t,
               {b.egoAt(t).position.x() + d.uniform(-10, 10), other_lane()});
  }
  TrajectorySpec back;
  back.heading = M_PI;
  for (int i = d.integer(1, 3); i > 0; --i) {  // oncoming, behind the barrier
    back.speed = d.uniform(20, 33);
    const double t = d.uniform(1, T - 2);
    const double lane = 2.75 + 3.5 * d.integer(0, 2);
    b.addMover(vehicleType(d), back, t, {b.egoAt(t).position.x() + d.uniform(5, 40), lane});
  }
  if (d.chance(0.6)) {  // merging from the on-ramp into the outer lane
    TrajectorySpec merge;
    merge.speed = d.uniform(std::max(12.0, v - 5), v + 5);
    const double D = 2.5;                                    // each half of the lane change [s]
    const double turn = 3.5 / (merge.speed * D * D) / kDeg;  // 3.5 m to the left in 2D seconds
    const double lead = d.uniform(1, T - 6);
    merge.segments = {segment(lead), segment(D, -1, turn), segment(D, -1, -turn)};
    const double t = lead + D;  // half-way through the lane change, at y = -10.5
    b.addMover(vehicleType(d), merge, t, {b.egoAt(t).position.x() + d.uniform(15, 40), -10.5});
  }
  // A vehicle stopped on the shoulder; its driver walks beside it.
  const double t_pass = d.uniform(4, T - 3);
  const std::string stopped = d.chance(0.5) ? "car" : (d.chance(0.5) ? "van" : "truck");
  const double width = stopped == "car" ? 1.8 : (stopped == "van" ? 2.0 : 2.5);
  const double x_stop = b.egoAt(t_pass).position.x() + d.uniform(0, 10);
  b.addStatic(stopped, {x_stop, -12.75}, 0);
  b.addWalkers(d.chance(0.5) ? 0 : 180, d.uniform(0.55, 1.3), t_pass,
               {x_stop + d.uniform(-2, 2), -12.75 - width / 2 - 0.3 - d.uniform(0.3, 0.5)}, 0.0,
               -1);
  // Roadside: trees and poles beyond the shoulders.
  for (double x = rounded(d.uniform(0, 40), 0); x < x_end - 300; x += d.uniform(40, 70))
    b.addStatic("pole", {x, -15.8}, 0);
  const int trees = int((x_end - 200) / 12);
  b.addClutter("tree", trees, {-50, x_end - 250, -45, -16}, 2.0);
  b.addClutter("tree", trees, {-50, x_end - 250, 14, 45}, 2.0);
  b.addClutter("brush", trees / 2, {-50, x_end - 250, -30, -16}, 1.0);
}

// ------------------------------------------------------------------ urban street and junction
// A street between building blocks, a cross street, parked cars along the kerbs, poles and trees
// on the sidewalks. The ego stops at the junction, waits and goes straight or turns. Crossing
// traffic passes while it waits, pedestrians cross in front of it, people walk along walls,
// parked cars and poles.
void urban(SceneBuilder& b) {
  Draw& d = b.draw();
  const double T = b.duration();
  const double J = d.uniform(35, 55, 1);  // cross street at x = J
  const double v = d.uniform(5, 9);
  const double brake = d.uniform(2, 3), wait = d.uniform(1, 4);
  const double stop_x = J - 9;
  const double cruise = std::max(0.5, (stop_x - v * brake / 2) / v);
  TrajectorySpec ego;
  ego.start = {rounded(stop_x - v * (cruise + brake / 2), 2), -2};
  ego.speed = v;
  ego.segments = {segment(cruise), segment(brake, 0), segment(wait, 0), segment(2, 4)};
  const int turn = d.integer(-1, 1);  // right, straight, left
  if (turn != 0) ego.segments.push_back(segment(3, -1, 30 * turn));
  ego.segments.push_back(segment(3, d.uniform(5, 8)));
  b.setEgo(ego);
  const double t_stop = cruise + brake;

  Scenario& sc = b.scenario();
  sc.terrain.surface = "sidewalk";
  RoadSpec main_street, cross_street;
  main_street.points = {{-200, 0}, {J + 300, 0}};
  main_street.width = 14;
  cross_street.points = {{J, -200}, {J, 200}};
  cross_street.width = 14;
  sc.roads = {main_street, cross_street};

  // Building blocks: faces 11 m from the street centre lines.
  auto block_row = [&](double from, double to, bool along_x, double side) {
    for (double s = from; s < to;) {
      const double len = std::min(d.uniform(12, 30), to - s), depth = d.uniform(8, 14);
      if (len < 4) break;
      const double mid = s + len / 2, off = side * (11 + depth / 2);
      const Eigen::Vector2d c = along_x ? Eigen::Vector2d(mid, off) : Eigen::Vector2d(J + off, mid);
      b.addBox("building", c, along_x ? 0 : 90, {len, depth, d.uniform(6, 20)});
      s += len + (d.chance(0.3) ? d.uniform(1, 3) : 0);
    }
  };
  for (double side : {-1.0, 1.0}) {
    block_row(-80, J - 11, true, side);
    block_row(J + 11, J + 250, true, side);
    block_row(25, 150, false, side);
    block_row(-150, -25, false, side);
  }
  // Parked cars along both kerbs of both streets, poles and trees on the sidewalks.
  auto kerb_row = [&](double from, double to, bool along_x, double side) {
    for (double s = from; s < to; s += d.uniform(5.5, 8)) {
      if (!d.chance(0.6)) continue;
      const Eigen::Vector2d c =
          along_x ? Eigen::Vector2d(s, side * 5.6) : Eigen::Vector2d(J + side * 5.6, s);
      b.addStatic(d.chance(0.8) ? "car" : "van", c, (along_x ? 0 : 90) + (d.chance(0.5) ? 180 : 0));
    }
  };
  for (double side : {-1.0, 1.0}) {
    kerb_row(-40, J - 14, true, side);
    kerb_row(J + 14, J + 140, true, side);
    kerb_row(14, 80, false, side);
    kerb_row(-80, -14, false, side);
  }
  std::vector<Eigen::Vector2d> poles;
  for (double side : {-1.0, 1.0})
    for (double x = d.uniform(-40, -25); x < J + 140; x += d.uniform(12, 22)) {
      if (std::abs(x - J) < 12) continue;
      if (d.chance(0.6)) {
        poles.emplace_back(rounded(x, 2), side * 9.6);
        b.addStatic("pole", poles.back(), 0);
      } else {
        ObjectSpec& tree = b.addStatic("tree", {x, side * 9.4}, 0);
        tree.size.z() = d.uniform(5, 9);
        tree.radius = d.uniform(1.2, 2.0);
      }
    }

  // Traffic.
  TrajectorySpec spec;
  if (d.chance(0.7)) {  // the car ahead of us goes on through the junction
    spec.speed = d.uniform(6, 10);
    b.addMover(vehicleType(d), spec, 0, {d.uniform(12, 20), -2});
  }
  spec.heading = M_PI;
  for (int i = d.integer(1, 2); i > 0; --i) {  // oncoming
    spec.speed = d.uniform(7, 13);
    const double t = d.uniform(1, T - 2);
    b.addMover(vehicleType(d), spec, t, {b.egoAt(t).position.x() + d.uniform(5, 40), 2});
  }
  for (int i = d.integer(1, 2); i > 0; --i) {  // crossing while we wait
    const double dir = d.sign();
    spec.heading = dir * M_PI / 2;
    spec.speed = d.uniform(6, 12);
    b.addMover(vehicleType(d), spec, t_stop + d.uniform(0, wait), {J + 2 * dir, 0});
  }
  if (d.chance(0.6)) {  // a cyclist along the kerb
    spec.heading = 0;
    spec.speed = d.uniform(3, 6);
    const double t = d.uniform(2, T - 2);
    b.addMover("cyclist", spec, t, {b.egoAt(t).position.x() + d.uniform(-5, 10), -4.2});
  }

  // People.
  {  // on the crossing in front of us while we wait
    const double dir = d.sign();
    b.addWalkers(90 * dir, b.walkingSpeed(), t_stop + d.uniform(0.2, 0.8) * wait,
                 {J - 6.5, d.uniform(-4, 4)}, 0.4, -1);
  }
  for (int i = d.integer(1, 3); i > 0; --i) {  // along a wall, beside parked cars, past poles
    const double side = d.sign(), heading = d.chance(0.5) ? 0 : 180;
    const double gap = d.uniform(0.3, 0.5);
    const int kind = d.integer(0, 2);
    const double y = kind == 0   ? side * (11 - 0.3 - gap)          // wall
                     : kind == 1 ? side * (5.6 + 0.9 + 0.3 + gap)   // parked cars
                                 : side * (9.6 - 0.1 - 0.3 - gap);  // poles
    const double t = d.uniform(1, T - 2);
    // Companions walk on the street side of the wall and the far side of the cars.
    const double toward_street = heading == 0 ? -side : side;
    b.addWalkers(heading, b.walkingSpeed(), t, {b.egoAt(t).position.x() + d.uniform(5, 30), y}, 0.3,
                 kind == 1 ? -toward_street : toward_street);
  }
  if (d.chance(0.7))  // a person standing by a wall: not a mover
    b.addStatic("person", {d.uniform(0, J - 15), d.sign() * 10.4}, d.uniform(-180, 180));
}

// ------------------------------------------------------------------ parking lot
// Rows of parked cars nose-in along three aisles; the ego creeps along the middle aisle. People
// walk along the car fronts and through the gaps between cars; cars reverse out of their slots.
void parking(SceneBuilder& b) {
  Draw& d = b.draw();
  const double T = b.duration();
  const double v = d.uniform(2, 5);
  TrajectorySpec ego;
  ego.start = {0, -1.5};
  ego.speed = v;
  if (d.chance(0.5))  // stops for a moment, as for someone crossing
    ego.segments = {segment(d.uniform(3, 7)), segment(1.5, 0), segment(d.uniform(1, 3), 0),
                    segment(2, v)};
  b.setEgo(ego);
  Scenario& sc = b.scenario();
  sc.terrain.surface = "parking";

  const double pitch = 2.7;  // slot width
  const double x_end = rounded(b.egoAt(T).position.x() + 45, 0);
  struct Slot {
    Eigen::Vector2d c;
    double yaw;
    bool filled;
  };
  std::vector<Slot> slots;
  // Rows: y = ±5.9 face the middle aisle (y = 0), ±11.1 and ±22.9 the side aisles (y = ±17).
  const double rows[3] = {5.9, 11.1, 22.9}, yaws[3] = {90, -90, 90};
  const double fill = d.uniform(0.65, 0.9);
  for (double side : {-1.0, 1.0})
    for (int r = 0; r < 3; ++r)
      for (double x = -25; x < x_end; x += pitch)
        slots.push_back({{x, side * rows[r]},
                         side * yaws[r] + (d.chance(0.3) ? 180 : 0),  // some parked nose-out
                         d.chance(fill)});

  // Cars reversing out of the middle aisle's left row (the ego keeps to the right) and of a side
  // aisle's row, then driving off.
  auto reverse_out = [&](double row_y, double aisle_side, double t_ref, double ahead) {
    const double x = b.egoAt(t_ref).position.x() + ahead;
    Slot* best = nullptr;
    for (Slot& s : slots)
      if (s.c.y() == row_y && (!best || std::abs(s.c.x() - x) < std::abs(best->c.x() - x)))
        best = &s;
    best->filled = false;
    TrajectorySpec spec;
    spec.heading = degrees(-90 * aisle_side);  // nose-in: facing away from the aisle
    const double wait = d.uniform(0.5, 3);
    const double turn = 30 * aisle_side * (d.chance(0.5) ? 1 : -1);
    spec.segments = {segment(wait, 0), segment(1.5, 1.2, 0, true), segment(3, -1, turn, true),
                     segment(1, 0, 0, true), segment(2, d.uniform(2.5, 4))};
    b.addMover(d.chance(0.8) ? "car" : "van", spec, 0, best->c);
  };
  reverse_out(5.9, -1, d.uniform(1, 5), d.uniform(15, 30));
  if (d.chance(0.6)) reverse_out(-11.1, -1, d.uniform(1, 5), d.uniform(-10, 30));
  for (const Slot& s : slots)
    if (s.filled) b.addStatic(d.chance(0.75) ? "car" : "van", s.c, s.yaw);
  for (double side : {-1.0, 1.0})  // lamp posts on the islands between back-to-back rows
    for (double x = -25 + pitch * d.integer(0, 4); x < x_end; x += 5 * pitch)
      b.addStatic("pole", {x, side * 8.5}, 0);  // at a slot's middle: never in a gap

  // A car driving along a side aisle.
  if (d.chance(0.7)) {
    TrajectorySpec spec;
    spec.heading = d.chance(0.5) ? 0 : M_PI;
    spec.speed = d.uniform(3, 7);
    const double t = d.uniform(2, T - 2);
    b.addMover(vehicleType(d) == "truck" ? "van" : "car", spec, t,
               {b.egoAt(t).position.x() + d.uniform(-5, 25), d.sign() * 17});
  }
  // People through the gaps between cars (0.15 m from each car), across the aisle.
  for (int i = d.integer(1, 3); i > 0; --i) {
    const double t = d.uniform(1, T - 2);
    const double x =
        -25 + pitch * (std::floor((b.egoAt(t).position.x() + d.uniform(6, 25) + 25) / pitch) + 0.5);
    const double side = d.sign();
    b.addWalkers(side > 0 ? -90 : 90, b.walkingSpeed(), t, {x, side * d.uniform(4, 9)}, 0.0, 1);
  }
  // People along the car fronts of the middle aisle, 0.3-0.5 m from the bumpers, some in groups.
  for (int i = d.integer(1, 2); i > 0; --i) {
    const double side = d.sign(), heading = d.chance(0.5) ? 0 : 180;
    const double t = d.uniform(1, T - 2);
    const double y = side * (5.9 - 2.2 - 0.3 - d.uniform(0.3, 0.5));
    b.addWalkers(heading, b.walkingSpeed(), t, {b.egoAt(t).position.x() + d.uniform(5, 25), y}, 0.5,
                 heading == 0 ? -side : side);
  }
  if (d.chance(0.7))  // someone standing at their car
    b.addStatic("person", {d.uniform(5, x_end - 45), d.sign() * 3.3}, d.uniform(-180, 180));
}

// ------------------------------------------------------------------ open / off-road
// Rolling terrain with a dirt track, brush and scattered trees; vehicles crossing, oncoming and
// off-road (one stopping and going on); people walking, some past a bush.
void open(SceneBuilder& b) {
  Draw& d = b.draw();
  const double T = b.duration();
  TrajectorySpec ego;
  ego.speed = d.uniform(3, 8);
  for (double t = 0; t < T; t += 4)
    ego.segments.push_back(segment(d.uniform(3, 5), -1, d.uniform(-6, 6)));
  b.setEgo(ego);
  Scenario& sc = b.scenario();
  sc.terrain.type = "rolling";
  sc.terrain.amplitude = d.uniform(0.3, 1.0);
  sc.terrain.wavelength = d.uniform(35, 60);
  sc.terrain.road_width = 5;
  const Eigen::Vector4d region = b.egoRegion(70);
  b.addClutter("brush", d.integer(50, 90), region, 2.0);
  b.addClutter("tree", d.integer(15, 40), region, 3.0);

  TrajectorySpec spec;
  for (int i = d.integer(1, 2); i > 0; --i) {  // crossing ahead of us
    const double t = d.uniform(2, T - 2);
    const Trajectory::State e = b.egoAt(t);
    spec.heading = degrees((e.heading + d.sign() * M_PI / 2) / kDeg + d.uniform(-20, 20));
    spec.speed = d.uniform(4, 12);
    b.addMover(vehicleType(d), spec, t, b.besideEgo(t, d.uniform(15, 40), 0));
  }
  {  // oncoming beside the track
    const double t = d.uniform(2, T - 2);
    spec.heading = degrees(b.egoAt(t).heading / kDeg + 180);
    spec.speed = d.uniform(4, 12);
    b.addMover(vehicleType(d), spec, t, b.besideEgo(t, d.uniform(10, 30), 3.5));
  }
  {  // off-road, stopping for a few seconds and going on
    const double t = d.uniform(2, T - 2);
    spec.heading = degrees(d.uniform(-180, 180));
    spec.speed = d.uniform(2, 12);
    spec.segments = {segment(d.uniform(1, 4)), segment(1.5, 0), segment(d.uniform(1, 3), 0),
                     segment(2, spec.speed)};
    b.addMover(d.chance(0.5) ? "van" : "truck", spec, t,
               b.besideEgo(t, d.uniform(10, 40), d.sign() * d.uniform(8, 30)));
    spec.segments.clear();
  }
  for (int i = d.integer(2, 3); i > 0; --i) {  // people, one of them past a bush
    const double t = d.uniform(1, T - 2);
    const double heading = d.uniform(-180, 180);
    const Eigen::Vector2d p = b.besideEgo(t, d.uniform(8, 35), d.sign() * d.uniform(4, 20));
    b.addWalkers(heading, b.walkingSpeed(), t, p, 0.3, 1);
    if (i == 1) {
      ObjectSpec& bush = b.addStatic(
          "brush", p - (0.3 + d.uniform(0.3, 0.5) + 0.8) * direction(degrees(heading) + M_PI / 2),
          0);
      bush.radius = 0.8;
      bush.size.z() = d.uniform(0.8, 1.4);
    }
  }
  if (d.chance(0.5)) {  // a cyclist on the track ahead
    spec.heading = degrees(b.egoAt(0).heading / kDeg);
    spec.speed = d.uniform(3, 6);
    b.addMover("cyclist", spec, 1, b.besideEgo(1, d.uniform(10, 25), 1.5));
  }
}

// ------------------------------------------------------------------ forest trail
// A winding trail through dense trees and brush; hikers (slow, in groups, beside trees), a
// cyclist and a slow vehicle.
void trail(SceneBuilder& b) {
  Draw& d = b.draw();
  const double T = b.duration();
  TrajectorySpec ego;
  ego.speed = d.uniform(2, 5);
  double sign = d.sign();
  for (double t = 0; t < T; t += 3, sign = -sign)
    ego.segments.push_back(segment(d.uniform(2, 4), -1, sign * d.uniform(4, 10)));
  b.setEgo(ego);
  Scenario& sc = b.scenario();
  sc.terrain.type = "rolling";
  sc.terrain.amplitude = d.uniform(0.2, 0.6);
  sc.terrain.wavelength = d.uniform(25, 45);
  sc.terrain.road_width = 3;
  const Eigen::Vector4d region = b.egoRegion(45);
  b.addClutter("tree", d.integer(150, 250), region, 1.0);
  b.addClutter("brush", d.integer(60, 120), region, 0.8);

  for (int i = d.integer(2, 4); i > 0; --i) {  // hikers, some beside a tree trunk or a bush
    const double t = d.uniform(1, T - 2);
    const double heading = d.uniform(-180, 180);
    const Eigen::Vector2d p = b.besideEgo(t, d.uniform(6, 30), d.sign() * d.uniform(2, 12));
    b.addWalkers(heading, b.walkingSpeed(), t, p, 0.4, 1);
    const Eigen::Vector2d right = -direction(degrees(heading) + M_PI / 2);
    const double gap = d.uniform(0.3, 0.5);
    if (d.chance(0.5)) {
      ObjectSpec& tree = b.addStatic("tree", p + (0.3 + gap + 0.25) * right, 0);
      tree.size.z() = d.uniform(6, 10);
      tree.radius = d.uniform(1.5, 2.5);
      tree.trunk_radius = 0.25;
      tree.trunk_height = rounded(0.45 * tree.size.z(), 2);  // the crown above a walker's head
    } else {
      ObjectSpec& bush = b.addStatic("brush", p + (0.3 + gap + 0.7) * right, 0);
      bush.radius = 0.7;
      bush.size.z() = d.uniform(0.8, 1.4);
    }
  }
  TrajectorySpec spec;
  {  // a cyclist
    const double t = d.uniform(2, T - 2);
    spec.heading = degrees(d.uniform(-180, 180));
    spec.speed = d.uniform(3, 7);
    b.addMover("cyclist", spec, t, b.besideEgo(t, d.uniform(8, 30), d.sign() * d.uniform(2, 10)));
  }
  {  // a slow vehicle (forestry, maintenance)
    const double t = d.uniform(2, T - 2);
    spec.heading = degrees(d.uniform(-180, 180));
    spec.speed = d.uniform(3, 8);
    b.addMover(d.chance(0.5) ? "car" : "truck", spec, t,
               b.besideEgo(t, d.uniform(10, 35), d.sign() * d.uniform(3, 15)));
  }
}

const std::map<std::string, std::function<void(SceneBuilder&)>>& generators() {
  static const std::map<std::string, std::function<void(SceneBuilder&)>> g = {{"highway", highway},
                                                                              {"urban", urban},
                                                                              {"parking", parking},
                                                                              {"open", open},
                                                                              {"trail", trail}};
  return g;
}

// ------------------------------------------------------------------ YAML

std::string num(double v) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.10g", v == 0.0 ? 0.0 : v);
  return text;
}
std::string deg(double rad) {
  return num(rounded(rad / kDeg, 6));
}
std::string xy(const Eigen::Vector2d& p) {
  return "[" + num(p.x()) + ", " + num(p.y()) + "]";
}

void writeTrajectory(std::ostringstream& out, const TrajectorySpec& t) {
  out << "    start: " << xy(t.start) << "\n    heading: " << deg(t.heading)
      << "\n    speed: " << num(t.speed) << "\n";
  if (t.segments.empty()) return;
  out << "    segments:\n";
  for (const TrajectorySegment& g : t.segments) {
    out << "      - {duration: " << num(g.duration);
    if (g.speed >= 0) out << ", speed: " << num(g.speed);
    if (g.turn_rate != 0) out << ", turn_rate: " << deg(g.turn_rate);
    if (g.reverse) out << ", reverse: true";
    out << "}\n";
  }
}

void writeObject(std::ostringstream& out, const ObjectSpec& o) {
  if (o.mover) {
    out << "  - type: " << o.type << "\n";
    writeTrajectory(out, o.trajectory);
  } else {
    out << "  - {type: " << o.type << ", position: " << xy(o.trajectory.start)
        << ", yaw: " << deg(o.trajectory.heading);
  }
  const bool round_shape = o.type == "tree" || o.type == "pole" || o.type == "brush";
  const std::string sep = o.mover ? "\n    " : ", ";
  if (!round_shape && o.size != Eigen::Vector3d::Zero())
    out << sep << "size: [" << num(o.size.x()) << ", " << num(o.size.y()) << ", " << num(o.size.z())
        << "]";
  if (round_shape && o.size.z() > 0) out << sep << "height: " << num(o.size.z());
  if (round_shape && o.radius > 0) out << sep << "radius: " << num(o.radius);
  if (o.trunk_radius > 0) out << sep << "trunk_radius: " << num(o.trunk_radius);
  if (o.trunk_height > 0) out << sep << "trunk_height: " << num(o.trunk_height);
  out << (o.mover ? "\n" : "}\n");
}

}  // namespace

const std::vector<std::string>& sceneFamilies() {
  static const std::vector<std::string> f = {"highway", "urban", "parking", "open", "trail"};
  return f;
}

const std::vector<std::string>& sceneSensors() {
  static const std::vector<std::string> s = {"hdl64", "hdl32", "vlp16", "os1_64", "ladar2d"};
  return s;
}

Split splitOf(std::uint64_t seed) {
  return seed % 2 == 1 ? Split::kTune : Split::kCheck;
}

std::string splitName(Split split) {
  return split == Split::kTune ? "tune" : "check";
}

std::string sensorOfSeed(std::uint64_t seed) {
  return sceneSensors()[((seed + 1) / 2) % sceneSensors().size()];
}

Scenario generateScene(const std::string& family, std::uint64_t seed, const SceneOptions& options) {
  const auto it = generators().find(family);
  if (it == generators().end()) {
    std::string known;
    for (const auto& f : sceneFamilies()) known += (known.empty() ? "" : ", ") + f;
    throw InputError("unknown scene family '" + family + "' (known: " + known + ")");
  }
  if (seed == 0) throw InputError("scene seeds start at 1 (odd seeds tune, even seeds check)");
  if (options.frames < 1 || !(options.rate_hz > 0))
    throw InputError("scene options: frames and rate must be positive");
  SceneBuilder builder(family, seed, options);
  builder.drawSensor();
  it->second(builder);
  builder.addBlindFrames();
  // Track ids follow the file: movers first, then statics (parseScenario's order).
  Scenario sc = builder.scenario();
  std::stable_partition(sc.objects.begin(), sc.objects.end(),
                        [](const ObjectSpec& o) { return o.mover; });
  return sc;
}

std::string toYaml(const Scenario& sc) {
  std::ostringstream out;
  out << "# Generated by pcl_movers::sim::generateScene; read by pcl_movers_simulate.\n"
      << "name: " << sc.name << "\nseed: " << sc.seed << "\nframes: " << sc.frames
      << "\nrate_hz: " << num(sc.rate_hz) << "\n\nsensor:\n  preset: " << sc.sensor.preset
      << "\n  height: " << num(sc.sensor.height) << "\n  max_range: " << num(sc.sensor.max_range)
      << "\n  min_range: " << num(sc.sensor.min_range)
      << "\n  range_noise: " << num(sc.sensor.range_noise)
      << "\n  dropout: " << num(sc.sensor.dropout) << "\n";
  if (sc.sensor.sweep != "instant") out << "  sweep: " << sc.sensor.sweep << "\n";
  if (!sc.blind_frames.empty()) {
    out << "blind_frames: [";
    for (std::size_t i = 0; i < sc.blind_frames.size(); ++i)
      out << (i ? ", " : "") << sc.blind_frames[i];
    out << "]\n";
  }
  const TerrainSpec& t = sc.terrain;
  out << "\nterrain:\n  type: " << t.type << "\n  height: " << num(t.height) << "\n";
  if (t.type != "plane")
    out << "  slope: [" << num(t.slope.x()) << ", " << num(t.slope.y()) << "]\n";
  if (t.type == "rolling")
    out << "  amplitude: " << num(t.amplitude) << "\n  wavelength: " << num(t.wavelength) << "\n";
  out << "  surface: " << t.surface << "\n  road_width: " << num(t.road_width) << "\n";
  if (!sc.roads.empty()) {
    out << "\nroads:\n";
    for (const RoadSpec& r : sc.roads) {
      out << "  - {points: [";
      for (std::size_t i = 0; i < r.points.size(); ++i) out << (i ? ", " : "") << xy(r.points[i]);
      out << "], width: " << num(r.width) << "}\n";
    }
  }
  out << "\nego:\n";
  std::ostringstream ego;
  writeTrajectory(ego, sc.ego);
  std::string ego_text = ego.str();  // written for a list item: two spaces too deep here
  std::string shallow;
  std::istringstream lines(ego_text);
  for (std::string line; std::getline(lines, line);) shallow += line.substr(2) + "\n";
  out << shallow;
  for (bool movers : {true, false}) {
    bool any = false;
    for (const ObjectSpec& o : sc.objects) {
      if (o.mover != movers) continue;
      if (!any) out << (movers ? "\nmovers:\n" : "\nstatics:\n");
      any = true;
      writeObject(out, o);
    }
  }
  if (!sc.clutter.empty()) {
    out << "\nclutter:\n";
    for (const ClutterSpec& c : sc.clutter)
      out << "  - {type: " << c.type << ", count: " << c.count << ", region: [" << num(c.region[0])
          << ", " << num(c.region[1]) << ", " << num(c.region[2]) << ", " << num(c.region[3])
          << "], min_spacing: " << num(c.min_spacing) << "}\n";
  }
  return out.str();
}

}  // namespace sim
}  // namespace pcl_movers
