/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/pcap_file.h>
#include <pcl_movers/io/velodyne_capture.h>

#include "velodyne_decoder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <numeric>

namespace pcl_movers {
namespace io {

VelodyneModel velodyneModelFromName(const std::string& name) {
  if (name == "hdl32") return VelodyneModel::kHdl32;
  if (name == "vlp16") return VelodyneModel::kVlp16;
  if (name == "hdl64") return VelodyneModel::kHdl64;
  throw InputError("unknown Velodyne sensor '" + name + "' (known: hdl32, vlp16, hdl64)");
}

std::string velodyneModelName(VelodyneModel model) {
  switch (model) {
    case VelodyneModel::kVlp16:
      return "vlp16";
    case VelodyneModel::kHdl64:
      return "hdl64";
    default:
      return "hdl32";
  }
}

SensorModel velodyneSensorModel(VelodyneModel model) {
  return SensorModel::fromName(velodyneModelName(model));
}

namespace {

constexpr std::size_t kPacketSize = 1206;
constexpr std::uint16_t kUpperBlock = 0xeeff, kLowerBlock = 0xddff;
constexpr std::uint8_t kVlpDualMode = 0x39, kFactoryHdl32 = 0x21, kFactoryVlp16 = 0x22;
// Firing timing [µs] of the manuals' timing tables (see the header).
constexpr double kHdl32Block = 46.08, kHdl32Laser = 1.152;
constexpr double kVlp16Block = 110.592, kVlp16Firing = 55.296, kVlp16Laser = 2.304;
constexpr double kHdl64BlockPair = 48.0;
constexpr double kHour = 3600e6;  // the time stamp counts µs past the hour

std::uint16_t little16(const std::uint8_t* p) {
  return std::uint16_t(p[0] | (p[1] << 8));
}

std::uint32_t little32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) |
         (std::uint32_t(p[3]) << 24);
}

}  // namespace

/** Decodes packets into organized sweeps; shared by the file path and the grabber's thread. */
struct VelodyneCapture::Impl {
  Impl(VelodyneModel model, const std::string& calibration, const std::string& pcap_path,
       int live_port = -1);

  void setColumns(int columns);
  void addPacket(const std::uint8_t* data, double capture_time);
  void finishSweep(bool at_wrap);
  void checkModel(const std::uint8_t* data) const;

  VelodyneModel model_;
  std::string path_;
  detail::VelodyneDecoder decoder_;
  SensorModel sensor_;
  std::vector<double> elevations_;
  std::vector<int> row_of_laser_;
  std::vector<double> azimuth_correction_;  // per laser [deg]
  std::deque<VelodyneSweep> done_;
  std::size_t packets_ = 0, partial_ = 0, bad_blocks_ = 0, other_ = 0;
  std::unique_ptr<PcapReader> reader_;  ///< the file path; none for the grabber's thread
  UdpDatagram datagram_;
  // Live capture (listen()): packets arrive on the grabber's thread.
  int live_port_ = -1;
  double timeout_seconds_ = 5.0;
  std::mutex mutex_;
  std::condition_variable sweep_done_;
  bool stopped_ = false;
  std::exception_ptr live_error_;  ///< thrown on the grabber's thread, rethrown by next()
  std::chrono::steady_clock::time_point last_packet_;

 private:
  void addHdl(const std::uint8_t* data, double stamp);
  void addVlp16(const std::uint8_t* data, double stamp);
  void beginFiring(std::uint16_t azimuth, double time, bool new_firing = true);
  void addReturn(std::uint16_t azimuth, const std::uint8_t* bytes, int laser, double time);
  int columnOf(std::uint16_t azimuth, int laser) const;
  double unwrapStamp(std::uint32_t stamp);
  void openSweep(std::uint16_t azimuth, double time);

  // Time stamp unwrapping.
  bool have_stamp_ = false;
  double hour_offset_ = 0.0, last_stamp_ = 0.0;
  // The sweep being filled.
  bool have_firing_ = false, open_ = false, started_at_wrap_ = false;
  std::uint16_t last_azimuth_ = 0, first_azimuth_ = 0;
  double packet_capture_time_ = 0.0;
  bool counted_packet_ = false;
  VelodyneSweep sweep_;
  std::vector<float> range_;
};

