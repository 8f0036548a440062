/*
 * Sequence, ground-truth and tracks I/O: round trips and every bad input named in DESIGN.md.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/point_times.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/io/tracks.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>

#include "test_util.h"

namespace fs = std::filesystem;
using namespace pcl_movers;

namespace {

using test_util::TempDir;
using test_util::writeFile;

pcl::PointCloud<pcl::PointXYZI> makeCloud(int n, float offset) {
  pcl::PointCloud<pcl::PointXYZI> cloud;
  for (int i = 0; i < n; ++i) {
    pcl::PointXYZI p;
    p.x = offset + i;
    p.y = -0.5f * i;
    p.z = 0.25f * i;
    p.intensity = float(i) / n;
    cloud.push_back(p);
  }
  return cloud;
}

std::string expectInputError(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected InputError";
  return {};
}

}  // namespace

TEST(SequenceIO, SortsNumerically) {
  std::vector<std::string> names = {"a/10.pcd", "a/2.pcd", "a/1.pcd", "a/000100.pcd", "a/x.pcd"};
  io::sortNumerically(names);
  EXPECT_EQ(names, (std::vector<std::string>{"a/x.pcd", "a/1.pcd", "a/2.pcd", "a/10.pcd",
                                             "a/000100.pcd"}));
}

TEST(SequenceIO, RoundTripFramesPosesTimes) {
  TempDir dir;
  const std::string seq = (dir.path() / "seq").string();
  std::vector<Eigen::Isometry3d> poses;
  std::vector<double> times;
  {
    io::SequenceWriter writer(seq);
    for (int i = 0; i < 12; ++i) {
      auto cloud = makeCloud(5 + i, float(i));
      writer.writeFrame(i, cloud);
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.rotate(Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d::UnitZ()));
      pose.translation() = Eigen::Vector3d(i * 0.7, -0.1 * i, 0.01 * i);
      poses.push_back(pose);
      times.push_back(0.1 * i + 5.0);
    }
    writer.writePoses(poses);
    writer.writeTimes(times);
  }
  io::SequenceReader reader(seq);
  ASSERT_EQ(reader.size(), 12u);
  EXPECT_EQ(reader.poseSource(), "poses.txt");
  EXPECT_EQ(reader.frameName(10), "000010");  // numeric order, not lexical
  for (std::size_t i = 0; i < reader.size(); ++i) {
    pcl::PointCloud<pcl::PointXYZI> cloud;
    reader.read(i, cloud);
    const auto expected = makeCloud(5 + int(i), float(i));
    ASSERT_EQ(cloud.size(), expected.size());
    for (std::size_t k = 0; k < cloud.size(); ++k) {
      EXPECT_FLOAT_EQ(cloud[k].x, expected[k].x);
      EXPECT_FLOAT_EQ(cloud[k].intensity, expected[k].intensity);
    }
    EXPECT_TRUE(reader.pose(i).isApprox(poses[i], 1e-7));
    EXPECT_NEAR(reader.time(i), times[i], 1e-6);
  }
}

// Per-point times (a float `time` field, NaN kept) and times.txt to the bit (`exact`), as
// pcl_movers_organize --pcap writes them.
TEST(SequenceIO, TimedFramesAndExactTimes) {
  TempDir dir;
  const std::string seq = (dir.path() / "seq").string();
  io::SequenceWriter writer(seq);
  const auto cloud = makeCloud(4, 1.f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::string path = writer.writeFrame(0, cloud, {0.f, 0.025f, nan, 0.0999f});
  EXPECT_EQ(io::pointTimeField(path), "time");
  const auto times = io::readPointTimes(path);
  ASSERT_EQ(times.size(), 4u);
  EXPECT_EQ(times[1], 0.025f);
  EXPECT_TRUE(std::isnan(times[2]));
  EXPECT_EQ(times[3], 0.0999f);
  EXPECT_THROW(writer.writeFrame(1, cloud, {0.f}), InputError);  // one time per point
  const std::vector<double> starts = {393.25332639999993, 393.3 + 1e-9, 0.1 * 3 + 400};
  writer.writeTimes(starts, true);
  EXPECT_EQ(io::readTimes(seq + "/times.txt"), starts);
  writer.writeTimes(starts);  // microseconds
  EXPECT_NE(io::readTimes(seq + "/times.txt"), starts);
}

TEST(SequenceIO, ViewpointIsThePoseWithoutPosesFile) {
  TempDir dir;
  fs::create_directories(dir.path() / "frames");
  for (int i = 0; i < 3; ++i) {
    auto cloud = makeCloud(4, 0);
    cloud.sensor_origin_ = Eigen::Vector4f(1.0f + i, 2.0f, 0.5f, 0.0f);
    cloud.sensor_orientation_ =
        Eigen::Quaternionf(Eigen::AngleAxisf(0.2f * i, Eigen::Vector3f::UnitZ()));
    pcl::io::savePCDFileBinary((dir.path() / "frames" / (std::to_string(i) + ".pcd")).string(),
                               cloud);
  }
  io::SequenceReader reader(dir.str(), 20.0);
  EXPECT_EQ(reader.poseSource(), "viewpoint");
  EXPECT_NEAR(reader.pose(2).translation().x(), 3.0, 1e-6);
  EXPECT_NEAR(Eigen::AngleAxisd(reader.pose(2).linear()).angle(), 0.4, 1e-5);
  EXPECT_FALSE(reader.hasTimes());
  EXPECT_NEAR(reader.time(2), 0.1, 1e-12);  // from --rate 20 Hz
}

// Geo-referenced poses (UTM: x 456789 m, y 5432101 m) keep their millimetres through poses.txt and
// through PCD VIEWPOINTs written by software that prints them in full (PCL parses into floats,
// which keep only 0.5 m of a northing).
TEST(SequenceIO, GeoReferencedPosesKeepTheirMillimetres) {
  TempDir dir;
  Eigen::Isometry3d pose(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  pose.translation() = Eigen::Vector3d(456789.1234, 5432101.5678, 250.0012);
  io::writePoses((dir.path() / "poses.txt").string(), {pose});
  const auto back = io::readPoses((dir.path() / "poses.txt").string());
  ASSERT_EQ(back.size(), 1u);
  EXPECT_LT((back[0].translation() - pose.translation()).norm(), 1e-6);
  EXPECT_LT((back[0].linear() - pose.linear()).norm(), 1e-8);

  fs::create_directories(dir.path() / "seq" / "frames");
  writeFile(dir.path() / "seq" / "frames" / "000000.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
            "HEIGHT 1\nVIEWPOINT 456789.1234 5432101.5678 250.0012 1 0 0 0\nPOINTS 1\n"
            "DATA ascii\n5 0 -1\n");
  io::SequenceReader reader((dir.path() / "seq").string());
  ASSERT_EQ(reader.poseSource(), "viewpoint");
  EXPECT_NEAR(reader.pose(0).translation().x(), 456789.1234, 1e-6);
  EXPECT_NEAR(reader.pose(0).translation().y(), 5432101.5678, 1e-6);
  EXPECT_NEAR(reader.pose(0).translation().z(), 250.0012, 1e-6);
}

TEST(SequenceIO, ReadsKittiBinAndPcdWithoutIntensity) {
  TempDir dir;
  const float raw[8] = {1, 2, 3, 0.5f, 4, 5, 6, 0.25f};
  std::ofstream(dir.path() / "0.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(raw), 32);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  io::readScan((dir.path() / "0.bin").string(), cloud);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_FLOAT_EQ(cloud[1].y, 5.0f);
  EXPECT_FLOAT_EQ(cloud[1].intensity, 0.25f);

  pcl::PointCloud<pcl::PointXYZ> xyz;
  xyz.push_back(pcl::PointXYZ(1, 2, 3));
  pcl::io::savePCDFileASCII((dir.path() / "xyz.pcd").string(), xyz);
  io::readScan((dir.path() / "xyz.pcd").string(), cloud);
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_FLOAT_EQ(cloud[0].z, 3.0f);
  EXPECT_FLOAT_EQ(cloud[0].intensity, 0.0f);
}

TEST(SequenceIO, BadInputsNameTheFileAndReason) {
  TempDir dir;
  // Missing folder, no frames.
  EXPECT_NE(expectInputError([&] {
              io::SequenceReader r((dir.path() / "nope").string());
            }).find("does not exist"),
            std::string::npos);
  EXPECT_NE(expectInputError([&] { io::SequenceReader r(dir.str()); }).find("no frames"),
            std::string::npos);
  // Truncated PCD (binary data cut in half).
  const auto good = (dir.path() / "good.pcd").string();
  pcl::io::savePCDFileBinary(good, makeCloud(1000, 0));
  const auto size = fs::file_size(good);
  fs::copy_file(good, dir.path() / "cut.pcd");
  fs::resize_file(dir.path() / "cut.pcd", size / 2);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  const std::string cut_msg =
      expectInputError([&] { io::readScan((dir.path() / "cut.pcd").string(), cloud); });
  EXPECT_NE(cut_msg.find("cut.pcd"), std::string::npos);
  // Not a PCD at all.
  writeFile(dir.path() / "junk.pcd", "hello world\n");
  expectInputError([&] { io::readScan((dir.path() / "junk.pcd").string(), cloud); });
  // PCD without x/y/z.
  writeFile(dir.path() / "noxyz.pcd",
            "VERSION .7\nFIELDS a b\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2\n");
  EXPECT_NE(expectInputError([&] {
              io::readScan((dir.path() / "noxyz.pcd").string(), cloud);
            }).find("no 'x' field"),
            std::string::npos);
  // A header line missing its value: PCL's parser throws std::out_of_range from vector::at(),
  // which must come out as an InputError naming the file (fuzz_pcd_pipeline finding,
  // test/fuzz/corpus_pcd/regression_pcd_header_out_of_range.pcd).
  writeFile(dir.path() / "nodata.pcd",
            "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA\nascii\n1 2 3\n");
  EXPECT_NE(expectInputError([&] {
              io::readScan((dir.path() / "nodata.pcd").string(), cloud);
            }).find("nodata.pcd"),
            std::string::npos);
  // Truncated .bin.
  writeFile(dir.path() / "cut.bin", "0123456789");
  EXPECT_NE(expectInputError([&] {
              io::readScan((dir.path() / "cut.bin").string(), cloud);
            }).find("truncated"),
            std::string::npos);
  // Missing file, malformed PLY, unknown extension.
  expectInputError([&] { io::readScan((dir.path() / "x.ply").string(), cloud); });
  writeFile(dir.path() / "x.ply", "ply");
  EXPECT_NE(
      expectInputError([&] { io::readScan((dir.path() / "x.ply").string(), cloud); }).find("x.ply"),
      std::string::npos);
  writeFile(dir.path() / "x.xyz", "1 2 3");
  EXPECT_NE(expectInputError([&] {
              io::readScan((dir.path() / "x.xyz").string(), cloud);
            }).find("unknown scan format"),
            std::string::npos);
}

// Headers whose layout PCL's reader would write past (it sizes its buffer at POINTS and writes
// every point with the final step: fuzz_pcd_pipeline found the heap corruption in CI). Each is
// refused before PCL reads the body, with the reason; the fields-past-the-step and
// compressed-size cases are the other two ways to make it write outside that buffer.
TEST(SequenceIO, PcdLayoutThatPclWouldOverrunIsRefused) {
  TempDir dir;
  pcl::PointCloud<pcl::PointXYZI> cloud;
  auto message = [&](const std::string& name, const std::string& text) {
    writeFile(dir.path() / name, text);
    const std::string m =
        expectInputError([&] { io::readScan((dir.path() / name).string(), cloud); });
    EXPECT_NE(m.find(name), std::string::npos) << m;
    return m;
  };
  std::string values;
  for (int i = 0; i < 2 * 120; ++i) values += i % 120 == 119 ? "0\n" : "0 ";
  EXPECT_NE(message("late_count.pcd",
                    "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
                    "HEIGHT 1\nPOINTS 2\nCOUNT 40 40 40\nDATA ascii\n" +
                        values)
                .find("changes after POINTS"),
            std::string::npos);
  // A second SIZE line after COUNT recomputes offsets without the counts: z at 8 with 4 x 4
  // bytes ends at 24 of a 12-byte point.
  EXPECT_NE(message("late_size.pcd",
                    "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 4\n"
                    "SIZE 4 4 4\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 4 5 6\n")
                .find("field 'z' ends at byte 24"),
            std::string::npos);
  // binary_compressed whose stored uncompressed size differs from the header's: PCL would
  // resize its buffer to the stored size and unpack the header's points into it.
  std::string compressed =
      "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\n"
      "POINTS 4\nDATA binary_compressed\n";
  const std::uint32_t sizes[2] = {8, 12};  // 12 bytes stored, 48 described
  compressed.append(reinterpret_cast<const char*>(sizes), sizeof(sizes));
  compressed.append(64, '\0');
  EXPECT_NE(message("small_lzf.pcd", compressed).find("stores 12 uncompressed bytes"),
            std::string::npos);
  // The same layouts written in the usual order are read.
  writeFile(dir.path() / "good.pcd",
            "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
            "HEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n");
  io::readScan((dir.path() / "good.pcd").string(), cloud);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_FLOAT_EQ(cloud[1].z, 6.f);
}

TEST(SequenceIO, PoseAndTimeFilesAreChecked) {
  TempDir dir;
  const std::string seq = (dir.path() / "seq").string();
  {
    io::SequenceWriter writer(seq);
    for (int i = 0; i < 3; ++i) writer.writeFrame(i, makeCloud(3, 0));
  }
  const fs::path poses = fs::path(seq) / "poses.txt";
  writeFile(poses, "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(expectInputError([&] { io::SequenceReader r(seq); }).find("has 2 poses"),
            std::string::npos);
  writeFile(poses, "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(expectInputError([&] { io::SequenceReader r(seq); }).find("poses.txt:2"),
            std::string::npos);
  writeFile(poses, "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 x 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(expectInputError([&] { io::SequenceReader r(seq); }).find("poses.txt:2"),
            std::string::npos);
  writeFile(poses, "2 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(expectInputError([&] { io::SequenceReader r(seq); }).find("orthonormal"),
            std::string::npos);
  fs::remove(poses);
  const fs::path times = fs::path(seq) / "times.txt";
  writeFile(times, "0.0\n0.1\n");
  EXPECT_NE(expectInputError([&] { io::SequenceReader r(seq); }).find("2 timestamps"),
            std::string::npos);
  writeFile(times, "0.0\n0.2\n0.1\n");
  EXPECT_NE(expectInputError([&] { io::SequenceReader r(seq); }).find("times.txt:3"),
            std::string::npos);
  writeFile(times, "0.0\n0.1\n0.2\n");
  EXPECT_NO_THROW(io::SequenceReader r(seq));
}

TEST(SequenceIO, WriterRefusesNonEmptyFolderUnlessAsked) {
  TempDir dir;
  writeFile(dir.path() / "precious.txt", "keep me");
  EXPECT_NE(expectInputError([&] { io::SequenceWriter w(dir.str()); }).find("--overwrite"),
            std::string::npos);
  EXPECT_TRUE(fs::exists(dir.path() / "precious.txt"));
  EXPECT_NO_THROW(io::SequenceWriter w(dir.str(), true));
  writeFile(dir.path() / "file", "x");
  expectInputError([&] { io::prepareOutputDirectory((dir.path() / "file").string(), true); });
}

TEST(GroundTruthIO, ObjectsRoundTripAndBoxTest) {
  TempDir dir;
  io::GroundTruthObject o;
  o.frame = 3;
  o.track_id = 7;
  o.type = "Van";
  o.center = Eigen::Vector3d(10, 2, -0.5);
  o.length = 4;
  o.width = 2;
  o.height = 2;
  o.yaw = M_PI / 2;
  o.moving = true;
  o.speed = 5.25;
  o.n_points = 321;
  io::writeObjects((dir.path() / "objects.txt").string(), {o, o});
  const auto back = io::readObjects((dir.path() / "objects.txt").string());
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].type, "Van");
  EXPECT_EQ(back[1].n_points, 321);
  EXPECT_TRUE(back[1].moving);
  EXPECT_NEAR(back[1].yaw, M_PI / 2, 1e-4);
  // Box rotated by 90°: length runs along y.
  EXPECT_TRUE(o.contains(Eigen::Vector3d(10, 3.9, -0.5)));
  EXPECT_FALSE(o.contains(Eigen::Vector3d(11.5, 2, -0.5)));
  EXPECT_TRUE(o.contains(Eigen::Vector3d(11.4, 2, -0.5), 1.0));  // grown by 1 m in width
  writeFile(dir.path() / "bad.txt", "# header\n0 1 Car 1 2 3 4 5 6 0.1 1 2.0 10\n0 1 Car 1 2 3\n");
  EXPECT_NE(expectInputError([&] {
              io::readObjects((dir.path() / "bad.txt").string());
            }).find("bad.txt:3"),
            std::string::npos);
}

TEST(GroundTruthIO, LabelsRoundTrip) {
  TempDir dir;
  std::vector<std::uint32_t> labels = {io::makeLabel(10, 5), io::makeLabel(40, 0), 0};
  io::writeLabels((dir.path() / "l.label").string(), labels);
  const auto back = io::readLabels((dir.path() / "l.label").string());
  ASSERT_EQ(back, labels);
  EXPECT_EQ(io::labelClass(back[0]), 10);
  EXPECT_EQ(io::labelInstance(back[0]), 5);
  EXPECT_TRUE(io::semantic::isGround(io::labelClass(back[1])));
  writeFile(dir.path() / "cut.label", "abcde");
  expectInputError([&] { io::readLabels((dir.path() / "cut.label").string()); });
}

TEST(TracksIO, RoundTripAndErrors) {
  TempDir dir;
  io::TrackRow r;
  r.frame = 4;
  r.time = 0.4;
  r.track_id = 12;
  r.mover = true;
  r.x = 1.5;
  r.wy = -2.25;
  r.speed = 3.5;
  r.yaw = 0.1234;
  r.similarity = 0.875;
  r.points = 99;
  const auto path = (dir.path() / "tracks.csv").string();
  io::writeTracks(path, {r});
  const auto back = io::readTracks(path);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(io::formatTrackRow(back[0]), io::formatTrackRow(r));
  writeFile(dir.path() / "bad.csv", std::string(io::tracksCsvHeader()) + "\n1,2,3\n");
  EXPECT_NE(expectInputError([&] {
              io::readTracks((dir.path() / "bad.csv").string());
            }).find("bad.csv:2"),
            std::string::npos);
  writeFile(dir.path() / "nohead.csv", "1,2,3\n");
  expectInputError([&] { io::readTracks((dir.path() / "nohead.csv").string()); });
}

// The `file` column (#29): the input file's number beside the 0-based frame index; tracks.csv
// files written before it are read with file = frame.
TEST(TracksIO, FileColumnBesideTheFrameIndex) {
  TempDir dir;
  io::TrackRow r;
  r.frame = 3;
  r.file = 43;
  r.track_id = 7;
  const auto path = (dir.path() / "tracks.csv").string();
  io::writeTracks(path, {r});
  EXPECT_EQ(io::formatTrackRow(r).rfind("3,43,", 0), 0u) << io::formatTrackRow(r);
  EXPECT_EQ(io::readTracks(path).at(0).file, 43);
  writeFile(dir.path() / "old.csv",
            "frame,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,"
            "similarity,points\n5,0.5,7,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,9\n");
  const auto old = io::readTracks((dir.path() / "old.csv").string());
  ASSERT_EQ(old.size(), 1u);
  EXPECT_EQ(old[0].file, 5);
  EXPECT_EQ(old[0].points, 9);
}

// The `reason` column (#28): written last, read back; files without it read with reason "".
TEST(TracksIO, ReasonColumnRoundTrips) {
  TempDir dir;
  io::TrackRow a, b;
  a.frame = 1, a.track_id = 4, a.mover = true, a.reason = "sustained";
  b.frame = 1, b.track_id = 5, b.reason = "";  // a row built without a decision
  const auto path = (dir.path() / "tracks.csv").string();
  io::writeTracks(path, {a, b});
  const auto rows = io::readTracks(path);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].reason, "sustained");
  EXPECT_TRUE(rows[0].mover);
  EXPECT_EQ(rows[1].reason, "");
  writeFile(dir.path() / "v2.csv",
            "frame,file,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,"
            "similarity,points\n5,45,0.5,7,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,9\n");
  const auto v2 = io::readTracks((dir.path() / "v2.csv").string());
  ASSERT_EQ(v2.size(), 1u);
  EXPECT_EQ(v2[0].file, 45);
  EXPECT_EQ(v2[0].reason, "");
}

TEST(SharedData, ReadsEverySet) {
  const fs::path data(PCL_MOVERS_SHARED_DATA);
  if (!fs::exists(data / "kitti-tracking-0000-a"))
    GTEST_SKIP() << "shared KITTI data not found at " << data << " (optional)";
  io::SequenceReader tracking((data / "kitti-tracking-0000-a").string());
  EXPECT_EQ(tracking.size(), 77u);
  EXPECT_EQ(tracking.poseSource(), "poses.txt");
  EXPECT_TRUE(tracking.hasTimes());
  EXPECT_FALSE(tracking.objectsPath().empty());
  pcl::PointCloud<pcl::PointXYZI> cloud;
  tracking.read(76, cloud);
  EXPECT_GT(cloud.size(), 90000u);

  io::SequenceReader odometry((data / "kitti-odometry-00").string());
  EXPECT_EQ(odometry.size(), 6u);
  EXPECT_FALSE(odometry.labelPath(0).empty());
  odometry.read(0, cloud);
  EXPECT_EQ(io::readLabels(odometry.labelPath(0)).size(), cloud.size());

  io::SequenceReader city((data / "kitti-city-22").string());
  EXPECT_EQ(city.size(), 22u);
  EXPECT_FALSE(city.hasPoses());
  io::SequenceReader object((data / "kitti-object-3").string());
  EXPECT_EQ(object.size(), 3u);
}
