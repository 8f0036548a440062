/*
 * pcl_movers_detect SEQ OUT — the mover-detection pipeline on a sequence folder, a Velodyne
 * packet capture (--pcap) or a live sensor (--live). Reading runs on a thread of its own
 * (io::FrameStream), detection and writing on the main thread.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/deskew.h>
#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/ego_motion_estimator.h>
#include <pcl_movers/io/frame_stream.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/point_labels.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/tracks.h>
#include <pcl_movers/io/velodyne_capture.h>
#include <pcl_movers/mover_detector.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/io/pcd_io.h>

#include <signal.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include "tool_utils.h"

namespace fs = std::filesystem;
using pcl::console::print_error;
using pcl::console::print_info;
using pcl::console::print_value;
using pcl_movers::DetectorParameters;
using pcl_movers::InputError;

namespace {

using PointT = pcl::PointXYZI;
using Detector = pcl_movers::MoverDetector<PointT>;

/// In OUT/labelled/: the run_key of the run that wrote the labelled clouds (see summary.json).
const char* const kRunKeyFile = "run_key.txt";

/** The command-line spelling of a parameter key: sensor_height -> --sensor-height. */
std::string optionName(std::string key) {
  std::replace(key.begin(), key.end(), '_', '-');
  return "--" + key;
}

/** Every option, with its default; the parameters' options come from DetectorParameters, so a
 * parameter added there is an option here. */
pcl_movers::tools::OptionTable optionTable() {
  const std::string rate = pcl_movers::tools::str(pcl_movers::io::SequenceOptions().rate_hz);
  pcl_movers::tools::OptionTable table(
      {{"--config", "FILE", "'key = value' lines with any of the parameters below"},
       {"--pcap", "FILE",
        "read a Velodyne packet capture (libpcap) instead of SEQ; --sensor\nhdl32, hdl64 (with "
        "--calibration) or vlp16 (auto: from the packets)"},
       {"--live", "",
        "receive a live Velodyne sensor's UDP packets instead of SEQ\n(--sensor "
        "required; ends on --frames, --duration, SIGINT)"},
       {"--port", "N", "--live: UDP port of the sensor's data packets", "2368"},
       {"--calibration", "XML", "--pcap/--live: VeloView/PCL calibration (db.xml) of the sensor"},
       {"--timeout", "S", "--live: error when no data packet comes for S seconds", "5"},
       {"--frames", "N", "read at most N frames (sweeps), then finish normally"},
       {"--duration", "S", "read for at most S seconds of wall time, then finish normally"},
       {"--queue-capacity", "N",
        "frames read ahead of detection (reading runs on its own thread);\nfull: a folder or "
        "--pcap waits, --live drops the oldest sweep\n(counted in summary.json)",
        "4"},
       {"--rate", "HZ", "frame rate when SEQ has no times.txt", rate},
       {"--poses", "FILE", "sensor poses from FILE instead of SEQ/poses.txt"},
       {"--poses-format", "F",
        "kitti (3x4 rows, one per frame), tum (timestamp x y z qx qy qz qw,\nmatched to the frame "
        "times and interpolated when the counts differ)\nor kitti-camera (KITTI odometry camera "
        "poses)",
        "kitti"},
       {"--calib", "FILE", "KITTI calib.txt for kitti-camera: pose = Tr^-1 * P_cam * Tr"},
       {"--estimate-poses", "",
        "estimate the sensor poses from the scans even when SEQ has poses\n(always done when it "
        "has none; SEQ/poses.txt is then not read)"},
       {"--labelled-clouds", "", "also write OUT/labelled/<input name>.pcd"},
       {"--point-labels", "", "also write OUT/labels/<input name>.label (moving / static)"},
       {"--overwrite", "",
        "write into a non-empty OUT; removes what an earlier run wrote\nthere (tracks.csv, "
        "tracks.json, summary.json, labelled/*.pcd, labels/*.label)"},
       {"--skip-bad-frames", "",
        "a malformed frame (truncated, not a PCD, ...) is warned about,\ncounted in summary.json "
        "and treated as blind instead of an error"},
       {"--resume", "",
        "continue the interrupted run in OUT after its last complete frame\n(same SEQ and "
        "options; the done frames are run again, unwritten)"},
       {"--stop-after-frames", "N", "stop as on SIGINT after N frames (for tests)"},
       {"--print-config", "", "print the parameters as a config file and exit"},
       {"", "",
        "\nParameters, by stage (--stage.name VALUE, or 'stage.name = value' in the config\n"
        "file, where the snake_case key, ground.max_slope_deg, also works; switches take\n"
        "1/0, true/false or on/off; the flat keys of earlier versions, --ground-distance,\n"
        "are read with a warning):"}});
  DetectorParameters().forEachParameter(
      [&](const std::string& key, const auto& value, const char* doc) {
        using T = std::decay_t<decltype(value)>;
        const char* kind = std::is_same<T, std::string>::value ? "S"
                           : std::is_same<T, int>::value       ? "N"
                           : std::is_same<T, bool>::value      ? "0|1"
                                                               : "X";
        std::vector<std::string> legacy;
        for (const auto& old : DetectorParameters::legacyKeys())
          if (old.second == key) {
            legacy.push_back(optionName(old.first));
            legacy.push_back("--" + old.first);  // the snake_case spelling
          }
        table.add({optionName(key), kind, doc, pcl_movers::detail::formatValue(value), legacy});
      });
  return table;
}

void printHelp(const char* name) {
  std::ostringstream os;
  os << "Usage: " << name << " SEQ OUT [options]\n"
     << "       " << name << " --pcap FILE OUT [--sensor hdl32|hdl64|vlp16] [options]\n"
     << "       " << name << " --live --sensor hdl32|hdl64|vlp16 [--port 2368] OUT [options]\n\n"
     << "Detects movers (moving vehicles and people) in the LiDAR sequence folder SEQ (scans\n"
     << ".pcd, .bin (KITTI) or .ply, one format, in SEQ itself, SEQ/frames/ or SEQ/velodyne/;\n"
     << "poses.txt, --poses or PCD VIEWPOINTs; times.txt) and writes to OUT:\n"
     << "  tracks.csv     one row per tracked object per frame (see DESIGN.md), written and\n"
     << "                 flushed frame by frame; `frame` is the 0-based index, `file` the\n"
     << "                 number in the input file's name (000040.bin -> 40)\n"
     << "  tracks.json    per frame: index, file number, time, track ids and the movers (box,\n"
     << "                 velocity, similarity)\n"
     << "  summary.json   state (running/interrupted/finished, last complete frame), blind and\n"
     << "                 bad frames, per-stage timings, counts, the parameters used and the\n"
     << "                 run_key (a hash of input, options and parameters)\n"
     << "  labelled/      with --labelled-clouds: one PCD per frame named as its input file,\n"
     << "                 the input's points in its order with its fields, plus label (0\n"
     << "                 unlabelled or not kept, 1 ground, 2 static, 3 mover) and track (or "
        "-1);\n"
     << "                 run_key.txt: summary.json's run_key (pcl_movers_viewer checks it)\n"
     << "  labels/        with --point-labels: NAME.label per frame (NAME: the input file's name\n"
     << "                 without extension, as labelled/), SemanticKITTI-MOS layout: one\n"
     << "                 little-endian uint32 per input point in the input's order, class in the\n"
     << "                 low 16 bits (mover points 252 car/van, 258 truck, 254 person, 253\n"
     << "                 bicyclist or 251 unknown, from the box size; 9 other returns; 0 no\n"
     << "                 return), the mover's track id in the high 16; all 0 for blind or bad\n"
     << "                 frames. Score with pcl_movers_eval --mos\n\n"
     << "Options (-h, --help: this help):\n"
     << optionTable().help() << "\n"
     << "--sensor auto estimates the beam layout of unorganized scans from the first one and\n"
     << "uses a preset's calibration when it recognizes its beams (organized scans keep theirs).\n"
     << "A frame without returns (or, with --sensor auto, too few to estimate the beam layout\n"
     << "from) is blind: a warning, its tracks coast, the run goes on. SIGINT/SIGTERM stop the "
        "run\n"
     << "after the current frame: tracks.csv keeps every complete frame, summary.json says\n"
     << "\"interrupted\": true, exit code 130/143. Geo-referenced (UTM) poses are fine.\n"
     << "Older spellings with '_' (--sensor_height) still work, with a warning.\n"
     << "--pcap/--live: frame i is the i-th full sweep (tracks.csv frame and file, outputs\n"
     << "NNNNNN.pcd/.label), its time the sweep's first firing [s past the hour, the sensor's\n"
     << "clock]; organized by laser and azimuth (PCL's grabber decodes the packets); --poses\n"
     << "gives one pose per sweep (kitti) or by time (tum), else they are estimated; --deskew\n"
     << "uses the packets' firing times. --live drops the oldest waiting sweep when detection\n"
     << "falls behind (counted: summary.json dropped_frames, progress lines); its tracks.csv\n"
     << "`file` is the sweep number, `frame` the index among the detected ones.\n";
  print_info("%s", os.str().c_str());
}

