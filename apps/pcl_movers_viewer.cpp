/*
 * pcl_movers_viewer — VTK playback of a LiDAR sequence with the detector's tracks: points coloured
 * by class and track, oriented boxes, velocity arrows, trails, a text overlay and optional ground
 * truth; or off-screen rendering of PNG screenshots for documentation and tests.
 *
 * Scene geometry and colours come from pcl_movers/viz/scene_style.h (core library, unit-tested);
 * this file only owns the VTK side: actors, camera, keys, image capture.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/ego_motion_estimator.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/tracks.h>
#include <pcl_movers/io/velodyne_capture.h>
#include <pcl_movers/mover_detector.h>
#include <pcl_movers/viz/scene_style.h>

#include "tool_utils.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/visualization/interactor_style.h>
#include <pcl/visualization/pcl_visualizer.h>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkImageData.h>
#include <vtkObjectFactory.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkRendererCollection.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using pcl::console::print_error;
using pcl::console::print_info;
using pcl::console::print_warn;

namespace pcl_movers {
namespace {

constexpr const char* kTool = "pcl_movers_viewer";

/** Every option with its default; the help text is generated from a default-constructed instance
 * so it cannot drift from what the tool does. */
struct ViewerParameters {
  std::string detections;      ///< --detections DIR (pcl_movers_detect output)
  bool ground_truth = false;   ///< --ground-truth: draw objects.txt boxes
  std::string screenshot_dir;  ///< --screenshot-dir DIR: off-screen mode
  std::string frames;          ///< --frames A:B (inclusive, empty = all)
  std::string size = "1280x720";
  std::string camera = "chase";
  std::string format = "png";  ///< png or ppm (binary P6, for tools without a PNG decoder)
  double point_size = 2.0;
  int trail = 10;              ///< trail length [frames]
  double arrow_seconds = 1.0;  ///< velocity arrows reach where the object will be after this
  double rate = 10.0;          ///< frame rate when the sequence has no times.txt [Hz]
  bool overwrite = false;
  bool live = false;          ///< --live: run MoverDetector while playing
  std::string config;         ///< --config FILE: detector parameters for --live
  bool movers_only = false;   ///< --movers-only: only the movers' points, boxes and trails
  bool point_labels = false;  ///< --point-labels: colour by DIR/labels/*.label (required)
  std::string pcap;  ///< --pcap FILE: a Velodyne capture instead of SEQUENCE (implies --live)
  std::string sensor_name = "auto";  ///< --sensor: the capture's or sensor's Velodyne model
  std::string calibration;           ///< --calibration XML: the capture's calibration (HDL-64E)
  bool live_sensor = false;          ///< --live without SEQUENCE: a sensor's packets on UDP --port
  int port = 2368;                   ///< --port: the sensor's UDP data port (Velodyne's default)
  double timeout = 5.0;  ///< --timeout: error when no data packet comes for this long [s]
};

tools::OptionTable optionTable() {
  const ViewerParameters d;
  return tools::OptionTable(
      {{"--detections", "DIR",
        "pcl_movers_detect output: DIR/tracks.csv (boxes, arrows, trails),\nDIR/labelled/*.pcd "
        "if present (point classes; refused when its\nrun_key.txt or file names do not match "
        "tracks.csv and SEQUENCE),\nelse DIR/labels/*.label if present (see --point-labels), "
        "else\npoints inside a track's box take its colour"},
       {"--point-labels", "",
        "colour points by DIR/labels/NAME.label (pcl_movers_detect\n--point-labels; SemanticKITTI: "
        "classes 251-259 movers, track in\nthe high 16 bits) even when DIR/labelled/ exists; "
        "an error when\nthey are missing. Without it they are used when DIR has no labelled/"},
       {"--movers-only", "", "draw only the movers: their points, boxes, arrows and trails"},
       {"--live", "",
        "run the detector (MoverDetector) while playing instead of reading\n--detections; poses "
        "from the sequence, else estimated from the scans.\nWithout SEQUENCE: a live Velodyne "
        "sensor (--sensor, --port), the\nnewest sweep shown while playing"},
       {"--port", "N", "--live sensor: UDP data port", std::to_string(d.port)},
       {"--timeout", "S", "--live sensor: error when no data packet comes for S seconds",
        tools::str(d.timeout)},
       {"--config", "FILE", "detector parameters for --live (pcl_movers_detect --print-config)"},
       {"--pcap", "FILE",
        "play a Velodyne packet capture instead of SEQUENCE, detecting while\nplaying (--live); "
        "frame i is the capture's i-th full sweep, as in\npcl_movers_detect --pcap; poses "
        "estimated. The sweeps are decoded\nonce and held in memory (about 1 MB per HDL-32E "
        "sweep): --frames\nA:B views part of a long capture"},
       {"--sensor", "NAME",
        "--pcap, --live sensor: hdl32, hdl64 or vlp16; auto (--pcap only):\nfrom the first data "
        "packet",
        d.sensor_name},
       {"--calibration", "XML",
        "--pcap, --live sensor: VeloView/PCL calibration (db.xml; required\nfor hdl64)"},
       {"--ground-truth", "", "also draw the ground-truth boxes of SEQUENCE/objects.txt (magenta)"},
       {"--frames", "A:B",
        "frames to show or render, 0-based inclusive (tracks.csv's `frame`);\nA:, :B, A also "
        "work",
        "all"},
       {"--camera", "NAME", "chase or bird", d.camera},
       {"--point-size", "PX", "point size in pixels", tools::str(d.point_size)},
       {"--trail", "N", "trail length in frames, 0 = none", std::to_string(d.trail)},
       {"--arrow-seconds", "S", "velocity arrows end where the object is S seconds later",
        tools::str(d.arrow_seconds)},
       {"--rate", "HZ", "frame rate when there is no times.txt", tools::str(d.rate)},
       {"--size", "WxH", "window / image size in pixels", d.size},
       {"", "", "Off-screen mode (no window; works under xvfb-run):"},
       {"--screenshot-dir", "DIR", "render the frames to DIR/<frame file name>.png and exit"},
       {"--format", "png|ppm", "image format", d.format},
       {"--overwrite", "", "allow writing into a non-empty DIR"}});
}

