/*
 * Private to the library: PCL's Velodyne grabbers with their packet-to-cloud step exposed.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/io/velodyne_capture.h>

#include <pcl/point_types.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace pcl_movers {
namespace io {
namespace detail {

/** One laser's calibration as the grabber holds it (degrees, metres). */
struct LaserCorrection {
  double elevation_deg = 0.0;
  double azimuth_deg = 0.0;  ///< rotCorrection_: the laser looks at azimuth - this
  double distance = 0.0;
  double vertical_offset = 0.0;
  double horizontal_offset = 0.0;
};

/** Lasers of a model: 32, 16 or 64. */
int laserCount(VelodyneModel model);

/** Checks a VeloView/PCL calibration XML before PCL reads it (PCL's reader writes past its table
 * on an id above 63, leaves missing lasers uninitialized and crashes on a file without points_):
 * readable XML, boost_serialization.DB.points_ with one px per laser id 0..lasers-1, finite
 * vertical angles within ±90°. Throws InputError naming the file. */
void checkCalibrationFile(const std::string& path, int lasers);

/** A pcl::HDLGrabber (HDL-32E, HDL-64E) or pcl::VLPGrabber (VLP-16) whose toPointClouds override
 * hands each 1206-byte data packet to a sink, and whose computeXYZI and calibration table are
 * used directly. */
class VelodyneDecoder {
 public:
  /** \param calibration XML ("" = the grabber's default table), checked first
   * \param pcap_path capture for replay() ("" = decoding only)
   * \param live_port UDP port for listen() (-1: none; the grabber is built for a file) */
  VelodyneDecoder(VelodyneModel model, const std::string& calibration,
                  const std::string& pcap_path = "", int live_port = -1);
  ~VelodyneDecoder();

  VelodyneModel model() const { return model_; }
  const std::vector<LaserCorrection>& lasers() const { return lasers_; }

  /** PCL's HDLGrabber::computeXYZI of one return (Velodyne frame: x right, y forward), NaN x
   * when PCL drops it. `azimuth` in 0.01°, ≤ 36000 (the size of PCL's lookup table). */
  void compute(std::uint16_t azimuth, std::uint16_t distance, std::uint8_t intensity, int laser,
               pcl::PointXYZI& point) const;

  /** Runs the grabber's own pcap thread (grabber start(), paced as recorded); `sink` is called on
   * the grabber's thread with each data packet. PCL 1.13's isRunning() stays true until stop(),
   * so this stops after `expected_packets` packets or `timeout_seconds`. Returns the packets. */
  std::size_t replay(const std::function<void(const std::uint8_t*)>& sink,
                     std::size_t expected_packets, double timeout_seconds);

  /** Starts the grabber's UDP thread (PCL's HDLGrabber/VLPGrabber(address, port), listening on
   * every address): `sink` is called on the grabber's thread with each data packet. Throws
   * InputError naming the port when it is in use or cannot be bound. */
  void listen(const std::function<void(const std::uint8_t*)>& sink);
  /** Stops listen(): joins the grabber's threads (no sink call after this). PCL's socket thread
   * blocks in receive_from until a datagram comes, so 1-byte datagrams (ignored: not 1206 bytes)
   * are sent to 127.0.0.1:port until it has stopped. Idempotent. */
  void stopListening();

  class Access;  ///< the grabber subclass's interface

 private:
  VelodyneModel model_;
  int live_port_ = -1;
  bool listening_ = false;
  std::unique_ptr<Access> grabber_;
  std::vector<LaserCorrection> lasers_;
};

}  // namespace detail
}  // namespace io
}  // namespace pcl_movers
