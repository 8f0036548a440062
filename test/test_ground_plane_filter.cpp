/*
 * Tests of pcl_movers::GroundPlaneFilter on synthetic terrain with known answers (flat, ramp,
 * rolling hills, kerb, boxes and walls on top) and, when present, on a labelled KITTI scan.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/segmentation_metrics.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <random>
#include <set>

using pcl_movers::GroundPlaneFilter;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace {

constexpr float kSensorHeight = 1.73f;

/** A synthetic scan: ground points on a polar pattern like a spinning LiDAR's (denser near),
 * plus object points, each flagged with its truth. */
struct Scene {
  Cloud::Ptr cloud{new Cloud};
  std::vector<int> is_ground;  ///< 1 ground, 0 object, -1 not scored

  void add(float x, float y, float z, int ground) {
    cloud->push_back(pcl::PointXYZ(x, y, z));
    is_ground.push_back(ground);
  }
};

/** Ground z(x, y) sampled on rings 3..70 m (spacing growing with range) at 0.5° azimuth steps,
 * with a little noise. */
Scene makeGround(const std::function<float(float, float)>& z_of, unsigned seed = 1) {
  Scene scene;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, 0.02f);
  for (float r = 3.f; r < 70.f; r *= 1.04f)
    for (float az = -180.f; az < 180.f; az += 0.5f) {
      const float x = r * std::cos(az * float(M_PI) / 180.f);
      const float y = r * std::sin(az * float(M_PI) / 180.f);
      scene.add(x, y, z_of(x, y) + noise(rng), 1);
    }
  return scene;
}

/** A box's vertical faces from `bottom` to `bottom + height` above the terrain. */
void addBox(Scene& scene, const std::function<float(float, float)>& z_of, float cx, float cy,
            float length, float width, float height) {
  const float step = 0.1f;
  const float base = z_of(cx, cy);
  for (float h = 0.f; h <= height; h += step)
    for (float t = -0.5f; t <= 0.5f; t += step / std::max(length, width)) {
      const float z = base + h;
      // The lowest 30 cm of an object cannot be told from ground by height alone (it is
      // within the classification threshold): not scored. Everything above must be non-ground.
      const int ground = h < 0.3f ? -1 : 0;
      scene.add(cx + t * length, cy - width / 2, z, ground);
      scene.add(cx + t * length, cy + width / 2, z, ground);
      scene.add(cx - length / 2, cy + t * width, z, ground);
      scene.add(cx + length / 2, cy + t * width, z, ground);
    }
}

struct Score {
  double precision = 0, recall = 0;
  std::size_t object_points_as_ground_high = 0;  ///< object points > 0.3 m up called ground
};

/** Precision/recall of the filter's ground output against the scene's truth. */
Score score(const Scene& scene, const pcl::Indices& ground) {
  std::vector<bool> called(scene.cloud->size(), false);
  for (const auto i : ground) called[i] = true;
  std::size_t tp = 0, fp = 0, fn = 0;
  for (std::size_t i = 0; i < called.size(); ++i) {
    if (scene.is_ground[i] < 0) continue;
    if (called[i] && scene.is_ground[i]) ++tp;
    if (called[i] && !scene.is_ground[i]) ++fp;
    if (!called[i] && scene.is_ground[i]) ++fn;
  }
  Score s;
  s.precision = tp + fp ? double(tp) / double(tp + fp) : 0.0;
  s.recall = tp + fn ? double(tp) / double(tp + fn) : 0.0;
  return s;
}

pcl::Indices groundOf(const Cloud::Ptr& cloud) {
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(cloud);
  filter.setNegative(true);  // ground
  pcl::Indices ground;
  filter.filter(ground);
  return ground;
}

void expectGoodSeparation(const std::function<float(float, float)>& z_of, const char* name) {
  Scene scene = makeGround(z_of);
  addBox(scene, z_of, 12.f, 4.f, 4.5f, 1.8f, 1.5f);    // car
  addBox(scene, z_of, -8.f, -6.f, 0.6f, 0.6f, 1.8f);   // person
  addBox(scene, z_of, 30.f, -10.f, 4.5f, 1.8f, 1.5f);  // far car
  addBox(scene, z_of, 5.f, 20.f, 20.f, 0.3f, 3.f);     // wall
  const Score s = score(scene, groundOf(scene.cloud));
  EXPECT_GT(s.precision, 0.97) << name;
  EXPECT_GT(s.recall, 0.97) << name;
}

