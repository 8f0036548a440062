/*
 * RangeImageOrganizer on the real KITTI frames: quality (cells kept, beams not mixed, estimate())
 * and speed against PCL's own pcl::RangeImage::createFromPointCloud.
 *
 *   bench_organizer               Google Benchmark timings on frame 0
 *   bench_organizer --report      one Markdown section over all frames (scripts/bench_organizer.sh)
 *   bench_organizer --speed N     only the side-by-side speed comparison, N times
 *   bench_organizer --digest      hashes of the outputs on all frames (index map, cells, organized
 *                                 cloud bytes, counters; PointXYZI and PointXYZ, scan order and
 *                                 shuffled), to check that an optimization changes no output
 *
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/sensor_model.h>

#include <benchmark/benchmark.h>
#include <pcl/common/angles.h>
#include <pcl/common/io.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/range_image/range_image.h>
#include "bench_common.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZI>;
const std::string kSequence = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a/frames";
constexpr float kMaxRange = 80.f;

std::vector<std::string> framePaths() {
  std::vector<std::string> paths;
  if (!std::filesystem::is_directory(kSequence)) return paths;
  for (const auto& entry : std::filesystem::directory_iterator(kSequence))
    if (entry.path().extension() == ".pcd") paths.push_back(entry.path().string());
  std::sort(paths.begin(), paths.end());
  return paths;
}

Cloud::Ptr load(const std::string& path) {
  Cloud::Ptr cloud(new Cloud);
  if (pcl::io::loadPCDFile(path, *cloud) != 0) cloud->clear();
  return cloud;
}

/** The laser of each point from the recording order, which these KITTI files keep: each beam's
 * turn starts at azimuth 0, wraps at ±180° and ends just below 0. Used only as ground truth. */
std::vector<int> scanOrderBeams(const Cloud& cloud) {
  std::vector<int> beam(cloud.size());
  int current = 0;
  bool wrapped = false;
  float previous = 0.f;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const float azimuth = std::atan2(cloud[i].y, cloud[i].x);
    if (i > 0 && previous - azimuth > 1.f) wrapped = true;
    if (wrapped && previous < 0.f && azimuth >= 0.f) {
      ++current;
      wrapped = false;
    }
    previous = azimuth;
    beam[i] = current;
  }
  return beam;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <typename F>
double millis(F&& f) {
  const double start = pcl_movers_bench::threadCpuMs();
  f();
  return pcl_movers_bench::threadCpuMs() - start;
}

template <typename PointT>
void pclRangeImage(const pcl::PointCloud<PointT>& cloud, int columns, pcl::RangeImage& image) {
  // Same azimuth resolution as the organizer, vertical resolution of the mean beam spacing.
  const float ang_x = float(2 * M_PI) / float(columns);
  const float ang_y = pcl::deg2rad(27.f / 64.f);
  image.createFromPointCloud(cloud, ang_x, ang_y, pcl::deg2rad(360.f), pcl::deg2rad(60.f),
                             Eigen::Affine3f::Identity(), pcl::RangeImage::LASER_FRAME, 0.f, 0.f,
                             0);
}

// ------------------------------------------------------------------ Google Benchmark timings
void BM_Organize(benchmark::State& state) {
  const auto paths = framePaths();
  if (paths.empty()) {
    state.SkipWithError("KITTI data not found under PCL_MOVERS_SHARED_DATA");
    return;
  }
  const auto cloud = load(paths.front());
  pcl_movers::RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(pcl_movers::SensorModel::hdl64());
  organizer.setInputCloud(cloud);
  Cloud out;
  for (auto _ : state) {
    organizer.organize(out);
    benchmark::DoNotOptimize(out.points.data());
  }
  state.counters["points"] = double(cloud->size());
}
BENCHMARK(BM_Organize)->Unit(benchmark::kMillisecond);

void BM_OrganizeEstimated(benchmark::State& state) {
  const auto paths = framePaths();
  if (paths.empty()) {
    state.SkipWithError("KITTI data not found under PCL_MOVERS_SHARED_DATA");
    return;
  }
  const auto cloud = load(paths.front());
  pcl_movers::RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setColumns(2200);
  organizer.setInputCloud(cloud);
  Cloud out;
  for (auto _ : state) {
    organizer.clearSensorModel();
    organizer.organize(out);
    benchmark::DoNotOptimize(out.points.data());
  }
}
BENCHMARK(BM_OrganizeEstimated)->Unit(benchmark::kMillisecond);

