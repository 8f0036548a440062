/*
 * Detection metrics (DESIGN.md "Metrics") on hand-made ground truth and tracks with known answers,
 * plus the pcl_movers_eval tool's handling of bad input.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/eval/detection_metrics.h>
#include <pcl_movers/eval/kitti_dont_care.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using pcl_movers::eval::DetectionMetricsParams;
using pcl_movers::eval::scoreDetections;
using pcl_movers::io::GroundTruthObject;
using pcl_movers::io::TrackRow;

namespace {

GroundTruthObject object(int frame, int id, double x, double y, bool moving, int points = 100,
                         double yaw = 0.0, const std::string& type = "Car") {
  GroundTruthObject o;
  o.frame = frame;
  o.track_id = id;
  o.type = type;
  o.center = Eigen::Vector3d(x, y, 0.0);
  o.length = 4.0;
  o.width = 2.0;
  o.height = 1.6;
  o.yaw = yaw;
  o.moving = moving;
  o.speed = moving ? 5.0 : 0.0;
  o.n_points = points;
  return o;
}

TrackRow row(int frame, int id, double x, double y, bool mover = true, double vx = 0,
             double vy = 0) {
  TrackRow r;
  r.frame = frame;
  r.time = 0.1 * frame;
  r.track_id = id;
  r.mover = mover;
  r.x = x;
  r.y = y;
  r.z = 0.1;
  r.vx = vx;
  r.vy = vy;
  r.speed = std::hypot(vx, vy);
  return r;
}

}  // namespace

TEST(DetectionMetrics, HitsDelayAndHitRate) {
  std::vector<GroundTruthObject> objects;
  std::vector<TrackRow> tracks;
  for (int f = 0; f < 10; ++f) {
    objects.push_back(object(f, 7, 10.0, 0.0, true, 100, 0.0, "Van"));
    if (f >= 3) tracks.push_back(row(f, 1, 10.3, 0.2));
    // A non-mover row on the target is neither a hit nor a false alarm.
    tracks.push_back(row(f, 2, 10.0, 0.0, false));
  }
  const auto s = scoreDetections(objects, tracks);
  ASSERT_EQ(s.targets.size(), 1u);
  const auto& t = s.targets[0];
  EXPECT_EQ(t.track_id, 7);
  EXPECT_EQ(t.type, "Van");
  EXPECT_EQ(t.visible_frames, 10);
  EXPECT_EQ(t.hits, 7);
  EXPECT_NEAR(t.hitRate(), 0.7, 1e-12);
  EXPECT_EQ(t.first_visible, 0);
  EXPECT_EQ(t.first_hit, 3);
  EXPECT_EQ(t.delay, 3);
  EXPECT_NEAR(s.mean_hit_rate, 0.7, 1e-12);
  EXPECT_NEAR(s.median_delay, 3.0, 1e-12);
  EXPECT_EQ(s.false_alarms, 0);
  EXPECT_EQ(s.frames, 10);
}

TEST(DetectionMetrics, GrownBoxFollowsYaw) {
  // Box 4 x 2 m; grown by 1 m -> half extents 2.5 (length) and 1.5 (width).
  std::vector<GroundTruthObject> objects = {object(0, 1, 10, 0, true),
                                            object(1, 1, 10, 0, true, 100, M_PI / 2)};
  // Frame 0, yaw 0: 2.4 m ahead of the centre is inside the grown box, 2.6 m is not.
  // Frame 1, yaw 90 deg: the length now runs along y, so 2.4 m along x is outside.
  std::vector<TrackRow> inside = {row(0, 1, 12.4, 0), row(1, 1, 10, 2.4)};
  std::vector<TrackRow> outside = {row(0, 1, 12.6, 0), row(1, 1, 12.4, 0)};
  const auto a = scoreDetections(objects, inside);
  EXPECT_EQ(a.targets[0].hits, 2);
  EXPECT_EQ(a.false_alarms, 0);
  const auto b = scoreDetections(objects, outside);
  EXPECT_EQ(b.targets[0].hits, 0);
  EXPECT_EQ(b.false_alarms, 2);
  EXPECT_EQ(b.targets_never_detected, 1);
  EXPECT_EQ(b.targets[0].delay, -1);
  // Without growth the 2.4 m row misses.
  DetectionMetricsParams tight;
  tight.grow_xy = 0.0;
  EXPECT_EQ(scoreDetections(objects, inside, tight).targets[0].hits, 0);
}

TEST(DetectionMetrics, SectorAndMinPoints) {
  // Target 1 at 90 deg (outside the KITTI 40 deg sector), target 2 ahead with too few points,
  // target 3 ahead and visible.
  std::vector<GroundTruthObject> objects;
  std::vector<TrackRow> tracks;
  for (int f = 0; f < 4; ++f) {
    objects.push_back(object(f, 1, 0.0, 10.0, true));
    objects.push_back(object(f, 2, 20.0, -5.0, true, 9));
    objects.push_back(object(f, 3, 15.0, 3.0, true));
    tracks.push_back(row(f, 11, 0.0, 10.0));
    tracks.push_back(row(f, 12, 20.0, -5.0));
    tracks.push_back(row(f, 13, 15.0, 3.0));
    tracks.push_back(row(f, 14, -10.0, 0.0));  // behind: outside the sector, ignored at 40 deg
  }
  const auto s = scoreDetections(objects, tracks);
  ASSERT_EQ(s.targets.size(), 3u);
  EXPECT_EQ(s.targets[0].visible_frames, 0);
  EXPECT_EQ(s.targets[1].visible_frames, 0);
  EXPECT_EQ(s.targets[2].visible_frames, 4);
  EXPECT_EQ(s.targets[2].hits, 4);
  EXPECT_NEAR(s.mean_hit_rate, 1.0, 1e-12);  // invisible targets do not dilute the mean
  // The row on the too-sparse target matches a target box: not a false alarm. The rows at 90 deg
  // and behind are outside the sector and unscored.
  EXPECT_EQ(s.false_alarms, 0);
  EXPECT_EQ(s.mover_rows_in_sector, 8);

  DetectionMetricsParams all_round;
  all_round.sector_deg = 180;
  all_round.min_points = 5;
  const auto r = scoreDetections(objects, tracks, all_round);
  EXPECT_EQ(r.targets[0].visible_frames, 4);
  EXPECT_EQ(r.targets[1].visible_frames, 4);
  EXPECT_EQ(r.false_alarms, 4);  // the row behind now counts
  EXPECT_NEAR(r.false_alarms_per_frame, 1.0, 1e-12);
}

TEST(DetectionMetrics, FalseAlarmsIncludeStaticObjectsAndUseFrameCount) {
  std::vector<GroundTruthObject> objects = {object(0, 1, 10, 0, true), object(0, 2, 10, 8, false),
                                            object(5, 1, 12, 0, true)};
  std::vector<TrackRow> tracks = {row(0, 1, 10, 0), row(0, 2, 10, 8), row(0, 3, 20, -3),
                                  row(5, 1, 12, 0), row(5, 4, 30, 0, false)};
  auto s = scoreDetections(objects, tracks);
  EXPECT_EQ(s.false_alarms, 2);  // the parked car declared moving + the row on nothing
  EXPECT_EQ(s.false_alarms_on_static_objects, 1);
  EXPECT_EQ(s.frames, 2);  // distinct frames 0 and 5
  EXPECT_NEAR(s.false_alarms_per_frame, 1.0, 1e-12);
  DetectionMetricsParams p;
  p.frames = 40;
  s = scoreDetections(objects, tracks, p);
  EXPECT_NEAR(s.false_alarms_per_frame, 0.05, 1e-12);
}

TEST(DetectionMetrics, MedianDelayOverDetectedTargets) {
  std::vector<GroundTruthObject> objects;
  std::vector<TrackRow> tracks;
  const int first_hit[3] = {1, 4, 6};
  for (int f = 0; f < 10; ++f)
    for (int id = 0; id < 4; ++id) {
      objects.push_back(object(f, id, 10.0 + 10 * id, 0.0, true));
      if (id < 3 && f >= first_hit[id]) tracks.push_back(row(f, id, 10.0 + 10 * id, 0.0));
    }
  const auto s = scoreDetections(objects, tracks);
  EXPECT_NEAR(s.median_delay, 4.0, 1e-12);
  EXPECT_EQ(s.targets_never_detected, 1);
  EXPECT_NEAR(s.mean_hit_rate, (0.9 + 0.6 + 0.4 + 0.0) / 4, 1e-12);
  EXPECT_NEAR(s.pooled_hit_rate, 19.0 / 40.0, 1e-12);
}

TEST(DetectionMetrics, VelocityErrorWithPosesAndSpeeds) {
  // The sensor drives along x at 4 m/s, the target at 5 m/s: in the sensor frame it creeps
  // ahead at 1 m/s, so only a pose-aware reference gives 5 m/s.
  std::vector<GroundTruthObject> objects;
  std::vector<TrackRow> tracks;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<double> times;
  for (int f = 0; f < 12; ++f) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0.4 * f, 0.0, 0.0);
    poses.push_back(pose);
    times.push_back(0.1 * f);
    objects.push_back(object(f, 3, 10.0 + 0.1 * f, 0.0, true));
    tracks.push_back(row(f, 9, 10.0 + 0.1 * f, 0.1, true, 5.3, 0.4));
  }
  const auto with_poses = scoreDetections(objects, tracks, DetectionMetricsParams(), poses, times);
  ASSERT_EQ(with_poses.targets.size(), 1u);
  EXPECT_EQ(with_poses.targets[0].velocity_samples, 12);
  EXPECT_NEAR(with_poses.targets[0].rms_velocity_error, 0.5, 1e-9);
  EXPECT_NEAR(with_poses.rms_velocity_error, 0.5, 1e-9);

  // Without poses: speed comparison, | |(5.3, 0.4)| - 5 |.
  const auto no_poses = scoreDetections(objects, tracks);
  EXPECT_NEAR(no_poses.rms_velocity_error, std::hypot(5.3, 0.4) - 5.0, 1e-9);

  // Rotated world: a pose yaw of 90 deg turns the target's +x motion into world +y.
  for (auto& p : poses) p.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).matrix();
  for (auto& p : poses) p.translation() = Eigen::Vector3d(0.0, p.translation().x(), 0.0);
  for (auto& r : tracks) {
    r.vx = 0.0;
    r.vy = 5.0;
  }
  const auto rotated = scoreDetections(objects, tracks, DetectionMetricsParams(), poses, times);
  EXPECT_NEAR(rotated.rms_velocity_error, 0.0, 1e-9);
}

TEST(DetectionMetrics, BadInputsThrow) {
  std::vector<GroundTruthObject> objects = {object(3, 1, 10, 0, true)};
  std::vector<TrackRow> tracks = {row(3, 1, 10, 0)};
  DetectionMetricsParams p;
  p.sector_deg = 0;
  EXPECT_THROW(scoreDetections(objects, tracks, p), pcl_movers::InputError);
  p.sector_deg = 40;
  p.grow_xy = -1;
  EXPECT_THROW(scoreDetections(objects, tracks, p), pcl_movers::InputError);
  // Poses that do not reach frame 3 are an input error, not a crash.
  std::vector<Eigen::Isometry3d> poses(2, Eigen::Isometry3d::Identity());
  EXPECT_THROW(scoreDetections(objects, tracks, DetectionMetricsParams(), poses),
               pcl_movers::InputError);
}

TEST(DetectionMetrics, ReportsAndChart) {
  std::vector<GroundTruthObject> objects;
  std::vector<TrackRow> tracks;
  for (int f = 0; f < 4; ++f) {
    objects.push_back(object(f, 0, 10, 0, true, 100, 0, "Van"));
    objects.push_back(object(f, 1, 20, 0, true, 100, 0, "Cyclist"));
    if (f >= 2) tracks.push_back(row(f, 5, 10, 0));
  }
  const auto s = scoreDetections(objects, tracks);
  const std::string md = pcl_movers::eval::formatMarkdown(s);
  EXPECT_NE(md.find("| 0 | Van | 4 | 2 | 50.0 | 2 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 1 | Cyclist | 4 | 0 | 0.0 | never |"), std::string::npos) << md;
  EXPECT_NE(md.find("mean hit % | 25.0"), std::string::npos) << md;
  const std::string js = pcl_movers::eval::formatJson(s);
  EXPECT_NE(js.find("\"mean_hit_rate\": 0.2500"), std::string::npos) << js;
  EXPECT_NE(js.find("\"delay\": null"), std::string::npos) << js;

  int w = 0, h = 0;
  std::vector<unsigned char> rgb;
  pcl_movers::eval::drawHitChart(s, "TEST", w, h, rgb);
  ASSERT_GT(w, 0);
  ASSERT_GT(h, 0);
  ASSERT_EQ(rgb.size(), std::size_t(w) * h * 3);
  // Bar pixels (the chart's blue) scale with the hit rate: one bar of 50 %, one of 0 %.
  std::size_t blue = 0;
  for (std::size_t i = 0; i < rgb.size(); i += 3)
    if (rgb[i] == 52 && rgb[i + 1] == 101 && rgb[i + 2] == 164) ++blue;
  EXPECT_NEAR(double(blue), 48.0 * 150.0, 48.0 * 3);
}

// ------------------------------------------------------------------ the tool on bad input
namespace {

std::string toolPath() {
  return std::string(PCL_MOVERS_BINARY_DIR) + "/apps/pcl_movers_eval";
}

int runTool(const std::string& args, std::string* output = nullptr) {
  // One output file per test: ctest runs the EvalTool tests in parallel processes.
  const std::string out_file =
      fs::temp_directory_path() /
      ("pcl_movers_eval_test_out." +
       std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".txt");
  const int rc = std::system((toolPath() + " " + args + " >" + out_file + " 2>&1").c_str());
  if (output) {
    std::ifstream in(out_file);
    output->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return rc;
}

void writeFile(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
}

}  // namespace

TEST(EvalTool, ScoresAndRejectsBadInput) {
  if (!fs::exists(toolPath())) GTEST_SKIP() << "pcl_movers_eval not built at " << toolPath();
  const fs::path dir = fs::temp_directory_path() / "pcl_movers_eval_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string header =
      "frame,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,similarity,"
      "points\n";
  writeFile(dir / "objects.txt",
            "# frame track_id class cx cy cz length width height yaw moving speed_mps n_points\n"
            "0 0 Van 10 0 0 4 2 2 0 1 5 100\n1 0 Van 10.5 0 0 4 2 2 0 1 5 100\n");
  writeFile(dir / "tracks.csv", header + "1,0.1,3,1,10.4,0,0,10.4,0,0,5,0,5,4,2,2,0,0.9,80\n");
  std::string out;
  ASSERT_EQ(
      runTool((dir / "objects.txt").string() + " " + (dir / "tracks.csv").string() + " --png " +
                  (dir / "c.png").string() + " --json " + (dir / "s.json").string(),
              &out),
      0)
      << out;
  EXPECT_NE(out.find("| 0 | Van | 2 | 1 | 50.0 | 1 |"), std::string::npos) << out;
  EXPECT_TRUE(fs::file_size(dir / "c.png") > 100);
  EXPECT_TRUE(fs::file_size(dir / "s.json") > 100);
  // Existing outputs are not replaced without --overwrite.
  EXPECT_NE(runTool((dir / "objects.txt").string() + " " + (dir / "tracks.csv").string() +
                    " --json " + (dir / "s.json").string()),
            0);
  // Missing file, unknown flag, malformed number, malformed rows: non-zero exit, file named.
  EXPECT_NE(runTool((dir / "nope.txt").string() + " " + (dir / "tracks.csv").string(), &out), 0);
  EXPECT_NE(out.find("nope.txt"), std::string::npos) << out;
  EXPECT_NE(
      runTool((dir / "objects.txt").string() + " " + (dir / "tracks.csv").string() + " --bogus"),
      0);
  EXPECT_NE(runTool((dir / "objects.txt").string() + " " + (dir / "tracks.csv").string() +
                    " --sector-deg abc"),
            0);
  writeFile(dir / "bad_objects.txt", "0 0 Van 10 0 0 4 2 2 0 1 5 100\n0 1 Van ten 0\n");
  EXPECT_NE(runTool((dir / "bad_objects.txt").string() + " " + (dir / "tracks.csv").string(), &out),
            0);
  EXPECT_NE(out.find("bad_objects.txt:2"), std::string::npos) << out;
  writeFile(dir / "bad_tracks.csv", header + "1,0.1,3,1,x\n");
  EXPECT_NE(runTool((dir / "objects.txt").string() + " " + (dir / "bad_tracks.csv").string(), &out),
            0);
  EXPECT_NE(out.find("bad_tracks.csv:2"), std::string::npos) << out;
  EXPECT_NE(runTool((dir / "objects.txt").string()), 0);  // TRACKS missing
  fs::remove_all(dir);
}

// The extra variant counts only frames in which the target itself moves (speed_mps >= 0.5): a van
// flagged moving that waits 4 frames before driving off is missed there by any motion detector.
// The DESIGN hit rate is unchanged and still counts all 10 frames.
TEST(DetectionMetrics, ExtraHitRateOverMovingFramesOnly) {
  std::vector<GroundTruthObject> objects;
  std::vector<TrackRow> tracks;
  for (int f = 0; f < 10; ++f) {
    objects.push_back(object(f, 3, 10.0 + (f >= 4 ? 0.5 * (f - 4) : 0.0), 0.0, true));
    if (f < 4) objects.back().speed = 0.0;  // standing still
    if (f >= 5) tracks.push_back(row(f, 1, objects.back().center.x(), 0.0));
  }
  const auto s = scoreDetections(objects, tracks);
  ASSERT_EQ(s.targets.size(), 1u);
  const auto& t = s.targets[0];
  EXPECT_EQ(t.visible_frames, 10);
  EXPECT_EQ(t.hits, 5);
  EXPECT_NEAR(t.hitRate(), 0.5, 1e-12);
  EXPECT_EQ(t.moving_frames, 6);
  EXPECT_EQ(t.moving_hits, 5);
  EXPECT_NEAR(t.movingHitRate(), 5.0 / 6.0, 1e-12);
  EXPECT_NEAR(s.mean_hit_rate, 0.5, 1e-12);
  EXPECT_NEAR(s.mean_moving_hit_rate, 5.0 / 6.0, 1e-12);
  const std::string md = pcl_movers::eval::formatMarkdown(s);
  EXPECT_NE(md.find("extra (not the DESIGN metric)"), std::string::npos);
  EXPECT_NE(pcl_movers::eval::formatJson(s).find("\"extra_mean_moving_hit_rate\": 0.8333"),
            std::string::npos);
}

TEST(DetectionMetrics, FirstReportedCountsLabelledFramesOutsideTheScoredSector) {
  // A pedestrian labelled in frames 0-5 walks out of the 40 deg sector after frame 3 (like KITTI
  // 0000-a's): it is scored in frames 0-3 only, but a mover row at frame 5 reports it.
  std::vector<GroundTruthObject> objects;
  std::vector<TrackRow> tracks;
  for (int f = 0; f < 6; ++f) {
    const double x = 9.0 - 0.3 * f, y = -6.3 - 0.15 * f;  // -35 deg .. -43 deg
    objects.push_back(object(f, 2, x, y, true, 300, 0.0, "Pedestrian"));
    if (f >= 5) tracks.push_back(row(f, 36, x, y));
  }
  tracks.push_back(row(5, 40, 30.0, 0.0));  // a mover elsewhere: not on the target
  auto s = scoreDetections(objects, tracks);
  ASSERT_EQ(s.targets.size(), 1u);
  EXPECT_EQ(s.targets[0].visible_frames, 4);
  EXPECT_EQ(s.targets[0].hits, 0);
  EXPECT_EQ(s.targets[0].first_reported, 5);
  EXPECT_FALSE(s.targets[0].first_reported_visible);
  EXPECT_NE(pcl_movers::eval::formatMarkdown(s).find("5 (not scored there)"), std::string::npos);
  EXPECT_NE(pcl_movers::eval::formatJson(s).find("\"first_reported\": 5"), std::string::npos);

  // Reported inside the sector: the first hit is the first report.
  tracks.push_back(row(2, 36, objects[2].center.x(), objects[2].center.y()));
  s = scoreDetections(objects, tracks);
  EXPECT_EQ(s.targets[0].first_reported, 2);
  EXPECT_TRUE(s.targets[0].first_reported_visible);
  EXPECT_EQ(s.targets[0].first_hit, 2);

  // Never reported.
  tracks.clear();
  s = scoreDetections(objects, tracks);
  EXPECT_EQ(s.targets[0].first_reported, -1);
}

// ------------------------------------------------------------------ KITTI DontCare regions
namespace {

/** A camera looking along the sensor's +x: (x, y, z) -> pixel (50 - 100 y/x, 50 - 100 z/x). */
pcl_movers::eval::KittiCalibration forwardCamera() {
  pcl_movers::eval::KittiCalibration c;
  c.tr_velo_cam << 0, -1, 0, 0, 0, 0, -1, 0, 1, 0, 0, 0;
  c.r0_rect.setIdentity();
  c.p2 << 100, 0, 50, 0, 0, 100, 50, 0, 0, 0, 1, 0;
  return c;
}