/** An organized scan (rows = 64 beams from +2° down to -24.9°, like an HDL-64E; `columns` azimuth
 * steps over 360°) ray-cast onto the surface z = terrain(x, y) + object(x, y), with Gaussian
 * range noise. A cell's truth is ground when object(x, y) is 0 where its ray hits. */
Scene castOrganized(const std::function<float(float, float)>& terrain,
                    const std::function<float(float, float)>& object, int columns = 1024,
                    float range_noise = 0.01f, unsigned seed = 3) {
  Scene scene;
  const int rows = 64;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, range_noise);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto above = [&](const Eigen::Vector3f& p) {
    return p.z() > terrain(p.x(), p.y()) + object(p.x(), p.y());
  };
  for (int row = 0; row < rows; ++row) {
    const float elevation = (2.f - 26.9f * float(row) / float(rows - 1)) * float(M_PI) / 180.f;
    for (int col = 0; col < columns; ++col) {
      const float azimuth = 2.f * float(M_PI) * float(col) / float(columns) - float(M_PI);
      const Eigen::Vector3f d(std::cos(elevation) * std::cos(azimuth),
                              std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      // March in 4 cm steps (finer than the rough surfaces below), then bisect to 1 mm.
      float t0 = 0.5f, t1 = -1.f;
      for (float t = 0.5f; t < 80.f; t += 0.04f) {
        if (!above(t * d)) {
          t1 = t;
          break;
        }
        t0 = t;
      }
      if (t1 < 0.f) {
        scene.add(nan, nan, nan, -1);
        continue;
      }
      while (t1 - t0 > 0.001f) {
        const float tm = 0.5f * (t0 + t1);
        (above(tm * d) ? t0 : t1) = tm;
      }
      const Eigen::Vector3f hit = t1 * d;
      const Eigen::Vector3f p = (t1 + noise(rng)) * d;
      scene.add(p.x(), p.y(), p.z(), object(hit.x(), hit.y()) > 0.f ? 0 : 1);
    }
  }
  scene.cloud->width = columns;
  scene.cloud->height = rows;
  scene.cloud->is_dense = false;
  return scene;
}

/** Ground and object points called ground by a filter configured by `setup`. */
struct Counts {
  std::size_t ground = 0, ground_kept = 0, object = 0, object_as_ground = 0;
};
Counts countGround(const Scene& scene, bool slope_check) {
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(scene.cloud);
  filter.setNegative(true);
  filter.setLocalSlopeCheck(slope_check);
  pcl::Indices ground;
  filter.filter(ground);
  std::vector<bool> called(scene.cloud->size(), false);
  for (const auto i : ground) called[i] = true;
  Counts c;
  for (std::size_t i = 0; i < called.size(); ++i) {
    if (scene.is_ground[i] == 1) {
      ++c.ground;
      c.ground_kept += called[i];
    } else if (scene.is_ground[i] == 0) {
      ++c.object;
      c.object_as_ground += called[i];
    }
  }
  return c;
}

/** A low bush: a patch whose height jumps between 0 and 0.25 m every 10 cm (rough, like grass
 * tufts and shrubs), 0 outside the patch. */
float bush(float x, float y, float x0, float x1, float y0, float y1) {
  if (x < x0 || x > x1 || y < y0 || y > y1) return 0.f;
  const auto ix = static_cast<std::uint32_t>(std::floor(x * 10.f) + 10000.f);
  const auto iy = static_cast<std::uint32_t>(std::floor(y * 10.f) + 10000.f);
  std::uint32_t h = ix * 73856093u ^ iy * 19349663u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return 0.25f * static_cast<float>(h % 1000u) / 999.f + 1e-3f;
}

}  // namespace

TEST(GroundPlaneFilter, FlatGroundWithObjects) {
  expectGoodSeparation([](float, float) { return -kSensorHeight; }, "flat");
}

TEST(GroundPlaneFilter, RampAheadOfTheVehicle) {
  // Flat to 10 m, then an 8 % ramp up: 4.8 m higher at 70 m, far above any global plane's
  // threshold.
  expectGoodSeparation(
      [](float x, float) { return -kSensorHeight + (x > 10.f ? 0.08f * (x - 10.f) : 0.f); },
      "ramp");
}

TEST(GroundPlaneFilter, RollingTerrain) {
  expectGoodSeparation(
      [](float x, float y) {
        return -kSensorHeight + 1.2f * std::sin(x / 14.f) * std::cos(y / 17.f) +
               0.4f * std::sin((x + y) / 9.f) * (std::hypot(x, y) / 70.f);
      },
      "rolling");
}

