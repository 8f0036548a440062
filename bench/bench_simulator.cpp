/*
 * Speed of LidarSimulator::simulate (ray casting + ground truth of one frame, no file writing) on
 * the shipped scenarios. Counters: objects in the scene, returns per frame, rays per second.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

namespace {

void simulateScenario(benchmark::State& state, const std::string& name, const std::string& sensor) {
  pcl_movers::sim::Scenario sc = pcl_movers::sim::loadScenario(std::string(PCL_MOVERS_SOURCE_DIR) +
                                                               "/data/scenarios/" + name + ".yaml");
  if (!sensor.empty()) sc.sensor.preset = sensor;
  pcl_movers::sim::LidarSimulator sim(sc);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  std::vector<std::uint32_t> labels;
  std::vector<pcl_movers::io::GroundTruthObject> objects;
  Eigen::Isometry3d pose;
  int frame = 0;
  std::size_t returns = 0, frames = 0;
  for (auto _ : state) {
    sim.simulate(frame, cloud, labels, objects, pose);
    frame = (frame + 7) % sc.frames;  // walk through the whole drive
    for (const auto& p : cloud) returns += std::isfinite(p.x);
    ++frames;
    benchmark::DoNotOptimize(cloud.points.data());
  }
  state.counters["objects"] = double(sim.getObjectCount());
  state.counters["returns"] = double(returns) / double(std::max<std::size_t>(frames, 1));
  state.counters["frames/s"] = benchmark::Counter(double(frames), benchmark::Counter::kIsRate);
  state.counters["rays/s"] =
      benchmark::Counter(double(frames) * double(cloud.size()), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK_CAPTURE(simulateScenario, sample_hdl64, "sample", "")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulateScenario, open_hdl64, "open", "")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulateScenario, urban_hdl64, "urban", "")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulateScenario, wooded_hdl64, "wooded", "")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulateScenario, wooded_vlp16, "wooded", "vlp16")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(simulateScenario, wooded_ladar2d, "wooded", "ladar2d")
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
