/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/eval/registration_pairs.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>

#include <pcl/common/centroid.h>
#include <pcl/common/transforms.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>

namespace pcl_movers {
namespace eval {

namespace {

constexpr float kPi = 3.14159265358979f;

float wrapAngle(float a) {
  while (a > kPi) a -= 2.f * kPi;
  while (a < -kPi) a += 2.f * kPi;
  return a;
}

/** Distance along the ray o + t·d to the solid, or +inf. */
float intersect(const SimShape& s, const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  const float inf = std::numeric_limits<float>::infinity();
  if (s.kind == SimShape::Box) {
    const float c = std::cos(-s.yaw), sn = std::sin(-s.yaw);
    const Eigen::Vector3f rel = o - s.centre;
    const Eigen::Vector3f lo(c * rel.x() - sn * rel.y(), sn * rel.x() + c * rel.y(), rel.z());
    const Eigen::Vector3f ld(c * d.x() - sn * d.y(), sn * d.x() + c * d.y(), d.z());
    const Eigen::Vector3f half(0.5f * s.length, 0.5f * s.width, 0.5f * s.height);
    float t0 = -inf, t1 = inf;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(ld[a]) < 1e-9f) {
        if (std::abs(lo[a]) > half[a]) return inf;
        continue;
      }
      float ta = (-half[a] - lo[a]) / ld[a], tb = (half[a] - lo[a]) / ld[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) return inf;
    }
    return t0 > 0.f ? t0 : inf;
  }
  // Vertical cylinder: side, then the top cap.
  const float r = 0.5f * s.width;
  const float zb = s.centre.z() - 0.5f * s.height, zt = s.centre.z() + 0.5f * s.height;
  float best = inf;
  const float ox = o.x() - s.centre.x(), oy = o.y() - s.centre.y();
  const float a = d.x() * d.x() + d.y() * d.y();
  if (a > 1e-12f) {
    const float b = 2.f * (ox * d.x() + oy * d.y());
    const float c = ox * ox + oy * oy - r * r;
    const float disc = b * b - 4.f * a * c;
    if (disc >= 0.f) {
      const float t = (-b - std::sqrt(disc)) / (2.f * a);
      const float z = o.z() + t * d.z();
      if (t > 0.f && z >= zb && z <= zt) best = t;
    }
  }
  if (std::abs(d.z()) > 1e-9f) {
    const float t = (zt - o.z()) / d.z();
    const float x = ox + t * d.x(), y = oy + t * d.y();
    if (t > 0.f && x * x + y * y <= r * r) best = std::min(best, t);
  }
  return best;
}

void addVehicle(std::vector<SimShape>& shapes, int object, const Eigen::Vector2f& xy, float yaw,
                float length, float width, float body_h, float cabin_h) {
  // Body from 0.3 m (wheel clearance) up; cabin on top, set back a little.
  SimShape body;
  body.kind = SimShape::Box;
  body.length = length;
  body.width = width;
  body.height = body_h;
  body.yaw = yaw;
  body.centre = Eigen::Vector3f(xy.x(), xy.y(), 0.3f + 0.5f * body_h);
  body.object = object;
  shapes.push_back(body);
  SimShape cabin = body;
  cabin.length = 0.55f * length;
  cabin.width = 0.9f * width;
  cabin.height = cabin_h;
  const float back = -0.1f * length;
  cabin.centre = Eigen::Vector3f(xy.x() + back * std::cos(yaw), xy.y() + back * std::sin(yaw),
                                 0.3f + body_h + 0.5f * cabin_h);
  shapes.push_back(cabin);
}

void addPerson(std::vector<SimShape>& shapes, int object, const Eigen::Vector2f& xy, float height,
               float radius) {
  SimShape torso;
  torso.kind = SimShape::Cylinder;
  torso.width = 2.f * radius;
  torso.height = height - 0.25f;
  torso.centre = Eigen::Vector3f(xy.x(), xy.y(), 0.5f * torso.height);
  torso.object = object;
  shapes.push_back(torso);
  SimShape head = torso;
  head.width = 0.2f;
  head.height = 0.25f;
  head.centre.z() = torso.height + 0.125f;
  shapes.push_back(head);
}

/** Object (id 0) + optional occluder (id 1) for one frame. */
struct SimObject {
  bool vehicle = true;
  float length = 4.f, width = 1.8f, body_h = 0.9f, cabin_h = 0.5f;  // vehicle
  float height = 1.75f, radius = 0.22f;                             // person
  void add(std::vector<SimShape>& shapes, int id, const Eigen::Vector2f& xy, float yaw) const {
    if (vehicle)
      addVehicle(shapes, id, xy, yaw, length, width, body_h, cabin_h);
    else
      addPerson(shapes, id, xy, height, radius);
  }
  Eigen::Vector3f centre(const Eigen::Vector2f& xy) const {
    return Eigen::Vector3f(xy.x(), xy.y(),
                           vehicle ? 0.5f * (0.3f + body_h + cabin_h + 0.3f) : 0.5f * height);
  }
};

SimObject randomObject(std::mt19937& rng, bool vehicle) {
  std::uniform_real_distribution<float> u(0.f, 1.f);
  SimObject o;
  o.vehicle = vehicle;
  if (vehicle) {
    o.length = 3.8f + 1.2f * u(rng);
    o.width = 1.6f + 0.4f * u(rng);
    o.body_h = 0.7f + 0.5f * u(rng);
    o.cabin_h = 0.4f + 0.3f * u(rng);
  } else {
    o.height = 1.55f + 0.35f * u(rng);
    o.radius = 0.18f + 0.1f * u(rng);
  }
  return o;
}

Eigen::Matrix4f planarMotion(const Eigen::Vector3f& from, const Eigen::Vector3f& to, float yaw) {
  // x ↦ Rz(yaw)(x - from) + to
  Eigen::Affine3f a = Eigen::Translation3f(to) * Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()) *
                      Eigen::Translation3f(-from);
  return a.matrix();
}

}  // namespace