/** DontCare box of frame 0 around pixel (60, 50), where the sensor point (10, -1, z≈0) lands. */
std::shared_ptr<const pcl_movers::eval::DontCareRegions> dontCareAhead() {
  return std::make_shared<const pcl_movers::eval::DontCareRegions>(
      forwardCamera(),
      std::map<int, std::vector<pcl_movers::eval::ImageBox>>{{0, {{55, 40, 65, 60}}}});
}

}  // namespace

TEST(DetectionMetrics, RowInADontCareBoxIsNeitherHitNorFalseAlarm) {
  // A target at (30, 8) in frames 0-1; mover rows: (10, -1) in frame 0's DontCare box, (10, 3)
  // outside it (pixel (20, 49)), (10, -1) again in frame 1 (no DontCare box there), and (-10, 1)
  // behind the camera: its pixel would be (60, 51) inside the box if the depth sign were ignored.
  std::vector<GroundTruthObject> objects = {object(0, 1, 30, 8, true), object(1, 1, 30, 8, true)};
  std::vector<TrackRow> tracks = {row(0, 5, 10, -1), row(0, 6, 10, 3), row(1, 5, 10, -1),
                                  row(0, 7, -10, 1)};
  DetectionMetricsParams p;
  p.sector_deg = 180;
  const auto counted = scoreDetections(objects, tracks, p);
  EXPECT_FALSE(counted.dont_care_used);
  EXPECT_EQ(counted.false_alarms, 4);
  EXPECT_EQ(counted.dont_care_ignored, 0);

  p.dont_care = dontCareAhead();
  const auto s = scoreDetections(objects, tracks, p);
  EXPECT_TRUE(s.dont_care_used);
  EXPECT_EQ(s.dont_care_ignored, 1);
  EXPECT_EQ(s.false_alarms, 3);
  EXPECT_EQ(s.mover_rows_in_sector, 4);
  EXPECT_EQ(s.targets[0].hits, 0);
  EXPECT_NEAR(s.false_alarms_per_frame, 1.5, 1e-12);
  EXPECT_NE(pcl_movers::eval::formatMarkdown(s).find("1 rows in KITTI DontCare regions ignored"),
            std::string::npos);
  const std::string js = pcl_movers::eval::formatJson(s);
  EXPECT_NE(js.find("\"dont_care\": true"), std::string::npos) << js;
  EXPECT_NE(js.find("\"dont_care_ignored\": 1"), std::string::npos) << js;
  EXPECT_NE(pcl_movers::eval::formatJson(counted).find("\"dont_care\": false"), std::string::npos);
}

