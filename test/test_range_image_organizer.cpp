/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/sensor_model.h>
#include <pcl_movers/impl/range_image_organizer.hpp>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace {

using pcl_movers::InputError;
using pcl_movers::RangeImageOrganizer;
using pcl_movers::SensorModel;
using Cloud = pcl::PointCloud<pcl::PointXYZI>;

struct Expected {
  int row, column;
};

/** Rings of `model`: one point at the centre of a random subset of cells, random ranges,
 * shuffled. `expected[i]` is the cell point i was made for. */
Cloud::Ptr rings(const SensorModel& model, std::vector<Expected>& expected, unsigned seed,
                 float fill = 0.7f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  Cloud::Ptr cloud(new Cloud);
  expected.clear();
  for (int r = 0; r < model.rows(); ++r)
    for (int c = 0; c < model.columns(); ++c) {
      if (unit(rng) > fill) continue;
      const float rho = 3.f + 50.f * unit(rng), a = model.azimuthOf(c);
      pcl::PointXYZI p;
      p.x = rho * std::cos(a);
      p.y = rho * std::sin(a);
      p.z = rho * std::tan(model.elevations()[r]) + model.verticalOffsets()[r];
      p.intensity = float(r * 10000 + c);
      cloud->push_back(p);
      expected.push_back({r, c});
    }
  std::vector<std::size_t> order(cloud->size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  Cloud::Ptr shuffled(new Cloud);
  std::vector<Expected> shuffled_expected;
  for (const auto i : order) {
    shuffled->push_back((*cloud)[i]);
    shuffled_expected.push_back(expected[i]);
  }
  expected = shuffled_expected;
  return shuffled;
}

void expectExactCells(const SensorModel& model, unsigned seed) {
  std::vector<Expected> expected;
  const auto cloud = rings(model, expected, seed);
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(model);
  organizer.setInputCloud(cloud);
  Cloud out;
  organizer.organize(out);
  ASSERT_EQ(int(out.height), model.rows());
  ASSERT_EQ(int(out.width), model.columns());
  EXPECT_FALSE(out.is_dense);
  EXPECT_FALSE(organizer.wasPassThrough());
  EXPECT_EQ(organizer.getDisplacedCount(), 0u);
  EXPECT_EQ(organizer.getShiftedCount(), 0u);
  const auto& index = organizer.getIndexImage();
  const auto& cell_of = organizer.getCellOfPoint();
  ASSERT_EQ(index.size(), out.size());
  ASSERT_EQ(cell_of.size(), cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const int cell = expected[i].row * model.columns() + expected[i].column;
    ASSERT_EQ(cell_of[i], cell) << "point " << i;
    ASSERT_EQ(index[cell], int(i));
    ASSERT_EQ(out.at(expected[i].column, expected[i].row).intensity, (*cloud)[i].intensity);
  }
  // Every other cell is empty and NaN.
  const std::size_t empty = std::count(index.begin(), index.end(), -1);
  EXPECT_EQ(empty, out.size() - cloud->size());
  for (std::size_t cell = 0; cell < out.size(); ++cell)
    if (index[cell] < 0) ASSERT_TRUE(std::isnan(out[cell].x));
}

TEST(RangeImageOrganizer, SyntheticRingsLandInExactCells) {
  expectExactCells(SensorModel::vlp16(), 1);
  expectExactCells(SensorModel::hdl64(), 2);  // uneven beams, vertical offsets
  expectExactCells(SensorModel::ladar2d(), 3);
}

TEST(RangeImageOrganizer, RowsAreTopToBottomAndColumnsRightToLeft) {
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(SensorModel::vlp16());
  Cloud::Ptr cloud(new Cloud);
  pcl::PointXYZI up, down;
  up.x = 10.f;
  up.y = 0.1f;  // slightly left
  up.z = 10.f * std::tan(15.f * float(M_PI) / 180.f);
  down = up;
  down.y = -0.1f;
  down.z = -up.z;
  cloud->push_back(up);
  cloud->push_back(down);
  organizer.setInputCloud(cloud);
  Cloud out;
  organizer.organize(out);
  const auto& cell_of = organizer.getCellOfPoint();
  EXPECT_EQ(cell_of[0] / int(out.width), 0);
  EXPECT_EQ(cell_of[1] / int(out.width), 15);
  EXPECT_LT(cell_of[0] % int(out.width), cell_of[1] % int(out.width));  // left = lower column
}

TEST(RangeImageOrganizer, CollisionsKeepTheNearerPointOrUseAFreeNeighbour) {
  const SensorModel model = SensorModel::vlp16();
  const float a = model.azimuthOf(100) + 0.2f * model.azimuthResolution();  // leans to column 99
  auto point = [&](float rho) {
    pcl::PointXYZI p;
    p.x = rho * std::cos(a);
    p.y = rho * std::sin(a);
    p.z = rho * std::tan(model.elevations()[7]);
    return p;
  };
  Cloud::Ptr cloud(new Cloud);
  cloud->push_back(point(20.f));
  cloud->push_back(point(10.f));  // nearer, same cell
  cloud->push_back(point(30.f));  // farther, same cell
  const int row = 7, columns = model.columns();

  RangeImageOrganizer<pcl::PointXYZI> strict;
  strict.setSensorModel(model);
  strict.setUseFreeNeighbour(false);
  strict.setInputCloud(cloud);
  Cloud out;
  strict.organize(out);
  EXPECT_EQ(strict.getDisplacedCount(), 2u);
  EXPECT_EQ(strict.getCellOfPoint()[1], row * columns + 100);
  EXPECT_EQ(strict.getCellOfPoint()[0], -1);
  EXPECT_EQ(strict.getCellOfPoint()[2], -1);
  EXPECT_EQ(strict.getIndexImage()[row * columns + 100], 1);

  RangeImageOrganizer<pcl::PointXYZI> lenient;
  lenient.setSensorModel(model);
  lenient.setInputCloud(cloud);
  lenient.organize(out);
  EXPECT_EQ(lenient.getShiftedCount(), 2u);
  EXPECT_EQ(lenient.getDisplacedCount(), 0u);
  EXPECT_EQ(lenient.getCellOfPoint()[0], row * columns + 100);
  EXPECT_EQ(lenient.getCellOfPoint()[1], row * columns + 99);   // the side its azimuth leans to
  EXPECT_EQ(lenient.getCellOfPoint()[2], row * columns + 101);  // then the other side

  // The same organizer again without the neighbours: the losers' entries of the previous frame
  // must not survive (the cell of each point is rewritten every frame, not refilled with -1).
  lenient.setUseFreeNeighbour(false);
  lenient.organize(out);
  EXPECT_EQ(lenient.getCellOfPoint(), strict.getCellOfPoint());
  EXPECT_EQ(lenient.getCellOfPoint()[2], -1);
}

TEST(RangeImageOrganizer, OrganizedInputPassesThrough) {
  Cloud::Ptr cloud(new Cloud(4, 3));
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    (*cloud)[i].x = float(i) + 1.f;
    (*cloud)[i].y = 0.f;
    (*cloud)[i].z = 0.f;
  }
  (*cloud)[5].x = std::nanf("");
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(SensorModel::hdl64());
  organizer.setInputCloud(cloud);
  Cloud out;
  organizer.organize(out);
  EXPECT_TRUE(organizer.wasPassThrough());
  EXPECT_EQ(out.width, 4u);
  EXPECT_EQ(out.height, 3u);
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    if (i == 5) {
      EXPECT_EQ(organizer.getIndexImage()[i], -1);
      EXPECT_EQ(organizer.getCellOfPoint()[i], -1);
      continue;
    }
    EXPECT_EQ(out[i].x, (*cloud)[i].x);
    EXPECT_EQ(organizer.getIndexImage()[i], int(i));
    EXPECT_EQ(organizer.getCellOfPoint()[i], int(i));
  }
}

