/*
 * libFuzzer target: scenario text → sim::parseScenario (the YAML subset parser and the scenario
 * validation). Hand-written scenario files are the simulator's user input; every malformed one
 * must end in an InputError "file:line: reason", never a crash, hang or other exception type.
 * Valid scenarios are also turned into a LidarSimulator and one small frame is simulated, so
 * values that parse but make no sense (zero sizes, huge counts) are caught too.
 *
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/sensor_model.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <pcl/console/print.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  pcl_movers::sim::Scenario scenario;
  try {
    scenario = pcl_movers::sim::parseScenario(text, "fuzz.yaml");
  } catch (const pcl_movers::InputError&) {
    return 0;
  }
  // Simulating is far slower than parsing; keep it to what a unit test would do so the fuzzer
  // spends its time on the parser. Clutter counts and long trajectories are bounded here only to
  // keep each input fast — their validation is the parser's job and is exercised above.
  // The simulator lays out the scene for the whole recording (mover paths sampled every 0.05 s
  // are rasterised to keep clutter off them), so the recording's duration is bounded too: the
  // 5-minute long_run.yaml seed took ~9 s of instrumented CPU per input, 20-30 s wall on a
  // loaded machine — past the per-input timeout, though it is a valid scenario, not a hang.
  if (scenario.frames > 100000 || scenario.clutter.size() > 4) return 0;
  if (!(double(scenario.frames) / scenario.rate_hz <= 60.0)) return 0;
  for (const auto& c : scenario.clutter)
    if (c.count > 50) return 0;
  if (scenario.objects.size() > 50) return 0;
  try {
    pcl_movers::sim::LidarSimulator simulator(scenario);
    simulator.setSensor(pcl_movers::SensorModel::vlp16());  // 16 beams keep one frame cheap
    pcl::PointCloud<pcl::PointXYZI> organized;
    std::vector<std::uint32_t> labels;
    std::vector<pcl_movers::io::GroundTruthObject> objects;
    Eigen::Isometry3d pose;
    simulator.simulate(0, organized, labels, objects, pose);
  } catch (const pcl_movers::InputError&) {
  }
  return 0;
}
