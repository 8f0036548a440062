/*
 * pcl_movers_detect SEQ OUT — the mover-detection pipeline on a sequence folder.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/detector_parameters.h>
#include <pcl_movers/ego_motion_estimator.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/tracks.h>
#include <pcl_movers/mover_detector.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

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

const std::vector<std::string> kFlags{
    "-h", "--help", "--overwrite", "--labelled-clouds", "--estimate-poses", "--print-config"};

std::vector<std::string> optionsWithValue() {
  std::vector<std::string> with_value{"--config", "--rate"};
  for (const auto& key : DetectorParameters().keys()) with_value.push_back("--" + key);
  return with_value;
}

void printHelp(const char* name) {
  const DetectorParameters defaults;
  std::ostringstream os;
  os << "Usage: " << name << " SEQ OUT [options]\n\n"
     << "Detects movers (moving vehicles and people) in the LiDAR sequence folder SEQ "
        "(frames/*.pcd,\n"
     << "*.pcd or velodyne/*.bin; poses.txt or PCD VIEWPOINTs; times.txt) and writes to OUT:\n"
     << "  tracks.csv     one row per tracked object per frame (see DESIGN.md)\n"
     << "  summary.json   per-stage timings, counts and the parameters used\n"
     << "  labelled/      with --labelled-clouds: NNNNNN.pcd, fields x y z label track\n"
     << "                 (label 0 unlabelled, 1 ground, 2 static, 3 mover; track id or -1)\n\n"
     << "Options:\n"
     << "  --config FILE      'key = value' lines with any of the parameters below\n"
     << "  --rate HZ          frame rate when SEQ has no times.txt (default 10)\n"
     << "  --estimate-poses   estimate the sensor poses from the scans even when SEQ has poses\n"
     << "                     (always done when it has none)\n"
     << "  --labelled-clouds  also write OUT/labelled/NNNNNN.pcd\n"
     << "  --overwrite        write into a non-empty OUT\n"
     << "  --print-config     print the parameters as a config file and exit\n"
     << "  -h, --help         this help\n\n"
     << "Parameters (--KEY VALUE or in the config file; defaults shown):\n";
  defaults.forEachParameter([&](const char* key, const auto& value, const char* doc) {
    std::string k = std::string("  --") + key + " " + pcl_movers::detail::formatValue(value);
    if (k.size() < 36) k.resize(36, ' ');
    os << k << " " << doc << "\n";
  });
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

/** Labelled cloud: finite points of the organized scan with their class and track id. */
void writeLabelledCloud(const std::string& path, const Detector::FrameResult& result) {
  const auto& cloud = *result.organized;
  pcl::PCLPointCloud2 out;
  const char* names[5] = {"x", "y", "z", "label", "track"};
  const std::uint8_t types[5] = {pcl::PCLPointField::FLOAT32, pcl::PCLPointField::FLOAT32,
                                 pcl::PCLPointField::FLOAT32, pcl::PCLPointField::UINT32,
                                 pcl::PCLPointField::INT32};
  for (int f = 0; f < 5; ++f) {
    pcl::PCLPointField field;
    field.name = names[f];
    field.offset = 4 * f;
    field.datatype = types[f];
    field.count = 1;
    out.fields.push_back(field);
  }
  out.point_step = 20;
  out.height = 1;
  out.is_dense = true;
  std::size_t count = 0;
  for (const auto& p : cloud.points)
    count += std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  out.data.resize(count * out.point_step);
  std::size_t k = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
    std::uint8_t* d = &out.data[k * out.point_step];
    const float xyz[3] = {p.x, p.y, p.z};
    const std::uint32_t label = result.labels[i];
    const std::int32_t track = result.track_ids[i];
    std::memcpy(d, xyz, 12);
    std::memcpy(d + 12, &label, 4);
    std::memcpy(d + 16, &track, 4);
    ++k;
  }
  out.width = static_cast<std::uint32_t>(count);
  out.row_step = out.point_step * out.width;
  pcl::PCDWriter writer;
  if (writer.writeBinary(path, out) != 0) throw InputError(path, 0, "cannot write labelled cloud");
}

