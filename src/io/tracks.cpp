/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/tracks.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace pcl_movers {
namespace io {

namespace {
/** The headers before the `file` and the `reason` columns (read, so older tracks.csv files stay
 * readable). */
const char* kHeaderWithoutFile =
    "frame,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,similarity,"
    "points";
const char* kHeaderWithoutReason =
    "frame,file,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,"
    "similarity,points";
}  // namespace

const char* tracksCsvHeader() {
  return "frame,file,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,"
         "similarity,points,reason";
}

std::string formatTrackRow(const TrackRow& r) {
  char buf[512];
  std::snprintf(
      buf, sizeof(buf),
      "%d,%lld,%.3f,%d,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.2f,%.2f,%.2f,%.4f,"
      "%.3f,%d,%s",
      r.frame, r.file >= 0 ? r.file : static_cast<long long>(r.frame), r.time, r.track_id,
      r.mover ? 1 : 0, r.x, r.y, r.z, r.wx, r.wy, r.wz, r.vx, r.vy, r.speed, r.length, r.width,
      r.height, r.yaw, r.similarity, r.points, r.reason.c_str());
  return buf;
}

void writeTracks(const std::string& path, const std::vector<TrackRow>& rows) {
  std::ofstream out(path);
  if (!out) throw InputError(path, 0, "cannot write tracks file");
  out << tracksCsvHeader() << '\n';
  for (const auto& r : rows) out << formatTrackRow(r) << '\n';
  if (!out) throw InputError(path, 0, "write failed");
}

std::vector<TrackRow> readTracks(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open tracks file");
  std::string line;
  std::size_t line_no = 1;
  if (!std::getline(in, line)) throw InputError(path, 1, "empty file (expected a header row)");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const bool with_reason = line == tracksCsvHeader();
  const bool with_file = with_reason || line == kHeaderWithoutReason;
  if (!with_file && line != kHeaderWithoutFile)
    throw InputError(path, 1, std::string("unexpected header, expected: ") + tracksCsvHeader());
  const std::size_t columns = with_reason ? 21 : with_file ? 20 : 19;
  std::vector<TrackRow> rows;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (line.back() == ',') cells.emplace_back();  // an empty last cell (reason "")
    if (cells.size() != columns)
      throw InputError(path, line_no,
                       "expected " + std::to_string(columns) + " columns, found " +
                           std::to_string(cells.size()));
    TrackRow r;
    try {
      std::size_t k = 0;
      auto num = [&](void) {
        std::size_t used = 0;
        const double v = std::stod(cells[k], &used);
        if (used != cells[k].size() && cells[k].find_first_not_of(" \r", used) != std::string::npos)
          throw std::invalid_argument(cells[k]);
        if (!std::isfinite(v)) throw std::invalid_argument(cells[k]);
        ++k;
        return v;
      };
      r.frame = static_cast<int>(num());
      r.file = with_file ? static_cast<long long>(num()) : r.frame;
      r.time = num();
      r.track_id = static_cast<int>(num());
      const double mover = num();
      if (mover != 0.0 && mover != 1.0) throw std::invalid_argument("mover");
      r.mover = mover == 1.0;
      r.x = num();
      r.y = num();
      r.z = num();
      r.wx = num();
      r.wy = num();
      r.wz = num();
      r.vx = num();
      r.vy = num();
      r.speed = num();
      r.length = num();
      r.width = num();
      r.height = num();
      r.yaw = num();
      r.similarity = num();
      r.points = static_cast<int>(num());
      if (with_reason) r.reason = cells[k].substr(0, cells[k].find_last_not_of(" \r") + 1);
    } catch (const std::exception& e) {
      throw InputError(path, line_no, std::string("bad value '") + e.what() + "'");
    }
    rows.push_back(r);
  }
  return rows;
}

}  // namespace io
}  // namespace pcl_movers