VelodyneCapture::Impl::Impl(VelodyneModel model, const std::string& calibration,
                            const std::string& pcap_path, int live_port)
    : model_(model),
      path_(pcap_path),
      decoder_(model, calibration, pcap_path, live_port),
      sensor_(velodyneSensorModel(model)) {
  live_port_ = live_port;
  const auto& lasers = decoder_.lasers();
  std::vector<int> order(lasers.size());
  std::iota(order.begin(), order.end(), 0);
  // Top to bottom, as SensorModel orders its rows; ties (none in real tables) by laser id.
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return lasers[a].elevation_deg > lasers[b].elevation_deg; });
  row_of_laser_.assign(lasers.size(), 0);
  for (std::size_t row = 0; row < order.size(); ++row) row_of_laser_[order[row]] = int(row);
  for (const auto& laser : lasers) {
    elevations_.push_back(laser.elevation_deg);
    azimuth_correction_.push_back(laser.azimuth_deg);
  }
}

void VelodyneCapture::Impl::setColumns(int columns) {
  if (columns < 1 || columns > 100000)
    throw InputError("VelodyneCapture: columns must be in 1..100000, got " +
                     std::to_string(columns));
  sensor_.setColumns(columns);
}

double VelodyneCapture::Impl::unwrapStamp(std::uint32_t stamp) {
  double t = double(stamp) + hour_offset_;
  if (have_stamp_ && t < last_stamp_ - 0.5 * kHour) {  // the hour turned
    hour_offset_ += kHour;
    t += kHour;
  }
  have_stamp_ = true;
  last_stamp_ = t;
  return t;
}

int VelodyneCapture::Impl::columnOf(std::uint16_t azimuth, int laser) const {
  // Velodyne azimuth φ (clockwise from ahead) is SensorModel azimuth -φ; column c holds
  // φ + 180° in [c, c + 1) · 360° / columns.
  double turn = (double(azimuth) * 0.01 - azimuth_correction_[laser] + 180.0) / 360.0;
  turn -= std::floor(turn);
  const int columns = sensor_.columns();
  return std::min(int(turn * columns), columns - 1);
}

void VelodyneCapture::Impl::openSweep(std::uint16_t azimuth, double time) {
  const std::size_t cells = std::size_t(sensor_.rows()) * std::size_t(sensor_.columns());
  sweep_ = VelodyneSweep();
  sweep_.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  pcl::PointXYZI empty;
  empty.x = empty.y = empty.z = std::numeric_limits<float>::quiet_NaN();
  empty.intensity = 0.f;
  sweep_.cloud->points.assign(cells, empty);
  sweep_.cloud->width = std::uint32_t(sensor_.columns());
  sweep_.cloud->height = std::uint32_t(sensor_.rows());
  sweep_.cloud->is_dense = false;
  sweep_.time_offsets.assign(cells, std::numeric_limits<float>::quiet_NaN());
  range_.assign(cells, std::numeric_limits<float>::infinity());
  sweep_.start_time = time * 1e-6;
  sweep_.capture_time = packet_capture_time_;
  sweep_.cloud->header.stamp = std::uint64_t(std::max(0.0, time));
  sweep_.packets = 1;
  counted_packet_ = true;
  started_at_wrap_ = have_firing_;
  first_azimuth_ = azimuth;
  open_ = true;
}

void VelodyneCapture::Impl::finishSweep(bool at_wrap) {
  if (!open_) return;
  open_ = false;
  const bool full_start = started_at_wrap_ || first_azimuth_ < 100;
  const bool full_end = at_wrap || last_azimuth_ >= 35900;
  if (!full_start || !full_end) {
    ++partial_;
    return;
  }
  sweep_.returns = 0;
  for (const float r : range_) sweep_.returns += std::isfinite(r);
  done_.push_back(std::move(sweep_));
}

void VelodyneCapture::Impl::beginFiring(std::uint16_t azimuth, double time, bool new_firing) {
  if (have_firing_ && azimuth < last_azimuth_) finishSweep(true);
  if (!open_) openSweep(azimuth, time);
  if (!counted_packet_) {
    ++sweep_.packets;
    counted_packet_ = true;
  }
  have_firing_ = true;
  last_azimuth_ = azimuth;
  sweep_.firings += new_firing;  // an HDL-64E lower block fires with its upper block
}

