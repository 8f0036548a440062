/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include "velodyne_decoder.h"

#include <pcl_movers/common.h>

#include <pcl/io/hdl_grabber.h>
#include <pcl/io/vlp_grabber.h>

#include <boost/property_tree/ptree.hpp>
#include <boost/property_tree/xml_parser.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <set>
#include <thread>

namespace pcl_movers {
namespace io {
namespace detail {

int laserCount(VelodyneModel model) {
  switch (model) {
    case VelodyneModel::kVlp16:
      return 16;
    case VelodyneModel::kHdl64:
      return 64;
    default:
      return 32;
  }
}

namespace {

std::set<int> calibrationIds(const boost::property_tree::ptree& points, const std::string& path) {
  std::set<int> ids;
  for (const auto& item : points) {
    if (item.first != "item") continue;
    for (const auto& px : item.second) {
      if (px.first != "px") continue;
      const auto id = px.second.get_optional<int>("id_");
      const auto vertical = px.second.get_optional<double>("vertCorrection_");
      if (!id) throw InputError(path, 0, "calibration entry without a numeric id_");
      if (*id < 0 || *id > 63)
        throw InputError(path, 0, "laser id_ " + std::to_string(*id) + " outside 0..63");
      if (!vertical || !std::isfinite(*vertical) || std::abs(*vertical) >= 90.0)
        throw InputError(
            path, 0, "laser " + std::to_string(*id) + ": vertCorrection_ missing or not in ±90°");
      ids.insert(*id);
    }
  }
  return ids;
}

}  // namespace

void checkCalibrationFile(const std::string& path, int lasers) {
  boost::property_tree::ptree tree;
  try {
    boost::property_tree::read_xml(path, tree);
  } catch (const std::exception& e) {
    throw InputError(path, 0, std::string("not a readable calibration XML (") + e.what() + ")");
  }
  const auto points = tree.get_child_optional("boost_serialization.DB.points_");
  if (!points)
    throw InputError(path, 0,
                     "not a VeloView/PCL calibration (no boost_serialization/DB/points_ element)");
  const std::set<int> ids = calibrationIds(*points, path);
  for (int id = 0; id < lasers; ++id)
    if (!ids.count(id))
      throw InputError(path, 0,
                       "no calibration for laser " + std::to_string(id) + " (the sensor has " +
                           std::to_string(lasers) + ")");
}

/** The interface the capture code uses; implemented by the grabber subclass below. */
class VelodyneDecoder::Access {
 public:
  virtual ~Access() = default;
  virtual void compute(std::uint16_t azimuth, std::uint16_t distance, std::uint8_t intensity,
                       int laser, pcl::PointXYZI& point) const = 0;
  virtual LaserCorrection correction(int laser) const = 0;
  virtual void setSink(std::function<void(const std::uint8_t*)> sink) = 0;
  virtual pcl::Grabber& grabber() = 0;
};

namespace {

/** PCL's grabber with its packet-to-cloud step replaced (PCL's VLPGrabber does the same): the
 * packet goes to a sink instead of PCL's sweep clouds, which drop the laser and empty returns. */
template <typename GrabberT>
class DecodingGrabber : public GrabberT, public VelodyneDecoder::Access {
 public:
  template <typename... Args>
  explicit DecodingGrabber(Args&&... args) : GrabberT(std::forward<Args>(args)...) {}
  ~DecodingGrabber() noexcept override { this->stop(); }

  void compute(std::uint16_t azimuth, std::uint16_t distance, std::uint8_t intensity, int laser,
               pcl::PointXYZI& point) const override {
    typename GrabberT::HDLLaserReturn laser_return;
    laser_return.distance = distance;
    laser_return.intensity = intensity;
    this->computeXYZI(point, azimuth, laser_return, this->laser_corrections_[laser]);
  }

  LaserCorrection correction(int laser) const override {
    const auto& c = this->laser_corrections_[laser];
    LaserCorrection out;
    out.elevation_deg = c.verticalCorrection;
    out.azimuth_deg = c.azimuthCorrection;
    out.distance = c.distanceCorrection;
    out.vertical_offset = c.verticalOffsetCorrection;
    out.horizontal_offset = c.horizontalOffsetCorrection;
    return out;
  }

  void setSink(std::function<void(const std::uint8_t*)> sink) override { sink_ = std::move(sink); }
  pcl::Grabber& grabber() override { return *this; }

 private:
  void toPointClouds(typename GrabberT::HDLDataPacket* packet) override {
    if (sink_) sink_(reinterpret_cast<const std::uint8_t*>(packet));
  }

