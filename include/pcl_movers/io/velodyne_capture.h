/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/sensor_model.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief The Velodyne sensors whose packets pcl_movers reads and writes. */
enum class VelodyneModel { kHdl32, kVlp16, kHdl64 };

/** \brief "hdl32", "vlp16", "hdl64" → the model; anything else throws InputError naming it. */
VelodyneModel velodyneModelFromName(const std::string& name);
std::string velodyneModelName(VelodyneModel model);
/** \brief The beam layout of the sweeps of a model: SensorModel::hdl32(), vlp16() or hdl64(). */
SensorModel velodyneSensorModel(VelodyneModel model);

/** \brief One full turn of a Velodyne sensor as an organized range image. */
struct VelodyneSweep {
  /** Rows = lasers sorted by elevation top to bottom, columns = firing azimuths as SensorModel
   * orders them (column c looks at azimuth π - (c + 0.5)·2π/columns in the x-forward, y-left
   * frame); NaN x y z where the laser gave no return (or did not fire into that column).
   * Intensity is the sensor's raw reflectivity byte (0-255), as PCL's grabbers give it.
   * `header.stamp` = start of the sweep [µs past the hour of the first packet, unwrapped]. */
  pcl::PointCloud<pcl::PointXYZI>::Ptr cloud;
  /** Per point of `cloud` (row-major): time of the firing [s] after the sweep's first firing,
   * from the packet time stamps and the sensor's documented firing timing; NaN without return. */
  std::vector<float> time_offsets;
  double start_time = 0.0;     ///< first firing [s past the hour of the first packet, unwrapped]
  double capture_time = 0.0;   ///< capture time of its first packet [s since the epoch, pcap]
  std::size_t packets = 0;     ///< data packets that contributed
  std::size_t firings = 0;     ///< firings (azimuth steps) in the sweep
  std::size_t returns = 0;     ///< points kept in the image
  std::size_t collisions = 0;  ///< returns dropped because a nearer one had their cell
};

/** \brief Reads a Velodyne packet capture (`.pcap`) sweep by sweep into organized clouds.
 *
 * Decoding is PCL's: the packets go through a subclass of `pcl::HDLGrabber` (HDL-32E, HDL-64E) or
 * `pcl::VLPGrabber` (VLP-16) whose packet-to-cloud step (`toPointClouds`, the virtual PCL's own
 * VLPGrabber overrides) keeps what PCL's sweep clouds drop: the laser of each return and the empty
 * returns. Each return is computed by the grabber's own `computeXYZI` with the grabber's own
 * calibration table (PCL's HDL-32E and VLP-16 tables, or the HDL-64E XML given, VeloView/PCL
 * `db.xml` format), with PCL's azimuth interpolation of the VLP-16's second firing of a block.
 * A return whose distance is 0 (the sensor's "no return") is empty even where the calibration's
 * offsets would make PCL place it at the laser's origin.
 *
 * Packet layout: Velodyne HDL-32E and VLP-16 user manuals ("Data packet format"): a 1206-byte UDP
 * payload of 12 blocks (flag 0xEEFF, or 0xDDFF for the HDL-64E's lower lasers; azimuth in
 * 0.01°; 32 returns of 2-byte distance in 2 mm and 1-byte reflectivity), a 4-byte time stamp
 * [µs past the hour] and 2 factory bytes. The VLP-16 fires its 16 lasers twice per block.
 * Every UDP payload of 1206 bytes is a data packet, as for PCL (position packets are 512 bytes).
 *
 * Frame: PCL's grabbers give Velodyne's frame (x right, y forward); sweeps here are in the
 * library's sensor frame (x forward, y left, z up): x = y_velodyne, y = -x_velodyne.
 *
 * Sweeps: a sweep ends where the firing azimuth wraps through 0 (straight ahead), as in PCL and
 * VeloView. Only full turns are delivered: the capture's first sweep is dropped unless it starts
 * within 1° after 0, the last one unless it reaches 359°. A firing goes to the column of its
 * azimuth (minus the laser's azimuth correction); when two firings of a laser fall in one column
 * (a sensor spinning slower than `columns` firings per turn) the nearer return is kept and the
 * other counted as a collision, and a column no firing fell in stays NaN (a faster sensor).
 *
 * Per-point times: time stamp of the packet + the firing's offset within it: HDL-32E 46.08 µs
 * per block and 1.152 µs per laser, VLP-16 110.592 µs per block, 55.296 µs per firing and 2.304
 * µs per laser (the manuals' timing tables); HDL-64E 48 µs per upper/lower block pair (its
 * manual gives no per-laser timing). The time stamp's hour wrap is unwrapped.
 *
 * \code
 * pcl_movers::io::VelodyneCapture capture("drive.pcap", pcl_movers::io::VelodyneModel::kHdl32);
 * pcl_movers::io::VelodyneSweep sweep;
 * while (capture.next(sweep)) use(*sweep.cloud, sweep.time_offsets);  // 32 x 2048, organized
 * \endcode
 */
