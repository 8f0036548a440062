/*
 * Ground removal and segmentation speed on real organized HDL-64E frames (KITTI odometry 00,
 * frames 0-2, organized to 64 x 2048 by RangeImageOrganizer), side by side with PCL's own classes:
 *  - GroundPlaneFilter vs. pcl::SACSegmentation (one global plane, RANSAC) + pcl::ExtractIndices;
 *  - RangeImageRegionGrowing vs. pcl::EuclideanClusterExtraction (kd-tree) and
 *    pcl::OrganizedConnectedComponentSegmentation with pcl::EuclideanClusterComparator,
 * with each method's ground precision/recall or object-recovery rate (SemanticKITTI labels) as
 * counters beside the time, so speed is compared at known quality. Single-threaded.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/segmentation_metrics.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/range_image_region_growing.h>

#include <pcl/filters/extract_indices.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/euclidean_cluster_comparator.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/organized_connected_component_segmentation.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>

namespace {

using Point = pcl::PointXYZI;
using Cloud = pcl::PointCloud<Point>;
namespace ev = pcl_movers::eval;

constexpr float kEuclideanTolerance = 0.5f;  // a usual KITTI choice for both Euclidean methods
constexpr float kSacDistance = 0.2f;

struct Frame {
  Cloud::Ptr image;             ///< organized 64 x 2048
  Cloud::Ptr non_ground;        ///< organized, ground cells NaN (GroundPlaneFilter)
  Cloud::Ptr non_ground_dense;  ///< the non-ground points only (for the kd-tree method)
  std::vector<int> dense_to_cell;
  pcl::IndicesPtr finite;                     ///< finite cells of image
  std::vector<int> index_image;               ///< cell -> scan index
  std::vector<ev::GroundTruth> ground_truth;  ///< per scan point
  std::vector<int> instances;                 ///< per scan point
  std::vector<std::uint8_t> placed;           ///< per scan point: has a cell
  std::size_t scan_size = 0;
};

/** Frames loaded once; empty when the data is missing. */
const std::vector<Frame>& frames() {
  static const std::vector<Frame> loaded = [] {
    std::vector<Frame> out;
    const std::string dir = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-odometry-00";
    for (int f = 0; f < 3; ++f) {
      char name[16];
      std::snprintf(name, sizeof(name), "%06d", f);
      const std::string scan = dir + "/velodyne/" + name + ".bin";
      const std::string label = dir + "/labels/" + name + ".label";
      if (!std::filesystem::exists(scan) || !std::filesystem::exists(label)) break;
      Cloud::Ptr cloud(new Cloud);
      pcl_movers::io::readScan(scan, *cloud);
      const auto labels = pcl_movers::io::readLabels(label);
      Frame fr;
      fr.scan_size = cloud->size();
      pcl_movers::RangeImageOrganizer<Point> organizer;
      organizer.setSensorModel(pcl_movers::SensorModel::hdl64());
      organizer.setInputCloud(cloud);
      fr.image.reset(new Cloud);
      organizer.organize(*fr.image);
      fr.index_image = organizer.getIndexImage();
      fr.finite.reset(new pcl::Indices);
      for (std::size_t c = 0; c < fr.image->size(); ++c)
        if (std::isfinite((*fr.image)[c].x)) fr.finite->push_back(static_cast<int>(c));
      // Ground truth per scan point.
      fr.ground_truth = ev::groundTruthFromLabels(labels);
      std::vector<Eigen::Vector3f> points(cloud->size());
      for (std::size_t i = 0; i < cloud->size(); ++i) points[i] = (*cloud)[i].getVector3fMap();
      fr.instances = ev::instancesFromLabels(labels, points);
      fr.placed.assign(cloud->size(), 0);
      for (const auto i : fr.index_image)
        if (i >= 0) fr.placed[i] = 1;
      // Non-ground image with the default GroundPlaneFilter: the common input of all clusterers.
      pcl_movers::GroundPlaneFilter<Point> ground(true);
      ground.setInputCloud(fr.image);
      ground.setKeepOrganized(true);
      fr.non_ground.reset(new Cloud);
      ground.filter(*fr.non_ground);
      fr.non_ground_dense.reset(new Cloud);
      for (std::size_t c = 0; c < fr.non_ground->size(); ++c)
        if (std::isfinite((*fr.non_ground)[c].x)) {
          fr.non_ground_dense->push_back((*fr.non_ground)[c]);
          fr.dense_to_cell.push_back(static_cast<int>(c));
        }
      out.push_back(std::move(fr));
    }
    return out;
  }();
  return loaded;
}

