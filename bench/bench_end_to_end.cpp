/*
 * The PCL-only baseline of scripts/bench_end_to_end.sh: what a PCL user would write to find
 * moving objects in a sequence, end to end on the 77 KITTI HDL-64E frames of
 * kitti-tracking-0000-a: read each PCD, remove the ground plane (pcl::SACSegmentation, RANSAC),
 * cluster the rest (pcl::EuclideanClusterExtraction), associate clusters to the previous frame's by
 * nearest centroid, write one row per cluster per frame. Wall time per frame.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl/ModelCoefficients.h>
#include <pcl/common/centroid.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace {

const std::string kSequence = PCL_MOVERS_SHARED_DATA "/kitti-tracking-0000-a/frames";

struct Track {
  int id;
  Eigen::Vector4f centroid;
};

/** One frame: ground plane out, clusters, nearest-centroid association; rows to `out`. */
void processFrame(const std::string& path, int frame, std::vector<Track>& tracks, int& next_id,
                  std::FILE* out) {
  using Cloud = pcl::PointCloud<pcl::PointXYZI>;
  Cloud::Ptr cloud(new Cloud), objects(new Cloud);
  pcl::io::loadPCDFile(path, *cloud);
  pcl::SACSegmentation<pcl::PointXYZI> sac;
  sac.setModelType(pcl::SACMODEL_PLANE);
  sac.setMethodType(pcl::SAC_RANSAC);
  sac.setDistanceThreshold(0.2);
  sac.setMaxIterations(100);
  sac.setInputCloud(cloud);
  pcl::PointIndices::Ptr ground(new pcl::PointIndices);
  pcl::ModelCoefficients plane;
  sac.segment(*ground, plane);
  pcl::ExtractIndices<pcl::PointXYZI> extract;
  extract.setInputCloud(cloud);
  extract.setIndices(ground);
  extract.setNegative(true);
  extract.filter(*objects);
  pcl::search::KdTree<pcl::PointXYZI>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZI>);
  tree->setInputCloud(objects);
  std::vector<pcl::PointIndices> clusters;
  pcl::EuclideanClusterExtraction<pcl::PointXYZI> ece;
  ece.setClusterTolerance(0.5);
  ece.setMinClusterSize(20);
  ece.setMaxClusterSize(25000);
  ece.setSearchMethod(tree);
  ece.setInputCloud(objects);
  ece.extract(clusters);
  std::vector<Track> now;
  for (const auto& c : clusters) {
    Eigen::Vector4f centroid;
    pcl::compute3DCentroid(*objects, c.indices, centroid);
    int id = -1;
    float best = 2.0f;  // m: nearest previous centroid within 2 m
    for (const auto& t : tracks) {
      const float d = (t.centroid - centroid).head<3>().norm();
      if (d < best) best = d, id = t.id;
    }
    if (id < 0) id = next_id++;
    now.push_back({id, centroid});
    std::fprintf(out, "%d,%d,%.3f,%.3f,%.3f,%zu\n", frame, id, centroid.x(), centroid.y(),
                 centroid.z(), c.indices.size());
  }
  tracks = std::move(now);
}

void BM_PclBaselineEndToEnd(benchmark::State& state) {
  std::vector<std::string> frames;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(kSequence, ec))
    if (e.path().extension() == ".pcd") frames.push_back(e.path().string());
  if (frames.empty()) {
    state.SkipWithError(("no frames in " + kSequence + " (../shared/data absent)").c_str());
    return;
  }
  std::sort(frames.begin(), frames.end());
  const std::string out_path = std::filesystem::temp_directory_path() / "pcl_baseline_tracks.csv";
  double seconds = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    std::FILE* out = std::fopen(out_path.c_str(), "w");
    std::vector<Track> tracks;
    int next_id = 0;
    for (std::size_t f = 0; f < frames.size(); ++f)
      processFrame(frames[f], static_cast<int>(f), tracks, next_id, out);
    std::fclose(out);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  std::filesystem::remove(out_path, ec);
  state.counters["frames"] = static_cast<double>(frames.size());
  state.counters["wall_ms_per_frame"] =
      1000.0 * seconds / static_cast<double>(state.iterations() * frames.size());
}
BENCHMARK(BM_PclBaselineEndToEnd)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