TEST(RangeImageOrganizer, OrganizedInputClosesAFullTurnOnlyWhenItsColumnsCoverOne) {
  // Organized input brings its own columns: whether the first and last are neighbours is measured
  // from the azimuth step between them (a forward-looking ladar covers a quarter turn, a spinning
  // sensor the whole of it, whichever way its columns run).
  const auto image = [](int columns, double field_deg, double sign) {
    Cloud::Ptr cloud(new Cloud(columns, 4));
    for (int c = 0; c < columns; ++c)
      for (int r = 0; r < 4; ++r) {
        const double azimuth =
            sign * (-0.5 * field_deg + (c + 0.5) * field_deg / columns) * M_PI / 180.0;
        auto& p = cloud->at(c, r);
        p.x = static_cast<float>(10.0 * std::cos(azimuth));
        p.y = static_cast<float>(10.0 * std::sin(azimuth));
        p.z = static_cast<float>(r) - 2.f;
      }
    for (int c = 0; c < columns; c += 7) cloud->at(c, 0).x = std::nanf("");  // dropouts
    return cloud;
  };
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  Cloud out;
  for (const double sign : {1.0, -1.0}) {
    organizer.setInputCloud(image(360, 90.0, sign));
    organizer.organize(out);
    EXPECT_FALSE(organizer.isFullTurn()) << "90°, sign " << sign;
    organizer.setInputCloud(image(1024, 360.0, sign));
    organizer.organize(out);
    EXPECT_TRUE(organizer.isFullTurn()) << "360°, sign " << sign;
  }
  // Unorganized input takes the field of view of its sensor model.
  organizer.setSensorModel(SensorModel::hdl64());
  Cloud::Ptr ring(new Cloud);
  for (int c = 0; c < 100; ++c) {
    pcl::PointXYZI p;
    p.x = 10.f * std::cos(0.06f * c);
    p.y = 10.f * std::sin(0.06f * c);
    p.z = -1.f;
    ring->push_back(p);
  }
  organizer.setInputCloud(ring);
  organizer.organize(out);
  EXPECT_TRUE(organizer.isFullTurn());
}

TEST(RangeImageOrganizer, BadInputsThrowInputError) {
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(SensorModel::vlp16());
  Cloud out;
  EXPECT_THROW(organizer.organize(out), InputError);  // no input
  organizer.setInputCloud(Cloud::Ptr(new Cloud));
  EXPECT_THROW(organizer.organize(out), InputError);  // empty
  Cloud::Ptr nan_cloud(new Cloud);
  pcl::PointXYZI nan_point;
  nan_point.x = nan_point.y = nan_point.z = std::nanf("");
  for (int i = 0; i < 10; ++i) nan_cloud->push_back(nan_point);
  organizer.setInputCloud(nan_cloud);
  try {
    organizer.organize(out);
    FAIL() << "all-NaN input accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("finite"), std::string::npos) << e.what();
  }
  // Everything outside the field of view (straight up).
  Cloud::Ptr up(new Cloud);
  pcl::PointXYZI p;
  p.x = 0.1f;
  p.y = 0.f;
  p.z = 10.f;
  up->push_back(p);
  organizer.setInputCloud(up);
  Cloud previous(3, 2);
  out = previous;
  EXPECT_THROW(organizer.organize(out), InputError);
  EXPECT_EQ(out.width, 3u);  // left as it was
  EXPECT_EQ(out.height, 2u);
  // No model and estimation off.
  RangeImageOrganizer<pcl::PointXYZI> no_model;
  no_model.setEstimateSensorModel(false);
  no_model.setInputCloud(up);
  EXPECT_THROW(no_model.organize(out), InputError);
  // Estimation on a cloud far too small.
  RangeImageOrganizer<pcl::PointXYZI> tiny;
  tiny.setInputCloud(up);
  EXPECT_THROW(tiny.organize(out), InputError);
  EXPECT_THROW(organizer.setSensorModel(SensorModel()), InputError);
}