void printHelp(const char* program) {
  std::printf(
      "Usage: %s SEQUENCE [options]\n"
      "       %s --pcap FILE [--sensor hdl32|hdl64|vlp16] [options]\n"
      "       %s --live --sensor hdl32|hdl64|vlp16 [--port 2368] [options]\n\n"
      "Plays a LiDAR sequence folder (frames/*.pcd, *.pcd, *.bin or velodyne/*.bin; poses.txt,\n"
      "times.txt, objects.txt optional) with the tracks of pcl_movers_detect, or renders PNG\n"
      "screenshots. The overlay shows `frame I/N (file NNNNNN)`: I is tracks.csv's `frame`, the\n"
      "file number its `file` column.\n\n"
      "Options (-h, --help: this help):\n%s\n"
      "Keys (interactive mode):\n"
      "  space                 play / pause\n"
      "  right, n / left, p    step one frame forward / back\n"
      "  + / -                 play faster / slower (x2 / x0.5)\n"
      "  1 / 2 / 3             camera: chase / bird's-eye / free (mouse)\n"
      "  tab                   select the next track (movers first); its speed is shown\n"
      "  s                     save a screenshot (viewer_NNNNNN.png in the current folder)\n"
      "  q                     quit\n\n"
      "Colours: ground dark grey, movers red with orange boxes, arrows and trails; stationary\n"
      "tracks in cool per-track colours; other points grey by height; ground truth magenta;\n"
      "the selected track yellow.\n",
      program, program, program, optionTable().help().c_str());
}

double parseNumber(const std::string& option, const std::string& text, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream s;
    s << option << " " << text << ": expected a number between " << lo << " and " << hi;
    throw InputError(s.str());
  }
  return v;
}

ViewerParameters parseParameters(int argc, char** argv, std::string& sequence) {
  const auto args = optionTable().parse(argc, argv);
  ViewerParameters p;
  args.get("--pcap", p.pcap);
  args.get("--sensor", p.sensor_name);
  args.get("--calibration", p.calibration);
  p.live_sensor = args.has("--live") && p.pcap.empty() && args.positional.empty();
  std::string v;
  if (args.get("--port", v)) p.port = static_cast<int>(parseNumber("--port", v, 1, 65535));
  if (args.get("--timeout", v)) p.timeout = parseNumber("--timeout", v, 0.1, 3600);
  if (!p.live_sensor && (args.has("--port") || args.has("--timeout")))
    throw InputError("--port and --timeout are for --live without SEQUENCE (a sensor)");
  if (p.live_sensor) {
    if (p.sensor_name == "auto")
      throw InputError(
          "--live without SEQUENCE listens to a sensor: give --sensor hdl32, hdl64 "
          "or vlp16");
  } else if (p.pcap.empty()) {
    if (args.positional.size() != 1)
      throw InputError("expected exactly one SEQUENCE folder, got " +
                       std::to_string(args.positional.size()) + " (see -h)");
    sequence = args.positional.front();
    if (args.has("--sensor") || !p.calibration.empty())
      throw InputError(
          "--sensor and --calibration are for --pcap or a --live sensor (a sequence folder is "
          "decoded)");
  } else if (!args.positional.empty()) {
    throw InputError("--pcap " + p.pcap + " and SEQUENCE " + args.positional.front() +
                     " exclude each other: give one");
  }
  args.get("--detections", p.detections);
  args.get("--screenshot-dir", p.screenshot_dir);
  args.get("--frames", p.frames);
  args.get("--size", p.size);
  args.get("--camera", p.camera);
  args.get("--format", p.format);
  if (args.get("--point-size", v)) p.point_size = parseNumber("--point-size", v, 1, 20);
  if (args.get("--trail", v)) p.trail = static_cast<int>(parseNumber("--trail", v, 0, 1000));
  if (args.get("--arrow-seconds", v)) p.arrow_seconds = parseNumber("--arrow-seconds", v, 0, 60);
  if (args.get("--rate", v)) p.rate = parseNumber("--rate", v, 0.01, 1000);
  p.ground_truth = args.has("--ground-truth");
  p.overwrite = args.has("--overwrite");
  p.live = args.has("--live") || !p.pcap.empty();
  p.movers_only = args.has("--movers-only");
  p.point_labels = args.has("--point-labels");
  args.get("--config", p.config);
  if (!p.pcap.empty() && (!p.detections.empty() || p.ground_truth))
    throw InputError(
        "--pcap detects while playing: --detections and --ground-truth need a "
        "SEQUENCE folder");
  if (p.point_labels && p.detections.empty())
    throw InputError("--point-labels needs --detections DIR (it reads DIR/labels/)");
  if (p.live && !p.detections.empty())
    throw InputError(
        "--live and --detections exclude each other (live detection makes the tracks)");
  if (!p.config.empty() && !p.live) throw InputError("--config only applies to --live");
  if (p.format != "png" && p.format != "ppm")
    throw InputError("--format " + p.format + ": use png or ppm");
  if (!p.screenshot_dir.empty() && !sequence.empty() && p.screenshot_dir == sequence)
    throw InputError("--screenshot-dir must not be the SEQUENCE folder");
  return p;
}

/** Per-point classes and track ids stored in a labelled cloud of pcl_movers_detect. Field names are
 * matched loosely so small naming differences in the detector's output do not break the viewer. */
bool readLabelledCloud(const std::string& path, pcl::PointCloud<pcl::PointXYZI>& cloud,
                       viz::PointLabels& labels) {
  pcl::PCLPointCloud2 blob;
  if (pcl::io::loadPCDFile(path, blob) < 0)
    throw InputError(path, 0, "not a readable labelled PCD file");
  auto find = [&](std::initializer_list<const char*> names) -> const pcl::PCLPointField* {
    for (const char* n : names)
      for (const auto& f : blob.fields)
        if (f.name == n) return &f;
    return nullptr;
  };
  const auto* fx = find({"x"});
  const auto* fcls = find({"class", "point_class", "label"});
  const auto* ftrack = find({"track_id", "track", "object", "instance"});
  if (!fx || (!fcls && !ftrack))
    throw InputError(path, 0, "labelled PCD needs x y z and a class or track_id field");
  // Through PointXYZ: labelled clouds have no intensity and PCL would warn about it.
  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::fromPCLPointCloud2(blob, xyz);
  cloud.resize(xyz.size());
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    cloud[i].x = xyz[i].x, cloud[i].y = xyz[i].y, cloud[i].z = xyz[i].z;
    cloud[i].intensity = 0.f;
  }
  cloud.width = xyz.width, cloud.height = xyz.height, cloud.is_dense = xyz.is_dense;
  auto value = [&](const pcl::PCLPointField* f, std::size_t i) -> double {
    const std::uint8_t* p = blob.data.data() + i * blob.point_step + f->offset;
    switch (f->datatype) {
      case pcl::PCLPointField::INT8:
        return *reinterpret_cast<const std::int8_t*>(p);
      case pcl::PCLPointField::UINT8:
        return *p;
      case pcl::PCLPointField::INT16: {
        std::int16_t v;
        std::memcpy(&v, p, 2);
        return v;
      }
      case pcl::PCLPointField::UINT16: {
        std::uint16_t v;
        std::memcpy(&v, p, 2);
        return v;
      }
      case pcl::PCLPointField::INT32: {
        std::int32_t v;
        std::memcpy(&v, p, 4);
        return v;
      }
      case pcl::PCLPointField::UINT32: {
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
      }
      case pcl::PCLPointField::FLOAT32: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      }
      case pcl::PCLPointField::FLOAT64: {
        double v;
        std::memcpy(&v, p, 8);
        return v;
      }
      default:
        return 0;
    }
  };
  const std::size_t n = cloud.size();
  labels.classes.assign(n, viz::PointClass::Unassigned);
  labels.track_ids.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    if (fcls) {
      const int c = static_cast<int>(std::lround(value(fcls, i)));
      if (c >= 0 && c <= 3) labels.classes[i] = static_cast<viz::PointClass>(c);
    }
    if (ftrack) {
      const double t = value(ftrack, i);
      labels.track_ids[i] = std::isfinite(t) && t >= 0 ? static_cast<int>(std::lround(t)) : -1;
    }
  }
  return true;
}

