/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scene_families.h>

#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

namespace pcl_movers {
namespace sim {

namespace fs = std::filesystem;
namespace sem = io::semantic;

namespace {

// ------------------------------------------------------------------ randomness
// splitmix64: a counter-based generator, so every ray's noise depends only on its own
// (seed, frame, row, column, object) and never on evaluation order or culling decisions.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class Rng {
 public:
  explicit Rng(std::uint64_t state) : state_(state) {}
  Rng(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0, std::uint64_t d = 0)
      : state_(mix64(mix64(mix64(mix64(a) ^ b) ^ c) ^ d)) {}
  /** Uniform in [0, 1). */
  double uniform() {
    state_ += 0x9E3779B97F4A7C15ull;
    return double(mix64(state_) >> 11) * (1.0 / 9007199254740992.0);
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /** Standard normal by Box-Muller (portable, unlike std::normal_distribution). */
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::uint64_t state_;
};

/** sin(x) from a 4096-entry table with linear interpolation (error < 3e-7): only used to find
 * the bracket of a terrain crossing, which the exact function then refines. */
class FastSin {
 public:
  FastSin() {
    for (int i = 0; i <= kSize; ++i) table_[i] = std::sin(2.0 * M_PI * i / kSize);
  }
  double operator()(double x) const {
    const double u = x * (kSize / (2.0 * M_PI));
    const double fl = std::floor(u);
    const int i = int(static_cast<std::int64_t>(fl) & (kSize - 1));
    const double w = u - fl;
    return table_[i] + w * (table_[i + 1] - table_[i]);
  }