pcl::PointCloud<pcl::PointXYZ> rayCastObject(const std::vector<SimShape>& shapes, int object,
                                             const Eigen::Vector3f& sensor, float azimuth_phase,
                                             float noise_sigma, std::mt19937& rng) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.sensor_origin_ = Eigen::Vector4f(sensor.x(), sensor.y(), sensor.z(), 0.f);
  // Azimuth interval covering the object's solids.
  float az_c = 0.f, az_half = 0.f;
  {
    Eigen::Vector2f mean = Eigen::Vector2f::Zero();
    float reach = 0.f;
    int n = 0;
    for (const auto& s : shapes)
      if (s.object == object) {
        mean += s.centre.head<2>();
        ++n;
      }
    if (n == 0) return cloud;
    mean /= static_cast<float>(n);
    for (const auto& s : shapes)
      if (s.object == object)
        reach = std::max(reach,
                         (s.centre.head<2>() - mean).norm() + 0.5f * std::hypot(s.length, s.width));
    const Eigen::Vector2f rel = mean - sensor.head<2>();
    const float dist = rel.norm();
    az_c = std::atan2(rel.y(), rel.x());
    az_half = dist > reach ? std::asin(std::min(1.f, reach / dist)) + 0.01f : kPi;
  }
  const int beams = 64;
  const float el_top = 2.0f * kPi / 180.f, el_bottom = -24.9f * kPi / 180.f;
  const float az_step = 0.18f * kPi / 180.f;
  std::normal_distribution<float> noise(0.f, noise_sigma);
  const int steps = static_cast<int>(std::ceil(az_half / az_step));
  const float base = std::round(az_c / az_step) * az_step + azimuth_phase * az_step;
  for (int b = 0; b < beams; ++b) {
    const float el = el_top + (el_bottom - el_top) * b / (beams - 1);
    for (int k = -steps; k <= steps; ++k) {
      const float az = base + k * az_step;
      const Eigen::Vector3f d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      float best = d.z() < 0.f ? -sensor.z() / d.z() : std::numeric_limits<float>::infinity();
      int hit = -1;
      for (const auto& s : shapes) {
        const float t = intersect(s, sensor, d);
        if (t < best) {
          best = t;
          hit = s.object;
        }
      }
      if (hit != object || best > 120.f) continue;
      const Eigen::Vector3f p = sensor + (best + (noise_sigma > 0.f ? noise(rng) : 0.f)) * d;
      cloud.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
  }
  return cloud;
}

