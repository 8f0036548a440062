/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <gtest/gtest.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/mover_detector.h>
#include <pcl_movers/range_image_region_growing.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <set>

namespace {

using PointT = pcl::PointXYZI;
using Detector = pcl_movers::MoverDetector<PointT>;
using pcl_movers::io::GroundTruthObject;

/** Hits and false alarms of one frame, as DESIGN.md scores them (box grown by 1 m). */
struct Score {
  std::map<int, int> visible, hits;
  int false_alarms = 0;
  int static_alarms = 0;  ///< mover rows on ground-truth static objects
  void add(const std::vector<GroundTruthObject>& truth,
           const std::vector<pcl_movers::io::TrackRow>& rows, double sector_deg) {
    for (const auto& o : truth) {
      if (!o.moving || o.n_points < 10) continue;
      if (std::abs(std::atan2(o.center.y(), o.center.x())) > sector_deg * M_PI / 180) continue;
      ++visible[o.track_id];
      for (const auto& r : rows)
        if (r.mover && o.contains(Eigen::Vector3d(r.x, r.y, r.z), 1.0, 1.0)) {
          ++hits[o.track_id];
          break;
        }
    }
    for (const auto& r : rows) {
      if (!r.mover || std::abs(std::atan2(r.y, r.x)) > sector_deg * M_PI / 180) continue;
      bool matched = false, on_static = false;
      for (const auto& o : truth) {
        if (!o.contains(Eigen::Vector3d(r.x, r.y, r.z), 1.0, 1.0)) continue;
        (o.moving ? matched : on_static) = true;
      }
      false_alarms += !matched;
      static_alarms += on_static && !matched;
    }
  }
};

/** The first frames of the simulator's sample scene (an HDL-64E at 5 m/s, an oncoming car, a
 * van ahead, a crossing person), in memory. */
struct SampleFrames {
  std::vector<pcl::PointCloud<PointT>::Ptr> scans;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<double> times;
};

/** The first `frames` frames of `simulator`'s scene, in memory. */
SampleFrames simulateFrames(pcl_movers::sim::LidarSimulator& simulator, int frames) {
  SampleFrames f;
  for (int i = 0; i < frames; ++i) {
    f.scans.emplace_back(new pcl::PointCloud<PointT>);
    std::vector<std::uint32_t> labels;
    std::vector<GroundTruthObject> truth;
    Eigen::Isometry3d pose;
    simulator.simulate(i, *f.scans.back(), labels, truth, pose);
    f.poses.push_back(pose);
    f.times.push_back(simulator.time(i));
  }
  return f;
}

/** Every frame of the scenario given as YAML text (`name` in its error messages), in memory. */
SampleFrames simulateScenario(const std::string& yaml, const std::string& name) {
  const pcl_movers::sim::Scenario scenario = pcl_movers::sim::parseScenario(yaml, name);
  pcl_movers::sim::LidarSimulator simulator(scenario);
  return simulateFrames(simulator, scenario.frames);
}

SampleFrames simulateSample(int frames) {
  const std::string path = std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/sample.yaml";
  pcl_movers::sim::LidarSimulator simulator(pcl_movers::sim::loadScenario(path));
  return simulateFrames(simulator, frames);
}

/** Rows of a detector run over `f` with every pose moved by `offset`; the frames in `blind` get
 * a scan without a single return instead of theirs. */
std::vector<pcl_movers::io::TrackRow> detectRows(const SampleFrames& f,
                                                 const Eigen::Vector3d& offset,
                                                 const std::set<int>& blind = {}) {
  Detector detector;
  detector.setParameters(pcl_movers::DetectorParameters());
  pcl::PointCloud<PointT>::Ptr nothing(new pcl::PointCloud<PointT>);
  std::vector<pcl_movers::io::TrackRow> rows;
  for (std::size_t i = 0; i < f.scans.size(); ++i) {
    Eigen::Isometry3d pose = f.poses[i];
    pose.translation() += offset;
    Detector::FrameResult result;
    const bool is_blind = blind.count(static_cast<int>(i)) > 0;
    detector.process(is_blind ? nothing : f.scans[i], pose, f.times[i], static_cast<int>(i),
                     result);
    EXPECT_EQ(result.blind, is_blind) << "frame " << i;
    rows.insert(rows.end(), result.rows.begin(), result.rows.end());
  }
  return rows;
}

/** Frames of the sample scene as `sensor` records them, unorganized: no-return cells dropped, the
 * point order shuffled. */
SampleFrames simulateUnorganized(const pcl_movers::SensorModel& sensor, int frames) {
  SampleFrames f;
  const std::string path = std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/sample.yaml";
  pcl_movers::sim::LidarSimulator simulator(pcl_movers::sim::loadScenario(path));
  simulator.setSensor(sensor);
  std::mt19937 rng(3);
  for (int i = 0; i < frames; ++i) {
    pcl::PointCloud<PointT> organized;
    std::vector<std::uint32_t> labels;
    std::vector<GroundTruthObject> truth;
    Eigen::Isometry3d pose;
    simulator.simulate(i, organized, labels, truth, pose);
    f.scans.emplace_back(new pcl::PointCloud<PointT>);
    for (const auto& p : organized)
      if (std::isfinite(p.x)) f.scans.back()->push_back(p);
    std::shuffle(f.scans.back()->begin(), f.scans.back()->end(), rng);
    f.poses.push_back(pose);
    f.times.push_back(simulator.time(i));
  }
  return f;
}

/** Mover rows of a run over `f` with `params` (and `sensor` set on the detector when given). */
std::vector<pcl_movers::io::TrackRow> moverRows(const SampleFrames& f,
                                                const pcl_movers::DetectorParameters& params,
                                                const pcl_movers::SensorModel* sensor = nullptr) {
  Detector detector;
  if (sensor) detector.setSensorModel(*sensor);
  detector.setParameters(params);
  std::vector<pcl_movers::io::TrackRow> rows;
  for (std::size_t i = 0; i < f.scans.size(); ++i) {
    Detector::FrameResult result;
    detector.process(f.scans[i], f.poses[i], f.times[i], static_cast<int>(i), result);
    for (const auto& r : result.rows)
      if (r.mover) rows.push_back(r);
  }
  return rows;
}

/** Fraction of the rows of `a` with a row of `b` in the same frame within 1 m. */
double matchedFraction(const std::vector<pcl_movers::io::TrackRow>& a,
                       const std::vector<pcl_movers::io::TrackRow>& b) {
  int matched = 0;
  for (const auto& r : a)
    for (const auto& q : b)
      if (q.frame == r.frame && std::hypot(q.x - r.x, q.y - r.y) < 1.0) {
        ++matched;
        break;
      }
  return a.empty() ? 0.0 : double(matched) / double(a.size());
}

}  // namespace

