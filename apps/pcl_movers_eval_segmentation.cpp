/*
 * pcl_movers_eval_segmentation — scores GroundPlaneFilter and RangeImageRegionGrowing against
 * point-wise labels (SemanticKITTI .label files, or the simulator's labels in the same format)
 * and prints the result as Markdown tables.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/segmentation_metrics.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/range_image_region_growing.h>

#include <pcl/console/parse.h>
#include <pcl/console/print.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>

#include "tool_utils.h"

namespace fs = std::filesystem;
using pcl_movers::InputError;
using Point = pcl::PointXYZI;
using Cloud = pcl::PointCloud<Point>;

namespace {

struct Options {
  // ground
  pcl_movers::tools::StageOptions<pcl_movers::GroundParameters> ground =
      pcl_movers::tools::groundOptions();
  bool per_frame = false;
  float baseline = 0.25f;
  // segmentation
  pcl_movers::tools::StageOptions<pcl_movers::SegmentationParameters> segment =
      pcl_movers::tools::segmentationOptions();
  // scoring
  int min_points = 30;
  float min_fraction = 0.8f;
  /// auto, as pcl_movers_ground and pcl_movers_detect: the scores are those of the tools'
  /// defaults (a preset name organizes every scan by that preset's beams instead).
  std::string sensor = "auto";
  int first = 0, last = std::numeric_limits<int>::max();
  std::vector<std::string> kitti, sequences;
};

pcl_movers::tools::OptionTable optionTable() {
  using pcl_movers::tools::str;
  const Options d;
  pcl_movers::tools::OptionTable table(
      {{"", "", "Inputs (at least one; each may be given several times):"},
       {"--kitti", "DIR",
        "SemanticKITTI layout: DIR/velodyne/NNNNNN.bin + DIR/labels/NNNNNN.label\n(only frames "
        "with a label file are used)"},
       {"--sequence", "DIR",
        "a sequence folder with labels/NNNNNN.label (pcl_movers_simulate output)"},
       {"--frames", "A-B", "frame index range within each input", "all"},
       {"--sensor", "NAME",
        "beam layout used to organize unorganized scans: auto (estimated from each\nscan, as "
        "pcl_movers_ground does), hdl64, hdl32, vlp16, os1_64, ladar2d",
        d.sensor},
       {"", "", "\nGround removal:"}});
  table.add(d.ground.options());
  table.add(
      {{"--baseline", "M",
        "the height-threshold baseline calls z < -sensor_height + M ground (the sensor height the "
        "filter used)",
        str(d.baseline)},
       {"", "", "\nSegmentation:"}});
  table.add(d.segment.options());
  table.add(
      {{"", "", "\nScoring:"},
       {"--min-points", "N", "smallest scored instance", std::to_string(d.min_points)},
       {"--min-fraction", "F", "share of an instance one cluster must hold", str(d.min_fraction)},
       {"--per-frame", "", "also print ground precision/recall of every frame"}});
  return table;
}

void printHelp(const char* argv0) {
  std::printf(
      "Usage: %s [--kitti DIR]... [--sequence DIR]... [options]\n"
      "  Scores ground removal (GroundPlaneFilter) and object segmentation (RangeImageOrganizer +\n"
      "  GroundPlaneFilter + RangeImageRegionGrowing) against point-wise labels and prints "
      "Markdown.\n"
      "  Ground truth: SemanticKITTI classes road, parking, sidewalk, other-ground, terrain and\n"
      "  lane-marking are ground; unlabelled/outlier points are not scored. Objects: labelled\n"
      "  instances with >= --min-points points (things by instance id; trunks and poles split by\n"
      "  3D connected components); recovered = one cluster holds >= --min-fraction of the object.\n"
      "  Points the organizer could not place in the range image are not scored for objects.\n"
      "  -h, --help: this help.\n\n%s",
      argv0, optionTable().help().c_str());
}

using pcl_movers::tools::parseNumber;

double nonNegative(const std::string& flag, const std::string& text) {
  const double v = parseNumber(flag, text);
  if (v < 0) throw InputError(flag + ": must be >= 0, got '" + text + "'");
  return v;
}

double positive(const std::string& flag, const std::string& text) {
  const double v = parseNumber(flag, text);
  if (!(v > 0)) throw InputError(flag + ": must be > 0, got '" + text + "'");
  return v;
}

int integer(const std::string& flag, const std::string& text, int min) {
  const double v = parseNumber(flag, text);
  if (v != std::floor(v) || v < min || v > 1e9)
    throw InputError(flag + ": expected an integer >= " + std::to_string(min) + ", got '" + text +
                     "'");
  return static_cast<int>(v);
}

/** One labelled frame to score. */
struct Frame {
  std::string scan, labels;
};