/** Median of a copy. */
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) {
    m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
  }
  return m;
}

/** The input scan's fields (without any own `label`/`track`, replaced here) plus `label`
 * (uint32) and `track` (int32), in the input's layout. */
void addLabelFields(const pcl::PCLPointCloud2& in, pcl::PCLPointCloud2& out) {
  out.fields.clear();
  for (const auto& f : in.fields)
    if (f.name != "label" && f.name != "track") out.fields.push_back(f);
  const char* names[2] = {"label", "track"};
  const std::uint8_t types[2] = {pcl::PCLPointField::UINT32, pcl::PCLPointField::INT32};
  for (int k = 0; k < 2; ++k) {
    pcl::PCLPointField field;
    field.name = names[k];
    field.offset = in.point_step + 4 * k;  // after the input's bytes, copied as they are
    field.datatype = types[k];
    field.count = 1;
    out.fields.push_back(field);
  }
  out.point_step = in.point_step + 8;
  out.width = in.width;
  out.height = in.height;
  out.row_step = out.point_step * out.width;
  out.is_dense = in.is_dense;
  out.is_bigendian = in.is_bigendian;
}

/** A binary PCD; one without points is its header alone (PCL's writer warns about those). */
void writeLabelledBlob(const std::string& path, const pcl::PCLPointCloud2& blob) {
  pcl::PCDWriter writer;
  if (blob.width * blob.height == 0) {
    std::ofstream f(path);
    f << writer.generateHeaderBinary(blob, Eigen::Vector4f::Zero(), Eigen::Quaternionf::Identity());
    if (!f) throw InputError(path, 0, "cannot write labelled cloud");
    return;
  }
  if (writer.writeBinary(path, blob) != 0) throw InputError(path, 0, "cannot write labelled cloud");
}

/** The detector's per-point labels and track ids of a frame in the order of its `n` input points
 * (through FrameResult::input_indices): class 0 (unlabelled) and track -1 for the points the range
 * image did not keep. Used by the labelled clouds and the point labels alike. */
void toInputOrder(const Detector::FrameResult& result, std::size_t n,
                  std::vector<std::uint32_t>& labels, std::vector<std::int32_t>& tracks) {
  labels.assign(n, Detector::kUnlabelled);
  tracks.assign(n, -1);
  for (std::size_t k = 0; k < result.labels.size(); ++k) {
    const long j = result.input_indices.empty() ? static_cast<long>(k) : result.input_indices[k];
    if (j < 0 || static_cast<std::size_t>(j) >= n) continue;
    labels[static_cast<std::size_t>(j)] = result.labels[k];
    tracks[static_cast<std::size_t>(j)] = result.track_ids[k];
  }
}

/** Labelled cloud: every point of the input file `input`, in its order and with its fields, plus
 * its class and track id (class 0, track -1 for the points the range image did not keep). */
void writeLabelledCloud(const std::string& path, const pcl::PCLPointCloud2& in,
                        const Detector::FrameResult& result) {
  pcl::PCLPointCloud2 out;
  const std::size_t n = static_cast<std::size_t>(in.width) * in.height;
  std::vector<std::uint32_t> labels;
  std::vector<std::int32_t> tracks;
  toInputOrder(result, n, labels, tracks);
  addLabelFields(in, out);
  out.data.resize(n * out.point_step);
  for (std::size_t j = 0; j < n; ++j) {
    std::uint8_t* d = &out.data[j * out.point_step];
    std::memcpy(d, &in.data[j * in.point_step], in.point_step);
    std::memcpy(d + in.point_step, &labels[j], 4);
    std::memcpy(d + in.point_step + 4, &tracks[j], 4);
  }
  writeLabelledBlob(path, out);
}

/** The same, for the input file `input` (read again: every field of the file). */
void writeLabelledCloud(const std::string& path, const std::string& input,
                        const Detector::FrameResult& result) {
  pcl::PCLPointCloud2 in;
  pcl_movers::io::readScanBlob(input, in);
  writeLabelledCloud(path, in, result);
}

/** Labelled cloud of a frame whose file could not be read (--skip-bad-frames): no point. */
void writeEmptyLabelledCloud(const std::string& path) {
  pcl::PCLPointCloud2 xyz, out;
  pcl::toPCLPointCloud2(pcl::PointCloud<pcl::PointXYZ>(), xyz);
  addLabelFields(xyz, out);
  out.width = 0;
  out.height = 1;
  writeLabelledBlob(path, out);
}

/** Per point of `scan` (as read, in the input's order): a return, i.e. finite and not at range 0.
 */
std::vector<bool> returnsOf(const pcl::PointCloud<PointT>& scan) {
  std::vector<bool> has_return(scan.size());
  for (std::size_t j = 0; j < scan.size(); ++j) {
    const PointT& p = scan[j];
    has_return[j] = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) &&
                    (p.x != 0.f || p.y != 0.f || p.z != 0.f);
  }
  return has_return;
}

/** OUT/labels/NAME.label of a frame (--point-labels): `has_return` per input point (empty for a
 * bad frame: `bad_points` zeros, its header's count or 0), all 0 when the frame is blind. */
void writePointLabels(const std::string& path, const std::vector<bool>& has_return,
                      std::size_t bad_points, const Detector::FrameResult& result) {
  const std::size_t n = has_return.empty() ? bad_points : has_return.size();
  std::vector<std::uint32_t> out(n, 0);
  if (!has_return.empty() && !result.blind) {
    std::vector<std::uint32_t> labels;
    std::vector<std::int32_t> tracks;
    toInputOrder(result, n, labels, tracks);
    std::vector<int> mover_track(n, -1);
    for (std::size_t j = 0; j < n; ++j)
      if (labels[j] == Detector::kMover) mover_track[j] = tracks[j];
    out = pcl_movers::io::movingPointLabels(has_return, mover_track, result.rows);
  }
  pcl_movers::io::writeLabels(path, out);
}

/** Points a frame that could not be read declares: a PCD header's WIDTH x HEIGHT, a .bin's size
 * / 16; 0 when unknown or implausible (over 50 million: a damaged header allocates nothing). */
std::size_t declaredPoints(const std::string& path) {
  std::error_code ec;
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".bin") {
    const std::uintmax_t size = fs::file_size(path, ec);
    return ec || size / 16 > 50'000'000 ? 0 : static_cast<std::size_t>(size / 16);
  }
  if (ext != ".pcd") return 0;
  pcl::PCLPointCloud2 header;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, type = 0;
  unsigned int data_at = 0;
  if (pcl::PCDReader().readHeader(path, header, origin, orientation, version, type, data_at) != 0)
    return 0;
  const std::size_t n = static_cast<std::size_t>(header.width) * header.height;
  return n <= 50'000'000 ? n : 0;
}

/** Rejects infinite coordinates (NaN marks empty cells and is fine). */
void checkFinite(const pcl::PointCloud<PointT>& cloud, const std::string& path) {
  for (const auto& p : cloud.points)
    if (std::isinf(p.x) || std::isinf(p.y) || std::isinf(p.z))
      throw InputError(path, 0, "scan has infinite coordinates");
}

// ------------------------------------------------------------------ interruption
/// SIGINT/SIGTERM received (or --stop-after-frames reached): the run stops after its current
/// frame. The handler is reset by the first signal, so a second one ends the process at once.
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void onStopSignal(int signal) {
  g_stop_signal = signal;
}

