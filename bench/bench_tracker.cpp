/*
 * Thread CPU time of the tracking stage alone (MoverTracker::update) on the 77 real KITTI HDL-64E
 * frames of kitti-tracking-0000-a, in registration and centroid mode.
 *
 * The tracker's inputs (world-frame cluster points, clusters, sensor positions, the free-space
 * map's scans) are produced once by the same stages as MoverDetector::process() before timing,
 * so the counters measure only what the tracker does. Thread CPU time is used because, unlike
 * wall-clock time, it is not inflated while other processes hold the cores; the counters are the
 * medians over the frames (and, per frame, the minimum over the repetitions) in milliseconds.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <benchmark/benchmark.h>
#include <pcl_movers/free_space_map.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/mover_detector.h>
#include <pcl_movers/mover_tracker.h>
#include <pcl_movers/range_image_region_growing.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace {

using PointT = pcl::PointXYZI;
using Cloud = pcl::PointCloud<PointT>;

/** What MoverTracker::update() receives for one frame. */
struct Frame {
  Cloud::ConstPtr organized;  ///< for the free-space map
  Cloud::Ptr world;           ///< cluster points in the world frame
  std::vector<pcl::PointIndices> clusters;
  Eigen::Isometry3d pose;
  double time = 0;
};

struct Inputs {
  std::vector<Frame> frames;
  std::string error;
};

const Inputs& trackerInputs() {
  static Inputs in = [] {
    Inputs s;
    const std::string folder = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a";
    if (!std::filesystem::is_directory(folder)) {
      s.error = "KITTI data not found at " + folder;
      return s;
    }
    try {
      const pcl_movers::DetectorParameters p;
      pcl_movers::io::SequenceReader reader(folder);
      // The detector organizes the scans (with its sensor model); the rest as in process().
      pcl_movers::MoverDetector<PointT> detector;
      detector.setParameters(p);
      for (std::size_t i = 0; i < reader.size(); ++i) {
        Cloud::Ptr scan(new Cloud);
        reader.read(i, *scan);
        scan->sensor_origin_.setZero();
        scan->sensor_orientation_.setIdentity();
        Frame f;
        f.pose = reader.pose(i);
        f.time = reader.time(i);
        pcl_movers::MoverDetector<PointT>::FrameResult result;
        detector.process(scan, f.pose, f.time, static_cast<int>(i), result);
        f.organized = result.organized;
        pcl_movers::GroundPlaneFilter<PointT> ground;
        ground.setInputCloud(f.organized);
        ground.setDistanceThreshold(static_cast<float>(p.ground_distance));
        ground.setMaxTilt(static_cast<float>(p.ground_max_slope_deg * M_PI / 180.0));
        ground.setSensorHeight(static_cast<float>(p.sensor_height));
        ground.setLocalSlopeCheck(p.ground_local_slope != 0);
        pcl::IndicesPtr objects(new pcl::Indices);
        ground.filter(*objects);
        pcl_movers::RangeImageRegionGrowing<PointT> segmenter;
        segmenter.setInputCloud(f.organized);
        segmenter.setIndices(objects);
        segmenter.setDepthThresholdFactor(static_cast<float>(p.depth_ratio));
        segmenter.setMinDepthThreshold(static_cast<float>(p.depth_min));
        segmenter.setMaxGap(p.max_gap);
        segmenter.setMinClusterSize(p.min_cluster_points);
        std::vector<pcl::PointIndices> clusters;
        segmenter.segment(clusters);
        const Eigen::Isometry3f pose_f = f.pose.cast<float>();
        f.world.reset(new Cloud);
        f.clusters.resize(clusters.size());
        for (std::size_t c = 0; c < clusters.size(); ++c)
          for (const auto k : clusters[c].indices) {
            PointT q = (*f.organized)[k];
            q.getVector3fMap() = pose_f * q.getVector3fMap();
            f.clusters[c].indices.push_back(static_cast<int>(f.world->size()));
            f.world->push_back(q);
          }
        s.frames.push_back(std::move(f));
      }
    } catch (const std::exception& e) {
      s.error = e.what();
    }
    return s;
  }();
  return in;
}

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (const double x : v) s += x;
  return v.empty() ? 0 : s / v.size();
}

void runTracker(benchmark::State& state, const std::string& mode) {
  const auto& in = trackerInputs();
  if (!in.error.empty()) {
    state.SkipWithError(in.error.c_str());
    return;
  }
  pcl_movers::DetectorParameters params;
  params.mode = mode;
  const std::size_t n = in.frames.size();
  // Per frame: the fastest of the repetitions (the least disturbed by other processes).
  std::vector<double> cpu_ms(n, std::numeric_limits<double>::max()), registrations(n, 0);
  for (auto _ : state) {
    pcl_movers::MoverTracker<PointT> tracker;
    tracker.setParameters(params);
    pcl_movers::FreeSpaceMap free_space;
    free_space.setHistory(params.free_space_lag + 1);
    free_space.setMargin(params.free_space_margin, params.free_space_margin_per_metre);
    for (std::size_t i = 0; i < n; ++i) {
      const Frame& f = in.frames[i];
      state.PauseTiming();
      if (params.free_space_lag > 0) {
        free_space.addScan(*f.organized, f.pose);
        tracker.setFreeSpaceMap(&free_space);
      }
      state.ResumeTiming();
      const double cpu0 = threadCpuMs();
      tracker.update(f.world, f.clusters, f.pose.translation(), f.time);
      cpu_ms[i] = std::min(cpu_ms[i], threadCpuMs() - cpu0);
      registrations[i] = tracker.getRegistrationCount();
    }
  }
  state.counters["track_cpu_ms"] = median(cpu_ms);
  state.counters["track_cpu_mean_ms"] = mean(cpu_ms);
  state.counters["registrations"] = median(registrations);
  state.counters["registrations_mean"] = mean(registrations);
}

void BM_TrackerKitti_Registration(benchmark::State& state) {
  runTracker(state, "registration");
}
void BM_TrackerKitti_Centroid(benchmark::State& state) {
  runTracker(state, "centroid");
}

BENCHMARK(BM_TrackerKitti_Registration)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TrackerKitti_Centroid)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
