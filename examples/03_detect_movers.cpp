/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * Example 3: the whole pipeline over a sequence, scored with the paper's metrics.
 *
 *   03_detect_movers [SEQUENCE_FOLDER [SECTOR_DEG]]
 *
 * A sequence folder is what pcl_movers_simulate writes or a KITTI-style folder (PCDs in frames/
 * or KITTI .bin files in velodyne/, poses.txt, optional times.txt and objects.txt). Without an
 * argument the 40 frames of data/scenarios/sample.yaml are simulated in memory. Each frame goes
 * through MoverDetector (organize → ground → objects → world frame → tracker); the movers of every
 * tenth frame are printed and, when there is ground truth, the run is scored as pcl_movers_eval
 * does (all round, or within ±SECTOR_DEG of the x axis: 40 for KITTI, whose labels cover the camera
 * view only). On the bundled scene it exits with 1 when most of the movers are missed.
 */
#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/eval/detection_metrics.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/mover_detector.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

using Point = pcl::PointXYZI;
using Cloud = pcl::PointCloud<Point>;
using Detector = pcl_movers::MoverDetector<Point>;

int main(int argc, char** argv) {
  try {
    double sector_deg = 180.0;
    if (argc > 2) {
      char* end = nullptr;
      sector_deg = std::strtod(argv[2], &end);
      if (end == argv[2] || *end != '\0' || !(sector_deg > 0.0 && sector_deg <= 180.0))
        throw std::runtime_error(std::string("SECTOR_DEG must be a number in (0, 180], not '") +
                                 argv[2] + "'");
    }
    // The frames come from a folder or from the simulator; both give scan, pose and time.
    std::unique_ptr<pcl_movers::io::SequenceReader> reader;
    std::unique_ptr<pcl_movers::sim::LidarSimulator> simulator;
    std::size_t frames = 0;
    if (argc > 1) {
      reader = std::make_unique<pcl_movers::io::SequenceReader>(argv[1]);
      if (reader->empty()) throw std::runtime_error(std::string(argv[1]) + ": no frames");
      if (!reader->hasPoses())
        std::fprintf(stderr, "%s has no poses: using identity (pcl_movers_detect estimates them)\n",
                     argv[1]);
      frames = reader->size();
    } else {
      simulator = std::make_unique<pcl_movers::sim::LidarSimulator>(
          pcl_movers::sim::loadScenario(PCL_MOVERS_EXAMPLE_SCENARIO));
      frames = static_cast<std::size_t>(simulator->getFrameCount());
    }

    Detector detector;
    pcl_movers::DetectorParameters params;  // the defaults of pcl_movers_detect
    detector.setParameters(params);

    std::vector<pcl_movers::io::TrackRow> rows;
    std::vector<pcl_movers::io::GroundTruthObject> truth;
    std::vector<Eigen::Isometry3d> poses;
    std::vector<double> times;
    for (std::size_t i = 0; i < frames; ++i) {
      Cloud::Ptr scan(new Cloud);
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      double time = 0.0;  // from times.txt (or the rate) or the simulator, below
      if (reader) {
        reader->read(i, *scan);
        if (reader->hasPoses()) pose = reader->pose(i);
        time = reader->time(i);
      } else {
        std::vector<std::uint32_t> labels;
        std::vector<pcl_movers::io::GroundTruthObject> objects;
        simulator->simulate(static_cast<int>(i), *scan, labels, objects, pose);
        time = simulator->time(static_cast<int>(i));
        truth.insert(truth.end(), objects.begin(), objects.end());
      }
      poses.push_back(pose);
      times.push_back(time);

      Detector::FrameResult result;
      detector.process(scan, pose, time, static_cast<int>(i), result);
      rows.insert(rows.end(), result.rows.begin(), result.rows.end());
      if (i % 10 == 0) {
        std::printf("frame %3zu: %3zu tracked objects, movers:", i, result.rows.size());
        for (const auto& r : result.rows)
          if (r.mover) std::printf("  #%d at (%.1f, %.1f) %.1f m/s", r.track_id, r.x, r.y, r.speed);
        std::printf("\n");
      }
    }

    if (reader && std::filesystem::exists(reader->objectsPath()))
      truth = pcl_movers::io::readObjects(reader->objectsPath());
    if (truth.empty()) return 0;
    pcl_movers::eval::DetectionMetricsParams metrics;
    metrics.sector_deg = sector_deg;
    const auto score = pcl_movers::eval::scoreDetections(truth, rows, metrics, poses, times);
    std::printf("\n%s", pcl_movers::eval::formatMarkdown(score).c_str());
    // Self-check on the bundled scene (it runs as a test): its movers are found most of the time
    // (docs/evaluation.md has the full evaluation).
    if (reader) return 0;
    const bool ok = score.mean_hit_rate > 0.5;
    if (!ok)
      std::fprintf(stderr, "error: mean hit rate %.2f on the bundled scene\n", score.mean_hit_rate);
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