/** Value of `"key": "..."` in summary.json text, "" when absent. */
std::string jsonString(const std::string& text, const std::string& key) {
  const std::string tag = "\"" + key + "\": \"";
  const std::size_t b = text.find(tag);
  if (b == std::string::npos) return "";
  const std::size_t e = text.find('"', b + tag.size());
  return e == std::string::npos ? "" : text.substr(b + tag.size(), e - b - tag.size());
}

std::string readText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/** Refuses a labelled/ folder that pcl_movers_detect did not write with the tracks.csv beside it
 * (copied from another run): its run_key.txt must hold summary.json's run_key, and every labelled
 * cloud must be named as a frame of the sequence. */
void checkLabelledBelongs(const fs::path& labelled, const fs::path& detections,
                          const io::SequenceReader& reader) {
  const std::string summary_key = jsonString(readText(detections / "summary.json"), "run_key");
  std::error_code ec;
  if (!summary_key.empty() && fs::exists(labelled / "run_key.txt", ec)) {
    std::string stamp = readText(labelled / "run_key.txt");
    stamp.erase(stamp.find_last_not_of(" \n\r") + 1);
    if (stamp != summary_key)
      throw InputError(labelled.string(), 0,
                       "written by another run than " + (detections / "tracks.csv").string() +
                           " (run_key.txt " + stamp + ", summary.json " + summary_key +
                           "); run pcl_movers_detect --labelled-clouds again");
  }
  std::set<std::string> frames;
  for (std::size_t i = 0; i < reader.size(); ++i) frames.insert(reader.frameName(i));
  for (const auto& e : fs::directory_iterator(labelled, ec))
    if (e.path().extension() == ".pcd" && !frames.count(e.path().stem().string()))
      throw InputError(e.path().string(), 0,
                       "is no frame of the sequence: labelled/ belongs to another sequence");
}

/** Colours from OUT/labels/NAME.label (pcl_movers_detect --point-labels, SemanticKITTI layout:
 * one uint32 per input point, class in the low 16 bits, 251-259 moving, track id in the high
 * 16): movers take their track, every other point keeps `labels` but is no mover. */
void applyPointLabels(const std::string& path, std::size_t points, viz::PointLabels& labels) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open point labels");
  std::vector<std::uint32_t> raw(points);
  in.read(reinterpret_cast<char*>(raw.data()), std::streamsize(4 * points));
  if (in.gcount() != std::streamsize(4 * points) || in.peek() != EOF)
    throw InputError(path, 0,
                     "expected " + std::to_string(points) +
                         " labels (one per point of the frame): labels of another sequence?");
  for (std::size_t k = 0; k < points; ++k) {
    const std::uint32_t cls = raw[k] & 0xFFFF;
    if (cls >= 251 && cls <= 259) {
      labels.classes[k] = viz::PointClass::Mover;
      labels.track_ids[k] = static_cast<int>(raw[k] >> 16);
    } else if (labels.classes[k] == viz::PointClass::Mover) {
      labels.classes[k] = viz::PointClass::Unassigned;
      labels.track_ids[k] = -1;
    }
  }
}

/** The frames the viewer shows: a sequence folder, the full sweeps of a Velodyne capture
 * (--pcap) decoded once, in order, and held in memory (the viewer steps back and forth, and a
 * capture can only be read forward), or a live sensor's sweeps (--live without SEQUENCE), appended
 * by a receiving thread as they complete, the last kLiveKept of them held. A sweep's frame i is
 * its i-th full sweep, as for pcl_movers_detect --pcap/--live; its time is its first firing
 * after the first sweep's. */
class FrameSource {
 public:
  static constexpr std::size_t kLiveKept = 600;  ///< a minute of a 10 Hz sensor

  FrameSource() = default;
  FrameSource(const FrameSource&) = delete;
  FrameSource& operator=(const FrameSource&) = delete;
  ~FrameSource() { stop(); }

  void openFolder(const std::string& folder, double rate_hz) { reader_.open(folder, rate_hz); }
  /** Decodes the sweeps 0..`last` (all when `last` is SIZE_MAX), with a progress line. */
  void openCapture(const std::string& pcap, io::VelodyneModel model, const std::string& calibration,
                   std::size_t last) {
    name_ = pcap;
    io::VelodyneCapture capture(pcap, model, calibration);
    io::VelodyneSweep sweep;
    while (size() <= last && capture.next(sweep)) {
      append(sweep);
      if (size() % 100 == 0)
        print_info("[%s] %zu sweeps decoded from %s\n", kTool, size(), pcap.c_str());
    }
    ended_ = true;
    print_info("[%s] %s: %zu full %s sweeps\n", kTool, pcap.c_str(), size(),
               io::velodyneModelName(model).c_str());
  }
  /** Listens to a sensor on UDP `port` (PCL's grabber) and receives on a thread of its own. */
  void openLive(int port, io::VelodyneModel model, const std::string& calibration, double timeout) {
    name_ = "udp:" + std::to_string(port);
    live_ = io::VelodyneCapture::listen(port, model, calibration, timeout);
    receiver_ = std::thread([this] { receive(); });
  }
  /** Live: stops listening (the frames received stay). */
  void stop() {
    if (live_) live_->stop();
    if (receiver_.joinable()) receiver_.join();
  }
  /** Waits until frame i has arrived; false when the sensor stream ended before it. Throws the
   * receiver's error (no data packet for the timeout). A folder or capture does not wait. */
  bool waitFor(std::size_t i) const {
    if (!isSweeps()) return i < reader_.size();
    std::unique_lock<std::mutex> lock(mutex_);
    arrived_.wait(lock, [&] { return times_.size() > i || ended_; });
    if (!error_.empty() && times_.size() <= i) throw InputError(name_ + ": " + error_);
    return times_.size() > i;
  }
  bool isSweeps() const { return !name_.empty(); }
  bool isLive() const { return live_ != nullptr; }
  std::size_t size() const {
    if (!isSweeps()) return reader_.size();
    std::lock_guard<std::mutex> lock(mutex_);
    return times_.size();
  }
  bool empty() const { return size() == 0; }
  /** Frame i is still held (a live source drops sweeps older than kLiveKept). */
  bool held(std::size_t i) const {
    if (!isSweeps()) return i < reader_.size();
    std::lock_guard<std::mutex> lock(mutex_);
    return i < sweeps_.size() && sweeps_[i];
  }
  void read(std::size_t i, pcl::PointCloud<pcl::PointXYZI>& cloud) const {
    if (!isSweeps()) return reader_.read(i, cloud);
    std::lock_guard<std::mutex> lock(mutex_);
    if (i >= sweeps_.size() || !sweeps_[i])
      throw InputError(framePath(i) + ": not held (a live view keeps the last " +
                       std::to_string(kLiveKept) + " sweeps)");
    cloud = *sweeps_[i];
  }
  double time(std::size_t i) const {
    if (!isSweeps()) return reader_.time(i);
    std::lock_guard<std::mutex> lock(mutex_);
    return times_.at(i);
  }
  bool hasPoses() const { return !isSweeps() && reader_.hasPoses(); }
  Eigen::Isometry3d pose(std::size_t i) const { return reader_.pose(i); }
  /** Screenshot and label file stem: the file's, or the sweep index in six digits. */
  std::string frameName(std::size_t i) const {
    if (!isSweeps()) return reader_.frameName(i);
    char name[32];
    std::snprintf(name, sizeof(name), "%06zu", i);
    return name;
  }
  long long frameNumber(std::size_t i) const {
    return isSweeps() ? static_cast<long long>(i) : reader_.frameNumber(i);
  }
  /** Frame i named for messages. */
  std::string framePath(std::size_t i) const {
    return isSweeps() ? name_ + " sweep " + std::to_string(i) : reader_.framePaths().at(i);
  }
  /** The sequence folder (empty for sweeps). */
  const io::SequenceReader& folder() const { return reader_; }