void VelodyneCapture::Impl::addReturn(std::uint16_t azimuth, const std::uint8_t* bytes, int laser,
                                      double time) {
  const std::uint16_t distance = little16(bytes);
  if (distance == 0) return;  // the sensor's "no return"
  pcl::PointXYZI p;
  decoder_.compute(azimuth, distance, bytes[2], laser, p);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return;
  const float x = p.y, y = -p.x;  // Velodyne (x right, y forward) → x forward, y left
  const float range = std::sqrt(x * x + y * y + p.z * p.z);
  const std::size_t cell = std::size_t(row_of_laser_[laser]) * std::size_t(sensor_.columns()) +
                           std::size_t(columnOf(azimuth, laser));
  if (std::isfinite(range_[cell])) {
    ++sweep_.collisions;
    if (!(range < range_[cell])) return;
  }
  range_[cell] = range;
  pcl::PointXYZI& out = sweep_.cloud->points[cell];
  out.x = x;
  out.y = y;
  out.z = p.z;
  out.intensity = p.intensity;
  sweep_.time_offsets[cell] = float((time - sweep_.start_time * 1e6) * 1e-6);
}

void VelodyneCapture::Impl::addHdl(const std::uint8_t* data, double stamp) {
  for (int b = 0; b < 12; ++b) {
    const std::uint8_t* block = data + 100 * b;
    const std::uint16_t flag = little16(block), azimuth = little16(block + 2);
    const int base = flag == kUpperBlock ? 0 : (flag == kLowerBlock ? 32 : -1);
    if (base < 0 || azimuth > 36000 || (base == 32 && model_ != VelodyneModel::kHdl64)) {
      ++bad_blocks_;
      continue;
    }
    const bool hdl64 = model_ == VelodyneModel::kHdl64;
    const double t = stamp + (hdl64 ? double(b / 2) * kHdl64BlockPair : double(b) * kHdl32Block);
    beginFiring(azimuth, t, base == 0);
    for (int j = 0; j < 32; ++j)
      addReturn(azimuth, block + 4 + 3 * j, base + j, t + (hdl64 ? 0.0 : j * kHdl32Laser));
  }
}

void VelodyneCapture::Impl::addVlp16(const std::uint8_t* data, double stamp) {
  // PCL's VLPGrabber: the second firing of a block is at the block's azimuth plus half the
  // azimuth step between blocks (0 and 1, or 0 and 2 in dual-return mode).
  const bool dual = data[1204] == kVlpDualMode;
  const std::uint16_t a0 = little16(data + 2), a1 = little16(data + 100 * (dual ? 2 : 1) + 2);
  const double delta = (a1 < a0 ? double(a1) + 36000.0 - a0 : double(a1) - a0) / 2.0;
  for (int b = 0; b < 12; b += dual ? 2 : 1) {  // dual mode: PCL's primary return, block b
    const std::uint8_t* block = data + 100 * b;
    const std::uint16_t flag = little16(block), azimuth = little16(block + 2);
    if (flag != kUpperBlock || azimuth > 36000) {
      ++bad_blocks_;
      continue;
    }
    const double block_time = stamp + double(dual ? b / 2 : b) * kVlp16Block;
    for (int firing = 0; firing < 2; ++firing) {
      double a = double(azimuth) + (firing ? delta : 0.0);
      if (a > 36000.0) a -= 36000.0;
      const auto az = std::uint16_t(a);  // PCL passes it to computeXYZI as an integer
      const double t = block_time + firing * kVlp16Firing;
      beginFiring(az, t);
      for (int j = 0; j < 16; ++j)
        addReturn(az, block + 4 + 3 * (16 * firing + j), j, t + j * kVlp16Laser);
    }
  }
}

void VelodyneCapture::Impl::checkModel(const std::uint8_t* data) const {
  const std::uint8_t factory = data[1205];
  if (model_ == VelodyneModel::kVlp16 && factory == kFactoryHdl32)
    throw InputError(path_, 0, "is an HDL-32E capture (factory byte 0x21), not vlp16: use hdl32");
  if (model_ != VelodyneModel::kVlp16 && factory == kFactoryVlp16)
    throw InputError(path_, 0,
                     "is a VLP-16 capture (factory byte 0x22), not " + velodyneModelName(model_) +
                         ": use vlp16");
  if (model_ != VelodyneModel::kHdl64)
    for (int b = 0; b < 12; ++b)
      if (little16(data + 100 * b) == kLowerBlock)
        throw InputError(path_, 0,
                         "has lower-block (0xDDFF) packets: an HDL-64E capture, not " +
                             velodyneModelName(model_) + ": use hdl64 with --calib");
}

void VelodyneCapture::Impl::addPacket(const std::uint8_t* data, double capture_time) {
  if (packets_ == 0) checkModel(data);
  ++packets_;
  packet_capture_time_ = capture_time;
  counted_packet_ = false;
  const double stamp = unwrapStamp(little32(data + 1200));
  if (model_ == VelodyneModel::kVlp16)
    addVlp16(data, stamp);
  else
    addHdl(data, stamp);
}