bool haveData(benchmark::State& state) {
  if (frames().empty()) {
    state.SkipWithError(
        "KITTI odometry 00 (velodyne + labels) not found under " PCL_MOVERS_SHARED_DATA);
    return false;
  }
  return true;
}

/** Ground counters from ground cell indices of an organized frame. */
void groundCounters(benchmark::State& state, const std::vector<pcl::Indices>& ground_cells) {
  ev::GroundScore score;
  for (std::size_t f = 0; f < frames().size(); ++f) {
    const Frame& fr = frames()[f];
    std::vector<std::uint8_t> is_ground(fr.scan_size, 0);
    for (const auto c : ground_cells[f]) is_ground[fr.index_image[c]] = 1;
    // Only points that made it into the range image can be judged by an organized method.
    std::vector<ev::GroundTruth> truth = fr.ground_truth;
    for (std::size_t i = 0; i < truth.size(); ++i)
      if (!fr.placed[i]) truth[i] = ev::GroundTruth::kIgnore;
    score += ev::scoreGround(truth, is_ground);
  }
  state.counters["precision_pct"] = 100.0 * score.precision();
  state.counters["recall_pct"] = 100.0 * score.recall();
}

/** Object counters from per-frame cluster lists over organized cells. */
void objectCounters(benchmark::State& state, const std::vector<std::vector<int>>& cell_clusters) {
  ev::ObjectScore score;
  for (std::size_t f = 0; f < frames().size(); ++f) {
    const Frame& fr = frames()[f];
    std::vector<int> cluster_of(fr.scan_size, -1);
    for (std::size_t c = 0; c < cell_clusters[f].size(); ++c)
      if (cell_clusters[f][c] >= 0 && fr.index_image[c] >= 0)
        cluster_of[fr.index_image[c]] = cell_clusters[f][c];
    score += ev::scoreObjects(fr.instances, cluster_of, 30, 0.8, &fr.placed);
  }
  state.counters["instances"] = static_cast<double>(score.instances);
  state.counters["recovered_pct"] = 100.0 * score.rate(score.recovered);
  state.counters["clean_pct"] = 100.0 * score.rate(score.clean);
  state.counters["over_pct"] = 100.0 * score.rate(score.over_segmented);
  state.counters["under_pct"] = 100.0 * score.rate(score.under_segmented);
}

std::vector<int> cellsOf(const std::vector<pcl::PointIndices>& clusters, std::size_t cells,
                         const std::vector<int>* dense_to_cell = nullptr) {
  std::vector<int> out(cells, -1);
  for (std::size_t k = 0; k < clusters.size(); ++k)
    for (const auto i : clusters[k].indices)
      out[dense_to_cell ? (*dense_to_cell)[i] : i] = static_cast<int>(k);
  return out;
}

/** Times `ground(frame, ground_cells)` round-robin over the frames, then scores every frame once
 * outside the timed loop (so the counters do not depend on the iteration count). */
template <typename GroundFn>
void runGround(benchmark::State& state, GroundFn&& ground) {
  if (!haveData(state)) return;
  pcl::Indices cells;
  std::size_t f = 0;
  for (auto _ : state) {
    ground(frames()[f], cells);
    benchmark::DoNotOptimize(cells.data());
    f = (f + 1) % frames().size();
  }
  std::vector<pcl::Indices> all(frames().size());
  for (std::size_t k = 0; k < frames().size(); ++k) ground(frames()[k], all[k]);
  groundCounters(state, all);
}

/** Same for a clusterer: `segment(frame, clusters)` returns clusters over organized cells. */
template <typename SegmentFn>
void runSegment(benchmark::State& state, SegmentFn&& segment) {
  if (!haveData(state)) return;
  std::vector<pcl::PointIndices> clusters;
  std::size_t f = 0;
  for (auto _ : state) {
    segment(frames()[f], clusters);
    benchmark::DoNotOptimize(clusters.data());
    f = (f + 1) % frames().size();
  }
  std::vector<std::vector<int>> cells(frames().size());
  for (std::size_t k = 0; k < frames().size(); ++k) {
    segment(frames()[k], clusters);
    cells[k] = cellsOf(clusters, frames()[k].image->size());
  }
  objectCounters(state, cells);
}

// ------------------------------------------------------------------------------ ground removal

