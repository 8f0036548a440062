/*
 * pcl_movers_simulate: scenario file → sequence folder with ground truth (frames/*.pcd organized,
 * labels/*.label, poses.txt, times.txt, objects.txt).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include "tool_utils.h"

#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/velodyne_capture.h>
#include <pcl_movers/sim/capture.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>
#include <pcl_movers/sim/scene_families.h>

#include <pcl/console/parse.h>
#include <pcl/console/print.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

namespace {

using pcl_movers::InputError;

/** Command-line options. Defaults live here only; the help text is generated from them. */
struct Options {
  int frames = 0;           ///< 0 = the scenario's `frames`
  long long seed = -1;      ///< < 0 = the scenario's `seed`
  std::string sensor;       ///< "" = the scenario's `sensor.preset`
  std::string family;       ///< generate the scene of this family instead of reading a file
  std::string pcap;         ///< also write the scene as a Velodyne packet capture
  bool print_yaml = false;  ///< print the scenario file and stop
  bool overwrite = false;
  bool progress = false;  ///< force the progress bar when stderr is not a terminal
};

pcl_movers::tools::OptionTable optionTable() {
  const Options d;
  const std::string scenario = "the scenario's value";
  std::string families;
  for (const auto& f : pcl_movers::sim::sceneFamilies())
    families += (families.empty() ? "" : ", ") + f;
  return pcl_movers::tools::OptionTable(
      {{"--frames", "N", "number of frames", d.frames <= 0 ? scenario : std::to_string(d.frames)},
       {"--seed", "S", "random seed for noise, dropouts, foliage and clutter placement",
        d.seed < 0 ? scenario : std::to_string(d.seed)},
       {"--sensor", "NAME", "hdl64, hdl32, vlp16, os1_64, ladar2d",
        d.sensor.empty() ? scenario : d.sensor},
       {"--family", "NAME",
        "generate a whole scene of a family instead of reading SCENARIO.yaml:\n" + families +
            ";\n--seed picks the scene (default 1; odd seeds are the corpus's tune\nhalf, even "
            "seeds its check half), --frames its length (default " +
            std::to_string(pcl_movers::sim::SceneOptions().frames) + ")"},
       {"--print-yaml", "", "print the scenario file (generated or read) to stdout and stop"},
       {"--pcap", "FILE",
        "also write the scene as a Velodyne packet capture (libpcap file of the\nsensor's UDP "
        "data packets, one turn per frame; hdl32, vlp16 or hdl64;\nfor hdl64 the calibration "
        "XML goes beside it as FILE.xml). Reading it\nback (pcl_movers_organize --pcap) gives the "
        "frames to 2 mm / 0.01 deg",
        d.pcap.empty() ? "none" : d.pcap},
       {"--recording", "",
        "write the scene as a recording looks: OUT_FOLDER/NNNNNN.bin (KITTI\nfloat32 x y z "
        "intensity, no-return points left out, labels/ to\nmatch) and poses.tum (TUM: time x y z "
        "qx qy qz qw) instead of\nframes/*.pcd and poses.txt"},
       {"--overwrite", "", "replace the sequence in a non-empty OUT_FOLDER",
        d.overwrite ? "on" : "off"},
       {"--progress", "", "show progress even when stderr is not a terminal",
        d.progress ? "on" : "off"}});
}

void printHelp(const char* prog) {
  pcl::console::print_info(
      "Usage: %s SCENARIO.yaml OUT_FOLDER [options]\n"
      "       %s --family NAME [--seed S] OUT_FOLDER [options]\n"
      "       %s SCENARIO.yaml | --family NAME [--seed S]  --print-yaml\n\n"
      "Ray-casts a scenario (see data/scenarios/README.md) into a sequence folder:\n"
      "  frames/NNNNNN.pcd   organized scans (rows = beams), sensor frame, x y z intensity,\n"
      "                      NaN where there is no return\n"
      "  labels/NNNNNN.label SemanticKITTI labels, one per organized point\n"
      "  poses.txt times.txt objects.txt scenario.yaml\n"
      "The same scenario and seed give byte-identical output.\n\n"
      "Options (-h, --help: this help):\n%s",
      prog, prog, prog, optionTable().help().c_str());
}

/** --recording: frames/NNNNNN.pcd -> NNNNNN.bin (finite points only, labels/ cut to match),
 * poses.txt -> poses.tum. */
void toRecording(const std::string& folder) {
  namespace fs = std::filesystem;
  const pcl_movers::io::SequenceReader reader(folder);
  std::ofstream tum(fs::path(folder) / "poses.tum");
  tum << "# timestamp x y z qx qy qz qw (sensor -> world)\n";
  for (std::size_t i = 0; i < reader.size(); ++i) {
    pcl::PointCloud<pcl::PointXYZI> cloud;
    reader.read(i, cloud);
    const fs::path labels_path = fs::path(folder) / "labels" / (reader.frameName(i) + ".label");
    std::vector<std::uint32_t> labels(cloud.size(), 0);
    std::ifstream(labels_path, std::ios::binary)
        .read(reinterpret_cast<char*>(labels.data()), std::streamsize(4 * labels.size()));
    std::ofstream bin(fs::path(folder) / (reader.frameName(i) + ".bin"), std::ios::binary);
    std::ofstream label(labels_path, std::ios::binary | std::ios::trunc);
    for (std::size_t k = 0; k < cloud.size(); ++k) {
      const auto& p = cloud[k];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
      const float xyzi[4] = {p.x, p.y, p.z, p.intensity};
      bin.write(reinterpret_cast<const char*>(xyzi), sizeof(xyzi));
      label.write(reinterpret_cast<const char*>(&labels[k]), 4);
    }
    if (!bin || !label) throw InputError(folder, 0, "cannot write " + reader.frameName(i) + ".bin");
    const Eigen::Isometry3d pose = reader.pose(i);
    const Eigen::Quaterniond q(pose.rotation());
    char line[256];
    std::snprintf(line, sizeof(line), "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", reader.time(i),
                  pose.translation().x(), pose.translation().y(), pose.translation().z(), q.x(),
                  q.y(), q.z(), q.w());
    tum << line;
  }
  if (!tum) throw InputError(folder + "/poses.tum", 0, "cannot write");
  fs::remove_all(fs::path(folder) / "frames");
  fs::remove(fs::path(folder) / "poses.txt");
}

