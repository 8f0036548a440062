/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/sequence.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <map>
#include <sstream>
#include <string_view>

namespace pcl_movers {
namespace io {
namespace detail {
/** A point with a per-point time [s after the frame's time], Velodyne-driver style. */
struct EIGEN_ALIGN16 PointXYZIT {
  PCL_ADD_POINT4D;
  float intensity;
  float time;
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};
}  // namespace detail
}  // namespace io
}  // namespace pcl_movers

// clang-format off
POINT_CLOUD_REGISTER_POINT_STRUCT(pcl_movers::io::detail::PointXYZIT,
                                  (float, x, x)(float, y, y)(float, z, z)
                                  (float, intensity, intensity)(float, time, time))
// clang-format on

namespace fs = std::filesystem;

namespace pcl_movers {
namespace io {
namespace {

bool hasExtension(const fs::path& p, const char* ext) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e == ext;
}

/** The last run of digits in the file stem, or -1 when there is none. */
long long fileNumber(const std::string& path) {
  const std::string stem = fs::path(path).stem().string();
  long long value = -1;
  std::size_t i = stem.size();
  while (i > 0 && !std::isdigit(static_cast<unsigned char>(stem[i - 1]))) --i;
  std::size_t end = i;
  while (i > 0 && std::isdigit(static_cast<unsigned char>(stem[i - 1]))) --i;
  if (end > i) value = std::stoll(stem.substr(i, std::min<std::size_t>(end - i, 18)));
  return value;
}

std::vector<std::string> listFiles(const fs::path& folder, const char* ext) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return out;
  for (const auto& entry : fs::directory_iterator(folder, ec))
    if (entry.is_regular_file(ec) && hasExtension(entry.path(), ext))
      out.push_back(entry.path().string());
  sortNumerically(out);
  return out;
}

bool isIdentityViewpoint(const Eigen::Vector4f& origin, const Eigen::Quaternionf& q) {
  return origin.head<3>().norm() < 1e-9f && std::abs(std::abs(q.w()) - 1.0f) < 1e-7f;
}

/** Refuses a PCD whose header claims more point data than the file can hold.
 *
 * pcl::PCDReader::readHeader allocates (and zero-fills) POINTS × point_step bytes as soon as it
 * parses the POINTS line, before it looks at the data: a 12 kB file claiming 371 million points of
 * 4 kB each asked for 1.5 TB (found by fuzz_pcd_pipeline in CI), and a claim of a few GB would
 * really be allocated. So the header is scanned here first, the way PCL scans it (same tokens,
 * same integer types, the point step as PCL has it when it reaches POINTS), and the claim is
 * compared with the bytes after the DATA line:
 * - binary: the data must be there, byte for byte;
 * - ascii: every value (Σ COUNT per point) is at least one character and a separator, and a
 *   value takes at most 8 bytes in memory;
 * - binary_compressed: LZF expands by at most 88× (264 bytes from a 3-byte back reference).
 * Headers this scan cannot follow are left to PCL, which rejects them. */
void checkPcdClaimedSize(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open file");
  std::vector<long long> sizes;
  std::uint32_t point_step = 0, width = 0, height = 0, claimed_step = 0;
  long long values_per_point = 0, claimed_values = 0;  // numbers per point in ascii (Σ COUNT)
  unsigned long long claimed_points = 0, claimed_bytes = 0;
  bool data_line = false;
  std::size_t points_line = 0, line_number = 0;
  std::string line, data_type = "ascii";  // PCL's default when there is no DATA line
  std::streamoff data_start = -1;
  // SIZE and COUNT entries as PCL reads them: one int per token; a token that does not parse
  // keeps what the failed extraction stores (0, or the int limit on overflow).
  auto intEntries = [](const std::string& text) {
    std::stringstream count(text), read(text);
    count.imbue(std::locale::classic());
    read.imbue(std::locale::classic());
    std::string token;
    count >> token;
    read >> token;
    std::vector<long long> out;
    while (count >> token) {
      int x = 0;
      read >> x;
      out.push_back(x);
    }
    return out;
  };
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    std::stringstream tokens(line);
    tokens.imbue(std::locale::classic());
    std::string key;
    tokens >> key;
    if (key.compare(0, 1, "#") == 0 || key.compare(0, 7, "VERSION") == 0 ||
        key.compare(0, 4, "TYPE") == 0 || key.compare(0, 9, "VIEWPOINT") == 0)
      continue;
    if (key.compare(0, 6, "FIELDS") == 0 || key.compare(0, 7, "COLUMNS") == 0) {
      std::size_t n = 0;
      for (std::string name; tokens >> name;) ++n;
      point_step = static_cast<std::uint32_t>(4 * n);  // PCL's default: one float per field
      values_per_point = static_cast<long long>(n);
    } else if (key.compare(0, 4, "SIZE") == 0) {
      sizes = intEntries(line);
      long long step = 0;
      for (const long long s : sizes) step += s;
      point_step = static_cast<std::uint32_t>(step);  // PCL keeps the step in 32 bits
    } else if (key.compare(0, 5, "COUNT") == 0) {
      const std::vector<long long> counts = intEntries(line);
      long long step = 0;
      values_per_point = 0;
      for (std::size_t i = 0; i < counts.size(); ++i) {
        if (i < sizes.size()) step += counts[i] * sizes[i];
        values_per_point += counts[i];
      }
      point_step = static_cast<std::uint32_t>(step);
    } else if (key.compare(0, 5, "WIDTH") == 0) {
      tokens >> width;
    } else if (key.compare(0, 6, "HEIGHT") == 0) {
      tokens >> height;
    } else if (key.compare(0, 6, "POINTS") == 0) {
      // PCL allocates POINTS × point_step right here. Read wider than PCL does (a value PCL would
      // clamp is refused, never let through) and count WIDTH × HEIGHT too, which it reads later.
      unsigned long long points = 0;
      tokens >> points;
      points = std::max(points, static_cast<unsigned long long>(width) * height);
      // Saturates: a product beyond 64 bits is kept as the largest claim, which no file holds.
      const bool too_many = point_step > 0 && points > ~0ull / point_step;
      const unsigned long long bytes = too_many ? ~0ull : points * point_step;
      if (bytes >= claimed_bytes) {
        claimed_bytes = bytes;
        claimed_points = points;
        claimed_step = point_step;
        claimed_values = values_per_point;
        points_line = line_number;
      }
    } else if (key.compare(0, 4, "DATA") == 0) {
      tokens >> data_type;
      data_line = true;
      data_start = in.tellg();  // -1 when the DATA line is the file's last
    } else {
      break;  // the first line that is not a header keyword ends PCL's header scan
    }
  }
  if (claimed_bytes == 0) return;
  in.clear();
  in.seekg(0, std::ios::end);
  const std::streamoff end = in.tellg();
  const std::streamoff start = data_start >= 0 ? data_start : data_line ? end : std::streamoff(0);
  const unsigned long long available =
      end > start ? static_cast<unsigned long long>(end - start) : 0ull;
  const bool compressed = data_type.compare(0, 17, "binary_compressed") == 0;
  const bool binary = !compressed && data_type.compare(0, 6, "binary") == 0;
  // ascii: each point's line holds its values, each at least one character plus a separator (or
  // the newline; the last line may lack it), and a value is at most 8 bytes in memory.
  const unsigned long long ascii_text_per_point =
      2 * static_cast<unsigned long long>(std::max(claimed_values, 1ll));
  const bool fits = binary       ? claimed_bytes <= available
                    : compressed ? claimed_bytes <= 88 * available
                                 : claimed_points <= (available + 1) / ascii_text_per_point &&
                                       claimed_bytes <= 8 * available + claimed_step;
  if (fits) return;
  std::ostringstream why;
  why << "header claims " << claimed_points << " points of " << claimed_step << " bytes ("
      << std::setprecision(3) << double(claimed_points) * double(claimed_step) / 1e6
      << " MB) but the file holds only " << available << " bytes of " << data_type << " data";
  throw InputError(path, points_line, why.str());
}