std::vector<RegistrationPair> makeSimulatedPairs(std::size_t count, unsigned seed,
                                                 float max_yaw_deg, int min_points) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<RegistrationPair> pairs;
  std::size_t attempts = 0;
  while (pairs.size() < count && attempts < 50 * count + 100) {
    ++attempts;
    const bool vehicle = u(rng) < 0.6f;
    const SimObject obj = randomObject(rng, vehicle);
    const float range = 10.f + 50.f * u(rng);
    const float az = (-40.f + 80.f * u(rng)) * kPi / 180.f;
    const Eigen::Vector3f sensor_a(0.f, 0.f, 1.73f);
    const Eigen::Vector3f sensor_b(1.5f * u(rng), 0.f, 1.73f);
    const Eigen::Vector2f xy_a(range * std::cos(az), range * std::sin(az));
    const float yaw_a = 2.f * kPi * u(rng);
    const float heading = vehicle ? yaw_a : 2.f * kPi * u(rng);
    const float step = 2.f * u(rng);
    const Eigen::Vector2f xy_b =
        xy_a + step * Eigen::Vector2f(std::cos(heading), std::sin(heading));
    const float dyaw = (2.f * u(rng) - 1.f) * max_yaw_deg * kPi / 180.f;
    const float yaw_b = yaw_a + dyaw;

    std::vector<SimShape> scene_a, scene_b;
    obj.add(scene_a, 0, xy_a, yaw_a);
    obj.add(scene_b, 0, xy_b, yaw_b);
    std::string label = vehicle ? "vehicle" : "person";
    if (u(rng) < 0.4f) {
      // A static occluder part way along the line of sight, laterally offset so it covers part.
      SimShape occ;
      occ.kind = u(rng) < 0.5f ? SimShape::Box : SimShape::Cylinder;
      const float frac = 0.4f + 0.4f * u(rng);
      const Eigen::Vector2f dir = xy_a.normalized();
      const Eigen::Vector2f side(-dir.y(), dir.x());
      const float lateral = (2.f * u(rng) - 1.f) * (vehicle ? 1.5f : 0.4f) * frac;
      const Eigen::Vector2f at = frac * xy_a + lateral * side;
      occ.length = occ.kind == SimShape::Box ? 0.5f + 1.5f * u(rng) : 0.4f;
      occ.width = occ.kind == SimShape::Box ? 0.5f + 1.f * u(rng) : 0.3f + 0.3f * u(rng);
      occ.height = 1.f + 1.5f * u(rng);
      occ.yaw = 2.f * kPi * u(rng);
      occ.centre = Eigen::Vector3f(at.x(), at.y(), 0.5f * occ.height);
      occ.object = 1;
      scene_a.push_back(occ);
      scene_b.push_back(occ);
      label += "+occluded";
    }
    RegistrationPair pair;
    const float phase_a = u(rng);
    pair.target = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>(
        rayCastObject(scene_a, 0, sensor_a, phase_a, 0.02f, rng));
    const float phase_b = u(rng);
    pair.source = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>(
        rayCastObject(scene_b, 0, sensor_b, phase_b, 0.02f, rng));
    if (static_cast<int>(pair.target->size()) < min_points ||
        static_cast<int>(pair.source->size()) < min_points)
      continue;
    // The occluder's returns in the same two scans, from a generator of their own so that the
    // pairs themselves stay those of earlier versions.
    std::mt19937 occ_rng(seed * 7919u + static_cast<unsigned>(pairs.size()));
    pair.target_occluders = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>(
        rayCastObject(scene_a, 1, sensor_a, phase_a, 0.02f, occ_rng));
    pair.source_occluders = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>(
        rayCastObject(scene_b, 1, sensor_b, phase_b, 0.02f, occ_rng));
    pair.reference = obj.centre(xy_b);
    pair.truth = planarMotion(obj.centre(xy_b), obj.centre(xy_a), -dyaw);
    pair.label = label;
    pair.range = range;
    pairs.push_back(pair);
  }
  return pairs;
}