// sensor "auto" (the default) on unorganized scans of the presets: the estimated layout is
// recognized and the detection is the preset's; on a sensor no preset describes the estimated
// layout is used and finds the same movers as the true layout.
TEST(MoverDetector, SensorAutoDetectsLikeTheRightLayout) {
  pcl_movers::DetectorParameters automatic;
  ASSERT_EQ(automatic.sensor, "auto");
  for (const char* name : {"vlp16", "hdl32", "os1_64"}) {
    SCOPED_TRACE(name);
    const SampleFrames frames = simulateUnorganized(pcl_movers::SensorModel::fromName(name), 15);
    pcl_movers::DetectorParameters preset;
    preset.sensor = name;
    const auto with_auto = moverRows(frames, automatic), with_preset = moverRows(frames, preset);
    EXPECT_GT(with_preset.size(), 5u) << "the scene's movers must be found";
    ASSERT_EQ(with_auto.size(), with_preset.size());
    for (std::size_t k = 0; k < with_auto.size(); ++k) {
      EXPECT_EQ(with_auto[k].track_id, with_preset[k].track_id);
      EXPECT_NEAR(with_auto[k].x, with_preset[k].x, 1e-3);
    }
  }
  // 40 uneven beams from +8° to -22°, 1500 columns: estimated, not recognized.
  std::vector<float> elevations;
  for (int k = 0; k < 40; ++k)
    elevations.push_back(static_cast<float>((8.0 - 0.55 * k - 0.0055 * k * k) * M_PI / 180));
  const pcl_movers::SensorModel custom(elevations, 1500);
  const SampleFrames frames = simulateUnorganized(custom, 15);
  const auto with_auto = moverRows(frames, automatic);
  const auto with_truth = moverRows(frames, automatic, &custom);
  ASSERT_GT(with_truth.size(), 5u);
  EXPECT_GE(matchedFraction(with_truth, with_auto), 0.8);
  EXPECT_GE(matchedFraction(with_auto, with_truth), 0.8);
}