 private:
  static constexpr int kSize = 4096;
  double table_[kSize + 1];
};

const FastSin& fastSin() {
  static const FastSin table;
  return table;
}

// ------------------------------------------------------------------ primitives
enum class Shape { Box, Cylinder, Ellipsoid };

/** In the object's local frame: x forward (heading), y left, z up, origin on the ground under the
 * object's centre. Box: centre ± half; Cylinder: vertical, radius half.x, z centre ± half.z;
 * Ellipsoid: radii half. */
struct Primitive {
  Shape shape = Shape::Box;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  std::uint16_t cls = sem::kUnlabeled;
  float reflectance = 0.3f;
  double free_path = 0;  ///< > 0: porous (foliage), mean penetration depth [m]
  int leg = 0;           ///< ±1: a walking person's leg, swung along x
};

Primitive box(double cx, double cy, double cz, double lx, double ly, double lz, std::uint16_t cls,
              float refl) {
  Primitive p;
  p.shape = Shape::Box;
  p.center = {cx, cy, cz};
  p.half = {lx / 2, ly / 2, lz / 2};
  p.cls = cls;
  p.reflectance = refl;
  return p;
}
Primitive cylinder(double cx, double cy, double z0, double z1, double r, std::uint16_t cls,
                   float refl) {
  Primitive p;
  p.shape = Shape::Cylinder;
  p.center = {cx, cy, (z0 + z1) / 2};
  p.half = {r, r, (z1 - z0) / 2};
  p.cls = cls;
  p.reflectance = refl;
  return p;
}
Primitive ellipsoid(double cx, double cy, double cz, double rx, double ry, double rz,
                    std::uint16_t cls, float refl, double free_path = 0) {
  Primitive p;
  p.shape = Shape::Ellipsoid;
  p.center = {cx, cy, cz};
  p.half = {rx, ry, rz};
  p.cls = cls;
  p.reflectance = refl;
  p.free_path = free_path;
  return p;
}

/** Entry and exit distances of a ray (o + t d) through a primitive; false when missed. */
bool intersect(const Primitive& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t0,
               double& t1, Eigen::Vector3d& normal) {
  const Eigen::Vector3d rel = o - p.center;
  switch (p.shape) {
    case Shape::Box: {
      t0 = -std::numeric_limits<double>::infinity();
      t1 = std::numeric_limits<double>::infinity();
      int axis = 0;
      for (int a = 0; a < 3; ++a) {
        if (std::abs(d[a]) < 1e-12) {
          if (std::abs(rel[a]) > p.half[a]) return false;
          continue;
        }
        const double inv = 1.0 / d[a];
        double ta = (-p.half[a] - rel[a]) * inv, tb = (p.half[a] - rel[a]) * inv;
        if (ta > tb) std::swap(ta, tb);
        if (ta > t0) {
          t0 = ta;
          axis = a;
        }
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
      }
      normal = Eigen::Vector3d::Zero();
      normal[axis] = d[axis] > 0 ? -1.0 : 1.0;
      return true;
    }
    case Shape::Cylinder: {
      const double r = p.half.x(), hz = p.half.z();
      // Side: |rel.xy + t d.xy| = r; caps: z = ±hz.
      const double a = d.x() * d.x() + d.y() * d.y();
      double s0 = -std::numeric_limits<double>::infinity(),
             s1 = std::numeric_limits<double>::infinity();
      if (a > 1e-12) {
        const double b = rel.x() * d.x() + rel.y() * d.y();
        const double c = rel.x() * rel.x() + rel.y() * rel.y() - r * r;
        const double disc = b * b - a * c;
        if (disc < 0) return false;
        const double sq = std::sqrt(disc);
        s0 = (-b - sq) / a;
        s1 = (-b + sq) / a;
      } else if (rel.x() * rel.x() + rel.y() * rel.y() > r * r) {
        return false;
      }
      double z0 = -std::numeric_limits<double>::infinity(),
             z1 = std::numeric_limits<double>::infinity();
      if (std::abs(d.z()) > 1e-12) {
        z0 = (-hz - rel.z()) / d.z();
        z1 = (hz - rel.z()) / d.z();
        if (z0 > z1) std::swap(z0, z1);
      } else if (std::abs(rel.z()) > hz) {
        return false;
      }
      t0 = std::max(s0, z0);
      t1 = std::min(s1, z1);
      if (t0 > t1) return false;
      if (s0 >= z0) {
        const Eigen::Vector3d q = rel + t0 * d;
        normal = Eigen::Vector3d(q.x(), q.y(), 0).normalized();
      } else {
        normal = Eigen::Vector3d(0, 0, d.z() > 0 ? -1.0 : 1.0);
      }
      return true;
    }
    case Shape::Ellipsoid: {
      const Eigen::Vector3d os = rel.cwiseQuotient(p.half), ds = d.cwiseQuotient(p.half);
      const double a = ds.squaredNorm(), b = os.dot(ds), c = os.squaredNorm() - 1.0;
      const double disc = b * b - a * c;
      if (disc < 0) return false;
      const double sq = std::sqrt(disc);
      t0 = (-b - sq) / a;
      t1 = (-b + sq) / a;
      const Eigen::Vector3d q = rel + t0 * d;
      normal = q.cwiseQuotient(p.half.cwiseProduct(p.half)).normalized();
      return true;
    }
  }
  return false;
}

// ------------------------------------------------------------------ objects
struct Object {
  int track_id = 0;
  std::string type;      ///< scenario type (car, tree, ...)
  std::string gt_class;  ///< objects.txt class (Car, Tree, ...)
  bool mover = false;    ///< follows a trajectory
  bool moving = false;   ///< track's median world speed > 0.5 m/s (objects.txt flag)
  Trajectory trajectory;
  std::vector<Primitive> prims;
  Eigen::Vector3d box_min = Eigen::Vector3d::Zero(), box_max = Eigen::Vector3d::Zero();
  double stride = 0;  ///< person/cyclist leg swing amplitude [m]
};

std::uint16_t movingClass(std::uint16_t cls, const std::string& type) {
  if (type == "person") return sem::kMovingPerson;
  if (type == "cyclist") return 253;  // SemanticKITTI moving-bicyclist
  if (type == "truck") return 258;    // moving-truck
  if (cls == sem::kCar) return sem::kMovingCar;
  return cls;
}

std::string gtClass(const std::string& type) {
  if (type == "car") return "Car";
  if (type == "van") return "Van";
  if (type == "truck") return "Truck";
  if (type == "person") return "Pedestrian";
  if (type == "cyclist") return "Cyclist";
  if (type == "tree") return "Tree";
  if (type == "pole") return "Pole";
  if (type == "brush") return "Brush";
  if (type == "wall") return "Wall";
  return "Building";
}

/** Builds the primitives of one object; sizes of 0 take the type's defaults. */
void buildShape(const ObjectSpec& spec, Object& obj) {
  const std::string& t = spec.type;
  auto& P = obj.prims;
  auto wheels = [&](double L, double W, double x_front, double x_rear, double d,
                    std::uint16_t cls) {
    for (double x : {x_front, x_rear})
      for (double s : {-1.0, 1.0})
        P.push_back(box(x, s * (W / 2 - 0.12), d / 2, d, 0.24, d, cls, 0.05f));
  };
  if (t == "car") {
    // Body, narrower glass cabin set back, wheels: a silhouette that changes with the view.
    const Eigen::Vector3d s = bodySize(spec);
    const double L = s.x(), W = s.y(), H = s.z(), belt = 0.62 * H;
    P.push_back(box(0, 0, (0.3 + belt) / 2, L, W, belt - 0.3, sem::kCar, 0.55f));
    P.push_back(box(-0.1 * L, 0, (belt + H) / 2, 0.5 * L, 0.88 * W, H - belt, sem::kCar, 0.15f));
    wheels(L, W, 0.32 * L, -0.32 * L, std::min(0.65, 0.45 * H), sem::kCar);
  } else if (t == "van") {
    const Eigen::Vector3d s = bodySize(spec);
    const double L = s.x(), W = s.y(), H = s.z();
    P.push_back(box(-0.1 * L, 0, (0.35 + H) / 2, 0.8 * L, W, H - 0.35, sem::kCar, 0.5f));
    P.push_back(
        box(0.4 * L, 0, (0.35 + 0.5 * H) / 2, 0.2 * L, 0.95 * W, 0.5 * H - 0.35, sem::kCar, 0.5f));
    wheels(L, W, 0.33 * L, -0.33 * L, 0.7, sem::kCar);
  } else if (t == "truck") {
    const Eigen::Vector3d s = bodySize(spec);
    const double L = s.x(), W = s.y(), H = s.z();
    P.push_back(
        box(0.39 * L, 0, (0.5 + 0.85 * H) / 2, 0.22 * L, W, 0.85 * H - 0.5, sem::kTruck, 0.5f));
    P.push_back(box(-0.125 * L, 0, (0.9 + H) / 2, 0.75 * L, W, H - 0.9, sem::kTruck, 0.6f));
    P.push_back(box(0, 0, 0.7, L, 0.7 * W, 0.4, sem::kTruck, 0.2f));
    wheels(L, W, 0.36 * L, -0.36 * L, 0.95, sem::kTruck);
    wheels(L, W, -0.22 * L, -0.22 * L, 0.95, sem::kTruck);
  } else if (t == "person") {
    const Eigen::Vector3d s = bodySize(spec);
    const double H = s.z(), w = s.y() / 0.6;
    const double hip = 0.47 * H;
    for (int side : {-1, 1}) {
      Primitive leg = cylinder(0, side * 0.1 * w, 0, hip, 0.075 * w, sem::kPerson, 0.35f);
      leg.leg = side;
      P.push_back(leg);
    }
    P.push_back(ellipsoid(0, 0, 0.66 * H, 0.12 * w, 0.2 * w, 0.2 * H, sem::kPerson, 0.4f));
    P.push_back(ellipsoid(0, 0, H - 0.065 * H, 0.1 * w, 0.09 * w, 0.065 * H, sem::kPerson, 0.3f));
    obj.stride = 0.2 * std::min(1.0, s.x() / 0.6);
  } else if (t == "cyclist") {
    const Eigen::Vector3d s = bodySize(spec);
    const double L = s.x(), H = s.z();
    const std::uint16_t c = sem::kBicyclist;
    P.push_back(box(0.3 * L, 0, 0.34, 0.37 * L, 0.06, 0.68, c, 0.3f));   // front wheel
    P.push_back(box(-0.3 * L, 0, 0.34, 0.37 * L, 0.06, 0.68, c, 0.3f));  // rear wheel
    P.push_back(box(0, 0, 0.7, 0.45 * L, 0.06, 0.25, c, 0.4f));          // frame
    for (int side : {-1, 1}) {
      Primitive leg = cylinder(0, side * 0.12, 0.35, 0.55 * H, 0.07, c, 0.35f);
      leg.leg = side;
      P.push_back(leg);
    }
    P.push_back(ellipsoid(-0.05 * L, 0, 0.73 * H, 0.2, 0.18, 0.17 * H, c, 0.4f));
    P.push_back(ellipsoid(0.05 * L, 0, H - 0.06 * H, 0.1, 0.09, 0.06 * H, c, 0.3f));
    obj.stride = 0.1;
  } else if (t == "tree") {
    const double H = spec.size.z() > 0 ? spec.size.z() : 7.0;
    const double R = spec.radius > 0 ? spec.radius : 2.2;
    const double r = spec.trunk_radius > 0 ? spec.trunk_radius : 0.2;
    const double base = spec.trunk_height > 0 ? std::min(spec.trunk_height, 0.9 * H) : 0.35 * H;
    P.push_back(cylinder(0, 0, 0, base + 0.5 * (H - base), r, sem::kTrunk, 0.25f));
    // Foliage is porous: rays penetrate an exponentially distributed depth, some pass through.
    P.push_back(ellipsoid(0, 0, (base + H) / 2, R, R, (H - base) / 2, sem::kVegetation, 0.3f, 0.7));
  } else if (t == "pole") {
    const double H = spec.size.z() > 0 ? spec.size.z() : 6.0;
    const double r = spec.radius > 0 ? spec.radius : 0.1;
    P.push_back(cylinder(0, 0, 0, H, r, sem::kPole, 0.45f));
  } else if (t == "brush") {
    const double H = spec.size.z() > 0 ? spec.size.z() : 1.0;
    const double R = spec.radius > 0 ? spec.radius : 1.0;
    P.push_back(ellipsoid(0, 0, 0.45 * H, R, 0.8 * R, 0.55 * H, sem::kVegetation, 0.25f, 0.35));
  } else if (t == "wall") {
    P.push_back(box(0, 0, spec.size.z() / 2, spec.size.x(), spec.size.y(), spec.size.z(),
                    sem::kFence, 0.35f));
  } else {  // building
    P.push_back(box(0, 0, spec.size.z() / 2, spec.size.x(), spec.size.y(), spec.size.z(),
                    sem::kBuilding, 0.4f));
  }
  // Ground-truth box: the primitives' bounds with legs at both ends of their swing.
  obj.box_min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  obj.box_max = -obj.box_min;
  for (const Primitive& p : P) {
    const Eigen::Vector3d swing(p.leg ? obj.stride : 0.0, 0, 0);
    obj.box_min = obj.box_min.cwiseMin(p.center - p.half - swing);
    obj.box_max = obj.box_max.cwiseMax(p.center + p.half + swing);
  }
  obj.box_min.z() = std::min(obj.box_min.z(), 0.0);
}

/** Footprint radius used to keep clutter apart and off paths. */
double footprint(const ObjectSpec& s) {
  if (s.type == "tree") return s.radius > 0 ? s.radius : 2.2;
  if (s.type == "brush") return s.radius > 0 ? s.radius : 1.0;
  if (s.type == "pole") return 0.3;
  if (s.type == "person") return 0.5;
  if (s.type == "car") return 2.4;
  return 0.5 * std::hypot(s.size.x(), s.size.y());
}

/** A boolean raster over the scene (roads; keep-clear zones for clutter). */
class Raster {
 public:
  void init(const Eigen::Vector4d& extent) {
    const double w = extent[1] - extent[0], h = extent[3] - extent[2];
    cell_ = std::max(0.25, std::max(w, h) / 4000.0);
    x0_ = extent[0];
    y0_ = extent[2];
    nx_ = std::max(1, int(std::ceil(w / cell_)));
    ny_ = std::max(1, int(std::ceil(h / cell_)));
    bits_.assign(std::size_t(nx_) * std::size_t(ny_), 0);
  }
  void stamp(const Eigen::Vector2d& c, double r) {
    forDisk(c, r, [&](std::size_t i) {
      bits_[i] = 1;
      return false;
    });
  }
  bool any(const Eigen::Vector2d& c, double r) const {
    return const_cast<Raster*>(this)->forDisk(c, r, [&](std::size_t i) { return bits_[i] != 0; });
  }
  bool at(double x, double y) const {
    const int i = int(std::floor((x - x0_) / cell_)), j = int(std::floor((y - y0_) / cell_));
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return false;
    return bits_[std::size_t(j) * nx_ + i] != 0;
  }
  /** Stamps disks of radius r at points every half cell along each segment. Each cell of a
   * segment's bounding box is tested against the two sample points nearest its projection
   * only (its distance to the samples is convex along the segment): the same cells as stamping
   * every disk, in time proportional to the area instead of the area times the samples (a 74 m
   * wide road took 39 s under the sanitizers). */
  void stampPolyline(const std::vector<Eigen::Vector2d>& pts, double r) {
    for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
      const Eigen::Vector2d a = pts[k], d = pts[k + 1] - pts[k];
      const double len = d.norm();
      const int n = std::max(1, int(std::ceil(len / (0.5 * cell_))));
      forBox(a.cwiseMin(pts[k + 1]), a.cwiseMax(pts[k + 1]), r,
             [&](double x, double y, std::size_t cell) {
               const double t =
                   len > 0 ? ((x - a.x()) * d.x() + (y - a.y()) * d.y()) / (len * len) : 0;
               const double u = std::clamp(t, 0.0, 1.0) * n;
               for (const int s : {int(std::floor(u)), int(std::ceil(u))}) {
                 const Eigen::Vector2d c = a + d * (double(std::clamp(s, 0, n)) / n);
                 if ((x - c.x()) * (x - c.x()) + (y - c.y()) * (y - c.y()) <= r * r) {
                   bits_[cell] = 1;
                   break;
                 }
               }
               return false;
             });
    }
  }

