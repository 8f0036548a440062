/*
 * pcl_movers_organize — unorganized LiDAR scans (PCD or KITTI .bin) → organized range-image PCDs
 * (RangeImageOrganizer): rows = beams top to bottom, columns = azimuth, NaN in empty cells; or a
 * Velodyne packet capture (--pcap) → one organized PCD per sweep (io::VelodyneCapture).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/velodyne_capture.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/sensor_model.h>

#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "tool_utils.h"

namespace fs = std::filesystem;
using pcl_movers::InputError;
using Point = pcl::PointXYZI;
using Cloud = pcl::PointCloud<Point>;

namespace {

/** Options and their defaults: the help text is generated from a default-constructed one. */
struct Options {
  std::string sensor = "auto";
  std::string pcap;         ///< a Velodyne capture instead of scans
  std::string calibration;  ///< VeloView/PCL calibration XML for --pcap
  int columns = pcl_movers::RangeImageOrganizer<Point>().getColumns();
  float max_range = pcl_movers::RangeImageOrganizer<Point>().getMaxRange();
  bool overwrite = false;
};

const char* kSensors = "hdl64, hdl32, vlp16, os1_64, ladar2d or auto";

pcl_movers::tools::OptionTable optionTable() {
  const Options d;
  return pcl_movers::tools::OptionTable(
      {{"--sensor", "S",
        std::string("beam layout: ") + kSensors +
            ";\nauto estimates it from the first scan and uses it for all, or the\npreset whose "
            "beams it recognizes; hdl64 is KITTI's calibrated HDL-64E.\nWith --pcap: hdl32, vlp16 "
            "or hdl64; auto tells it from the packets'\nfactory byte",
        d.sensor},
       {"--pcap", "FILE", "read a Velodyne capture instead of scans (see above)"},
       {"--calib",
        "XML",
        "with --pcap: VeloView/PCL calibration file (db.xml format), required\nfor hdl64, "
        "optional for hdl32 (default PCL's table), refused for vlp16",
        "",
        {"--calibration"}},
       {"--columns", "N",
        "azimuth columns per image (0 = the sensor's: hdl64 2200,\nhdl32/os1_64 2048, vlp16 "
        "1800, ladar2d 360, auto: the beams' firings\nper turn + 2 %)",
        std::to_string(d.columns)},
       {"--max-range", "M", "leave out points further than M metres (0 = no limit)",
        pcl_movers::tools::str(d.max_range)},
       {"--overwrite", "", "replace an existing output file or non-empty output folder"}});
}

void printHelp(const char* argv0) {
  std::printf(
      "Usage: %s INPUT OUTPUT [options]\n"
      "       %s --pcap CAPTURE.pcap OUT_FOLDER [--sensor hdl32|vlp16|hdl64] [--calib XML]\n"
      "  Turns unorganized LiDAR scans into organized clouds (range images): one row per beam,\n"
      "  top to bottom, one column per azimuth step, NaN where no return (pcl_movers::\n"
      "  RangeImageOrganizer). Each point goes to the beam that best explains it, taking the\n"
      "  lasers' vertical offsets into account; when two points share a cell the second takes a\n"
      "  free neighbouring column, else the nearer one wins. Scans that are already organized\n"
      "  are copied unchanged.\n\n"
      "  INPUT is a .pcd or KITTI .bin scan, or a sequence folder (frames/*.pcd, *.pcd or\n"
      "  velodyne/*.bin). OUTPUT is a folder that receives one <name>.pcd per scan (binary,\n"
      "  fields of the input, VIEWPOINT kept); for a single scan it may also be a .pcd file.\n"
      "  poses.txt, times.txt and objects.txt of a sequence folder are copied along.\n\n"
      "  With --pcap, reads a Velodyne packet capture (libpcap .pcap, as the sensor sends it or\n"
      "  pcl_movers_simulate --pcap writes it) through PCL's HDLGrabber/VLPGrabber decoding and\n"
      "  writes each full sweep (one turn) as OUT_FOLDER/frames/NNNNNN.pcd: organized by the "
      "laser\n"
      "  each return came from (rows top to bottom) and its firing azimuth (the sensor's "
      "columns),\n"
      "  NaN where a laser gave no return; x forward, y left, z up; intensity = the sensor's\n"
      "  reflectivity (0-255); time (float) = the firing time in s after the sweep's start (NaN\n"
      "  where no return), for pcl_movers_detect --deskew. times.txt holds each sweep's start\n"
      "  (its first firing, s past the hour from the packets' time stamps), as pcl_movers_detect\n"
      "  --pcap takes it. The output is a sequence folder every pcl_movers tool reads. Partial\n"
      "  turns at the start and end of the capture are left out.\n\n"
      "Options (-h, --help: this help):\n%s",
      argv0, argv0, optionTable().help().c_str());
}