TEST(GroundPlaneFilter, KerbAndSidewalkAreGround) {
  // Road, a 15 cm kerb at y = 5 m, sidewalk beyond: both sides are ground.
  expectGoodSeparation([](float, float y) { return -kSensorHeight + (y > 5.f ? 0.15f : 0.f); },
                       "kerb");
}

TEST(GroundPlaneFilter, AGlobalThresholdFailsOnTheRamp) {
  // Sanity check of the test itself: on the ramp a fixed height threshold loses the far ground,
  // so the local planes above are what makes RampAheadOfTheVehicle pass.
  auto z_of = [](float x, float) { return -kSensorHeight + (x > 10.f ? 0.08f * (x - 10.f) : 0.f); };
  Scene scene = makeGround(z_of);
  pcl::Indices ground;
  for (std::size_t i = 0; i < scene.cloud->size(); ++i)
    if ((*scene.cloud)[i].z < -kSensorHeight + 0.25f) ground.push_back(static_cast<int>(i));
  EXPECT_LT(score(scene, ground).recall, 0.9);
}

TEST(GroundPlaneFilter, CellPlanesFitATiltedRoadThroughClutter) {
  // A 4 % road slope (2.3°, within the tilt limit) where a third of the points are clutter 0.3 to
  // 0.5 m above the road (within the 0.5 m step band, so they are plane candidates): a plain
  // least-squares plane would sit ~0.13 m above the road and call it non-ground; the RANSAC must
  // ignore the clutter, so the road stays ground and every fitted plane has the road's slope
  // (within 3°: 2 cm noise on the smallest cells).
  auto z_of = [](float x, float) { return -kSensorHeight + 0.04f * x; };
  Scene scene = makeGround(z_of, 5);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> lift(0.3f, 0.5f);
  std::bernoulli_distribution clutter(0.33);
  for (std::size_t i = 0; i < scene.cloud->size(); ++i)
    if (clutter(rng)) {
      (*scene.cloud)[i].z += lift(rng);
      scene.is_ground[i] = 0;
    }
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(scene.cloud);
  filter.setNegative(true);
  pcl::Indices ground;
  filter.filter(ground);
  const Score s = score(scene, ground);
  EXPECT_GT(s.precision, 0.99);
  EXPECT_GT(s.recall, 0.98);
  const Eigen::Vector3f road = Eigen::Vector3f(-0.04f, 0.f, 1.f).normalized();
  int fitted = 0;
  for (std::size_t c = 0; c < filter.getCellPlanes().size(); ++c) {
    if (!filter.getCellFitted()[c]) continue;
    ++fitted;
    EXPECT_GT(filter.getCellPlanes()[c].normal.dot(road), std::cos(3.f * float(M_PI) / 180.f))
        << "cell " << c;
  }
  EXPECT_GT(fitted, static_cast<int>(filter.getCellPlanes().size()) / 2);
}

// ------------------------------------------------------------- local-slope test (organized)

TEST(GroundPlaneFilter, RoughLowBushIsNotGround) {
  // Flat road with a low rough bush 6-9 m ahead: the lower part of the bush is within the plane
  // distance threshold, so the plane test alone calls much of it ground; the column slope test
  // must reject it while the road (with 1 cm range noise) stays ground.
  const auto terrain = [](float, float) { return -kSensorHeight; };
  const auto object = [](float x, float y) { return bush(x, y, 6.f, 9.f, -2.f, 2.f); };
  const Scene scene = castOrganized(terrain, object);
  const Counts plain = countGround(scene, false);
  const Counts checked = countGround(scene, true);
  ASSERT_GT(checked.object, 500u);
  // The case is meaningful: the bush fills whole cells, their planes settle on it, and without
  // the slope test most of the bush is "ground".
  EXPECT_GT(plain.object_as_ground, checked.object / 2);
  // Rises of a few centimetres between tufts 20 cm apart are not steep, so not every bush point
  // is caught; the test must still remove well over half of what the plane test let through.
  EXPECT_LT(checked.object_as_ground, plain.object_as_ground / 2);
  EXPECT_GT(double(checked.ground_kept) / double(checked.ground), 0.97);
}