 private:
  /** Calls f(x, y, cell) for the cells whose index box covers [lo - r, hi + r] (x, y: the cell's
   * centre) until it returns true; returns whether it did. */
  template <typename F>
  bool forBox(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double r, F f) {
    const int i0 = std::max(0, int(std::floor((lo.x() - r - x0_) / cell_)));
    const int i1 = std::min(nx_ - 1, int(std::floor((hi.x() + r - x0_) / cell_)));
    const int j0 = std::max(0, int(std::floor((lo.y() - r - y0_) / cell_)));
    const int j1 = std::min(ny_ - 1, int(std::floor((hi.y() + r - y0_) / cell_)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        if (f(x0_ + (i + 0.5) * cell_, y0_ + (j + 0.5) * cell_, std::size_t(j) * nx_ + i))
          return true;
    return false;
  }
  template <typename F>
  bool forDisk(const Eigen::Vector2d& c, double r, F f) {
    return forBox(c, c, r, [&](double x, double y, std::size_t cell) {
      return (x - c.x()) * (x - c.x()) + (y - c.y()) * (y - c.y()) <= r * r && f(cell);
    });
  }
  double x0_ = 0, y0_ = 0, cell_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint8_t> bits_;
};

std::uint16_t surfaceClass(const std::string& s) {
  if (s == "road") return sem::kRoad;
  if (s == "sidewalk") return sem::kSidewalk;
  if (s == "parking") return sem::kParking;
  if (s == "other-ground") return sem::kOtherGround;
  return sem::kTerrain;
}

/** Per-frame state of one object, with the ray transform into its local frame. */
struct FrameObject {
  const Object* obj = nullptr;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, ground contact
  double yaw = 0, speed = 0;
  Eigen::Vector3d origin_local = Eigen::Vector3d::Zero();  // sensor origin in local frame
  Eigen::Matrix3d sensor_to_local = Eigen::Matrix3d::Identity();
  std::vector<Primitive> prims;  // legs moved to this frame's swing
  double near = 0;               // distance to the bounding sphere [m]
  float elev_min = 0, elev_max = 0;
  Eigen::Vector3d center_s = Eigen::Vector3d::Zero();  // bounding sphere centre, sensor frame
  double radius = 0;                                   // bounding sphere radius [m]
  int n_points = 0;
};

/** Indices of the objects of `fobs` whose bounding sphere covers azimuth `az` of the sensor they
 * were placed for (all of it when the sensor is inside it), nearest first. */
std::vector<int> columnCandidates(const std::vector<FrameObject>& fobs, double az) {
  std::vector<int> cand;
  for (std::size_t i = 0; i < fobs.size(); ++i) {
    const FrameObject& fo = fobs[i];
    if (!std::isfinite(fo.near)) continue;
    const double horiz = std::hypot(fo.center_s.x(), fo.center_s.y());
    if (horiz > fo.radius) {
      const double diff =
          std::remainder(az - std::atan2(fo.center_s.y(), fo.center_s.x()), 2 * M_PI);
      if (std::abs(diff) > std::asin(fo.radius / horiz)) continue;
    }
    cand.push_back(int(i));
  }
  std::stable_sort(cand.begin(), cand.end(),
                   [&](int a, int b) { return fobs[a].near < fobs[b].near; });
  return cand;
}

}  // namespace

// ------------------------------------------------------------------ scene
struct LidarSimulator::Scene {
  std::vector<Object> objects;
  Trajectory ego;
  Raster roads;
  std::uint16_t surface = sem::kTerrain;
  // Terrain: h = height + slope·xy + amplitude·(0.75 sin(k x + p1) sin(k y + p2)
  //                                             + 0.25 sin(k2 (x cos a + y sin a) + p3))
  double height = 0;
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();
  double amplitude = 0, k = 0, k2 = 0, p1 = 0, p2 = 0, p3 = 0, ca = 1, sa = 0;
  double gradient_bound = 0;  // Lipschitz bound of h, for safe ray-marching steps
  double min_step = 1.0;      // smallest ray-marching step [m]
  Eigen::Isometry3d world_from_first = Eigen::Isometry3d::Identity();