  std::function<void(const std::uint8_t*)> sink_;
};

}  // namespace

VelodyneDecoder::VelodyneDecoder(VelodyneModel model, const std::string& calibration,
                                 const std::string& pcap_path, int live_port)
    : model_(model), live_port_(live_port) {
  if (live_port > 65535)
    throw InputError("--port " + std::to_string(live_port) + ": not a UDP port (0-65535)");
  if (!calibration.empty()) {
    if (model == VelodyneModel::kVlp16)
      throw InputError(calibration, 0,
                       "--calib is for the HDL-32E/HDL-64E: PCL's VLPGrabber decodes the "
                       "VLP-16 with its fixed table");
    checkCalibrationFile(calibration, laserCount(model));
  } else if (model == VelodyneModel::kHdl64) {
    throw InputError(
        "hdl64: a calibration XML is required (--calib; VeloView/PCL db.xml format): PCL "
        "has no default HDL-64E table and decodes lasers 32-63 at elevation 0 without one");
  }
  const auto any = boost::asio::ip::address(boost::asio::ip::address_v4::any());
  const auto port = static_cast<std::uint16_t>(std::max(live_port, 0));
  if (model == VelodyneModel::kVlp16 && live_port >= 0)
    grabber_ = std::make_unique<DecodingGrabber<pcl::VLPGrabber>>(any, port);
  else if (model == VelodyneModel::kVlp16)
    grabber_ = std::make_unique<DecodingGrabber<pcl::VLPGrabber>>(pcap_path);
  else if (live_port >= 0)
    grabber_ = std::make_unique<DecodingGrabber<pcl::HDLGrabber>>(any, port, calibration);
  else
    grabber_ = std::make_unique<DecodingGrabber<pcl::HDLGrabber>>(calibration, pcap_path);
  for (int laser = 0; laser < laserCount(model); ++laser)
    lasers_.push_back(grabber_->correction(laser));
}

VelodyneDecoder::~VelodyneDecoder() {
  stopListening();
}

void VelodyneDecoder::compute(std::uint16_t azimuth, std::uint16_t distance, std::uint8_t intensity,
                              int laser, pcl::PointXYZI& point) const {
  grabber_->compute(azimuth, distance, intensity, laser, point);
}

std::size_t VelodyneDecoder::replay(const std::function<void(const std::uint8_t*)>& sink,
                                    std::size_t expected_packets, double timeout_seconds) {
  std::atomic<std::size_t> packets{0};
  grabber_->setSink([&](const std::uint8_t* data) {
    sink(data);
    ++packets;
  });
  pcl::Grabber& grabber = grabber_->grabber();
  const auto start = std::chrono::steady_clock::now();
  grabber.start();
  while (packets < expected_packets &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() <
             timeout_seconds)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  grabber.stop();  // joins the grabber's threads: no sink call after this
  grabber_->setSink({});
  return packets;
}

namespace {

/** Fails with a clear message when UDP `port` cannot be bound on every address (PCL's grabber
 * only prints an error and does not start). */
void checkPortFree(int port) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) throw InputError(std::string("cannot open a UDP socket: ") + std::strerror(errno));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_ANY);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  const int ok = ::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address));
  const int error = errno;
  ::close(fd);
  if (ok != 0)
    throw InputError("--port " + std::to_string(port) + ": cannot listen on UDP port " +
                     std::to_string(port) + " (" + std::strerror(error) +
                     (error == EADDRINUSE ? ": another program receives on it" : "") + ")");
}

/** A 1-byte UDP datagram to 127.0.0.1:port (wakes a socket blocked in receive). */
void sendWakeUp(int fd, int port) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  const char byte = 0;
  ::sendto(fd, &byte, 1, 0, reinterpret_cast<const sockaddr*>(&address), sizeof(address));
}

}  // namespace

void VelodyneDecoder::listen(const std::function<void(const std::uint8_t*)>& sink) {
  if (live_port_ < 0) throw InputError("VelodyneDecoder::listen: built for a capture file");
  if (listening_) return;
  checkPortFree(live_port_);
  grabber_->setSink(sink);
  grabber_->grabber().start();
  if (!grabber_->grabber().isRunning()) {
    grabber_->setSink({});
    throw InputError("--port " + std::to_string(live_port_) +
                     ": PCL's grabber could not bind "
                     "UDP port " +
                     std::to_string(live_port_));
  }
  listening_ = true;
}

void VelodyneDecoder::stopListening() {
  if (!listening_) return;
  std::atomic<bool> stopped{false};
  std::thread waker([&] {
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    while (!stopped) {
      if (fd >= 0) sendWakeUp(fd, live_port_);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (fd >= 0) ::close(fd);
  });
  grabber_->grabber().stop();
  stopped = true;
  waker.join();
  grabber_->setSink({});
  listening_ = false;
}

}  // namespace detail
}  // namespace io
}  // namespace pcl_movers