TEST(RangeImageOrganizer, NanAndInfPointsAreSkippedAndCounted) {
  std::vector<Expected> expected;
  const SensorModel model = SensorModel::vlp16();
  auto cloud = rings(model, expected, 5, 0.2f);
  const std::size_t valid = cloud->size();
  pcl::PointXYZI bad;
  bad.x = std::nanf("");
  bad.y = bad.z = 0.f;
  cloud->push_back(bad);
  bad.x = std::numeric_limits<float>::infinity();
  cloud->push_back(bad);
  bad.x = 1.f;
  bad.z = -std::numeric_limits<float>::infinity();
  cloud->push_back(bad);
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(model);
  organizer.setInputCloud(cloud);
  Cloud out;
  organizer.organize(out);
  EXPECT_EQ(organizer.getInvalidCount(), 3u);
  for (std::size_t i = 0; i < valid; ++i)
    EXPECT_EQ(organizer.getCellOfPoint()[i],
              expected[i].row * model.columns() + expected[i].column);
  for (std::size_t i = valid; i < cloud->size(); ++i) EXPECT_EQ(organizer.getCellOfPoint()[i], -1);
  for (const auto& q : out)
    if (std::isfinite(q.x)) EXPECT_TRUE(std::isfinite(q.y) && std::isfinite(q.z));
}

TEST(RangeImageOrganizer, EstimatesTheModelWhenNoneIsSet) {
  std::vector<Expected> expected;
  const SensorModel model = SensorModel::vlp16();
  const auto cloud = rings(model, expected, 6, 0.9f);
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setColumns(model.columns());
  organizer.setInputCloud(cloud);
  Cloud out;
  organizer.organize(out);
  EXPECT_FALSE(organizer.hasSensorModel());
  EXPECT_EQ(organizer.getSensorModel().rows(), 16);
  ASSERT_EQ(out.height, 16u);
  ASSERT_EQ(int(out.width), model.columns());
  std::size_t right = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i)
    right += organizer.getCellOfPoint()[i] / model.columns() == expected[i].row;
  EXPECT_EQ(right, cloud->size());
}

TEST(RangeImageOrganizer, RangeLimitsIndicesAndInPlaceOrganize) {
  std::vector<Expected> expected;
  const SensorModel model = SensorModel::vlp16();
  const auto cloud = rings(model, expected, 8, 0.3f);
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(model);
  organizer.setMaxRange(20.f);
  organizer.setInputCloud(cloud);
  Cloud out;
  organizer.organize(out);
  std::size_t near = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const auto& p = (*cloud)[i];
    const bool inside = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z) <= 20.f;
    near += inside;
    EXPECT_EQ(organizer.getCellOfPoint()[i] >= 0, inside);
  }
  EXPECT_EQ(organizer.getOutOfViewCount(), cloud->size() - near);

  // Only the given indices are organized.
  organizer.setMaxRange(0.f);
  pcl::IndicesPtr indices(new pcl::Indices{0, 2, 4});
  organizer.setIndices(indices);
  organizer.organize(out);
  for (std::size_t i = 0; i < cloud->size(); ++i)
    EXPECT_EQ(organizer.getCellOfPoint()[i] >= 0, i == 0 || i == 2 || i == 4);

  // organize(*input) replaces the input by its image.
  Cloud::Ptr copy(new Cloud(*cloud));
  RangeImageOrganizer<pcl::PointXYZI> in_place;
  in_place.setSensorModel(model);
  in_place.setInputCloud(copy);
  in_place.organize(*copy);
  EXPECT_EQ(copy->height, 16u);
  EXPECT_EQ((*copy)[in_place.getCellOfPoint()[0]].intensity, (*cloud)[0].intensity);
}

TEST(RangeImageOrganizer, WorksForPointXYZ) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  const SensorModel model = SensorModel::hdl32();
  cloud->push_back(pcl::PointXYZ(10.f, 0.f, 10.f * std::tan(model.elevations()[3])));
  RangeImageOrganizer<pcl::PointXYZ> organizer;
  organizer.setSensorModel(model);
  organizer.setInputCloud(cloud);
  pcl::PointCloud<pcl::PointXYZ> out;
  organizer.organize(out);
  EXPECT_EQ(out.height, 32u);
  EXPECT_EQ(organizer.getCellOfPoint()[0], 3 * model.columns() + model.columnOf(0.f));
}

// The lookup layout both kernel tests use: a 560 x 32 row table over the elevation band of an
// HDL-64E, 2200 columns over a full turn, points up to 80 m. Each test sets its own row limits.
pcl_movers::detail::OrganizerKernelParams kernelTableParams() {
  pcl_movers::detail::OrganizerKernelParams c;
  c.max_range2 = 80.f * 80.f;
  c.g_min = -0.6f;
  c.g_scale = 800.f;
  c.g_bins = 560.f;
  c.w_scale = 32.f;
  c.w_bins = 32.f;
  c.azimuth_max = float(M_PI);
  c.columns_per_radian = 2200.f / float(2 * M_PI);
  c.columns = 2200.f;
  return c;
}