void BM_PclRangeImage(benchmark::State& state) {
  const auto paths = framePaths();
  if (paths.empty()) {
    state.SkipWithError("KITTI data not found under PCL_MOVERS_SHARED_DATA");
    return;
  }
  const auto cloud = load(paths.front());
  pcl::RangeImage image;
  for (auto _ : state) {
    pclRangeImage(*cloud, 2200, image);
    benchmark::DoNotOptimize(image.points.data());
  }
}
BENCHMARK(BM_PclRangeImage)->Unit(benchmark::kMillisecond);

// ------------------------------------------------------------------ the Markdown report
struct Quality {
  std::size_t in_range = 0, kept = 0, kept_known = 0, right_beam = 0;
  std::size_t overlapping_rows = 0, row_pairs = 0;
  bool rows_ordered = true;
};

/** Organizes one frame and scores it against the scan-order beams. */
void score(const Cloud& cloud, const std::vector<int>& beams,
           pcl_movers::RangeImageOrganizer<pcl::PointXYZI>& organizer, Quality& q, bool bands) {
  Cloud out;
  organizer.organize(out);
  const auto& cell_of = organizer.getCellOfPoint();
  const int columns = int(out.width), rows = int(out.height);
  const auto& model = organizer.getSensorModel();
  std::vector<float> lo(rows, 1e9f), hi(rows, -1e9f);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const float range = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    if (range > kMaxRange) continue;
    ++q.in_range;
    if (cell_of[i] < 0) continue;
    ++q.kept;
    const int row = cell_of[i] / columns;
    if (beams[i] < 64) {
      ++q.kept_known;
      if (beams[i] == row) ++q.right_beam;
    }
    if (bands) {
      // The elevation of the point seen from its row's laser (origin raised by the beam offset).
      const float rho = std::sqrt(p.x * p.x + p.y * p.y);
      const float elevation = std::atan2(p.z - model.verticalOffsets()[row], rho);
      lo[row] = std::min(lo[row], elevation);
      hi[row] = std::max(hi[row], elevation);
    }
  }
  if (bands)
    for (int r = 0; r + 1 < rows; ++r) {
      if (hi[r + 1] < -1e8f || hi[r] < -1e8f) continue;
      ++q.row_pairs;
      if (hi[r + 1] >= lo[r]) ++q.overlapping_rows;
    }
  for (int r = 0; r + 1 < rows; ++r)
    if (!(model.elevations()[r] > model.elevations()[r + 1])) q.rows_ordered = false;
}

struct Speed {
  double ours, theirs, ours_xyz, theirs_xyz;  ///< median thread CPU time per frame [ms]
};

/** Median over the frames of `RangeImageOrganizer` and of `pcl::RangeImage` (first, second)
 * thread CPU time [ms]: both methods on the same cloud, alternating, one frame after the other,
 * over kPasses passes of all frames; the first warms caches and the allocator, and per frame and
 * method the fastest of the others is kept (as bench_detector does: a short interruption by
 * another process then counts for neither, and both methods get the same treatment). */
template <typename PointT>
std::pair<double, double> medianFastestTimes(
    const std::vector<typename pcl::PointCloud<PointT>::Ptr>& clouds, int width) {
  pcl_movers::RangeImageOrganizer<PointT> organizer;
  organizer.setSensorModel(pcl_movers::SensorModel::hdl64());
  pcl::PointCloud<PointT> out;
  pcl::RangeImage image;
  constexpr int kPasses = 4;
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> ours_ms(clouds.size(), inf), pcl_ms(clouds.size(), inf);
  for (int pass = 0; pass < kPasses; ++pass)
    for (std::size_t f = 0; f < clouds.size(); ++f) {
      organizer.setInputCloud(clouds[f]);
      const double a = millis([&] { organizer.organize(out); });
      const double b = millis([&] { pclRangeImage(*clouds[f], width, image); });
      if (pass > 0) {
        ours_ms[f] = std::min(ours_ms[f], a);
        pcl_ms[f] = std::min(pcl_ms[f], b);
      }
    }
  return {median(ours_ms), median(pcl_ms)};
}