TEST(GroundPlaneFilter, WallBaseIsNotGroundRoadAtItsFootIs) {
  // A wall 12 m ahead: its lowest 10 cm are within the distance threshold but rise vertically.
  const auto terrain = [](float, float) { return -kSensorHeight; };
  const auto object = [](float x, float y) {
    return x > 12.f && x < 12.3f && std::abs(y) < 6.f ? 3.f : 0.f;
  };
  const Scene scene = castOrganized(terrain, object);
  Counts plain = countGround(scene, false), checked = countGround(scene, true);
  // Count only the wall's points low enough to pass the distance test.
  std::size_t low = 0, low_as_ground = 0;
  {
    GroundPlaneFilter<pcl::PointXYZ> filter;
    filter.setInputCloud(scene.cloud);
    filter.setNegative(true);
    pcl::Indices ground;
    filter.filter(ground);
    std::vector<bool> called(scene.cloud->size(), false);
    for (const auto i : ground) called[i] = true;
    for (std::size_t i = 0; i < called.size(); ++i)
      if (scene.is_ground[i] == 0 && (*scene.cloud)[i].z < -kSensorHeight + 0.1f) {
        ++low;
        low_as_ground += called[i];
      }
  }
  ASSERT_GT(low, 20u);
  EXPECT_LT(low_as_ground, low / 5);
  EXPECT_LE(checked.object_as_ground, plain.object_as_ground);
  EXPECT_GT(double(checked.ground_kept) / double(checked.ground), 0.97);
}

TEST(GroundPlaneFilter, OrganizedKerbStaysGround) {
  // A 12 cm kerb 4 m to the left: road and sidewalk are ground; at most the beams hitting the
  // kerb face are lost to the slope test.
  const auto terrain = [](float, float y) { return -kSensorHeight + (y > 4.f ? 0.12f : 0.f); };
  const auto object = [](float, float) { return 0.f; };
  const Scene scene = castOrganized(terrain, object);
  const Counts c = countGround(scene, true);
  EXPECT_GT(double(c.ground_kept) / double(c.ground), 0.97);
}

TEST(GroundPlaneFilter, OrganizedSmoothSlopesStayGround) {
  // An 8° ramp ahead and rolling terrain elsewhere: smooth rises are not steep.
  const auto terrain = [](float x, float y) {
    return -kSensorHeight + (x > 8.f ? 0.14f * (x - 8.f) : 0.f) +
           0.8f * std::sin(y / 9.f) * std::cos(x / 13.f) * std::min(1.f, std::hypot(x, y) / 20.f);
  };
  const auto object = [](float, float) { return 0.f; };
  const Scene scene = castOrganized(terrain, object);
  const Counts plain = countGround(scene, false), checked = countGround(scene, true);
  EXPECT_GT(double(checked.ground_kept) / double(checked.ground), 0.97);
  // The slope test costs (almost) nothing on smooth terrain.
  EXPECT_GT(double(checked.ground_kept), 0.99 * double(plain.ground_kept));
}

TEST(GroundPlaneFilter, IsolatedNoiseSpikeStaysGround) {
  // One point of flat road 6 cm too high (an outlier within the distance threshold) makes a
  // steep rise to its column neighbours, but no row neighbour is rough: it stays ground. A
  // 0.6 m wide strip raised the same way is rough over many columns and is rejected.
  const auto terrain = [](float, float) { return -kSensorHeight; };
  const auto none = [](float, float) { return 0.f; };
  Scene scene = castOrganized(terrain, none, 1024, 0.f);
  const int width = static_cast<int>(scene.cloud->width);
  const int spike = 56 * width + 512;  // a low beam straight behind, a few metres out
  ASSERT_TRUE(std::isfinite((*scene.cloud)[spike].z));
  (*scene.cloud)[spike].z += 0.06f;
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(scene.cloud);
  filter.setNegative(true);
  pcl::Indices ground;
  filter.filter(ground);
  EXPECT_TRUE(std::find(ground.begin(), ground.end(), spike) != ground.end());
  for (int c = 0; c < 12; ++c) (*scene.cloud)[56 * width + 200 + c].z += 0.06f;
  filter.filter(ground);
  int strip_ground = 0;
  for (int c = 0; c < 12; ++c)
    strip_ground += std::find(ground.begin(), ground.end(), 56 * width + 200 + c) != ground.end();
  EXPECT_LT(strip_ground, 3);
}

TEST(GroundPlaneFilter, LocalSlopeNeedsAnOrganizedCloud) {
  // The same scan flattened to one row has no beam neighbours: the slope test cannot run and
  // the result equals the plane test alone.
  const auto terrain = [](float, float) { return -kSensorHeight; };
  const auto object = [](float x, float y) { return bush(x, y, 6.f, 9.f, -2.f, 2.f); };
  Scene scene = castOrganized(terrain, object);
  const Counts plain = countGround(scene, false);
  scene.cloud->width = static_cast<std::uint32_t>(scene.cloud->size());
  scene.cloud->height = 1;
  const Counts flat = countGround(scene, true);
  EXPECT_EQ(flat.object_as_ground, plain.object_as_ground);
  EXPECT_EQ(flat.ground_kept, plain.ground_kept);
}