void installStopHandlers() {
  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

// ------------------------------------------------------------------ options
struct Options {
  std::string seq, out;
  pcl_movers::io::SequenceOptions input;  ///< rate, --poses, --poses-format, --calib
  DetectorParameters params;
  double rate = 10.0;
  bool overwrite = false, labelled = false, force_estimate = false, skip_bad = false;
  bool point_labels = false;
  bool resume = false;
  long stop_after = -1;     ///< hidden --stop-after-frames N (tests): stop as on SIGINT after N
  std::string pcap;         ///< --pcap FILE
  bool live = false;        ///< --live
  int port = 2368;          ///< --port
  std::string calibration;  ///< --calibration XML
  double timeout = 5.0;     ///< --timeout S (live)
  double duration = 0.0;    ///< --duration S (0: none)
  long frames = -1;         ///< --frames N (-1: all)
  std::size_t queue = 4;    ///< --queue-capacity N
  bool packets() const { return live || !pcap.empty(); }
  /** What the frames come from, for messages and summary.json. */
  std::string inputName() const {
    return live ? "udp:" + std::to_string(port) : pcap.empty() ? seq : pcap;
  }
};

/** A positive whole number given to `flag`. */
long parseCount(const std::string& flag, const std::string& v) {
  const double n = pcl_movers::tools::parseNumber(flag, v);
  if (!(n >= 1) || n != std::floor(n) || n > 1e12)
    throw InputError(flag + ": '" + v + "' is not a positive whole number");
  return static_cast<long>(n);
}

/** A positive number of seconds given to `flag`. */
double parseSeconds(const std::string& flag, const std::string& v) {
  const double s = pcl_movers::tools::parseNumber(flag, v);
  if (!(s > 0)) throw InputError(flag + ": '" + v + "' is not a positive number of seconds");
  return s;
}

/** --pcap, --live and their options, checked together. */
void parseInputOptions(const pcl_movers::tools::Arguments& args, Options& o) {
  std::string v;
  args.get("--pcap", o.pcap);
  o.live = args.has("--live");
  if (o.live && !o.pcap.empty()) throw InputError("--pcap and --live exclude each other: give one");
  if (args.get("--port", v)) {
    const double port = pcl_movers::tools::parseNumber("--port", v);
    if (!(port >= 1 && port <= 65535) || port != std::floor(port))
      throw InputError("--port: '" + v + "' is not a UDP port (1-65535)");
    o.port = static_cast<int>(port);
  }
  args.get("--calibration", o.calibration);
  if (args.get("--timeout", v)) o.timeout = parseSeconds("--timeout", v);
  if (args.get("--duration", v)) o.duration = parseSeconds("--duration", v);
  if (args.get("--frames", v)) o.frames = parseCount("--frames", v);
  if (args.get("--queue-capacity", v))
    o.queue = static_cast<std::size_t>(parseCount("--queue-capacity", v));
  for (const char* live_only : {"--port", "--timeout"})
    if (args.has(live_only) && !o.live) throw InputError(std::string(live_only) + " is for --live");
  if (args.has("--calibration") && !o.packets())
    throw InputError("--calibration is for --pcap or --live (a sequence folder is decoded)");
  if (!o.packets()) return;
  if (o.live && o.resume) throw InputError("--resume cannot continue a --live run");
  const std::string& sensor = o.params.sensor;
  if (sensor != "hdl32" && sensor != "hdl64" && sensor != "vlp16" && !(sensor == "auto" && !o.live))
    throw InputError("--sensor '" + sensor + "': " + (o.live ? "--live" : "--pcap") +
                     " needs a Velodyne sensor: hdl32, hdl64 or vlp16" +
                     (o.live ? "" : " (or auto: from the packets)"));
}

double parseRate(const std::string& r) {
  char* end = nullptr;
  const double rate = std::strtod(r.c_str(), &end);
  if (end == r.c_str() || *end != '\0' || !(rate > 0) || !std::isfinite(rate))
    throw InputError("--rate: '" + r + "' is not a positive number");
  return rate;
}

/** --poses, --poses-format, --calib and --estimate-poses, checked together. */
void parsePoseOptions(const pcl_movers::tools::Arguments& args, Options& o) {
  auto& in = o.input;
  std::string format;
  args.get("--poses", in.poses_path);
  args.get("--calib", in.calib_path);
  if (args.get("--poses-format", format)) in.poses_format = pcl_movers::io::parsePoseFormat(format);
  o.force_estimate = args.has("--estimate-poses");
  if (in.poses_path.empty() && (!format.empty() || !in.calib_path.empty()))
    throw InputError(std::string(format.empty() ? "--calib" : "--poses-format") +
                     " needs --poses FILE");
  if (!in.poses_path.empty() && o.force_estimate)
    throw InputError("--poses and --estimate-poses exclude each other: give one");
  if (!in.calib_path.empty() && in.poses_format != pcl_movers::io::PoseFormat::kitti_camera)
    throw InputError("--calib is for --poses-format kitti-camera");
  in.load_poses = !o.force_estimate;  // a bad SEQ/poses.txt does not stop --estimate-poses
}

/** Options from argv; false when the run is done already (--print-config). */
bool parseOptions(int argc, char** argv, Options& o) {
  const auto args = optionTable().parse(argc, argv);
  std::string config, v;
  if (args.get("--config", config)) o.params.readConfig(config);
  for (const auto& key : o.params.keys())
    if (args.get(optionName(key), v)) o.params.set(key, v, optionName(key));
  o.params.validate();
  if (args.has("--print-config")) {
    std::printf("%s", o.params.toConfig().c_str());
    return false;
  }
  if (args.get("--rate", v)) o.rate = parseRate(v);
  parsePoseOptions(args, o);
  if (args.get("--stop-after-frames", v)) {
    const double n = pcl_movers::tools::parseNumber("--stop-after-frames", v);
    if (!(n >= 1) || n != std::floor(n))
      throw InputError("--stop-after-frames: '" + v + "' is not a positive whole number");
    o.stop_after = static_cast<long>(n);
  }
  o.resume = args.has("--resume");
  parseInputOptions(args, o);
  if (o.packets()) {
    const char* input = o.live ? "--live" : "--pcap";
    if (args.positional.size() == 2)
      throw InputError(std::string(input) + " reads the frames: give OUT only, not SEQ ('" +
                       args.positional[0] + "') as well");
    if (args.positional.size() != 1)
      throw InputError(std::string("expected 1 argument OUT with ") + input + ", got " +
                       std::to_string(args.positional.size()));
    o.out = args.positional[0];
  } else {
    if (args.positional.size() != 2) {
      printHelp(argv[0]);
      throw InputError("expected 2 arguments SEQ OUT (or --pcap FILE OUT, --live OUT), got " +
                       std::to_string(args.positional.size()));
    }
    o.seq = args.positional[0];
    o.out = args.positional[1];
  }
  o.overwrite = args.has("--overwrite");
  o.labelled = args.has("--labelled-clouds");
  o.point_labels = args.has("--point-labels");
  o.input.rate_hz = o.rate;
  o.skip_bad = args.has("--skip-bad-frames");
  if (o.resume && o.overwrite)
    throw InputError("--resume continues the run in OUT; it cannot be combined with --overwrite");
  return true;
}

/** FNV-1a, 64 bits, as 16 hex digits. */
std::string hashHex(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  char buf[20];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

/** What a resumed run must share with the run it continues: the input (path, frame files and
 * their sizes), the frame rate, the options that change the output, and every parameter. */
std::string runKey(const Options& o, const pcl_movers::io::SequenceReader* reader) {
  std::ostringstream key;
  std::error_code ec;
  key << (o.live ? o.inputName() : fs::weakly_canonical(o.inputName(), ec).string()) << "\nrate "
      << o.rate << "\nestimate " << o.force_estimate << "\nlabelled " << o.labelled << "\nskip_bad "
      << o.skip_bad << "\nposes " << o.input.poses_path << " "
      << static_cast<int>(o.input.poses_format) << " " << o.input.calib_path << "\n";
  if (o.point_labels) key << "point_labels 1\n";  // absent otherwise: older run keys unchanged
  if (reader)
    for (const auto& path : reader->framePaths())
      key << fs::path(path).filename().string() << " " << fs::file_size(path, ec) << "\n";
  if (!o.pcap.empty())  // absent for folders: their run keys unchanged
    key << "pcap " << fs::file_size(o.pcap, ec) << " calibration " << o.calibration << "\n";
  if (o.frames > 0 || o.duration > 0) key << "frames " << o.frames << " " << o.duration << "\n";
  key << o.params.toConfig();
  return hashHex(key.str());
}

// ------------------------------------------------------------------ summary.json
/** Value of `"key": ...` in summary.json text (number, bool or string without its quotes), or
 * "" when absent. Enough for the keys this tool writes itself. */
std::string jsonValue(const std::string& text, const std::string& key) {
  const std::string tag = "\"" + key + "\": ";
  const std::size_t at = text.find(tag);
  if (at == std::string::npos) return "";
  std::size_t b = at + tag.size();
  if (b < text.size() && text[b] == '"') {
    const std::size_t e = text.find('"', b + 1);
    return e == std::string::npos ? "" : text.substr(b + 1, e - b - 1);
  }
  std::size_t e = b;
  while (e < text.size() && text[e] != ',' && text[e] != '\n' && text[e] != '}') ++e;
  return text.substr(b, e - b);
}

std::string jsonList(const std::vector<std::size_t>& v) {
  std::string s = "[";
  for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + std::to_string(v[k]);
  return s + "]";
}

std::string jsonString(const std::string& text) {
  std::string s = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') s += '\\';
    s += c;
  }
  return s + "\"";
}

/** Everything the run has counted so far. */
struct RunState {
  std::string run_key, pose_source, sensor = "organized input (its own rows and columns)";
  std::size_t frames_done = 0;  ///< complete frames (0 .. frames_done - 1) in tracks.csv
  std::size_t resumed_from = 0;
  bool resumed = false;
  std::vector<std::size_t> blind, bad;
  std::map<std::string, std::vector<double>> stage_ms;
  std::set<int> track_ids, mover_ids;
  std::size_t rows = 0;
  std::string deskew = "{}";  ///< ScanDeskewer::toJson()
  std::string input = "{}";   ///< what the frames came from, read, dropped (DetectRun::inputJson)
  std::size_t dropped = 0;    ///< sweeps dropped because detection fell behind (--live)
};

std::string timingsJson(const RunState& st, bool estimate) {
  std::ostringstream js;
  bool first = true;
  std::vector<std::string> order = Detector::stageNames();
  if (estimate) order.insert(order.begin(), "ego_motion");
  for (const auto& stage : order) {
    const auto it = st.stage_ms.find(stage);
    if (it == st.stage_ms.end()) continue;
    double mean = 0;
    for (const double v : it->second) mean += v;
    mean /= std::max<std::size_t>(1, it->second.size());
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%s\n    \"%s\": {\"median\": %.3f, \"mean\": %.3f}",
                  first ? "" : ",", stage.c_str(), median(it->second), mean);
    js << buf;
    first = false;
  }
  return js.str();
}