Speed measureSpeed(const std::vector<Cloud::Ptr>& clouds, int width) {
  const auto [ours, theirs] = medianFastestTimes<pcl::PointXYZI>(clouds, width);
  // The same with PointXYZ (16-byte points: half the image to write).
  std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr> xyz;
  for (const auto& c : clouds) {
    xyz.emplace_back(new pcl::PointCloud<pcl::PointXYZ>);
    pcl::copyPointCloud(*c, *xyz.back());
  }
  const auto [ours_xyz, theirs_xyz] = medianFastestTimes<pcl::PointXYZ>(xyz, width);
  return {ours, theirs, ours_xyz, theirs_xyz};
}

/** Only the speed comparison, `repeats` times (quick side-by-side checks while optimizing). */
int speedOnly(int repeats) {
  const auto paths = framePaths();
  if (paths.empty()) {
    std::printf("KITTI data not found (%s)\n", kSequence.c_str());
    return 1;
  }
  std::vector<Cloud::Ptr> clouds;
  for (const auto& path : paths) clouds.push_back(load(path));
  const int width = pcl_movers::SensorModel::hdl64().columns();
  for (int r = 0; r < repeats; ++r) {
    const Speed s = measureSpeed(clouds, width);
    std::printf(
        "PointXYZI: organizer %.2f ms, pcl::RangeImage %.2f ms, %.1fx | PointXYZ: %.2f ms, %.2f "
        "ms, %.1fx\n",
        s.ours, s.theirs, s.theirs / s.ours, s.ours_xyz, s.theirs_xyz, s.theirs_xyz / s.ours_xyz);
    std::fflush(stdout);
  }
  return 0;
}

/** FNV-1a over raw bytes. */
void fnv(std::uint64_t& h, const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 1099511628211ull;
}

template <typename PointT>
std::uint64_t digestOf(const std::vector<typename pcl::PointCloud<PointT>::Ptr>& clouds) {
  std::uint64_t h = 1469598103934665603ull;
  pcl_movers::RangeImageOrganizer<PointT> organizer;
  organizer.setSensorModel(pcl_movers::SensorModel::hdl64());
  pcl::PointCloud<PointT> out;
  for (const auto& cloud : clouds) {
    organizer.setInputCloud(cloud);
    organizer.organize(out);
    fnv(h, organizer.getIndexImage().data(), organizer.getIndexImage().size() * sizeof(int));
    fnv(h, organizer.getCellOfPoint().data(), organizer.getCellOfPoint().size() * sizeof(int));
    fnv(h, out.points.data(), out.points.size() * sizeof(PointT));
    const std::size_t counts[] = {organizer.getDisplacedCount(), organizer.getShiftedCount(),
                                  organizer.getInvalidCount(),   organizer.getOutOfViewCount(),
                                  std::size_t(out.width),        std::size_t(out.height)};
    fnv(h, counts, sizeof(counts));
  }
  return h;
}

/** Output hashes over all frames: equal hashes before and after a change = identical output. */
int digest() {
  const auto paths = framePaths();
  if (paths.empty()) {
    std::printf("KITTI data not found (%s)\n", kSequence.c_str());
    return 1;
  }
  std::vector<Cloud::Ptr> clouds, shuffled;
  std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr> xyz;
  std::mt19937 rng(7);
  for (const auto& path : paths) {
    clouds.push_back(load(path));
    xyz.emplace_back(new pcl::PointCloud<pcl::PointXYZ>);
    pcl::copyPointCloud(*clouds.back(), *xyz.back());
    shuffled.emplace_back(new Cloud(*clouds.back()));
    std::shuffle(shuffled.back()->points.begin(), shuffled.back()->points.end(), rng);
  }
  std::printf("PointXYZI %016llx\n", (unsigned long long)digestOf<pcl::PointXYZI>(clouds));
  std::printf("PointXYZ  %016llx\n", (unsigned long long)digestOf<pcl::PointXYZ>(xyz));
  std::printf("shuffled  %016llx\n", (unsigned long long)digestOf<pcl::PointXYZI>(shuffled));
  return 0;
}

