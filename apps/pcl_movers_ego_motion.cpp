/*
 * pcl_movers_ego_motion — estimates the sensor poses of a sequence folder from its scans
 * (EgoMotionEstimator) and writes them as poses.txt; with a reference poses file it reports the
 * drift (final translation error, error per metre travelled, yaw error).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/ego_motion_estimator.h>
#include <pcl_movers/io/sequence.h>

#include <pcl/console/parse.h>
#include <pcl/console/print.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "tool_utils.h"

namespace fs = std::filesystem;
using pcl_movers::InputError;

namespace {

struct Options {
  float voxel = 0.5f;
  float min_range = 3.0f;
  float max_range = 60.0f;
  float max_correspondence = 1.5f;
  float trim = 0.8f;
  int iterations = 30;
  int map_size = 8;
  bool planar = false;
  bool vertical_ground = false;
  std::string reference;
  std::string calib;
  bool overwrite = false;
  int max_frames = 0;
};

pcl_movers::tools::OptionTable optionTable() {
  using pcl_movers::tools::str;
  const Options d;
  return pcl_movers::tools::OptionTable(
      {{"--voxel", "M", "voxel grid leaf [m]", str(d.voxel)},
       {"--min-range", "M", "drop nearer points (ego vehicle) [m]", str(d.min_range)},
       {"--max-range", "M", "drop further points [m]", str(d.max_range)},
       {"--max-corr", "M", "correspondence distance of the first iteration [m]",
        str(d.max_correspondence)},
       {"--trim", "F", "fraction of correspondences kept", str(d.trim)},
       {"--iterations", "N", "ICP iterations per frame", std::to_string(d.iterations)},
       {"--map-size", "N", "keyframes in the local map", std::to_string(d.map_size)},
       {"--planar", "", "estimate x, y and yaw only"},
       {"--vertical-ground", "",
        "make near-horizontal map normals exactly vertical, so the ground\nfixes only z, roll "
        "and pitch",
        "off"},
       {"--max-frames", "N", "only the first N frames", "all"},
       {"--reference", "FILE",
        "reference poses (KITTI format) to report the drift against; re-based\nso that its "
        "first pose is the identity"},
       {"--calib", "FILE",
        "the reference is in another frame (KITTI odometry poses of camera 0):\nmap it with this "
        "file's Tr (velodyne->camera):\npose_velo = Tr^-1 * pose_cam * Tr"},
       {"--overwrite", "", "replace OUT_POSES if it exists"}});
}

void printHelp(const char* argv0) {
  std::printf(
      "Usage: %s SEQUENCE OUT_POSES [options]\n"
      "  Estimates the sensor->world pose of every frame of SEQUENCE from the scans themselves\n"
      "  (point-to-plane ICP against a local map of recent keyframes; world = first frame) and\n"
      "  writes them to OUT_POSES in the KITTI poses.txt format. Any poses the sequence has are\n"
      "  ignored (use --reference to compare against them).\n\n"
      "Options (-h, --help: this help):\n%s",
      argv0, optionTable().help().c_str());
}

using pcl_movers::tools::parseNumber;

double positive(const std::string& flag, const std::string& text) {
  const double v = parseNumber(flag, text);
  if (!(v > 0)) throw InputError(flag + ": must be > 0, got '" + text + "'");
  return v;
}

int count(const std::string& flag, const std::string& text) {
  const double v = positive(flag, text);
  if (v != std::floor(v) || v > 1e9)
    throw InputError(flag + ": expected a positive integer, got '" + text + "'");
  return static_cast<int>(v);
}

/** The velodyne->camera transform of a KITTI calib file ("Tr:", "Tr_velo_cam" or
 * "Tr_velo_to_cam", 12 numbers). */
Eigen::Isometry3d readVeloToCam(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open");
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream ss(line);
    std::string key;
    ss >> key;
    if (key != "Tr:" && key != "Tr" && key != "Tr_velo_cam" && key != "Tr_velo_cam:" &&
        key != "Tr_velo_to_cam:" && key != "Tr_velo_to_cam")
      continue;
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    for (int i = 0; i < 12; ++i)
      if (!(ss >> m(i / 4, i % 4)))
        throw InputError(path, line_no, "expected 12 numbers after " + key);
    Eigen::Isometry3d t;
    t.matrix() = m;
    return t;
  }
  throw InputError(path + ": no Tr / Tr_velo_cam line");
}

double yawOf(const Eigen::Matrix3d& r) {
  return std::atan2(r(1, 0), r(0, 0));
}

