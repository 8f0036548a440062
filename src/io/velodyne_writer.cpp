/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/pcap_file.h>
#include <pcl_movers/io/velodyne_writer.h>

#include "velodyne_decoder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

namespace pcl_movers {
namespace io {

namespace {

constexpr std::uint16_t kPort = 2368;
constexpr double kEpoch = 1704067200.0;  // 2024-01-01 00:00:00 UTC, on the hour
constexpr double kDistanceUnit = 0.002;  // m
constexpr std::uint8_t kStrongest = 0x37;

void putLittle16(std::uint8_t* p, std::uint16_t v) {
  p[0] = std::uint8_t(v);
  p[1] = std::uint8_t(v >> 8);
}

/** Laser id of each row: the laser of the default calibration table with the row's elevation. */
std::vector<int> laserOfRow(VelodyneModel model, const SensorModel& sensor) {
  const int lasers = detail::laserCount(model);
  if (sensor.rows() != lasers)
    throw InputError("VelodyneCaptureWriter: " + velodyneModelName(model) + " has " +
                     std::to_string(lasers) + " lasers, the frames' sensor '" + sensor.name() +
                     "' " + std::to_string(sensor.rows()) + " rows");
  std::vector<int> laser_of_row(lasers);
  if (model == VelodyneModel::kHdl64) {  // the calibration XML is written from the sensor
    for (int row = 0; row < lasers; ++row) laser_of_row[row] = row;
    return laser_of_row;
  }
  const detail::VelodyneDecoder decoder(model, "");
  for (int row = 0; row < lasers; ++row) {
    const double elevation = double(sensor.elevations()[row]) * 180.0 / M_PI;
    int best = 0;
    for (int laser = 1; laser < lasers; ++laser)
      if (std::abs(decoder.lasers()[laser].elevation_deg - elevation) <
          std::abs(decoder.lasers()[best].elevation_deg - elevation))
        best = laser;
    if (std::abs(decoder.lasers()[best].elevation_deg - elevation) > 1e-3)
      throw InputError("VelodyneCaptureWriter: row " + std::to_string(row) + " of sensor '" +
                       sensor.name() + "' is at " + std::to_string(elevation) +
                       "°, no laser of PCL's " + velodyneModelName(model) +
                       " table is: the capture would not decode to the frames");
    laser_of_row[row] = best;
  }
  return laser_of_row;
}

}  // namespace

struct VelodyneCaptureWriter::Impl {
  Impl(const std::string& path, VelodyneModel model, const SensorModel& sensor)
      : model_(model), sensor_(sensor), pcap_(path), laser_of_row_(laserOfRow(model, sensor)) {
    firings_per_packet_ = model == VelodyneModel::kVlp16 ? 24 : (model == kHdl64 ? 6 : 12);
  }

  static constexpr VelodyneModel kHdl64 = VelodyneModel::kHdl64;

  /** Velodyne azimuth of column c [0.01°]: φ = -(SensorModel azimuth) in [0, 360). */
  std::uint16_t azimuthOf(int column) const {
    const double phi = (double(column) + 0.5) * 360.0 / double(sensor_.columns()) - 180.0;
    long hundredths = std::lround(phi * 100.0) % 36000;
    if (hundredths < 0) hundredths += 36000;
    return std::uint16_t(hundredths);
  }

  /** Appends one firing; `returns` = (distance, reflectivity) per laser id. */
  void fire(std::uint16_t azimuth, double time,
            const std::vector<std::array<std::uint16_t, 2>>& returns);
  void flush();

