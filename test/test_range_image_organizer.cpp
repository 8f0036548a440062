/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/sensor_model.h>

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
