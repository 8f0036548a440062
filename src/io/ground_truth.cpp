/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/ground_truth.h>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace pcl_movers {
namespace io {

bool GroundTruthObject::contains(const Eigen::Vector3d& p, double grow_xy, double grow_z) const {
  const Eigen::Vector3d d = p - center;
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double along = c * d.x() + s * d.y();
  const double across = -s * d.x() + c * d.y();
  return std::abs(along) <= 0.5 * (length + grow_xy) &&
         std::abs(across) <= 0.5 * (width + grow_xy) && std::abs(d.z()) <= 0.5 * (height + grow_z);
}

std::vector<GroundTruthObject> readObjects(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open objects file");
  std::vector<GroundTruthObject> objects;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream row(line);
    GroundTruthObject o;
    int moving = 0;
    if (!(row >> o.frame >> o.track_id >> o.type >> o.center.x() >> o.center.y() >> o.center.z() >>
          o.length >> o.width >> o.height >> o.yaw >> moving >> o.speed >> o.n_points))
      throw InputError(path, line_no,
                       "expected 13 columns: frame track_id class cx cy cz length width height yaw "
                       "moving speed_mps n_points");
    std::string rest;
    if (row >> rest) throw InputError(path, line_no, "unexpected extra column '" + rest + "'");
    if (o.frame < 0) throw InputError(path, line_no, "negative frame number");
    if (moving != 0 && moving != 1) throw InputError(path, line_no, "moving must be 0 or 1");
    if (!o.center.allFinite() || !std::isfinite(o.yaw) || !(o.length >= 0) || !(o.width >= 0) ||
        !(o.height >= 0))
      throw InputError(path, line_no, "box has NaN/Inf or negative size");
    o.moving = moving == 1;
    objects.push_back(o);
  }
  return objects;
}

void writeObjects(const std::string& path, const std::vector<GroundTruthObject>& objects) {
  std::ofstream out(path);
  if (!out) throw InputError(path, 0, "cannot write objects file");
  out << "# frame track_id class cx cy cz length width height yaw moving speed_mps n_points\n";
  out << std::fixed;
  for (const auto& o : objects) {
    out << o.frame << ' ' << o.track_id << ' ' << o.type << ' ' << std::setprecision(3)
        << o.center.x() << ' ' << o.center.y() << ' ' << o.center.z() << ' ' << o.length << ' '
        << o.width << ' ' << o.height << ' ' << std::setprecision(4) << o.yaw << ' '
        << (o.moving ? 1 : 0) << ' ' << std::setprecision(2) << o.speed << ' ' << o.n_points
        << '\n';
  }
  if (!out) throw InputError(path, 0, "write failed");
}

std::vector<std::uint32_t> readLabels(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(path, 0, "cannot open label file");
  const std::streamsize bytes = in.tellg();
  if (bytes % 4 != 0) throw InputError(path, 0, "truncated label file (size not a multiple of 4)");
  in.seekg(0);
  std::vector<std::uint32_t> labels(static_cast<std::size_t>(bytes) / 4);
  if (!in.read(reinterpret_cast<char*>(labels.data()), bytes))
    throw InputError(path, 0, "could not read label file");
  return labels;
}

void writeLabels(const std::string& path, const std::vector<std::uint32_t>& labels) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError(path, 0, "cannot write label file");
  out.write(reinterpret_cast<const char*>(labels.data()),
            static_cast<std::streamsize>(labels.size() * sizeof(std::uint32_t)));
  if (!out) throw InputError(path, 0, "write failed");
}

}  // namespace io
}  // namespace pcl_movers