void BM_Ground_GroundPlaneFilter(benchmark::State& state) {
  pcl_movers::GroundPlaneFilter<Point> filter;
  filter.setNegative(true);
  runGround(state, [&](const Frame& fr, pcl::Indices& ground) {
    filter.setInputCloud(fr.image);
    filter.filter(ground);
  });
}
BENCHMARK(BM_Ground_GroundPlaneFilter)->Unit(benchmark::kMillisecond);

void BM_Ground_GroundPlaneFilter_PlaneOnly(benchmark::State& state) {
  // The plane-distance test alone (local-slope test off): what the column test costs and buys.
  pcl_movers::GroundPlaneFilter<Point> filter;
  filter.setNegative(true);
  filter.setLocalSlopeCheck(false);
  runGround(state, [&](const Frame& fr, pcl::Indices& ground) {
    filter.setInputCloud(fr.image);
    filter.filter(ground);
  });
}
BENCHMARK(BM_Ground_GroundPlaneFilter_PlaneOnly)->Unit(benchmark::kMillisecond);

void BM_Ground_SACSegmentation_ExtractIndices(benchmark::State& state) {
  pcl::SACSegmentation<Point> sac;
  sac.setModelType(pcl::SACMODEL_PLANE);
  sac.setMethodType(pcl::SAC_RANSAC);
  sac.setDistanceThreshold(kSacDistance);
  sac.setMaxIterations(100);
  pcl::ExtractIndices<Point> extract;
  extract.setNegative(true);
  Cloud non_ground;
  runGround(state, [&](const Frame& fr, pcl::Indices& ground) {
    pcl::PointIndices::Ptr inliers(new pcl::PointIndices);
    pcl::ModelCoefficients coefficients;
    sac.setInputCloud(fr.image);
    sac.setIndices(fr.finite);  // PCL's RANSAC needs finite points: given to it for free
    sac.segment(*inliers, coefficients);
    extract.setInputCloud(fr.image);
    extract.setIndices(inliers);
    extract.filter(non_ground);
    benchmark::DoNotOptimize(non_ground.data());
    ground = inliers->indices;
  });
}
BENCHMARK(BM_Ground_SACSegmentation_ExtractIndices)->Unit(benchmark::kMillisecond);

// ---------------------------------------------------- ground removal as MoverDetector runs it

/** The first 20 frames of kitti-tracking-0000-a organized as MoverDetector does (HDL-64E model);
 * empty when the data is missing. */
const std::vector<Cloud::Ptr>& trackingImages() {
  static const std::vector<Cloud::Ptr> loaded = [] {
    std::vector<Cloud::Ptr> out;
    const std::string folder = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a";
    if (!std::filesystem::is_directory(folder)) return out;
    pcl_movers::io::SequenceReader reader(folder);
    for (std::size_t i = 0; i < reader.size() && i < 20; ++i) {
      Cloud::Ptr scan(new Cloud);
      reader.read(i, *scan);
      scan->sensor_origin_.setZero();
      pcl_movers::RangeImageOrganizer<Point> organizer;
      organizer.setSensorModel(pcl_movers::SensorModel::hdl64());
      organizer.setInputCloud(scan);
      Cloud::Ptr image(new Cloud);
      organizer.organize(*image);
      out.push_back(image);
    }
    return out;
  }();
  return loaded;
}

/** The ground stage of MoverDetector on real frames: the detector uses GroundParameters'
 * defaults, as the filter does. */
void BM_Ground_DetectorSettings_Tracking0000(benchmark::State& state) {
  const auto& images = trackingImages();
  if (images.empty()) {
    state.SkipWithError("kitti-tracking-0000-a not found under " PCL_MOVERS_SHARED_DATA);
    return;
  }
  pcl_movers::GroundPlaneFilter<Point> filter;
  pcl::IndicesPtr objects(new pcl::Indices);
  std::size_t f = 0;
  for (auto _ : state) {
    filter.setInputCloud(images[f]);
    filter.filter(*objects);
    benchmark::DoNotOptimize(objects->data());
    f = (f + 1) % images.size();
  }
  state.counters["columns"] = images.front()->width;
}
BENCHMARK(BM_Ground_DetectorSettings_Tracking0000)->Unit(benchmark::kMillisecond);

// -------------------------------------------------------------------------------- segmentation

void BM_Segment_RangeImageRegionGrowing(benchmark::State& state) {
  pcl_movers::RangeImageRegionGrowing<Point> rg;
  runSegment(state, [&](const Frame& fr, std::vector<pcl::PointIndices>& clusters) {
    rg.setInputCloud(fr.non_ground);
    rg.segment(clusters);
  });
}
BENCHMARK(BM_Segment_RangeImageRegionGrowing)->Unit(benchmark::kMillisecond);

