/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include "tool_utils.h"

#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace fs = std::filesystem;

namespace pcl_movers {
namespace tools {
namespace {

bool isNumber(const std::string& s) {
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return end && *end == '\0' && !s.empty();
}

bool contains(const std::vector<std::string>& list, const std::string& s) {
  return std::find(list.begin(), list.end(), s) != list.end();
}

}  // namespace

void checkArguments(int argc, char** argv, const std::vector<std::string>& flags,
                    const std::vector<std::string>& with_value) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.size() < 2 || arg[0] != '-' || isNumber(arg)) continue;
    if (contains(with_value, arg)) {
      if (i + 1 >= argc) throw InputError("option " + arg + " needs a value");
      ++i;
      continue;
    }
    if (!contains(flags, arg) && arg != "-h" && arg != "--help")
      throw InputError("unknown option " + arg + " (see -h)");
  }
}

std::vector<std::string> positionalArguments(int argc, char** argv,
                                             const std::vector<std::string>& with_value) {
  std::vector<std::string> out;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.size() >= 2 && arg[0] == '-' && !isNumber(arg)) {
      if (contains(with_value, arg)) ++i;
      continue;
    }
    out.push_back(arg);
  }
  return out;
}

std::vector<std::string> listScanInputs(const std::string& file_or_folder) {
  std::error_code ec;
  if (!fs::exists(file_or_folder, ec)) throw InputError(file_or_folder, 0, "does not exist");
  if (fs::is_directory(file_or_folder, ec)) {
    io::SequenceOptions options;
    options.load_poses = false;  // only the frames are needed: a bad poses.txt does not matter
    return io::SequenceReader(file_or_folder, options).framePaths();
  }
  if (!io::isScanFile(file_or_folder))
    throw InputError(file_or_folder, 0, "unknown scan format (expected .pcd, .ply or KITTI .bin)");
  return {file_or_folder};
}

double parseNumber(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v))
    throw InputError(flag + ": expected a number, got '" + text + "'");
  return v;
}

GroundOptions::GroundOptions() {
  const GroundPlaneFilter<pcl::PointXYZ> defaults;
  distance = defaults.getDistanceThreshold();
  tilt_deg = defaults.getMaxTilt() * 180.f / float(M_PI);
  sensor_height = defaults.getSensorHeight();
  sectors = defaults.getNumSectors();
}

std::vector<std::string> GroundOptions::flags() {
  return {"--distance", "--tilt-deg", "--sensor-height", "--sectors"};
}

void GroundOptions::parse(int argc, char** argv) {
  std::string v;
  if (pcl::console::parse_argument(argc, argv, "--distance", v) >= 0) {
    distance = static_cast<float>(parseNumber("--distance", v));
    if (!(distance > 0)) throw InputError("--distance: must be > 0, got '" + v + "'");
  }
  if (pcl::console::parse_argument(argc, argv, "--tilt-deg", v) >= 0) {
    tilt_deg = static_cast<float>(parseNumber("--tilt-deg", v));
    if (tilt_deg < 0 || tilt_deg >= 90)
      throw InputError("--tilt-deg: must be in [0, 90), got '" + v + "'");
  }
  if (pcl::console::parse_argument(argc, argv, "--sensor-height", v) >= 0) {
    sensor_height = static_cast<float>(parseNumber("--sensor-height", v));
    if (sensor_height < 0) throw InputError("--sensor-height: must be >= 0, got '" + v + "'");
  }
  if (pcl::console::parse_argument(argc, argv, "--sectors", v) >= 0) {
    const double s = parseNumber("--sectors", v);
    if (s < 1 || s > 4096 || s != std::floor(s))
      throw InputError("--sectors: expected an integer in 1..4096, got '" + v + "'");
    sectors = static_cast<int>(s);
  }
}

void GroundOptions::applyTo(GroundPlaneFilter<pcl::PointXYZI>& filter) const {
  filter.setDistanceThreshold(distance);
  filter.setMaxTilt(tilt_deg * float(M_PI) / 180.f);
  filter.setSensorHeight(sensor_height);
  filter.setNumSectors(sectors);
}

std::string GroundOptions::help() const {
  char text[512];
  std::snprintf(text, sizeof(text),
                "  --distance M       ground if within M metres of its cell's plane (default %g)\n"
                "  --tilt-deg D       steepest plane taken for ground [deg] (default %.3g)\n"
                "  --sensor-height M  sensor height above the ground under it [m] (default %g)\n"
                "  --sectors N        azimuth sectors of the polar cells (default %d)\n",
                distance, tilt_deg, sensor_height, sectors);
  return text;
}

