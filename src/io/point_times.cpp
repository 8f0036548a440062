/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/point_times.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace pcl_movers {
namespace io {

namespace {

/** Names drivers give the per-point time, in the order they are looked for. */
const char* const kTimeFields[] = {"time", "t", "timestamp"};

const pcl::PCLPointField* findField(const pcl::PCLPointCloud2& cloud, const std::string& name) {
  for (const pcl::PCLPointField& f : cloud.fields)
    if (f.name == name) return &f;
  return nullptr;
}

template <typename T>
double load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return double(v);
}

/** Value of `field` at `p` (the start of a point), whatever its type. */
double fieldValue(const pcl::PCLPointField& field, const std::uint8_t* p) {
  p += field.offset;
  switch (field.datatype) {
    case pcl::PCLPointField::INT8:
      return load<std::int8_t>(p);
    case pcl::PCLPointField::UINT8:
      return load<std::uint8_t>(p);
    case pcl::PCLPointField::INT16:
      return load<std::int16_t>(p);
    case pcl::PCLPointField::UINT16:
      return load<std::uint16_t>(p);
    case pcl::PCLPointField::INT32:
      return load<std::int32_t>(p);
    case pcl::PCLPointField::UINT32:
      return load<std::uint32_t>(p);
    case pcl::PCLPointField::FLOAT32:
      return load<float>(p);
    case pcl::PCLPointField::FLOAT64:
      return load<double>(p);
    default:
      return std::numeric_limits<double>::quiet_NaN();
  }
}

double smallestFinite(const std::vector<double>& v) {
  double m = std::numeric_limits<double>::infinity();
  for (const double x : v)
    if (std::isfinite(x)) m = std::min(m, x);
  return std::isfinite(m) ? m : 0.0;
}

}  // namespace

std::string pointTimeField(const std::string& path) {
  pcl::PCLPointCloud2 header;
  pcl::PCDReader reader;
  if (reader.readHeader(path, header) < 0) throw InputError(path, 0, "cannot read the PCD header");
  for (const char* name : kTimeFields)
    if (findField(header, name)) return name;
  return "";
}

std::vector<float> readPointTimes(const std::string& path) {
  const std::string name = pointTimeField(path);
  if (name.empty()) return {};
  pcl::PCLPointCloud2 cloud;
  pcl::PCDReader reader;
  if (reader.read(path, cloud) < 0) throw InputError(path, 0, "cannot read the PCD");
  const pcl::PCLPointField& field = *findField(cloud, name);
  const std::size_t n = std::size_t(cloud.width) * cloud.height;
  std::vector<double> raw(n);
  for (std::size_t i = 0; i < n; ++i) raw[i] = fieldValue(field, &cloud.data[i * cloud.point_step]);
  double offset = 0, scale = 1;
  if (name == "t") {
    scale = 1e-9;  // Ouster: nanoseconds from the start of the scan
  } else if (name == "timestamp") {
    offset = smallestFinite(raw);  // absolute
    if (offset > 1e12) scale = 1e-9;
  } else {
    offset = std::min(0.0, smallestFinite(raw));  // Velodyne: relative to the stamp
  }
  std::vector<float> times(n);
  for (std::size_t i = 0; i < n; ++i) times[i] = float((raw[i] - offset) * scale);
  return times;
}

}  // namespace io
}  // namespace pcl_movers