/** Refuses a cloud with a field that does not lie inside its point step (or has no valid type):
 * PCL's PCD reader would write past its buffer there, and pcl::fromPCLPointCloud2, which copies
 * each field from offset to offset + size within every point, would read past the data (both
 * found by fuzzing). Checked on a PCD's header before PCL reads its body, and on every blob read.
 */
void checkFieldsInsidePoint(const std::string& path, const pcl::PCLPointCloud2& cloud) {
  for (const auto& field : cloud.fields) {
    const std::size_t size =
        pcl::getFieldSize(field.datatype) * std::max<std::size_t>(1, field.count);
    const std::size_t end = field.offset + size;
    if (size == 0 || end > cloud.point_step)
      throw InputError(path, 0,
                       "field '" + field.name + "' ends at byte " + std::to_string(end) +
                           ", outside the point's " + std::to_string(cloud.point_step) +
                           " bytes (SIZE, TYPE or COUNT do not match FIELDS)");
  }
}

/** Refuses a PCD header whose point layout PCL's reader would write past.
 *
 * pcl::PCDReader sizes its buffer when it parses POINTS, with the point step known then, but
 * writes every point with the step and field offsets of the whole header: a COUNT, SIZE or FIELDS
 * line after POINTS (or fields reaching past the step, checkFieldsInsidePoint()) makes it write
 * beyond the buffer, in PCL's own, uninstrumented code (a 24-byte buffer took 960 bytes of ASCII
 * values; found by fuzz_pcd_pipeline in CI as heap corruption that ASan noticed only inputs
 * later). A
 * binary_compressed body is unpacked into its stored uncompressed size, so that must be the
 * header's size too. The header PCL parsed (`header`, `data_type`, `data_idx` from readHeader)
 * is the one its read() parses again. */