 private:
  void append(const io::VelodyneSweep& sweep) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (times_.empty()) start_ = sweep.start_time;
    times_.push_back(sweep.start_time - start_);
    sweeps_.push_back(sweep.cloud);
    if (isLive() && sweeps_.size() > kLiveKept) sweeps_[sweeps_.size() - kLiveKept - 1].reset();
    arrived_.notify_all();
  }
  void receive() {
    std::string error;
    try {
      io::VelodyneSweep sweep;
      while (live_->next(sweep)) append(sweep);
    } catch (const std::exception& e) {
      error = e.what();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = error;
    ended_ = true;
    arrived_.notify_all();
  }

  io::SequenceReader reader_;
  std::string name_;  ///< the capture or "udp:PORT"; empty for a folder
  std::unique_ptr<io::VelodyneCapture> live_;
  std::thread receiver_;
  mutable std::mutex mutex_;  ///< guards what follows (the receiver appends)
  mutable std::condition_variable arrived_;
  std::vector<pcl::PointCloud<pcl::PointXYZI>::ConstPtr> sweeps_;
  std::vector<double> times_;
  double start_ = 0.0;
  bool ended_ = false;
  std::string error_;
};

/** Everything the viewer shows, loaded and validated before any window opens. */
struct SceneData {
  FrameSource source;
  viz::TrackIndex tracks;
  bool has_tracks = false;
  std::string labelled_dir;
  std::string labels_dir;  ///< DIR/labels (SemanticKITTI .label per frame), "" = not used
  std::map<int, std::vector<io::GroundTruthObject>> ground_truth;
  bool has_ground_truth = false;
};

/** --pcap: the capture's sweeps up to the last one --frames asks for. */
void loadCapture(const ViewerParameters& p, SceneData& scene) {
  std::error_code ec;
  if (!fs::is_regular_file(p.pcap, ec))
    throw InputError(p.pcap, 0,
                     fs::exists(p.pcap, ec) ? "--pcap: not a file" : "--pcap: does not exist");
  const auto model = io::velodyneModelFor(p.sensor_name, p.pcap);
  const std::size_t last =
      p.frames.empty() ? SIZE_MAX : viz::parseFrameRange(p.frames, SIZE_MAX).last;
  scene.source.openCapture(p.pcap, model, p.calibration, last);
  if (scene.source.empty()) throw InputError(p.pcap, 0, "no full sweep in the capture");
}

/** --live without SEQUENCE: listens to the sensor and waits for its first sweep. */
void loadLive(const ViewerParameters& p, SceneData& scene) {
  const auto model = io::velodyneModelFromName(p.sensor_name);
  scene.source.openLive(p.port, model, p.calibration, p.timeout);
  print_info("[%s] listening to a %s on UDP port %d\n", kTool, io::velodyneModelName(model).c_str(),
             p.port);
  if (!scene.source.waitFor(0))
    throw InputError("udp:" + std::to_string(p.port) + ": the sensor stream ended before a sweep");
}

void loadScene(const std::string& sequence, const ViewerParameters& p, SceneData& scene) {
  if (!p.pcap.empty()) return loadCapture(p, scene);
  if (p.live_sensor) return loadLive(p, scene);
  std::error_code ec;
  if (!fs::exists(sequence, ec)) throw InputError(sequence, 0, "no such sequence folder");
  if (!fs::is_directory(sequence, ec)) throw InputError(sequence, 0, "not a folder");
  scene.source.openFolder(sequence, p.rate);
  if (scene.source.empty())
    throw InputError(sequence, 0,
                     "no frames (expected frames/*.pcd, *.pcd or velodyne/*.bin in the folder)");
  const std::size_t n = scene.source.size();
  if (!p.detections.empty()) {
    if (!fs::is_directory(p.detections, ec))
      throw InputError(p.detections, 0, "--detections: no such folder");
    const std::string csv = (fs::path(p.detections) / "tracks.csv").string();
    if (!fs::is_regular_file(csv, ec))
      throw InputError(csv, 0, "missing (is --detections a pcl_movers_detect output folder?)");
    auto rows = io::readTracks(csv);
    for (const auto& r : rows)
      if (r.frame < 0 || static_cast<std::size_t>(r.frame) >= n)
        throw InputError(csv, 0,
                         "row for frame " + std::to_string(r.frame) + " but " + sequence + " has " +
                             std::to_string(n) + " frames: detections of another sequence?");
    scene.tracks = viz::TrackIndex(std::move(rows));
    scene.has_tracks = true;
    const fs::path labelled = fs::path(p.detections) / "labelled";
    if (fs::is_directory(labelled, ec)) {
      checkLabelledBelongs(labelled, fs::path(p.detections), scene.source.folder());
      scene.labelled_dir = labelled.string();
    }
    const fs::path labels = fs::path(p.detections) / "labels";
    if (fs::is_directory(labels, ec) && (p.point_labels || scene.labelled_dir.empty()))
      scene.labels_dir = labels.string();
    if (p.point_labels && scene.labels_dir.empty())
      throw InputError(labels.string(), 0,
                       "--point-labels: no such folder (pcl_movers_detect --point-labels writes "
                       "it)");
    if (p.point_labels) scene.labelled_dir.clear();
  }
  if (p.ground_truth) {
    const std::string path = scene.source.folder().objectsPath();
    if (path.empty())
      throw InputError(sequence, 0, "--ground-truth: the sequence has no objects.txt");
    for (auto& o : io::readObjects(path)) {
      if (o.frame < 0 || static_cast<std::size_t>(o.frame) >= n)
        throw InputError(path, 0,
                         "object in frame " + std::to_string(o.frame) + " but the sequence has " +
                             std::to_string(n) + " frames");
      scene.ground_truth[o.frame].push_back(std::move(o));
    }
    scene.has_ground_truth = true;
  }
}