// Geo-referenced poses (an INS's UTM coordinates): the same frames with every pose moved by
// (456789, 5432101, 250) m give the same tracks, their world columns moved by exactly that offset.
// In single precision a coordinate of 5.4e6 m keeps only 0.5 m: without the detector's local
// origin the tracks differ (ids, movers, positions by decimetres).
TEST(MoverDetector, GeoReferencedPosesGiveTheSameTracks) {
  const SampleFrames frames = simulateSample(20);
  const Eigen::Vector3d offset(456789.0, 5432101.0, 250.0);
  const auto local = detectRows(frames, Eigen::Vector3d::Zero());
  const auto utm = detectRows(frames, offset);
  ASSERT_EQ(local.size(), utm.size());
  ASSERT_GT(local.size(), 100u);
  int movers = 0;
  for (std::size_t k = 0; k < local.size(); ++k) {
    const auto &a = local[k], &b = utm[k];
    SCOPED_TRACE("row " + std::to_string(k) + " frame " + std::to_string(a.frame));
    ASSERT_EQ(a.frame, b.frame);
    ASSERT_EQ(a.track_id, b.track_id);
    EXPECT_EQ(a.mover, b.mover);
    movers += a.mover;
    EXPECT_EQ(a.points, b.points);
    for (const auto& [u, v] :
         {std::pair(a.x, b.x), std::pair(a.y, b.y), std::pair(a.z, b.z), std::pair(a.vx, b.vx),
          std::pair(a.vy, b.vy), std::pair(a.length, b.length), std::pair(a.width, b.width),
          std::pair(a.height, b.height), std::pair(a.yaw, b.yaw),
          std::pair(a.similarity, b.similarity)})
      EXPECT_NEAR(u, v, 1e-3);
    EXPECT_NEAR(b.wx - a.wx, offset.x(), 1e-3);
    EXPECT_NEAR(b.wy - a.wy, offset.y(), 1e-3);
    EXPECT_NEAR(b.wz - a.wz, offset.z(), 1e-3);
  }
  EXPECT_GT(movers, 10) << "the scene's movers must be found for the comparison to mean much";
}

// A scan without a single return (a covered sensor, a dropped batch of packets) is a frame with
// no observations: it returns no rows, the tracks coast through it, and a mover keeps its track.
TEST(MoverDetector, BlindFramesCoast) {
  const SampleFrames frames = simulateSample(24);
  const std::set<int> blind{12, 13};
  const auto all = detectRows(frames, Eigen::Vector3d::Zero());
  const auto gappy = detectRows(frames, Eigen::Vector3d::Zero(), blind);
  for (const auto& r : gappy) EXPECT_EQ(blind.count(r.frame), 0u) << "a row in a blind frame";
  // Mover tracks before the gap.
  std::map<int, int> before;  // track id → mover rows before the gap
  for (const auto& r : all)
    if (r.frame < 12 && r.mover) ++before[r.track_id];
  ASSERT_GE(before.size(), 2u) << "the scene's movers are found before the gap";
  // After the gap the same ids are reported as movers again, in most frames they were before.
  for (const auto& [id, n] : before) {
    int all_after = 0, gappy_after = 0;
    for (const auto& r : all) all_after += r.frame > 13 && r.mover && r.track_id == id;
    for (const auto& r : gappy) gappy_after += r.frame > 13 && r.mover && r.track_id == id;
    if (all_after == 0) continue;  // left the scene anyway
    EXPECT_GE(gappy_after, all_after - 2) << "track " << id << " lost across the blind frames";
  }
  // A scan with points but none finite is blind too, and so is the first frame.
  Detector detector;
  detector.setParameters(pcl_movers::DetectorParameters());
  pcl::PointCloud<PointT>::Ptr nan_scan(new pcl::PointCloud<PointT>);
  PointT nan_point;
  nan_point.x = nan_point.y = nan_point.z = std::numeric_limits<float>::quiet_NaN();
  nan_scan->resize(1000, nan_point);
  Detector::FrameResult result;
  EXPECT_NO_THROW(detector.process(nan_scan, Eigen::Isometry3d::Identity(), 0.0, 0, result));
  EXPECT_TRUE(result.blind);
  EXPECT_TRUE(result.rows.empty());
  EXPECT_TRUE(result.organized && result.organized->empty());
  // With sensor auto, an unorganized scan with too few returns to estimate the beam layout from
  // is blind too; the layout comes from the first scan that has enough.
  pcl::PointCloud<PointT>::Ptr sparse(new pcl::PointCloud<PointT>);
  for (int k = 0; k < 50; ++k) {
    PointT p;
    p.x = 10.f + 0.1f * float(k);
    p.y = 0.f;
    p.z = -1.7f;
    sparse->push_back(p);
  }
  Detector automatic;
  automatic.setParameters(pcl_movers::DetectorParameters());
  automatic.process(sparse, Eigen::Isometry3d::Identity(), 0.0, 0, result);
  EXPECT_TRUE(result.blind);
  EXPECT_NE(result.blind_reason.find("too few"), std::string::npos) << result.blind_reason;
  const SampleFrames vlp = simulateUnorganized(pcl_movers::SensorModel::vlp16(), 1);
  automatic.process(vlp.scans[0], vlp.poses[0], 0.1, 1, result);
  EXPECT_FALSE(result.blind);
  EXPECT_EQ(automatic.getSensorModel().name(), "vlp16");
}