void checkPcdLayout(const std::string& path, const pcl::PCLPointCloud2& header, int data_type,
                    unsigned int data_idx) {
  const std::size_t points = static_cast<std::size_t>(header.width) * header.height;
  const std::size_t bytes = points * header.point_step;
  checkFieldsInsidePoint(path, header);
  if (header.data.size() != bytes)
    throw InputError(path, 0,
                     "malformed PCD header: the point layout changes after POINTS (" +
                         std::to_string(header.data.size() / std::max<std::size_t>(points, 1)) +
                         " bytes per point when POINTS was read, " +
                         std::to_string(header.point_step) +
                         " at the end); put FIELDS, SIZE, TYPE and COUNT before POINTS");
  if (data_type != 2) return;
  std::ifstream in(path, std::ios::binary);
  std::uint32_t sizes[2] = {0, 0};
  in.seekg(data_idx);
  if (!in.read(reinterpret_cast<char*>(sizes), sizeof(sizes)))
    throw InputError(path, 0, "binary_compressed PCD without its compressed-size record");
  if (sizes[1] != bytes)
    throw InputError(path, 0,
                     "binary_compressed PCD stores " + std::to_string(sizes[1]) +
                         " uncompressed bytes, the header describes " + std::to_string(bytes));
}

void readPcdHeader(const std::string& path, pcl::PCLPointCloud2& header, Eigen::Vector4f& origin,
                   Eigen::Quaternionf& orientation) {
  checkPcdClaimedSize(path);
  pcl::PCDReader reader;
  int version = 0, data_type = 0;
  unsigned int data_idx = 0;
  int status = -1;
  try {
    status = reader.readHeader(path, header, origin, orientation, version, data_type, data_idx);
  } catch (const std::exception& e) {
    // PCL's header parser indexes its tokens with vector::at(), so a malformed line (e.g. fewer
    // SIZE entries than FIELDS) escapes as std::out_of_range (found by fuzz_pcd_pipeline).
    throw InputError(path, 0,
                     std::string("not a readable PCD file (malformed header: ") + e.what() + ")");
  }
  if (status < 0) throw InputError(path, 0, "not a readable PCD file (bad or missing header)");
  checkPcdLayout(path, header, data_type, data_idx);
}

bool hasField(const pcl::PCLPointCloud2& cloud, const char* name) {
  return std::any_of(cloud.fields.begin(), cloud.fields.end(),
                     [&](const pcl::PCLPointField& f) { return f.name == name; });
}

template <typename PointT>
void readKittiBin(const std::string& path, pcl::PointCloud<PointT>& cloud) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(path, 0, "cannot open file");
  const std::streamsize bytes = in.tellg();
  if (bytes % (4 * sizeof(float)) != 0)
    throw InputError(path, 0,
                     "truncated KITTI .bin: size " + std::to_string(bytes) +
                         " is not a multiple of 16 bytes (x y z reflectance)");
  in.seekg(0);
  std::vector<float> raw(static_cast<std::size_t>(bytes) / sizeof(float));
  if (!in.read(reinterpret_cast<char*>(raw.data()), bytes))
    throw InputError(path, 0, "could not read the whole file");
  const std::size_t n = raw.size() / 4;
  cloud.clear();
  cloud.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    PointT& p = cloud[i];
    p.x = raw[4 * i];
    p.y = raw[4 * i + 1];
    p.z = raw[4 * i + 2];
    if constexpr (pcl::traits::has_intensity_v<PointT>) p.intensity = raw[4 * i + 3];
  }
  cloud.width = static_cast<std::uint32_t>(n);
  cloud.height = 1;
  cloud.is_dense = false;
  cloud.sensor_origin_ = Eigen::Vector4f(0, 0, 0, 1);
  cloud.sensor_orientation_ = Eigen::Quaternionf::Identity();
}

/** The translation of a PCD's VIEWPOINT line in double precision (PCL parses it into floats,
 * which keep only ~0.5 m of a UTM northing); `fallback` when the header has no readable one. */
Eigen::Vector3d viewpointTranslation(const std::string& path, const Eigen::Vector3d& fallback) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  for (int n = 0; n < 64 && std::getline(in, line); ++n) {
    std::istringstream tokens(line);
    tokens.imbue(std::locale::classic());
    std::string key;
    tokens >> key;
    if (key == "DATA") break;
    if (key != "VIEWPOINT") continue;
    Eigen::Vector3d t;
    if (tokens >> t.x() >> t.y() >> t.z() && t.allFinite()) return t;
    break;
  }
  return fallback;
}