std::vector<Frame> kittiFrames(const std::string& dir, int first, int last) {
  if (!fs::is_directory(dir + "/velodyne") || !fs::is_directory(dir + "/labels"))
    throw InputError(dir, 0, "expected velodyne/ and labels/ folders (SemanticKITTI layout)");
  std::vector<std::string> labels;
  for (const auto& e : fs::directory_iterator(dir + "/labels"))
    if (e.path().extension() == ".label") labels.push_back(e.path().string());
  pcl_movers::io::sortNumerically(labels);
  std::vector<Frame> frames;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (int(i) < first || int(i) > last) continue;
    const std::string scan = dir + "/velodyne/" + fs::path(labels[i]).stem().string() + ".bin";
    if (!fs::exists(scan)) throw InputError(labels[i], 0, "no matching scan " + scan);
    frames.push_back({scan, labels[i]});
  }
  if (frames.empty()) throw InputError(dir, 0, "no labelled frames in the requested range");
  return frames;
}

std::vector<Frame> sequenceFrames(const std::string& dir, int first, int last) {
  pcl_movers::io::SequenceReader reader(dir);
  std::vector<Frame> frames;
  for (std::size_t i = 0; i < reader.size(); ++i) {
    if (int(i) < first || int(i) > last) continue;
    const std::string labels = reader.labelPath(i);
    if (labels.empty()) continue;
    frames.push_back({reader.framePaths()[i], labels});
  }
  if (frames.empty()) throw InputError(dir, 0, "no frames with labels/NNNNNN.label in range");
  return frames;
}

struct Result {
  std::string name;
  std::size_t frames = 0, points = 0, unplaced_instance_points = 0, instance_points = 0;
  pcl_movers::eval::GroundScore ground, baseline;
  std::vector<pcl_movers::eval::GroundScore> ground_per_frame;
  /// Ground scores by horizontal distance from the sensor (kRangeBands): far cells are deep and
  /// hold few scan lines, so an overall score hides where the filter fails.
  std::array<pcl_movers::eval::GroundScore, 5> ground_by_range;
  pcl_movers::eval::ObjectScore objects;
  std::map<std::uint16_t, std::size_t> false_ground;  ///< true class of points called ground
  /// Per instance class: scored, recovered, over-segmented, under-segmented (merged).
  std::map<std::uint16_t, std::array<std::size_t, 4>> by_class;
  double ground_ms = 0, organize_ms = 0, segment_ms = 0;
};

