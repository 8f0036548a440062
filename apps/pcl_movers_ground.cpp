/*
 * pcl_movers_ground — ground removal (GroundPlaneFilter) on a scan or a folder of scans.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>

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

#include "tool_utils.h"

namespace fs = std::filesystem;
using pcl_movers::InputError;
using Point = pcl::PointXYZI;
using Cloud = pcl::PointCloud<Point>;

namespace {

struct Options {
  pcl_movers::tools::GroundOptions ground;
  std::string mode = "label";
  bool overwrite = false;
};

pcl_movers::tools::OptionTable optionTable() {
  const Options d;
  pcl_movers::tools::OptionTable table({{"--mode", "M", "label, nonground or ground", d.mode},
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
      "work.\n\n"
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

void processOne(const std::string& in, const std::string& out, const Options& opt,
                std::size_t& selected_total, std::size_t& points_total, double& ms_total) {
  const Cloud::Ptr cloud = readScanChecked(in);
  // extract_removed_indices = true: keep-organized output needs them (PCL warns otherwise).
  pcl_movers::GroundPlaneFilter<Point> filter(true);
  opt.ground.applyTo(filter);
  filter.setInputCloud(cloud);
  pcl::PCLPointCloud2 blob;
  const auto t0 = std::chrono::steady_clock::now();
  if (opt.mode == "label") {
    filter.setNegative(true);
    pcl::Indices ground;
    filter.filter(ground);
    ms_total +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    selected_total += ground.size();
    std::vector<std::uint32_t> labels(cloud->size(), 0);
    for (const auto i : ground) labels[i] = 1;
    labelledBlob(*cloud, labels, blob);
  } else {
    filter.setNegative(opt.mode == "ground");
    filter.setKeepOrganized(cloud->isOrganized());
    Cloud result;
    filter.filter(result);
    ms_total +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::size_t finite = 0;
    for (const auto& p : result) finite += std::isfinite(p.x);
    selected_total += finite;
    points_total += cloud->size();
    writeAtomically(out, [&](pcl::PCDWriter& w, const std::string& path) {
      return w.writeBinary(path, result);
    });
    return;
  }
  points_total += cloud->size();
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
