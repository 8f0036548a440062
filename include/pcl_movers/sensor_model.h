/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/point_cloud.h>

#include <string>
#include <vector>

namespace pcl_movers {

/** \brief Geometry of a scanning LiDAR: one elevation per beam (row) and the azimuth sampling.
 *
 * Rows are ordered top to bottom (row 0 = highest elevation), columns by azimuth. For 360° sensors
 * column 0 looks backwards (azimuth +π) and azimuth decreases to the right with column index, as in
 * a range image seen from behind the sensor: column c covers azimuth
 * `azimuthMax() - (c + 0.5) * azimuthResolution()`. Angles are in radians, sensor frame x forward,
 * y left, z up.
 */
class SensorModel {
 public:
  SensorModel() = default;
  /** \param elevations beam elevations [rad], any order (stored top to bottom)
   * \param columns azimuth samples over the field of view
   * \param azimuth_min, azimuth_max horizontal field of view [rad] (-π, π for 360° sensors) */
  SensorModel(std::vector<float> elevations, int columns, float azimuth_min = -float(M_PI),
              float azimuth_max = float(M_PI), std::string name = "custom");

  /** \brief Velodyne HDL-64E as calibrated in KITTI: 64 beams, +1.94° to -25.0°, with the per-beam
   * vertical offsets of the lasers (0.21 m upper block, 0.12 m lower block) measured on KITTI
   * scans; 2200 columns (KITTI fires every ~0.18° with an extra half step every ~7 samples, up to
   * ~2150 samples per beam per turn: measured on 77 KITTI frames, 2200 columns keep 99.96 % of the
   * points in a cell of their own with RangeImageOrganizer, 2048 only 96.0 %; see
   * docs/benchmarks.md). Fitted on KITTI's 2011-09-26 drives; other KITTI days differ by ~0.01°. */
  static SensorModel hdl64();
  /** \brief Velodyne HDL-32E: 32 beams, +10.67° to -30.67° at the manual's vertical angles (4/3°
   * apart, rounded to 0.01°; PCL's HDLGrabber default table), 2048 columns. */
  static SensorModel hdl32();
  /** \brief Velodyne VLP-16: 16 beams, ±15°, 1800 columns. */
  static SensorModel vlp16();
  /** \brief Ouster OS1-64: 64 beams, ±16.6° uniform, 2048 columns. */
  static SensorModel os1_64();
  /** \brief A 2D-scanning ladar like the paper's: limited field of view (90° × 30°: azimuth ±45°,
   * elevation +10° to -20°, looking down at the road ahead), 60 rows, 360 columns, ~10 Hz. */
  static SensorModel ladar2d();
  /** \brief A preset by name: "hdl64", "hdl32", "vlp16", "os1_64", "ladar2d". Throws InputError. */
  static SensorModel fromName(const std::string& name);

  /** \brief Estimates the beam layout of a spinning sensor from one unorganized scan: beams are the
   * modes of the elevation histogram of points (for the vertical offset of the lasers that
   * maximizes the histogram's sharpness), then each beam's elevation and vertical offset are
   * refitted by least squares on the points nearest to it (a few rounds). Points nearer than 2 m
   * are ignored. Throws InputError when the cloud has too few valid points or no beam structure.
   * \param num_beams expected beams (0 = detect), \param columns azimuth columns (0 = estimated:
   * the beams' firings per turn + 2 %, see the implementation; 2048 for a narrow field of view). */
  template <typename PointT>
  static SensorModel estimate(const pcl::PointCloud<PointT>& cloud, int num_beams = 0,
                              int columns = 0);

  /** \brief The preset (hdl64, hdl32, vlp16, os1_64) that has every beam of `estimated` — each
   * within a quarter of the preset beam's spacing to its neighbours at 5 m and at 50 m, and at
   * least half the preset's beams (beams that see nothing, the upward ones in an open scene, are
   * missing from a scan and so from its estimate) — with that preset's
   * calibrated elevations and offsets, and its columns unless the estimate differs from them by
   * more than 5 % (an OS1-64 in 1024-column mode); `estimated` itself when none has. The
   * organized image, and so the detection, is then the same as with the preset: a grid shifted or
   * stretched by a fraction of a column changes which returns share a cell and, with that, a few
   * clusters (on KITTI city-22, estimated 2160 columns instead of 2200 gave two spurious movers).
   */
  static SensorModel recognize(const SensorModel& estimated);

  /** \brief Vertical offset [m] of each beam's origin above the sensor origin, top to bottom (all 0
   * unless set). A beam with elevation θ and offset h hits the points with z = ρ·tan θ + h, ρ the
   * horizontal distance: near points of a beam mounted off the origin do not share its elevation.
   */
  const std::vector<float>& verticalOffsets() const { return vertical_offsets_; }
  /** \brief Sets the per-beam vertical offsets [m], top to bottom (size rows()); throws InputError.
   */
  void setVerticalOffsets(std::vector<float> offsets);
  /** \brief Row of the beam that best explains a point at horizontal distance `rho` and height `z`
   * (vertical offsets taken into account), or -1 outside the beams by more than half a spacing. */
  int rowOfPoint(float rho, float z) const;

  const std::string& name() const { return name_; }
  int rows() const { return static_cast<int>(elevations_.size()); }
  int columns() const { return columns_; }
  /** \brief Beam elevations [rad], top to bottom. */
  const std::vector<float>& elevations() const { return elevations_; }
  float azimuthMin() const { return azimuth_min_; }
  float azimuthMax() const { return azimuth_max_; }
  float azimuthResolution() const { return (azimuth_max_ - azimuth_min_) / float(columns_); }
  /** \brief True when the azimuth field of view is a full turn (the range image wraps). */
  bool isFullRevolution() const;
  /** \brief Row of the beam nearest to `elevation` [rad], or -1 when further than half a beam
   * spacing outside the outermost beams. */
  int rowOf(float elevation) const;
  /** \brief Column of `azimuth` [rad] (wrapped for 360° sensors), -1 outside the field of view. */
  int columnOf(float azimuth) const;
  /** \brief Centre azimuth of column c [rad]. */
  float azimuthOf(int column) const {
    return azimuth_max_ - (float(column) + 0.5f) * azimuthResolution();
  }
  void setColumns(int columns) { columns_ = columns; }

 private:
  std::string name_ = "custom";
  std::vector<float> elevations_;
  std::vector<float> vertical_offsets_;
  int columns_ = 0;
  float azimuth_min_ = -float(M_PI);
  float azimuth_max_ = float(M_PI);
};

}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/sensor_model.hpp>
#endif
