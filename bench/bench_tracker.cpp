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
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/mover_detector.h>
#include <pcl_movers/mover_tracker.h>
#include "bench_common.h"

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
      // The detector organizes the scans (with its sensor model).
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
        // The detector's own stage functions, so the tracker sees exactly its input.
        const pcl::IndicesPtr objects = detector.removeGround(f.organized);
        const std::vector<pcl::PointIndices> clusters =
            detector.segmentObjects(f.organized, objects);
        f.world.reset(new Cloud);
        pcl_movers::MoverDetector<PointT>::clustersToWorld(*f.organized, clusters, f.pose, *f.world,
                                                           f.clusters);
        s.frames.push_back(std::move(f));
      }
    } catch (const std::exception& e) {
      s.error = e.what();
    }
    return s;
  }();
  return in;
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
  params.track.mode = mode;
  const std::size_t n = in.frames.size();
  // Per frame: the fastest of the repetitions (the least disturbed by other processes).
  std::vector<double> cpu_ms(n, std::numeric_limits<double>::max()), registrations(n, 0);
  for (auto _ : state) {
    pcl_movers::MoverTracker<PointT> tracker;
    tracker.setParameters(params);
    pcl_movers::FreeSpaceMap free_space;
    free_space.setHistory(params.free_space.lag + 1);
    free_space.setMargin(params.free_space.margin, params.free_space.margin_per_metre);
    for (std::size_t i = 0; i < n; ++i) {
      const Frame& f = in.frames[i];
      state.PauseTiming();
      if (params.free_space.lag > 0) {
        free_space.addScan(*f.organized, f.pose);
        tracker.setFreeSpaceMap(&free_space);
      }
      state.ResumeTiming();
      const double cpu0 = pcl_movers_bench::threadCpuMs();
      tracker.update(f.world, f.clusters, f.pose.translation(), f.time);
      cpu_ms[i] = std::min(cpu_ms[i], pcl_movers_bench::threadCpuMs() - cpu0);
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
