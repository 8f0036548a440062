/*
 * Velodyne packet captures: reading the real HDL-32E capture into organized sweeps through PCL's
 * grabbers, and the simulator's captures read back to the simulated frames.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/pcap_file.h>
#include <pcl_movers/io/velodyne_capture.h>
#include <pcl_movers/io/velodyne_writer.h>
#include <pcl_movers/sensor_model.h>
#include <pcl_movers/sim/capture.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <pcl/ModelCoefficients.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using pcl_movers::InputError;
using pcl_movers::SensorModel;
using pcl_movers::io::VelodyneCapture;
using pcl_movers::io::VelodyneModel;
using pcl_movers::io::VelodyneSweep;

namespace {

const std::string kMonterey = std::string(PCL_MOVERS_SHARED_DATA) +
                              "/velodyne-hdl32-monterey/monterey-first-100-packets.pcap";

#define SKIP_WITHOUT_MONTEREY() \
  if (!fs::exists(kMonterey))   \
  GTEST_SKIP() << kMonterey << " is absent (the real HDL-32E capture, ../shared/data)"

fs::path tempDir() {
  return fs::temp_directory_path() / ("pcl_movers_velodyne_" + std::to_string(::getpid()));
}

std::string tempPath(const std::string& name) {
  fs::create_directories(tempDir());
  return (tempDir() / name).string();
}

/** Removes this process's captures at the end. */
class TempCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(tempDir(), ec);
  }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new TempCleanup);

/** Height of the sensor above the ground: a RANSAC plane through the returns of the lowest
 * `beams` rows within 25 m, distance of the sensor origin to it. */
double groundHeight(const pcl::PointCloud<pcl::PointXYZI>& image, int beams, double* tilt_deg) {
  pcl::PointCloud<pcl::PointXYZI>::Ptr low(new pcl::PointCloud<pcl::PointXYZI>);
  for (int r = int(image.height) - beams; r < int(image.height); ++r)
    for (std::uint32_t c = 0; c < image.width; ++c) {
      const auto& p = image.at(c, r);
      if (std::isfinite(p.x) && std::hypot(p.x, p.y) < 25.f) low->push_back(p);
    }
  pcl::SACSegmentation<pcl::PointXYZI> seg;
  seg.setModelType(pcl::SACMODEL_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setDistanceThreshold(0.1);
  seg.setMaxIterations(500);
  seg.setInputCloud(low);
  pcl::PointIndices inliers;
  pcl::ModelCoefficients plane;
  seg.segment(inliers, plane);
  if (plane.values.size() != 4) return std::nan("");
  const double n = std::sqrt(plane.values[0] * plane.values[0] + plane.values[1] * plane.values[1] +
                             plane.values[2] * plane.values[2]);
  if (tilt_deg) *tilt_deg = std::acos(std::abs(plane.values[2]) / n) * 180.0 / M_PI;
  return std::abs(plane.values[3]) / n;
}

}  // namespace