TEST(MoverDetector, RejectsBadParameters) {
  Detector detector;
  auto params = pcl_movers::DetectorParameters();
  params.track.mode = "magic";
  EXPECT_THROW(detector.setParameters(params), pcl_movers::InputError);
  params = pcl_movers::DetectorParameters();
  params.decision.votes = params.decision.window + 1;
  EXPECT_THROW(detector.setParameters(params), pcl_movers::InputError);
  params = pcl_movers::DetectorParameters();
  params.segment.row_bridge = -0.1;
  EXPECT_THROW(detector.setParameters(params), pcl_movers::InputError);
  params.segment.row_bridge = 0.5;
  EXPECT_NO_THROW(detector.setParameters(params));
}

TEST(DetectorParameters, ConfigRoundTripAndErrors) {
  pcl_movers::DetectorParameters p;
  p.decision.speed = 2.5;
  p.track.mode = "centroid";
  const std::string path = std::string(PCL_MOVERS_BINARY_DIR) + "/test_detector_params.cfg";
  {
    std::ofstream f(path);
    f << "# comment\n\n" << p.toConfig();
  }
  pcl_movers::DetectorParameters q;
  q.readConfig(path);
  EXPECT_DOUBLE_EQ(q.decision.speed, 2.5);
  EXPECT_EQ(q.track.mode, "centroid");
  {
    std::ofstream f(path);
    f << "mover_speed = 1\nno_such_key = 3\n";
  }
  try {
    q.readConfig(path);
    FAIL() << "unknown key accepted";
  } catch (const pcl_movers::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(":2:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no_such_key"), std::string::npos) << e.what();
  }
  {
    std::ofstream f(path);
    f << "mover_speed = fast\n";
  }
  EXPECT_THROW(q.readConfig(path), pcl_movers::InputError);
  std::filesystem::remove(path);
}

// Stage keys, the flat keys of earlier versions, switches.
TEST(DetectorParameters, StageKeysLegacyKeysAndSwitches) {
  pcl_movers::DetectorParameters p;
  p.set("ground.distance", "0.2", "cli");
  p.set("ground.max-slope-deg", "12", "cli");  // the command line's kebab spelling
  p.set("mover_speed", "1.5", "cli");          // a flat key of earlier versions
  p.set("ground_local_slope", "0", "cli");
  p.set("decision.latch", "off", "cli");
  EXPECT_DOUBLE_EQ(p.ground.distance, 0.2);
  EXPECT_DOUBLE_EQ(p.ground.max_slope_deg, 12.0);
  EXPECT_DOUBLE_EQ(p.decision.speed, 1.5);
  EXPECT_FALSE(p.ground.local_slope);
  EXPECT_FALSE(p.decision.latch);
  EXPECT_EQ(pcl_movers::DetectorParameters::canonicalKey("free-space-lag"), "free_space.lag");
  EXPECT_THROW(p.set("decision.latch", "2", "cli"), pcl_movers::InputError);
  EXPECT_THROW(p.set("ground.distance_m", "1", "cli"), pcl_movers::InputError);
  // Every legacy key names a current key or a constant of a rule.
  auto names = p.keys();
  const auto settings = names.size();
  p.forEachConstant(
      [&](const std::string& key, const auto&, const char*) { names.push_back(key); });
  for (const auto& legacy : pcl_movers::DetectorParameters::legacyKeys())
    EXPECT_NE(std::find(names.begin(), names.end(), legacy.second), names.end()) << legacy.first;
  // Keys and constants are disjoint, and the constants are read in the config's own units.
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
  EXPECT_GT(names.size(), settings);
  // A constant set to its own value is ignored (old configs print every value); any other value
  // is an error naming the key, never silently a different run.
  p.set("registration.turn_yaw_step_deg", "5", "cli");
  p.set("max_registration_points", "100", "cli");  // a flat key of earlier versions
  EXPECT_DOUBLE_EQ(p.registration.turn_yaw_step_deg, 5.0);
  try {
    p.set("registration.turn_yaw_step_deg", "7", "cfg:3");
    FAIL() << "a constant changed through a config key";
  } catch (const pcl_movers::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cfg:3: 'registration.turn_yaw_step_deg' is no longer"),
              std::string::npos)
        << e.what();
  }
  EXPECT_DOUBLE_EQ(p.registration.turn_yaw_step_deg, 5.0);
  // The config round trip writes switches as true/false and reads them back.
  const std::string config = p.toConfig();
  EXPECT_NE(config.find("decision.latch = false"), std::string::npos);
  EXPECT_NE(config.find("ground.local_slope = false"), std::string::npos);
  // Range errors name the stage key.
  p.ground.max_slope_deg = 95;
  try {
    p.validate();
    FAIL() << "a 95 degree ground plane accepted";
  } catch (const pcl_movers::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ground.max_slope_deg"), std::string::npos) << e.what();
  }
}