Eigen::Isometry3d isometryFromViewpoint(const std::string& path, const Eigen::Vector4f& origin,
                                        const Eigen::Quaternionf& q) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = q.cast<double>().normalized().toRotationMatrix();
  pose.translation() = viewpointTranslation(path, origin.head<3>().cast<double>());
  return pose;
}

}  // namespace

void sortNumerically(std::vector<std::string>& paths) {
  std::stable_sort(paths.begin(), paths.end(), [](const std::string& a, const std::string& b) {
    const long long na = fileNumber(a), nb = fileNumber(b);
    if (na != nb) return na < nb;
    return a < b;
  });
}

namespace {

/** PCD or PLY file into a blob that has x y z; throws InputError naming the file. */
void readBlob(const std::string& path, pcl::PCLPointCloud2& blob, Eigen::Vector4f& origin,
              Eigen::Quaternionf& orientation) {
  if (hasExtension(path, ".ply")) {
    pcl::PLYReader reader;
    int version = 0, status = -1;
    try {
      status = reader.read(path, blob, origin, orientation, version);
    } catch (const std::exception& e) {
      throw InputError(path, 0, std::string("not a readable PLY file (") + e.what() + ")");
    }
    if (status < 0) throw InputError(path, 0, "not a readable PLY file");
  } else if (hasExtension(path, ".pcd")) {
    readPcdHeader(path, blob, origin, orientation);
    for (const char* f : {"x", "y", "z"})
      if (!hasField(blob, f))
        throw InputError(path, 0, std::string("PCD has no '") + f + "' field");
    pcl::PCDReader reader;
    int pcd_version = 0;
    if (reader.read(path, blob, origin, orientation, pcd_version) < 0)
      throw InputError(path, 0, "could not read PCD data (truncated or malformed file)");
  } else {
    throw InputError(path, 0, "unknown scan format (expected .pcd, .ply or KITTI .bin)");
  }
  for (const char* f : {"x", "y", "z"})
    if (!hasField(blob, f)) throw InputError(path, 0, std::string("scan has no '") + f + "' field");
  if (blob.data.size() < static_cast<std::size_t>(blob.width) * blob.height * blob.point_step)
    throw InputError(path, 0, "truncated point data");
  checkFieldsInsidePoint(path, blob);
}

/** The blob's points as PointT (intensity 0 when the blob has none). */
template <typename PointT>
void blobToCloud(const pcl::PCLPointCloud2& blob, pcl::PointCloud<PointT>& cloud) {
  if (static_cast<std::size_t>(blob.width) * blob.height == 0) {
    // pcl::fromPCLPointCloud2 indexes the first point even of an empty blob: return empty here.
    cloud.clear();
    return;
  }
  if constexpr (pcl::traits::has_intensity_v<PointT>) {
    if (!hasField(blob, "intensity")) {
      // A scan without intensity is still a valid scan: read x y z, intensity 0.
      pcl::PointCloud<pcl::PointXYZ> xyz;
      pcl::fromPCLPointCloud2(blob, xyz);
      cloud.resize(xyz.size());
      for (std::size_t i = 0; i < xyz.size(); ++i) {
        cloud[i].x = xyz[i].x;
        cloud[i].y = xyz[i].y;
        cloud[i].z = xyz[i].z;
        cloud[i].intensity = 0.0f;
      }
      cloud.width = xyz.width;
      cloud.height = xyz.height;
      cloud.is_dense = xyz.is_dense;
      return;
    }
  }
  pcl::fromPCLPointCloud2(blob, cloud);
}

void checkScanFile(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, 0, "file does not exist");
  if (!fs::is_regular_file(path, ec)) throw InputError(path, 0, "not a regular file");
}

}  // namespace

template <typename PointT>
void readScan(const std::string& path, pcl::PointCloud<PointT>& cloud) {
  checkScanFile(path);
  if (hasExtension(path, ".bin")) {
    readKittiBin(path, cloud);
    return;
  }
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  readBlob(path, blob, origin, orientation);
  blobToCloud(blob, cloud);
  cloud.sensor_origin_ = origin;
  cloud.sensor_orientation_ = orientation;
}

void readScanBlob(const std::string& path, pcl::PCLPointCloud2& blob) {
  checkScanFile(path);
  if (hasExtension(path, ".bin")) {
    // x y z intensity, 16 bytes a point as in the file (no padding of pcl::PointXYZI).
    pcl::PointCloud<pcl::PointXYZI> cloud;
    readKittiBin(path, cloud);
    blob = pcl::PCLPointCloud2();
    const char* names[4] = {"x", "y", "z", "intensity"};
    for (std::uint32_t f = 0; f < 4; ++f) {
      pcl::PCLPointField field;
      field.name = names[f];
      field.offset = 4 * f;
      field.datatype = pcl::PCLPointField::FLOAT32;
      field.count = 1;
      blob.fields.push_back(field);
    }
    blob.point_step = 16;
    blob.height = 1;
    blob.width = static_cast<std::uint32_t>(cloud.size());
    blob.row_step = blob.point_step * blob.width;
    blob.is_dense = cloud.is_dense;
    blob.data.resize(cloud.size() * blob.point_step);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const float v[4] = {cloud[i].x, cloud[i].y, cloud[i].z, cloud[i].intensity};
      std::memcpy(&blob.data[i * blob.point_step], v, sizeof(v));
    }
    return;
  }
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  readBlob(path, blob, origin, orientation);
}