  double terrain(double x, double y) const {
    double h = height + slope.x() * x + slope.y() * y;
    if (amplitude > 0)
      h += amplitude * (0.75 * std::sin(k * x + p1) * std::sin(k * y + p2) +
                        0.25 * std::sin(k2 * (x * ca + y * sa) + p3));
    return h;
  }
  /** terrain() with table sines, for bracketing only. */
  double terrainFast(double x, double y) const {
    const FastSin& fs = fastSin();
    return height + slope.x() * x + slope.y() * y +
           amplitude *
               (0.75 * fs(k * x + p1) * fs(k * y + p2) + 0.25 * fs(k2 * (x * ca + y * sa) + p3));
  }
  /** terrainGradient() with table sines (shading only). */
  Eigen::Vector2d terrainGradientFast(double x, double y) const {
    Eigen::Vector2d g = slope;
    if (amplitude > 0) {
      const FastSin& fs = fastSin();
      const double h = 0.5 * M_PI;
      const double sx = fs(k * x + p1), cx = fs(k * x + p1 + h), sy = fs(k * y + p2),
                   cy = fs(k * y + p2 + h), c2 = fs(k2 * (x * ca + y * sa) + p3 + h);
      g.x() += amplitude * (0.75 * k * cx * sy + 0.25 * k2 * ca * c2);
      g.y() += amplitude * (0.75 * k * sx * cy + 0.25 * k2 * sa * c2);
    }
    return g;
  }
  Eigen::Vector2d terrainGradient(double x, double y) const {
    Eigen::Vector2d g = slope;
    if (amplitude > 0) {
      g.x() += amplitude * (0.75 * k * std::cos(k * x + p1) * std::sin(k * y + p2) +
                            0.25 * k2 * ca * std::cos(k2 * (x * ca + y * sa) + p3));
      g.y() += amplitude * (0.75 * k * std::sin(k * x + p1) * std::cos(k * y + p2) +
                            0.25 * k2 * sa * std::cos(k2 * (x * ca + y * sa) + p3));
    }
    return g;
  }

  /** Objects (in `objects` order) at time t, seen from the sensor at T_ws (scenario world); those
   * whose bounding sphere lies beyond max_range have near = +inf and no ray data. */
  std::vector<FrameObject> frameObjects(double t, const Eigen::Isometry3d& T_ws,
                                        double max_range) const {
    const Eigen::Matrix3d R = T_ws.linear();
    const Eigen::Vector3d O = T_ws.translation();
    const Eigen::Isometry3d T_sw = T_ws.inverse();
    std::vector<FrameObject> fobs;
    fobs.reserve(objects.size());
    for (const Object& obj : objects) {
      FrameObject fo;
      fo.obj = &obj;
      const Trajectory::State st = obj.trajectory.at(t);
      fo.yaw = st.heading;
      fo.speed = obj.mover ? st.speed : 0.0;
      fo.position = {st.position.x(), st.position.y(), terrain(st.position.x(), st.position.y())};
      const double c = std::cos(fo.yaw), s = std::sin(fo.yaw);
      Eigen::Matrix3d Rz;
      Rz << c, -s, 0, s, c, 0, 0, 0, 1;
      const Eigen::Vector3d box_center = 0.5 * (obj.box_min + obj.box_max);
      const double radius = 0.5 * (obj.box_max - obj.box_min).norm();
      const Eigen::Vector3d center_s = T_sw * (fo.position + Rz * box_center);
      const double dist = center_s.norm();
      fo.near = dist - radius;
      fo.center_s = center_s;
      fo.radius = radius;
      if (fo.near > max_range) {
        fobs.push_back(fo);  // kept for objects.txt bookkeeping only if within range (below)
        fobs.back().near = std::numeric_limits<double>::infinity();
        continue;
      }
      fo.origin_local = Rz.transpose() * (O - fo.position);
      fo.sensor_to_local = Rz.transpose() * R;
      fo.prims = obj.prims;
      if (obj.stride > 0 && fo.speed > 0.05) {
        // Legs swing at a cadence that grows with speed (about 1.8 steps/s at walking pace).
        const double phase = 2 * M_PI * 0.9 * std::min(2.0, std::max(0.5, fo.speed / 1.4)) * t;
        for (Primitive& p : fo.prims)
          if (p.leg) p.center.x() += p.leg * obj.stride * std::sin(phase + obj.track_id);
      }
      const double horiz = std::hypot(center_s.x(), center_s.y());
      const double el = std::atan2(center_s.z(), horiz);
      const double half = dist > radius ? std::asin(radius / dist) : M_PI;
      fo.elev_min = float(el - half);
      fo.elev_max = float(el + half);
      fobs.push_back(std::move(fo));
    }
    return fobs;
  }