TEST(VelodyneCapture, RealHdl32Capture) {
  SKIP_WITHOUT_MONTEREY();
  VelodyneCapture capture(kMonterey, VelodyneModel::kHdl32);
  std::vector<VelodyneSweep> sweeps;
  VelodyneSweep sweep;
  while (capture.next(sweep)) sweeps.push_back(std::move(sweep));
  std::printf("monterey: %zu packets, %zu full sweeps, %zu partial dropped, %zu other datagrams\n",
              capture.getPacketCount(), sweeps.size(), capture.getPartialSweepCount(),
              capture.getOtherDatagramCount());
  EXPECT_EQ(capture.getPacketCount(), 2702u);
  EXPECT_EQ(capture.getOtherDatagramCount(), 299u);  // the 512-byte position packets
  EXPECT_EQ(capture.getPartialSweepCount(), 2u);     // the first and the last turn
  EXPECT_EQ(capture.getBadBlockCount(), 0u);         // one block is at 360.00°: valid, as for PCL
  ASSERT_GE(sweeps.size(), 16u);
  ASSERT_LE(sweeps.size(), 18u);
  std::vector<double> heights;
  for (std::size_t k = 0; k < sweeps.size(); ++k) {
    const VelodyneSweep& s = sweeps[k];
    ASSERT_EQ(s.cloud->height, 32u);
    ASSERT_EQ(s.cloud->width, 2048u);
    std::size_t finite = 0;
    float max_offset = 0.f;
    for (std::size_t i = 0; i < s.cloud->size(); ++i) {
      const bool valid = std::isfinite((*s.cloud)[i].x);
      finite += valid;
      EXPECT_EQ(valid, std::isfinite(s.time_offsets[i]));
      if (valid) max_offset = std::max(max_offset, s.time_offsets[i]);
    }
    EXPECT_EQ(finite, s.returns);
    double tilt = 0.0;
    const double h = groundHeight(*s.cloud, 8, &tilt);
    heights.push_back(h);
    std::printf(
        "sweep %2zu: %5zu firings %5zu returns %3zu collisions, %.4f s, ground %.3f m "
        "(tilt %.2f deg)\n",
        k, s.firings, s.returns, s.collisions, double(max_offset), h, tilt);
    EXPECT_GT(s.returns, 45000u);
    EXPECT_LT(s.returns, 55000u);
    EXPECT_GT(max_offset, 0.07f);  // one turn at ~11.8 Hz is 85 ms
    EXPECT_LT(max_offset, 0.1f);
    // PCL's own sweeps of this capture put the road 2.20-2.24 m below the sensor too (see
    // docs/velodyne.md), not the 1.76 m the data's README states.
    EXPECT_GT(h, 2.1);
    EXPECT_LT(h, 2.35);
    EXPECT_LT(tilt, 3.0);
  }
  const auto [lo, hi] = std::minmax_element(heights.begin(), heights.end());
  EXPECT_LT(*hi - *lo, 0.05) << "the ground moved between sweeps";
  // pcl::HDLGrabber's own sweep clouds of these turns (its signal, no override) have these
  // points: the same returns, less the ones that met another in a cell. In sweep 4 a firing at
  // 360.00° (PCL keeps it in the turn it ends) shares its column with the turn's first firing.
  const std::size_t pcl_points[] = {49426, 49485, 49543, 49523, 49615, 49667, 49673};
  for (std::size_t k = 0; k < 7; ++k)
    EXPECT_EQ(sweeps[k].returns + sweeps[k].collisions, pcl_points[k]) << "sweep " << k;
  EXPECT_EQ(sweeps[4].collisions, 14u);
}

// ------------------------------------------------------------------ simulated captures