bool isScanFile(const std::string& path) {
  return hasExtension(path, ".pcd") || hasExtension(path, ".bin") || hasExtension(path, ".ply");
}

long long frameNumber(const std::string& path) {
  return fileNumber(path);
}

std::vector<Eigen::Isometry3d> readPoses(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open pose file");
  std::vector<Eigen::Isometry3d> poses;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream row(line);
    double v[12];
    int count = 0;
    double x;
    while (row >> x) {
      if (count < 12) v[count] = x;
      ++count;
    }
    if (!row.eof() || count != 12)
      throw InputError(path, line_no,
                       "expected 12 numbers (row-major 3x4 pose), found " +
                           (row.eof() ? std::to_string(count) : "a non-number"));
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = v[4 * r + c];
    for (double value : v)
      if (!std::isfinite(value)) throw InputError(path, line_no, "pose has NaN/Inf entries");
    const Eigen::Matrix3d rtr = pose.linear().transpose() * pose.linear();
    if ((rtr - Eigen::Matrix3d::Identity()).norm() > 1e-3)
      throw InputError(path, line_no, "rotation part is not orthonormal");
    poses.push_back(pose);
  }
  return poses;
}

void writePoses(const std::string& path, const std::vector<Eigen::Isometry3d>& poses) {
  std::ofstream out(path);
  if (!out) throw InputError(path, 0, "cannot write pose file");
  out << std::scientific;
  for (const auto& pose : poses) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) {
        // 10 significant digits, more for geo-referenced translations: at least micrometres
        // (5.432101e6 m needs 13). Values below 10^4 are written as they always were.
        const double v = pose.matrix()(r, c);
        const int exponent = v != 0 ? static_cast<int>(std::floor(std::log10(std::abs(v)))) : 0;
        out << std::setprecision(std::max(9, std::min(16, exponent + 6))) << v
            << ((r == 2 && c == 3) ? '\n' : ' ');
      }
  }
  if (!out) throw InputError(path, 0, "write failed");
}

std::vector<double> readTimes(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open times file");
  std::vector<double> times;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream row(line);
    double t;
    std::string rest;
    if (!(row >> t) || (row >> rest) || !std::isfinite(t))
      throw InputError(path, line_no, "expected one timestamp in seconds");
    if (!times.empty() && t <= times.back())
      throw InputError(path, line_no,
                       "timestamps must increase (got " + std::to_string(t) + " after " +
                           std::to_string(times.back()) + ")");
    times.push_back(t);
  }
  return times;
}

void writeTimes(const std::string& path, const std::vector<double>& times, bool exact) {
  std::ofstream out(path);
  if (!out) throw InputError(path, 0, "cannot write times file");
  out << std::fixed << std::setprecision(6);
  for (const double t : times) {
    if (exact) {  // fixed notation, the fewest decimals that read back to `t`
      char text[400];
      const auto r = std::to_chars(text, text + sizeof(text), t, std::chars_format::fixed);
      if (r.ec == std::errc()) {
        out << std::string_view(text, std::size_t(r.ptr - text)) << '\n';
        continue;
      }
    }
    out << t << '\n';
  }
  if (!out) throw InputError(path, 0, "write failed");
}

namespace {

/** The scan files directly in `folder` (.pcd, .bin or .ply, one format), sorted numerically;
 * empty when there are none. Throws InputError naming the folder when formats are mixed. */
std::vector<std::string> listScans(const fs::path& folder) {
  std::map<std::string, std::vector<std::string>> by_ext;
  for (const char* ext : {".pcd", ".bin", ".ply"}) {
    auto files = listFiles(folder, ext);
    if (!files.empty()) by_ext[ext] = std::move(files);
  }
  if (by_ext.empty()) return {};
  if (by_ext.size() > 1) {
    std::string found;
    for (const auto& kv : by_ext)
      found += (found.empty() ? "" : " and ") + std::to_string(kv.second.size()) + " " + kv.first;
    throw InputError(folder.string(), 0, found + " files: keep one format");
  }
  return by_ext.begin()->second;
}

/** Median spacing of the frame times (0.1 s with fewer than two frames). */
double framePeriod(const std::vector<double>& times) {
  std::vector<double> gaps;
  for (std::size_t i = 1; i < times.size(); ++i) gaps.push_back(times[i] - times[i - 1]);
  if (gaps.empty()) return 0.1;
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  return gaps[gaps.size() / 2];
}

}  // namespace