  /** Sensor→world pose in the scenario's world at time t. */
  Eigen::Isometry3d egoPose(double t, double sensor_height) const {
    const Trajectory::State s = ego.at(t);
    const double z = terrain(s.position.x(), s.position.y());
    const Eigen::Vector2d g = terrainGradient(s.position.x(), s.position.y());
    // The vehicle sits on the terrain: z axis along the terrain normal, x along the heading.
    const Eigen::Vector3d n = Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized();
    const Eigen::Vector3d f(std::cos(s.heading), std::sin(s.heading), 0.0);
    const Eigen::Vector3d x = (f - f.dot(n) * n).normalized();
    Eigen::Matrix3d R;
    R.col(0) = x;
    R.col(1) = n.cross(x);
    R.col(2) = n;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() = Eigen::Vector3d(s.position.x(), s.position.y(), z) + sensor_height * n;
    return T;
  }

  /** Nearest terrain intersection of world ray o + t d within (0, t_max). */
  bool intersectTerrain(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max,
                        double& t_hit) const {
    if (amplitude <= 0) {
      // Plane: z - (height + slope·xy) is linear in t.
      const double f0 = o.z() - (height + slope.x() * o.x() + slope.y() * o.y());
      const double f1 = d.z() - (slope.x() * d.x() + slope.y() * d.y());
      if (f1 >= 0 || f0 <= 0) return false;
      t_hit = -f0 / f1;
      return t_hit < t_max;
    }
    // The hills stay within ±amplitude of the mean plane: only the part of the ray inside that
    // slab can hit, and it must hit before it leaves the slab through the bottom.
    const double f0 = o.z() - (height + slope.x() * o.x() + slope.y() * o.y());
    const double f1 = d.z() - (slope.x() * d.x() + slope.y() * d.y());
    double t_begin = 0, t_end = t_max;
    if (f0 > amplitude) {
      if (f1 >= 0) return false;
      t_begin = (f0 - amplitude) / -f1;
    }
    if (f1 < 0) t_end = std::min(t_end, (f0 + amplitude) / -f1);
    if (t_begin >= t_end) return false;
    // Table sines: the root moves by < 1e-5 m against exact sines, below float storage.
    auto f = [&](double t) {
      const Eigen::Vector3d p = o + t * d;
      return p.z() - terrainFast(p.x(), p.y());
    };
    // f changes at most L per metre of ray, so a step of f / L never skips a crossing; the
    // minimum step (1/8 of the shorter hill wavelength) can only miss grazing clips of crests.
    const double L = std::abs(d.z()) + gradient_bound * std::hypot(d.x(), d.y());
    double t = t_begin, ft = f(t);
    if (ft <= 0) {
      if (t > 0) {
        t_hit = t;
        return true;
      }
      return false;  // sensor below the ground
    }
    for (int it = 0; it < 1000 && t < t_end; ++it) {
      const double tn = std::min(t + std::max(ft / L, min_step), t_end);
      const double fn = f(tn);
      if (fn <= 0) {
        // Illinois regula falsi on [t, tn]: f(a) > 0 >= f(b).
        double a = t, b = tn, fa = ft, fb = fn;
        int side = 0;
        for (int k = 0; k < 40 && b - a > 1e-6; ++k) {
          const double m = (a * fb - b * fa) / (fb - fa);
          const double fm = f(m);
          if (std::abs(fm) < 1e-7) {
            a = b = m;
            break;
          }
          if (fm > 0) {
            a = m;
            fa = fm;
            if (side == 1) fb *= 0.5;
            side = 1;
          } else {
            b = m;
            fb = fm;
            if (side == -1) fa *= 0.5;
            side = -1;
          }
        }
        t_hit = 0.5 * (a + b);
        return t_hit < t_max;
      }
      t = tn;
      ft = fn;
    }
    return false;
  }
};

LidarSimulator::LidarSimulator(const Scenario& scenario)
    : scenario_(scenario),
      sensor_(SensorModel::fromName(scenario.sensor.preset)),
      scene_(new Scene) {
  Scene& S = *scene_;
  const double horizon = double(scenario_.frames) / scenario_.rate_hz + 1.0;
  const TerrainSpec& T = scenario_.terrain;
  S.height = T.height;
  S.slope = T.slope;
  if (T.type == "rolling" && T.amplitude > 0) {
    Rng r(scenario_.seed, 0x7e77a1full);
    S.amplitude = T.amplitude;
    S.k = 2 * M_PI / T.wavelength;
    S.k2 = 2 * M_PI / (0.37 * T.wavelength);
    S.p1 = r.uniform(0, 2 * M_PI);
    S.p2 = r.uniform(0, 2 * M_PI);
    S.p3 = r.uniform(0, 2 * M_PI);
    const double a = r.uniform(0, M_PI);
    S.ca = std::cos(a);
    S.sa = std::sin(a);
    S.min_step = 0.37 * T.wavelength / 8.0;
  }
  S.gradient_bound = S.slope.norm() + S.amplitude * (0.75 * S.k * std::sqrt(2.0) + 0.25 * S.k2);
  S.surface = surfaceClass(T.surface);
  S.ego = Trajectory(scenario_.ego, horizon);

  // Scene extent: everything that moves plus roads and clutter regions, padded.
  Eigen::Vector4d ext(1e300, -1e300, 1e300, -1e300);
  auto grow = [&](const Eigen::Vector2d& p, double pad) {
    ext[0] = std::min(ext[0], p.x() - pad);
    ext[1] = std::max(ext[1], p.x() + pad);
    ext[2] = std::min(ext[2], p.y() - pad);
    ext[3] = std::max(ext[3], p.y() + pad);
  };
  std::vector<Trajectory> mover_paths;
  for (const ObjectSpec& o : scenario_.objects) {
    mover_paths.emplace_back(o.trajectory, horizon);
    for (double t = 0; t <= horizon; t += 0.5) grow(mover_paths.back().at(t).position, 10);
  }
  for (double t = 0; t <= horizon; t += 0.5) grow(S.ego.at(t).position, 30);
  for (const RoadSpec& r : scenario_.roads)
    for (const auto& p : r.points) grow(p, r.width);
  for (const ClutterSpec& c : scenario_.clutter) {
    grow({c.region[0], c.region[2]}, 5);
    grow({c.region[1], c.region[3]}, 5);
  }
  std::vector<Eigen::Vector2d> ego_path;
  {
    // The road runs on well before the start and beyond the end of the drive.
    const Trajectory::State first = S.ego.at(0.0), last = S.ego.at(horizon);
    ego_path.push_back(first.position -
                       150.0 * Eigen::Vector2d(std::cos(first.heading), std::sin(first.heading)));
    for (double t = 0; t <= horizon; t += 0.05) ego_path.push_back(S.ego.at(t).position);
    ego_path.push_back(last.position +
                       150.0 * Eigen::Vector2d(std::cos(last.heading), std::sin(last.heading)));
    for (const auto& p : ego_path) grow(p, 20);
  }
  S.roads.init(ext);
  Raster clear;  // zones clutter must avoid
  clear.init(ext);
  if (T.road_width > 0) S.roads.stampPolyline(ego_path, T.road_width / 2);
  for (const RoadSpec& r : scenario_.roads) S.roads.stampPolyline(r.points, r.width / 2);
  clear.stampPolyline(ego_path, std::max(T.road_width / 2, 2.0) + 1.0);
  for (const RoadSpec& r : scenario_.roads) clear.stampPolyline(r.points, r.width / 2 + 1.0);

  // Explicit objects, then clutter; track ids 1..N in this order.
  std::vector<ObjectSpec> specs = scenario_.objects;
  std::vector<std::pair<Eigen::Vector2d, double>> placed;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const ObjectSpec& o = specs[i];
    if (o.mover) {
      std::vector<Eigen::Vector2d> path;
      for (double t = 0; t <= horizon; t += 0.05) path.push_back(mover_paths[i].at(t).position);
      clear.stampPolyline(path, (o.type == "person" ? 0.6 : 2.0) + 1.0);
    } else {
      placed.emplace_back(o.trajectory.start, footprint(o));
    }
  }
  for (std::size_t ci = 0; ci < scenario_.clutter.size(); ++ci) {
    const ClutterSpec& c = scenario_.clutter[ci];
    Rng r(scenario_.seed, 0xc1a77e5ull, ci);
    int made = 0;
    for (int attempt = 0; attempt < 200 * std::max(1, c.count) && made < c.count; ++attempt) {
      ObjectSpec o;
      o.type = c.type;
      o.line = c.line;
      o.trajectory.start = {r.uniform(c.region[0], c.region[1]),
                            r.uniform(c.region[2], c.region[3])};
      o.trajectory.heading = r.uniform(-M_PI, M_PI);
      if (c.type == "tree") {
        o.size.z() = r.uniform(5.0, 11.0);
        o.radius = r.uniform(1.3, 3.0);
        o.trunk_radius = r.uniform(0.12, 0.3);
        o.trunk_height = r.uniform(0.25, 0.5) * o.size.z();
      } else if (c.type == "brush") {
        o.radius = r.uniform(0.5, 1.5);
        o.size.z() = r.uniform(0.5, 1.4);
      } else if (c.type == "pole") {
        o.size.z() = r.uniform(4.0, 8.0);
        o.radius = r.uniform(0.06, 0.15);
      }
      const double fp = footprint(o);
      if (clear.any(o.trajectory.start, fp)) continue;
      bool crowded = false;
      for (const auto& p : placed)
        if ((p.first - o.trajectory.start).norm() < p.second + fp + c.min_spacing) {
          crowded = true;
          break;
        }
      if (crowded) continue;
      placed.emplace_back(o.trajectory.start, fp);
      specs.push_back(o);
      ++made;
    }
  }