pcl::PointCloud<pcl::PointXYZI>::Ptr readScanChecked(const std::string& path) {
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZI>>();
  io::readScan(path, *cloud);
  if (cloud->empty()) throw InputError(path, 0, "the cloud is empty");
  std::size_t finite = 0, nan = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const auto& p = (*cloud)[i];
    if (std::isinf(p.x) || std::isinf(p.y) || std::isinf(p.z))
      throw InputError(path, 0, "point " + std::to_string(i) + " has an infinite coordinate");
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
      ++finite;
    else
      ++nan;
  }
  if (finite == 0) throw InputError(path, 0, "no finite point (all NaN)");
  if (nan > 0 && !cloud->isOrganized())
    pcl::console::print_warn("%s: %zu NaN point(s) in an unorganized cloud are left out\n",
                             path.c_str(), nan);
  return cloud;
}

void labelledBlob(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                  const std::vector<std::uint32_t>& labels, pcl::PCLPointCloud2& blob) {
  blob = pcl::PCLPointCloud2();
  blob.header = cloud.header;
  blob.width = cloud.width;
  blob.height = cloud.height;
  blob.is_dense = cloud.is_dense;
  const char* names[] = {"x", "y", "z", "intensity", "label"};
  for (int f = 0; f < 5; ++f) {
    pcl::PCLPointField field;
    field.name = names[f];
    field.offset = 4 * f;
    field.datatype = f < 4 ? pcl::PCLPointField::FLOAT32 : pcl::PCLPointField::UINT32;
    field.count = 1;
    blob.fields.push_back(field);
  }
  blob.point_step = 20;
  blob.row_step = blob.point_step * blob.width;
  blob.data.resize(std::size_t(blob.point_step) * cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    std::uint8_t* dst = &blob.data[i * blob.point_step];
    const float xyzi[4] = {cloud[i].x, cloud[i].y, cloud[i].z, cloud[i].intensity};
    std::memcpy(dst, xyzi, sizeof(xyzi));
    std::memcpy(dst + 16, &labels[i], sizeof(std::uint32_t));
  }
}

void writeAtomically(const std::string& path,
                     const std::function<int(pcl::PCDWriter&, const std::string&)>& write) {
  const std::string tmp = path + ".tmp";
  pcl::PCDWriter writer;
  if (write(writer, tmp) != 0) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot write");
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot write (" + ec.message() + ")");
  }
}

std::vector<std::string> planScanOutputs(const std::string& input,
                                         const std::vector<std::string>& inputs,
                                         const std::string& output, bool overwrite) {
  std::vector<std::string> outputs;
  if (fs::is_directory(input)) {
    io::prepareOutputDirectory(output, overwrite);
    for (const auto& path : inputs)
      outputs.push_back((fs::path(output) / fs::path(path).stem()).string() + ".pcd");
  } else {
    if (fs::is_directory(output))
      throw InputError(output, 0, "is a folder; give an output .pcd file for a single scan");
    if (fs::exists(output) && !overwrite)
      throw InputError(output, 0, "exists (use --overwrite to replace it)");
    outputs.push_back(output);
  }
  return outputs;
}

int runTool(const char* tool_name, const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& e) {
    pcl::console::print_error("[%s] error: %s\n", tool_name, e.what());
  } catch (const std::exception& e) {
    pcl::console::print_error("[%s] error: %s\n", tool_name, e.what());
  } catch (...) {
    pcl::console::print_error("[%s] error: unknown failure\n", tool_name);
  }
  return 1;
}

OutputCleanup::OutputCleanup(std::string output)
    : output_(std::move(output)), existed_(fs::exists(output_)) {}

OutputCleanup::~OutputCleanup() {
  if (committed_) return;
  std::error_code ec;
  for (const auto& path : written_) fs::remove(path, ec);
  if (!existed_) fs::remove_all(output_, ec);
}

ProgressBar::ProgressBar(std::size_t total, std::string unit, bool force)
    : total_(total), unit_(std::move(unit)), enabled_(force || isatty(STDERR_FILENO)) {}

void ProgressBar::update(std::size_t done) {
  if (!enabled_ || total_ == 0) return;
  const int width = 30;
  const int filled = static_cast<int>(width * std::min(done, total_) / total_);
  std::string bar(static_cast<std::size_t>(filled), '=');
  if (filled < width) bar += '>';
  bar.resize(width, ' ');
  std::fprintf(stderr, "\r[%s] %zu/%zu %s", bar.c_str(), done, total_, unit_.c_str());
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (!enabled_) return;
  update(total_);
  std::fprintf(stderr, "\n");
}

}  // namespace tools
}  // namespace pcl_movers