TEST(GroundPlaneFilter, NegativeAndDefaultAreComplementary) {
  auto z_of = [](float, float) { return -kSensorHeight; };
  Scene scene = makeGround(z_of);
  addBox(scene, z_of, 10.f, 0.f, 4.f, 2.f, 1.5f);
  scene.add(std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f, 0);

  GroundPlaneFilter<pcl::PointXYZ> filter(true);
  filter.setInputCloud(scene.cloud);
  pcl::Indices non_ground, ground;
  filter.filter(non_ground);
  const pcl::Indices removed_non_ground = *filter.getRemovedIndices();
  filter.setNegative(true);
  filter.filter(ground);

  std::set<int> all(non_ground.begin(), non_ground.end());
  for (const auto i : ground) EXPECT_TRUE(all.insert(i).second) << "point " << i << " in both";
  // Every finite point is in exactly one output; the NaN point in neither.
  EXPECT_EQ(all.size(), scene.cloud->size() - 1);
  EXPECT_EQ(all.count(static_cast<int>(scene.cloud->size() - 1)), 0u);
  // The removed indices of the default mode are the ground plus the NaN point.
  EXPECT_EQ(removed_non_ground.size(), ground.size() + 1);
  EXPECT_FALSE(non_ground.empty());
  EXPECT_GT(ground.size(), non_ground.size());
  // Output order follows input order.
  EXPECT_TRUE(std::is_sorted(non_ground.begin(), non_ground.end()));
}

TEST(GroundPlaneFilter, KeepOrganizedKeepsLayout) {
  // An organized 10 x N cloud: ground rows and object rows.
  auto z_of = [](float, float) { return -kSensorHeight; };
  Scene scene = makeGround(z_of);
  const std::size_t width = 100;
  scene.cloud->resize(width * 10);
  scene.cloud->width = static_cast<std::uint32_t>(width);
  scene.cloud->height = 10;
  for (std::size_t c = 0; c < width; ++c)  // the first row: a wall 1 m up at 8 m
    (*scene.cloud)[c] = pcl::PointXYZ(8.f, -5.f + 0.1f * float(c), -0.7f);

  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(scene.cloud);
  filter.setKeepOrganized(true);
  Cloud out;
  filter.filter(out);
  ASSERT_EQ(out.size(), scene.cloud->size());
  EXPECT_EQ(out.width, scene.cloud->width);
  EXPECT_EQ(out.height, scene.cloud->height);
  EXPECT_FALSE(out.is_dense);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < out.size(); ++i)
    if (std::isfinite(out[i].x)) {
      ++kept;
      EXPECT_LT(i, width) << "a ground point survived";
      EXPECT_EQ(out[i].z, (*scene.cloud)[i].z);
    }
  EXPECT_GT(kept, width * 9 / 10);
}

TEST(GroundPlaneFilter, FollowsTheSensorOrigin) {
  // The same scene shifted by (50, -20, 7) with sensor_origin_ set accordingly classifies alike.
  auto z_of = [](float x, float) { return -kSensorHeight + (x > 10.f ? 0.08f * (x - 10.f) : 0.f); };
  Scene scene = makeGround(z_of);
  addBox(scene, z_of, 12.f, 4.f, 4.5f, 1.8f, 1.5f);
  const Score reference = score(scene, groundOf(scene.cloud));
  const Eigen::Vector3f shift(50.f, -20.f, 7.f);
  for (auto& p : *scene.cloud) p.getVector3fMap() += shift;
  scene.cloud->sensor_origin_ = Eigen::Vector4f(shift.x(), shift.y(), shift.z(), 0.f);
  const Score shifted = score(scene, groundOf(scene.cloud));
  EXPECT_GT(shifted.recall, 0.97);
  EXPECT_NEAR(shifted.precision, reference.precision, 0.01);
  EXPECT_NEAR(shifted.recall, reference.recall, 0.01);
}

TEST(GroundPlaneFilter, Deterministic) {
  auto z_of = [](float x, float y) {
    return -kSensorHeight + 0.5f * std::sin(x / 10.f + y / 13.f);
  };
  Scene scene = makeGround(z_of, 7);
  addBox(scene, z_of, 10.f, 0.f, 4.f, 2.f, 1.5f);
  EXPECT_EQ(groundOf(scene.cloud), groundOf(scene.cloud));
}