TEST(RangeImageOrganizer, VectorizedKernelMatchesTheScalarReference) {
  // The SIMD kernel (SSE2, or AVX2 when the CPU has it) must give bit-identical results to the
  // scalar loop, including NaN/Inf, the origin, far points and the padding lanes.
  pcl_movers::detail::OrganizerKernelParams c = kernelTableParams();
  c.min_range2 = 0.5f * 0.5f;
  c.upper_limit = 0.04f;
  c.upper_offset = 0.21f;
  c.lower_limit = -0.47f;
  c.lower_offset = 0.12f;
  c.mean_offset = 0.16f;
  std::mt19937 rng(11);
  // A random row table (with ambiguous cells) and mid-lines: only the lookup is compared here.
  std::vector<std::uint16_t> table(560 * 32 + 1);
  for (auto& e : table)
    e = rng() % 10 == 0 ? pcl_movers::detail::kTableAmbiguous : std::uint16_t(rng() % 64);
  std::vector<float> mid_a(64), mid_h(64);
  for (int k = 0; k < 64; ++k) {
    mid_a[k] = 0.03f - 0.0075f * float(k) + 0.002f * float(rng() % 100) / 100.f;
    mid_h[k] = 0.1f + 0.1f * float(rng() % 100) / 100.f;
  }
  c.row_table = table.data();
  c.mid_a = mid_a.data();
  c.mid_h = mid_h.data();
  std::uniform_real_distribution<float> u(-90.f, 90.f), uz(-4.f, 2.f);
  const std::size_t n = 4096;
  std::vector<float> x(n), y(n), z(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = u(rng);
    y[i] = u(rng);
    z[i] = uz(rng);
  }
  const float inf = std::numeric_limits<float>::infinity(), nan = std::nanf("");
  const float specials[][3] = {{nan, 1, 1},   {1, inf, 1},       {1, 1, -inf},
                               {0, 0, 1},     {0, 0, 0},         {-1, 0, 0},
                               {-1, -0.f, 0}, {1e30f, 1e30f, 0}, {0.3f, 0.1f, 0}};
  for (std::size_t i = 0; i < sizeof(specials) / sizeof(specials[0]); ++i) {
    x[i * 7] = specials[i][0];
    y[i * 7] = specials[i][1];
    z[i * 7] = specials[i][2];
  }
  for (const bool full : {true, false}) {
    c.full_revolution = full;
    if (!full) {
      c.azimuth_max = float(M_PI / 4);
      c.columns_per_radian = 360.f / float(M_PI / 2);
      c.columns = 360.f;
    }
    std::vector<float> w1(n), t1(n), w2(n), t2(n);
    std::vector<int> s1(n), s2(n), g1(n), g2(n), c1(n), c2(n), r1(n), r2(n);
    pcl_movers::detail::organizerKernelScalar(c, x.data(), y.data(), z.data(), n, w1.data(),
                                              t1.data(), s1.data(), g1.data(), c1.data(),
                                              r1.data());
    pcl_movers::detail::organizerKernel(c, x.data(), y.data(), z.data(), n, w2.data(), t2.data(),
                                        s2.data(), g2.data(), c2.data(), r2.data());
    std::size_t placed = 0, resolved = 0;
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ(s1[i], s2[i]) << i;
      if (s1[i] != 0) continue;
      ++placed;
      ASSERT_EQ(w1[i], w2[i]) << i;
      ASSERT_EQ(t1[i], t2[i]) << i;
      ASSERT_EQ(g1[i], g2[i]) << i;
      ASSERT_EQ(c1[i], c2[i]) << i;
      ASSERT_EQ(r1[i], r2[i]) << i;
      resolved += r1[i] >= 0;
    }
    EXPECT_GT(placed, n / 10);  // the comparison covered real points
    EXPECT_GT(resolved, placed / 2);
    EXPECT_EQ(s1[0], 1);      // NaN
    EXPECT_EQ(s1[3 * 7], 2);  // on the z axis: no azimuth
  }
}

