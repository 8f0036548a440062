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

std::string describe(const Options& d) {
  auto or_scenario = [](bool unset, const std::string& v) {
    return unset ? std::string("scenario's value") : v;
  };
  std::string s;
  s += "  --frames N      number of frames (default: " +
       or_scenario(d.frames <= 0, std::to_string(d.frames)) + ")\n";
  s += "  --seed S        random seed for noise, dropouts, foliage and clutter placement "
       "(default: " +
       or_scenario(d.seed < 0, std::to_string(d.seed)) + ")\n";
  s += "  --sensor NAME   hdl64, hdl32, vlp16, os1_64, ladar2d (default: " +
       or_scenario(d.sensor.empty(), d.sensor) + ")\n";
  std::string families;
  for (const auto& f : pcl_movers::sim::sceneFamilies())
    families += (families.empty() ? "" : ", ") + f;
  s += "  --family NAME   generate a whole scene of a family instead of reading SCENARIO.yaml:\n"
       "                  " +
       families +
       "; --seed picks the scene (default 1; odd seeds\n"
       "                  are the corpus's tune half, even seeds its check half), --frames its\n"
       "                  length (default " +
       std::to_string(pcl_movers::sim::SceneOptions().frames) + ")\n";
  s += "  --print-yaml    print the scenario file (generated or read) to stdout and stop\n";
  s += "  --pcap FILE     also write the scene as a Velodyne packet capture (libpcap file of the\n"
       "                  sensor's UDP data packets, one turn per frame; hdl32, vlp16 or hdl64;\n"
       "                  for hdl64 the calibration XML goes beside it as FILE.xml). Reading it\n"
       "                  back (pcl_movers_organize --pcap) gives the frames to 2 mm / 0.01 deg\n"
       "                  (default: " +
       (d.pcap.empty() ? std::string("none") : d.pcap) + ")\n";
  s += std::string("  --overwrite     replace the sequence in a non-empty OUT_FOLDER (default: ") +
       (d.overwrite ? "on" : "off") + ")\n";
  s +=
      std::string("  --progress      show progress even when stderr is not a terminal (default: ") +
      (d.progress ? "on" : "off") + ")\n";
  return s;
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
      "Options:\n%s  -h, --help      this help\n",
      prog, prog, prog, describe(Options()).c_str());
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
    const std::vector<std::string> with_value = {"--frames", "--seed", "--sensor", "--family",
                                                 "--pcap"};
    tools::checkArguments(argc, argv, {"--overwrite", "--progress", "--print-yaml"}, with_value);
    const auto positional = tools::positionalArguments(argc, argv, with_value);
    Options opt;
    for (int i = 1; i + 1 < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--frames") opt.frames = int(parseInteger(a, argv[i + 1], 1, 1000000));
      if (a == "--seed") opt.seed = parseInteger(a, argv[i + 1], 0, (1LL << 53));
      if (a == "--sensor") opt.sensor = argv[i + 1];
      if (a == "--family") opt.family = argv[i + 1];
      if (a == "--pcap") opt.pcap = argv[i + 1];
    }
    opt.overwrite = pcl::console::find_switch(argc, argv, "--overwrite");
    opt.progress = pcl::console::find_switch(argc, argv, "--progress");
    opt.print_yaml = pcl::console::find_switch(argc, argv, "--print-yaml");
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