std::vector<RegistrationPair> makeSimulatedDifferentPairs(std::size_t count, unsigned seed,
                                                          int min_points) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<RegistrationPair> pairs;
  std::size_t attempts = 0;
  while (pairs.size() < count && attempts < 50 * count + 100) {
    ++attempts;
    const float range = 10.f + 50.f * u(rng);
    const float az = (-40.f + 80.f * u(rng)) * kPi / 180.f;
    const Eigen::Vector3f sensor(0.f, 0.f, 1.73f);
    const Eigen::Vector2f xy(range * std::cos(az), range * std::sin(az));
    const float yaw = 2.f * kPi * u(rng);
    std::vector<SimShape> scene_a, scene_b;
    // A: a vehicle or a person.
    const bool a_vehicle = u(rng) < 0.6f;
    randomObject(rng, a_vehicle).add(scene_a, 0, xy, yaw);
    // B: something else of comparable size: a different-looking vehicle, a person, a wall, a pole
    // group or a bush-like cluster of cylinders.
    const int kind = static_cast<int>(4.f * u(rng));
    std::string label;
    if (kind == 0) {
      randomObject(rng, !a_vehicle).add(scene_b, 0, xy, yaw);
      label = a_vehicle ? "vehicle-vs-person" : "person-vs-vehicle";
    } else if (kind == 1) {
      SimShape wall;
      wall.length = a_vehicle ? 4.f + 2.f * u(rng) : 1.f + u(rng);
      wall.width = 0.3f;
      wall.height = 1.f + 1.5f * u(rng);
      wall.yaw = 2.f * kPi * u(rng);
      wall.centre = Eigen::Vector3f(xy.x(), xy.y(), 0.5f * wall.height);
      scene_b.push_back(wall);
      label = "vs-wall";
    } else if (kind == 2) {
      const int n = 2 + static_cast<int>(4.f * u(rng));
      for (int i = 0; i < n; ++i) {
        SimShape c;
        c.kind = SimShape::Cylinder;
        c.width = 0.2f + 0.6f * u(rng);
        c.height = 0.5f + 2.f * u(rng);
        const float spread = a_vehicle ? 2.f : 0.6f;
        c.centre = Eigen::Vector3f(xy.x() + spread * (2.f * u(rng) - 1.f),
                                   xy.y() + spread * (2.f * u(rng) - 1.f), 0.5f * c.height);
        scene_b.push_back(c);
      }
      label = "vs-bush";
    } else {
      // Same class, clearly different shape: short tall van vs long low car, tall vs short person.
      SimObject b = randomObject(rng, a_vehicle);
      if (a_vehicle) {
        b.length = 3.f + 3.5f * u(rng);
        b.body_h = 1.3f + 0.6f * u(rng);
        b.cabin_h = 0.1f;
      } else {
        b.height = 0.9f + 0.4f * u(rng);  // a child or a crouching person
        b.radius = 0.3f + 0.2f * u(rng);
      }
      b.add(scene_b, 0, xy, yaw + kPi * 0.5f * u(rng));
      label = a_vehicle ? "vehicle-vs-van" : "person-vs-child";
    }
    RegistrationPair pair;
    pair.source = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>(
        rayCastObject(scene_a, 0, sensor, u(rng), 0.02f, rng));
    pair.target = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>(
        rayCastObject(scene_b, 0, sensor, u(rng), 0.02f, rng));
    if (static_cast<int>(pair.target->size()) < min_points ||
        static_cast<int>(pair.source->size()) < min_points)
      continue;
    Eigen::Vector4f cs, ct;
    pcl::compute3DCentroid(*pair.source, cs);
    pcl::compute3DCentroid(*pair.target, ct);
    pair.reference = cs.head<3>();
    pair.truth = planarMotion(cs.head<3>(), ct.head<3>(), 0.f);
    pair.label = label;
    pair.range = range;
    pairs.push_back(pair);
  }
  return pairs;
}

namespace {

struct KittiObjectCloud {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud;  // world frame
  Eigen::Vector3f centre;                     // world
  float yaw = 0.f;                            // world
  float range = 0.f;
};

class KittiSequence {
 public:
  explicit KittiSequence(const std::string& folder) : folder_(folder) {
    poses_ = io::readPoses(folder + "/poses.txt");
    for (const auto& o : io::readObjects(folder + "/objects.txt")) objects_[o.frame].push_back(o);
  }
  std::size_t frames() const { return poses_.size(); }