// One source of defaults per stage: the ground filter and the region growing start from the
// structs the detector reads (the tools build their options from the same structs).
TEST(DetectorParameters, StageClassesStartFromTheDetectorDefaults) {
  const pcl_movers::DetectorParameters d;
  const pcl_movers::GroundParameters g =
      pcl_movers::GroundPlaneFilter<pcl::PointXYZI>().getParameters();
  EXPECT_NEAR(g.distance, d.ground.distance, 1e-6);
  EXPECT_NEAR(g.max_slope_deg, d.ground.max_slope_deg, 1e-4);
  EXPECT_NEAR(g.sensor_height, d.ground.sensor_height, 1e-6);
  EXPECT_EQ(g.sectors, d.ground.sectors);
  EXPECT_EQ(g.local_slope, d.ground.local_slope);
  EXPECT_NEAR(g.local_slope_deg, d.ground.local_slope_deg, 1e-4);
  EXPECT_NEAR(g.range_noise, d.ground.range_noise, 1e-6);
  EXPECT_NEAR(g.slope_band, d.ground.slope_band, 1e-6);
  const pcl_movers::SegmentationParameters s =
      pcl_movers::RangeImageRegionGrowing<pcl::PointXYZI>().getParameters();
  EXPECT_NEAR(s.depth_ratio, d.segment.depth_ratio, 1e-6);
  EXPECT_NEAR(s.depth_min, d.segment.depth_min, 1e-6);
  EXPECT_EQ(s.max_gap, d.segment.max_gap);
  EXPECT_NEAR(s.row_bridge, d.segment.row_bridge, 1e-6);
  EXPECT_EQ(s.min_cluster_points, d.segment.min_cluster_points);
  // setParameters() and getParameters() are inverse.
  pcl_movers::GroundParameters other;
  other.distance = 0.3;
  other.max_slope_deg = 7;
  other.local_slope = !other.local_slope;
  pcl_movers::GroundPlaneFilter<pcl::PointXYZI> filter;
  filter.setParameters(other);
  EXPECT_NEAR(filter.getDistanceThreshold(), 0.3f, 1e-6);
  EXPECT_NEAR(filter.getMaxTilt(), 7 * M_PI / 180, 1e-6);
  EXPECT_EQ(filter.getParameters().local_slope, other.local_slope);
}

namespace {

// Mover rows reporting another mover row's velocity to the last bit: a part of a larger mover
// (its track born as that mover's fragment) reports the mover's; two tracks' own filters never
// agree so exactly.
int moverRowsWithAnothersVelocity(const Detector::FrameResult& result) {
  int parts = 0;
  for (const auto& row : result.rows)
    parts += row.mover && std::any_of(result.rows.begin(), result.rows.end(), [&](const auto& r) {
               return r.mover && r.track_id != row.track_id && r.vx == row.vx && r.vy == row.vy &&
                      r.points > row.points;
             });
  return parts;
}

}  // namespace