TEST(DetectionMetrics, DontCareNeverTakesAHitNorExcusesALabelledStaticObject) {
  // KITTI's devkit matches detections to labelled objects first: a row on a target whose centre
  // projects into a DontCare box (the box overlaps the target in the image) stays a hit, and a
  // parked car declared moving stays a false alarm.
  DetectionMetricsParams p;
  p.dont_care = dontCareAhead();
  std::vector<GroundTruthObject> objects = {object(0, 1, 10, -1, true)};
  const auto hit = scoreDetections(objects, {row(0, 5, 10, -1)}, p);
  EXPECT_EQ(hit.targets[0].hits, 1);
  EXPECT_EQ(hit.dont_care_ignored, 0);
  objects[0].moving = false;
  const auto parked = scoreDetections(objects, {row(0, 5, 10, -1)}, p);
  EXPECT_EQ(parked.false_alarms, 1);
  EXPECT_EQ(parked.false_alarms_on_static_objects, 1);
  EXPECT_EQ(parked.dont_care_ignored, 0);
}

// ------------------------------------------------------------------ "why missed" diagnostics
TEST(DetectionMetrics, TrackedFramesFirstTrackedAndMedianSpeed) {
  // Target 4 in frames 0-9, too sparse to be visible in frames 0 and 1, speed_mps = frame number.
  // Any row (mover or not) on its grown box counts as tracked: a non-mover row in frames 1-9
  // except 5, where the row is 3 m beside the box; movers from frame 7.
  std::vector<GroundTruthObject> objects;
  std::vector<TrackRow> tracks;
  for (int f = 0; f < 10; ++f) {
    objects.push_back(object(f, 4, 20.0, 0.0, true, f < 2 ? 5 : 100));
    objects.back().speed = f;
    if (f >= 1) tracks.push_back(row(f, 8, 20.4, f == 5 ? 4.5 : 0.3, f >= 7));
    if (f >= 1 && f != 3) tracks.back().reason = f >= 7 ? "latched" : "no_motion";
  }
  objects.push_back(object(0, 9, 40.0, 0.0, true, 5));  // never visible
  const auto s = scoreDetections(objects, tracks);
  ASSERT_EQ(s.targets.size(), 2u);
  const auto& t = s.targets[0];
  EXPECT_EQ(t.visible_frames, 8);
  EXPECT_EQ(t.tracked_frames, 7);  // frames 2-9 but 5; frame 1 is not visible
  EXPECT_EQ(t.first_tracked, 2);
  EXPECT_EQ(t.hits, 3);
  EXPECT_NEAR(t.median_speed, 5.5, 1e-12);  // median of 2..9
  // Missed visible frames 2-6: the row's reason, "unknown" without one (3), "no row" (5).
  const std::map<std::string, int> missed = {{"no row", 1}, {"no_motion", 3}, {"unknown", 1}};
  EXPECT_EQ(t.missed_by_reason, missed);
  EXPECT_EQ(s.targets[1].tracked_frames, 0);
  EXPECT_EQ(s.targets[1].first_tracked, -1);
  EXPECT_TRUE(std::isnan(s.targets[1].median_speed));
  const std::string js = pcl_movers::eval::formatJson(s);
  EXPECT_NE(js.find("\"tracked_frames\": 7, \"first_tracked\": 2, \"median_speed\": 5.500"),
            std::string::npos)
      << js;
  EXPECT_NE(js.find("\"tracked_frames\": 0, \"first_tracked\": -1, \"median_speed\": null"),
            std::string::npos)
      << js;
  EXPECT_NE(js.find("\"missed_by_reason\": {\"no row\": 1, \"no_motion\": 3, \"unknown\": 1}"),
            std::string::npos)
      << js;
}