PoseFormat parsePoseFormat(const std::string& name) {
  if (name == "kitti") return PoseFormat::kitti;
  if (name == "tum") return PoseFormat::tum;
  if (name == "kitti-camera") return PoseFormat::kitti_camera;
  throw InputError("--poses-format: '" + name + "' is not one of kitti, tum, kitti-camera");
}

std::vector<StampedPose> readTumPoses(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open pose file");
  std::vector<StampedPose> poses;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream row(line);
    double v[8];
    int count = 0;
    for (double x; count < 9 && row >> x; ++count)
      if (count < 8) v[count] = x;
    std::string rest;
    if (count != 8 || !(row.eof() || (row.clear(), !(row >> rest))))
      throw InputError(path, line_no, "expected 8 numbers: timestamp x y z qx qy qz qw (TUM)");
    for (const double value : v)
      if (!std::isfinite(value)) throw InputError(path, line_no, "pose has NaN/Inf entries");
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > 1e-3)
      throw InputError(path, line_no, "quaternion qx qy qz qw is not of unit length");
    if (!poses.empty() && v[0] <= poses.back().time)
      throw InputError(path, line_no, "timestamps must increase");
    StampedPose p{v[0], Eigen::Isometry3d::Identity()};
    p.pose.linear() = q.normalized().toRotationMatrix();
    p.pose.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    poses.push_back(p);
  }
  if (poses.empty()) throw InputError(path, 0, "no poses in the file");
  return poses;
}

Eigen::Isometry3d readKittiCalibTr(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open calibration file");
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream row(line);
    std::string key;
    if (!(row >> key) || (key != "Tr:" && key != "Tr_velo_to_cam:" && key != "Tr_velo_cam:"))
      continue;
    double v[12];
    for (double& x : v)
      if (!(row >> x) || !std::isfinite(x))
        throw InputError(path, line_no, "expected 12 numbers after " + key);
    Eigen::Isometry3d tr = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) tr.matrix()(r, c) = v[4 * r + c];
    if ((tr.linear().transpose() * tr.linear() - Eigen::Matrix3d::Identity()).norm() > 1e-3)
      throw InputError(path, line_no, "rotation part of " + key + " is not orthonormal");
    return tr;
  }
  throw InputError(path, 0, "no 'Tr:' row (velodyne to camera 0) in the calibration file");
}

std::vector<Eigen::Isometry3d> cameraToVelodynePoses(const std::vector<Eigen::Isometry3d>& cam,
                                                     const Eigen::Isometry3d& tr) {
  std::vector<Eigen::Isometry3d> velo;
  velo.reserve(cam.size());
  const Eigen::Isometry3d tr_inv = tr.inverse();
  for (const auto& p : cam) velo.push_back(tr_inv * p * tr);
  return velo;
}

std::vector<Eigen::Isometry3d> posesAtTimes(const std::vector<StampedPose>& stamped,
                                            const std::vector<double>& times,
                                            const std::string& path, double tolerance) {
  std::vector<Eigen::Isometry3d> out;
  for (std::size_t i = 0; i < times.size(); ++i) {
    const double t = times[i];
    const auto after =
        std::lower_bound(stamped.begin(), stamped.end(), t,
                         [](const StampedPose& p, double time) { return p.time < time; });
    const bool has_after = after != stamped.end(), has_before = after != stamped.begin();
    const double d_after = has_after ? after->time - t : INFINITY;
    const double d_before = has_before ? t - std::prev(after)->time : INFINITY;
    const double nearest = std::min(d_after, d_before);
    if (!(nearest <= tolerance)) {
      std::ostringstream why;
      why << std::setprecision(10) << "no pose for frame " << i << " at time " << t
          << " s: the nearest pose is at " << (d_after < d_before ? after->time : t - d_before)
          << " s, more than " << std::setprecision(3) << tolerance << " s away";
      throw InputError(path, 0, why.str());
    }
    if (!has_after || !has_before || d_after == 0.0) {
      out.push_back(d_after <= d_before ? after->pose : std::prev(after)->pose);
      continue;
    }
    const StampedPose& a = *std::prev(after);
    const double s = d_before / (after->time - a.time);
    const Eigen::Quaterniond qa(a.pose.linear()), qb(after->pose.linear());
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = qa.slerp(s, qb).toRotationMatrix();
    pose.translation() = (1 - s) * a.pose.translation() + s * after->pose.translation();
    out.push_back(pose);
  }
  return out;
}

void SequenceReader::open(const std::string& folder, double rate_hz) {
  SequenceOptions options;
  options.rate_hz = rate_hz;
  open(folder, options);
}