// ---------------------------------------------------------------- VelodyneCapture

VelodyneCapture::VelodyneCapture(const std::string& pcap_path, VelodyneModel model,
                                 const std::string& calibration) {
  auto reader = std::make_unique<PcapReader>(pcap_path);  // checks the file first
  try {
    impl_ = std::make_unique<Impl>(model, calibration, "");
  } catch (const InputError& e) {
    if (!calibration.empty()) throw;  // the message names the calibration file
    throw InputError(pcap_path, 0, e.what());
  }
  impl_->path_ = pcap_path;
  impl_->reader_ = std::move(reader);
}

VelodyneCapture::~VelodyneCapture() {
  // Before the members the grabber's thread uses go away.
  if (impl_ && impl_->live_port_ >= 0) impl_->decoder_.stopListening();
}

void VelodyneCapture::setColumns(int columns) {
  impl_->setColumns(columns);
}
int VelodyneCapture::getColumns() const {
  return impl_->sensor_.columns();
}
const SensorModel& VelodyneCapture::getSensorModel() const {
  return impl_->sensor_;
}
const std::vector<double>& VelodyneCapture::getLaserElevations() const {
  return impl_->elevations_;
}
const std::vector<int>& VelodyneCapture::getRowOfLaser() const {
  return impl_->row_of_laser_;
}
std::size_t VelodyneCapture::getPacketCount() const {
  return impl_->packets_;
}
std::size_t VelodyneCapture::getPartialSweepCount() const {
  return impl_->partial_;
}
std::size_t VelodyneCapture::getBadBlockCount() const {
  return impl_->bad_blocks_;
}
std::size_t VelodyneCapture::getOtherDatagramCount() const {
  return impl_->other_;
}
bool VelodyneCapture::isTruncated() const {
  return impl_->reader_ && impl_->reader_->isTruncated();
}

bool VelodyneCapture::isLive() const {
  return impl_->live_port_ >= 0;
}

std::unique_ptr<VelodyneCapture> VelodyneCapture::listen(int port, VelodyneModel model,
                                                         const std::string& calibration,
                                                         double timeout_seconds) {
  if (port < 0 || port > 65535)
    throw InputError("--port " + std::to_string(port) + ": not a UDP port (0-65535)");
  std::unique_ptr<VelodyneCapture> capture(new VelodyneCapture());
  capture->impl_ = std::make_unique<Impl>(model, calibration, "", port);
  Impl& impl = *capture->impl_;
  impl.path_ = "UDP port " + std::to_string(port);
  impl.timeout_seconds_ = timeout_seconds;
  impl.last_packet_ = std::chrono::steady_clock::now();
  impl.decoder_.listen([&impl](const std::uint8_t* data) {
    std::lock_guard<std::mutex> lock(impl.mutex_);
    if (impl.live_error_ || impl.stopped_) return;
    impl.last_packet_ = std::chrono::steady_clock::now();
    try {
      const std::size_t before = impl.done_.size();
      impl.addPacket(data, 0.0);
      if (impl.done_.size() > before) impl.sweep_done_.notify_all();
    } catch (...) {  // never through PCL's thread: next() rethrows it
      impl.live_error_ = std::current_exception();
      impl.sweep_done_.notify_all();
    }
  });
  return capture;
}

void VelodyneCapture::stop() {
  if (!isLive()) return;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex_);
    impl_->stopped_ = true;
    impl_->sweep_done_.notify_all();
  }
}

bool VelodyneCapture::nextLive(VelodyneSweep& sweep) {
  Impl& impl = *impl_;
  std::unique_lock<std::mutex> lock(impl.mutex_);
  const auto timeout = std::chrono::duration<double>(impl.timeout_seconds_);
  for (;;) {
    if (impl.live_error_) std::rethrow_exception(impl.live_error_);
    if (impl.stopped_) return false;
    if (!impl.done_.empty()) break;
    const auto deadline = impl.last_packet_ +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(timeout);
    if (std::chrono::steady_clock::now() >= deadline) {
      char seconds[32];
      std::snprintf(seconds, sizeof(seconds), "%g", impl.timeout_seconds_);
      throw InputError(
          impl.path_, 0,
          std::string("no Velodyne data packet for ") + seconds +
              " s (--timeout): is the sensor sending to this port?" +
              (impl.packets_ > 0 ? " (" + std::to_string(impl.packets_) + " packets came before)"
                                 : ""));
    }
    impl.sweep_done_.wait_until(lock, std::min(deadline, std::chrono::steady_clock::now() +
                                                             std::chrono::milliseconds(100)));
  }
  sweep = std::move(impl.done_.front());
  impl.done_.pop_front();
  return true;
}