TEST(RangeImageOrganizer, EveryKernelVariantMatchesTheScalarReference) {
  // Each vectorized kernel the CPU runs (SSE2 through organizerKernel's fallback is covered
  // above; here AVX2 and AVX-512 explicitly, and SSE2 through a count not a multiple of 8), on
  // points that come in runs of one row (the shortcut that confirms the previous row) and on
  // shuffled ones, with a row table consistent with its mid-lines as prepareLookup builds it:
  // horizontal mid-lines 0.0075 apart, table cells of 0.00125, a cell holding a mid-line within
  // 1e-4 (a float rounding away) ambiguous.
  pcl_movers::detail::OrganizerKernelParams c = kernelTableParams();
  c.min_range2 = 0.f;
  c.upper_limit = 0.035f;
  c.upper_offset = 0.f;
  c.lower_limit = 0.03f - 0.0075f * 63.f - 0.004f;
  c.lower_offset = 0.f;
  c.mean_offset = 0.f;
  c.full_revolution = true;
  c.ordered_mid_lines = true;
  std::vector<float> mid_a(64, -std::numeric_limits<float>::infinity()), mid_h(64, 0.f);
  for (int k = 0; k < 63; ++k) mid_a[k] = 0.03f - 0.0075f * float(k);
  std::vector<std::uint16_t> table(560 * 32 + 1, pcl_movers::detail::kTableAmbiguous);
  for (int i = 0; i < 560; ++i) {
    const double g0 = -0.6 + i / 800.0, g1 = -0.6 + (i + 1) / 800.0;
    int above = 0, inside = 0;
    for (int k = 0; k < 63; ++k) {
      above += mid_a[k] > g1 + 1e-4;
      inside += mid_a[k] >= g0 - 1e-4 && mid_a[k] <= g1 + 1e-4;
    }
    if (inside <= 1)
      for (int j = 0; j < 32; ++j)
        table[std::size_t(j) * 560 + std::size_t(i)] = std::uint16_t(above);
  }
  c.row_table = table.data();
  c.mid_a = mid_a.data();
  c.mid_h = mid_h.data();
  std::mt19937 rng(41);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  std::vector<float> x, y, z;
  for (int run = 0; run < 300; ++run) {  // runs of one band, some points just across its edges
    const int row = int(unit(rng) * 64.f) % 64;
    const int length = 1 + int(unit(rng) * 60.f);
    for (int i = 0; i < length; ++i) {
      const float rho = unit(rng) < 0.05f ? 0.5f + 0.5f * unit(rng) : 1.f + 79.f * unit(rng);
      const float a = float(2 * M_PI) * unit(rng) - float(M_PI);
      const float centre = 0.03f + 0.00375f - 0.0075f * float(row);
      const float t = centre + 0.0075f * (unit(rng) < 0.1f ? 1.2f : 0.98f) * (unit(rng) - 0.5f);
      x.push_back(rho * std::cos(a));
      y.push_back(rho * std::sin(a));
      z.push_back(t * rho);
    }
  }
  const std::size_t ordered = x.size();
  for (std::size_t i = 0; i < ordered; ++i) {  // the same points shuffled
    const std::size_t j = rng() % ordered;
    x.push_back(x[j]);
    y.push_back(y[j]);
    z.push_back(z[j]);
  }
  x.push_back(std::nanf(""));
  y.push_back(0.f);
  z.push_back(0.f);
  while (x.size() % 16 != 0) {
    x.push_back(-5.f);  // azimuth exactly pi
    y.push_back(0.f);
    z.push_back(0.f);
  }
  const std::size_t n = x.size();
  std::vector<float> w1(n), t1(n), w2(n), t2(n);
  std::vector<int> s1(n), s2(n), g1(n), g2(n), c1(n), c2(n), r1(n), r2(n);
  pcl_movers::detail::organizerKernelScalar(c, x.data(), y.data(), z.data(), n, w1.data(),
                                            t1.data(), s1.data(), g1.data(), c1.data(), r1.data());
  auto compare = [&](const char* name, std::size_t count) {
    SCOPED_TRACE(name);
    std::size_t placed = 0, resolved = 0;
    for (std::size_t i = 0; i < count; ++i) {
      ASSERT_EQ(s1[i], s2[i]) << i;
      if (s1[i] != 0) continue;
      ++placed;
      ASSERT_EQ(w1[i], w2[i]) << i;
      ASSERT_EQ(t1[i], t2[i]) << i;
      ASSERT_EQ(c1[i], c2[i]) << i;
      // Where the table is ambiguous the scalar reference leaves the row to the search (-1); a
      // confirmed run may already give it: then it must be the true band.
      if (r1[i] >= 0)
        ASSERT_EQ(r1[i], r2[i]) << i;
      else if (r2[i] >= 0)
        ASSERT_TRUE(t1[i] < (r2[i] > 0 ? mid_a[r2[i] - 1] : 1e9f) && t1[i] >= mid_a[r2[i]]) << i;
      resolved += r1[i] >= 0;
    }
    EXPECT_GT(placed, count * 8 / 10);
    EXPECT_GT(resolved, placed * 8 / 10);
  };
  auto clear = [&] {  // so that a kernel that skips lanes cannot pass on the previous results
    std::fill(s2.begin(), s2.end(), -7);
    std::fill(c2.begin(), c2.end(), -7);
    std::fill(r2.begin(), r2.end(), -7);
  };
#if defined(PCL_MOVERS_ORGANIZER_AVX2)
  if (pcl_movers::detail::organizerHasAvx2()) {
    clear();
    pcl_movers::detail::organizerKernelAvx2(c, x.data(), y.data(), z.data(), n, w2.data(),
                                            t2.data(), s2.data(), g2.data(), c2.data(), r2.data());
    compare("AVX2", n);
  }
  if (pcl_movers::detail::organizerHasAvx512()) {
    clear();
    pcl_movers::detail::organizerKernelAvx512x16<0>(c, x.data(), y.data(), z.data(), n, w2.data(),
                                                    t2.data(), s2.data(), g2.data(), c2.data(),
                                                    r2.data());
    compare("AVX-512 from arrays", n);
    // Straight from 16- and 32-byte points; the other floats of each point are NaN (PointXYZ's
    // padding, PointXYZI's intensity and padding) and must not matter.
    for (const int stride : {4, 8}) {
      std::vector<float> points(n * std::size_t(stride), std::nanf(""));
      for (std::size_t i = 0; i < n; ++i) {
        points[i * std::size_t(stride)] = x[i];
        points[i * std::size_t(stride) + 1] = y[i];
        points[i * std::size_t(stride) + 2] = z[i];
      }
      clear();
      if (stride == 4)
        pcl_movers::detail::organizerKernelAvx512x16<4>(c, points.data(), nullptr, nullptr, n,
                                                        w2.data(), t2.data(), s2.data(), g2.data(),
                                                        c2.data(), r2.data());
      else
        pcl_movers::detail::organizerKernelAvx512x16<8>(c, points.data(), nullptr, nullptr, n,
                                                        w2.data(), t2.data(), s2.data(), g2.data(),
                                                        c2.data(), r2.data());
      compare(stride == 4 ? "AVX-512 from 16-byte points" : "AVX-512 from 32-byte points", n);
    }
  }
#endif
  clear();
  pcl_movers::detail::organizerKernel(c, x.data(), y.data(), z.data(), n, w2.data(), t2.data(),
                                      s2.data(), g2.data(), c2.data(), r2.data());
  compare("dispatched", n);
  // A count that is a multiple of 4 but not of 8: the SSE2 fallback every x86-64 CPU runs (the
  // kernel a CPU without AVX2 or AVX-512 uses for all points).
  clear();
  pcl_movers::detail::organizerKernel(c, x.data(), y.data(), z.data(), n - 4, w2.data(), t2.data(),
                                      s2.data(), g2.data(), c2.data(), r2.data());
  compare("SSE2", n - 4);
}