TEST(GroundPlaneFilter, ReusedFilterMatchesAFreshOne) {
  // The filter keeps work buffers between calls and its RANSAC must restart from the same seed
  // every call: one instance run over frames of different sizes and layouts must give exactly
  // what a fresh instance gives on each frame.
  auto rolling = [](float x, float y) {
    return -kSensorHeight + 0.5f * std::sin(x / 10.f + y / 13.f);
  };
  Scene unorganized = makeGround(rolling, 11);
  addBox(unorganized, rolling, 10.f, 0.f, 4.f, 2.f, 1.5f);
  addBox(unorganized, rolling, -6.f, 8.f, 2.f, 2.f, 1.0f);
  const auto kerb = [](float, float y) { return -kSensorHeight + (y > 4.f ? 0.12f : 0.f); };
  const auto car = [](float x, float y) {
    return std::abs(x - 12.f) < 2.f && std::abs(y + 3.f) < 1.f ? 1.4f : 0.f;
  };
  const Scene organized = castOrganized(kerb, car);
  ASSERT_GT(organized.cloud->height, 1u);
  const std::vector<Cloud::Ptr> frames{unorganized.cloud, organized.cloud, unorganized.cloud,
                                       organized.cloud};
  GroundPlaneFilter<pcl::PointXYZ> reused;
  reused.setNegative(true);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    pcl::Indices ground;
    reused.setInputCloud(frames[f]);
    reused.filter(ground);
    const pcl::Indices fresh = groundOf(frames[f]);
    EXPECT_GT(fresh.size(), frames[f]->size() / 2) << "frame " << f;
    EXPECT_EQ(ground, fresh) << "frame " << f;
  }
}

TEST(GroundPlaneFilter, IndicesActLikeRemovedPoints) {
  // Points left out by setIndices() must be absent for every part of the filter, the local-slope
  // test's column neighbours included: the ground found with indices equals the ground of the
  // same cloud with the left-out cells set to NaN. Every fourth row band is left out, so many
  // slope tests lose a neighbour; a bush makes the slope test reject points.
  const auto terrain = [](float, float) { return -kSensorHeight; };
  const auto object = [](float x, float y) { return bush(x, y, 6.f, 9.f, -2.f, 2.f); };
  const Scene scene = castOrganized(terrain, object);
  const Cloud& cloud = *scene.cloud;
  pcl::IndicesPtr kept(new pcl::Indices);
  Cloud::Ptr masked(new Cloud(cloud));
  for (std::uint32_t row = 0; row < cloud.height; ++row)
    for (std::uint32_t col = 0; col < cloud.width; ++col) {
      const int idx = static_cast<int>(row * cloud.width + col);
      if (row % 4 == 1)
        (*masked)[idx].x = (*masked)[idx].y = (*masked)[idx].z =
            std::numeric_limits<float>::quiet_NaN();
      else
        kept->push_back(idx);
    }
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setNegative(true);
  filter.setInputCloud(scene.cloud);
  filter.setIndices(kept);
  pcl::Indices with_indices;
  filter.filter(with_indices);
  const pcl::Indices expected = groundOf(masked);
  EXPECT_GT(expected.size(), kept->size() / 2);
  EXPECT_EQ(with_indices, expected);
  // The slope test is active on this input (it rejects bush points the plane test keeps).
  GroundPlaneFilter<pcl::PointXYZ> plane_only;
  plane_only.setNegative(true);
  plane_only.setLocalSlopeCheck(false);
  plane_only.setInputCloud(masked);
  pcl::Indices plane_ground;
  plane_only.filter(plane_ground);
  EXPECT_GT(plane_ground.size(), expected.size() + 100);
}

TEST(GroundPlaneFilter, EmptyAndNanOnlyInputs) {
  GroundPlaneFilter<pcl::PointXYZ> filter(true);
  Cloud::Ptr empty(new Cloud);
  filter.setInputCloud(empty);
  pcl::Indices out{1, 2, 3};
  filter.filter(out);
  EXPECT_TRUE(out.empty());

  Cloud::Ptr nans(new Cloud);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < 50; ++i) nans->push_back(pcl::PointXYZ(nan, nan, nan));
  nans->is_dense = false;
  filter.setInputCloud(nans);
  filter.filter(out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(filter.getRemovedIndices()->size(), 50u);
  filter.setNegative(true);
  filter.filter(out);
  EXPECT_TRUE(out.empty());
}

TEST(GroundPlaneFilter, InvalidParametersGiveNoOutput) {
  auto z_of = [](float, float) { return -kSensorHeight; };
  Scene scene = makeGround(z_of);
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(scene.cloud);
  filter.setRingEdges({5.f, 3.f});
  pcl::Indices out;
  filter.filter(out);
  EXPECT_TRUE(out.empty());
}