/// Upper edges of the range bands of Result::ground_by_range [m] (the last band is open).
constexpr std::array<float, 4> kRangeBands = {20.f, 40.f, 60.f, 70.f};

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void scoreFrame(const Frame& frame, const Options& opt, Result& result) {
  Cloud::Ptr cloud(new Cloud);
  pcl_movers::io::readScan(frame.scan, *cloud);
  const auto labels = pcl_movers::io::readLabels(frame.labels);
  if (labels.size() != cloud->size())
    throw InputError(frame.labels, 0,
                     "has " + std::to_string(labels.size()) + " labels but " + frame.scan +
                         " has " + std::to_string(cloud->size()) + " points");
  const std::size_t n = cloud->size();
  ++result.frames;
  result.points += n;

  // Organize first (pass-through for organized scans): the pipeline (MoverDetector) runs the
  // ground filter on the range image, where its local-slope test has beam neighbours.
  pcl_movers::RangeImageOrganizer<Point> organizer;
  if (opt.sensor != "auto") organizer.setSensorModel(pcl_movers::SensorModel::fromName(opt.sensor));
  organizer.setInputCloud(cloud);
  Cloud::Ptr image(new Cloud);
  auto t0 = std::chrono::steady_clock::now();
  organizer.organize(*image);
  result.organize_ms += msSince(t0);
  std::vector<int> index_image = organizer.getIndexImage();
  if (organizer.wasPassThrough() || index_image.size() != image->size()) {
    index_image.resize(image->size());
    for (std::size_t i = 0; i < index_image.size(); ++i) index_image[i] = static_cast<int>(i);
  }
  std::vector<std::uint8_t> placed(n, 0);
  std::size_t unplaced = 0;
  for (std::size_t c = 0; c < index_image.size(); ++c)
    if (index_image[c] >= 0) placed[index_image[c]] = 1;
  for (std::size_t i = 0; i < n; ++i) unplaced += !placed[i];

  auto configure = [&opt](pcl_movers::GroundPlaneFilter<Point>& f) {
    f.setParameters(opt.ground.parameters);
    f.setNegative(true);
  };
  std::vector<std::uint8_t> is_ground(n, 0), is_baseline(n, 0);
  float sensor_height = 0.f;  // the height the filter started from: the set one or its estimate
  {
    pcl_movers::GroundPlaneFilter<Point> ground_filter;
    configure(ground_filter);
    ground_filter.setInputCloud(image);
    pcl::Indices ground;
    t0 = std::chrono::steady_clock::now();
    ground_filter.filter(ground);
    result.ground_ms += msSince(t0);
    sensor_height = ground_filter.getUsedSensorHeight();
    for (const auto c : ground)
      if (index_image[c] >= 0) is_ground[index_image[c]] = 1;
  }
  if (unplaced > 0) {
    // Points the range image could not hold (a nearer return took their cell) are still scored:
    // they get the plane test alone, from the same filter run on the raw scan (not timed).
    pcl_movers::GroundPlaneFilter<Point> raw_filter;
    configure(raw_filter);
    raw_filter.setInputCloud(cloud);
    pcl::Indices ground;
    raw_filter.filter(ground);
    for (const auto i : ground)
      if (!placed[i]) is_ground[i] = 1;
  }
  const float z0 = cloud->sensor_origin_.z() - sensor_height + opt.baseline;
  for (std::size_t i = 0; i < n; ++i) is_baseline[i] = (*cloud)[i].z < z0;
  const auto truth = pcl_movers::eval::groundTruthFromLabels(labels);
  const auto frame_score = pcl_movers::eval::scoreGround(truth, is_ground);
  result.ground += frame_score;
  result.ground_per_frame.push_back(frame_score);
  {
    std::vector<pcl_movers::eval::GroundTruth> band_truth(n);
    const Eigen::Vector3f origin = cloud->sensor_origin_.head<3>();
    for (std::size_t b = 0; b < result.ground_by_range.size(); ++b) {
      const float lo = b == 0 ? 0.f : kRangeBands[b - 1];
      const float hi = b < kRangeBands.size() ? kRangeBands[b] : std::numeric_limits<float>::max();
      for (std::size_t i = 0; i < n; ++i) {
        const float r = ((*cloud)[i].getVector3fMap() - origin).head<2>().norm();
        band_truth[i] = r >= lo && r < hi ? truth[i] : pcl_movers::eval::GroundTruth::kIgnore;
      }
      result.ground_by_range[b] += pcl_movers::eval::scoreGround(band_truth, is_ground);
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    if (is_ground[i] && truth[i] == pcl_movers::eval::GroundTruth::kObject)
      ++result.false_ground[pcl_movers::io::labelClass(labels[i])];
  result.baseline += pcl_movers::eval::scoreGround(truth, is_baseline);

  // Objects: blank the ground in the range image, grow regions.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t c = 0; c < image->size(); ++c)
    if (index_image[c] >= 0 && is_ground[index_image[c]]) {
      auto& p = (*image)[c];
      p.x = p.y = p.z = nan;
    }
  pcl_movers::RangeImageRegionGrowing<Point> rg;
  rg.setParameters(opt.segment.parameters);
  // Organized input keeps its rows and columns (a full revolution, as the detector assumes).
  rg.setWrapAround(organizer.wasPassThrough() || organizer.getSensorModel().isFullRevolution());
  rg.setInputCloud(image);
  std::vector<pcl::PointIndices> clusters;
  t0 = std::chrono::steady_clock::now();
  rg.segment(clusters);
  result.segment_ms += msSince(t0);

  std::vector<int> cluster_of(n, -1);
  for (std::size_t k = 0; k < clusters.size(); ++k)
    for (const auto c : clusters[k].indices)
      if (index_image[c] >= 0) cluster_of[index_image[c]] = static_cast<int>(k);

  std::vector<Eigen::Vector3f> points(n);
  for (std::size_t i = 0; i < n; ++i) points[i] = (*cloud)[i].getVector3fMap();
  const auto instance_of = pcl_movers::eval::instancesFromLabels(labels, points);
  for (std::size_t i = 0; i < n; ++i)
    if (instance_of[i] > 0) {
      ++result.instance_points;
      result.unplaced_instance_points += !placed[i];
    }
  std::vector<pcl_movers::eval::InstanceOutcome> outcomes;
  result.objects += pcl_movers::eval::scoreObjects(instance_of, cluster_of, opt.min_points,
                                                   opt.min_fraction, &placed, &outcomes);
  std::map<int, std::uint16_t> class_of;  // instance -> its class (all its points share one)
  for (std::size_t i = 0; i < n; ++i)
    if (instance_of[i] > 0) class_of[instance_of[i]] = pcl_movers::io::labelClass(labels[i]);
  for (const auto& o : outcomes) {
    auto& row = result.by_class[class_of[o.instance]];
    ++row[0];
    row[1] += o.recovered;
    row[2] += o.over_segmented;
    row[3] += o.under_segmented;
  }
}

std::string className(std::uint16_t c) {
  static const std::map<std::uint16_t, std::string> names = {
      {10, "car"},           {11, "bicycle"},     {18, "truck"},
      {20, "other-vehicle"}, {30, "person"},      {31, "bicyclist"},
      {50, "building"},      {51, "fence"},       {52, "other-structure"},
      {70, "vegetation"},    {71, "trunk"},       {80, "pole"},
      {81, "traffic-sign"},  {99, "other-object"}};
  const auto it = names.find(c);
  return it != names.end() ? it->second : "class " + std::to_string(c);
}

std::string pct(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f %%", 100.0 * v);
  return buf;
}

int run(int argc, char** argv) {
  const auto args = optionTable().parse(argc, argv);
  const auto& positional = args.positional;
  if (!positional.empty())
    throw InputError("unexpected argument '" + positional.front() +
                     "' (inputs are given with --kitti / --sequence; see -h)");
  Options opt;
  std::string v;
  opt.ground.parse(args);
  if (args.has("--per-frame")) opt.per_frame = true;
  if (args.get("--baseline", v)) opt.baseline = parseNumber("--baseline", v);
  opt.segment.parse(args);
  if (args.get("--min-points", v)) opt.min_points = integer("--min-points", v, 1);
  if (args.get("--min-fraction", v)) {
    opt.min_fraction = positive("--min-fraction", v);
    if (opt.min_fraction > 1) throw InputError("--min-fraction: must be <= 1");
  }
  if (args.get("--sensor", v)) opt.sensor = v;
  if (opt.sensor != "auto") pcl_movers::SensorModel::fromName(opt.sensor);  // throws on a bad name
  if (args.get("--frames", v)) {
    const auto dash = v.find('-');
    if (dash == std::string::npos) {
      opt.first = opt.last = integer("--frames", v, 0);
    } else {
      opt.first = integer("--frames", v.substr(0, dash), 0);
      opt.last = integer("--frames", v.substr(dash + 1), 0);
    }
    if (opt.last < opt.first) throw InputError("--frames: empty range '" + v + "'");
  }
  opt.kitti = args.all("--kitti");
  opt.sequences = args.all("--sequence");
  if (opt.kitti.empty() && opt.sequences.empty())
    throw InputError("no input: give --kitti DIR and/or --sequence DIR (see -h)");

  std::vector<Result> results;
  auto evaluate = [&](const std::string& dir, const std::vector<Frame>& frames) {
    Result r;
    r.name = fs::path(dir).filename().string();
    if (r.name.empty()) r.name = fs::path(dir).parent_path().filename().string();
    for (const auto& f : frames) scoreFrame(f, opt, r);
    results.push_back(r);
  };
  for (const auto& dir : opt.kitti) evaluate(dir, kittiFrames(dir, opt.first, opt.last));
  for (const auto& dir : opt.sequences) evaluate(dir, sequenceFrames(dir, opt.first, opt.last));

  const pcl_movers::GroundParameters& g = opt.ground.parameters;
  const pcl_movers::SegmentationParameters& sp = opt.segment.parameters;
  char slope_text[128] = "local-slope test off";
  if (g.local_slope)
    std::snprintf(slope_text, sizeof(slope_text),
                  "local slope <= %.0f° with %g m noise, neighbour band %g m", g.local_slope_deg,
                  g.range_noise, g.slope_band);
  std::printf(
      "Ground: GroundPlaneFilter on the range image (distance %g m, tilt %.1f°, %d sectors, %s) "
      "vs. a height threshold %g m above the ground under the sensor (%s). Objects: ground "
      "removed, RangeImageRegionGrowing (k = %g, "
      "floor %g m, gap %d, row bridge %g m, clusters of >= %d points); instances with >= %d "
      "points, recovered = one cluster holds >= %g %% of them. These are the defaults of "
      "GroundParameters and SegmentationParameters, which pcl_movers_ground, pcl_movers_segment "
      "and pcl_movers_detect share.\n\n",
      g.distance, g.max_slope_deg, g.sectors, slope_text, opt.baseline,
      g.sensor_height > 0 ? "the set sensor height" : "the sensor height the filter estimated",
      sp.depth_ratio, sp.depth_min, sp.max_gap, sp.row_bridge, sp.min_cluster_points,
      opt.min_points, 100.0 * opt.min_fraction);
  std::printf(
      "| data | frames | ground precision | ground recall | baseline precision | baseline recall "
      "|\n|---|---|---|---|---|---|\n");
  for (const auto& r : results)
    std::printf("| %s | %zu | %s | %s | %s | %s |\n", r.name.c_str(), r.frames,
                pct(r.ground.precision()).c_str(), pct(r.ground.recall()).c_str(),
                pct(r.baseline.precision()).c_str(), pct(r.baseline.recall()).c_str());
  std::printf("\nGround precision / recall by horizontal distance from the sensor:\n\n| data |");
  for (std::size_t b = 0; b <= kRangeBands.size(); ++b) {
    if (b < kRangeBands.size())
      std::printf(" %.0f-%.0f m |", b ? kRangeBands[b - 1] : 0.f, kRangeBands[b]);
    else
      std::printf(" >= %.0f m |", kRangeBands.back());
  }
  std::printf("\n|---|");
  for (std::size_t b = 0; b <= kRangeBands.size(); ++b) std::printf("---|");
  std::printf("\n");
  for (const auto& r : results) {
    std::printf("| %s |", r.name.c_str());
    for (const auto& g : r.ground_by_range) {
      if (g.tp + g.fp + g.fn == 0)
        std::printf(" - |");  // no labelled ground and nothing called ground there
      else
        std::printf(" %s / %s |", pct(g.precision()).c_str(), pct(g.recall()).c_str());
    }
    std::printf("\n");
  }
  if (opt.per_frame) {
    std::printf("\n| data | frame | ground precision | ground recall |\n|---|---|---|---|\n");
    for (const auto& r : results)
      for (std::size_t f = 0; f < r.ground_per_frame.size(); ++f)
        std::printf("| %s | %zu | %s | %s |\n", r.name.c_str(), f + std::size_t(opt.first),
                    pct(r.ground_per_frame[f].precision()).c_str(),
                    pct(r.ground_per_frame[f].recall()).c_str());
  }
  std::printf("\nFalse ground (non-ground points called ground) by their true class:\n\n");
  for (const auto& r : results) {
    std::vector<std::pair<std::size_t, std::uint16_t>> sorted;
    std::size_t total = 0;
    for (const auto& [cls, count] : r.false_ground) {
      sorted.emplace_back(count, cls);
      total += count;
    }
    std::sort(sorted.rbegin(), sorted.rend());
    std::printf("- %s:", r.name.c_str());
    for (std::size_t k = 0; k < sorted.size() && k < 4; ++k)
      std::printf("%s %s %.0f %%", k ? "," : "", className(sorted[k].second).c_str(),
                  total ? 100.0 * double(sorted[k].first) / double(total) : 0.0);
    std::printf(" (%zu points in all)\n", total);
  }
  std::printf(
      "\n| data | instances | recovered | recovered, not merged | over-segmented | "
      "under-segmented (merged) | missed | instance points not in the range image |\n"
      "|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : results) {
    const auto& o = r.objects;
    std::printf("| %s | %zu | %s | %s | %s | %s | %s | %s |\n", r.name.c_str(), o.instances,
                pct(o.rate(o.recovered)).c_str(), pct(o.rate(o.clean)).c_str(),
                pct(o.rate(o.over_segmented)).c_str(), pct(o.rate(o.under_segmented)).c_str(),
                pct(o.rate(o.missed)).c_str(),
                pct(r.instance_points ? double(r.unplaced_instance_points) / r.instance_points : 0)
                    .c_str());
  }
  std::printf("\nObject outcomes by class (scored / recovered / over-segmented / merged):\n\n");
  for (const auto& r : results) {
    std::printf("- %s:", r.name.c_str());
    bool first = true;
    for (const auto& [cls, row] : r.by_class) {
      std::printf("%s %s %zu/%zu/%zu/%zu", first ? "" : ",", className(cls).c_str(), row[0], row[1],
                  row[2], row[3]);
      first = false;
    }
    std::printf("\n");
  }
  std::printf(
      "\n| data | points/frame | ground ms/frame | organize ms/frame | segment ms/frame |\n"
      "|---|---|---|---|---|\n");
  for (const auto& r : results)
    std::printf("| %s | %zu | %.2f | %.2f | %.2f |\n", r.name.c_str(),
                r.frames ? r.points / r.frames : 0, r.ground_ms / r.frames,
                r.organize_ms / r.frames, r.segment_ms / r.frames);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  return pcl_movers::tools::runTool("pcl_movers_eval_segmentation",
                                    [&] { return run(argc, argv); });
}
