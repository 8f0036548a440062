/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/deskew.h>
#include <pcl_movers/io/point_times.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

namespace pcl_movers {

Eigen::Isometry3d sweepMotion(const StampedPose& frame, const StampedPose& other, double dt) {
  const double span = other.time - frame.time;
  if (!(std::abs(span) > 0))
    throw InputError("deskew: the two poses have the same time (" + std::to_string(frame.time) +
                     " s)");
  // Motion over |span| from the earlier pose to the later one, in the earlier one's frame; at
  // constant velocity it is also the motion from `frame` on over the same time.
  const Eigen::Isometry3d step =
      span > 0 ? frame.pose.inverse() * other.pose : other.pose.inverse() * frame.pose;
  const double s = dt / std::abs(span);
  const Eigen::AngleAxisd rotation(step.linear());
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = Eigen::AngleAxisd(s * rotation.angle(), rotation.axis()).toRotationMatrix();
  motion.translation() = s * step.translation();
  return motion;
}

template <typename PointT>
bool deskewScan(pcl::PointCloud<PointT>& cloud, const std::vector<float>& times,
                const StampedPose& frame, const StampedPose& other) {
  if (times.empty()) return false;
  if (times.size() != cloud.size())
    throw InputError("deskew: " + std::to_string(times.size()) + " point times for " +
                     std::to_string(cloud.size()) + " points");
  // Points of one column share a time: reuse the motion while the time does not change.
  float last = std::numeric_limits<float>::quiet_NaN();
  Eigen::Isometry3f motion = Eigen::Isometry3f::Identity();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    PointT& p = cloud.points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    if (times[i] != last) {
      last = times[i];
      motion = sweepMotion(frame, other, double(last)).cast<float>();
    }
    p.getVector3fMap() = motion * p.getVector3fMap();
  }
  return true;
}

template bool deskewScan<pcl::PointXYZ>(pcl::PointCloud<pcl::PointXYZ>&, const std::vector<float>&,
                                        const StampedPose&, const StampedPose&);
template bool deskewScan<pcl::PointXYZI>(pcl::PointCloud<pcl::PointXYZI>&,
                                         const std::vector<float>&, const StampedPose&,
                                         const StampedPose&);

ScanDeskewer::ScanDeskewer(const std::string& mode) : mode_(mode) {
  if (mode_ != "auto" && mode_ != "on" && mode_ != "off")
    throw InputError("parameter deskew: unknown mode '" + mode_ + "' (auto, on, off)");
}

bool ScanDeskewer::apply(const std::string& path, pcl::PointCloud<pcl::PointXYZI>& cloud,
                         const StampedPose& frame, const StampedPose& other) {
  if (mode_ == "off") return false;
  const bool pcd = std::filesystem::path(path).extension() == ".pcd";
  const std::vector<float> times = pcd ? io::readPointTimes(path) : std::vector<float>();
  if (times.empty()) {
    ++without_times_;
    if (mode_ == "on")
      throw InputError(path, 0, "--deskew on: no per-point time field (time, t or timestamp)");
    return false;
  }
  field_ = io::pointTimeField(path);
  if (!frame.valid || !other.valid) {
    ++without_poses_;
    if (mode_ == "on")
      throw InputError(path, 0, "--deskew on: needs the sequence's poses and more than one frame");
    return false;
  }
  if (times.size() != cloud.size())
    throw InputError(path, 0,
                     "deskew: " + std::to_string(times.size()) + " point times for " +
                         std::to_string(cloud.size()) + " points read");
  deskewScan(cloud, times, frame, other);
  ++deskewed_;
  return true;
}

std::string ScanDeskewer::toJson() const {
  std::ostringstream js;
  js << "{\"mode\": \"" << mode_ << "\", \"time_field\": \"" << field_
     << "\", \"frames\": " << deskewed_ << ", \"without_times\": " << without_times_
     << ", \"without_poses\": " << without_poses_ << "}";
  return js.str();
}

}  // namespace pcl_movers
