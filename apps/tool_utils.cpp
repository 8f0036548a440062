/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include "tool_utils.h"

#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>

#include <unistd.h>
#include <algorithm>
#include <cerrno>
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

std::string kebab(std::string name) {
  std::replace(name.begin(), name.end(), '_', '-');
  return name;
}

}  // namespace

bool Arguments::get(const std::string& name, std::string& value) const {
  const auto it = given.find(name);
  if (it == given.end()) return false;
  value = it->second;
  return true;
}

double Arguments::number(const std::string& name, double fallback) const {
  std::string v;
  return get(name, v) ? parseNumber(name, v) : fallback;
}

std::vector<std::string> Arguments::all(const std::string& name) const {
  std::vector<std::string> values;
  for (const auto& option : list)
    if (option.first == name) values.push_back(option.second);
  return values;
}

void OptionTable::add(const std::vector<Option>& options) {
  options_.insert(options_.end(), options.begin(), options.end());
}

const Option* OptionTable::find(const std::string& name) const {
  for (const auto& o : options_)
    if (!o.name.empty() && o.name == name) return &o;
  return nullptr;
}

Arguments OptionTable::parse(int argc, char** argv) const {
  Arguments args;
  const std::string tool = argc > 0 ? fs::path(argv[0]).filename().string() : "tool";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.size() < 2 || arg[0] != '-' || isNumber(arg)) {
      args.positional.push_back(arg);
      continue;
    }
    if (arg == "-h" || arg == "--help") {
      args.given["--help"] = "";
      continue;
    }
    const Option* option = find(arg);
    for (std::size_t k = 0; !option && k < options_.size(); ++k) {
      const auto& aliases = options_[k].aliases;
      if (kebab(arg) == options_[k].name ||
          std::find(aliases.begin(), aliases.end(), arg) != aliases.end())
        option = &options_[k];
    }
    if (!option) throw InputError("unknown option " + arg + " (see -h)");
    if (arg != option->name)
      std::fprintf(stderr, "[%s] warning: %s is deprecated, use %s\n", tool.c_str(), arg.c_str(),
                   option->name.c_str());
    if (!option->value.empty() && i + 1 >= argc)
      throw InputError("option " + arg + " needs a value " + option->value);
    const std::string value = option->value.empty() ? "" : argv[++i];
    args.given[option->name] = value;
    args.list.emplace_back(option->name, value);
  }
  return args;
}

std::string OptionTable::help() const {
  std::size_t width = 0;
  auto left = [](const Option& o) {
    return "  " + o.name + (o.value.empty() ? "" : " " + o.value);
  };
  for (const auto& o : options_)
    if (!o.name.empty() && left(o).size() < 34) width = std::max(width, left(o).size());
  std::string out;
  for (const auto& o : options_) {
    if (o.name.empty()) {
      out += o.help + "\n";
      continue;
    }
    std::string line = left(o);
    line.resize(std::max(line.size() + 1, width + 2), ' ');
    std::string text = o.help + (o.def.empty() ? "" : " (default: " + o.def + ")");
    for (std::size_t nl = text.find('\n'); nl != std::string::npos; nl = text.find('\n', nl + 1))
      text.insert(nl + 1, width + 2, ' ');
    out += line + text + "\n";
  }
  return out;
}

std::string str(double value, int digits) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.*g", digits, value);
  return text;
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
  const fs::path folder = fs::path(path).parent_path();
  std::error_code ec;
  if (!folder.empty() && !fs::is_directory(folder, ec))
    throw InputError(path, 0, "cannot write: no folder " + folder.string());
  pcl::PCDWriter writer;
  int status = -1;
  std::string why;
  errno = 0;
  try {  // PCL throws "Error during open!" naming no file: name it here
    status = write(writer, tmp);
  } catch (const std::exception& e) {
    why = std::string(" (") + (errno ? std::strerror(errno) : e.what()) + ")";
  }
  if (status != 0) {
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot write" + why);
  }
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