// The simulator's sample scene (ego at 5 m/s, an oncoming car, a braking van, a crossing person,
// a parked car, a standing person, trees, a pole): movers found, statics never movers, labels and
// rows consistent.
TEST(MoverDetector, SimulatedSampleScene) {
  const std::string scenario_path =
      std::string(PCL_MOVERS_SOURCE_DIR) + "/data/scenarios/sample.yaml";
  if (!std::filesystem::exists(scenario_path)) GTEST_SKIP() << "no " << scenario_path;
  const auto scenario = pcl_movers::sim::loadScenario(scenario_path);
  pcl_movers::sim::LidarSimulator simulator(scenario);
  Detector detector;
  detector.setParameters(pcl_movers::DetectorParameters());
  Score score;
  int mover_points = 0, ground_points = 0, mover_parts = 0;
  for (int i = 0; i < simulator.getFrameCount(); ++i) {
    pcl::PointCloud<PointT>::Ptr scan(new pcl::PointCloud<PointT>);
    std::vector<std::uint32_t> labels;
    std::vector<GroundTruthObject> truth;
    Eigen::Isometry3d pose;
    simulator.simulate(i, *scan, labels, truth, pose);
    Detector::FrameResult result;
    detector.process(scan, pose, simulator.time(i), i, result);
    ASSERT_EQ(result.labels.size(), result.organized->size());
    ASSERT_EQ(result.rows.size(), result.cluster_indices.size());
    for (std::size_t k = 0; k < result.rows.size(); ++k) {
      const auto& row = result.rows[k];
      // Sensor and world centroids agree through the pose.
      const Eigen::Vector3d w = pose * Eigen::Vector3d(row.x, row.y, row.z);
      EXPECT_NEAR(w.x(), row.wx, 1e-3);
      EXPECT_NEAR(w.y(), row.wy, 1e-3);
      EXPECT_EQ(row.points, static_cast<int>(result.cluster_indices[k].indices.size()));
      // Its points carry its track, or, when it is a fragment of a mover, that mover's.
      for (const auto idx : result.cluster_indices[k].indices)
        if (result.track_ids[idx] != row.track_id) {
          ASSERT_FALSE(row.mover);
          ASSERT_EQ(result.labels[idx], Detector::kMover);
          ASSERT_TRUE(std::any_of(result.rows.begin(), result.rows.end(), [&](const auto& r) {
            return r.mover && r.track_id == result.track_ids[idx];
          }));
        }
    }
    mover_parts += moverRowsWithAnothersVelocity(result);
    for (const auto l : result.labels) {
      mover_points += l == Detector::kMover;
      ground_points += l == Detector::kGround;
    }
    score.add(truth, result.rows, 180.0);
  }
  EXPECT_GT(ground_points, 100000);
  EXPECT_GT(mover_points, 1000);
  // The oncoming car, passing close by, is tracked twice in two frames: a part split off it
  // (none without the rule).
  EXPECT_GT(mover_parts, 0);
  int visible = 0, hits = 0;
  for (const auto& v : score.visible) {
    visible += v.second;
    hits += score.hits[v.first];
  }
  ASSERT_GT(visible, 40);
  EXPECT_GT(double(hits) / visible, 0.6) << hits << " hits of " << visible;
  // No mover rows on static objects: the free-space test rejects the occlusion-edge and
  // coming-into-view drags of the registered reference point (8 rows in 40 frames without it).
  EXPECT_EQ(score.static_alarms, 0);
  EXPECT_EQ(score.false_alarms, 0);
}

// A VLP-16 (2° between beams) 1.73 m up sees a car crossing 36 m ahead with one beam: a slice a
// few centimetres tall at 1.1 m above the road, the beams below it reach the road in front. Its
// top above the ground under it is what the mover height test asks, not the slice's own extent:
// it becomes a mover with decision.standing_height, never without. (The free-space test is off
// here: a point on a sparse sensor's beam is judged with the beams around it, and the one below
// ends on the road in front of the car, so one beam's slice never shows free-space evidence.)
TEST(MoverDetector, CarSeenByOneBeamIsMeasuredFromTheGroundUnderIt) {
  const std::string yaml = R"(name: one_beam
seed: 3
frames: 40
rate_hz: 10
sensor: {preset: vlp16, height: 1.73, max_range: 80, range_noise: 0.0, dropout: 0.0}
terrain: {type: plane, height: 0, surface: terrain}
ego: {start: [0, 0], heading: 0, speed: 0}
movers:
  - {type: car, start: [36, -16], heading: 90, speed: 8}
)";
  const SampleFrames f = simulateScenario(yaml, "one_beam");
  double tallest_slice = 0;
  for (const auto& scan : f.scans) {
    float lo = 1e9f, hi = -1e9f;  // the car's returns (everything above the road)
    for (const auto& p : *scan)
      if (std::isfinite(p.z) && p.z > -1.5f) {
        lo = std::min(lo, p.z);
        hi = std::max(hi, p.z);
      }
    if (hi > lo) tallest_slice = std::max(tallest_slice, double(hi - lo));
  }
  ASSERT_LT(tallest_slice, 0.4) << "the scene no longer shows the car as one beam's slice";
  for (const bool standing : {true, false}) {
    pcl_movers::DetectorParameters params;
    params.decision.standing_height = standing;
    params.free_space.lag = 0;
    const auto rows = moverRows(f, params);
    int on_car = 0;
    for (const auto& r : rows) on_car += std::abs(r.x - 36.0) < 3.0;
    if (standing) {
      EXPECT_GE(on_car, 15) << "of 40 frames";
      EXPECT_EQ(on_car, static_cast<int>(rows.size())) << "a mover row off the car";
    } else {
      EXPECT_EQ(rows.size(), 0u);
    }
  }
}