TEST(EvalTool, DontCareFlagsAndErrors) {
  if (!fs::exists(toolPath())) GTEST_SKIP() << "pcl_movers_eval not built at " << toolPath();
  const fs::path dir = fs::temp_directory_path() / "pcl_movers_eval_dontcare_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  writeFile(dir / "objects.txt", "0 0 Van 30 8 0 4 2 2 0 1 5 100\n");
  // One mover row at (10, -1, 0): pixel (60, 50) with the calib below, in the DontCare box.
  writeFile(dir / "tracks.csv",
            "frame,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,"
            "similarity,points\n0,0,3,1,10,-1,0,10,-1,0,5,0,5,4,2,2,0,0.9,80\n");
  writeFile(dir / "calib.txt",
            "P2: 100 0 50 0 0 100 50 0 0 0 1 0\nR0_rect: 1 0 0 0 1 0 0 0 1\n"
            "Tr_velo_cam: 0 -1 0 0 0 0 -1 0 1 0 0 0\n");
  writeFile(dir / "labels.txt",
            "0 -1 DontCare -1 -1 -10 55 40 65 60 -1000 -1000 -1000 -10 -1 -1 -1\n");
  const std::string base = (dir / "objects.txt").string() + " " + (dir / "tracks.csv").string();
  const std::string flags =
      " --dont-care " + (dir / "labels.txt").string() + " --calib " + (dir / "calib.txt").string();
  std::string out;
  ASSERT_EQ(runTool(base + flags + " --json " + (dir / "s.json").string(), &out), 0) << out;
  EXPECT_NE(out.find("0 in 1 frames, 0 on static objects; 1 rows in KITTI DontCare regions "
                     "ignored"),
            std::string::npos)
      << out;
  std::ifstream json(dir / "s.json");
  const std::string js((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
  EXPECT_NE(js.find("\"dont_care_ignored\": 1"), std::string::npos) << js;
  ASSERT_EQ(runTool(base, &out), 0) << out;  // no regions: the row is a false alarm
  EXPECT_NE(out.find("(1 in 1 frames, 0 on static objects)"), std::string::npos) << out;

  // One of the pair, contradicting switches, malformed files: non-zero exit naming the problem.
  EXPECT_NE(runTool(base + " --dont-care " + (dir / "labels.txt").string(), &out), 0);
  EXPECT_NE(out.find("--dont-care needs --calib"), std::string::npos) << out;
  EXPECT_NE(runTool(base + flags + " --no-dont-care", &out), 0);
  EXPECT_NE(out.find("--no-dont-care contradicts"), std::string::npos) << out;
  writeFile(dir / "bad_calib.txt", "P2: 100 0 50\n");
  EXPECT_NE(runTool(base + " --dont-care " + (dir / "labels.txt").string() + " --calib " +
                        (dir / "bad_calib.txt").string(),
                    &out),
            0);
  EXPECT_NE(out.find("bad_calib.txt:1: P2: expected 12 numbers"), std::string::npos) << out;
  writeFile(dir / "bad_labels.txt", "0 -1 DontCare -1 -1 -10 55 40 65\n");
  EXPECT_NE(runTool(base + " --dont-care " + (dir / "bad_labels.txt").string() + " --calib " +
                        (dir / "calib.txt").string(),
                    &out),
            0);
  EXPECT_NE(out.find("bad_labels.txt:1: expected 17 or 18 columns"), std::string::npos) << out;
  fs::remove_all(dir);
}

// With --sequence on the real KITTI folder its labels and calib are used by default (said on
// stderr); --no-dont-care counts the row in frame 0's DontCare box as a false alarm again.
TEST(EvalTool, SequenceFolderDontCareByDefault) {
  if (!fs::exists(toolPath())) GTEST_SKIP() << "pcl_movers_eval not built at " << toolPath();
  const std::string seq = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a";
  if (!fs::exists(seq + "/labels_kitti_tracking.txt"))
    GTEST_SKIP() << "KITTI data not found at " << seq << " (set PCL_MOVERS_SHARED_DATA)";
  const fs::path dir = fs::temp_directory_path() / "pcl_movers_eval_dontcare_seq_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  // (26.602, 13.848, -0.733) projects into frame 0's DontCare box (232, 202.5); no label there.
  writeFile(dir / "tracks.csv",
            "frame,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,"
            "similarity,points\n0,0,3,1,26.602,13.848,-0.733,0,0,0,5,0,5,4,2,2,0,0.9,80\n");
  const std::string base =
      seq + "/objects.txt " + (dir / "tracks.csv").string() + " --sequence " + seq;
  std::string out;
  ASSERT_EQ(runTool(base, &out), 0) << out;
  EXPECT_NE(out.find("DontCare: 122 KITTI DontCare boxes from " + seq), std::string::npos) << out;
  EXPECT_NE(out.find("| false alarms / frame | 0.0000 (0 in 77 frames, 0 on static objects; 1 "
                     "rows in KITTI DontCare regions ignored) |"),
            std::string::npos)
      << out;
  ASSERT_EQ(runTool(base + " --no-dont-care", &out), 0) << out;
  EXPECT_EQ(out.find("DontCare"), std::string::npos) << out;
  EXPECT_NE(out.find("(1 in 77 frames, 0 on static objects) |"), std::string::npos) << out;
  fs::remove_all(dir);
}