int report() {
  const auto paths = framePaths();
  if (paths.empty()) {
    std::printf("## Range image organizer\n\nKITTI data not found (%s); nothing measured.\n",
                kSequence.c_str());
    return 0;
  }
  std::vector<Cloud::Ptr> clouds;
  std::vector<std::vector<int>> beams;
  for (const auto& path : paths) {
    clouds.push_back(load(path));
    beams.push_back(scanOrderBeams(*clouds.back()));
  }
  const auto hdl64 = pcl_movers::SensorModel::hdl64();

  // Quality at the default width, and the keep fraction over a sweep of widths.
  pcl_movers::RangeImageOrganizer<pcl::PointXYZI> organizer;
  organizer.setSensorModel(hdl64);
  Quality main_quality;
  std::size_t height = 0, width = 0;
  for (std::size_t f = 0; f < clouds.size(); ++f) {
    organizer.setInputCloud(clouds[f]);
    score(*clouds[f], beams[f], organizer, main_quality, true);
  }
  {
    Cloud out;
    organizer.setInputCloud(clouds.front());
    organizer.organize(out);
    height = out.height;
    width = out.width;
  }
  struct Sweep {
    int columns;
    bool neighbour;
    double kept;
  };
  std::vector<Sweep> sweep;
  for (const int columns : {2048, 2100, 2150, 2200, 2250, 4096})
    for (const bool neighbour : {true, false}) {
      if (columns == 4096 && neighbour) continue;
      pcl_movers::RangeImageOrganizer<pcl::PointXYZI> o;
      o.setSensorModel(hdl64);
      o.setColumns(columns);
      o.setUseFreeNeighbour(neighbour);
      Quality q;
      for (std::size_t f = 0; f < clouds.size(); ++f) {
        o.setInputCloud(clouds[f]);
        score(*clouds[f], beams[f], o, q, false);
      }
      sweep.push_back({columns, neighbour, double(q.kept) / double(q.in_range)});
    }

  // estimate() on every frame: beams found and their error against the preset table.
  int frames_64 = 0;
  double worst_error_deg = 0.0;
  std::vector<double> estimate_ms;
  Quality estimated_quality;
  for (std::size_t f = 0; f < clouds.size(); ++f) {
    pcl_movers::SensorModel model;
    estimate_ms.push_back(
        millis([&] { model = pcl_movers::SensorModel::estimate(*clouds[f], 0, 2200); }));
    if (model.rows() == 64) {
      ++frames_64;
      for (int k = 0; k < 64; ++k)
        worst_error_deg = std::max(
            worst_error_deg,
            std::abs(double(model.elevations()[k] - hdl64.elevations()[k])) * 180.0 / M_PI);
    }
    pcl_movers::RangeImageOrganizer<pcl::PointXYZI> o;
    o.setSensorModel(model);
    o.setInputCloud(clouds[f]);
    if (model.rows() == 64) score(*clouds[f], beams[f], o, estimated_quality, false);
  }

  const Speed speed = measureSpeed(clouds, int(width));
  const double ours = speed.ours, theirs = speed.theirs;
  const double ours_xyz = speed.ours_xyz, theirs_xyz = speed.theirs_xyz;

  // estimate() on every frame of the other KITTI sets (odometry and object are raw .bin scans).
  struct SetResult {
    std::string name;
    int frames = 0, frames_64 = 0, min_beams = 1 << 30, max_beams = 0;
    double worst_deg = 0.0;
  };
  std::vector<SetResult> sets;
  for (const auto& [name, folder] : std::vector<std::pair<std::string, std::string>>{
           {"kitti-tracking-0000-a", "kitti-tracking-0000-a/frames"},
           {"kitti-city-22", "kitti-city-22/frames"},
           {"kitti-odometry-00", "kitti-odometry-00/velodyne"},
           {"kitti-object-3", "kitti-object-3/velodyne"}}) {
    const std::string dir = std::string(PCL_MOVERS_SHARED_DATA) + "/" + folder;
    if (!std::filesystem::is_directory(dir)) continue;
    std::vector<std::string> files;
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      if (entry.path().extension() == ".pcd" || entry.path().extension() == ".bin")
        files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
    SetResult r;
    r.name = name;
    for (const auto& file : files) {
      Cloud cloud;
      pcl_movers::io::readScan(file, cloud);
      int beams = 0;
      try {
        const auto model = pcl_movers::SensorModel::estimate(cloud, 0, 2200);
        beams = model.rows();
        if (beams == 64)
          for (int k = 0; k < 64; ++k)
            r.worst_deg = std::max(
                r.worst_deg,
                std::abs(double(model.elevations()[k] - hdl64.elevations()[k])) * 180.0 / M_PI);
      } catch (const pcl_movers::InputError&) {
        beams = 0;
      }
      ++r.frames;
      r.frames_64 += beams == 64;
      r.min_beams = std::min(r.min_beams, beams);
      r.max_beams = std::max(r.max_beams, beams);
    }
    sets.push_back(r);
  }

  std::size_t points = 0;
  for (const auto& c : clouds) points += c->size();
  std::printf("## Range image organizer (`RangeImageOrganizer`, `SensorModel`)\n\n");
  std::printf(
      "All %zu frames of `kitti-tracking-0000-a` (KITTI HDL-64E, %.0f points per frame on "
      "average), preset `hdl64`, points within %.0f m. The beam of each point is known from the "
      "recording order these KITTI files keep (used only to score).\n\n",
      clouds.size(), double(points) / double(clouds.size()), double(kMaxRange));
  std::printf("| measure | value |\n|---|---|\n");
  std::printf("| output size (rows × columns) | %zu × %zu |\n", height, width);
  std::printf("| input points within %.0f m keeping a cell of their own | %.2f %% |\n",
              double(kMaxRange), 100.0 * double(main_quality.kept) / double(main_quality.in_range));
  std::printf("| kept points whose row is their laser (scan order) | %.3f %% |\n",
              100.0 * double(main_quality.right_beam) / double(main_quality.kept_known));
  std::printf("| rows ordered by elevation, top to bottom | %s |\n",
              main_quality.rows_ordered ? "yes" : "NO");
  std::printf(
      "| neighbouring rows whose elevation bands overlap (elevation from the beam's own origin) | "
      "%zu of %zu row pairs (all frames) |\n",
      main_quality.overlapping_rows, main_quality.row_pairs);
  std::printf("| median CPU time per frame, `RangeImageOrganizer` | %.2f ms |\n", ours);
  std::printf(
      "| median CPU time per frame, `pcl::RangeImage::createFromPointCloud` (same cloud, "
      "%.3f° × %.3f°) | %.2f ms |\n",
      360.0 / double(width), 27.0 / 64.0, theirs);
  std::printf("| speed-up | **%.1f×** |\n", theirs / ours);
  std::printf(
      "| the same with `PointXYZ`: `RangeImageOrganizer` / `pcl::RangeImage` / speed-up | %.2f ms "
      "/ "
      "%.2f ms / **%.1f×** |\n\n",
      ours_xyz, theirs_xyz, theirs_xyz / ours_xyz);
  std::printf(
      "Times are thread CPU time, both methods on the same cloud one after the other, per frame "
      "the fastest of three passes over all frames after a warm-up pass (a short interruption by "
      "another process counts for neither method), then the median over the frames; the "
      "organizer is reused from frame to frame as a PCL user would "
      "(its lookups and buffers are kept); both produce their full output (organized cloud plus "
      "index map / `pcl::RangeImage`).\n\n");

  std::printf(
      "Columns per turn vs. points keeping a cell of their own (KITTI fires about every "
      "0.18° with an extra half step every ~7 samples, ~2150 samples per beam per turn; "
      "\"neighbour\" lets a point take a free adjacent column):\n\n");
  std::printf("| columns | neighbour | kept |\n|---|---|---|\n");
  for (const auto& s : sweep)
    std::printf("| %d | %s | %.2f %% |\n", s.columns, s.neighbour ? "yes" : "no", 100.0 * s.kept);
  std::printf(
      "\n`SensorModel::estimate` on each frame (no prior): 64 beams found in %d of %zu "
      "frames; worst beam elevation error against the preset %.3f°; median %.0f ms per "
      "frame; organizing with the estimated model puts %.3f %% of kept points in their "
      "laser's row.\n",
      frames_64, clouds.size(), worst_error_deg, median(estimate_ms),
      estimated_quality.kept_known
          ? 100.0 * double(estimated_quality.right_beam) / double(estimated_quality.kept_known)
          : 0.0);
  std::printf(
      "\n`SensorModel::estimate` (no prior) on every frame of each KITTI set, against the `hdl64` "
      "preset:\n\n| set | frames | frames with 64 beams | beams found (min-max) | worst elevation "
      "error (64-beam frames) |\n|---|---|---|---|---|\n");
  for (const auto& r : sets)
    std::printf("| %s | %d | %d | %d-%d | %.3f° |\n", r.name.c_str(), r.frames, r.frames_64,
                r.min_beams, r.max_beams, r.worst_deg);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--report") == 0) return report();
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--digest") == 0) return digest();
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--speed") == 0) return speedOnly(std::atoi(argv[i + 1]));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