// A person walks at 1 m/s 0.3 m in front of a wall 20 m ahead, another stands by it further on.
// Region growing joins both to the wall (their 0.6-0.9 m in depth are within its 0.05 · range
// rule at 20 m). The motion evidence splits the walker off as its own cluster (its space was seen
// empty 1.5 s earlier, the wall was seen where it is) and it becomes a mover; the standing person
// was seen where it stands, stays with the wall, and is never a mover.
TEST(MoverDetector, WalkerBesideAWallIsItsOwnClusterAndAMover) {
  const std::string yaml = R"(name: walker_by_wall
seed: 5
frames: 60
rate_hz: 10
sensor: {preset: hdl64, height: 1.8, max_range: 80, range_noise: 0.0, dropout: 0.0}
terrain: {type: plane, height: 0, surface: terrain}
ego: {start: [0, 0], heading: 0, speed: 0}
movers:
  - {type: person, start: [19.25, -6], heading: 90, speed: 1.0}
statics:
  - {type: wall, position: [20, 0], yaw: 90, size: [30, 0.3, 2.5]}
  - {type: person, position: [19.25, 5], yaw: 180}
)";
  const SampleFrames f = simulateScenario(yaml, "walker_by_wall");
  const auto walkerAt = [](int frame) { return Eigen::Vector2d(19.25, -6 + 0.1 * frame); };
  for (const bool split : {false, true}) {
    pcl_movers::DetectorParameters params;
    params.free_space.split = split;
    Detector detector;
    detector.setParameters(params);
    int own_frames = 0, mover_frames = 0, other_movers = 0;  // frames with a row on the walker
    for (std::size_t i = 0; i < f.scans.size(); ++i) {
      Detector::FrameResult result;
      detector.process(f.scans[i], f.poses[i], f.times[i], static_cast<int>(i), result);
      bool own = false, mover = false;
      for (const auto& r : result.rows) {
        const bool on_walker = (Eigen::Vector2d(r.x, r.y) - walkerAt(int(i))).norm() < 0.5;
        own = own || on_walker;
        mover = mover || (on_walker && r.mover);
        other_movers += !on_walker && r.mover;
      }
      own_frames += own && i >= 20;
      mover_frames += mover;
    }
    if (!split) {
      // The scene shows the problem: without the evidence the walker is part of the wall.
      EXPECT_LT(own_frames, 10) << "of 40 frames: the walker is no longer joined to the wall";
      continue;
    }
    EXPECT_GE(own_frames, 30) << "of 40 frames";
    EXPECT_GE(mover_frames, 20) << "of 60 frames";
    EXPECT_EQ(other_movers, 0) << "a mover row off the walker (the wall, the standing person)";
  }
}

// A forward-looking ladar's image covers a quarter turn: its first and last columns are 90° apart,
// and the two cars standing at its left and right edges are two objects, not one joined across
// the image's ends as a spinning sensor's seam would be.
TEST(MoverDetector, AForwardLookingImageDoesNotJoinItsTwoEdges) {
  const std::string yaml = R"(name: edges
seed: 5
frames: 2
rate_hz: 10
sensor: {preset: ladar2d, height: 1.8, max_range: 80, range_noise: 0.0, dropout: 0.0}
terrain: {type: plane, height: 0, surface: terrain}
ego: {start: [0, 0], heading: 0, speed: 0}
statics:
  - {type: car, position: [11.5, 11], yaw: 0}
  - {type: car, position: [11.5, -11], yaw: 0}
)";
  const SampleFrames f = simulateScenario(yaml, "edges");
  ASSERT_GT(f.scans[0]->height, 1u);  // organized: the detector takes its columns as they are
  Detector detector;
  detector.setParameters(pcl_movers::DetectorParameters());
  Detector::FrameResult result;
  for (std::size_t i = 0; i < f.scans.size(); ++i)
    detector.process(f.scans[i], f.poses[i], f.times[i], static_cast<int>(i), result);
  int left = 0, right = 0;
  for (const auto& r : result.rows) {
    left += r.y > 8;
    right += r.y < -8;
    EXPECT_GT(std::abs(r.y), 8) << "a row between the cars: the two edges joined";
  }
  EXPECT_EQ(left, 1);
  EXPECT_EQ(right, 1);
}

// Real KITTI frames: the moving van and cyclist become movers within a few frames, the parked van
// (track 3) never does.
TEST(MoverDetector, KittiVanAndCyclist) {
  const std::string folder = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a";
  if (!std::filesystem::is_directory(folder))
    GTEST_SKIP() << "KITTI data not found at " << folder << " (set PCL_MOVERS_SHARED_DATA)";
  pcl_movers::io::SequenceReader reader(folder);
  const auto truth = pcl_movers::io::readObjects(reader.objectsPath());
  Detector detector;
  detector.setParameters(pcl_movers::DetectorParameters());
  Score score;
  const std::size_t frames = std::min<std::size_t>(reader.size(), 25);
  for (std::size_t i = 0; i < frames; ++i) {
    pcl::PointCloud<PointT>::Ptr scan(new pcl::PointCloud<PointT>);
    reader.read(i, *scan);
    scan->sensor_origin_.setZero();
    scan->sensor_orientation_.setIdentity();
    Detector::FrameResult result;
    detector.process(scan, reader.pose(i), reader.time(i), static_cast<int>(i), result);
    std::vector<GroundTruthObject> now;
    for (const auto& o : truth)
      if (o.frame == static_cast<int>(i)) now.push_back(o);
    score.add(now, result.rows, 40.0);
  }
  // Van (0) and cyclist (1): visible in every frame; allow the confirmation delay.
  EXPECT_GE(score.hits[0], static_cast<int>(frames) - 7);
  EXPECT_GE(score.hits[1], static_cast<int>(frames) - 7);
  // The parked van (track 3) must never be a mover (5 of 25 frames before the free-space test,
  // while it comes into view at ~40 m).
  EXPECT_EQ(score.static_alarms, 0);
}

