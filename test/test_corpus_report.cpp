/*
 * Tests of the scene-corpus report: speed bands, why a target was missed, and the aggregation by
 * family, sensor, class and speed band.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/eval/corpus_report.h>

#include <gtest/gtest.h>

using namespace pcl_movers::eval;

namespace {

TargetScore target(int id, const std::string& type, int visible, int hits, int delay, int tracked,
                   double speed) {
  TargetScore t;
  t.track_id = id;
  t.type = type;
  t.visible_frames = visible;
  t.hits = hits;
  t.delay = delay;
  t.tracked_frames = tracked;
  t.median_speed = speed;
  return t;
}

CorpusRun run(const std::string& family, std::uint64_t seed, const std::string& sensor,
              const std::string& mode, int false_alarms, std::vector<TargetScore> targets) {
  CorpusRun r;
  r.family = family;
  r.seed = seed;
  r.sensor = sensor;
  r.mode = mode;
  r.frames = 100;
  r.ok = true;
  r.score.false_alarms = false_alarms;
  r.score.targets = std::move(targets);
  return r;
}

/** The table row that starts with "| key |" in the section under `heading`. */
std::string row(const std::string& report, const std::string& heading, const std::string& key) {
  const std::size_t section = report.find(heading);
  if (section == std::string::npos) return "";
  const std::size_t at = report.find("\n| " + key + " |", section);
  if (at == std::string::npos) return "";
  return report.substr(at + 1, report.find('\n', at + 1) - at - 1);
}

}  // namespace

TEST(CorpusReport, SpeedBands) {
  EXPECT_EQ(speedBand(0.6), "< 1 m/s");
  EXPECT_EQ(speedBand(1.0), "1-2 m/s");
  EXPECT_EQ(speedBand(4.9), "2-5 m/s");
  EXPECT_EQ(speedBand(15.0), "5-15 m/s");
  EXPECT_EQ(speedBand(30.0), "> 15 m/s");
  EXPECT_EQ(speedBand(NAN), "< 1 m/s");
}

TEST(CorpusReport, WhyMissed) {
  EXPECT_EQ(missReason(target(1, "Car", 50, 0, -1, 0, 5), true), "never its own object");
  EXPECT_EQ(missReason(target(1, "Car", 50, 0, -1, 30, 5), true), "tracked, never a mover");
  auto failing = target(1, "Car", 50, 0, -1, 30, 5);
  failing.missed_by_reason = {{"no row", 30}, {"young", 5}, {"no_free_space", 15}};
  EXPECT_EQ(missReason(failing, true), "tracked, never a mover: no_free_space");
  EXPECT_EQ(missReason(target(1, "Car", 50, 20, 25, 30, 5), true, 10), "late (25 frames)");
  EXPECT_EQ(missReason(target(1, "Car", 50, 10, 2, 30, 5), true), "intermittent");
  EXPECT_EQ(missReason(target(1, "Car", 50, 40, 2, 45, 5), true), "missed 10 frames");
  EXPECT_EQ(missReason(target(1, "Car", 50, 40, 2, 45, 5), false), "run failed");
}