int run(int argc, char** argv) {
  const auto args = optionTable().parse(argc, argv);
  const auto& positional = args.positional;
  if (positional.size() != 2)
    throw InputError("expected SEQUENCE and OUT_POSES, got " + std::to_string(positional.size()) +
                     " argument(s); see -h");
  Options opt;
  std::string v;
  if (args.get("--voxel", v)) opt.voxel = positive("--voxel", v);
  if (args.get("--min-range", v)) {
    opt.min_range = parseNumber("--min-range", v);
    if (opt.min_range < 0) throw InputError("--min-range: must be >= 0, got '" + v + "'");
  }
  if (args.get("--max-range", v)) opt.max_range = positive("--max-range", v);
  if (opt.max_range <= opt.min_range) throw InputError("--max-range must exceed --min-range");
  if (args.get("--max-corr", v)) opt.max_correspondence = positive("--max-corr", v);
  if (args.get("--trim", v)) {
    opt.trim = positive("--trim", v);
    if (opt.trim > 1) throw InputError("--trim: must be in (0, 1], got '" + v + "'");
  }
  if (args.get("--iterations", v)) opt.iterations = count("--iterations", v);
  if (args.get("--map-size", v)) opt.map_size = count("--map-size", v);
  if (args.get("--max-frames", v)) opt.max_frames = count("--max-frames", v);
  args.get("--reference", opt.reference);
  args.get("--calib", opt.calib);
  opt.planar = args.has("--planar");
  opt.vertical_ground = args.has("--vertical-ground");
  opt.overwrite = args.has("--overwrite");
  if (!opt.calib.empty() && opt.reference.empty())
    throw InputError("--calib only applies to --reference");

  const std::string& out_path = positional[1];
  if (fs::exists(out_path) && !opt.overwrite)
    throw InputError(out_path + ": exists; pass --overwrite to replace it");
  if (fs::is_directory(out_path)) throw InputError(out_path + ": is a folder, expected a file");
  const fs::path parent = fs::path(out_path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent))
    throw InputError(out_path + ": folder " + parent.string() + " does not exist");

  pcl_movers::io::SequenceOptions input;
  input.load_poses = false;  // the poses are estimated here: a bad poses.txt does not matter
  pcl_movers::io::SequenceReader seq(positional[0], input);
  if (seq.empty()) throw InputError(positional[0] + ": no frames found");
  std::size_t n = seq.size();
  if (opt.max_frames > 0) n = std::min<std::size_t>(n, opt.max_frames);

  // Read the reference first so that a bad file fails before minutes of work.
  std::vector<Eigen::Isometry3d> reference;
  if (!opt.reference.empty()) {
    reference = pcl_movers::io::readPoses(opt.reference);
    if (reference.size() < n)
      throw InputError(opt.reference + ": " + std::to_string(reference.size()) + " poses for " +
                       std::to_string(n) + " frames");
    if (!opt.calib.empty()) {
      const Eigen::Isometry3d tr = readVeloToCam(opt.calib);
      for (auto& p : reference) p = tr.inverse() * p * tr;
    }
    const Eigen::Isometry3d first_inv = reference.front().inverse();
    for (auto& p : reference) p = first_inv * p;
  }

  pcl_movers::EgoMotionEstimator<pcl::PointXYZ> estimator;
  estimator.setVoxelSize(opt.voxel);
  estimator.setMinRange(opt.min_range);
  estimator.setMaxRange(opt.max_range);
  estimator.setMaxCorrespondenceDistance(opt.max_correspondence);
  estimator.setTrimRatio(opt.trim);
  estimator.setMaximumIterations(opt.iterations);
  estimator.setLocalMapSize(opt.map_size);
  estimator.setPlanarMotion(opt.planar);
  estimator.setVerticalGroundNormals(opt.vertical_ground);

  std::vector<Eigen::Isometry3d> poses;
  pcl::PointCloud<pcl::PointXYZ> scan;
  pcl_movers::tools::ProgressBar bar(n);
  double total_ms = 0;
  for (std::size_t i = 0; i < n; ++i) {
    seq.read(i, scan);
    std::size_t finite = 0;
    for (const auto& p : scan.points)
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) ++finite;
    if (finite == 0) throw InputError(seq.framePaths()[i] + ": no finite points");
    const auto t0 = std::chrono::steady_clock::now();
    poses.push_back(estimator.estimate(scan));
    total_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    bar.update(i + 1);
  }
  bar.finish();

  const std::string tmp = out_path + ".tmp-pcl_movers_ego_motion";
  try {
    pcl_movers::io::writePoses(tmp, poses);
    fs::rename(tmp, out_path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
  pcl::console::print_info("wrote %zu poses to %s (%.1f ms/frame)\n", poses.size(),
                           out_path.c_str(), total_ms / n);

  std::printf("| metric | value |\n|---|---:|\n");
  std::printf("| frames | %zu |\n| time per frame [ms] | %.1f |\n", n, total_ms / n);
  if (!reference.empty()) {
    double travelled = 0, max_err = 0, rel_sq = 0;
    for (std::size_t i = 1; i < n; ++i) {
      travelled += (reference[i].translation() - reference[i - 1].translation()).norm();
      max_err = std::max(max_err, (poses[i].translation() - reference[i].translation()).norm());
      const Eigen::Isometry3d rel_est = poses[i - 1].inverse() * poses[i];
      const Eigen::Isometry3d rel_ref = reference[i - 1].inverse() * reference[i];
      rel_sq += (rel_est.translation() - rel_ref.translation()).squaredNorm();
    }
    const Eigen::Isometry3d& e = poses[n - 1];
    const Eigen::Isometry3d& r = reference[n - 1];
    const double final_err = (e.translation() - r.translation()).norm();
    const Eigen::Matrix3d dr = r.linear().transpose() * e.linear();
    const double yaw_err = yawOf(dr) * 180.0 / M_PI;
    const double rot_err = Eigen::AngleAxisd(dr).angle() * 180.0 / M_PI;
    std::printf("| distance travelled (reference) [m] | %.2f |\n", travelled);
    std::printf("| final translation error [m] | %.3f |\n", final_err);
    std::printf("| error per metre travelled [%%] | %.2f |\n",
                travelled > 0 ? 100.0 * final_err / travelled : 0.0);
    std::printf("| max translation error [m] | %.3f |\n", max_err);
    std::printf("| RMS frame-to-frame translation error [m] | %.4f |\n",
                n > 1 ? std::sqrt(rel_sq / (n - 1)) : 0.0);
    std::printf("| final yaw error [deg] | %.3f |\n", yaw_err);
    std::printf("| final rotation error [deg] | %.3f |\n", rot_err);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  return pcl_movers::tools::runTool("pcl_movers_ego_motion", [&] { return run(argc, argv); });
}