namespace {

pcl_movers::sim::Scenario shortScene(const std::string& sensor, int frames) {
  const std::string text =
      "name: capture\nseed: 5\nframes: " + std::to_string(frames) +
      "\nrate_hz: 10\n"
      "sensor: {preset: " +
      sensor +
      ", height: 1.8, max_range: 90, min_range: 1.5}\n"
      "terrain: {type: plane, height: 0}\n"
      "ego: {start: [0, 0], heading: 0, speed: 6}\n"
      "movers:\n  - {type: car, start: [14, 3], heading: 180, speed: 9}\n"
      "  - {type: person, start: [9, -5], heading: 90, speed: 1.4}\n"
      "statics:\n  - {type: tree, position: [8, 8], height: 6, radius: 2}\n"
      "  - {type: building, position: [30, -20], yaw: 30, size: [20, 10, 8]}\n";
  return pcl_movers::sim::parseScenario(text, "capture.yaml");
}

struct RoundTrip {
  double max_error = 0.0;   ///< largest |Δxyz| [m]
  double max_excess = 1.0;  ///< largest |Δxyz| / allowed (≤ 1 passes)
  std::size_t points = 0;
  std::size_t mismatched_cells = 0;  ///< return in one and not the other
};

/** Compares a read sweep with the simulated frame cell by cell; allowed error: half the 2 mm
 * distance step plus half the 0.01° azimuth step at the point's range. */
RoundTrip compare(const pcl::PointCloud<pcl::PointXYZI>& simulated, const VelodyneSweep& read) {
  RoundTrip result;
  result.max_excess = 0.0;
  for (std::size_t i = 0; i < simulated.size(); ++i) {
    const auto& a = simulated[i];
    const auto& b = (*read.cloud)[i];
    const bool va = std::isfinite(a.x), vb = std::isfinite(b.x);
    if (va != vb) {
      ++result.mismatched_cells;
      continue;
    }
    if (!va) continue;
    ++result.points;
    const double d = std::sqrt(double(a.x) * a.x + double(a.y) * a.y + double(a.z) * a.z);
    const double error =
        std::sqrt(double(a.x - b.x) * (a.x - b.x) + double(a.y - b.y) * (a.y - b.y) +
                  double(a.z - b.z) * (a.z - b.z));
    const double allowed = 0.001 + d * (0.005 * M_PI / 180.0) + 2e-6 * d;
    result.max_error = std::max(result.max_error, error);
    result.max_excess = std::max(result.max_excess, error / allowed);
    EXPECT_EQ(b.intensity, std::round(std::clamp(a.intensity, 0.f, 1.f) * 255.f)) << "cell " << i;
  }
  return result;
}

void expectRoundTrip(const std::string& sensor_name) {
  SCOPED_TRACE(sensor_name);
  const int frames = 3;
  pcl_movers::sim::LidarSimulator simulator(shortScene(sensor_name, frames));
  const std::string pcap = tempPath("roundtrip_" + sensor_name + ".pcap");
  pcl_movers::sim::writeCapture(simulator, pcap, true);
  const VelodyneModel model = pcl_movers::io::velodyneModelFromName(sensor_name);
  const std::string xml =
      model == VelodyneModel::kHdl64 ? pcl_movers::sim::captureCalibrationPath(pcap) : "";
  const auto sweeps = pcl_movers::io::readVelodyneCapture(pcap, model, xml);
  ASSERT_EQ(sweeps.size(), std::size_t(frames));
  const SensorModel& sensor = simulator.getSensor();
  for (int f = 0; f < frames; ++f) {
    pcl::PointCloud<pcl::PointXYZI> frame;
    std::vector<std::uint32_t> labels;
    std::vector<pcl_movers::io::GroundTruthObject> objects;
    Eigen::Isometry3d pose;
    simulator.simulate(f, frame, labels, objects, pose);
    const VelodyneSweep& s = sweeps[std::size_t(f)];
    ASSERT_EQ(s.cloud->width, frame.width);
    ASSERT_EQ(s.cloud->height, frame.height);
    const RoundTrip r = compare(frame, s);
    std::printf(
        "%s frame %d: %zu points, max error %.2f mm (%.2f of the quantization bound), "
        "%zu cells differ, %zu collisions\n",
        sensor_name.c_str(), f, r.points, r.max_error * 1e3, r.max_excess, r.mismatched_cells,
        s.collisions);
    EXPECT_GT(r.points, std::size_t(sensor.rows() * sensor.columns() / 4));
    EXPECT_EQ(r.mismatched_cells, 0u);
    EXPECT_LE(r.max_excess, 1.0);
    EXPECT_EQ(s.collisions, 0u);
    EXPECT_EQ(s.firings, std::size_t(sensor.columns()));
    // The reader times firings by the manual's timing within a packet, the simulated turn
    // spreads them evenly: they differ by less than a packet's span.
    EXPECT_NEAR(s.start_time, 0.1 * f, 1e-4);
    // Firing k of the turn is k / (rate · columns) after its start, to within a packet's timing.
    const int first = sensor.columns() / 2;
    for (int c = 0; c < sensor.columns(); ++c) {
      const float t = s.time_offsets[std::size_t(sensor.rows() - 1) * sensor.columns() + c];
      if (!std::isfinite(t)) continue;
      const int k = (c - first + sensor.columns()) % sensor.columns();
      EXPECT_NEAR(t, 0.1 * k / sensor.columns(), 1e-4) << "column " << c;
    }
  }
}

}  // namespace