/** Live detection (--live): runs MoverDetector frame by frame as the viewer reaches new frames. The
 * tracker is sequential, so frames are processed in order from the first frame shown; the last
 * kCached frames keep their organized clouds and labels for display, older ones are drawn from
 * their rows like --detections without labelled clouds. */
class LiveDetector {
 public:
  using Detector = MoverDetector<pcl::PointXYZI>;
  static constexpr std::size_t kCached = 30;

  LiveDetector(const SceneData& scene, const ViewerParameters& p, std::size_t first)
      : scene_(scene), next_(first) {
    DetectorParameters params;
    if (!p.config.empty()) params.readConfig(p.config);
    detector_.setParameters(params);
  }

  /** Processes every frame up to and including i (no-op when done already). */
  void ensure(std::size_t i) {
    while (next_ <= i) {
      pcl::PointCloud<pcl::PointXYZI>::Ptr scan(new pcl::PointCloud<pcl::PointXYZI>);
      scene_.source.read(next_, *scan);
      const Eigen::Isometry3d pose =
          scene_.source.hasPoses() ? scene_.source.pose(next_) : ego_.estimate(*scan);
      scan->sensor_origin_.setZero();
      scan->sensor_orientation_.setIdentity();
      auto result = std::make_shared<Detector::FrameResult>();
      try {
        detector_.process(scan, pose, scene_.source.time(next_), static_cast<int>(next_), *result);
      } catch (const InputError& e) {
        throw InputError(scene_.source.framePath(next_) + ": " + e.what());
      }
      rows_.insert(rows_.end(), result->rows.begin(), result->rows.end());
      cache_.emplace_back(next_, result);
      if (cache_.size() > kCached) cache_.pop_front();
      ++next_;
      dirty_ = true;
    }
  }
  /** All rows so far, re-indexed only when new frames were processed. */
  const viz::TrackIndex& tracks() {
    if (dirty_) index_ = viz::TrackIndex(rows_);
    dirty_ = false;
    return index_;
  }
  /** The detector's output of frame i if still cached, else null. */
  std::shared_ptr<const Detector::FrameResult> frame(std::size_t i) const {
    for (const auto& c : cache_)
      if (c.first == i) return c.second;
    return nullptr;
  }

 private:
  const SceneData& scene_;
  Detector detector_;
  EgoMotionEstimator<pcl::PointXYZI> ego_;
  std::size_t next_;
  std::vector<io::TrackRow> rows_;
  std::deque<std::pair<std::size_t, std::shared_ptr<const Detector::FrameResult>>> cache_;
  viz::TrackIndex index_;
  bool dirty_ = true;
};

/** Per-key behaviour without PCLVisualizer's own bindings for the same keys (its '1' recolours
 * clouds, 's' switches to surfaces, 'p' to points, '+'/'-' change point size), which would fight
 * with ours. Keys we do not use keep PCL's behaviour (mouse, 'r' reset, 'q' quit, ...). */
class ViewerInteractorStyle : public pcl::visualization::PCLVisualizerInteractorStyle {
 public:
  static ViewerInteractorStyle* New();
  vtkTypeMacro(ViewerInteractorStyle, pcl::visualization::PCLVisualizerInteractorStyle);
  /** Returns true when the key was handled. */
  std::function<bool(const std::string& keysym, char code)> handler;

 protected:
  void OnKeyDown() override {
    if (handler && Interactor && handler(safeKeySym(), Interactor->GetKeyCode())) return;
    pcl::visualization::PCLVisualizerInteractorStyle::OnKeyDown();
  }
  void OnChar() override {
    if (Interactor && isOurs(safeKeySym(), Interactor->GetKeyCode())) return;
    pcl::visualization::PCLVisualizerInteractorStyle::OnChar();
  }

 private:
  std::string safeKeySym() const {
    const char* s = Interactor ? Interactor->GetKeySym() : nullptr;
    return s ? s : "";
  }
  static bool isOurs(const std::string& sym, char c) {
    static const char* syms[] = {"space", "Right", "Left",   "Tab",        "plus",
                                 "minus", "equal", "KP_Add", "KP_Subtract"};
    for (const char* s : syms)
      if (sym == s) return true;
    return std::string(" np+-=123\ts").find(c) != std::string::npos && c != '\0';
  }
};
vtkStandardNewMacro(ViewerInteractorStyle);

/** Builds the VTK actors of one frame on a PCLVisualizer. */
class FrameRenderer {
 public:
  FrameRenderer(const SceneData& scene, const ViewerParameters& params, bool offscreen, int width,
                int height)
      : scene_(scene), params_(params), width_(width), height_(height) {
    if (offscreen) {
      viewer_.reset(new pcl::visualization::PCLVisualizer(kTool, false));
      viewer_->getRenderWindow()->SetOffScreenRendering(1);
    } else {
      int argc = 1;
      char name[] = "pcl_movers_viewer";
      char* argv[] = {name, nullptr};
      style_ = ViewerInteractorStyle::New();
      viewer_.reset(new pcl::visualization::PCLVisualizer(argc, argv, kTool, style_, true));
    }
    viewer_->setSize(width, height);
    viewer_->setShowFPS(false);
    const auto& bg = style_colors_.background;
    viewer_->setBackgroundColor(bg.r / 255.0, bg.g / 255.0, bg.b / 255.0);
    renderer_ = viewer_->getRendererCollection()->GetFirstRenderer();
    font_size_ = std::max(10, height / 42);
  }

  pcl::visualization::PCLVisualizer& viewer() { return *viewer_; }
  void setLive(LiveDetector* live) { live_ = live; }
  const viz::TrackIndex& tracks() const { return live_ ? live_->tracks() : scene_.tracks; }
  ViewerInteractorStyle* style() { return style_; }
  int selectedTrack() const { return selected_; }
  void setSelectedTrack(int id) { selected_ = id; }
  const std::vector<io::TrackRow>& rows(std::size_t frame) const {
    return tracks().frame(static_cast<int>(frame));
  }