  VelodyneModel model_;
  SensorModel sensor_;
  PcapWriter pcap_;
  std::vector<int> laser_of_row_;
  double rate_ = 10.0;
  double last_time_ = -std::numeric_limits<double>::infinity();
  int firings_per_packet_ = 12;
  int filled_ = 0;  ///< firings in the packet being built
  double packet_time_ = 0.0;
  std::array<std::uint8_t, 1206> packet_{};
  double last_fire_time_ = 0.0;
  std::uint16_t last_azimuth_ = 0;
  std::size_t dropped_ = 0;
};

void VelodyneCaptureWriter::Impl::fire(std::uint16_t azimuth, double time,
                                       const std::vector<std::array<std::uint16_t, 2>>& returns) {
  if (filled_ == 0) {
    packet_.fill(0);
    packet_time_ = time;
  }
  auto put = [&](std::uint8_t* block, std::uint16_t flag, int first_slot, int first_laser,
                 int count) {
    putLittle16(block, flag);
    putLittle16(block + 2, azimuth);
    for (int j = 0; j < count; ++j) {
      std::uint8_t* slot = block + 4 + 3 * (first_slot + j);
      putLittle16(slot, returns[first_laser + j][0]);
      slot[2] = std::uint8_t(returns[first_laser + j][1]);
    }
  };
  if (model_ == VelodyneModel::kVlp16) {
    std::uint8_t* block = packet_.data() + 100 * (filled_ / 2);
    if (filled_ % 2 == 0)
      put(block, 0xeeff, 0, 0, 16);
    else  // the second firing: azimuth not sent, the block keeps the first one's
      for (int j = 0; j < 16; ++j) {
        std::uint8_t* slot = block + 4 + 3 * (16 + j);
        putLittle16(slot, returns[j][0]);
        slot[2] = std::uint8_t(returns[j][1]);
      }
  } else if (model_ == VelodyneModel::kHdl64) {
    put(packet_.data() + 100 * (2 * filled_), 0xeeff, 0, 0, 32);
    put(packet_.data() + 100 * (2 * filled_ + 1), 0xddff, 0, 32, 32);
  } else {
    put(packet_.data() + 100 * filled_, 0xeeff, 0, 0, 32);
  }
  last_azimuth_ = azimuth;
  last_fire_time_ = time;
  if (++filled_ == firings_per_packet_) flush();
}

void VelodyneCaptureWriter::Impl::flush() {
  if (filled_ == 0) return;
  const double micro = std::round(packet_time_ * 1e6);
  const auto stamp = std::uint32_t(std::fmod(micro, 3600e6));
  for (int k = 0; k < 4; ++k) packet_[1200 + k] = std::uint8_t(stamp >> (8 * k));
  packet_[1204] = kStrongest;
  packet_[1205] = model_ == VelodyneModel::kVlp16 ? 0x22 : (model_ == kHdl64 ? 0x00 : 0x21);
  pcap_.write(kEpoch + packet_time_, packet_.data(), packet_.size(), kPort, kPort);
  filled_ = 0;
}

VelodyneCaptureWriter::VelodyneCaptureWriter(const std::string& pcap_path, VelodyneModel model,
                                             const SensorModel& sensor)
    : impl_(std::make_unique<Impl>(pcap_path, model, sensor)) {}

VelodyneCaptureWriter::~VelodyneCaptureWriter() = default;

void VelodyneCaptureWriter::setRotationRate(double hz) {
  if (!(hz > 0.1 && hz < 100.0))
    throw InputError("VelodyneCaptureWriter: rotation rate must be in (0.1, 100) Hz, got " +
                     std::to_string(hz));
  impl_->rate_ = hz;
}

void VelodyneCaptureWriter::writeFrame(const pcl::PointCloud<pcl::PointXYZI>& frame, double time) {
  Impl& w = *impl_;
  const int rows = w.sensor_.rows(), columns = w.sensor_.columns();
  if (int(frame.height) != rows || int(frame.width) != columns)
    throw InputError("VelodyneCaptureWriter: frame is " + std::to_string(frame.height) + " x " +
                     std::to_string(frame.width) + ", the sensor " + std::to_string(rows) + " x " +
                     std::to_string(columns));
  const double period = 1.0 / w.rate_;
  if (!(time >= 0.0) || time < w.last_time_ + period * (1.0 - 1e-9))
    throw InputError("VelodyneCaptureWriter: frame time " + std::to_string(time) +
                     " s is negative or less than one turn after the previous frame");
  w.last_time_ = time;
  // Sweeps begin at the first column clockwise from straight ahead (the smallest azimuth).
  int first = 0;
  for (int c = 1; c < columns; ++c)
    if (w.azimuthOf(c) < w.azimuthOf(first)) first = c;
  std::vector<std::array<std::uint16_t, 2>> returns(static_cast<std::size_t>(rows));
  for (int k = 0; k < columns; ++k) {
    const int c = (first + k) % columns;
    for (int row = 0; row < rows; ++row) {
      const pcl::PointXYZI& p = frame.at(c, row);
      auto& out = returns[std::size_t(w.laser_of_row_[row])];
      out = {0, 0};
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
      const double d = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
      const long q = std::lround(d / kDistanceUnit);
      if (q > 65535) {
        ++w.dropped_;
        continue;
      }
      const float i = std::isfinite(p.intensity) ? p.intensity : 0.f;
      const long reflectivity = i <= 1.f ? std::lround(std::max(0.f, i) * 255.f) : std::lround(i);
      out = {std::uint16_t(q), std::uint16_t(std::min(255L, reflectivity))};
    }
    w.fire(w.azimuthOf(c), time + period * double(k) / double(columns), returns);
  }
}

void VelodyneCaptureWriter::close() {
  Impl& w = *impl_;
  if (w.filled_ > 0) {
    // Empty firings at the following azimuths: a reader sees them as the start of a turn that
    // never completes.
    const std::vector<std::array<std::uint16_t, 2>> none(w.laser_of_row_.size(), {0, 0});
    const double step_time = 1.0 / (w.rate_ * w.sensor_.columns());
    const double step = 36000.0 / w.sensor_.columns();
    double azimuth = w.last_azimuth_, time = w.last_fire_time_;
    while (w.filled_ > 0) {
      azimuth = std::fmod(azimuth + step, 36000.0);
      time += step_time;
      w.fire(std::uint16_t(std::lround(azimuth) % 36000), time, none);
    }
  }
  w.pcap_.close();
}

std::size_t VelodyneCaptureWriter::getPacketCount() const {
  return impl_->pcap_.packetCount();
}
std::size_t VelodyneCaptureWriter::getDroppedCount() const {
  return impl_->dropped_;
}
const std::vector<int>& VelodyneCaptureWriter::getLaserOfRow() const {
  return impl_->laser_of_row_;
}

void writeVelodyneCalibration(const std::string& xml_path, const SensorModel& sensor) {
  std::ofstream out(xml_path, std::ios::trunc);
  if (!out) throw InputError(xml_path, 0, "cannot write");
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\" ?>\n"
         "<!DOCTYPE boost_serialization>\n"
         "<boost_serialization signature=\"serialization::archive\" version=\"4\">\n"
         "<!-- written by pcl_movers for sensor '"
      << sensor.name()
      << "': laser id = row, top to bottom; no offsets -->\n"
         "<DB class_id=\"0\" tracking_level=\"0\" version=\"0\">\n"
         "\t<distLSB_>0.2</distLSB_>\n"
         "\t<points_ class_id=\"3\" tracking_level=\"0\" version=\"0\">\n"
         "\t\t<count>"
      << sensor.rows() << "</count>\n\t\t<item_version>1</item_version>\n";
  char elevation[64];
  for (int row = 0; row < sensor.rows(); ++row) {
    std::snprintf(elevation, sizeof(elevation), "%.12f",
                  double(sensor.elevations()[row]) * 180.0 / M_PI);
    out << "\t\t<item class_id=\"4\" tracking_level=\"0\" version=\"1\">\n"
           "\t\t\t<px class_id=\"5\" tracking_level=\"0\" version=\"1\">\n"
           "\t\t\t\t<id_>"
        << row << "</id_>\n\t\t\t\t<rotCorrection_>0</rotCorrection_>\n"
        << "\t\t\t\t<vertCorrection_>" << elevation << "</vertCorrection_>\n"
        << "\t\t\t\t<distCorrection_>0</distCorrection_>\n"
           "\t\t\t\t<vertOffsetCorrection_>0</vertOffsetCorrection_>\n"
           "\t\t\t\t<horizOffsetCorrection_>0</horizOffsetCorrection_>\n"
           "\t\t\t</px>\n\t\t</item>\n";
  }
  out << "\t</points_>\n</DB>\n</boost_serialization>\n";
  if (!out) throw InputError(xml_path, 0, "cannot write");
}

}  // namespace io
}  // namespace pcl_movers
