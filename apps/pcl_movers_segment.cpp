/*
 * pcl_movers_segment — object segmentation of LiDAR scans: ground removal (GroundPlaneFilter),
 * range image (RangeImageOrganizer, for unorganized scans) and region growing in angle-depth
 * space (RangeImageRegionGrowing). Writes one label per input point.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/range_image_region_growing.h>

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
  pcl_movers::tools::StageOptions<pcl_movers::SegmentationParameters> segment =
      pcl_movers::tools::segmentationOptions();
  bool keep_ground = false;
  std::string sensor = "hdl64";
  int max_size = std::numeric_limits<int>::max();
  bool overwrite = false;
};

pcl_movers::tools::OptionTable optionTable() {
  const Options d;
  pcl_movers::tools::OptionTable table(
      {{"--max-size", "N", "largest cluster kept", "no limit"},
       {"--sensor", "NAME",
        "beam layout for unorganized scans, and whether azimuth wraps\naround (360-degree "
        "sensors): hdl64, hdl32, vlp16, os1_64, ladar2d",
        d.sensor},
       {"--keep-ground", "", "do not remove the ground first"},
       {"--overwrite", "", "replace existing output files"}});
  table.add(d.segment.options());
  table.add(d.ground.options());
  return table;
}

void printHelp(const char* argv0) {
  std::printf(
      "Usage: %s INPUT OUTPUT [options]\n"
      "  Segments LiDAR scans into objects as Morris et al. do: the ground is removed with local\n"
      "  planes, then neighbouring range-image cells join when their depth difference is below\n"
      "  k * range (8-neighbours, azimuth wrapping around for 360-degree sensors). Unorganized\n"
      "  scans (KITTI .bin, unorganized PCD) are first organized into a range image with the beam\n"
      "  layout of --sensor. INPUT is a .pcd/.bin scan or a sequence folder; OUTPUT is a .pcd "
      "file\n"
      "  or a folder receiving one NNNNNN.pcd per frame.\n\n"
      "Output: every input point, in the input's order and layout, with fields x y z intensity\n"
      "  label (uint32): the cluster id, 1 = largest cluster, 2 = next, ...; 0 = ground, invalid,\n"
      "  in a cluster outside --min-size/--max-size, or (unorganized input) a point that shared "
      "its\n"
      "  range-image cell with a nearer point.\n\n"
      "Options (-h, --help: this help):\n%s",
      argv0, optionTable().help().c_str());
}

using pcl_movers::tools::labelledBlob;
using pcl_movers::tools::parseNumber;
using pcl_movers::tools::readScanChecked;
using pcl_movers::tools::writeAtomically;

struct Totals {
  std::size_t points = 0, clusters = 0, unplaced = 0;
  double ms = 0;
};

void processOne(const std::string& in, const std::string& out, const Options& opt, Totals& totals) {
  const Cloud::Ptr cloud = readScanChecked(in);
  const std::size_t n = cloud->size();
  const auto t0 = std::chrono::steady_clock::now();
  // The range image: organized input is used as is, unorganized input is organized. The ground
  // is removed on it, as MoverDetector does, so that the local-slope test has beam neighbours.
  Cloud::Ptr image(new Cloud);
  std::vector<int> index_image;
  const pcl_movers::SensorModel model = pcl_movers::SensorModel::fromName(opt.sensor);
  bool wrap = model.isFullRevolution();
  if (cloud->isOrganized()) {
    *image = *cloud;
    index_image.resize(n);
    for (std::size_t i = 0; i < n; ++i) index_image[i] = static_cast<int>(i);
  } else {
    pcl_movers::RangeImageOrganizer<Point> organizer;
    organizer.setSensorModel(model);
    organizer.setInputCloud(cloud);
    organizer.organize(*image);
    index_image = organizer.getIndexImage();
  }
  std::vector<std::uint8_t> is_ground(n, 0);
  if (!opt.keep_ground) {
    pcl_movers::GroundPlaneFilter<Point> filter;
    filter.setParameters(opt.ground.parameters);
    filter.setInputCloud(image);
    filter.setNegative(true);
    pcl::Indices ground;
    filter.filter(ground);
    for (const auto c : ground)
      if (index_image[c] >= 0) is_ground[index_image[c]] = 1;
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t c = 0; c < image->size(); ++c)
    if (index_image[c] < 0 || is_ground[index_image[c]]) {
      auto& p = (*image)[c];
      p.x = p.y = p.z = nan;
    }
  pcl_movers::RangeImageRegionGrowing<Point> rg;
  rg.setParameters(opt.segment.parameters);
  rg.setMaxClusterSize(opt.max_size);
  rg.setWrapAround(wrap);
  rg.setInputCloud(image);
  std::vector<pcl::PointIndices> clusters;
  rg.segment(clusters);
  totals.ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  std::vector<std::uint32_t> labels(n, 0);
  std::vector<std::uint8_t> placed(n, 0);
  for (const auto i : index_image)
    if (i >= 0) placed[i] = 1;
  for (std::size_t k = 0; k < clusters.size(); ++k)  // sorted largest first: id 1 = largest
    for (const auto c : clusters[k].indices)
      labels[index_image[c]] = static_cast<std::uint32_t>(k + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = (*cloud)[i];
    totals.unplaced += !placed[i] && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  }
  totals.points += n;
  totals.clusters += clusters.size();
  pcl::PCLPointCloud2 blob;
  labelledBlob(*cloud, labels, blob);
  writeAtomically(out, [&](pcl::PCDWriter& w, const std::string& path) {
    return w.writeBinary(path, blob, cloud->sensor_origin_, cloud->sensor_orientation_);
  });
}

int parseCount(const std::string& flag, const std::string& text, int min) {
  const double v = parseNumber(flag, text);
  if (v != std::floor(v) || v < min || v > 2e9)
    throw InputError(flag + ": expected an integer >= " + std::to_string(min) + ", got '" + text +
                     "'");
  return static_cast<int>(v);
}

int run(int argc, char** argv) {
  const auto args = optionTable().parse(argc, argv);
  const auto& positional = args.positional;
  if (positional.size() != 2)
    throw InputError("expected INPUT and OUTPUT, got " + std::to_string(positional.size()) +
                     " argument(s); see -h");
  Options opt;
  opt.overwrite = args.has("--overwrite");
  opt.keep_ground = args.has("--keep-ground");
  std::string v;
  opt.segment.parse(args);
  if (args.get("--max-size", v)) opt.max_size = parseCount("--max-size", v, 1);
  if (opt.max_size < opt.segment.parameters.min_cluster_points)
    throw InputError("--max-size must be >= --min-cluster-points");
  if (args.get("--sensor", v)) opt.sensor = v;
  pcl_movers::SensorModel::fromName(opt.sensor);  // throws InputError on an unknown name
  opt.ground.parse(args);

  const std::string& input = positional[0];
  const std::string& output = positional[1];
  const auto inputs = pcl_movers::tools::listScanInputs(input);
  pcl_movers::tools::OutputCleanup cleanup(output);
  const std::vector<std::string> outputs =
      pcl_movers::tools::planScanOutputs(input, inputs, output, opt.overwrite);
  Totals totals;
  pcl_movers::tools::ProgressBar bar(inputs.size());
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    processOne(inputs[i], outputs[i], opt, totals);
    cleanup.track(outputs[i]);
    bar.update(i + 1);
  }
  bar.finish();
  cleanup.commit();
  pcl::console::print_info(
      "%zu scan(s), %zu points, %.1f clusters per scan, %.2f ms per scan -> %s\n", inputs.size(),
      totals.points, double(totals.clusters) / double(inputs.size()),
      totals.ms / double(inputs.size()), output.c_str());
  if (totals.unplaced > 0)
    pcl::console::print_info(
        "%zu point(s) shared a range-image cell with a nearer point and got label 0\n",
        totals.unplaced);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  return pcl_movers::tools::runTool("pcl_movers_segment", [&] { return run(argc, argv); });
}
