/*
 * Moving-object segmentation scoring (eval::scoreMos*, SemanticKITTI-MOS) and the per-point moving
 * labels of detections (io::moverClassFromBox, io::movingPointLabels).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/eval/mos_metrics.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/point_labels.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using pcl_movers::InputError;
using pcl_movers::io::makeLabel;
namespace eval = pcl_movers::eval;
namespace io = pcl_movers::io;

namespace {

class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/pcl_movers_mos_XXXXXX";
    path_ = mkdtemp(tmpl);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

/** The message of the InputError `f` throws ("" when it throws none). */
template <typename F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MosMetrics, MovingClasses) {
  EXPECT_FALSE(eval::isMovingClass(250));
  for (int c = 251; c <= 259; ++c) EXPECT_TRUE(eval::isMovingClass(std::uint16_t(c))) << c;
  EXPECT_FALSE(eval::isMovingClass(260));
  EXPECT_FALSE(eval::isMovingClass(10));
  EXPECT_FALSE(eval::isMovingClass(9));
}

TEST(MosMetrics, PerfectPredictionScoresOne) {
  // Instances and the exact moving / static class do not matter, only moving vs static.
  const std::vector<std::uint32_t> truth = {makeLabel(252, 3), makeLabel(254, 4), makeLabel(10, 5),
                                            makeLabel(40, 0), makeLabel(0, 0)};
  const std::vector<std::uint32_t> pred = {makeLabel(251, 7), makeLabel(253, 8), makeLabel(9, 0),
                                           makeLabel(9, 0), makeLabel(0, 0)};
  const eval::MosCounts c = eval::scoreMosFrame(truth, pred);
  EXPECT_EQ(c.tp(), 2u);
  EXPECT_EQ(c.fp(), 0u);
  EXPECT_EQ(c.fn(), 0u);
  EXPECT_EQ(c.unscored, 1u);
  EXPECT_DOUBLE_EQ(c.movingIou(), 1.0);
  EXPECT_DOUBLE_EQ(c.staticIou(), 1.0);
}

TEST(MosMetrics, KnownPartialCase) {
  // Ground truth: 4 moving, 6 static, 2 unlabeled (0) and 1 outlier (1), not scored whatever is
  // predicted there. Prediction: 2 of the moving found, 1 predicted static, 1 not labelled (0:
  // an FN too); 1 static point predicted moving, 1 not labelled.
  std::vector<std::uint32_t> truth, pred;
  auto add = [&](std::uint16_t t, std::uint16_t p) {
    truth.push_back(makeLabel(t, 1));
    pred.push_back(makeLabel(p, 2));
  };
  add(252, 252);
  add(254, 251);
  add(252, 9);
  add(258, 0);
  add(40, 252);
  add(40, 0);
  for (int k = 0; k < 4; ++k) add(50, 9);
  add(0, 252);
  add(0, 9);
  add(1, 252);
  const eval::MosCounts c = eval::scoreMosFrame(truth, pred);
  EXPECT_EQ(c.tp(), 2u);
  EXPECT_EQ(c.fp(), 1u);
  EXPECT_EQ(c.fn(), 2u);
  EXPECT_EQ(c.unscored, 3u);
  EXPECT_EQ(c.movingTruth(), 4u);
  EXPECT_EQ(c.staticTruth(), 6u);
  EXPECT_DOUBLE_EQ(c.movingIou(), 2.0 / 5.0);
  // Static: TP 4, FP 1 (moving predicted static), FN 2 (static predicted moving or 0).
  EXPECT_DOUBLE_EQ(c.staticIou(), 4.0 / 7.0);

  // Accumulated over frames, not averaged: a second frame with 1 TP and 3 FP.
  const std::vector<std::uint32_t> t2 = {makeLabel(252, 1), makeLabel(9, 0), makeLabel(9, 0),
                                         makeLabel(9, 0)};
  const std::vector<std::uint32_t> p2 = {makeLabel(252, 1), makeLabel(252, 1), makeLabel(252, 1),
                                         makeLabel(252, 1)};
  eval::MosCounts sum = c;
  sum += eval::scoreMosFrame(t2, p2);
  EXPECT_DOUBLE_EQ(sum.movingIou(), 3.0 / (3.0 + 4.0 + 2.0));

  // Nothing predicted: every moving point an FN; nothing moving and nothing predicted: no IoU.
  EXPECT_DOUBLE_EQ(eval::scoreMosFrame(truth, {}).movingIou(), 0.0);
  EXPECT_TRUE(std::isnan(eval::scoreMosFrame({makeLabel(9, 0)}, {makeLabel(9, 0)}).movingIou()));
}

TEST(MosMetrics, MismatchedCountsNameTheFile) {
  const std::string e = errorOf([] {
    eval::scoreMosFrame({makeLabel(9, 0), makeLabel(9, 0)}, {makeLabel(9, 0)}, "pred/000003.label");
  });
  EXPECT_NE(e.find("pred/000003.label"), std::string::npos) << e;
  EXPECT_NE(e.find("1 points"), std::string::npos) << e;
}