using pcl_movers::tools::parseNumber;

/** Files and the folder this run created, removed again if it fails: no half-written output. */
class OutputGuard {
 public:
  void created(const std::string& path) { files_.push_back(path); }
  void createdFolder(const std::string& path) { folder_ = path; }
  void commit() { committed_ = true; }
  ~OutputGuard() {
    if (committed_) return;
    std::error_code ec;
    for (const auto& f : files_) fs::remove(f, ec);
    if (!folder_.empty() && fs::is_empty(folder_, ec)) fs::remove(folder_, ec);
  }

 private:
  std::vector<std::string> files_;
  std::string folder_;
  bool committed_ = false;
};

/** Writes a binary PCD to a temporary name, then renames it into place. */
void writeAtomically(const std::string& path, const Cloud& cloud, OutputGuard& guard) {
  const std::string tmp = path + ".tmp";
  pcl::PCDWriter writer;
  std::error_code ec;
  if (writer.writeBinary(tmp, cloud) != 0) {
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot write");
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot write (" + ec.message() + ")");
  }
  guard.created(path);
}

/** --pcap: the full sweeps of a Velodyne capture → OUT_FOLDER/frames/NNNNNN.pcd (x y z intensity
 * time) + times.txt. */
int runCapture(const Options& opt, const std::string& output, bool columns_given) {
  pcl_movers::io::VelodyneModel model;
  try {
    model = pcl_movers::io::velodyneModelFor(opt.sensor, opt.pcap);
  } catch (const InputError& e) {
    if (opt.sensor == "auto") throw;
    throw InputError(std::string("--sensor: ") + e.what());
  }
  pcl_movers::io::VelodyneCapture capture(opt.pcap, model, opt.calibration);
  if (columns_given) capture.setColumns(opt.columns);
  // The first sweep before anything is created: no output for a capture without one.
  pcl_movers::io::VelodyneSweep sweep;
  if (!capture.next(sweep)) {
    if (capture.getPacketCount() == 0)
      throw InputError(opt.pcap, 0, "no Velodyne data packets (UDP payloads of 1206 bytes)");
    throw InputError(opt.pcap, 0,
                     "no full sweep in " + std::to_string(capture.getPacketCount()) +
                         " data packets (a sweep is one turn between two azimuth wraps)");
  }
  const bool existed = fs::exists(output);
  try {
    pcl_movers::io::SequenceWriter writer(output, opt.overwrite);
    std::vector<double> times;
    std::size_t returns = 0, collisions = 0;
    do {  // each point's `time` after its sweep's start, the sweep's line of times.txt
      writer.writeFrame(times.size(), *sweep.cloud, sweep.time_offsets);
      times.push_back(sweep.start_time);
      returns += sweep.returns;
      collisions += sweep.collisions;
    } while (capture.next(sweep));
    // The start times as pcl_movers_detect --pcap takes them, to the bit: a detection on this
    // folder gives its tracks (times, velocities, de-skewing).
    writer.writeTimes(times, true);
    pcl::console::print_info(
        "%s (%s): %zu data packets, %zu full sweeps of %d x %d, %.0f returns per sweep, %zu "
        "returns lost to a nearer one in their cell, %zu partial sweeps left out%s -> %s\n",
        opt.pcap.c_str(), pcl_movers::io::velodyneModelName(model).c_str(),
        capture.getPacketCount(), times.size(), capture.getSensorModel().rows(),
        capture.getColumns(), double(returns) / double(times.size()), collisions,
        capture.getPartialSweepCount(), capture.isTruncated() ? " (file cut inside a packet)" : "",
        output.c_str());
  } catch (...) {
    std::error_code ec;
    if (!existed) fs::remove_all(output, ec);
    throw;
  }
  return 0;
}