long long parseInteger(const std::string& option, const std::string& value, long long lo,
                       long long hi) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || errno == ERANGE || v < lo || v > hi)
    throw InputError("option " + option + ": expected an integer in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "], got '" + value + "'");
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  return pcl_movers::tools::runTool("pcl_movers_simulate", [&]() -> int {
    namespace tools = pcl_movers::tools;
    if (tools::wantsHelp(argc, argv)) {
      printHelp(argv[0]);
      return 0;
    }
    const auto args = optionTable().parse(argc, argv);
    const auto& positional = args.positional;
    Options opt;
    std::string v;
    if (args.get("--frames", v)) opt.frames = int(parseInteger("--frames", v, 1, 1000000));
    if (args.get("--seed", v)) opt.seed = parseInteger("--seed", v, 0, (1LL << 53));
    args.get("--sensor", opt.sensor);
    args.get("--family", opt.family);
    args.get("--pcap", opt.pcap);
    opt.overwrite = args.has("--overwrite");
    opt.progress = args.has("--progress");
    opt.print_yaml = args.has("--print-yaml");
    const std::size_t wanted = (opt.family.empty() ? 1 : 0) + (opt.print_yaml ? 0 : 1);
    if (positional.size() != wanted) {
      printHelp(argv[0]);
      throw InputError(std::string("expected ") +
                       (opt.family.empty() ? "SCENARIO" : "no scenario file (--family)") +
                       (opt.print_yaml ? "" : " and OUT_FOLDER") + ", got " +
                       std::to_string(positional.size()) + " positional arguments");
    }
    const std::string out_folder = opt.print_yaml ? std::string() : positional.back();

    // Refuse early, before minutes of simulation (writeSequence checks again).
    if (!opt.print_yaml && !opt.overwrite && !pcl_movers::io::isMissingOrEmptyDirectory(out_folder))
      throw InputError(out_folder, 0, "output folder exists and is not empty (use --overwrite)");
    pcl_movers::sim::Scenario scenario;
    if (!opt.family.empty()) {
      pcl_movers::sim::SceneOptions scene;
      if (opt.frames > 0) scene.frames = opt.frames;
      scenario = pcl_movers::sim::generateScene(
          opt.family, static_cast<std::uint64_t>(opt.seed < 0 ? 1 : opt.seed), scene);
    } else {
      scenario = pcl_movers::sim::loadScenario(positional[0]);
      if (opt.frames > 0) scenario.frames = opt.frames;
      if (opt.seed >= 0) scenario.seed = static_cast<std::uint64_t>(opt.seed);
    }
    if (!opt.sensor.empty()) scenario.sensor.preset = opt.sensor;
    if (opt.print_yaml) {
      pcl_movers::SensorModel::fromName(scenario.sensor.preset);  // validates the sensor name
      std::cout << pcl_movers::sim::toYaml(scenario) << std::flush;
      return 0;
    }
    pcl_movers::sim::LidarSimulator simulator(scenario);  // validates the sensor name
    if (!opt.pcap.empty()) {  // refuse before minutes of simulation (writeCapture checks again)
      try {
        pcl_movers::io::velodyneModelFromName(simulator.getSensor().name());
      } catch (const InputError&) {
        throw InputError("--pcap " + opt.pcap + ": sensor '" + simulator.getSensor().name() +
                         "' has no Velodyne packet format (hdl32, vlp16, hdl64)");
      }
      if (std::filesystem::exists(opt.pcap) && !opt.overwrite)
        throw InputError(opt.pcap, 0, "exists (use --overwrite to replace it)");
    }

    pcl::console::print_info("Simulating '%s': %d frames, %s, %zu objects, seed %llu → %s\n",
                             scenario.name.c_str(), scenario.frames,
                             simulator.getSensor().name().c_str(), simulator.getObjectCount(),
                             static_cast<unsigned long long>(scenario.seed), out_folder.c_str());
    tools::ProgressBar bar(std::size_t(scenario.frames), "frames", opt.progress);
    const auto start = std::chrono::steady_clock::now();
    pcl_movers::sim::writeSequence(simulator, out_folder, opt.overwrite,
                                   [&](std::size_t done, std::size_t) { bar.update(done); });
    bar.finish();
    if (args.has("--recording")) toRecording(out_folder);
    if (!opt.pcap.empty()) {
      pcl_movers::sim::writeCapture(simulator, opt.pcap, opt.overwrite);
      pcl::console::print_info(
          "Wrote the capture %s%s\n", opt.pcap.c_str(),
          simulator.getSensor().name() == "hdl64"
              ? (" and its calibration " + pcl_movers::sim::captureCalibrationPath(opt.pcap))
                    .c_str()
              : "");
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    pcl::console::print_info("Wrote %d frames in %.1f s (%.1f frames/s, including PCD writing)\n",
                             scenario.frames, seconds, scenario.frames / std::max(seconds, 1e-9));
    return 0;
  });
}