/** summary.json, through a temporary name. `state`: running, interrupted or finished. */
void writeSummary(const Options& o, std::size_t frames, const RunState& st,
                  const std::string& state, int signal, bool estimate) {
  std::ostringstream js;
  js << "{\n  \"sequence\": " << jsonString(o.inputName()) << ",\n  \"frames\": " << frames
     << ",\n  \"state\": \"" << state
     << "\",\n  \"interrupted\": " << (state == "finished" ? "false" : "true");
  if (signal != 0)
    js << ",\n  \"signal\": \"" << (signal == SIGTERM ? "SIGTERM" : "SIGINT") << "\"";
  js << ",\n  \"frames_done\": " << st.frames_done
     << ",\n  \"last_complete_frame\": " << static_cast<long>(st.frames_done) - 1;
  if (st.resumed) js << ",\n  \"resumed_from_frame\": " << st.resumed_from;
  js << ",\n  \"run_key\": \"" << st.run_key << "\",\n  \"pose_source\": \"" << st.pose_source
     << "\",\n  \"sensor\": " << jsonString(st.sensor)
     << ",\n  \"blind_frames\": " << jsonList(st.blind)
     << ",\n  \"blind_frame_count\": " << st.blind.size() << ",\n  \"deskew\": " << st.deskew
     << ",\n  \"bad_frames\": " << jsonList(st.bad) << ",\n  \"bad_frame_count\": " << st.bad.size()
     << ",\n  \"rows\": " << st.rows << ",\n  \"tracks\": " << st.track_ids.size()
     << ",\n  \"movers\": " << st.mover_ids.size() << ",\n  \"input\": " << st.input
     << ",\n  \"dropped_frames\": " << st.dropped << ",\n  \"timings_ms\": {"
     << timingsJson(st, estimate) << "\n  },\n  \"parameters\": " << o.params.toJson() << "\n}\n";
  const std::string path = o.out + "/summary.json", tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    f << js.str();
    if (!f) throw InputError(tmp, 0, "cannot write");
  }
  fs::rename(tmp, path);
}

// ------------------------------------------------------------------ tracks.json
std::string jsonNumbers(std::initializer_list<double> values, const char* format) {
  std::string s = "[";
  char buf[64];
  for (const double v : values) {
    std::snprintf(buf, sizeof(buf), format, v);
    s += (s.size() > 1 ? ", " : "") + std::string(buf);
  }
  return s + "]";
}

/** One number as `format` prints it. */
std::string jsonNumber(double v, const char* format) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

/** A mover of tracks.json: its track, box (sensor frame), world centre, velocity, similarity. */
std::string moverJson(const pcl_movers::io::TrackRow& r) {
  std::ostringstream js;
  js << "{\"track_id\": " << r.track_id << ", \"center\": " << jsonNumbers({r.x, r.y, r.z}, "%.3f")
     << ", \"size\": " << jsonNumbers({r.length, r.width, r.height}, "%.2f")
     << ", \"yaw\": " << jsonNumber(r.yaw, "%.4f")
     << ", \"world_center\": " << jsonNumbers({r.wx, r.wy, r.wz}, "%.3f")
     << ", \"velocity\": " << jsonNumbers({r.vx, r.vy}, "%.3f")
     << ", \"speed\": " << jsonNumber(r.speed, "%.3f")
     << ", \"similarity\": " << jsonNumber(r.similarity, "%.3f") << ", \"points\": " << r.points
     << ", \"reason\": \"" << r.reason << "\"}";
  return js.str();
}

/** One frame of tracks.json: index, file number, time, blind, every track id, the movers. */
std::string frameJson(std::size_t i, long long file, double time, bool blind,
                      const std::vector<pcl_movers::io::TrackRow>& rows) {
  std::ostringstream js;
  char t[32];
  std::snprintf(t, sizeof(t), "%.3f", time);
  js << "  {\"frame\": " << i << ", \"file\": " << file << ", \"time\": " << t
     << ", \"blind\": " << (blind ? "true" : "false") << ", \"track_ids\": [";
  for (std::size_t k = 0; k < rows.size(); ++k) js << (k ? ", " : "") << rows[k].track_id;
  js << "], \"movers\": [";
  bool first = true;
  for (const auto& r : rows) {
    if (!r.mover) continue;
    js << (first ? "" : ", ") << moverJson(r);
    first = false;
  }
  // Why every other track is not a mover (the first decision test it failed).
  js << "], \"not_movers\": [";
  first = true;
  for (const auto& r : rows) {
    if (r.mover) continue;
    js << (first ? "" : ", ") << "{\"track_id\": " << r.track_id << ", \"reason\": \"" << r.reason
       << "\"}";
    first = false;
  }
  js << "]}";
  return js.str();
}

/** tracks.json (a JSON array, one object per frame), through a temporary name. */
void writeTracksJson(const std::string& path, const std::vector<std::string>& frames) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    f << "[\n";
    for (std::size_t k = 0; k < frames.size(); ++k)
      f << frames[k] << (k + 1 < frames.size() ? ",\n" : "\n");
    f << "]\n";
    if (!f) throw InputError(tmp, 0, "cannot write");
  }
  fs::rename(tmp, path);
}

// ------------------------------------------------------------------ tracks.csv
/** The rows already on disk of the run being resumed. */
struct PreviousRun {
  std::size_t frames_done = 0;
  std::vector<std::string> lines;  ///< rows of frames < frames_done, in file order
};

/** Reads OUT/summary.json and OUT/tracks.csv of the run --resume continues; refuses a folder
 * written by another run (other input, options or parameters) or a finished one. */
