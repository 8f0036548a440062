/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <string>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief One row of tracks.csv, as DESIGN.md defines it:
 * `frame,file,time,track_id,mover,x,y,z,wx,wy,wz,vx,vy,speed,length,width,height,yaw,similarity,
 * points`. frame: 0-based index in the sequence; file: the number in the input file's name
 * (000040.bin → 40; labelled clouds carry the same name), the index when the name has none.
 * x y z: centroid in the sensor frame of that frame; w*: the same in the world frame; v*: world
 * velocity [m/s]; length/width/height/yaw: the oriented box of the object's points. */
struct TrackRow {
  int frame = 0;
  double time = 0;
  int track_id = 0;
  bool mover = false;
  double x = 0, y = 0, z = 0;
  double wx = 0, wy = 0, wz = 0;
  double vx = 0, vy = 0, speed = 0;
  double length = 0, width = 0, height = 0, yaw = 0;
  double similarity = 0;
  int points = 0;
  long long file = -1;  ///< the input file's number; -1: unknown, written as `frame`
  /// Why it is, or is not, a mover: the decision test that settled it (moverReasonName(); "new"
  /// for a track seen once); "" when read from a tracks.csv without the column.
  std::string reason;
};

/** \brief The exact header line of tracks.csv. */
const char* tracksCsvHeader();
/** \brief Reads tracks.csv (also the older header without `file`: file = frame); throws InputError
 * naming file and line on a bad row or header. */
std::vector<TrackRow> readTracks(const std::string& path);
/** \brief Writes tracks.csv (header + rows, fixed precision so output is deterministic). */
void writeTracks(const std::string& path, const std::vector<TrackRow>& rows);
/** \brief Formats one row exactly as writeTracks() does (no newline). */
std::string formatTrackRow(const TrackRow& row);

}  // namespace io
}  // namespace pcl_movers
