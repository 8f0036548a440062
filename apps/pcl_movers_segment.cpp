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
  pcl_movers::tools::GroundOptions ground;
  bool keep_ground = false;
  std::string sensor = "hdl64";
  float k = pcl_movers::RangeImageRegionGrowing<Point>().getDepthThresholdFactor();
  float floor = pcl_movers::RangeImageRegionGrowing<Point>().getMinDepthThreshold();
  int gap = pcl_movers::RangeImageRegionGrowing<Point>().getMaxGap();
  int min_size = 10;
  int max_size = std::numeric_limits<int>::max();
  bool overwrite = false;
};

void printHelp(const char* argv0) {
  const Options d;
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
      "Options:\n"
      "  --k F              depth threshold factor (default %g)\n"
      "  --floor M          absolute floor of the depth threshold [m] (default %g)\n"
      "  --gap N            empty cells bridged between neighbours, 0 = strict 8-neighbours\n"
      "                     (default %d)\n"
      "  --min-size N       smallest cluster kept (default %d)\n"
      "  --max-size N       largest cluster kept (default: no limit)\n"
      "  --sensor NAME      beam layout for unorganized scans, and whether azimuth wraps\n"
      "                     around (360-degree sensors): hdl64, hdl32, vlp16, os1_64, ladar2d\n"
      "                     (default %s)\n"
      "  --keep-ground      do not remove the ground first\n"
      "%s"
      "  --overwrite        replace existing output files\n"
      "  -h, --help         this help\n",
      argv0, d.k, d.floor, d.gap, d.min_size, d.sensor.c_str(), d.ground.help().c_str());
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
  std::vector<std::uint8_t> is_ground(n, 0);
  if (!opt.keep_ground) {
    pcl_movers::GroundPlaneFilter<Point> filter;
    opt.ground.applyTo(filter);
    filter.setInputCloud(cloud);
    filter.setNegative(true);
    pcl::Indices ground;
    filter.filter(ground);
    for (const auto i : ground) is_ground[i] = 1;
  }
  // The range image: organized input is used as is, unorganized input is organized.
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
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t c = 0; c < image->size(); ++c)
    if (index_image[c] < 0 || is_ground[index_image[c]]) {
      auto& p = (*image)[c];
      p.x = p.y = p.z = nan;
    }
  pcl_movers::RangeImageRegionGrowing<Point> rg;
  rg.setDepthThresholdFactor(opt.k);
  rg.setMinDepthThreshold(opt.floor);
  rg.setMaxGap(opt.gap);
  rg.setMinClusterSize(opt.min_size);
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
  std::vector<std::string> with_value = pcl_movers::tools::GroundOptions::flags();
  for (const char* flag : {"--k", "--floor", "--gap", "--min-size", "--max-size", "--sensor"})
    with_value.push_back(flag);
  pcl_movers::tools::checkArguments(argc, argv, {"-h", "--help", "--overwrite", "--keep-ground"},
                                    with_value);
  const auto positional = pcl_movers::tools::positionalArguments(argc, argv, with_value);
  if (positional.size() != 2)
    throw InputError("expected INPUT and OUTPUT, got " + std::to_string(positional.size()) +
                     " argument(s); see -h");
  Options opt;
  opt.overwrite = pcl::console::find_switch(argc, argv, "--overwrite");
  opt.keep_ground = pcl::console::find_switch(argc, argv, "--keep-ground");
  std::string v;
  if (pcl::console::parse_argument(argc, argv, "--k", v) >= 0) {
    opt.k = static_cast<float>(parseNumber("--k", v));
    if (opt.k < 0) throw InputError("--k: must be >= 0, got '" + v + "'");
  }
  if (pcl::console::parse_argument(argc, argv, "--floor", v) >= 0) {
    opt.floor = static_cast<float>(parseNumber("--floor", v));
    if (opt.floor < 0) throw InputError("--floor: must be >= 0, got '" + v + "'");
  }
  if (pcl::console::parse_argument(argc, argv, "--gap", v) >= 0)
    opt.gap = parseCount("--gap", v, 0);
  if (pcl::console::parse_argument(argc, argv, "--min-size", v) >= 0)
    opt.min_size = parseCount("--min-size", v, 1);
  if (pcl::console::parse_argument(argc, argv, "--max-size", v) >= 0)
    opt.max_size = parseCount("--max-size", v, 1);
  if (opt.max_size < opt.min_size) throw InputError("--max-size must be >= --min-size");
  if (pcl::console::parse_argument(argc, argv, "--sensor", v) >= 0) opt.sensor = v;
  pcl_movers::SensorModel::fromName(opt.sensor);  // throws InputError on an unknown name
  opt.ground.parse(argc, argv);

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
