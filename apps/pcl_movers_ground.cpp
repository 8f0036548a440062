/*
 * pcl_movers_ground — ground removal (GroundPlaneFilter) on a scan or a folder of scans.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/sensor_model.h>

#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>

#include "tool_utils.h"

namespace fs = std::filesystem;
using pcl_movers::InputError;
using Point = pcl::PointXYZI;
using Cloud = pcl::PointCloud<Point>;

namespace {

struct Options {
  pcl_movers::tools::StageOptions<pcl_movers::GroundParameters> ground =
      pcl_movers::tools::groundOptions();
  std::string sensor = "auto";
  std::string mode = "label";
  bool overwrite = false;
};

pcl_movers::tools::OptionTable optionTable() {
  const Options d;
  pcl_movers::tools::OptionTable table({{"--mode", "M", "label, nonground or ground", d.mode},
                                        {"--sensor", "NAME",
                                         "beam layout that organizes unorganized scans for the "
                                         "local-slope test:\nauto (estimated), hdl64, hdl32, "
                                         "vlp16, os1_64, ladar2d",
                                         d.sensor},
                                        {"--overwrite", "", "replace existing output files"}});
  table.add(d.ground.options());
  return table;
}

void printHelp(const char* argv0) {
  std::printf(
      "Usage: %s INPUT OUTPUT [options]\n"
      "  Finds the ground of LiDAR scans with local, roughly horizontal planes fitted by RANSAC "
      "in\n"
      "  polar cells (pcl_movers::GroundPlaneFilter). INPUT is a .pcd or KITTI .bin scan, or a\n"
      "  sequence folder (frames/*.pcd, *.pcd or velodyne/*.bin); OUTPUT is then a .pcd file, or "
      "a\n"
      "  folder that receives one NNNNNN.pcd per frame. Points are in the sensor frame (z up); "
      "the\n"
      "  PCD VIEWPOINT origin is taken as the sensor position. Organized and unorganized scans "
      "work:\n  unorganized ones are organized into a range image first (--sensor), as the "
      "detector does,\n  so that the local-slope test has beam neighbours.\n\n"
      "Output (--mode):\n"
      "  label      (default) every input point in the input's order and layout, fields of the\n"
      "             input plus `label` (uint32): 1 = ground, 0 = not ground or invalid (NaN)\n"
      "  nonground  only the non-ground points (organized input stays organized, NaN elsewhere)\n"
      "  ground     only the ground points (same layout rule)\n\n"
      "Options (-h, --help: this help):\n%s",
      argv0, optionTable().help().c_str());
}

using pcl_movers::tools::labelledBlob;
using pcl_movers::tools::parseNumber;
using pcl_movers::tools::readScanChecked;
using pcl_movers::tools::writeAtomically;

/** 1 for the ground points of `cloud`. Unorganized scans are organized first, as MoverDetector
 * does, so that the local-slope test has beam neighbours; the few points the range image has no
 * cell for (a nearer return took it) keep the plane-distance test of a pass over the raw scan. */
std::vector<std::uint8_t> groundOf(const Cloud::Ptr& cloud, const Options& opt) {
  std::vector<std::uint8_t> is_ground(cloud->size(), 0);
  auto groundIndices = [&](const Cloud::Ptr& input) {
    pcl_movers::GroundPlaneFilter<Point> filter;
    filter.setParameters(opt.ground.parameters);
    filter.setInputCloud(input);
    filter.setNegative(true);
    pcl::Indices ground;
    filter.filter(ground);
    return ground;
  };
  if (cloud->isOrganized() || !opt.ground.parameters.local_slope) {
    for (const auto i : groundIndices(cloud)) is_ground[i] = 1;
    return is_ground;
  }
  pcl_movers::RangeImageOrganizer<Point> organizer;
  if (opt.sensor != "auto") organizer.setSensorModel(pcl_movers::SensorModel::fromName(opt.sensor));
  organizer.setInputCloud(cloud);
  Cloud::Ptr image(new Cloud);
  try {
    organizer.organize(*image);
  } catch (const InputError& e) {
    if (opt.sensor != "auto") throw;
    // Too few returns to estimate the beam layout: no beam neighbours to test slopes with.
    pcl::console::print_warn("%s; the local-slope test is skipped for this scan\n", e.what());
    for (const auto i : groundIndices(cloud)) is_ground[i] = 1;
    return is_ground;
  }
  const std::vector<int>& cell = organizer.getCellOfPoint();
  bool unplaced = false;
  for (std::size_t i = 0; i < cloud->size(); ++i) unplaced = unplaced || cell[i] < 0;
  if (unplaced)
    for (const auto i : groundIndices(cloud)) is_ground[i] = 1;
  const std::vector<int>& index_image = organizer.getIndexImage();
  std::vector<std::uint8_t> image_ground(image->size(), 0);
  for (const auto c : groundIndices(image)) image_ground[c] = 1;
  for (std::size_t c = 0; c < image->size(); ++c)
    if (index_image[c] >= 0) is_ground[index_image[c]] = image_ground[c];
  return is_ground;
}