/** Rejects infinite coordinates (NaN marks empty cells and is fine). */
void checkFinite(const pcl::PointCloud<PointT>& cloud, const std::string& path) {
  for (const auto& p : cloud.points)
    if (std::isinf(p.x) || std::isinf(p.y) || std::isinf(p.z))
      throw InputError(path, 0, "scan has infinite coordinates");
}

int run(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  const auto with_value = optionsWithValue();
  pcl_movers::tools::checkArguments(argc, argv, kFlags, with_value);

  DetectorParameters params;
  std::string config;
  if (pcl::console::parse_argument(argc, argv, "--config", config) >= 0) params.readConfig(config);
  for (const auto& key : params.keys()) {
    std::string value;
    if (pcl::console::parse_argument(argc, argv, ("--" + key).c_str(), value) >= 0)
      params.set(key, value, "--" + key);
  }
  params.validate();
  if (pcl::console::find_switch(argc, argv, "--print-config")) {
    std::printf("%s", params.toConfig().c_str());
    return 0;
  }
  double rate = 10.0;
  {
    std::string r;
    if (pcl::console::parse_argument(argc, argv, "--rate", r) >= 0) {
      char* end = nullptr;
      rate = std::strtod(r.c_str(), &end);
      if (end == r.c_str() || *end != '\0' || !(rate > 0) || !std::isfinite(rate))
        throw InputError("--rate: '" + r + "' is not a positive number");
    }
  }

  const auto positional = pcl_movers::tools::positionalArguments(argc, argv, with_value);
  if (positional.size() != 2) {
    printHelp(argv[0]);
    throw InputError("expected 2 arguments SEQ OUT, got " + std::to_string(positional.size()));
  }
  const std::string seq = positional[0], out = positional[1];
  const bool overwrite = pcl::console::find_switch(argc, argv, "--overwrite");
  const bool labelled = pcl::console::find_switch(argc, argv, "--labelled-clouds");
  const bool force_estimate = pcl::console::find_switch(argc, argv, "--estimate-poses");

  if (!fs::is_directory(seq)) throw InputError(seq, 0, "sequence folder does not exist");
  pcl_movers::io::SequenceReader reader(seq, rate);
  if (reader.empty()) throw InputError(seq, 0, "no frames (frames/*.pcd, *.pcd or velodyne/*.bin)");
  if (fs::exists(out) && !fs::is_directory(out))
    throw InputError(out, 0, "output exists and is not a folder");
  if (fs::exists(out) && fs::equivalent(out, seq))
    throw InputError(out, 0, "output folder is the input sequence");

  // Everything this run creates, so that a failure leaves nothing half-written behind.
  const bool out_existed = fs::exists(out);
  pcl_movers::io::prepareOutputDirectory(out, overwrite);
  std::vector<std::string> created;
  bool created_labelled_dir = false;
  const std::string labelled_dir = out + "/labelled";
  auto cleanup = [&]() {
    std::error_code ec;
    for (const auto& f : created) fs::remove(f, ec);
    if (created_labelled_dir) fs::remove(labelled_dir, ec);
    if (!out_existed) fs::remove(out, ec);  // only removes it when empty
  };

  try {
    if (labelled) {
      if (!fs::exists(labelled_dir)) {
        fs::create_directories(labelled_dir);
        created_labelled_dir = true;
      }
    }
    const bool estimate = force_estimate || !reader.hasPoses();
    const std::string pose_source = estimate ? "estimated" : reader.poseSource();
    print_info("Sequence ");
    print_value("%s", seq.c_str());
    print_info(": %zu frames, poses: %s, mode: %s\n", reader.size(), pose_source.c_str(),
               params.mode.c_str());

    Detector detector;
    detector.setParameters(params);
    pcl_movers::EgoMotionEstimator<PointT> ego;

    std::vector<pcl_movers::io::TrackRow> rows;
    std::map<std::string, std::vector<double>> stage_ms;
    std::set<int> track_ids, mover_ids;
    pcl_movers::tools::ProgressBar progress(reader.size());
    pcl::PointCloud<PointT>::Ptr scan(new pcl::PointCloud<PointT>);
    for (std::size_t i = 0; i < reader.size(); ++i) {
      const std::string& path = reader.framePaths()[i];
      reader.read(i, *scan);
      checkFinite(*scan, path);
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      double ego_ms = 0;
      if (estimate) {
        const auto t0 = std::chrono::steady_clock::now();
        pose = ego.estimate(*scan);
        ego_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                     .count();
      } else {
        pose = reader.pose(i);
      }
      // The scan is in the sensor frame; its VIEWPOINT (if any) is the pose, used above.
      scan->sensor_origin_.setZero();
      scan->sensor_orientation_.setIdentity();
      Detector::FrameResult result;
      try {
        detector.process(scan, pose, reader.time(i), static_cast<int>(i), result);
      } catch (const InputError& e) {
        throw InputError(path + ": " + e.what());
      }
      for (const auto& t : detector.getTimings()) stage_ms[t.first].push_back(t.second);
      if (estimate) stage_ms["ego_motion"].push_back(ego_ms);
      for (const auto& r : result.rows) {
        track_ids.insert(r.track_id);
        if (r.mover) mover_ids.insert(r.track_id);
      }
      rows.insert(rows.end(), result.rows.begin(), result.rows.end());
      if (labelled) {
        const std::string lpath = labelled_dir + "/" + reader.frameName(i) + ".pcd";
        if (fs::exists(lpath) && !overwrite) throw InputError(lpath, 0, "exists (use --overwrite)");
        created.push_back(lpath);
        writeLabelledCloud(lpath, result);
      }
      progress.update(i + 1);
    }
    progress.finish();

    // tracks.csv and summary.json go through temporary names: a crash never leaves a truncated
    // file under the real name.
    const std::string tracks_path = out + "/tracks.csv", tmp_tracks = tracks_path + ".tmp";
    created.push_back(tmp_tracks);
    pcl_movers::io::writeTracks(tmp_tracks, rows);
    std::ostringstream js;
    js << "{\n  \"sequence\": \"" << seq << "\",\n  \"frames\": " << reader.size()
       << ",\n  \"pose_source\": \"" << pose_source << "\",\n  \"rows\": " << rows.size()
       << ",\n  \"tracks\": " << track_ids.size() << ",\n  \"movers\": " << mover_ids.size()
       << ",\n  \"timings_ms\": {";
    bool first = true;
    std::vector<std::string> order = Detector::stageNames();
    if (estimate) order.insert(order.begin(), "ego_motion");
    for (const auto& stage : order) {
      const auto it = stage_ms.find(stage);
      if (it == stage_ms.end()) continue;
      double mean = 0;
      for (const double v : it->second) mean += v;
      mean /= std::max<std::size_t>(1, it->second.size());
      char buf[160];
      std::snprintf(buf, sizeof(buf), "%s\n    \"%s\": {\"median\": %.3f, \"mean\": %.3f}",
                    first ? "" : ",", stage.c_str(), median(it->second), mean);
      js << buf;
      first = false;
    }
    js << "\n  },\n  \"parameters\": " << params.toJson() << "\n}\n";
    const std::string summary_path = out + "/summary.json", tmp_summary = summary_path + ".tmp";
    created.push_back(tmp_summary);
    {
      std::ofstream f(tmp_summary);
      f << js.str();
      if (!f) throw InputError(tmp_summary, 0, "cannot write");
    }
    if (fs::exists(tracks_path) && !overwrite) throw InputError(tracks_path, 0, "exists");
    fs::rename(tmp_tracks, tracks_path);
    created.push_back(tracks_path);
    fs::rename(tmp_summary, summary_path);
    created.push_back(summary_path);

    const auto total = stage_ms["total"];
    print_info("Wrote ");
    print_value("%s", tracks_path.c_str());
    print_info(": %zu rows, %zu tracks, %zu movers; median %.1f ms/frame (pipeline, without I/O)\n",
               rows.size(), track_ids.size(), mover_ids.size(), median(total));
  } catch (...) {
    cleanup();
    throw;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return pcl_movers::tools::runTool("pcl_movers_detect", [&]() { return run(argc, argv); });
}