PreviousRun readPreviousRun(const Options& o, const std::string& run_key) {
  const std::string summary_path = o.out + "/summary.json", tracks_path = o.out + "/tracks.csv";
  if (!fs::is_regular_file(summary_path) || !fs::is_regular_file(tracks_path))
    throw InputError(o.out, 0, "--resume: no summary.json and tracks.csv of an earlier run here");
  std::ifstream in(summary_path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (jsonValue(text, "run_key") != run_key)
    throw InputError(summary_path, 0,
                     "--resume: written by a different run (input, frames, options or parameters "
                     "differ); give the same SEQ and options, or start afresh with --overwrite");
  if (jsonValue(text, "state") == "finished")
    throw InputError(summary_path, 0, "--resume: this run is finished; nothing to resume");
  PreviousRun prev;
  prev.frames_done = static_cast<std::size_t>(std::atol(jsonValue(text, "frames_done").c_str()));
  std::ifstream tracks(tracks_path);
  std::string line;
  if (!std::getline(tracks, line) || line != pcl_movers::io::tracksCsvHeader())
    throw InputError(tracks_path, 1, "--resume: not a tracks.csv of this tool");
  while (std::getline(tracks, line))
    if (std::atol(line.c_str()) < static_cast<long>(prev.frames_done)) prev.lines.push_back(line);
  return prev;
}

/** tracks.csv, written frame by frame: each complete frame is flushed to disk at once. */
class TracksFile {
 public:
  /** A new file with the header. */
  void create(const std::string& path) {
    path_ = path;
    open(std::ios::trunc);
    out_ << pcl_movers::io::tracksCsvHeader() << '\n';
    flush();
  }
  /** An existing file cut to its header and `lines` (the verified rows), continued after them. */
  void resume(const std::string& path, const std::vector<std::string>& lines) {
    path_ = path;
    std::uintmax_t size = std::strlen(pcl_movers::io::tracksCsvHeader()) + 1;
    for (const auto& l : lines) size += l.size() + 1;
    fs::resize_file(path, size);
    kept_size_ = size;
    open(std::ios::app);
  }
  void writeFrame(const std::vector<pcl_movers::io::TrackRow>& rows) {
    for (const auto& r : rows) out_ << pcl_movers::io::formatTrackRow(r) << '\n';
    flush();
  }
  /** Back to what resume() kept (a resumed run that fails leaves the folder as it found it). */
  void rollBack() {
    out_.close();
    std::error_code ec;
    if (kept_size_ > 0) fs::resize_file(path_, kept_size_, ec);
  }

 private:
  void open(std::ios::openmode mode) {
    out_.open(path_, std::ios::out | mode);
    if (!out_) throw InputError(path_, 0, "cannot write tracks file");
  }
  void flush() {
    out_.flush();
    if (!out_) throw InputError(path_, 0, "write failed");
  }
  std::string path_;
  std::ofstream out_;
  std::uintmax_t kept_size_ = 0;
};

// ------------------------------------------------------------------ input frames
/** One frame as the reading thread hands it to detection. */
struct InputFrame {
  std::size_t sweep = 0;  ///< index in the input: the folder's frame, the capture's full sweep
  pcl::PointCloud<PointT>::Ptr scan;
  bool readable = true;
  std::string error;                ///< why it could not be read (--skip-bad-frames)
  double time = 0;                  ///< sweeps: first firing [s past the hour, sensor clock]
  std::vector<float> time_offsets;  ///< sweeps: per point [s after `time`], NaN without return
  /** The first sweep, when de-skewed with given poses: the next sweep's `time` (NaN: none). */
  double next_time = std::numeric_limits<double>::quiet_NaN();
};

/** Frame i of a folder, read on the reading thread; with --skip-bad-frames a malformed one is
 * handed on as unreadable (detection warns and counts it). */
InputFrame readFolderFrame(const pcl_movers::io::SequenceReader& reader, std::size_t i,
                           bool skip_bad) {
  InputFrame f;
  f.sweep = i;
  f.scan.reset(new pcl::PointCloud<PointT>);
  const std::string& path = reader.framePaths()[i];
  try {
    reader.read(i, *f.scan);
    checkFinite(*f.scan, path);
  } catch (const InputError& e) {
    if (!skip_bad) throw;
    f.readable = false;
    f.error = e.what();
    f.scan->clear();
    return f;
  }
  // The scan is in the sensor frame; its VIEWPOINT (if any) is the pose.
  f.scan->sensor_origin_.setZero();
  f.scan->sensor_orientation_.setIdentity();
  return f;
}

/** The Velodyne model of --sensor (auto: from the capture's first data packet). */
pcl_movers::io::VelodyneModel velodyneModelOf(const Options& o) {
  return pcl_movers::io::velodyneModelFor(o.params.sensor, o.pcap);
}

/** --poses for a capture's sweeps: one per sweep (kitti, kitti-camera) or by time (tum). */
class SweepPoses {
 public:
  explicit SweepPoses(const pcl_movers::io::SequenceOptions& in) : path_(in.poses_path) {
    using pcl_movers::io::PoseFormat;
    if (path_.empty() || !in.load_poses) return;
    format_ = in.poses_format;
    if (format_ == PoseFormat::tum) {
      stamped_ = pcl_movers::io::readTumPoses(path_);
      if (stamped_.empty()) throw InputError(path_, 0, "no pose");
      return;
    }
    indexed_ = pcl_movers::io::readPoses(path_);
    if (format_ == PoseFormat::kitti_camera)
      indexed_ = pcl_movers::io::cameraToVelodynePoses(
          indexed_, pcl_movers::io::readKittiCalibTr(in.calib_path));
    if (indexed_.empty()) throw InputError(path_, 0, "no pose");
  }
  bool empty() const { return indexed_.empty() && stamped_.empty(); }
  std::string source() const {
    const char* names[] = {"kitti", "tum", "kitti-camera"};
    return path_ + " (" + names[static_cast<int>(format_)] + ")";
  }
  /** The pose of sweep `sweep`, which started at `time`. */
  Eigen::Isometry3d at(std::size_t sweep, double time) const {
    if (!stamped_.empty())
      return pcl_movers::io::posesAtTimes(stamped_, {time}, path_, kTolerance).front();
    if (sweep >= indexed_.size())
      throw InputError(path_, 0,
                       "has " + std::to_string(indexed_.size()) + " poses; the capture has sweep " +
                           std::to_string(sweep) + " (one pose per sweep)");
    return indexed_[sweep];
  }

 private:
  static constexpr double kTolerance = 0.1;  ///< [s] a sweep's time to its nearest TUM pose
  std::string path_;
  pcl_movers::io::PoseFormat format_ = pcl_movers::io::PoseFormat::kitti;
  std::vector<Eigen::Isometry3d> indexed_;
  std::vector<pcl_movers::io::StampedPose> stamped_;
};

/** Duration of a sweep: its last firing's time offset (0 when it has no return). */
double sweepDuration(const std::vector<float>& time_offsets) {
  float last = 0.f;
  for (const float t : time_offsets)
    if (std::isfinite(t)) last = std::max(last, t);
  return last;
}

/** The capture of --pcap / --live. */
std::unique_ptr<pcl_movers::io::VelodyneCapture> openCapture(const Options& o) {
  const auto model = velodyneModelOf(o);
  if (o.live)
    return pcl_movers::io::VelodyneCapture::listen(o.port, model, o.calibration, o.timeout);
  return std::make_unique<pcl_movers::io::VelodyneCapture>(o.pcap, model, o.calibration);
}

// ------------------------------------------------------------------ the run
class DetectRun {
 public:
  /** `reader`: the sequence folder, or null with --pcap/--live (`capture`). */
  DetectRun(const Options& o, const pcl_movers::io::SequenceReader* reader,
            std::unique_ptr<pcl_movers::io::VelodyneCapture> capture)
      : o_(o),
        reader_(reader),
        capture_(std::move(capture)),
        sweep_poses_(o.input),
        estimate_(o.force_estimate || (reader ? !reader->hasPoses() : sweep_poses_.empty())) {
    st_.run_key = runKey(o, reader);
    st_.pose_source = estimate_ ? "estimated"
                      : reader  ? reader->poseSource()
                                : sweep_poses_.source();
    if (o.params.sensor != "auto") st_.sensor = o.params.sensor;
    if (capture_) {
      st_.sensor = pcl_movers::io::velodyneModelName(velodyneModelOf(o)) +
                   (o.live ? ": live packets" : ": packet capture") + " (" +
                   std::to_string(capture_->getSensorModel().rows()) + " x " +
                   std::to_string(capture_->getColumns()) + " organized sweeps)";
      if (o.params.deskew == "on" && estimate_)
        throw InputError(
            "--deskew on: de-skewing a capture's sweeps needs their poses (--poses); "
            "estimated poses come from the skewed sweeps");
    }
    detector_.setParameters(o.params);
  }

  /** Runs every frame; returns the exit code (0, or 128 + the signal that stopped it). */
  int run();

 private:
  std::unique_ptr<pcl_movers::io::FrameStream<InputFrame>> openStream();
  void prepare();
  void cleanUp();
  void processFrame(std::size_t i, InputFrame& frame);
  void applyDeskew(std::size_t i, InputFrame& frame, const Eigen::Isometry3d& pose);
  void replayFrame(std::size_t i, const Detector::FrameResult& result);
  void reportSensor(std::size_t i, const pcl::PointCloud<PointT>& scan);
  void reportStream(bool last);
  std::string inputJson() const;
  template <typename Write>
  void writeFrameFile(std::size_t i, const std::string& path, Write&& write);
  void clearEarlierOutputs() const;
  std::size_t knownFrames() const { return reader_ ? reader_->size() : st_.frames_done; }
  /** Output name of input frame `sweep`: the folder's file name, or the sweep index NNNNNN. */
  std::string frameName(std::size_t sweep) const {
    if (reader_) return reader_->frameName(sweep);
    std::ostringstream name;
    name << std::setw(6) << std::setfill('0') << sweep;
    return name.str();
  }
  long long frameNumber(std::size_t sweep) const {
    return reader_ ? reader_->frameNumber(sweep) : static_cast<long long>(sweep);
  }
  /** The input frame `sweep` named for messages. */
  std::string framePath(std::size_t sweep) const {
    return reader_ ? reader_->framePaths()[sweep]
                   : o_.inputName() + " sweep " + std::to_string(sweep);
  }
  std::string labelledPath(std::size_t sweep) const {
    return o_.out + "/labelled/" + frameName(sweep) + ".pcd";
  }
  std::string pointLabelsPath(std::size_t sweep) const {
    return o_.out + "/labels/" + frameName(sweep) + ".label";
  }

  const Options& o_;
  const pcl_movers::io::SequenceReader* reader_;
  std::unique_ptr<pcl_movers::io::VelodyneCapture> capture_;
  const SweepPoses sweep_poses_;
  const bool estimate_;
  Detector detector_;
  pcl_movers::EgoMotionEstimator<PointT> ego_;
  pcl_movers::ScanDeskewer deskew_{o_.params.deskew};
  RunState st_;
  PreviousRun prev_;
  std::size_t prev_cursor_ = 0;  ///< next line of prev_ a replayed row must equal
  TracksFile tracks_;
  bool out_existed_ = false, created_labelled_dir_ = false, sensor_reported_ = false;
  bool created_labels_dir_ = false;
  std::vector<std::string> created_;      ///< files a failure removes
  std::vector<std::string> frames_json_;  ///< tracks.json, one object per frame so far
  // Streaming (reading thread → detection).
  std::unique_ptr<pcl_movers::io::FrameStream<InputFrame>> stream_;
  std::chrono::steady_clock::time_point started_, last_report_;
  double wall_seconds_ = 0;
  pcl_movers::StampedPose previous_pose_;  ///< sweeps: the previous detected sweep's pose
  std::size_t sweeps_deskewed_ = 0, sweeps_without_poses_ = 0;
};

/** --overwrite: removes what an earlier run of this tool wrote in OUT (tracks.csv, tracks.json,
 * summary.json, labelled/*.pcd, labels/*.label, then labelled/ and labels/ when that leaves them
 * empty) and nothing else. */
void DetectRun::clearEarlierOutputs() const {
  std::error_code ec;
  for (const char* name : {"tracks.csv", "tracks.json", "summary.json"})
    fs::remove(fs::path(o_.out) / name, ec);
  for (const auto& [folder, extension] :
       {std::pair<const char*, const char*>{"labelled", ".pcd"},
        std::pair<const char*, const char*>{"labels", ".label"}}) {
    const fs::path dir = fs::path(o_.out) / folder;
    if (!fs::is_directory(dir, ec)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (e.is_regular_file(ec) && e.path().extension() == extension) files.push_back(e.path());
    for (const auto& f : files) fs::remove(f, ec);
    if (std::string(folder) == "labelled") fs::remove(dir / kRunKeyFile, ec);
    if (fs::is_empty(dir, ec)) fs::remove(dir, ec);
  }
}

void DetectRun::prepare() {
  out_existed_ = fs::exists(o_.out);
  const std::string tracks_path = o_.out + "/tracks.csv";
  if (o_.resume) {
    prev_ = readPreviousRun(o_, st_.run_key);
    st_.resumed = true;
    st_.resumed_from = prev_.frames_done;
  } else {
    pcl_movers::io::prepareOutputDirectory(o_.out, o_.overwrite);
    if (o_.overwrite) clearEarlierOutputs();
    created_.push_back(o_.out + "/tracks.json");
    created_.push_back(tracks_path);
    tracks_.create(tracks_path);
    created_.push_back(o_.out + "/summary.json");
    st_.input = inputJson();
    writeSummary(o_, knownFrames(), st_, "running", 0, estimate_);
  }
  const std::string labelled_dir = o_.out + "/labelled";
  if (o_.labelled && !fs::exists(labelled_dir)) {
    fs::create_directories(labelled_dir);
    created_labelled_dir_ = true;
  }
  if (o_.labelled && !o_.resume) {  // pcl_movers_viewer checks it against summary.json's run_key
    const std::string stamp = labelled_dir + "/" + kRunKeyFile;
    created_.push_back(stamp);
    std::ofstream(stamp) << st_.run_key << "\n";
  }
  const std::string labels_dir = o_.out + "/labels";
  if (o_.point_labels && !fs::exists(labels_dir)) {
    fs::create_directories(labels_dir);
    created_labels_dir_ = true;
  }
}

void DetectRun::cleanUp() {
  std::error_code ec;
  if (o_.resume) tracks_.rollBack();
  for (const auto& f : created_) fs::remove(f, ec);
  if (created_labelled_dir_) fs::remove(o_.out + "/labelled", ec);
  if (created_labels_dir_) fs::remove(o_.out + "/labels", ec);
  if (!out_existed_) fs::remove(o_.out, ec);  // only removes it when empty
}

/** The reading thread: a folder's frames or the capture's sweeps, --frames/--duration applied.
 * Files wait for detection (nothing is lost); a live sensor drops its oldest waiting sweep. */
std::unique_ptr<pcl_movers::io::FrameStream<InputFrame>> DetectRun::openStream() {
  using pcl_movers::io::QueuePolicy;
  const std::size_t limit = o_.frames > 0 ? static_cast<std::size_t>(o_.frames) : SIZE_MAX;
  const auto deadline =
      o_.duration > 0 ? started_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                       std::chrono::duration<double>(o_.duration))
                      : std::chrono::steady_clock::time_point::max();
  auto in_bounds = [=](std::size_t read) {
    return read < limit && std::chrono::steady_clock::now() < deadline;
  };
  if (reader_) {
    auto next = std::make_shared<std::size_t>(0);
    return std::make_unique<pcl_movers::io::FrameStream<InputFrame>>(
        [this, next, in_bounds](InputFrame& f) {
          if (*next >= reader_->size() || !in_bounds(*next)) return false;
          f = readFolderFrame(*reader_, (*next)++, o_.skip_bad);
          return true;
        },
        o_.queue, QueuePolicy::kBlock);
  }
  // The first sweep's de-skewing takes the next sweep's pose at its start (applyDeskew()), so
  // the second sweep is read with it; an error reading it comes after the first sweep.
  struct Reading {
    std::size_t read = 0;
    std::unique_ptr<pcl_movers::io::VelodyneSweep> ahead;
    std::exception_ptr error;
  };
  auto state = std::make_shared<Reading>();
  const bool look_ahead = o_.params.deskew != "off" && !estimate_;
  pcl_movers::io::VelodyneCapture* capture = capture_.get();
  return std::make_unique<pcl_movers::io::FrameStream<InputFrame>>(
      [capture, state, in_bounds, look_ahead](InputFrame& f) {
        if (state->error) std::rethrow_exception(std::exchange(state->error, nullptr));
        pcl_movers::io::VelodyneSweep sweep;
        if (!in_bounds(state->read)) return false;
        if (state->ahead)
          sweep = std::move(*std::exchange(state->ahead, nullptr));
        else if (!capture->next(sweep))
          return false;
        f.sweep = state->read++;
        f.scan = sweep.cloud;
        f.time = sweep.start_time;
        f.time_offsets = std::move(sweep.time_offsets);
        if (look_ahead && f.sweep == 0 && in_bounds(state->read)) {
          auto next = std::make_unique<pcl_movers::io::VelodyneSweep>();
          try {
            if (capture->next(*next)) {
              f.next_time = next->start_time;
              state->ahead = std::move(next);
            }
          } catch (...) {
            state->error = std::current_exception();
          }
        }
        return true;
      },
      o_.queue, o_.live ? QueuePolicy::kDropOldest : QueuePolicy::kBlock,
      [capture] { capture->stop(); });
}

/** Reading state for summary.json: what the frames came from, read, dropped, queue, wall time. */
std::string DetectRun::inputJson() const {
  std::ostringstream js;
  const char* kind = o_.live ? "live" : o_.pcap.empty() ? "folder" : "pcap";
  const std::size_t read = stream_ ? stream_->producedCount() : 0;
  const std::size_t dropped = stream_ ? stream_->droppedCount() : 0;
  js << "{\"kind\": \"" << kind << "\", \"source\": " << jsonString(o_.inputName())
     << ", \"frames_read\": " << read << ", \"dropped_frames\": " << dropped
     << ", \"queue_capacity\": " << o_.queue << ", \"queue_policy\": \""
     << (o_.live ? "drop-oldest" : "block") << "\"";
  if (capture_)
    js << ", \"packets\": " << capture_->getPacketCount()
       << ", \"partial_sweeps\": " << capture_->getPartialSweepCount();
  js << ", \"wall_seconds\": " << jsonNumber(wall_seconds_, "%.3f") << "}";
  return js.str();
}

/** A progress line for --pcap/--live: once a second, and at the end. */
void DetectRun::reportStream(bool last) {
  if (!stream_ || reader_) return;
  const auto now = std::chrono::steady_clock::now();
  if (!last && now - last_report_ < std::chrono::seconds(1)) return;
  last_report_ = now;
  print_info("%s: %zu sweeps read, %zu detected, %zu dropped (detection behind)\n",
             o_.inputName().c_str(), stream_->producedCount(), st_.frames_done,
             stream_->droppedCount());
}

/** Prints the beam layout once it is known ("auto" estimates it from the first usable scan). */
void DetectRun::reportSensor(std::size_t i, const pcl::PointCloud<PointT>& scan) {
  if (sensor_reported_ || (scan.isOrganized() && scan.height > 1)) return;
  const auto& model = detector_.getSensorModel();
  if (model.rows() == 0) return;
  sensor_reported_ = true;
  if (o_.params.sensor != "auto") return;
  const auto& est = detector_.getEstimatedSensorModel();
  char buf[300];
  const int n =
      std::snprintf(buf, sizeof(buf), "estimated from %s: %d beams, %.2f to %.2f deg, %d columns",
                    fs::path(framePath(i)).filename().c_str(), est.rows(),
                    est.elevations().front() * 180.0 / M_PI, est.elevations().back() * 180.0 / M_PI,
                    est.columns());
  if (model.name() != est.name() && n > 0 && n < static_cast<int>(sizeof(buf)))
    std::snprintf(buf + n, sizeof(buf) - static_cast<std::size_t>(n),
                  "; recognized as %s (its calibration and %d columns used)", model.name().c_str(),
                  model.columns());
  st_.sensor = std::string("auto: ") + buf;
  print_info("Beam layout %s\n", buf);
}

/** A per-frame file (labelled cloud, point labels) through a temporary name; kept when the run
 * being resumed wrote it. */
template <typename Write>
void DetectRun::writeFrameFile(std::size_t i, const std::string& path, Write&& write) {
  const bool replay = i < prev_.frames_done;
  if (replay && fs::exists(path)) return;  // written by the run being resumed
  if (!o_.resume && fs::exists(path) && !o_.overwrite)
    throw InputError(path, 0, "exists (use --overwrite)");
  created_.push_back(path);
  write(path + ".tmp");
  fs::rename(path + ".tmp", path);
}

/** A frame of the run being resumed: its rows must be those on disk. */
void DetectRun::replayFrame(std::size_t i, const Detector::FrameResult& result) {
  for (const auto& r : result.rows) {
    const std::string line = pcl_movers::io::formatTrackRow(r);
    if (prev_cursor_ >= prev_.lines.size() || prev_.lines[prev_cursor_] != line)
      throw InputError(o_.out + "/tracks.csv", 0,
                       "--resume: frame " + std::to_string(i) +
                           " gives other rows than the interrupted run wrote (different input "
                           "files or software version); start afresh with --overwrite");
    ++prev_cursor_;
  }
  if (i + 1 == prev_.frames_done) {
    if (prev_cursor_ != prev_.lines.size())
      throw InputError(o_.out + "/tracks.csv", 0, "--resume: holds rows this run does not give");
    tracks_.resume(o_.out + "/tracks.csv", prev_.lines);
  }
}

/** De-skews frame i (pose `pose`): a folder's frames with their PCD's times (ScanDeskewer), a
 * capture's sweeps with their packets' firing times and the neighbouring sweep's pose. */
void DetectRun::applyDeskew(std::size_t i, InputFrame& f, const Eigen::Isometry3d& pose) {
  if (reader_) {
    const std::size_t j = i > 0 ? i - 1 : i + 1;  // previous pose; the next one at the first frame
    pcl_movers::StampedPose other;
    if (!estimate_ && j < reader_->size()) other = {reader_->pose(j), reader_->time(j), true};
    deskew_.apply(reader_->framePaths()[i], *f.scan, {pose, f.time, true}, other);
    st_.deskew = deskew_.toJson();
    return;
  }
  const pcl_movers::StampedPose frame{pose, f.time, !estimate_};
  pcl_movers::StampedPose other = previous_pose_;
  // The first sweep: the next sweep's pose at its start, as a folder's first frame takes it
  // (a capture of one sweep: the pose at its last firing).
  const double next =
      std::isfinite(f.next_time) ? f.next_time : f.time + sweepDuration(f.time_offsets);
  if (!other.valid && frame.valid && next > f.time) {
    try {
      other = {sweep_poses_.at(f.sweep + 1, next), next, true};
    } catch (const InputError&) {  // no pose after the first sweep: it stays as it is
    }
  }
  previous_pose_ = frame;
  if (o_.params.deskew != "off") {
    if (frame.valid && other.valid && other.time != frame.time) {
      pcl_movers::deskewScan(*f.scan, f.time_offsets, frame, other);
      ++sweeps_deskewed_;
    } else {
      ++sweeps_without_poses_;
    }
  }
  std::ostringstream js;
  js << "{\"mode\": \"" << o_.params.deskew << "\", \"time_field\": \""
     << (o_.params.deskew == "off" ? "" : "packets") << "\", \"frames\": " << sweeps_deskewed_
     << ", \"without_times\": 0, \"without_poses\": " << sweeps_without_poses_ << "}";
  st_.deskew = js.str();
}

void DetectRun::processFrame(std::size_t i, InputFrame& f) {
  const std::size_t sweep = f.sweep;
  if (reader_) f.time = reader_->time(sweep);
  if (!f.readable) {
    pcl::console::print_warn(
        "[pcl_movers_detect] warning: %s; frame %zu skipped "
        "(--skip-bad-frames), its tracks coast\n",
        f.error.c_str(), i);
    st_.bad.push_back(i);
  }
  const bool readable = f.readable;
  pcl::PointCloud<PointT>::Ptr scan = f.scan;
  std::vector<bool> has_return;  // before de-skewing moves the points
  if (o_.point_labels && readable) has_return = returnsOf(*scan);
  pcl::PCLPointCloud2 sweep_blob;  // a sweep as read, for its labelled cloud
  if (o_.labelled && !reader_) pcl::toPCLPointCloud2(*scan, sweep_blob);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  if (!estimate_) pose = reader_ ? reader_->pose(sweep) : sweep_poses_.at(sweep, f.time);
  double ego_ms = 0;
  if (estimate_) {
    const auto t0 = std::chrono::steady_clock::now();
    const bool blind = !readable || std::none_of(scan->begin(), scan->end(), [](const PointT& p) {
      return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    });
    pose = blind ? ego_.coast() : ego_.estimate(*scan);
    ego_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  if (readable) applyDeskew(i, f, pose);
  Detector::FrameResult result;
  try {
    detector_.process(scan, pose, f.time, static_cast<int>(i), result);
  } catch (const InputError& e) {
    throw InputError(framePath(sweep) + ": " + e.what());
  }
  for (auto& r : result.rows) r.file = frameNumber(sweep);
  frames_json_.push_back(frameJson(i, frameNumber(sweep), f.time, result.blind, result.rows));
  if (result.blind && readable) {
    pcl::console::print_warn(
        "[pcl_movers_detect] warning: frame %zu (%s) is blind (%s); its "
        "tracks coast\n",
        i, framePath(sweep).c_str(), result.blind_reason.c_str());
    st_.blind.push_back(i);
  }
  reportSensor(sweep, *scan);
  for (const auto& t : detector_.getTimings()) st_.stage_ms[t.first].push_back(t.second);
  if (estimate_ && !result.blind) st_.stage_ms["ego_motion"].push_back(ego_ms);
  for (const auto& r : result.rows) {
    st_.track_ids.insert(r.track_id);
    if (r.mover) st_.mover_ids.insert(r.track_id);
  }
  st_.rows += result.rows.size();
  if (o_.labelled)
    writeFrameFile(i, labelledPath(sweep), [&](const std::string& tmp) {
      if (!reader_)
        writeLabelledCloud(tmp, sweep_blob, result);
      else if (readable)
        writeLabelledCloud(tmp, reader_->framePaths()[sweep], result);
      else
        writeEmptyLabelledCloud(tmp);
    });
  if (o_.point_labels)
    writeFrameFile(i, pointLabelsPath(sweep), [&](const std::string& tmp) {
      writePointLabels(tmp, has_return,
                       readable || !reader_ ? 0 : declaredPoints(reader_->framePaths()[sweep]),
                       result);
    });
  if (i < prev_.frames_done)
    replayFrame(i, result);
  else
    tracks_.writeFrame(result.rows);
  st_.frames_done = std::max(st_.frames_done, i + 1);
}

int DetectRun::run() {
  if (reader_) {
    print_info("Sequence ");
    print_value("%s", o_.seq.c_str());
    print_info(": %zu frames, poses: %s, mode: %s\n", reader_->size(), st_.pose_source.c_str(),
               o_.params.track.mode.c_str());
  } else {
    print_info(o_.live ? "Live sensor on " : "Capture ");
    print_value("%s", o_.inputName().c_str());
    print_info(": %s, poses: %s, mode: %s\n", st_.sensor.c_str(), st_.pose_source.c_str(),
               o_.params.track.mode.c_str());
  }
  started_ = last_report_ = std::chrono::steady_clock::now();
  try {
    prepare();
    if (o_.resume)
      print_info(
          "Resuming at frame %zu (the %zu done frames are run again and checked against "
          "tracks.csv)\n",
          prev_.frames_done, prev_.frames_done);
    if (o_.resume && prev_.frames_done == 0) tracks_.resume(o_.out + "/tracks.csv", {});
    st_.frames_done = prev_.frames_done;
    pcl_movers::tools::ProgressBar progress(reader_ ? reader_->size() : 0, "frames",
                                            false);  // folders only: captures print lines
    stream_ = openStream();
    InputFrame frame;
    for (std::size_t i = 0; g_stop_signal == 0; ++i) {
      try {
        if (!stream_->next(frame)) break;
      } catch (const InputError& e) {
        if (!o_.live || st_.frames_done == 0) throw;
        pcl::console::print_warn("[pcl_movers_detect] warning: %s; the run ends\n", e.what());
        break;
      }
      processFrame(i, frame);
      if (reader_) progress.update(i + 1);
      reportStream(false);
      if (o_.stop_after > 0 && static_cast<long>(i) + 1 == o_.stop_after) g_stop_signal = SIGINT;
    }
    stream_->stop();
    if (reader_) progress.finish();
    reportStream(true);
    if (capture_ && st_.frames_done == 0 && g_stop_signal == 0)
      throw InputError(o_.inputName(), 0,
                       "no full sweep in " + std::to_string(capture_->getPacketCount()) +
                           " data packets (a sweep is one turn between two azimuth wraps)");
    if (g_stop_signal == 0 && st_.frames_done > 0 &&
        st_.blind.size() + st_.bad.size() == st_.frames_done)
      throw InputError(o_.inputName(), 0,
                       "no frame has a return (all " + std::to_string(st_.frames_done) +
                           " frames are blind or bad)");
  } catch (...) {
    if (stream_) stream_->stop();
    cleanUp();
    throw;
  }
  wall_seconds_ =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  st_.input = inputJson();
  st_.dropped = stream_->droppedCount();
  const int signal = g_stop_signal;
  writeTracksJson(o_.out + "/tracks.json", frames_json_);
  writeSummary(o_, knownFrames(), st_, signal ? "interrupted" : "finished", signal, estimate_);
  if (signal != 0) {
    pcl::console::print_warn(
        "[pcl_movers_detect] interrupted by %s after %zu of %zu frames: "
        "%s/tracks.csv holds frames 0-%ld; continue with --resume\n",
        signal == SIGTERM ? "SIGTERM" : "SIGINT", st_.frames_done, knownFrames(), o_.out.c_str(),
        static_cast<long>(st_.frames_done) - 1);
    return 128 + signal;
  }
  print_info("Wrote ");
  print_value("%s/tracks.csv", o_.out.c_str());
  print_info(
      ": %zu rows, %zu tracks, %zu movers, %zu blind and %zu bad frames; median %.1f "
      "ms/frame (pipeline, without I/O), %.1f ms/frame wall\n",
      st_.rows, st_.track_ids.size(), st_.mover_ids.size(), st_.blind.size(), st_.bad.size(),
      median(st_.stage_ms["total"]),
      st_.frames_done ? 1000.0 * wall_seconds_ / static_cast<double>(st_.frames_done) : 0.0);
  return 0;
}

int run(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  Options o;
  if (!parseOptions(argc, argv, o)) return 0;
  if (o.packets()) {
    if (fs::exists(o.out) && !fs::is_directory(o.out))
      throw InputError(o.out, 0, "output exists and is not a folder");
    if (!o.pcap.empty() && !fs::is_regular_file(o.pcap))
      throw InputError(o.pcap, 0,
                       fs::exists(o.pcap) ? "--pcap: not a file" : "--pcap: does not exist");
    installStopHandlers();
    DetectRun detect(o, nullptr, openCapture(o));
    return detect.run();
  }
  if (!fs::is_directory(o.seq) && (fs::exists(o.seq) || pcl_movers::io::isScanFile(o.seq)))
    throw InputError(o.seq, 0,
                     std::string(fs::exists(o.seq) ? "is a file" : "does not exist") +
                         ": pcl_movers_detect takes a sequence folder (the folder holding the "
                         "scans, or the one holding frames/ or velodyne/), not a single scan");
  pcl_movers::io::SequenceReader reader(o.seq, o.input);
  if (fs::exists(o.out) && !fs::is_directory(o.out))
    throw InputError(o.out, 0, "output exists and is not a folder");
  if (fs::exists(o.out) && fs::equivalent(o.out, o.seq))
    throw InputError(o.out, 0, "output folder is the input sequence");
  installStopHandlers();
  DetectRun detect(o, &reader, nullptr);
  return detect.run();
}

}  // namespace

int main(int argc, char** argv) {
  return pcl_movers::tools::runTool("pcl_movers_detect", [&]() { return run(argc, argv); });
}