void processOne(const std::string& in, const std::string& out, const Options& opt,
                std::size_t& selected_total, std::size_t& points_total, double& ms_total) {
  const Cloud::Ptr cloud = readScanChecked(in);
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<std::uint8_t> is_ground = groundOf(cloud, opt);
  ms_total +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  points_total += cloud->size();
  pcl::PCLPointCloud2 blob;
  if (opt.mode == "label") {
    std::vector<std::uint32_t> labels(is_ground.begin(), is_ground.end());
    for (const auto g : is_ground) selected_total += g;
    labelledBlob(*cloud, labels, blob);
  } else {
    // The selected points; organized input keeps its layout with NaN elsewhere.
    const bool want_ground = opt.mode == "ground";
    const float nan = std::numeric_limits<float>::quiet_NaN();
    Cloud result;
    result.header = cloud->header;
    result.sensor_origin_ = cloud->sensor_origin_;
    result.sensor_orientation_ = cloud->sensor_orientation_;
    for (std::size_t i = 0; i < cloud->size(); ++i) {
      const Point& p = (*cloud)[i];
      const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
      const bool selected = finite && (is_ground[i] != 0) == want_ground;
      if (selected) ++selected_total;
      if (selected) {
        result.push_back(p);
      } else if (cloud->isOrganized()) {
        Point q = p;
        q.x = q.y = q.z = nan;
        result.push_back(q);
      }
    }
    if (cloud->isOrganized()) {
      result.width = cloud->width;
      result.height = cloud->height;
      result.is_dense = false;
    }
    writeAtomically(out, [&](pcl::PCDWriter& w, const std::string& path) {
      return w.writeBinary(path, result);
    });
    return;
  }
  writeAtomically(out, [&](pcl::PCDWriter& w, const std::string& path) {
    return w.writeBinary(path, blob, cloud->sensor_origin_, cloud->sensor_orientation_);
  });
}

int run(int argc, char** argv) {
  const auto args = optionTable().parse(argc, argv);
  const auto& positional = args.positional;
  if (positional.size() != 2)
    throw InputError("expected INPUT and OUTPUT, got " + std::to_string(positional.size()) +
                     " argument(s); see -h");
  Options opt;
  opt.overwrite = args.has("--overwrite");
  std::string v;
  if (args.get("--mode", v)) {
    if (v != "label" && v != "nonground" && v != "ground")
      throw InputError("--mode: expected label, nonground or ground, got '" + v + "'");
    opt.mode = v;
  }
  opt.ground.parse(args);
  if (args.get("--sensor", v)) {
    if (v != "auto") pcl_movers::SensorModel::fromName(v);  // throws InputError on a bad name
    opt.sensor = v;
  }

  const std::string& input = positional[0];
  const std::string& output = positional[1];
  const auto inputs = pcl_movers::tools::listScanInputs(input);
  pcl_movers::tools::OutputCleanup cleanup(output);
  const std::vector<std::string> outputs =
      pcl_movers::tools::planScanOutputs(input, inputs, output, opt.overwrite);
  std::size_t ground = 0, points = 0;
  double ms = 0;
  pcl_movers::tools::ProgressBar bar(inputs.size());
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    processOne(inputs[i], outputs[i], opt, ground, points, ms);
    cleanup.track(outputs[i]);
    bar.update(i + 1);
  }
  bar.finish();
  cleanup.commit();
  pcl::console::print_info("%zu scan(s), %zu points, %zu %s, %.2f ms per scan -> %s\n",
                           inputs.size(), points, ground,
                           opt.mode == "nonground" ? "non-ground" : "ground",
                           ms / double(inputs.size()), output.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  return pcl_movers::tools::runTool("pcl_movers_ground", [&] { return run(argc, argv); });
}
