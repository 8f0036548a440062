/*
 * End-to-end and per-stage timing of MoverDetector on the 77 real KITTI HDL-64E frames of
 * kitti-tracking-0000-a (poses from poses.txt), in registration and centroid mode.
 *
 * Each benchmark iteration runs the whole sequence three times, each through a fresh detector; the
 * counters are the per-stage medians over all frames of each frame's fastest pass (ms per frame).
 * Scans are read before timing starts, so I/O is excluded.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <benchmark/benchmark.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/mover_detector.h>
#include "bench_common.h"

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace {

using PointT = pcl::PointXYZI;
using Detector = pcl_movers::MoverDetector<PointT>;

struct Sequence {
  std::vector<pcl::PointCloud<PointT>::ConstPtr> scans;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<double> times;
  std::string error;
};

const Sequence& kittiSequence() {
  static Sequence seq = [] {
    Sequence s;
    const std::string folder = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a";
    if (!std::filesystem::is_directory(folder)) {
      s.error = "KITTI data not found at " + folder;
      return s;
    }
    try {
      pcl_movers::io::SequenceReader reader(folder);
      for (std::size_t i = 0; i < reader.size(); ++i) {
        pcl::PointCloud<PointT>::Ptr scan(new pcl::PointCloud<PointT>);
        reader.read(i, *scan);
        scan->sensor_origin_.setZero();
        scan->sensor_orientation_.setIdentity();
        s.scans.push_back(scan);
        s.poses.push_back(reader.pose(i));
        s.times.push_back(reader.time(i));
      }
    } catch (const std::exception& e) {
      s.error = e.what();
    }
    return s;
  }();
  return seq;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

void runSequence(benchmark::State& state, const std::string& mode, bool split = true) {
  const auto& seq = kittiSequence();
  if (!seq.error.empty()) {
    state.SkipWithError(seq.error.c_str());
    return;
  }
  pcl_movers::DetectorParameters params;
  params.track.mode = mode;
  params.free_space.split = split;
  // Per frame, the fastest of kPasses runs of the whole sequence (the detector is deterministic:
  // every pass does the same work), as for the tracker benchmark: short interruptions by other
  // processes then do not count. (Slower periods of a shared host, which last longer than a
  // pass, still do.)
  constexpr int kPasses = 3;
  std::map<std::string, std::vector<double>> stage_ms;
  std::vector<double> registrations, cpu_ms;
  for (auto _ : state) {
    stage_ms.clear();
    cpu_ms.assign(seq.scans.size(), std::numeric_limits<double>::max());
    registrations.clear();
    for (int pass = 0; pass < kPasses; ++pass) {
      Detector detector;
      detector.setParameters(params);
      for (std::size_t i = 0; i < seq.scans.size(); ++i) {
        Detector::FrameResult result;
        const double cpu0 = pcl_movers_bench::threadCpuMs();
        detector.process(seq.scans[i], seq.poses[i], seq.times[i], static_cast<int>(i), result);
        cpu_ms[i] = std::min(cpu_ms[i], pcl_movers_bench::threadCpuMs() - cpu0);
        for (const auto& t : detector.getTimings()) {
          auto& v = stage_ms[t.first];
          if (v.size() < seq.scans.size())
            v.resize(seq.scans.size(), std::numeric_limits<double>::max());
          v[i] = std::min(v[i], t.second);
        }
        if (pass == 0) registrations.push_back(detector.getTracker().getRegistrationCount());
        benchmark::DoNotOptimize(result.rows.data());
      }
    }
  }
  for (const auto& name : Detector::stageNames())
    state.counters[name + "_ms"] = median(stage_ms[name]);
  state.counters["total_cpu_ms"] = median(cpu_ms);
  state.counters["registrations"] = median(registrations);
  state.counters["frames"] = static_cast<double>(seq.scans.size());
}

void BM_DetectorKitti_Registration(benchmark::State& state) {
  runSequence(state, "registration");
}
void BM_DetectorKitti_Centroid(benchmark::State& state) {
  runSequence(state, "centroid");
}
// The segmentation without the motion-aware split, side by side: what the split adds per frame.
void BM_DetectorKitti_RegistrationNoSplit(benchmark::State& state) {
  runSequence(state, "registration", false);
}

BENCHMARK(BM_DetectorKitti_Registration)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_DetectorKitti_Centroid)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_DetectorKitti_RegistrationNoSplit)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