void BM_Segment_RangeImageRegionGrowing_NoGap(benchmark::State& state) {
  pcl_movers::RangeImageRegionGrowing<Point> rg;
  rg.setMaxGap(0);  // the paper's strict 8-neighbour rule
  rg.setBridgeLength(0.f);
  runSegment(state, [&](const Frame& fr, std::vector<pcl::PointIndices>& clusters) {
    rg.setInputCloud(fr.non_ground);
    rg.segment(clusters);
  });
}
BENCHMARK(BM_Segment_RangeImageRegionGrowing_NoGap)->Unit(benchmark::kMillisecond);

void BM_Segment_RangeImageRegionGrowing_NoBridge(benchmark::State& state) {
  pcl_movers::RangeImageRegionGrowing<Point> rg;
  rg.setBridgeLength(0.f);  // empty-cell gaps only: what the row bridge costs and buys
  runSegment(state, [&](const Frame& fr, std::vector<pcl::PointIndices>& clusters) {
    rg.setInputCloud(fr.non_ground);
    rg.segment(clusters);
  });
}
BENCHMARK(BM_Segment_RangeImageRegionGrowing_NoBridge)->Unit(benchmark::kMillisecond);

void BM_Segment_EuclideanClusterExtraction(benchmark::State& state) {
  std::vector<pcl::PointIndices> dense;
  runSegment(state, [&](const Frame& fr, std::vector<pcl::PointIndices>& clusters) {
    // The kd-tree build is part of the method's cost (a new one per frame).
    pcl::search::KdTree<Point>::Ptr tree(new pcl::search::KdTree<Point>);
    tree->setInputCloud(fr.non_ground_dense);
    pcl::EuclideanClusterExtraction<Point> ec;
    ec.setClusterTolerance(kEuclideanTolerance);
    ec.setMinClusterSize(1);
    ec.setSearchMethod(tree);
    ec.setInputCloud(fr.non_ground_dense);
    dense.clear();  // extract() appends to what the vector holds
    ec.extract(dense);
    // Back to organized cells (cheap, a copy of the indices).
    clusters = dense;
    for (auto& c : clusters)
      for (auto& i : c.indices) i = fr.dense_to_cell[i];
  });
}
BENCHMARK(BM_Segment_EuclideanClusterExtraction)->Unit(benchmark::kMillisecond);

void BM_Segment_OrganizedConnectedComponents(benchmark::State& state) {
  using Comparator = pcl::EuclideanClusterComparator<Point, pcl::Label>;
  pcl::PointCloud<pcl::Label> labels;
  std::vector<pcl::PointIndices> all;
  runSegment(state, [&](const Frame& fr, std::vector<pcl::PointIndices>& clusters) {
    typename Comparator::Ptr comparator(new Comparator);
    comparator->setInputCloud(fr.non_ground);
    comparator->setDistanceThreshold(kEuclideanTolerance, false);
    pcl::OrganizedConnectedComponentSegmentation<Point, pcl::Label> occs(comparator);
    occs.setInputCloud(fr.non_ground);
    // segment() only resizes `labels`: stale labels of a previous frame would index out of
    // range, so start from an empty label cloud every time.
    labels.clear();
    occs.segment(labels, all);
    // OCCS also returns the invalid (NaN) cells as a label: keep real clusters only.
    clusters.clear();
    for (auto& c : all)
      if (!c.indices.empty() && std::isfinite((*fr.non_ground)[c.indices[0]].x))
        clusters.push_back(c);
  });
}
BENCHMARK(BM_Segment_OrganizedConnectedComponents)->Unit(benchmark::kMillisecond);

// ----------------------------------------------------------------------------------- pipeline

void BM_Pipeline_GroundAndRegionGrowing(benchmark::State& state) {
  // Chained through indices (no copy of the cloud): the filter's non-ground indices are the
  // region growing's input indices.
  pcl_movers::GroundPlaneFilter<Point> filter;
  pcl_movers::RangeImageRegionGrowing<Point> rg;
  pcl::IndicesPtr non_ground(new pcl::Indices);
  runSegment(state, [&](const Frame& fr, std::vector<pcl::PointIndices>& clusters) {
    filter.setInputCloud(fr.image);
    filter.filter(*non_ground);
    rg.setInputCloud(fr.image);
    rg.setIndices(non_ground);
    rg.segment(clusters);
  });
}
BENCHMARK(BM_Pipeline_GroundAndRegionGrowing)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