  /** Loads frame i and replaces all actors. `status` is appended to the overlay. */
  void show(std::size_t i, const std::string& status = "") {
    pcl::PointCloud<pcl::PointXYZI> cloud;
    viz::PointLabels labels;
    if (live_) live_->ensure(i);
    const auto live_frame = live_ ? live_->frame(i) : nullptr;
    const auto& rows = this->rows(i);
    const std::string labelled = labelledPath(i);
    if (live_frame && live_frame->organized) {
      cloud = *live_frame->organized;
      const std::size_t n = cloud.size();
      labels.classes.assign(n, viz::PointClass::Unassigned);
      labels.track_ids.assign(n, -1);
      // MoverDetector::Label and viz::PointClass share their values (0 none .. 3 mover).
      for (std::size_t k = 0; k < n && k < live_frame->labels.size(); ++k)
        if (live_frame->labels[k] <= 3)
          labels.classes[k] = static_cast<viz::PointClass>(live_frame->labels[k]);
      for (std::size_t k = 0; k < n && k < live_frame->track_ids.size(); ++k)
        labels.track_ids[k] = live_frame->track_ids[k];
    } else if (!labelled.empty()) {
      readLabelledCloud(labelled, cloud, labels);
    } else {
      scene_.source.read(i, cloud);
      const auto ground = viz::estimateGroundMask(cloud);
      labels = viz::labelPointsFromTracks(cloud, ground, rows);
      const fs::path label_file =
          fs::path(scene_.labels_dir) / (scene_.source.frameName(i) + ".label");
      std::error_code ec;
      if (!scene_.labels_dir.empty() && fs::exists(label_file, ec))
        applyPointLabels(label_file.string(), cloud.size(), labels);
    }
    std::vector<int> movers;
    for (const auto& r : rows)
      if (r.mover) movers.push_back(r.track_id);
    const auto colors = viz::colorPoints(cloud, labels, movers, style_colors_);

    // Mover points go into a second cloud drawn with bigger points: they are what the viewer is
    // for, and at 30 m a car has only a few dozen returns.
    pcl::PointCloud<pcl::PointXYZRGB>::Ptr coloured(new pcl::PointCloud<pcl::PointXYZRGB>);
    pcl::PointCloud<pcl::PointXYZRGB>::Ptr mover_points(new pcl::PointCloud<pcl::PointXYZRGB>);
    coloured->reserve(cloud.size());
    std::size_t finite = 0;
    for (std::size_t k = 0; k < cloud.size(); ++k) {
      const auto& p = cloud[k];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
      pcl::PointXYZRGB q;
      q.x = p.x, q.y = p.y, q.z = p.z;
      q.r = colors[k].r, q.g = colors[k].g, q.b = colors[k].b;
      const bool mover = colors[k] == style_colors_.mover_points;
      if (mover || !params_.movers_only) (mover ? mover_points : coloured)->push_back(q);
      ++finite;
    }
    if (finite == 0) print_warn("[%s] frame %zu has no finite points\n", kTool, i);
    setCloud(coloured, "points", params_.point_size);
    setCloud(mover_points, "movers", params_.point_size + 2.0);
    const auto boxes = viz::fitTrackBoxes(cloud, labels, rows);

    // Pose of this frame: the sequence's, else fitted to the rows' sensor/world pairs.
    std::optional<Eigen::Isometry3d> pose;
    if (scene_.source.hasPoses()) pose = scene_.source.pose(i);
    if (!pose) pose = viz::fitSensorPose(rows);
    const Eigen::Isometry3d sensor_to_world = pose ? *pose : Eigen::Isometry3d::Identity();
    const Eigen::Isometry3d world_to_sensor = sensor_to_world.inverse();

    viz::LineSet lines, thick;
    const io::TrackRow* selected = nullptr;
    int mover_count = 0;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const auto& r = rows[k];
      const bool is_selected = r.track_id == selected_;
      if (is_selected) selected = &r;
      if (r.mover) ++mover_count;
      if (params_.movers_only && !r.mover && !is_selected) continue;
      const viz::Color box_color = is_selected ? style_colors_.selected
                                   : r.mover   ? style_colors_.mover_box
                                               : viz::trackColor(r.track_id);
      auto& target = (r.mover || is_selected) ? thick : lines;
      if (r.length > 0 && r.width > 0 && r.height > 0) target.addBox(boxes[k], box_color);
      // Arrows for movers and the selection only: the filter velocities of stationary tracks are
      // noise (a few tenths of m/s, more on walls) and would only add clutter.
      if (r.mover || is_selected) {
        const auto arrow = viz::velocityArrow(r, sensor_to_world, params_.arrow_seconds);
        target.addArrow(arrow.first, arrow.second, box_color);
      }
      if ((r.mover || is_selected) && params_.trail > 0) {
        const auto trail =
            pose ? tracks().trail(r.track_id, static_cast<int>(i), params_.trail, world_to_sensor)
                 : tracks().sensorTrail(r.track_id, static_cast<int>(i), params_.trail);
        target.addPolyline(trail, box_color);
      }
    }
    if (scene_.has_ground_truth) {
      auto it = scene_.ground_truth.find(static_cast<int>(i));
      if (it != scene_.ground_truth.end())
        for (const auto& o : it->second)
          lines.addBox(viz::OrientedBox::fromGroundTruth(o), style_colors_.ground_truth);
    }
    setLines(thin_actor_, lines, 1.5);
    setLines(thick_actor_, thick, 3.0);