TEST(MosMetrics, Folders) {
  TempDir dir;
  fs::create_directories(dir / "gt");
  fs::create_directories(dir / "pred");
  io::writeLabels(dir / "gt/000000.label", {makeLabel(252, 1), makeLabel(9, 0), makeLabel(0, 0)});
  io::writeLabels(dir / "gt/000001.label", {makeLabel(254, 2), makeLabel(40, 0)});
  io::writeLabels(dir / "pred/000000.label", {makeLabel(252, 5), makeLabel(9, 0), makeLabel(9, 0)});
  io::writeLabels(dir / "pred/000001.label", {makeLabel(9, 0), makeLabel(251, 5)});
  io::writeLabels(dir / "pred/000002.label", {makeLabel(9, 0)});  // no ground truth: listed
  eval::MosScore s = eval::scoreMosFolders(dir / "gt", dir / "pred");
  ASSERT_EQ(s.frames.size(), 2u);
  EXPECT_EQ(s.frames[0].name, "000000");
  EXPECT_DOUBLE_EQ(s.frames[0].counts.movingIou(), 1.0);
  EXPECT_DOUBLE_EQ(s.frames[1].counts.movingIou(), 0.0);
  EXPECT_DOUBLE_EQ(s.total.movingIou(), 1.0 / 3.0);
  ASSERT_EQ(s.unmatched_predictions.size(), 1u);
  const std::string md = eval::formatMosMarkdown(s);
  EXPECT_NE(md.find("| moving | 33.3 | 1 | 1 | 1 | 2 |"), std::string::npos) << md;
  EXPECT_NE(eval::formatMosJson(s).find("\"name\": \"000001\""), std::string::npos);

  // A failed run (no prediction folder): everything moving missed.
  EXPECT_DOUBLE_EQ(eval::scoreMosFolders(dir / "gt", "").total.movingIou(), 0.0);

  // Point counts differ: the prediction file is named.
  io::writeLabels(dir / "pred/000001.label", {makeLabel(9, 0)});
  std::string e = errorOf([&] { eval::scoreMosFolders(dir / "gt", dir / "pred"); });
  EXPECT_NE(e.find(dir / "pred/000001.label"), std::string::npos) << e;
  EXPECT_NE(e.find("1 points"), std::string::npos) << e;
  // A frame not predicted: named.
  fs::remove(dir / "pred/000001.label");
  e = errorOf([&] { eval::scoreMosFolders(dir / "gt", dir / "pred"); });
  EXPECT_NE(e.find(dir / "pred/000001.label"), std::string::npos) << e;
  EXPECT_NE(e.find("missing"), std::string::npos) << e;
  // No ground truth at all; a folder that does not exist.
  fs::create_directories(dir / "empty");
  EXPECT_NE(errorOf([&] { eval::scoreMosFolders(dir / "empty", dir / "pred"); }), "");
  EXPECT_NE(errorOf([&] { eval::scoreMosFolders(dir / "gt", dir / "nope"); }).find(dir / "nope"),
            std::string::npos);
}

TEST(PointLabels, MoverClassFromBox) {
  EXPECT_EQ(io::moverClassFromBox(12.0, 2.5, 3.5), 258);  // lorry
  EXPECT_EQ(io::moverClassFromBox(2.5, 8.0, 3.5), 258);   // sides in either order
  EXPECT_EQ(io::moverClassFromBox(4.5, 1.8, 1.5), 252);   // car
  EXPECT_EQ(io::moverClassFromBox(5.2, 2.0, 2.2), 252);   // van
  EXPECT_EQ(io::moverClassFromBox(0.6, 0.5, 1.75), 254);  // person
  EXPECT_EQ(io::moverClassFromBox(1.8, 0.6, 1.7), 253);   // cyclist
  EXPECT_EQ(io::moverClassFromBox(1.9, 1.7, 1.4), 251);   // car seen from behind: unknown
  EXPECT_EQ(io::moverClassFromBox(0.8, 0.6, 0.5), 251);   // low fragment: unknown
  EXPECT_EQ(io::moverClassFromBox(2.0, 0.5, 0.9), 251);
}

TEST(PointLabels, MovingPointLabels) {
  io::TrackRow car, person, parked;
  car.track_id = 7;
  car.mover = true;
  car.length = 4.4, car.width = 1.8, car.height = 1.5;
  person.track_id = 70000;  // the instance keeps the low 16 bits
  person.mover = true;
  person.length = 0.5, person.width = 0.6, person.height = 1.8;
  parked.track_id = 3;
  parked.length = 4.4, parked.width = 1.8, parked.height = 1.5;
  const std::vector<bool> has_return = {false, true, true, true, true, false, true};
  const std::vector<int> mover = {-1, -1, 7, 70000, 12, 7, -1};
  const auto labels = io::movingPointLabels(has_return, mover, {car, person, parked});
  ASSERT_EQ(labels.size(), 7u);
  EXPECT_EQ(labels[0], 0u);
  EXPECT_EQ(labels[1], makeLabel(9, 0));
  EXPECT_EQ(labels[2], makeLabel(252, 7));
  EXPECT_EQ(labels[3], makeLabel(254, 70000 & 0xFFFF));
  EXPECT_EQ(labels[4], makeLabel(251, 12)) << "a mover without its row is of unknown class";
  EXPECT_EQ(labels[5], 0u) << "no return, whatever the track";
  EXPECT_EQ(labels[6], makeLabel(9, 0));
  EXPECT_THROW(io::movingPointLabels({true}, {}, {}), InputError);
}
