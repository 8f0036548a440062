/*
 * Long-run driver (issue #8, docs/reliability.md): simulates a scenario frame by frame in memory
 * (no disk I/O, so the numbers are the pipeline's own) and feeds each frame to MoverDetector.
 * Prints resident memory (VmRSS from /proc/self/status) at chosen frames and ms/frame per block
 * of frames, as Markdown table rows. Exit code 1 when memory or throughput degrade beyond the
 * bounds given on the command line, so scripts/long_run.sh can gate on it.
 *
 *   pcl_movers_long_run SCENARIO [--frames N] [--block 500] [--rss-tolerance 0.10]
 *                                [--slowdown-tolerance 0.25]
 *
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/mover_detector.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <pcl/console/print.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace {

/** VmRSS in KiB, or -1 when /proc is not available. */
long residentKiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atol(line.c_str() + 6);
  return -1;
}

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s SCENARIO [--frames N] [--block 500] [--rss-tolerance 0.10] "
               "[--slowdown-tolerance 0.25]\n",
               argv0);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage(argv[0]);
  std::string scenario_path;
  int frames = -1, block = 500;
  double rss_tolerance = 0.10, slowdown_tolerance = 0.25;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--frames" && has_value)
      frames = std::atoi(argv[++i]);
    else if (a == "--block" && has_value)
      block = std::max(1, std::atoi(argv[++i]));
    else if (a == "--rss-tolerance" && has_value)
      rss_tolerance = std::atof(argv[++i]);
    else if (a == "--slowdown-tolerance" && has_value)
      slowdown_tolerance = std::atof(argv[++i]);
    else if (!a.empty() && a[0] != '-' && scenario_path.empty())
      scenario_path = a;
    else
      return usage(argv[0]);
  }
  if (scenario_path.empty()) return usage(argv[0]);

  // PCL's sample-consensus warnings (collinear samples on sparse cells) would flood the output.
  pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
  try {
    const auto scenario = pcl_movers::sim::loadScenario(scenario_path);
    pcl_movers::sim::LidarSimulator simulator(scenario);
    if (frames <= 0) frames = simulator.getFrameCount();

    pcl_movers::MoverDetector<pcl::PointXYZI> detector;
    pcl_movers::DetectorParameters params;
    params.sensor = scenario.sensor.preset;
    params.ground.sensor_height = scenario.sensor.height;
    detector.setParameters(params);
    detector.setSensorModel(simulator.getSensor());

    // Memory is sampled at the frames the issue names (300 is the reference: by then every
    // buffer has reached its working size) plus the end.
    std::vector<int> checkpoints{300, 1000, 2000, 3000};
    checkpoints.erase(
        std::remove_if(checkpoints.begin(), checkpoints.end(), [&](int f) { return f > frames; }),
        checkpoints.end());
    if (checkpoints.empty() || checkpoints.back() != frames) checkpoints.push_back(frames);

    std::vector<std::pair<int, long>> rss;
    std::vector<double> block_ms;  // detector ms/frame of each block
    std::vector<int> block_tracks;
    double block_sum = 0;
    long rows = 0, mover_rows = 0;
    auto scan = pcl::make_shared<pcl::PointCloud<pcl::PointXYZI>>();
    std::vector<std::uint32_t> labels;
    std::vector<pcl_movers::io::GroundTruthObject> objects;
    pcl_movers::MoverDetector<pcl::PointXYZI>::FrameResult result;
    for (int f = 0; f < frames; ++f) {
      Eigen::Isometry3d pose;
      simulator.simulate(f, *scan, labels, objects, pose);
      const auto t0 = std::chrono::steady_clock::now();
      detector.process(scan, pose, simulator.time(f), f, result);
      const auto t1 = std::chrono::steady_clock::now();
      block_sum += std::chrono::duration<double, std::milli>(t1 - t0).count();
      rows += long(result.rows.size());
      for (const auto& r : result.rows) mover_rows += r.mover ? 1 : 0;
      if ((f + 1) % block == 0 || f + 1 == frames) {
        const int n = (f + 1) % block == 0 ? block : (f + 1) % block;
        block_ms.push_back(block_sum / n);
        block_tracks.push_back(int(detector.getTracker().getTracks().size()));
        block_sum = 0;
      }
      if (std::find(checkpoints.begin(), checkpoints.end(), f + 1) != checkpoints.end())
        rss.emplace_back(f + 1, residentKiB());
    }

    std::printf("| after frame | VmRSS [MiB] | vs. frame %d |\n|---:|---:|---:|\n",
                rss.front().first);
    const double ref = double(rss.front().second);
    double worst_rss = 0;
    for (const auto& [frame, kib] : rss) {
      const double rel = ref > 0 ? (double(kib) - ref) / ref : 0;
      worst_rss = std::max(worst_rss, rel);
      std::printf("| %d | %.1f | %+.1f %% |\n", frame, kib / 1024.0, 100 * rel);
    }
    std::printf("\n| frames | detector ms/frame | live tracks at block end |\n|---|---:|---:|\n");
    for (std::size_t b = 0; b < block_ms.size(); ++b)
      std::printf("| %zu–%zu | %.2f | %d |\n", b * block + 1,
                  std::min<std::size_t>((b + 1) * block, std::size_t(frames)), block_ms[b],
                  block_tracks[b]);
    // Throughput: the last full block against the second (the first includes warm-up).
    const bool last_full = frames % block == 0;
    const std::size_t full_blocks = block_ms.size() - (last_full ? 0 : 1);
    const double base = full_blocks > 1 ? block_ms[1] : block_ms[0];
    const double last = full_blocks > 0 ? block_ms[full_blocks - 1] : block_ms.back();
    const double slowdown = base > 0 ? (last - base) / base : 0;
    std::printf("\nframes: %d, track rows: %ld (mover rows: %ld), tracks started: %d\n", frames,
                rows, mover_rows, detector.getTracker().getTracksStarted());
    std::printf(
        "max RSS growth vs. frame %d: %+.1f %% (bound %.0f %%); ms/frame of the last full "
        "block vs. block 2: %+.1f %% (bound %.0f %%)\n",
        rss.front().first, 100 * worst_rss, 100 * rss_tolerance, 100 * slowdown,
        100 * slowdown_tolerance);
    const bool ok = worst_rss <= rss_tolerance && slowdown <= slowdown_tolerance;
    std::printf("result: %s\n", ok ? "PASS" : "FAIL");
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcl_movers_long_run: %s\n", e.what());
    return 1;
  }
}