  S.objects.resize(specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i) {
    Object& obj = S.objects[i];
    obj.track_id = int(i) + 1;
    obj.type = specs[i].type;
    obj.gt_class = gtClass(obj.type);
    obj.mover = specs[i].mover;
    obj.trajectory = i < mover_paths.size() ? mover_paths[i] : Trajectory(specs[i].trajectory, 0);
    buildShape(specs[i], obj);
    if (obj.mover) {
      std::vector<double> speeds;
      for (int f = 0; f < scenario_.frames; ++f) speeds.push_back(obj.trajectory.at(time(f)).speed);
      std::nth_element(speeds.begin(), speeds.begin() + speeds.size() / 2, speeds.end());
      obj.moving = speeds[speeds.size() / 2] > 0.5;
    }
  }
  S.world_from_first = S.egoPose(0.0, scenario_.sensor.height);
}

LidarSimulator::~LidarSimulator() = default;

void LidarSimulator::setSensor(const SensorModel& sensor) {
  sensor_ = sensor;
}

std::size_t LidarSimulator::getObjectCount() const {
  return scene_->objects.size();
}

double LidarSimulator::terrainHeight(double x, double y) const {
  return scene_->terrain(x, y);
}

double LidarSimulator::columnTime(int column) const {
  if (scenario_.sensor.sweep != "rolling") return 0.0;
  return double(column) / (double(sensor_.columns()) * scenario_.rate_hz);
}

Eigen::Isometry3d LidarSimulator::pose(int frame) const {
  return scene_->world_from_first.inverse() * scene_->egoPose(time(frame), scenario_.sensor.height);
}

Eigen::Isometry3d LidarSimulator::worldPose(int frame) const {
  return scene_->egoPose(time(frame), scenario_.sensor.height);
}

void LidarSimulator::simulate(int frame, pcl::PointCloud<pcl::PointXYZI>& cloud,
                              std::vector<std::uint32_t>& labels,
                              std::vector<io::GroundTruthObject>& objects,
                              Eigen::Isometry3d& pose_out) const {
  const Scene& S = *scene_;
  const SensorSpec& spec = scenario_.sensor;
  const double t = time(frame);
  const Eigen::Isometry3d T_ws = S.egoPose(t, spec.height);  // sensor → scenario world
  const Eigen::Isometry3d T_sw = T_ws.inverse();
  pose_out = S.world_from_first.inverse() * T_ws;

  const int rows = sensor_.rows(), cols = sensor_.columns();
  const double max_range = spec.max_range;

  // ---- objects in this frame (ground truth; the rays of an instant sweep)
  std::vector<FrameObject> fobs = S.frameObjects(t, T_ws, max_range);

  // ---- cast
  cloud.width = std::uint32_t(cols);
  cloud.height = std::uint32_t(rows);
  cloud.is_dense = false;
  cloud.points.assign(std::size_t(rows) * cols, pcl::PointXYZI());
  cloud.sensor_origin_ = Eigen::Vector4f::Zero();
  cloud.sensor_orientation_ = Eigen::Quaternionf::Identity();
  labels.assign(std::size_t(rows) * cols, 0u);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<double> cos_el(rows), sin_el(rows);
  for (int r = 0; r < rows; ++r) {
    cos_el[r] = std::cos(double(sensor_.elevations()[r]));
    sin_el[r] = std::sin(double(sensor_.elevations()[r]));
  }
  const std::uint64_t seed = scenario_.seed;
  // A blind frame (covered sensor, lost packets) has no return at all; its objects get 0 points.
  const bool blind =
      std::binary_search(scenario_.blind_frames.begin(), scenario_.blind_frames.end(), frame);
  if (blind)
    for (pcl::PointXYZI& pt : cloud.points) pt.x = pt.y = pt.z = nan;
  // One column of rays from the sensor at T_col against the objects `fl` placed for it.
  auto cast = [&](int col, std::vector<FrameObject>& fl, const std::vector<int>& cand,
                  const Eigen::Isometry3d& T_col) {
    const Eigen::Matrix3d R = T_col.linear();
    const Eigen::Vector3d O = T_col.translation();
    const double az = sensor_.azimuthOf(col);
    const double ca = std::cos(az), sa = std::sin(az);
    for (int row = 0; row < rows; ++row) {
      const Eigen::Vector3d d_s(cos_el[row] * ca, cos_el[row] * sa, sin_el[row]);
      const float elev = sensor_.elevations()[row];
      Rng rng(seed, std::uint64_t(frame), std::uint64_t(row) << 32 | std::uint64_t(col));
      double best = max_range;
      int best_obj = -1;
      std::uint16_t best_cls = 0;
      float best_refl = 0;
      double best_cos = 1;
      for (int idx : cand) {
        const FrameObject& fo = fl[idx];
        if (fo.near >= best) break;  // sorted: nothing further can be nearer
        if (elev < fo.elev_min || elev > fo.elev_max) continue;
        const Eigen::Vector3d d = fo.sensor_to_local * d_s;
        const Eigen::Vector3d& o = fo.origin_local;
        for (std::size_t pi = 0; pi < fo.prims.size(); ++pi) {
          const Primitive& p = fo.prims[pi];
          double t0, t1;
          Eigen::Vector3d n;
          if (!intersect(p, o, d, t0, t1, n)) continue;
          if (t1 <= 0 || t0 >= best) continue;
          double th = t0;
          double cosi = std::abs(n.dot(d));
          if (p.free_path > 0) {
            Rng leaf(seed, std::uint64_t(frame), std::uint64_t(row) << 32 | std::uint64_t(col),
                     std::uint64_t(fo.obj->track_id) << 8 | pi);
            th = std::max(t0, 0.0) - p.free_path * std::log(1.0 - leaf.uniform());
            if (th >= t1) continue;  // passed through the foliage
            cosi = 0.5 + 0.5 * leaf.uniform();
          } else if (t0 <= 0) {
            continue;  // sensor inside a solid: ignore it
          }
          if (th < best) {
            best = th;
            best_obj = idx;
            best_cls = p.cls;
            best_refl = p.reflectance;
            best_cos = cosi;
          }
        }
      }
      const Eigen::Vector3d d_w = R * d_s;
      double tg;
      bool ground = false;
      if (S.intersectTerrain(O, d_w, best, tg)) {
        best = tg;
        best_obj = -1;
        ground = true;
        const Eigen::Vector3d p = O + tg * d_w;
        const Eigen::Vector2d g = S.terrainGradientFast(p.x(), p.y());
        best_cos = std::abs(Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized().dot(d_w));
        best_cls = S.roads.at(p.x(), p.y()) ? sem::kRoad : S.surface;
        best_refl = best_cls == sem::kRoad ? 0.18f : 0.3f;
      }
      const std::size_t k = std::size_t(row) * cols + col;
      pcl::PointXYZI& pt = cloud.points[k];
      const double noise = rng.normal() * spec.range_noise;
      const bool dropped = spec.dropout > 0 && rng.uniform() < spec.dropout;
      const double range = best + noise;
      if ((!ground && best_obj < 0) || dropped || best < spec.min_range || range > max_range ||
          range <= 0) {
        pt.x = pt.y = pt.z = nan;
        pt.intensity = 0.f;
        continue;
      }
      pt.x = float(range * d_s.x());
      pt.y = float(range * d_s.y());
      pt.z = float(range * d_s.z());
      pt.intensity = float(std::min(1.0, best_refl * (0.35 + 0.65 * best_cos)));
      if (ground) {
        labels[k] = io::makeLabel(best_cls, 0);
      } else {
        FrameObject& fo = fl[best_obj];
        // Moving classes only while the object moves in this frame (MOS ground truth): a parked
        // car, a standing person or a car waiting at a light keeps its static class.
        const std::uint16_t cls =
            fo.speed > sem::kMovingLabelSpeed ? movingClass(best_cls, fo.obj->type) : best_cls;
        labels[k] = io::makeLabel(cls, std::uint16_t(fo.obj->track_id));
        ++fo.n_points;
      }
    }
  };
  if (!blind && spec.sweep == "rolling") {
    // Each column at its own time: the ego pose and every object are evaluated then.
    for (int col = 0; col < cols; ++col) {
      const double tc = t + columnTime(col);
      const Eigen::Isometry3d T_col = S.egoPose(tc, spec.height);
      std::vector<FrameObject> fl = S.frameObjects(tc, T_col, max_range);
      cast(col, fl, columnCandidates(fl, sensor_.azimuthOf(col)), T_col);
      for (std::size_t i = 0; i < fl.size(); ++i) fobs[i].n_points += fl[i].n_points;
    }
  } else if (!blind) {
    std::vector<int> order(fobs.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = int(i);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return fobs[a].near < fobs[b].near; });
    // ---- per-column candidate lists (azimuth interval of each bounding sphere is exact)
    std::vector<std::vector<int>> column_objects(cols);
    const double res = sensor_.azimuthResolution();
    const bool full = sensor_.isFullRevolution();
    for (int idx : order) {
      const FrameObject& fo = fobs[idx];
      if (!std::isfinite(fo.near)) continue;
      const Object& obj = *fo.obj;
      const Eigen::Vector3d box_center = 0.5 * (obj.box_min + obj.box_max);
      const double radius = 0.5 * (obj.box_max - obj.box_min).norm();
      const double c = std::cos(fo.yaw), s = std::sin(fo.yaw);
      const Eigen::Vector3d center_w =
          fo.position + Eigen::Vector3d(c * box_center.x() - s * box_center.y(),
                                        s * box_center.x() + c * box_center.y(), box_center.z());
      const Eigen::Vector3d cs = T_sw * center_w;
      const double horiz = std::hypot(cs.x(), cs.y());
      if (horiz <= radius) {
        for (int col = 0; col < cols; ++col) column_objects[col].push_back(idx);
        continue;
      }
      const double az = std::atan2(cs.y(), cs.x()), half = std::asin(radius / horiz);
      // Column c looks at azimuthMax - (c + 0.5) res.
      const double c_lo = (sensor_.azimuthMax() - (az + half)) / res - 0.5;
      const double c_hi = (sensor_.azimuthMax() - (az - half)) / res - 0.5;
      long lo = long(std::ceil(c_lo)), hi = long(std::floor(c_hi));
      if (!full) {
        lo = std::max(lo, 0L);
        hi = std::min(hi, long(cols) - 1);
      } else if (hi - lo >= cols) {
        lo = 0;
        hi = cols - 1;
      }
      for (long k = lo; k <= hi; ++k) {
        const long col = full ? ((k % cols) + cols) % cols : k;
        column_objects[col].push_back(idx);
      }
    }

    for (int col = 0; col < cols; ++col) cast(col, fobs, column_objects[col], T_ws);
  }