TEST(GroundPlaneFilter, KittiSemanticLabels) {
  const std::string dir = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-odometry-00";
  if (!std::filesystem::exists(dir + "/labels/000000.label"))
    GTEST_SKIP() << "KITTI odometry data not found in " << dir;
  pcl::PointCloud<pcl::PointXYZI>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZI>);
  pcl_movers::io::readScan(dir + "/velodyne/000000.bin", *cloud);
  const auto labels = pcl_movers::io::readLabels(dir + "/labels/000000.label");
  ASSERT_EQ(labels.size(), cloud->size());

  GroundPlaneFilter<pcl::PointXYZI> filter;
  filter.setInputCloud(cloud);
  filter.setNegative(true);
  pcl::Indices ground;
  filter.filter(ground);
  std::vector<std::uint8_t> called(cloud->size(), 0);
  for (const auto i : ground) called[i] = 1;
  const auto score =
      pcl_movers::eval::scoreGround(pcl_movers::eval::groundTruthFromLabels(labels), called);
  const double precision = score.precision(), recall = score.recall();
  // Generous bounds (pcl_movers_eval_segmentation prints the exact numbers). Much of the
  // remaining false ground is SemanticKITTI "vegetation" lying at ground level.
  EXPECT_GT(precision, 0.85);
  EXPECT_GT(recall, 0.95);
}

namespace {
/** Scan lines of a spinning LiDAR (one per beam, `beams` in degrees below the horizon, samples
 * every 0.18° of azimuth out to 80 m) on terrain z(x, y), which stays within `amplitude` of
 * -kSensorHeight, with objects of height object(x, y) on it no nearer than `objects_from`. Truth:
 * ground points at least `scored_from` away (horizontally) are scored as ground; object points more
 * than 0.3 m up as not ground; the rest is not scored. */
Scene castLines(const std::function<float(float, float)>& z_of,
                const std::function<float(float, float)>& object, float objects_from,
                float amplitude, const std::vector<float>& beams, float scored_from,
                unsigned seed) {
  Scene scene;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, 0.02f);
  for (const float beam : beams) {
    const float el = -beam * float(M_PI) / 180.f;
    const float s = std::sin(-el);
    // The beam is above the terrain before t_lo (objects stand beyond `objects_from`) and below
    // it after t_hi.
    const float t_lo = std::max(1.f, std::min((kSensorHeight - amplitude) / s, objects_from));
    const float t_hi = std::min(85.f, (kSensorHeight + amplitude) / s);
    for (float az = -180.f; az < 180.f; az += 0.18f) {
      const float a = az * float(M_PI) / 180.f;
      const Eigen::Vector3f d(std::cos(el) * std::cos(a), std::cos(el) * std::sin(a), -s);
      auto below = [&](float t) {
        const Eigen::Vector3f q = t * d;
        return q.z() < z_of(q.x(), q.y()) + object(q.x(), q.y());
      };
      float t0 = t_lo, t1 = -1.f;
      for (float t = t_lo; t <= t_hi; t += 0.1f) {
        if (below(t)) {
          t1 = t;
          break;
        }
        t0 = t;
      }
      if (t1 < 0.f) continue;
      for (int k = 0; k < 8; ++k) {
        const float tm = 0.5f * (t0 + t1);
        (below(tm) ? t1 : t0) = tm;
      }
      const Eigen::Vector3f hit = t1 * d;
      const Eigen::Vector3f p = (t1 + noise(rng)) * d;
      const float r = std::hypot(p.x(), p.y());
      if (r > 80.f) continue;
      const float up = hit.z() - z_of(hit.x(), hit.y());
      int truth = -1;
      if (object(hit.x(), hit.y()) > 0.f)
        truth = up > 0.3f ? 0 : -1;
      else if (r >= scored_from)
        truth = 1;
      scene.add(p.x(), p.y(), p.z(), truth);
    }
  }
  return scene;
}
}  // namespace

