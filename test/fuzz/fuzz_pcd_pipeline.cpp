/*
 * libFuzzer target: PCD bytes → io::readScan → RangeImageOrganizer → GroundPlaneFilter →
 * RangeImageRegionGrowing → BhattacharyaRegistration (largest cluster against a shifted copy of
 * itself). This is the path every tool takes with a user's file, so any crash, leak, UB or hang
 * here is one a user can hit with a bad recording (docs/reliability.md).
 *
 * Contract checked: each stage either succeeds or throws pcl_movers::InputError (a clear message)
 * — any other exception type escapes and libFuzzer reports it as a crash. PCL's own reader prints
 * errors with PCL_ERROR; those are silenced so the fuzzer runs at full speed.
 *
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/bhattacharya_registration.h>
#include <pcl_movers/common.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/range_image_region_growing.h>
#include <pcl_movers/sensor_model.h>

#include <pcl/console/print.h>
#include <pcl/point_types.h>

#include <unistd.h>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

namespace {

// Big clouds only make the run slower, not more interesting: the parsers see every byte anyway,
// and the algorithms are exercised by a few thousand points.
constexpr std::size_t kMaxPoints = 20000;

std::string scratchPath() {
  // One file per process (libFuzzer -jobs/-fork run several); /dev/shm keeps it in memory.
  const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  return std::string(dir) + "/pcl_movers_fuzz_" + std::to_string(getpid()) + ".pcd";
}

void runPipeline(const pcl::PointCloud<pcl::PointXYZ>::Ptr& scan, std::uint8_t knobs) {
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  Cloud::Ptr organized(new Cloud);
  pcl_movers::RangeImageOrganizer<pcl::PointXYZ> organizer;
  organizer.setInputCloud(scan);
  // Both organizer modes: a fixed beam layout, and estimating the layout from the data (the
  // estimator sees the garbage too).
  if (knobs & 1)
    organizer.setEstimateSensorModel(true);
  else
    organizer.setSensorModel((knobs & 2) ? pcl_movers::SensorModel::vlp16()
                                         : pcl_movers::SensorModel::hdl64());
  organizer.organize(*organized);

  Cloud::Ptr objects(new Cloud);
  pcl_movers::GroundPlaneFilter<pcl::PointXYZ> ground;
  ground.setInputCloud(organized);
  ground.setKeepOrganized(true);         // non-ground points, NaN where ground was removed
  ground.setNegative((knobs & 8) != 0);  // sometimes segment the ground points instead
  ground.filter(*objects);

  std::vector<pcl::PointIndices> clusters;
  pcl_movers::RangeImageRegionGrowing<pcl::PointXYZ> segmentation;
  segmentation.setInputCloud(objects);
  segmentation.setMinClusterSize(3);
  segmentation.segment(clusters);
  if (clusters.empty()) return;

  const auto largest = std::max_element(
      clusters.begin(), clusters.end(),
      [](const auto& a, const auto& b) { return a.indices.size() < b.indices.size(); });
  Cloud::Ptr source(new Cloud), target(new Cloud);
  for (const auto i : largest->indices) {
    target->push_back((*objects)[i]);
    auto p = (*objects)[i];
    p.x += 0.4f;
    p.y -= 0.3f;
    source->push_back(p);
  }
  pcl_movers::BhattacharyaRegistration<pcl::PointXYZ, pcl::PointXYZ> registration;
  registration.setInputSource(source);
  registration.setInputTarget(target);
  registration.setYawSamples((knobs & 4) ? 3 : 1);
  Cloud aligned;
  registration.align(aligned);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = scratchPath();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  // The last byte picks pipeline options, so one corpus covers all modes.
  const std::uint8_t knobs = size > 0 ? data[size - 1] : 0;
  pcl::PointCloud<pcl::PointXYZ>::Ptr scan(new pcl::PointCloud<pcl::PointXYZ>);
  try {
    pcl_movers::io::readScan(path, *scan);
  } catch (const pcl_movers::InputError&) {
    return 0;  // rejected with a message: the right outcome for a bad file
  }
  if (scan->size() > kMaxPoints) return 0;
  try {
    runPipeline(scan, knobs);
  } catch (const pcl_movers::InputError&) {
  }
  return 0;
}
