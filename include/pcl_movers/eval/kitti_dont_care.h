/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace pcl_movers {
namespace eval {

/** \brief The KITTI calibration needed to project a sensor (velodyne) point into camera 2's image:
 * p_cam = Tr_velo_cam · [p; 1], p_rect = R0_rect · p_cam, [u·w, v·w, w] = P2 · [p_rect; 1]. */
struct KittiCalibration {
  Eigen::Matrix<double, 3, 4> tr_velo_cam = Eigen::Matrix<double, 3, 4>::Zero();
  Eigen::Matrix3d r0_rect = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 3, 4> p2 = Eigen::Matrix<double, 3, 4>::Zero();
};

/** \brief Reads a KITTI calib file: one `KEY: numbers` (or `KEY numbers`) line per matrix. Needs
 * `P2` (12 numbers), `R0_rect` or `R_rect` (9) and `Tr_velo_cam` or `Tr_velo_to_cam` (12); other
 * keys (P0, Tr_imu_velo, ...) are skipped. Throws InputError naming the file and line. */
KittiCalibration readKittiCalibration(const std::string& path);

/** \brief Projects sensor-frame point `p` into camera 2's image [pixels]. Returns false, leaving
 * `pixel` unchanged, when the point is not in front of the camera (z <= 0 after R0_rect). */
bool projectToImage(const KittiCalibration& calib, const Eigen::Vector3d& p,
                    Eigen::Vector2d& pixel);

/** \brief An axis-aligned image box [pixels], edges included. */
struct ImageBox {
  double x1 = 0, y1 = 0, x2 = 0, y2 = 0;
  bool contains(const Eigen::Vector2d& pixel) const {
    return pixel.x() >= x1 && pixel.x() <= x2 && pixel.y() >= y1 && pixel.y() <= y2;
  }
};

/** \brief Reads the `DontCare` rows of a KITTI tracking label file (`frame track_id type truncated
 * occluded alpha x1 y1 x2 y2 h w l x y z rotation_y [score]`): their image boxes by frame. Every
 * row is checked (17 or 18 columns, numbers where numbers belong, x1 <= x2 and y1 <= y2 for
 * DontCare); throws InputError naming the file and line. */
std::map<int, std::vector<ImageBox>> readKittiDontCareBoxes(const std::string& path);

/** \brief KITTI's DontCare regions of a sequence: a sensor-frame point of a frame is in them when
 * it projects (KittiCalibration) into one of that frame's DontCare image boxes. KITTI's benchmark
 * ignores a detection there: something is present but was not labelled (far or small objects,
 * crowds), so the detection is neither a hit nor a false alarm. */
class DontCareRegions {
 public:
  DontCareRegions() = default;
  DontCareRegions(const KittiCalibration& calib, std::map<int, std::vector<ImageBox>> boxes)
      : calib_(calib), boxes_(std::move(boxes)) {}

  /** \brief Reads the label file's DontCare rows and the calib file. */
  static DontCareRegions fromFiles(const std::string& labels_path, const std::string& calib_path);

  /** \brief Whether sensor-frame point `p` of `frame` projects into a DontCare box of that frame;
   * never for a point behind the camera. */
  bool contains(int frame, const Eigen::Vector3d& p) const;

  /** \brief Number of DontCare boxes over all frames. */
  std::size_t size() const;

  const KittiCalibration& calibration() const { return calib_; }

 private:
  KittiCalibration calib_;
  std::map<int, std::vector<ImageBox>> boxes_;
};

}  // namespace eval
}  // namespace pcl_movers