// The organizer, ground filter and segmenter are kept from frame to frame (their buffers and the
// organizer's row lookup are reused): every frame must still come out as from a fresh detector,
// whatever the earlier frames' sizes were, and a copied detector must run on its own objects.
TEST(MoverDetector, StageObjectsReusedAcrossFrames) {
  const std::string folder = std::string(PCL_MOVERS_SHARED_DATA) + "/kitti-tracking-0000-a";
  if (!std::filesystem::is_directory(folder))
    GTEST_SKIP() << "KITTI data not found at " << folder << " (set PCL_MOVERS_SHARED_DATA)";
  pcl_movers::io::SequenceReader reader(folder);
  const pcl_movers::DetectorParameters params;
  Detector detector;
  detector.setParameters(params);
  Detector copy;
  const std::size_t frames = std::min<std::size_t>(reader.size(), 6), copy_at = 3;
  const auto same_xyz = [](const PointT& a, const PointT& b) {
    const auto eq = [](float u, float v) { return u == v || (std::isnan(u) && std::isnan(v)); };
    return eq(a.x, b.x) && eq(a.y, b.y) && eq(a.z, b.z);
  };
  for (std::size_t i = 0; i < frames; ++i) {
    pcl::PointCloud<PointT>::Ptr scan(new pcl::PointCloud<PointT>);
    reader.read(i, *scan);
    scan->sensor_origin_.setZero();
    scan->sensor_orientation_.setIdentity();
    ASSERT_FALSE(scan->isOrganized() && scan->height > 1);  // so the organizer runs
    if (i == copy_at) copy = detector;
    Detector::FrameResult result, fresh_result, copy_result;
    detector.process(scan, reader.pose(i), reader.time(i), static_cast<int>(i), result);
    Detector fresh;
    fresh.setParameters(params);
    fresh.process(scan, reader.pose(i), reader.time(i), static_cast<int>(i), fresh_result);
    ASSERT_EQ(result.organized->size(), fresh_result.organized->size());
    for (std::size_t k = 0; k < result.organized->size(); ++k)
      ASSERT_TRUE(same_xyz((*result.organized)[k], (*fresh_result.organized)[k])) << i << " " << k;
    const auto objects = detector.removeGround(result.organized);
    EXPECT_EQ(*objects, *fresh.removeGround(result.organized)) << "frame " << i;
    const auto clusters = detector.segmentObjects(result.organized, objects);
    const auto fresh_clusters = fresh.segmentObjects(result.organized, objects);
    ASSERT_EQ(clusters.size(), fresh_clusters.size()) << "frame " << i;
    EXPECT_GT(clusters.size(), 10u);
    for (std::size_t c = 0; c < clusters.size(); ++c)
      EXPECT_EQ(clusters[c].indices, fresh_clusters[c].indices) << "frame " << i;
    EXPECT_EQ(result.clusters, static_cast<int>(clusters.size()));
    if (i >= copy_at) {
      // The copy organizes and segments with its own stage objects and continues the sequence
      // exactly as the original (own tracker models: same tracks, same rows).
      copy.process(scan, reader.pose(i), reader.time(i), static_cast<int>(i), copy_result);
      ASSERT_EQ(result.organized->size(), copy_result.organized->size());
      for (std::size_t k = 0; k < result.organized->size(); ++k)
        ASSERT_TRUE(same_xyz((*result.organized)[k], (*copy_result.organized)[k])) << i;
      EXPECT_EQ(*copy.removeGround(result.organized), *objects) << "frame " << i;
      ASSERT_EQ(result.rows.size(), copy_result.rows.size()) << "frame " << i;
      for (std::size_t r = 0; r < result.rows.size(); ++r) {
        EXPECT_EQ(result.rows[r].track_id, copy_result.rows[r].track_id);
        EXPECT_EQ(result.rows[r].mover, copy_result.rows[r].mover);
        EXPECT_DOUBLE_EQ(result.rows[r].vx, copy_result.rows[r].vx);
        EXPECT_DOUBLE_EQ(result.rows[r].similarity, copy_result.rows[r].similarity);
        EXPECT_EQ(result.cluster_indices[r].indices, copy_result.cluster_indices[r].indices);
      }
    }
  }
}