    std::string extra = status;
    if (selected_ >= 0 && !selected)
      extra += (extra.empty() ? "" : "   ") + std::string("track ") + std::to_string(selected_) +
               " not in this frame";
    const double t = scene_.source.time(i);
    const std::string text = viz::overlayText(i, scene_.source.size(), t, mover_count, selected,
                                              extra, scene_.source.frameNumber(i)) +
                             (scene_.has_tracks || live_ ? "" : "\n(no --detections: points only)");
    // VTK anchors multi-line text at its bottom-left corner: place it so the first line sits at
    // the top of the window whatever the number of lines.
    const int text_lines = 1 + static_cast<int>(std::count(text.begin(), text.end(), '\n'));
    const int text_y = height_ - 10 - static_cast<int>(text_lines * font_size_ * 1.2);
    const auto& tc = style_colors_.text;
    if (!viewer_->updateText(text, 12, text_y, font_size_, tc.r / 255.0, tc.g / 255.0, tc.b / 255.0,
                             "overlay"))
      viewer_->addText(text, 12, text_y, font_size_, tc.r / 255.0, tc.g / 255.0, tc.b / 255.0,
                       "overlay");
    std::string legend =
        "red: mover points   orange: mover box/arrow/trail   colours: static tracks";
    if (scene_.has_ground_truth) legend += "   magenta: ground truth";
    const int legend_size = std::max(9, font_size_ - 4);
    if (!viewer_->updateText(legend, 12, 8, legend_size, 0.7, 0.7, 0.7, "legend"))
      viewer_->addText(legend, 12, 8, legend_size, 0.7, 0.7, 0.7, "legend");
    renderer_->ResetCameraClippingRange();
  }

  void applyCamera(viz::CameraPreset preset) {
    if (preset == viz::CameraPreset::Free) return;
    const auto c = viz::cameraView(preset);
    viewer_->setCameraPosition(c.position.x(), c.position.y(), c.position.z(), c.focal.x(),
                               c.focal.y(), c.focal.z(), c.up.x(), c.up.y(), c.up.z());
    viewer_->setCameraFieldOfView(c.fov_y_deg * M_PI / 180.0);
    renderer_->ResetCameraClippingRange();
  }

  /** Renders and writes the current view; via a temporary name so a failed write leaves nothing
   * half-written under the final name. */
  void writeImage(const std::string& path, const std::string& format) {
    vtkSmartPointer<vtkRenderWindow> window = viewer_->getRenderWindow();
    renderer_->ResetCameraClippingRange();
    window->Render();
    vtkSmartPointer<vtkWindowToImageFilter> grab = vtkSmartPointer<vtkWindowToImageFilter>::New();
    grab->SetInput(window);
    grab->SetInputBufferTypeToRGB();
    grab->ReadFrontBufferOff();
    grab->Update();
    const std::string tmp = path + ".part";
    bool ok = false;
    if (format == "ppm") {
      ok = writePpm(grab->GetOutput(), tmp);
    } else {
      vtkSmartPointer<vtkPNGWriter> writer = vtkSmartPointer<vtkPNGWriter>::New();
      writer->SetFileName(tmp.c_str());
      writer->SetInputConnection(grab->GetOutputPort());
      writer->Write();
      std::error_code ec;
      ok = writer->GetErrorCode() == 0 && fs::file_size(tmp, ec) > 0 && !ec;
    }
    std::error_code ec;
    if (ok) fs::rename(tmp, path, ec);
    if (!ok || ec) {
      fs::remove(tmp, ec);
      throw InputError(path, 0, "cannot write image");
    }
  }

 private:
  std::string labelledPath(std::size_t i) const {
    if (scene_.labelled_dir.empty()) return "";
    const fs::path p = fs::path(scene_.labelled_dir) / (scene_.source.frameName(i) + ".pcd");
    std::error_code ec;
    return fs::is_regular_file(p, ec) ? p.string() : "";
  }

  static bool writePpm(vtkImageData* image, const std::string& path) {
    int dims[3];
    image->GetDimensions(dims);
    if (image->GetNumberOfScalarComponents() < 3 || dims[0] <= 0 || dims[1] <= 0) return false;
    const int comps = image->GetNumberOfScalarComponents();
    const auto* data = static_cast<const unsigned char*>(image->GetScalarPointer());
    std::ofstream out(path, std::ios::binary);
    out << "P6\n" << dims[0] << " " << dims[1] << "\n255\n";
    std::vector<unsigned char> row(static_cast<std::size_t>(dims[0]) * 3);
    // VTK images start at the bottom row; PPM at the top.
    for (int y = dims[1] - 1; y >= 0; --y) {
      for (int x = 0; x < dims[0]; ++x)
        for (int c = 0; c < 3; ++c)
          row[static_cast<std::size_t>(x) * 3 + c] =
              data[(static_cast<std::size_t>(y) * dims[0] + x) * comps + c];
      out.write(reinterpret_cast<const char*>(row.data()),
                static_cast<std::streamsize>(row.size()));
    }
    return static_cast<bool>(out);
  }

  void setCloud(const pcl::PointCloud<pcl::PointXYZRGB>::Ptr& cloud, const std::string& id,
                double size) {
    pcl::visualization::PointCloudColorHandlerRGBField<pcl::PointXYZRGB> rgb(cloud);
    if (!viewer_->updatePointCloud<pcl::PointXYZRGB>(cloud, rgb, id))
      viewer_->addPointCloud<pcl::PointXYZRGB>(cloud, rgb, id);
    viewer_->setPointCloudRenderingProperties(pcl::visualization::PCL_VISUALIZER_POINT_SIZE, size,
                                              id);
  }

  void setLines(vtkSmartPointer<vtkActor>& actor, const viz::LineSet& set, double width) {
    if (actor) renderer_->RemoveActor(actor);
    actor = nullptr;
    if (set.segments.empty()) return;
    auto points = vtkSmartPointer<vtkPoints>::New();
    auto cells = vtkSmartPointer<vtkCellArray>::New();
    auto colors = vtkSmartPointer<vtkUnsignedCharArray>::New();
    colors->SetNumberOfComponents(3);
    colors->SetName("colors");
    for (const auto& s : set.segments) {
      const vtkIdType a = points->InsertNextPoint(s.a.x(), s.a.y(), s.a.z());
      const vtkIdType b = points->InsertNextPoint(s.b.x(), s.b.y(), s.b.z());
      const unsigned char rgb[3] = {s.color.r, s.color.g, s.color.b};
      colors->InsertNextTypedTuple(rgb);
      colors->InsertNextTypedTuple(rgb);
      const vtkIdType ids[2] = {a, b};
      cells->InsertNextCell(2, ids);
    }
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    poly->SetPoints(points);
    poly->SetLines(cells);
    poly->GetPointData()->SetScalars(colors);
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(poly);
    mapper->SetColorModeToDirectScalars();
    mapper->ScalarVisibilityOn();
    actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetLineWidth(static_cast<float>(width));
    actor->GetProperty()->LightingOff();
    renderer_->AddActor(actor);
  }

  const SceneData& scene_;
  const ViewerParameters& params_;
  viz::SceneStyle style_colors_;
  int width_, height_;
  int font_size_ = 16;
  int selected_ = -1;
  pcl::visualization::PCLVisualizer::Ptr viewer_;
  ViewerInteractorStyle* style_ = nullptr;
  vtkRenderer* renderer_ = nullptr;
  vtkSmartPointer<vtkActor> thin_actor_, thick_actor_;
  LiveDetector* live_ = nullptr;
};

bool hasDisplay() {
  const char* d = std::getenv("DISPLAY");
  return d && *d;
}

/** Off-screen mode: frames A..B to DIR/NNNNNN.png. On any error the images written so far (and
 * the folder, if this run created it) are removed, so a failed run leaves nothing behind. */
int renderScreenshots(const SceneData& scene, const ViewerParameters& p, viz::FrameRange range,
                      int width, int height, viz::CameraPreset camera) {
  std::error_code ec;
  const bool created = !fs::exists(p.screenshot_dir, ec);
  io::prepareOutputDirectory(p.screenshot_dir, p.overwrite);
  std::vector<std::string> written;
  try {
    FrameRenderer renderer(scene, p, true, width, height);
    std::unique_ptr<LiveDetector> live;
    if (p.live) live.reset(new LiveDetector(scene, p, range.first));
    renderer.setLive(live.get());
    tools::ProgressBar bar(range.last - range.first + 1, "frames");
    for (std::size_t i = range.first; i <= range.last; ++i) {
      renderer.show(i);
      renderer.applyCamera(camera);
      const std::string path =
          (fs::path(p.screenshot_dir) / (scene.source.frameName(i) + "." + p.format)).string();
      renderer.writeImage(path, p.format);
      written.push_back(path);
      bar.update(i - range.first + 1);
    }
    bar.finish();
  } catch (...) {
    for (const auto& w : written) fs::remove(w, ec);
    if (created) fs::remove(p.screenshot_dir, ec);
    throw;
  }
  print_info("[%s] wrote %zu %s images to %s\n", kTool, written.size(), p.format.c_str(),
             p.screenshot_dir.c_str());
  return 0;
}