int run(int argc, char** argv) {
  const auto args = optionTable().parse(argc, argv);
  const auto& positional = args.positional;
  Options opt;
  std::string value;
  if (args.get("--pcap", value)) opt.pcap = value;
  if (args.get("--calib", value)) opt.calibration = value;
  if (!opt.calibration.empty() && opt.pcap.empty()) throw InputError("--calib: only with --pcap");
  if (!opt.pcap.empty() && positional.size() != 1)
    throw InputError("--pcap " + opt.pcap + ": expected one OUT_FOLDER, got " +
                     std::to_string(positional.size()) + " argument(s); see -h");
  if (opt.pcap.empty() && positional.size() != 2)
    throw InputError("expected INPUT and OUTPUT, got " + std::to_string(positional.size()) +
                     " argument(s); see -h");
  opt.overwrite = args.has("--overwrite");
  std::string v;
  if (args.get("--sensor", v)) opt.sensor = v;
  if (args.get("--columns", v)) {
    const double c = parseNumber("--columns", v);
    if (c < 1 || c > 100000 || c != std::floor(c))
      throw InputError("--columns: expected an integer in 1..100000, got '" + v + "'");
    opt.columns = int(c);
  }
  if (args.get("--max-range", v)) {
    opt.max_range = float(parseNumber("--max-range", v));
    if (!(opt.max_range > 0)) throw InputError("--max-range: must be > 0, got '" + v + "'");
  }

  if (!opt.pcap.empty()) return runCapture(opt, positional[0], args.has("--columns"));

  pcl_movers::RangeImageOrganizer<Point> organizer;
  if (opt.sensor != "auto") organizer.setSensorModel(pcl_movers::SensorModel::fromName(opt.sensor));
  organizer.setColumns(opt.columns);
  organizer.setMaxRange(opt.max_range);

  const std::string& input = positional[0];
  const std::string& output = positional[1];
  const auto inputs = pcl_movers::tools::listScanInputs(input);
  if (inputs.empty()) throw InputError(input, 0, "no scans found");
  const bool folder_input = fs::is_directory(input);
  const bool file_output = !folder_input && fs::path(output).extension() == ".pcd";

  OutputGuard guard;
  std::vector<std::string> outputs;
  if (file_output) {
    if (fs::is_directory(output)) throw InputError(output, 0, "is a folder, not a .pcd file");
    if (fs::exists(output) && !opt.overwrite)
      throw InputError(output, 0, "exists (use --overwrite to replace it)");
    const fs::path parent = fs::path(output).parent_path();
    if (!parent.empty() && !fs::is_directory(parent))
      throw InputError(output, 0, "its folder " + parent.string() + " does not exist");
    outputs.push_back(output);
  } else {
    const bool existed = fs::exists(output);
    pcl_movers::io::prepareOutputDirectory(output, opt.overwrite);
    if (!existed) guard.createdFolder(output);
    for (const auto& path : inputs)
      outputs.push_back((fs::path(output) / fs::path(path).stem()).string() + ".pcd");
  }

  std::size_t points = 0, kept = 0, displaced = 0, out_of_view = 0, invalid = 0, passed = 0;
  pcl_movers::tools::ProgressBar bar(inputs.size());
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const Cloud::Ptr cloud = pcl_movers::tools::readScanChecked(inputs[i]);
    organizer.setInputCloud(cloud);
    Cloud image;
    organizer.organize(image);
    if (opt.sensor == "auto" && !organizer.wasPassThrough() && !organizer.hasSensorModel()) {
      // One layout for the whole sequence: the first scan's, or the preset it is recognized as
      // (as pcl_movers_detect does). Keeps every frame the same size.
      const pcl_movers::SensorModel estimated = organizer.getSensorModel();
      const pcl_movers::SensorModel model = pcl_movers::SensorModel::recognize(estimated);
      organizer.setSensorModel(model);
      pcl::console::print_info(
          "estimated beam layout from %s: %d beams, %.2f to %.2f deg, %d columns",
          inputs[i].c_str(), estimated.rows(), estimated.elevations().front() * 180.0 / M_PI,
          estimated.elevations().back() * 180.0 / M_PI, estimated.columns());
      if (model.name() != estimated.name()) {
        pcl::console::print_info("; recognized as %s (its calibration and %d columns used)",
                                 model.name().c_str(), model.columns());
        organizer.organize(image);
      }
      pcl::console::print_info("\n");
    }
    points += cloud->size();
    passed += organizer.wasPassThrough();
    displaced += organizer.getDisplacedCount();
    out_of_view += organizer.getOutOfViewCount();
    invalid += organizer.getInvalidCount();
    for (const int cell : organizer.getCellOfPoint()) kept += cell >= 0;
    writeAtomically(outputs[i], image, guard);
    bar.update(i + 1);
  }
  bar.finish();

  if (folder_input) {
    // Make the output a sequence folder of its own: the other tools read these alongside.
    for (const char* name : {"poses.txt", "times.txt", "objects.txt"}) {
      const fs::path from = fs::path(input) / name;
      if (!fs::exists(from)) continue;
      const fs::path to = fs::path(output) / name;
      std::error_code ec;
      fs::copy_file(from, to, fs::copy_options::overwrite_existing, ec);
      if (ec) throw InputError(to.string(), 0, "cannot copy (" + ec.message() + ")");
      guard.created(to.string());
    }
  }
  guard.commit();
  pcl::console::print_info(
      "%zu scan(s) (%zu already organized), %zu points: %zu in a cell of their own (%.2f %%), "
      "%zu lost their cell to a nearer point, %zu outside the beams/range, %zu NaN -> %s\n",
      inputs.size(), passed, points, kept, points ? 100.0 * double(kept) / double(points) : 0.0,
      displaced, out_of_view, invalid, output.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  return pcl_movers::tools::runTool("pcl_movers_organize", [&] { return run(argc, argv); });
}
