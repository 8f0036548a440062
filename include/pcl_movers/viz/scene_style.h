/*
 * Scene geometry and colouring for the pcl_movers viewer, kept free of VTK so it lives in the core
 * library and can be unit-tested without a display: what colour each point gets, where boxes,
 * velocity arrows and trails go, and which pixel a sensor-frame point lands on for a camera preset.
 * The viewer tool (apps/pcl_movers_viewer.cpp) only turns these into VTK actors.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>
#include <pcl_movers/io/ground_truth.h>
#include <pcl_movers/io/tracks.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pcl_movers {
namespace viz {

/** \brief An 8-bit RGB colour. */
struct Color {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Color& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Color& o) const { return !(*this == o); }
};

/** \brief The viewer's colour scheme. Movers get the only saturated warm colours so they stand out
 * against the dimmed ground and the cool per-track colours of stationary clusters. */
struct SceneStyle {
  Color background{16, 18, 24};
  Color ground{58, 60, 66};              ///< dimmed: ground is context, not content
  Color unassigned_low{105, 110, 120};   ///< non-ground points outside every box, low ...
  Color unassigned_high{190, 195, 205};  ///< ... to high (height shading gives depth cues)
  Color mover_points{255, 32, 16};       ///< points of a mover: strong red
  Color mover_box{255, 150, 0};          ///< box, arrow and trail of a mover: orange
  Color ground_truth{255, 60, 255};      ///< ground-truth boxes: magenta
  Color selected{255, 255, 60};          ///< the selected track's box: yellow
  Color text{235, 235, 235};
};

/** \brief A stable colour for a stationary track: cool hues (green-cyan-blue) only, so no
 * stationary cluster can be mistaken for a mover or for ground truth (magenta); neighbouring ids
 * get well separated hues. */
Color trackColor(int track_id);

/** \brief What a point is, for colouring. */
enum class PointClass : std::uint8_t { Unassigned = 0, Ground = 1, Static = 2, Mover = 3 };

/** \brief An oriented box: centre, size along its own axes (length along yaw), yaw about z. */
struct OrientedBox {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double length = 0, width = 0, height = 0;
  double yaw = 0;

  /** \brief The box of a tracks.csv row: its oriented box placed at the sensor-frame centroid. */
  static OrientedBox fromTrack(const io::TrackRow& row);
  /** \brief The box of an objects.txt row. */
  static OrientedBox fromGroundTruth(const io::GroundTruthObject& object);
  /** \brief Corners: 0-3 the bottom face counter-clockwise from (-l/2, -w/2), 4-7 the top face. */
  std::array<Eigen::Vector3d, 8> corners() const;
  /** \brief Whether p lies inside the box grown by `margin` on every side. */
  bool contains(const Eigen::Vector3d& p, double margin = 0.0) const;
};

/** \brief Coloured line segments: the viewer draws all boxes, arrows and trails of a frame as one
 * VTK actor built from this. */
struct LineSet {
  struct Segment {
    Eigen::Vector3f a, b;
    Color color;
  };
  std::vector<Segment> segments;

  void addSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Color& color);
  /** \brief The 12 edges of a box. */
  void addBox(const OrientedBox& box, const Color& color);
  /** \brief A shaft from `from` to `to` and a two-stroke head at `to` in the plane containing the
   * shaft and z (so it is visible from the chase and bird's-eye cameras). Nothing when shorter than
   * 1 cm. */
  void addArrow(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Color& color);
  /** \brief Consecutive points joined. */
  void addPolyline(const std::vector<Eigen::Vector3d>& points, const Color& color);
  std::size_t size() const { return segments.size(); }
};

/** \brief Marks ground points with a height-above-local-minimum test on a 2D grid: a point is
 * ground when it is within `tolerance` of the lowest point of its cell and the 8 neighbouring
 * cells. Only for display when no labelled clouds are given — the detector uses GroundPlaneFilter.
 * NaN points are not ground. */
template <typename PointT>
std::vector<bool> estimateGroundMask(const pcl::PointCloud<PointT>& cloud, double cell_size = 1.0,
                                     double tolerance = 0.25);

/** \brief Per-point class and track id (-1 = none). */
struct PointLabels {
  std::vector<PointClass> classes;
  std::vector<int> track_ids;
};

/** \brief Labels points from the tracks of this frame: a non-ground point inside a track's box
 * (grown by `margin`) belongs to that track; rows with no box size fall back to the nearest
 * centroid within `fallback_radius`. Ground wins over boxes (the road under a car is ground). */
template <typename PointT>
PointLabels labelPointsFromTracks(const pcl::PointCloud<PointT>& cloud,
                                  const std::vector<bool>& ground_mask,
                                  const std::vector<io::TrackRow>& frame_rows, double margin = 0.3,
                                  double fallback_radius = 1.0);

/** \brief The boxes to draw for the rows of a frame. tracks.csv gives a box's size and yaw but
 * places it at the points' centroid, which lies on the visible side of an object, so a box drawn
 * there sticks out on the far side. Where a row's points are known (labels from a labelled cloud,
 * live detection, or points inside the grown box) the box is re-centred on the middle of their
 * extent along the box axes, as the detector measured it, and grown to cover them; rows with
 * fewer than 3 points keep the centroid. */