TEST(VelodyneCapture, SimulatedHdl32RoundTrip) {
  expectRoundTrip("hdl32");
}

TEST(VelodyneCapture, SimulatedVlp16RoundTrip) {
  expectRoundTrip("vlp16");
}

TEST(VelodyneCapture, SimulatedHdl64RoundTripWithItsCalibration) {
  expectRoundTrip("hdl64");
}

// The beam layouts of SensorModel are the grabbers' calibration tables (elevation per row).
TEST(VelodyneCapture, SensorModelsMatchTheGrabbersTables) {
  pcl_movers::sim::LidarSimulator simulator(shortScene("hdl32", 1));
  const std::string pcap = tempPath("tables.pcap");
  pcl_movers::sim::writeCapture(simulator, pcap, true);
  for (const auto model : {VelodyneModel::kHdl32, VelodyneModel::kVlp16}) {
    VelodyneCapture capture(pcap, model);
    const SensorModel sensor = pcl_movers::io::velodyneSensorModel(model);
    const auto& elevations = capture.getLaserElevations();
    ASSERT_EQ(int(elevations.size()), sensor.rows());
    EXPECT_EQ(capture.getColumns(), sensor.columns());
    for (std::size_t laser = 0; laser < elevations.size(); ++laser) {
      const int row = capture.getRowOfLaser()[laser];
      EXPECT_NEAR(sensor.elevations()[row] * 180.0 / M_PI, elevations[laser], 1e-4)
          << pcl_movers::io::velodyneModelName(model) << " laser " << laser << " row " << row;
    }
  }
  // HDL-32E lasers interleave: laser 0 is the lowest, laser 1 at -9.33°, laser 31 the highest.
  VelodyneCapture hdl32(pcap, VelodyneModel::kHdl32);
  EXPECT_EQ(hdl32.getRowOfLaser()[0], 31);
  EXPECT_EQ(hdl32.getRowOfLaser()[1], 15);
  EXPECT_EQ(hdl32.getRowOfLaser()[31], 0);
}

// PCL's own capture thread (libpcap, paced as recorded) reads the simulator's file and hands
// the same packets to the same decoding: identical sweeps.
TEST(VelodyneCapture, GrabberThreadReadsTheSameSweeps) {
  pcl_movers::sim::LidarSimulator simulator(shortScene("vlp16", 3));
  const std::string pcap = tempPath("grabber_thread.pcap");
  pcl_movers::sim::writeCapture(simulator, pcap, true);
  const auto by_file = pcl_movers::io::readVelodyneCapture(pcap, VelodyneModel::kVlp16);
  const auto by_grabber = VelodyneCapture::readWithGrabberThread(pcap, VelodyneModel::kVlp16);
  ASSERT_EQ(by_file.size(), 3u);
  ASSERT_EQ(by_grabber.size(), by_file.size());
  for (std::size_t k = 0; k < by_file.size(); ++k) {
    EXPECT_EQ(by_grabber[k].returns, by_file[k].returns);
    for (std::size_t i = 0; i < by_file[k].cloud->size(); ++i) {
      const auto &a = (*by_file[k].cloud)[i], &b = (*by_grabber[k].cloud)[i];
      if (std::isfinite(a.x) || std::isfinite(b.x)) {
        ASSERT_EQ(a.x, b.x) << "sweep " << k << " cell " << i;
        ASSERT_EQ(a.z, b.z) << "sweep " << k << " cell " << i;
      }
    }
  }
}