TEST(RangeImageOrganizer, PointsReadInPlaceMatchCopiedPoints) {
  // Without indices, whole blocks of 16 points are read by the AVX-512 kernel straight from the
  // cloud (PointXYZ and PointXYZI); with indices, and for the last partial block, the points are
  // copied into arrays first. Same cells either way: a scan in recording order with collisions
  // (the free-neighbour rule and nearest-wins both run), NaN/Inf points, points on the ±pi seam,
  // nearer than 1 m and beyond the field of view, trimmed to sizes that are and are not multiples
  // of 16.
  const SensorModel model = SensorModel::hdl64();
  std::mt19937 rng(53);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  Cloud::Ptr scan(new Cloud);
  const float inf = std::numeric_limits<float>::infinity();
  for (int r = 0; r < 64; ++r) {
    // More points than columns per turn: collisions.
    const int length = 1000 + int(unit(rng) * 3000.f);
    for (int j = 0; j < length; ++j) {
      pcl::PointXYZI p;
      const float u = unit(rng);
      const float rho = u < 0.03f ? 0.4f + 0.5f * unit(rng) : 1.5f + 70.f * unit(rng);
      const float a = float(M_PI) - float(2 * M_PI) * float(j) / float(length);
      const float e = model.elevations()[r] + 0.004f * (unit(rng) - 0.5f);
      p.x = rho * std::cos(a);
      p.y = j == 0 ? (r % 2 ? 0.f : -0.f) : rho * std::sin(a);  // j == 0: azimuth exactly ±pi
      if (j == 0) p.x = -rho;
      p.z = u > 0.99f ? 5.f * rho : rho * std::tan(e) + model.verticalOffsets()[r];  // above all
      p.intensity = float(scan->size());
      if (u > 0.97f && u <= 0.98f) p.x = std::nanf("");
      if (u > 0.98f && u <= 0.99f) p.y = unit(rng) < 0.5f ? inf : -inf;
      scan->push_back(p);
    }
  }
  for (const std::size_t trim : {0, 1, 7, 15, 16}) {
    SCOPED_TRACE(trim);
    Cloud::Ptr cloud(new Cloud);
    cloud->points.assign(scan->points.begin(), scan->points.end() - long(trim));
    cloud->width = std::uint32_t(cloud->size());
    cloud->height = 1;
    pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
    for (const auto& p : *cloud) xyz->push_back(pcl::PointXYZ(p.x, p.y, p.z));
    pcl::IndicesPtr all(new pcl::Indices(cloud->size()));
    std::iota(all->begin(), all->end(), 0);
    RangeImageOrganizer<pcl::PointXYZI> direct, copied;
    RangeImageOrganizer<pcl::PointXYZ> direct_xyz;
    for (auto* organizer : {&direct, &copied}) organizer->setSensorModel(model);
    direct_xyz.setSensorModel(model);
    direct.setInputCloud(cloud);
    copied.setInputCloud(cloud);
    copied.setIndices(all);
    direct_xyz.setInputCloud(xyz);
    Cloud out_direct, out_copied;
    pcl::PointCloud<pcl::PointXYZ> out_xyz;
    direct.organize(out_direct);
    copied.organize(out_copied);
    direct_xyz.organize(out_xyz);
    EXPECT_GT(direct.getShiftedCount(), 100u);
    EXPECT_GT(direct.getDisplacedCount(), 10u);
    EXPECT_GT(direct.getInvalidCount(), 100u);
    EXPECT_GT(direct.getOutOfViewCount(), 100u);
    for (const auto* o : {&copied}) {
      EXPECT_EQ(o->getShiftedCount(), direct.getShiftedCount());
      EXPECT_EQ(o->getDisplacedCount(), direct.getDisplacedCount());
      EXPECT_EQ(o->getInvalidCount(), direct.getInvalidCount());
      EXPECT_EQ(o->getOutOfViewCount(), direct.getOutOfViewCount());
      ASSERT_TRUE(o->getIndexImage() == direct.getIndexImage());
      ASSERT_TRUE(o->getCellOfPoint() == direct.getCellOfPoint());
    }
    EXPECT_EQ(direct_xyz.getShiftedCount(), direct.getShiftedCount());
    EXPECT_EQ(direct_xyz.getInvalidCount(), direct.getInvalidCount());
    ASSERT_TRUE(direct_xyz.getIndexImage() == direct.getIndexImage());
    ASSERT_TRUE(direct_xyz.getCellOfPoint() == direct.getCellOfPoint());
    ASSERT_EQ(out_direct.size(), out_copied.size());
    for (std::size_t c = 0; c < out_direct.size(); ++c) {
      const int i = direct.getIndexImage()[c];
      ASSERT_EQ(std::isnan(out_direct[c].x), i < 0) << c;
      if (i < 0) continue;
      ASSERT_EQ(out_direct[c].intensity, float(i)) << c;
      ASSERT_EQ(out_copied[c].intensity, float(i)) << c;
      ASSERT_EQ(out_xyz[c].x, (*cloud)[std::size_t(i)].x) << c;
    }
  }
}