  // ---- ground truth rows, sensor frame
  objects.clear();
  for (const FrameObject& fo : fobs) {
    const Object& obj = *fo.obj;
    const double c = std::cos(fo.yaw), s = std::sin(fo.yaw);
    const Eigen::Vector3d bc = 0.5 * (obj.box_min + obj.box_max);
    const Eigen::Vector3d center_w =
        fo.position + Eigen::Vector3d(c * bc.x() - s * bc.y(), s * bc.x() + c * bc.y(), bc.z());
    const Eigen::Vector3d center_s = T_sw * center_w;
    // An object whose centre is out of range can still have points in the scan (the near end of a
    // car leaving the range): it keeps its row while it has any, or a correct detection of those
    // points would match no box and count as a false alarm.
    if (center_s.norm() > max_range && fo.n_points == 0) continue;
    io::GroundTruthObject g;
    g.frame = frame;
    g.track_id = obj.track_id;
    g.type = obj.gt_class;
    g.center = center_s;
    g.length = obj.box_max.x() - obj.box_min.x();
    g.width = obj.box_max.y() - obj.box_min.y();
    g.height = obj.box_max.z() - obj.box_min.z();
    const Eigen::Vector3d heading_s = T_sw.linear() * Eigen::Vector3d(c, s, 0);
    g.yaw = std::atan2(heading_s.y(), heading_s.x());
    g.moving = obj.moving;
    g.speed = fo.speed;
    g.n_points = fo.n_points;
    objects.push_back(g);
  }
}

// ------------------------------------------------------------------ writing a sequence

void writeSequence(const LidarSimulator& sim, const std::string& folder, bool overwrite,
                   const std::function<void(std::size_t, std::size_t)>& progress) {
  std::error_code ec;
  if (fs::exists(folder, ec) && !fs::is_directory(folder, ec))
    throw InputError(folder, 0, "output exists and is not a folder");
  if (!io::isMissingOrEmptyDirectory(folder) && !overwrite)
    throw InputError(folder, 0, "output folder exists and is not empty (use --overwrite)");
  fs::path target = fs::path(folder);
  if (target.filename().empty()) target = target.parent_path();  // "out/" → "out"
  const fs::path tmp = target.string() + ".simulate-partial";
  fs::remove_all(tmp, ec);
  try {
    io::SequenceWriter writer(tmp.string(), true);
    fs::create_directories(tmp / "labels", ec);
    if (ec) throw InputError((tmp / "labels").string(), 0, "cannot create folder: " + ec.message());
    const int n = sim.getFrameCount();
    std::vector<Eigen::Isometry3d> poses;
    std::vector<double> times;
    std::vector<io::GroundTruthObject> all_objects, objects;
    pcl::PointCloud<pcl::PointXYZI> cloud;
    std::vector<std::uint32_t> labels;
    const bool rolling = sim.getScenario().sensor.sweep == "rolling";
    std::vector<float> point_times;
    for (int f = 0; f < n; ++f) {
      Eigen::Isometry3d pose;
      sim.simulate(f, cloud, labels, objects, pose);
      if (rolling) {  // each point at its column's time, as the Velodyne driver writes it
        point_times.resize(cloud.size());
        for (std::size_t k = 0; k < cloud.size(); ++k)
          point_times[k] = float(sim.columnTime(int(k % cloud.width)));
        writer.writeFrame(std::size_t(f), cloud, point_times);
      } else {
        writer.writeFrame(std::size_t(f), cloud);
      }
      std::ostringstream name;
      name << std::setw(6) << std::setfill('0') << f << ".label";
      io::writeLabels((tmp / "labels" / name.str()).string(), labels);
      poses.push_back(pose);
      times.push_back(sim.time(f));
      all_objects.insert(all_objects.end(), objects.begin(), objects.end());
      if (progress) progress(std::size_t(f + 1), std::size_t(n));
    }
    writer.writePoses(poses);
    writer.writeTimes(times);
    io::writeObjects((tmp / "objects.txt").string(), all_objects);
    const std::string& src = sim.getScenario().path;
    if (!src.empty() && fs::exists(src, ec)) {
      fs::copy_file(src, tmp / "scenario.yaml", fs::copy_options::overwrite_existing, ec);
      if (ec) throw InputError(src, 0, "cannot copy scenario: " + ec.message());
    } else {  // a generated scene: its plain scenario file, which reproduces it
      std::ofstream yaml(tmp / "scenario.yaml");
      yaml << toYaml(sim.getScenario());
      if (!yaml) throw InputError((tmp / "scenario.yaml").string(), 0, "cannot write");
    }
    fs::remove(tmp / ".pcl_movers_write_probe", ec);
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
  // Move into place: replace only what a simulated sequence consists of.
  if (!fs::exists(target, ec)) {
    fs::rename(tmp, target, ec);
    if (ec) {
      fs::remove_all(tmp, ec);
      throw InputError(folder, 0, "cannot move the sequence into place");
    }
    return;
  }
  for (const char* part :
       {"frames", "labels", "poses.txt", "times.txt", "objects.txt", "scenario.yaml"}) {
    fs::remove_all(target / part, ec);
    if (fs::exists(tmp / part)) {
      fs::rename(tmp / part, target / part, ec);
      if (ec) {
        fs::remove_all(tmp, ec);
        throw InputError(folder, 0, std::string("cannot move ") + part + " into place");
      }
    }
  }
  fs::remove_all(tmp, ec);
}

}  // namespace sim
}  // namespace pcl_movers
