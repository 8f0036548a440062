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

/** a[i] - b[i] for every frame. */
std::vector<double> pairedDifferences(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d(std::min(a.size(), b.size()));
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = a[i] - b[i];
  return d;
}

/** Per frame, the fastest of the passes given to it: per stage (wall) and the thread's CPU time. */
struct FrameTimes {
  std::map<std::string, std::vector<double>> stage_ms;
  std::vector<double> cpu_ms;
  std::vector<double> registrations;
};

/** Frame i of `seq` through `detector`, keeping the frame's fastest time in `t`. */
void timeFrame(const Sequence& seq, std::size_t i, Detector& detector, FrameTimes& t) {
  const std::size_t n = seq.scans.size();
  t.cpu_ms.resize(n, std::numeric_limits<double>::max());
  Detector::FrameResult result;
  const double cpu0 = pcl_movers_bench::threadCpuMs();
  detector.process(seq.scans[i], seq.poses[i], seq.times[i], static_cast<int>(i), result);
  t.cpu_ms[i] = std::min(t.cpu_ms[i], pcl_movers_bench::threadCpuMs() - cpu0);
  for (const auto& stage : detector.getTimings()) {
    auto& v = t.stage_ms[stage.first];
    v.resize(n, std::numeric_limits<double>::max());
    v[i] = std::min(v[i], stage.second);
  }
  if (t.registrations.size() < n)
    t.registrations.push_back(detector.getTracker().getRegistrationCount());
  benchmark::DoNotOptimize(result.rows.data());
}

/** One pass of the whole sequence through a fresh detector, keeping each frame's fastest time. */
void timePass(const Sequence& seq, const pcl_movers::DetectorParameters& params, FrameTimes& t) {
  Detector detector;
  detector.setParameters(params);
  for (std::size_t i = 0; i < seq.scans.size(); ++i) timeFrame(seq, i, detector, t);
}

/** One pass through two fresh detectors side by side: each frame through one and then the
 * other (which goes first alternates), so that both meet the host in the same state. */
void timePairedPass(const Sequence& seq, const pcl_movers::DetectorParameters& params_a,
                    const pcl_movers::DetectorParameters& params_b, FrameTimes& a, FrameTimes& b) {
  Detector detector_a, detector_b;
  detector_a.setParameters(params_a);
  detector_b.setParameters(params_b);
  for (std::size_t i = 0; i < seq.scans.size(); ++i) {
    if (i % 2 == 0) {
      timeFrame(seq, i, detector_a, a);
      timeFrame(seq, i, detector_b, b);
    } else {
      timeFrame(seq, i, detector_b, b);
      timeFrame(seq, i, detector_a, a);
    }
  }
}

// Per frame, the fastest of kPasses runs of the whole sequence (the detector is deterministic:
// every pass does the same work), as for the tracker benchmark: short interruptions by other
// processes then do not count. (Slower periods of a shared host, which last longer than a pass,
// still do.)
constexpr int kPasses = 3;

void runSequence(benchmark::State& state, const std::string& mode) {
  const auto& seq = kittiSequence();
  if (!seq.error.empty()) {
    state.SkipWithError(seq.error.c_str());
    return;
  }
  pcl_movers::DetectorParameters params;
  params.track.mode = mode;
  FrameTimes t;
  for (auto _ : state) {
    t = FrameTimes();
    for (int pass = 0; pass < kPasses; ++pass) timePass(seq, params, t);
  }
  for (const auto& name : Detector::stageNames())
    state.counters[name + "_ms"] = median(t.stage_ms[name]);
  state.counters["total_cpu_ms"] = median(t.cpu_ms);
  state.counters["registrations"] = median(t.registrations);
  state.counters["frames"] = static_cast<double>(seq.scans.size());
}

void BM_DetectorKitti_Registration(benchmark::State& state) {
  runSequence(state, "registration");
}
void BM_DetectorKitti_Centroid(benchmark::State& state) {
  runSequence(state, "centroid");
}

/** What the motion-aware split adds per frame: registration mode with and without it, frame by
 * frame side by side (timePairedPass()), so that a slower period of the host weighs on both
 * alike. */
void BM_DetectorKitti_SplitCost(benchmark::State& state) {
  const auto& seq = kittiSequence();
  if (!seq.error.empty()) {
    state.SkipWithError(seq.error.c_str());
    return;
  }
  pcl_movers::DetectorParameters with, without;
  without.free_space.split = false;
  FrameTimes on, off;
  for (auto _ : state) {
    on = off = FrameTimes();
    for (int pass = 0; pass < kPasses; ++pass) timePairedPass(seq, with, without, on, off);
  }
  state.counters["with_split_ms"] = median(on.stage_ms["total"]);
  state.counters["without_split_ms"] = median(off.stage_ms["total"]);
  state.counters["with_split_cpu_ms"] = median(on.cpu_ms);
  state.counters["without_split_cpu_ms"] = median(off.cpu_ms);
  state.counters["split_ms"] = median(on.stage_ms["split"]);
  // The cost as the median of the frames' own differences: a frame's time varies with its
  // content far more than with the split, and the difference of two medians carries both
  // distributions' noise.
  state.counters["added_ms"] =
      median(pairedDifferences(on.stage_ms["total"], off.stage_ms["total"]));
  state.counters["added_cpu_ms"] = median(pairedDifferences(on.cpu_ms, off.cpu_ms));
}

BENCHMARK(BM_DetectorKitti_Registration)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_DetectorKitti_Centroid)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_DetectorKitti_SplitCost)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