TEST(VelodyneCapture, RealCaptureThroughTheGrabberThread) {
  SKIP_WITHOUT_MONTEREY();
  const auto by_file = pcl_movers::io::readVelodyneCapture(kMonterey, VelodyneModel::kHdl32);
  const auto by_grabber = VelodyneCapture::readWithGrabberThread(kMonterey, VelodyneModel::kHdl32);
  ASSERT_EQ(by_grabber.size(), by_file.size());
  for (std::size_t k = 0; k < by_file.size(); ++k)
    EXPECT_EQ(by_grabber[k].returns, by_file[k].returns) << "sweep " << k;
}

TEST(VelodyneCapture, Errors) {
  EXPECT_THROW(pcl_movers::io::velodyneModelFromName("hdl999"), InputError);
  const std::string missing = tempPath("missing.pcap");
  try {
    VelodyneCapture capture(missing, VelodyneModel::kHdl32);
    FAIL() << "no error for a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  const std::string text = tempPath("text.pcap");
  std::ofstream(text) << "not a capture at all, just some words in a text file\n";
  EXPECT_THROW(VelodyneCapture(text, VelodyneModel::kHdl32), InputError);
  // The HDL-64E needs its calibration; the VLP-16 takes none.
  pcl_movers::sim::LidarSimulator simulator(shortScene("vlp16", 1));
  const std::string pcap = tempPath("errors.pcap");
  pcl_movers::sim::writeCapture(simulator, pcap, true);
  EXPECT_THROW(VelodyneCapture(pcap, VelodyneModel::kHdl64), InputError);
  const std::string xml = tempPath("bad.xml");
  std::ofstream(xml) << "<boost_serialization><DB><points_><item><px><id_>99</id_>"
                        "<vertCorrection_>1</vertCorrection_></px></item></points_></DB>"
                        "</boost_serialization>\n";
  EXPECT_THROW(VelodyneCapture(pcap, VelodyneModel::kHdl64, xml), InputError);  // id 99
  EXPECT_THROW(VelodyneCapture(pcap, VelodyneModel::kVlp16, xml), InputError);
  // A VLP-16 capture read as an HDL-32E is recognised by its factory byte.
  VelodyneCapture wrong(pcap, VelodyneModel::kHdl32);
  VelodyneSweep sweep;
  EXPECT_THROW(wrong.next(sweep), InputError);
}

TEST(PcapFile, WritesWhatItReads) {
  const std::string path = tempPath("datagrams.pcap");
  {
    pcl_movers::io::PcapWriter writer(path);
    const std::vector<std::uint8_t> a(1206, 7), b = {1, 2, 3};
    writer.write(1704067200.25, a.data(), a.size(), 2368, 2368);
    writer.write(1704067200.5, b.data(), b.size(), 8308, 8308);
    writer.close();
  }
  pcl_movers::io::PcapReader reader(path);
  pcl_movers::io::UdpDatagram d;
  ASSERT_TRUE(reader.next(d));
  EXPECT_EQ(d.payload.size(), 1206u);
  EXPECT_EQ(d.destination_port, 2368);
  EXPECT_NEAR(d.time, 1704067200.25, 1e-6);
  ASSERT_TRUE(reader.next(d));
  EXPECT_EQ(d.payload, std::vector<std::uint8_t>({1, 2, 3}));
  EXPECT_EQ(d.source_port, 8308);
  EXPECT_FALSE(reader.next(d));
  EXPECT_FALSE(reader.isTruncated());
  // Cut inside the second record: the first datagram is still read, the cut is reported.
  const auto size = fs::file_size(path);
  fs::resize_file(path, size - 2);
  pcl_movers::io::PcapReader cut(path);
  EXPECT_TRUE(cut.next(d));
  EXPECT_FALSE(cut.next(d));
  EXPECT_TRUE(cut.isTruncated());
}