std::string freeScreenshotName(std::size_t frame, const SceneData& scene) {
  const std::string base = "viewer_" + scene.source.frameName(frame);
  std::error_code ec;
  for (int k = 0; k < 10000; ++k) {
    const std::string name = base + (k ? "_" + std::to_string(k) : "") + ".png";
    if (!fs::exists(name, ec)) return name;
  }
  return base + "_last.png";
}

int runInteractive(const SceneData& scene, const ViewerParameters& p, viz::FrameRange range,
                   int width, int height, viz::CameraPreset camera) {
  FrameRenderer renderer(scene, p, false, width, height);
  std::unique_ptr<LiveDetector> live;
  if (p.live) live.reset(new LiveDetector(scene, p, range.first));
  renderer.setLive(live.get());
  std::size_t frame = range.first;
  bool playing = scene.source.isLive(), dirty = true, camera_dirty = true, screenshot = false;
  double speed = 1.0;
  renderer.style()->handler = [&](const std::string& sym, char code) {
    if (sym == "space" || code == ' ') {
      playing = !playing;
      dirty = true;
    } else if (sym == "Right" || code == 'n') {
      playing = false;
      if (frame < range.last && scene.source.held(frame + 1)) ++frame;
      dirty = true;
    } else if (sym == "Left" || code == 'p') {
      playing = false;
      if (frame > range.first && scene.source.held(frame - 1)) --frame;
      dirty = true;
    } else if (sym == "plus" || sym == "KP_Add" || sym == "equal" || code == '+' || code == '=') {
      speed = std::min(speed * 2.0, 16.0);
      dirty = true;
    } else if (sym == "minus" || sym == "KP_Subtract" || code == '-') {
      speed = std::max(speed * 0.5, 1.0 / 16);
      dirty = true;
    } else if (code == '1' || code == '2' || code == '3') {
      camera = static_cast<viz::CameraPreset>(code - '1');
      camera_dirty = dirty = true;
    } else if (sym == "Tab" || code == '\t') {
      renderer.setSelectedTrack(
          viz::nextSelectedTrack(renderer.rows(frame), renderer.selectedTrack()));
      dirty = true;
    } else if (code == 's') {
      screenshot = true;
    } else {
      return false;
    }
    return true;
  };
  auto last_step = std::chrono::steady_clock::now();
  while (!renderer.viewer().wasStopped()) {
    if (dirty) {
      char status[128];
      std::snprintf(status, sizeof(status), "%s  x%g   camera: %s", playing ? "playing" : "paused",
                    speed, viz::cameraPresetName(camera));
      renderer.show(frame, status);
      if (camera_dirty) renderer.applyCamera(camera);
      dirty = camera_dirty = false;
    }
    if (screenshot) {
      screenshot = false;
      const std::string name = freeScreenshotName(frame, scene);
      renderer.writeImage(name, "png");
      print_info("[%s] saved %s\n", kTool, name.c_str());
    }
    renderer.viewer().spinOnce(15, true);
    if (playing && scene.source.isLive()) {  // a sensor: follow its newest sweep
      const std::size_t newest = std::min(range.last, scene.source.size() - 1);
      if (newest != frame) frame = newest, dirty = true;
    } else if (playing) {
      const double dt =
          frame + 1 < scene.source.size()
              ? std::max(1e-3, scene.source.time(frame + 1) - scene.source.time(frame))
              : 1.0 / p.rate;
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_step).count() >= dt / speed) {
        last_step = now;
        frame = frame < range.last ? frame + 1 : range.first;  // loop the range
        dirty = true;
      }
    }
  }
  return 0;
}

/** The frames to show: --frames within the sequence or capture; a live sensor's are waited for
 * (off-screen, up to the last one asked for: --frames A:B is required there). */
viz::FrameRange frameRange(const ViewerParameters& p, const FrameSource& source) {
  if (!source.isLive())
    return p.frames.empty() ? viz::FrameRange{0, source.size() - 1}
                            : viz::parseFrameRange(p.frames, source.size());
  constexpr std::size_t kOpen = std::numeric_limits<std::size_t>::max() / 2;
  const viz::FrameRange range =
      p.frames.empty() ? viz::FrameRange{0, kOpen - 1} : viz::parseFrameRange(p.frames, kOpen);
  const bool offscreen = !p.screenshot_dir.empty();
  if (offscreen && range.last == kOpen - 1)
    throw InputError(
        "--live sensor with --screenshot-dir: give --frames A:B (the sweeps to render)");
  const std::size_t wait = offscreen ? range.last : range.first;
  if (!source.waitFor(wait))
    throw InputError(source.framePath(wait) + ": the sensor stream ended after " +
                     std::to_string(source.size()) + " sweeps");
  return range;
}

int run(int argc, char** argv) {
  if (tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  std::string sequence;
  const ViewerParameters p = parseParameters(argc, argv, sequence);
  const auto size = viz::parseImageSize(p.size);
  const auto camera = viz::parseCameraPreset(p.camera);
  SceneData scene;
  loadScene(sequence, p, scene);
  const viz::FrameRange range = frameRange(p, scene.source);
  // Everything that can be checked without a display is checked first, so a bad input is reported
  // as such on any machine: the first frame must be readable, the output folder usable.
  {
    pcl::PointCloud<pcl::PointXYZI> probe;
    scene.source.read(range.first, probe);
  }
  if (!p.screenshot_dir.empty()) {
    std::error_code ec;
    if (fs::exists(p.screenshot_dir, ec) && !fs::is_directory(p.screenshot_dir, ec))
      throw InputError(p.screenshot_dir, 0, "--screenshot-dir exists and is not a folder");
    if (!p.overwrite && !io::isMissingOrEmptyDirectory(p.screenshot_dir))
      throw InputError(
          p.screenshot_dir, 0,
          "--screenshot-dir exists and is not empty (use --overwrite to write into it)");
  }
  // VTK's X11 window aborts the process without a display; say so instead.
  if (!hasDisplay())
    throw InputError("no X display (DISPLAY is unset): run under xvfb-run for --screenshot-dir");
  if (!p.screenshot_dir.empty())
    return renderScreenshots(scene, p, range, size.first, size.second, camera);
  return runInteractive(scene, p, range, size.first, size.second, camera);
}

}  // namespace
}  // namespace pcl_movers

int main(int argc, char** argv) {
  return pcl_movers::tools::runTool(pcl_movers::kTool,
                                    [&]() { return pcl_movers::run(argc, argv); });
}
