/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/io/velodyne_capture.h>
#include <pcl_movers/sensor_model.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief Writes organized frames (rows = SensorModel beams, columns = azimuths) as the packet
 * capture a Velodyne sensor would have produced: what VelodyneCapture, PCL's grabbers, VeloView
 * or Wireshark read.
 *
 * Packets follow the sensors' documented data packet format (HDL-32E and VLP-16 user manuals,
 * "Data packet format"; HDL-64E S2 manual): 1206-byte UDP payloads from port 2368 to port 2368,
 * 12 blocks of flag (0xEEFF; 0xDDFF for the HDL-64E's lower lasers 32-63), azimuth [0.01°] and
 * 32 returns of distance [2 mm] and reflectivity, then a time stamp [µs past the hour] and two
 * factory bytes (0x37 "strongest return", 0x21 HDL-32E / 0x22 VLP-16). An HDL-32E block is one
 * firing of its 32 lasers, a VLP-16 block two firings of its 16 lasers (the second azimuth is not
 * sent; readers interpolate it), an HDL-64E packet six firings as upper/lower block pairs. The
 * datagrams go into a libpcap file (PcapWriter).
 *
 * Each frame becomes one turn: its columns are fired in the sensor's order (clockwise, starting
 * at the first column after straight ahead, where sweeps begin), one column per firing, spread
 * evenly over 1 / rotation rate from the frame's time. Row r is fired by the laser whose
 * calibrated elevation is row r's (HDL-32E: PCL's interleaved table, laser 0 at -30.67°, laser 1
 * at -9.33°, ...; VLP-16: -15°, 1°, -13°, ...; HDL-64E: laser id = row, with the calibration XML
 * written by writeVelodyneCalibration). Only each cell's range goes into the packet (its
 * direction is the laser's and the column's, as for a real sensor): rounded to 2 mm; the
 * column azimuth is rounded to 0.01°. Returns beyond 131.07 m (the 16-bit distance) are dropped
 * and counted. Intensities in [0, 1] (the simulator's) are scaled to 0-255; larger values are
 * taken as the sensor's reflectivity byte.
 *
 * The capture is written to a temporary file and moved into place by close() (see PcapWriter).
 */
class VelodyneCaptureWriter {
 public:
  /** \brief Writes `pcap_path` for `model`; frames must have the shape of `sensor`
   * (velodyneSensorModel(model), possibly with other columns). Throws InputError when the
   * sensor's elevations are not the model's calibration (the capture would not decode to the
   * frames) or the file cannot be written. */
  VelodyneCaptureWriter(const std::string& pcap_path, VelodyneModel model,
                        const SensorModel& sensor);
  VelodyneCaptureWriter(const std::string& pcap_path, VelodyneModel model)
      : VelodyneCaptureWriter(pcap_path, model, velodyneSensorModel(model)) {}
  ~VelodyneCaptureWriter();
  VelodyneCaptureWriter(const VelodyneCaptureWriter&) = delete;
  VelodyneCaptureWriter& operator=(const VelodyneCaptureWriter&) = delete;

  /** \brief Turns per second (default 10): a frame's firings span 1 / rate. */
  void setRotationRate(double hz);
  /** \brief Appends a frame taken at `time` [s, ≥ 0, increasing by at least 1 / rate]. */
  void writeFrame(const pcl::PointCloud<pcl::PointXYZI>& frame, double time);
  /** \brief Fills the last packet with empty firings and moves the file into place. */
  void close();

  std::size_t getPacketCount() const;
  /** \brief Returns too far for the 16-bit distance field. */
  std::size_t getDroppedCount() const;
  /** \brief Laser id of each row. */
  const std::vector<int>& getLaserOfRow() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/** \brief Writes a VeloView/PCL calibration XML (`boost_serialization` db.xml layout that
 * `pcl::HDLGrabber` reads) giving laser id r the elevation of row r of `sensor` and no offsets:
 * the calibration of HDL-64E captures written by VelodyneCaptureWriter. Throws InputError. */
void writeVelodyneCalibration(const std::string& xml_path, const SensorModel& sensor);

}  // namespace io
}  // namespace pcl_movers