void SequenceReader::open(const std::string& folder, const SequenceOptions& options) {
  folder_ = folder;
  frame_paths_.clear();
  poses_.clear();
  times_.clear();
  pose_source_ = "none";
  has_times_ = false;
  std::error_code ec;
  if (!fs::exists(folder, ec)) throw InputError(folder, 0, "sequence folder does not exist");
  if (!fs::is_directory(folder, ec))
    throw InputError(folder, 0,
                     isScanFile(folder) ? "is a scan file; a sequence folder is expected (the "
                                          "folder holding it, or frames/ or velodyne/ beside it)"
                                        : "not a folder");
  const fs::path root(folder);
  for (const fs::path& where : {root / "frames", root, root / "velodyne"}) {
    frame_paths_ = listScans(where);
    if (!frame_paths_.empty()) break;
  }
  if (frame_paths_.empty())
    throw InputError(folder, 0,
                     "no frames (expected .pcd, .bin or .ply scans in the folder, in frames/ or "
                     "in velodyne/)");
  loadTimes(options.rate_hz);
  if (options.load_poses) loadPoses(options);
}

void SequenceReader::loadTimes(double rate_hz) {
  std::error_code ec;
  const std::string times_path = (fs::path(folder_) / "times.txt").string();
  if (fs::exists(times_path, ec)) {
    times_ = io::readTimes(times_path);
    if (times_.size() != frame_paths_.size())
      throw InputError(times_path, 0,
                       "has " + std::to_string(times_.size()) +
                           " timestamps but the sequence has " +
                           std::to_string(frame_paths_.size()) + " frames");
    has_times_ = true;
    return;
  }
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
    throw InputError("--rate: must be positive, got " + std::to_string(rate_hz));
  for (std::size_t i = 0; i < frame_paths_.size(); ++i) times_.push_back(double(i) / rate_hz);
}

void SequenceReader::loadPoses(const SequenceOptions& options) {
  std::error_code ec;
  if (!options.poses_path.empty()) {
    loadPoseFile(options);
    return;
  }
  const std::string poses_path = (fs::path(folder_) / "poses.txt").string();
  if (fs::exists(poses_path, ec)) {
    poses_ = io::readPoses(poses_path);
    checkPoseCount(poses_path);
    pose_source_ = "poses.txt";
  } else if (hasExtension(frame_paths_.front(), ".pcd")) {
    pcl::PCLPointCloud2 header;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    readPcdHeader(frame_paths_.front(), header, origin, orientation);
    if (!isIdentityViewpoint(origin, orientation)) {
      for (const auto& path : frame_paths_) {
        readPcdHeader(path, header, origin, orientation);
        poses_.push_back(isometryFromViewpoint(path, origin, orientation));
      }
      pose_source_ = "viewpoint";
    }
  }
}

void SequenceReader::loadPoseFile(const SequenceOptions& options) {
  const std::string& path = options.poses_path;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, 0, "--poses: file does not exist");
  switch (options.poses_format) {
    case PoseFormat::kitti:
      poses_ = io::readPoses(path);
      pose_source_ = path + " (kitti)";
      break;
    case PoseFormat::kitti_camera:
      if (options.calib_path.empty())
        throw InputError("--poses-format kitti-camera needs --calib FILE (KITTI calib.txt)");
      poses_ = cameraToVelodynePoses(io::readPoses(path), readKittiCalibTr(options.calib_path));
      pose_source_ = path + " (kitti-camera, " + options.calib_path + ")";
      break;
    case PoseFormat::tum: {
      const auto stamped = readTumPoses(path);
      if (stamped.size() == frame_paths_.size()) {
        for (const auto& p : stamped) poses_.push_back(p.pose);
      } else {
        poses_ = posesAtTimes(stamped, times_, path, 0.5 * framePeriod(times_));
      }
      pose_source_ = path + " (tum)";
      break;
    }
  }
  checkPoseCount(path);
}

void SequenceReader::checkPoseCount(const std::string& path) const {
  if (poses_.size() != frame_paths_.size())
    throw InputError(path, 0,
                     "has " + std::to_string(poses_.size()) + " poses but the sequence has " +
                         std::to_string(frame_paths_.size()) + " frames");
}

long long SequenceReader::frameNumber(std::size_t i) const {
  const long long n = fileNumber(frame_paths_.at(i));
  return n >= 0 ? n : static_cast<long long>(i);
}

std::string SequenceReader::frameName(std::size_t i) const {
  return fs::path(frame_paths_.at(i)).stem().string();
}

Eigen::Isometry3d SequenceReader::pose(std::size_t i) const {
  if (poses_.empty()) return Eigen::Isometry3d::Identity();
  return poses_.at(i);
}

std::string SequenceReader::objectsPath() const {
  const fs::path p = fs::path(folder_) / "objects.txt";
  std::error_code ec;
  return fs::exists(p, ec) ? p.string() : std::string();
}

std::string SequenceReader::labelPath(std::size_t i) const {
  const fs::path p = fs::path(folder_) / "labels" / (frameName(i) + ".label");
  std::error_code ec;
  return fs::exists(p, ec) ? p.string() : std::string();
}