TEST(RangeImageOrganizer, FastAnglesAndRowTableMatchTheExactAssignment) {
  // Random points around every beam of the HDL-64E (uneven beams, two offset blocks), from 1.5 m
  // (nearer than the row table reaches) to 80 m: the row must be SensorModel::rowOfPoint's and
  // the column that of std::atan2, except within a tiny fraction of a column of its border.
  const SensorModel model = SensorModel::hdl64();
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  Cloud::Ptr cloud(new Cloud);
  for (int i = 0; i < 60000; ++i) {
    const int k = int(unit(rng) * 64.f) % 64;
    const float rho = 1.5f + 78.5f * unit(rng) * unit(rng);
    const float a = float(M_PI) * (2.f * unit(rng) - 1.f);
    // Up to 40 % of the way to the neighbouring beam: clear of the half-way line.
    const float spacing = k > 0 ? model.elevations()[k - 1] - model.elevations()[k]
                                : model.elevations()[0] - model.elevations()[1];
    const float e = model.elevations()[k] + 0.8f * (unit(rng) - 0.5f) * spacing;
    pcl::PointXYZI p;
    p.x = rho * std::cos(a);
    p.y = rho * std::sin(a);
    p.z = rho * std::tan(e) + model.verticalOffsets()[k];
    cloud->push_back(p);
  }
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(model);
  organizer.setUseFreeNeighbour(false);
  organizer.setInputCloud(cloud);
  Cloud out;
  organizer.organize(out);
  const int columns = int(out.width);
  std::size_t checked = 0, near_border = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const auto& p = (*cloud)[i];
    const float rho = std::sqrt(p.x * p.x + p.y * p.y);
    const int exact_row = model.rowOfPoint(rho, p.z);
    const int cell = organizer.getCellOfPoint()[i];
    if (cell < 0) {
      EXPECT_GE(exact_row, 0);  // lost to a nearer point, not rejected
      continue;
    }
    ASSERT_EQ(cell / columns, exact_row) << "point " << i << " rho " << rho;
    double f = (M_PI - std::atan2(double(p.y), double(p.x))) * columns / (2 * M_PI);
    if (f >= columns) f -= columns;
    if (std::abs(f - std::round(f)) < 2e-3) {
      ++near_border;
      continue;
    }
    ASSERT_EQ(cell % columns, int(f)) << "point " << i << " f " << f;
    ++checked;
  }
  EXPECT_GT(checked, 40000u);
  EXPECT_LT(near_border, 500u);
  EXPECT_EQ(organizer.getDisplacedCount() + checked + near_border, cloud->size());
}

TEST(RangeImageOrganizer, ReusedOrganizerMatchesAFreshOne) {
  // One organizer over frames of different sizes, a width change and a model change must give
  // what a new organizer gives for each: buffers and lookups are reused, never stale.
  std::vector<Expected> expected;
  const auto big = rings(SensorModel::hdl64(), expected, 21, 0.6f);
  const auto small = rings(SensorModel::hdl64(), expected, 22, 0.05f);
  const auto vlp = rings(SensorModel::vlp16(), expected, 23, 0.8f);
  struct Step {
    Cloud::Ptr cloud;
    SensorModel model;
    int columns;
  };
  const std::vector<Step> steps = {
      {big, SensorModel::hdl64(), 0}, {small, SensorModel::hdl64(), 0},
      {big, SensorModel::hdl64(), 0}, {big, SensorModel::hdl64(), 2048},
      {vlp, SensorModel::vlp16(), 0}, {small, SensorModel::hdl64(), 0}};
  RangeImageOrganizer<pcl::PointXYZI> reused;
  Cloud reused_out;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    const Step& step = steps[s];
    reused.setSensorModel(step.model);
    reused.setColumns(step.columns);
    reused.setInputCloud(step.cloud);
    reused.organize(reused_out);
    RangeImageOrganizer<pcl::PointXYZI> fresh;
    fresh.setSensorModel(step.model);
    fresh.setColumns(step.columns);
    fresh.setInputCloud(step.cloud);
    Cloud fresh_out;
    fresh.organize(fresh_out);
    ASSERT_EQ(reused_out.width, fresh_out.width);
    ASSERT_EQ(reused_out.height, fresh_out.height);
    EXPECT_EQ(reused.getIndexImage(), fresh.getIndexImage());
    EXPECT_EQ(reused.getCellOfPoint(), fresh.getCellOfPoint());
    EXPECT_EQ(reused.getShiftedCount(), fresh.getShiftedCount());
    EXPECT_EQ(reused.getDisplacedCount(), fresh.getDisplacedCount());
    for (std::size_t c = 0; c < fresh_out.size(); ++c) {
      const auto& a = reused_out[c];
      const auto& b = fresh_out[c];
      ASSERT_TRUE((std::isnan(a.x) && std::isnan(b.x)) ||
                  (a.x == b.x && a.intensity == b.intensity))
          << "cell " << c;
    }
  }
}