TEST(CorpusReport, AggregatesByFamilySensorClassAndSpeed) {
  std::vector<CorpusRun> runs = {
      run("highway", 2, "hdl64", "registration", 5,
          {target(1, "Car", 100, 100, 2, 100, 30), target(2, "Pedestrian", 10, 0, -1, 0, 0.8)}),
      run("urban", 4, "vlp16", "registration", 1, {target(1, "Car", 50, 25, 4, 50, 8)}),
      run("highway", 2, "hdl64", "centroid", 20, {target(1, "Car", 100, 50, 2, 100, 30)}),
  };
  // Moving points of the registration runs: highway TP 30, FP 10, FN 10 (60 %); urban TP 10,
  // FN 30 (25 %); pooled TP 40, FP 10, FN 40 (44.4 %). The centroid run was not scored.
  runs[0].has_mos = runs[1].has_mos = true;
  runs[0].mos.moving_as_moving = 30;
  runs[0].mos.static_as_moving = 10;
  runs[0].mos.moving_as_static = 10;
  runs[0].mos.static_as_static = 1000;
  runs[1].mos.moving_as_moving = 10;
  runs[1].mos.moving_as_none = 30;
  // Missed frames by reason, registration only: urban 15 without a row and 10 young, highway's
  // pedestrian 10 without a row; the centroid run's are not counted.
  runs[1].score.targets[0].missed_by_reason = {{"no row", 15}, {"young", 10}};
  runs[0].score.targets[1].missed_by_reason = {{"no row", 10}};
  runs[2].score.targets[0].missed_by_reason = {{"no_motion", 50}};
  CorpusReportOptions options;
  const std::string report = formatCorpusReport(runs, options);
  // Overall, registration: targets 100 %, 0 %, 50 % → mean 50.0; FA 6 in 200 frames.
  EXPECT_NE(row(report, "### Overall", "all").find("| 3 | 50.0 | 0.030 | 44.4 |"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("| moving IoU % |"), std::string::npos) << report;
  // By family: highway 100 % and 0 % → 50.0, 5 FA / 100 frames; centroid 20 / 100.
  EXPECT_NE(row(report, "### By family", "highway").find("| 50.0 | 0.050 | 60.0 | 2.0 | 1 |"),
            std::string::npos)
      << report;
  EXPECT_NE(row(report, "### By family", "highway").find("| 0.200 | – |"), std::string::npos);
  EXPECT_NE(row(report, "### By sensor", "vlp16").find("| 50.0 | 0.010 | 25.0 |"),
            std::string::npos);
  const std::string json = formatCorpusJson(runs);
  EXPECT_NE(json.find("\"mos\": {\"tp\": 30, \"fp\": 10, \"fn\": 10, \"moving_iou\": 0.6,"),
            std::string::npos)
      << json;
  EXPECT_NE(row(report, "### By class", "Pedestrian").find("| 0.0 |"), std::string::npos);
  EXPECT_NE(row(report, "### By speed band", "> 15 m/s").find("| 100.0 |"), std::string::npos);
  EXPECT_NE(row(report, "### By speed band", "< 1 m/s").find("| 0.0 |"), std::string::npos);
  const std::string why = "### Why visible frames were missed";
  EXPECT_NE(report.find("| family | missed frames | no row | young |", report.find(why)),
            std::string::npos)
      << report;
  EXPECT_EQ(row(report, why, "urban"), "| urban | 25 | 60.0 | 40.0 |") << report;
  EXPECT_EQ(row(report, why, "highway"), "| highway | 10 | 100.0 | 0.0 |") << report;
  EXPECT_EQ(row(report, why, "all"), "| all | 35 | 71.4 | 28.6 |") << report;
  // The worst target first: the pedestrian, never its own object.
  const std::size_t worst = report.find("worst targets");
  ASSERT_NE(worst, std::string::npos);
  EXPECT_NE(report.find("| highway-2 | hdl64 | 2 | Pedestrian |", worst), std::string::npos);
  EXPECT_NE(report.find("never its own object", worst), std::string::npos);
  EXPECT_EQ(report.find("Failed runs"), std::string::npos);
}

TEST(CorpusReport, FailedRunsAreListed) {
  CorpusRun failed =
      run("trail", 6, "ladar2d", "registration", 0, {target(3, "Cyclist", 20, 0, -1, 0, 4)});
  failed.ok = false;
  failed.error = "exit 1: frame 7: no finite point";
  const std::string report = formatCorpusReport({failed}, CorpusReportOptions());
  EXPECT_NE(report.find("| trail-6 | registration | exit 1: frame 7: no finite point |"),
            std::string::npos);
  EXPECT_NE(report.find("run failed"), std::string::npos);
  EXPECT_NE(formatCorpusJson({failed}).find("\"ok\": false"), std::string::npos);
}