bool isMissingOrEmptyDirectory(const std::string& folder) {
  std::error_code ec;
  if (!fs::exists(folder, ec)) return true;
  return fs::is_directory(folder, ec) && fs::is_empty(folder, ec);
}

void prepareOutputDirectory(const std::string& folder, bool overwrite) {
  std::error_code ec;
  if (fs::exists(folder, ec) && !fs::is_directory(folder, ec))
    throw InputError(folder, 0, "output exists and is not a folder");
  if (!isMissingOrEmptyDirectory(folder) && !overwrite)
    throw InputError(folder, 0, "output folder exists and is not empty (use --overwrite)");
  fs::create_directories(folder, ec);
  if (ec) throw InputError(folder, 0, "cannot create output folder: " + ec.message());
  const fs::path probe = fs::path(folder) / ".pcl_movers_write_probe";
  {
    std::ofstream out(probe);
    if (!out) throw InputError(folder, 0, "output folder is not writable");
  }
  fs::remove(probe, ec);
}

SequenceWriter::SequenceWriter(const std::string& folder, bool overwrite) : folder_(folder) {
  prepareOutputDirectory(folder, overwrite);
  std::error_code ec;
  fs::create_directories(framesFolder(), ec);
  if (ec) throw InputError(framesFolder(), 0, "cannot create folder: " + ec.message());
}

namespace {

/** Writes `cloud` as frames/NNNNNN.pcd of `writer` (binary) under a temporary name, then renames
 * it, so an interrupted run never leaves a half file. Returns the path. */
template <typename PointT>
std::string saveFrame(const SequenceWriter& writer, std::size_t index,
                      const pcl::PointCloud<PointT>& cloud) {
  std::ostringstream name;
  name << std::setw(6) << std::setfill('0') << index << ".pcd";
  const std::string path = (fs::path(writer.framesFolder()) / name.str()).string();
  const std::string tmp = path + ".tmp";
  if (pcl::io::savePCDFileBinary(tmp, cloud) < 0) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot write PCD");
  }
  fs::rename(tmp, path);
  return path;
}

}  // namespace

template <typename PointT>
std::string SequenceWriter::writeFrame(std::size_t index,
                                       const pcl::PointCloud<PointT>& cloud) const {
  return saveFrame(*this, index, cloud);
}

std::string SequenceWriter::writeFrame(std::size_t index,
                                       const pcl::PointCloud<pcl::PointXYZI>& cloud,
                                       const std::vector<float>& times) const {
  if (times.size() != cloud.size())
    throw InputError(framesFolder(), 0,
                     "frame " + std::to_string(index) + ": " + std::to_string(times.size()) +
                         " point times for " + std::to_string(cloud.size()) + " points");
  pcl::PointCloud<detail::PointXYZIT> out;
  out.width = cloud.width;
  out.height = cloud.height;
  out.is_dense = cloud.is_dense;
  out.sensor_origin_ = cloud.sensor_origin_;
  out.sensor_orientation_ = cloud.sensor_orientation_;
  out.points.resize(cloud.size());
  for (std::size_t k = 0; k < cloud.size(); ++k) {
    detail::PointXYZIT& p = out.points[k];
    p.x = cloud.points[k].x;
    p.y = cloud.points[k].y;
    p.z = cloud.points[k].z;
    p.intensity = cloud.points[k].intensity;
    p.time = times[k];
  }
  return saveFrame(*this, index, out);
}

void SequenceWriter::writePoses(const std::vector<Eigen::Isometry3d>& poses) const {
  io::writePoses((fs::path(folder_) / "poses.txt").string(), poses);
}

void SequenceWriter::writeTimes(const std::vector<double>& times, bool exact) const {
  io::writeTimes((fs::path(folder_) / "times.txt").string(), times, exact);
}

#define PCL_MOVERS_INSTANTIATE_SEQUENCE_IO(T)                         \
  template void readScan<T>(const std::string&, pcl::PointCloud<T>&); \
  template std::string SequenceWriter::writeFrame<T>(std::size_t, const pcl::PointCloud<T>&) const;
PCL_MOVERS_INSTANTIATE_SEQUENCE_IO(pcl::PointXYZ)
PCL_MOVERS_INSTANTIATE_SEQUENCE_IO(pcl::PointXYZI)
PCL_MOVERS_INSTANTIATE_SEQUENCE_IO(pcl::PointXYZL)
PCL_MOVERS_INSTANTIATE_SEQUENCE_IO(pcl::PointXYZRGB)
PCL_MOVERS_INSTANTIATE_SEQUENCE_IO(pcl::PointXYZRGBL)
PCL_MOVERS_INSTANTIATE_SEQUENCE_IO(pcl::PointXYZINormal)
#undef PCL_MOVERS_INSTANTIATE_SEQUENCE_IO

}  // namespace io
}  // namespace pcl_movers
