/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/eval/kitti_dont_care.h>

#include <Eigen/Geometry>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace pcl_movers {
namespace eval {

namespace {

std::vector<std::string> splitWords(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

/** Parses a whole word as a finite number; throws naming file, line and what was expected. */
double parseWord(const std::string& word, const std::string& path, std::size_t line,
                 const std::string& what) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(word.c_str(), &end);
  if (word.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
    throw InputError(path, line, what + ": expected a number, got '" + word + "'");
  return v;
}

/** The key of a calib line without its trailing ':', mapped to the canonical name. */
std::string calibKey(std::string key) {
  if (!key.empty() && key.back() == ':') key.pop_back();
  if (key == "R_rect") return "R0_rect";
  if (key == "Tr_velo_to_cam") return "Tr_velo_cam";
  return key;
}

}  // namespace

KittiCalibration readKittiCalibration(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open KITTI calib file");
  const std::map<std::string, std::size_t> sizes = {
      {"P2", 12}, {"R0_rect", 9}, {"Tr_velo_cam", 12}};
  std::map<std::string, std::vector<double>> values;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto words = splitWords(line);
    if (words.empty() || words[0][0] == '#') continue;
    const std::string key = calibKey(words[0]);
    const auto size = sizes.find(key);
    if (size == sizes.end()) continue;
    if (values.count(key)) throw InputError(path, line_no, key + " given twice");
    if (words.size() - 1 != size->second)
      throw InputError(path, line_no,
                       key + ": expected " + std::to_string(size->second) + " numbers, got " +
                           std::to_string(words.size() - 1));
    auto& v = values[key];
    for (std::size_t i = 1; i < words.size(); ++i)
      v.push_back(parseWord(words[i], path, line_no, key));
  }
  for (const auto& s : sizes)
    if (!values.count(s.first))
      throw InputError(path, 0, "no " + s.first + " line (needs P2, R0_rect and Tr_velo_cam)");
  KittiCalibration calib;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      calib.p2(r, c) = values["P2"][4 * r + c];
      calib.tr_velo_cam(r, c) = values["Tr_velo_cam"][4 * r + c];
    }
    for (int c = 0; c < 3; ++c) calib.r0_rect(r, c) = values["R0_rect"][3 * r + c];
  }
  return calib;
}

bool projectToImage(const KittiCalibration& calib, const Eigen::Vector3d& p,
                    Eigen::Vector2d& pixel) {
  const Eigen::Vector3d rect = calib.r0_rect * (calib.tr_velo_cam * p.homogeneous());
  if (!(rect.z() > 0)) return false;
  const Eigen::Vector3d image = calib.p2 * rect.homogeneous();
  if (!(image.z() > 0)) return false;
  pixel = image.head<2>() / image.z();
  return true;
}

std::map<int, std::vector<ImageBox>> readKittiDontCareBoxes(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open KITTI tracking label file");
  std::map<int, std::vector<ImageBox>> boxes;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto words = splitWords(line);
    if (words.empty() || words[0][0] == '#') continue;
    if (words.size() != 17 && words.size() != 18)
      throw InputError(path, line_no,
                       "expected 17 or 18 columns (frame track_id type truncated occluded alpha x1 "
                       "y1 x2 y2 h w l x y z rotation_y [score]), got " +
                           std::to_string(words.size()));
    std::vector<double> v(words.size());
    for (std::size_t i = 0; i < words.size(); ++i)
      if (i != 2) v[i] = parseWord(words[i], path, line_no, "column " + std::to_string(i + 1));
    if (v[0] < 0 || v[0] != std::floor(v[0]))
      throw InputError(path, line_no, "frame must be an integer >= 0, got '" + words[0] + "'");
    if (words[2] != "DontCare") continue;
    const ImageBox box{v[6], v[7], v[8], v[9]};
    if (box.x1 > box.x2 || box.y1 > box.y2)
      throw InputError(path, line_no, "DontCare box has x1 > x2 or y1 > y2");
    boxes[static_cast<int>(v[0])].push_back(box);
  }
  return boxes;
}

DontCareRegions DontCareRegions::fromFiles(const std::string& labels_path,
                                           const std::string& calib_path) {
  return DontCareRegions(readKittiCalibration(calib_path), readKittiDontCareBoxes(labels_path));
}

bool DontCareRegions::contains(int frame, const Eigen::Vector3d& p) const {
  const auto it = boxes_.find(frame);
  if (it == boxes_.end()) return false;
  Eigen::Vector2d pixel;
  if (!projectToImage(calib_, p, pixel)) return false;
  for (const auto& box : it->second)
    if (box.contains(pixel)) return true;
  return false;
}

std::size_t DontCareRegions::size() const {
  std::size_t n = 0;
  for (const auto& kv : boxes_) n += kv.second.size();
  return n;
}

}  // namespace eval
}  // namespace pcl_movers