  /** Cut of track `id` in frame f (cloud null when absent). */
  KittiObjectCloud object(int f, int id, float grow, float ground_cut) {
    KittiObjectCloud out;
    const auto it = objects_.find(f);
    if (it == objects_.end()) return out;
    const io::GroundTruthObject* box = nullptr;
    for (const auto& o : it->second)
      if (o.track_id == id) box = &o;
    if (!box) return out;
    const auto& scan = load(f);
    const Eigen::Isometry3d pose = poses_.at(static_cast<std::size_t>(f));
    const Eigen::Affine3f pose_f(pose.matrix().cast<float>());
    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    const float c = std::cos(static_cast<float>(box->yaw)),
                s = std::sin(static_cast<float>(box->yaw));
    const Eigen::Vector3f centre = box->center.cast<float>();
    const float hl = 0.5f * (static_cast<float>(box->length) + grow);
    const float hw = 0.5f * (static_cast<float>(box->width) + grow);
    const float zlo = centre.z() - 0.5f * static_cast<float>(box->height) + ground_cut;
    const float zhi = centre.z() + 0.5f * static_cast<float>(box->height) + 0.2f;
    for (const auto& p : scan) {
      if (!std::isfinite(p.x) || p.z < zlo || p.z > zhi) continue;
      const float dx = p.x - centre.x(), dy = p.y - centre.y();
      if (std::abs(c * dx + s * dy) > hl || std::abs(-s * dx + c * dy) > hw) continue;
      const Eigen::Vector3f w = pose_f * Eigen::Vector3f(p.x, p.y, p.z);
      cloud->push_back(pcl::PointXYZ(w.x(), w.y(), w.z()));
    }
    const Eigen::Vector3f origin = pose_f.translation();
    cloud->sensor_origin_ = Eigen::Vector4f(origin.x(), origin.y(), origin.z(), 0.f);
    out.cloud = cloud;
    out.centre = pose_f * centre;
    const Eigen::Vector3f heading = pose_f.linear() * Eigen::Vector3f(c, s, 0.f);
    out.yaw = std::atan2(heading.y(), heading.x());
    out.range = centre.head<2>().norm();
    return out;
  }

 private:
  const pcl::PointCloud<pcl::PointXYZ>& load(int f) {
    if (cached_frame_ != f) {
      char name[32];
      std::snprintf(name, sizeof(name), "/frames/%06d.pcd", f);
      const std::string path = folder_ + name;
      scan_.clear();
      if (pcl::io::loadPCDFile(path, scan_) < 0) throw InputError(path, 0, "cannot read scan");
      cached_frame_ = f;
    }
    return scan_;
  }

  std::string folder_;
  std::vector<Eigen::Isometry3d> poses_;
  std::map<int, std::vector<io::GroundTruthObject>> objects_;
  pcl::PointCloud<pcl::PointXYZ> scan_;
  int cached_frame_ = -1;
};

}  // namespace

std::vector<RegistrationPair> loadKittiPairs(const std::string& folder,
                                             const std::vector<int>& track_ids,
                                             const std::vector<int>& gaps, int stride, float grow,
                                             float ground_cut, int min_points) {
  KittiSequence seq(folder);
  std::vector<RegistrationPair> pairs;
  const int frames = static_cast<int>(seq.frames());
  // Cache cuts per (frame, track) so scans are read once each.
  std::map<std::pair<int, int>, KittiObjectCloud> cuts;
  auto cut = [&](int f, int id) -> const KittiObjectCloud& {
    const auto key = std::make_pair(f, id);
    auto it = cuts.find(key);
    if (it == cuts.end()) it = cuts.emplace(key, seq.object(f, id, grow, ground_cut)).first;
    return it->second;
  };
  for (int f = 0; f < frames; f += std::max(1, stride))
    for (int id : track_ids)
      for (int gap : gaps) {
        const int g = f + gap;
        if (g >= frames) continue;
        const KittiObjectCloud& a = cut(f, id);
        const KittiObjectCloud& b = cut(g, id);
        if (!a.cloud || !b.cloud || static_cast<int>(a.cloud->size()) < min_points ||
            static_cast<int>(b.cloud->size()) < min_points)
          continue;
        RegistrationPair pair;
        pair.target = a.cloud;
        pair.source = b.cloud;
        pair.reference = b.centre;
        pair.truth = planarMotion(b.centre, a.centre, wrapAngle(a.yaw - b.yaw));
        pair.label = "track " + std::to_string(id) + " gap " + std::to_string(gap);
        pair.range = a.range;
        pairs.push_back(pair);
      }
  return pairs;
}

