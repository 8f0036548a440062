/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/velodyne_writer.h>
#include <pcl_movers/sim/capture.h>

#include <filesystem>

namespace pcl_movers {
namespace sim {

std::string captureCalibrationPath(const std::string& pcap_path) {
  return std::filesystem::path(pcap_path).replace_extension(".xml").string();
}

void writeCapture(const LidarSimulator& simulator, const std::string& pcap_path, bool overwrite,
                  const std::function<void(std::size_t, std::size_t)>& progress) {
  const SensorModel& sensor = simulator.getSensor();
  io::VelodyneModel model;
  try {
    model = io::velodyneModelFromName(sensor.name());
  } catch (const InputError&) {
    throw InputError(pcap_path, 0,
                     "sensor '" + sensor.name() +
                         "' has no Velodyne packet format (a capture needs hdl32, vlp16 or hdl64)");
  }
  std::error_code ec;
  if (std::filesystem::is_directory(pcap_path, ec))
    throw InputError(pcap_path, 0, "is a folder, not a capture file");
  if (std::filesystem::exists(pcap_path, ec) && !overwrite)
    throw InputError(pcap_path, 0, "exists (use --overwrite to replace it)");
  const std::string xml = captureCalibrationPath(pcap_path);
  if (model == io::VelodyneModel::kHdl64 && std::filesystem::exists(xml, ec) && !overwrite)
    throw InputError(xml, 0, "exists (use --overwrite to replace it)");

  io::VelodyneCaptureWriter writer(pcap_path, model, sensor);
  writer.setRotationRate(simulator.getScenario().rate_hz);
  pcl::PointCloud<pcl::PointXYZI> frame;
  std::vector<std::uint32_t> labels;
  std::vector<io::GroundTruthObject> objects;
  Eigen::Isometry3d pose;
  const auto frames = std::size_t(simulator.getFrameCount());
  for (std::size_t f = 0; f < frames; ++f) {
    simulator.simulate(int(f), frame, labels, objects, pose);
    writer.writeFrame(frame, simulator.time(int(f)));
    if (progress) progress(f + 1, frames);
  }
  if (model == io::VelodyneModel::kHdl64) io::writeVelodyneCalibration(xml, sensor);
  writer.close();
}

}  // namespace sim
}  // namespace pcl_movers