bool VelodyneCapture::next(VelodyneSweep& sweep) {
  if (isLive()) return nextLive(sweep);
  while (impl_->done_.empty()) {
    if (!impl_->reader_->next(impl_->datagram_)) {
      impl_->finishSweep(false);
      if (impl_->done_.empty()) return false;
      break;
    }
    if (impl_->datagram_.payload.size() != kPacketSize) {
      ++impl_->other_;
      continue;
    }
    impl_->addPacket(impl_->datagram_.payload.data(), impl_->datagram_.time);
  }
  sweep = std::move(impl_->done_.front());
  impl_->done_.pop_front();
  return true;
}

std::vector<VelodyneSweep> VelodyneCapture::readWithGrabberThread(const std::string& pcap_path,
                                                                  VelodyneModel model,
                                                                  const std::string& calibration) {
  // Count the packets PCL's reader will deliver (it enqueues UDP payloads of 1206 bytes), and
  // check the file first: PCL's reader crashes on a file libpcap cannot open.
  std::size_t expected = 0;
  double first = 0.0, last = 0.0;
  {
    PcapReader reader(pcap_path);
    UdpDatagram datagram;
    while (reader.next(datagram)) {
      if (datagram.payload.size() != kPacketSize) continue;
      if (expected++ == 0) first = datagram.time;
      last = datagram.time;
    }
  }
  Impl impl(model, calibration, pcap_path);
  impl.path_ = pcap_path;
  std::mutex mutex;
  impl.decoder_.replay(
      [&](const std::uint8_t* data) {
        std::lock_guard<std::mutex> lock(mutex);
        impl.addPacket(data, 0.0);
      },
      expected, (last - first) * 1.5 + 5.0);
  std::lock_guard<std::mutex> lock(mutex);
  impl.finishSweep(false);
  return std::vector<VelodyneSweep>(std::make_move_iterator(impl.done_.begin()),
                                    std::make_move_iterator(impl.done_.end()));
}

VelodyneModel velodyneModelFor(const std::string& name, const std::string& pcap_path) {
  return name == "auto" ? detectVelodyneModel(pcap_path) : velodyneModelFromName(name);
}

VelodyneModel detectVelodyneModel(const std::string& pcap_path) {
  PcapReader reader(pcap_path);
  UdpDatagram datagram;
  while (reader.next(datagram)) {
    if (datagram.payload.size() != kPacketSize) continue;
    const std::uint8_t* data = datagram.payload.data();
    for (int b = 0; b < 12; ++b)
      if (little16(data + 100 * b) == kLowerBlock) return VelodyneModel::kHdl64;
    if (data[1205] == kFactoryVlp16) return VelodyneModel::kVlp16;
    if (data[1205] == kFactoryHdl32) return VelodyneModel::kHdl32;
    char hex[8];
    std::snprintf(hex, sizeof(hex), "0x%02x", unsigned(data[1205]));
    throw InputError(pcap_path, 0,
                     std::string("cannot tell the sensor from the factory byte ") + hex +
                         ": give it (hdl32, vlp16, hdl64)");
  }
  throw InputError(pcap_path, 0, "no Velodyne data packets (UDP payloads of 1206 bytes)");
}

std::vector<VelodyneSweep> readVelodyneCapture(const std::string& pcap_path, VelodyneModel model,
                                               const std::string& calibration) {
  VelodyneCapture capture(pcap_path, model, calibration);
  std::vector<VelodyneSweep> sweeps;
  VelodyneSweep sweep;
  while (capture.next(sweep)) sweeps.push_back(std::move(sweep));
  if (capture.getPacketCount() == 0)
    throw InputError(pcap_path, 0,
                     "no Velodyne data packets (UDP payloads of 1206 bytes) in " +
                         std::to_string(capture.getOtherDatagramCount()) + " UDP datagrams");
  if (sweeps.empty())
    throw InputError(pcap_path, 0,
                     "no full sweep in " + std::to_string(capture.getPacketCount()) +
                         " data packets (a sweep is one turn between two azimuth wraps)");
  return sweeps;
}

}  // namespace io
}  // namespace pcl_movers