std::vector<RegistrationPair> loadKittiDifferentPairs(const std::string& folder,
                                                      const std::vector<int>& track_ids, int gap,
                                                      int stride, float grow, float ground_cut,
                                                      int min_points) {
  KittiSequence seq(folder);
  std::vector<RegistrationPair> pairs;
  const int frames = static_cast<int>(seq.frames());
  for (int f = 0; f + gap < frames; f += std::max(1, stride)) {
    std::vector<KittiObjectCloud> now, later;
    for (int id : track_ids) now.push_back(seq.object(f, id, grow, ground_cut));
    for (int id : track_ids) later.push_back(seq.object(f + gap, id, grow, ground_cut));
    for (std::size_t i = 0; i < track_ids.size(); ++i)
      for (std::size_t j = 0; j < track_ids.size(); ++j) {
        if (i == j) continue;
        const auto& a = now[i];
        const auto& b = later[j];
        if (!a.cloud || !b.cloud || static_cast<int>(a.cloud->size()) < min_points ||
            static_cast<int>(b.cloud->size()) < min_points)
          continue;
        Eigen::Vector4f ca, cb;
        pcl::compute3DCentroid(*a.cloud, ca);
        pcl::compute3DCentroid(*b.cloud, cb);
        RegistrationPair pair;
        pair.source = a.cloud;
        // B moved onto A's position (keeping its own sensor geometry for the σ of its points).
        auto moved = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
        const Eigen::Vector3f shift = (ca - cb).head<3>();
        const Eigen::Affine3f t = Eigen::Affine3f(Eigen::Translation3f(shift));
        pcl::transformPointCloud(*b.cloud, *moved, t);
        moved->sensor_origin_ =
            b.cloud->sensor_origin_ + Eigen::Vector4f(shift.x(), shift.y(), shift.z(), 0.f);
        pair.target = moved;
        pair.reference = ca.head<3>();
        pair.truth = Eigen::Matrix4f::Identity();
        pair.label =
            "track " + std::to_string(track_ids[i]) + " vs " + std::to_string(track_ids[j]);
        pair.range = a.range;
        pairs.push_back(pair);
      }
  }
  return pairs;
}

float translationError(const Eigen::Matrix4f& estimate, const RegistrationPair& pair) {
  const Eigen::Vector4f r(pair.reference.x(), pair.reference.y(), pair.reference.z(), 1.f);
  return ((estimate * r) - (pair.truth * r)).head<3>().norm();
}

float yawError(const Eigen::Matrix4f& estimate, const RegistrationPair& pair) {
  const float ye = std::atan2(estimate(1, 0), estimate(0, 0));
  const float yt = std::atan2(pair.truth(1, 0), pair.truth(0, 0));
  return std::abs(wrapAngle(ye - yt));
}

Eigen::Matrix4f perturbedGuess(const RegistrationPair& pair, float offset, float angle) {
  const Eigen::Vector4f r(pair.reference.x(), pair.reference.y(), pair.reference.z(), 1.f);
  const Eigen::Vector3f target =
      (pair.truth * r).head<3>() + offset * Eigen::Vector3f(std::cos(angle), std::sin(angle), 0.f);
  Eigen::Matrix4f g = Eigen::Matrix4f::Identity();
  g.block<3, 1>(0, 3) = target - pair.reference;
  return g;
}

double rocAuc(const std::vector<float>& positives, const std::vector<float>& negatives) {
  if (positives.empty() || negatives.empty()) return 0.0;
  double wins = 0.0;
  for (float p : positives)
    for (float n : negatives) wins += p > n ? 1.0 : (p == n ? 0.5 : 0.0);
  return wins / (static_cast<double>(positives.size()) * negatives.size());
}

}  // namespace eval
}  // namespace pcl_movers
