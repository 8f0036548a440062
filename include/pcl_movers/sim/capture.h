/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/sim/lidar_simulator.h>

#include <cstddef>
#include <functional>
#include <string>

namespace pcl_movers {
namespace sim {

/** \brief Where writeCapture puts the calibration XML of an HDL-64E capture: `pcap_path` with its
 * extension replaced by `.xml` ("scene.pcap" → "scene.xml"). */
std::string captureCalibrationPath(const std::string& pcap_path);

/** \brief Simulates every frame of `simulator` and writes them as a Velodyne packet capture
 * (io::VelodyneCaptureWriter: the sensor's documented packet format in a libpcap file), one turn
 * per frame starting at the frame's time, at the scenario's frame rate.
 *
 * The scenario's sensor must be a Velodyne: hdl32, vlp16 or hdl64 (InputError otherwise). For
 * the HDL-64E, whose calibration is not in PCL, the calibration XML of the simulated beams is
 * written beside it (captureCalibrationPath) and must be given to the reader. Frames are the
 * same as writeSequence's (same seed, same bits), so reading the capture back
 * (io::VelodyneCapture) gives the sequence's frames to within the packet format's 2 mm and
 * 0.01°. An existing capture is refused unless `overwrite`; on error nothing is left behind.
 * \param progress called after each frame with (frames done, total); may be empty. */
void writeCapture(const LidarSimulator& simulator, const std::string& pcap_path, bool overwrite,
                  const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace sim
}  // namespace pcl_movers