class VelodyneCapture {
 public:
  /** \brief Opens `pcap_path` for `model`. `calibration` is a VeloView/PCL calibration XML; it is
   * required for the HDL-64E (PCL has no default HDL-64E table), optional for the HDL-32E and
   * refused for the VLP-16 (PCL's VLPGrabber takes none). Throws InputError naming the file. */
  VelodyneCapture(const std::string& pcap_path, VelodyneModel model,
                  const std::string& calibration = "");
  ~VelodyneCapture();
  VelodyneCapture(const VelodyneCapture&) = delete;
  VelodyneCapture& operator=(const VelodyneCapture&) = delete;

  /** \brief Azimuth columns of the sweeps (default: the SensorModel's); call before next(). */
  void setColumns(int columns);
  int getColumns() const;
  /** \brief The beam layout of the sweeps: rows = velodyneSensorModel(model) rows, columns. */
  const SensorModel& getSensorModel() const;

  /** \brief Reads packets up to the end of the next full sweep; false when the capture has none
   * left. Throws InputError on a packet that does not belong to this model.
   * A live capture (listen()) waits for the sweep: false once stop() was called; InputError
   * naming the port when no data packet came for the listen() timeout. */
  bool next(VelodyneSweep& sweep);

  /** \brief A live sensor: PCL's grabber (`pcl::HDLGrabber` / `pcl::VLPGrabber` built with an
   * address and a port, the same toPointClouds override as for files) receives the data packets
   * on UDP `port` on every address, on the grabber's own threads; next() hands out the full
   * sweeps as they complete (the first, partial turn is dropped as for files). Throws InputError
   * naming the port when it is in use, or the calibration as the constructor.
   * \param timeout_seconds next() throws when no data packet came for this long */
  static std::unique_ptr<VelodyneCapture> listen(int port, VelodyneModel model,
                                                 const std::string& calibration = "",
                                                 double timeout_seconds = 5.0);
  /** \brief Live capture: stops the grabber (thread-safe, idempotent); a waiting next() returns
   * false. No effect on a file. */
  void stop();
  /** \brief True for a capture made by listen(). */
  bool isLive() const;

  /** \brief Elevation [deg] of each laser id from the grabber's calibration (not sorted). */
  const std::vector<double>& getLaserElevations() const;
  /** \brief Row of each laser id in the sweeps (lasers sorted by elevation, top to bottom). */
  const std::vector<int>& getRowOfLaser() const;

  /** \brief Velodyne data packets read so far. */
  std::size_t getPacketCount() const;
  /** \brief Partial sweeps dropped so far (at the start or end of the capture). */
  std::size_t getPartialSweepCount() const;
  /** \brief Blocks ignored so far: azimuth above 360.00° (PCL accepts 360.00°), or a lower block in
   * an HDL-32E/VLP-16 packet. */
  std::size_t getBadBlockCount() const;
  /** \brief UDP datagrams that were not Velodyne data packets (position packets, other traffic). */
  std::size_t getOtherDatagramCount() const;
  /** \brief True when the file ended inside a packet record. */
  bool isTruncated() const;

  /** \brief The same sweeps, read by the grabber's own capture thread (`pcl::HDLGrabber::start`
   * with the pcap file: libpcap, replayed at the recorded speed, so it takes as long as the
   * recording). The packets reach the same toPointClouds override; for a check that both paths
   * agree, and the basis of live reading. Throws InputError as the constructor. */
  static std::vector<VelodyneSweep> readWithGrabberThread(const std::string& pcap_path,
                                                          VelodyneModel model,
                                                          const std::string& calibration = "");

 private:
  struct Impl;
  VelodyneCapture() = default;
  bool nextLive(VelodyneSweep& sweep);
  std::unique_ptr<Impl> impl_;
};

/** \brief The sensor of a capture, from its first data packet: lower-block (0xDDFF) blocks →
 * HDL-64E, factory byte 0x22 → VLP-16, 0x21 → HDL-32E (the manuals' "factory bytes"). Throws
 * InputError naming the file when it has no data packet or the packet does not tell. */
VelodyneModel detectVelodyneModel(const std::string& pcap_path);

/** \brief The model a tool's --sensor NAME names for the capture `pcap_path`: "auto" reads it
 * from the capture (detectVelodyneModel()), any other name is velodyneModelFromName(). Throws
 * InputError naming the file or the name. */
VelodyneModel velodyneModelFor(const std::string& name, const std::string& pcap_path);

/** \brief Reads all full sweeps of a capture (VelodyneCapture::next until the end). Throws
 * InputError naming the file when the capture has no Velodyne data packet or no full sweep. */
std::vector<VelodyneSweep> readVelodyneCapture(const std::string& pcap_path, VelodyneModel model,
                                               const std::string& calibration = "");

}  // namespace io
}  // namespace pcl_movers