template <typename PointT>
std::vector<OrientedBox> fitTrackBoxes(const pcl::PointCloud<PointT>& cloud,
                                       const PointLabels& labels,
                                       const std::vector<io::TrackRow>& frame_rows);

/** \brief Colour of every point: ground dimmed, movers red, stationary tracks by trackColor(),
 * unassigned grey shaded by height. `movers` lists the track ids that are movers in this frame. */
template <typename PointT>
std::vector<Color> colorPoints(const pcl::PointCloud<PointT>& cloud, const PointLabels& labels,
                               const std::vector<int>& movers, const SceneStyle& style = {});

/** \brief Camera presets of the viewer (keys 1/2/3). */
enum class CameraPreset { Chase = 0, Bird = 1, Free = 2 };
/** \brief "chase", "bird" (also "free" when `allow_free`); throws InputError otherwise. */
CameraPreset parseCameraPreset(const std::string& name, bool allow_free = false);
const char* cameraPresetName(CameraPreset preset);

/** \brief A pinhole camera as VTK defines it (vertical field of view, aspect from the image). */
struct CameraView {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d focal = Eigen::Vector3d::UnitX();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  double fov_y_deg = 45.0;
};

/** \brief The camera of a preset in the sensor frame: chase = behind and above the ego vehicle,
 * looking ahead; bird = straight down, forward (x) at the top of the image. Free returns chase. */
CameraView cameraView(CameraPreset preset);

/** \brief Pixel (column, row from the top-left) where sensor-frame point p appears in a
 * width × height image of `camera`; nullopt when p is behind the camera or off the image. */
std::optional<Eigen::Vector2d> projectToPixel(const CameraView& camera, const Eigen::Vector3d& p,
                                              int width, int height);

/** \brief Inclusive frame range. */
struct FrameRange {
  std::size_t first = 0, last = 0;
};
/** \brief Parses "A:B", "A:", ":B" or "A" (0-based, inclusive) against a sequence of `frames`
 * frames; throws InputError naming the option when malformed, reversed or out of range. */
FrameRange parseFrameRange(const std::string& text, std::size_t frames);

/** \brief Parses "WxH" (16..8192 each); throws InputError when malformed. */
std::pair<int, int> parseImageSize(const std::string& text);

/** \brief tracks.csv rows indexed by frame and by track. */
class TrackIndex {
 public:
  TrackIndex() = default;
  explicit TrackIndex(std::vector<io::TrackRow> rows);

  bool empty() const { return rows_.empty(); }
  /** \brief Rows of one frame, sorted by track id (empty when none). */
  const std::vector<io::TrackRow>& frame(int frame) const;
  /** \brief Highest frame number present (-1 when empty). */
  int lastFrame() const;
  /** \brief Up to `length` past world positions of `track_id` up to and including `frame`
   * (oldest first), mapped into the sensor frame with `world_to_sensor`. Positions from frames
   * more than `length` frames back are left out, so a trail never spans a long gap. */
  std::vector<Eigen::Vector3d> trail(int track_id, int frame, int length,
                                     const Eigen::Isometry3d& world_to_sensor) const;
  /** \brief The same trail from the rows' sensor-frame centroids: used when the sequence has no
   * poses and none can be fitted, so only meaningful for a nearly stationary ego vehicle. */
  std::vector<Eigen::Vector3d> sensorTrail(int track_id, int frame, int length) const;

 private:
  std::vector<io::TrackRow> rows_;
  std::map<int, std::vector<io::TrackRow>> by_frame_;
  std::map<int, std::vector<io::TrackRow>> by_track_;  // each sorted by frame
};

/** \brief The sensor→world pose of a frame fitted to its rows' (x,y,z) ↔ (wx,wy,wz) pairs (rigid,
 * least squares). Needs 3 rows whose centroids are not collinear; nullopt otherwise. Lets the
 * viewer draw trails for detections of sequences without poses.txt. */
std::optional<Eigen::Isometry3d> fitSensorPose(const std::vector<io::TrackRow>& frame_rows);

/** \brief The velocity arrow of a row in the sensor frame: from its centroid to where it will be
 * in `seconds` (world velocity rotated into the sensor frame). */
std::pair<Eigen::Vector3d, Eigen::Vector3d> velocityArrow(const io::TrackRow& row,
                                                          const Eigen::Isometry3d& sensor_to_world,
                                                          double seconds = 1.0);

/** \brief The next track id after `current` among the rows (wrapping; movers are visited
 * first), or -1 when there are no rows. Used by the Tab key. */
int nextSelectedTrack(const std::vector<io::TrackRow>& frame_rows, int current);

/** \brief The overlay text: frame (with `file`, the number in its file's name, when >= 0: as
 * tracks.csv's `frame` and `file`), time, number of movers, selected track and its speed. */
std::string overlayText(std::size_t frame, std::size_t frames, double time, int movers,
                        const io::TrackRow* selected, const std::string& extra = "",
                        long long file = -1);

}  // namespace viz
}  // namespace pcl_movers

#ifdef PCL_NO_PRECOMPILE
#include <pcl_movers/viz/impl/scene_style.hpp>
#endif