TEST(RangeImageOrganizer, ScanOrderedInputMatchesShuffledInput) {
  // The AVX2 kernel confirms the previous row for eight points at once when the input comes beam
  // after beam (as KITTI's does) and looks rows up otherwise. Both must give the same cells: the
  // same scan in recording order and shuffled, with points 49 % of the way to the neighbouring
  // beam (the band edges) and a few just past half-way (in the neighbouring row, amid a run of
  // this beam), azimuth exactly ±pi, points nearer than the row table
  // reaches (< 1 m), runs broken by NaN points, and rows changing in the middle of eight points.
  const SensorModel model = SensorModel::hdl64();
  const int columns = model.columns();
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  Cloud::Ptr ordered(new Cloud);
  std::vector<float> fraction;  // how far towards a neighbouring beam, in beam spacings
  for (int r = 0; r < 64; ++r) {
    const float spacing_up = r > 0 ? model.elevations()[r - 1] - model.elevations()[r]
                                   : model.elevations()[0] - model.elevations()[1];
    const float spacing_down = r < 63 ? model.elevations()[r] - model.elevations()[r + 1]
                                      : model.elevations()[62] - model.elevations()[63];
    // Beam r uses every fourth column (offset r % 4), so a point leaning into a neighbouring
    // row never meets that row's points nor those leaning in from its other side: no
    // collision, the cells do not depend on the order.
    const int length = 100 + int(unit(rng) * 450.f);  // a part of the turn, odd lengths too
    for (int j = 0; j < length; ++j) {
      const int c = 4 * j + (r % 4);
      pcl::PointXYZI p;
      if (unit(rng) < 0.01f) {
        p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
        ordered->push_back(p);
        fraction.push_back(0.f);
        continue;
      }
      const float rho = unit(rng) < 0.03f ? 0.4f + 0.5f * unit(rng) : 1.5f + 60.f * unit(rng);
      const float u = unit(rng);
      // Just inside the band edges, just across them (the point belongs to the neighbouring
      // row: a lane of eight in another row than the run), or well inside.
      const float across = 0.51f + 0.1f * unit(rng);
      const float f = u < 0.2f    ? 0.49f
                      : u < 0.4f  ? -0.49f
                      : u < 0.45f ? across
                      : u < 0.5f  ? -across
                                  : 0.8f * (unit(rng) - 0.5f);
      const float e = model.elevations()[r] + (f > 0.f ? f * spacing_up : f * spacing_down);
      const float a =
          model.azimuthOf(c) + 0.6f * (unit(rng) - 0.5f) * float(2 * M_PI) / float(columns);
      p.x = rho * std::cos(a);
      p.y = rho * std::sin(a);
      if (c == 0) {  // exactly on the ±pi seam, from either side of y = 0
        p.x = -rho;
        p.y = r % 8 == 0 ? 0.f : -0.f;
      }
      p.z = rho * std::tan(e) + model.verticalOffsets()[r];
      p.intensity = float(ordered->size());
      ordered->push_back(p);
      fraction.push_back(rho < 1.f ? 1.f : f);  // near points: no exact-row check below
    }
  }
  std::vector<std::size_t> order(ordered->size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  Cloud::Ptr shuffled(new Cloud);
  for (const auto i : order) shuffled->push_back((*ordered)[i]);

  RangeImageOrganizer<pcl::PointXYZI> a, b;
  for (auto* organizer : {&a, &b}) {
    organizer->setSensorModel(model);
    organizer->setUseFreeNeighbour(false);
  }
  a.setInputCloud(ordered);
  b.setInputCloud(shuffled);
  Cloud out_a, out_b;
  a.organize(out_a);
  b.organize(out_b);
  ASSERT_EQ(a.getDisplacedCount(), 0u);  // else the cells would depend on the order
  ASSERT_EQ(b.getDisplacedCount(), 0u);
  EXPECT_EQ(a.getInvalidCount(), b.getInvalidCount());
  EXPECT_GT(a.getInvalidCount(), 100u);
  std::size_t placed = 0, checked_rows = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t i = order[k];
    ASSERT_EQ(a.getCellOfPoint()[i], b.getCellOfPoint()[k]) << "point " << i;
    const int cell = a.getCellOfPoint()[i];
    if (cell < 0) continue;
    ++placed;
    ASSERT_EQ(out_a[std::size_t(cell)].intensity, float(i));
    const auto& p = (*ordered)[i];
    if (std::abs(fraction[i]) <= 0.4f) {
      ASSERT_EQ(cell / columns, model.rowOfPoint(std::sqrt(p.x * p.x + p.y * p.y), p.z))
          << "point " << i;
      ++checked_rows;
    }
  }
  EXPECT_GT(placed, ordered->size() * 9 / 10);
  EXPECT_GT(checked_rows, placed / 3);  // half are at or past the band edges
  for (std::size_t c = 0; c < out_a.size(); ++c)
    ASSERT_EQ(a.getIndexImage()[c] < 0, b.getIndexImage()[c] < 0) << "cell " << c;
}

/** The laser of each point from the recording order KITTI keeps (turns start at azimuth 0). */
std::vector<int> scanOrderBeams(const Cloud& cloud) {
  std::vector<int> beam(cloud.size());
  int current = 0;
  bool wrapped = false;
  float previous = 0.f;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const float azimuth = std::atan2(cloud[i].y, cloud[i].x);
    if (i > 0 && previous - azimuth > 1.f) wrapped = true;
    if (wrapped && previous < 0.f && azimuth >= 0.f) {
      ++current;
      wrapped = false;
    }
    previous = azimuth;
    beam[i] = current;
  }
  return beam;
}

TEST(RangeImageOrganizer, RealKittiScanKeepsPointsAndBeams) {
  const std::string path =
      std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a/frames/000040.pcd";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "KITTI data not found: " << path;
  Cloud::Ptr cloud(new Cloud);
  ASSERT_EQ(pcl::io::loadPCDFile(path, *cloud), 0);
  const auto beams = scanOrderBeams(*cloud);
  RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(SensorModel::hdl64());
  organizer.setInputCloud(cloud);
  Cloud out;
  organizer.organize(out);
  ASSERT_EQ(out.height, 64u);
  std::size_t in_range = 0, kept = 0, right_row = 0, known = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const auto& p = (*cloud)[i];
    if (std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z) > 80.f) continue;
    ++in_range;
    const int cell = organizer.getCellOfPoint()[i];
    if (cell < 0) continue;
    ++kept;
    if (beams[i] < 64) {
      ++known;
      right_row += cell / int(out.width) == beams[i];
    }
  }
  EXPECT_GT(double(kept) / double(in_range), 0.97);
  EXPECT_GT(double(right_row) / double(known), 0.999);
}

}  // namespace