TEST(GroundPlaneFilter, CurvedFarCellsKeepAPlaneThatLoweringWouldRaise) {
  // Rolling terrain (hills 50 m apart) seen by HDL-64E-like beams, with cars at 70-79 m all
  // around: the cells beyond 57 m are 11-14 m deep and hold two or three scan lines. A plane
  // leaving points below it is refitted to those points, and on curved ground that refit often
  // rises elsewhere; keeping the earlier plane there (getCurvedCellDepth()) must find more of
  // the far ground, and call no more of the cars ground, than refitting in every cell.
  std::vector<float> beams;
  for (float b = 24.9f; b > 1.2f; b -= (b > 8.f ? 0.5f : 0.35f)) beams.push_back(b);
  struct Car {
    float x, y, c, s;  // centre, heading cosine and sine
  };
  std::vector<Car> parked;
  for (int k = 0; k < 24; ++k) {
    const float a = float(k) * 15.f * float(M_PI) / 180.f, r = 70.f + float(k % 4) * 3.f;
    parked.push_back({r * std::cos(a), r * std::sin(a), std::cos(a + 1.2f), std::sin(a + 1.2f)});
  }
  auto cars = [&parked](float x, float y) {
    if (x * x + y * y < 66.f * 66.f) return 0.f;
    for (const Car& car : parked) {
      const float u = (x - car.x) * car.c + (y - car.y) * car.s;
      const float v = -(x - car.x) * car.s + (y - car.y) * car.c;
      if (std::abs(u) < 2.2f && std::abs(v) < 0.9f) return 1.5f;
    }
    return 0.f;
  };
  int improved = 0, worse = 0, scenes = 0;
  double precision_change = 0;
  for (const float amplitude : {0.3f, 0.6f, 0.9f})
    for (const float phase : {0.f, 1.f, 2.f, 3.f, 4.f, 5.f}) {
      auto z_of = [amplitude, phase](float x, float y) {
        return -kSensorHeight + amplitude * std::sin(2.f * float(M_PI) * x / 50.f + phase) *
                                    std::cos(2.f * float(M_PI) * y / 50.f);
      };
      const Scene scene = castLines(z_of, cars, 66.f, amplitude, beams, 57.f, 5);
      Score with_rule, without;
      for (const bool rule : {true, false}) {
        GroundPlaneFilter<pcl::PointXYZ> filter;  // the detector's thresholds
        filter.setInputCloud(scene.cloud);
        filter.setNegative(true);
        filter.setDistanceThreshold(0.25f);
        filter.setMaxTilt(15.f * float(M_PI) / 180.f);
        if (!rule) filter.setCurvedCellDepth(std::numeric_limits<float>::infinity());
        pcl::Indices ground;
        filter.filter(ground);
        (rule ? with_rule : without) = score(scene, ground);
      }
      improved += with_rule.recall > without.recall + 0.005;
      worse += with_rule.recall < without.recall - 0.005;
      precision_change += with_rule.precision - without.precision;
      ++scenes;
    }
  // In most scenes no far cell meets the case; where one does, the far ground found grows.
  EXPECT_GE(improved, 3) << "of " << scenes << " scenes";
  EXPECT_EQ(worse, 0);
  EXPECT_GT(precision_change / scenes, -0.002);
}

TEST(GroundPlaneFilter, EstimatesTheSensorHeightBesideParkedCars) {
  // A sensor mounted 2.4 m high (not KITTI's 1.73 m) in a car park: rows of cars 3-12 m around
  // it, whose roofs and bonnets make dense layers 0.9-1.4 m below the sensor. The ground is the
  // deepest dense layer, and its depth is the height the filter starts from.
  constexpr float kMount = 2.4f;
  std::vector<float> beams;
  for (float b = 24.9f; b > 1.2f; b -= (b > 8.f ? 0.5f : 0.35f)) beams.push_back(b);
  auto z_of = [](float, float) { return -kMount; };
  auto cars = [](float x, float y) {
    const float r = std::hypot(x, y);
    const bool row = (r > 3.f && r < 4.8f) || (r > 7.f && r < 8.8f) || (r > 10.5f && r < 12.3f);
    const float a = std::atan2(y, x) * 180.f / float(M_PI) + 180.f;
    return row && std::fmod(a, 30.f) < 24.f ? 1.5f : 0.f;  // cars with gaps between them
  };
  const Scene scene = castLines(z_of, cars, 3.f, 1.f, beams, 3.f, 7);
  GroundPlaneFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(scene.cloud);
  filter.setNegative(true);
  pcl::Indices ground;
  filter.filter(ground);
  EXPECT_EQ(filter.getSensorHeight(), 0.f);  // the default: estimate
  EXPECT_NEAR(filter.getUsedSensorHeight(), kMount, 0.05f);
  const Score s = score(scene, ground);
  EXPECT_GT(s.recall, 0.95);
  EXPECT_GT(s.precision, 0.95);

  // A scan without near returns (a blind frame) keeps the last estimate; a set height is used.
  filter.setInputCloud(Cloud::Ptr(new Cloud));
  filter.filter(ground);
  EXPECT_NEAR(filter.getUsedSensorHeight(), kMount, 0.05f);
  filter.setSensorHeight(1.73f);
  filter.setInputCloud(scene.cloud);
  filter.filter(ground);
  EXPECT_EQ(filter.getUsedSensorHeight(), 1.73f);
}
