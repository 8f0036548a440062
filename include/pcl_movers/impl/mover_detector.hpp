/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/mover_detector.h>
#include <pcl_movers/mover_fragments.h>
#if __has_include(<pcl_movers/range_image_organizer.h>)
#include <pcl_movers/range_image_organizer.h>
#define PCL_MOVERS_HAVE_ORGANIZER 1
#endif
#include <pcl_movers/range_image_region_growing.h>
#include <pcl_movers/range_roughness.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace pcl_movers {

template <typename PointT>
const std::vector<std::string>& MoverDetector<PointT>::stageNames() {
  static const std::vector<std::string> names{"organize", "ground", "segment", "transform",
                                              "split",    "track",  "total"};
  return names;
}

template <typename PointT>
void MoverDetector<PointT>::setParameters(const DetectorParameters& parameters) {
  parameters.validate();
  parameters_ = parameters;
  tracker_.setParameters(parameters);
  reset();
  if (!has_sensor_model_ && parameters.sensor != "auto") {
    sensor_model_ = SensorModel::fromName(parameters.sensor);
    organizer_.object.reset();
  }
}

template <typename PointT>
Eigen::Isometry3d MoverDetector<PointT>::localPose(const Eigen::Isometry3d& world_pose) {
  if (!has_origin_) {
    origin_ = world_pose.translation();
    has_origin_ = true;
  }
  Eigen::Isometry3d local = world_pose;
  local.translation() -= origin_;
  return local;
}

template <typename PointT>
std::string MoverDetector<PointT>::blindReason(const PointCloudConstPtr& scan) {
  const auto finite = [](const PointT& pt) {
    return std::isfinite(pt.x) && std::isfinite(pt.y) && std::isfinite(pt.z);
  };
  // Only whether there is one: stops at the first finite point instead of reading all ~140k.
  if (!scan || std::none_of(scan->points.begin(), scan->points.end(), finite)) return "no return";
  if ((scan->isOrganized() && scan->height > 1) || has_sensor_model_ || sensor_model_.rows() > 0)
    return "";
  // "auto": the beam layout is estimated from the first scan that has enough returns for it.
  try {
    estimated_model_ = SensorModel::estimate(*scan);
    setSensorModel(SensorModel::recognize(estimated_model_));
  } catch (const InputError& e) {
    const auto returns = std::count_if(scan->points.begin(), scan->points.end(), finite);
    if (returns >= kMinReturnsToEstimate) throw;  // returns enough, but no beam structure
    return std::to_string(returns) + " returns, too few to estimate the beam layout from";
  }
  return "";
}

template <typename PointT>
void MoverDetector<PointT>::coast(const Eigen::Isometry3d& pose, double time, FrameResult& result) {
  result.blind = true;
  result.organized.reset(new PointCloud);
  if (parameters_.free_space.lag > 0) {
    free_space_.addBlindScan();  // keeps the map's frame lags in step with the frames
    tracker_.setFreeSpaceMap(&free_space_);
  } else {
    tracker_.setFreeSpaceMap(nullptr);
  }
  // No cluster: every track is predicted to `time` and counts a missed frame.
  tracker_.update(PointCloudConstPtr(new PointCloud), std::vector<Observation>(),
                  pose.translation(), time);
}

template <typename PointT>
typename MoverDetector<PointT>::PointCloudConstPtr MoverDetector<PointT>::organize(
    const PointCloudConstPtr& scan) {
  if (scan->isOrganized() && scan->height > 1) {
#ifdef PCL_MOVERS_HAVE_ORGANIZER
    full_turn_ = RangeImageOrganizer<PointT>::columnsCloseFullTurn(*scan);
#endif
    return scan;
  }
  if (!has_sensor_model_ && sensor_model_.rows() == 0)
    throw InputError("MoverDetector: no sensor model (process() estimates it first)");
  // The previous frame's range image is written over when neither the caller nor a stage holds
  // it any more: no allocation, page faults and construction of ~140k points per HDL-64E frame.
  if (ground_.object) ground_.object->setInputCloud(PointCloudConstPtr());
  if (segmenter_.object) segmenter_.object->setInputCloud(PointCloudConstPtr());
  PointCloudPtr organized = organized_buffer_.object;
  if (!organized || organized.use_count() > 2) {  // held elsewhere besides these two handles
    organized.reset(new PointCloud);
    organized_buffer_.object = organized;
  }
#ifdef PCL_MOVERS_HAVE_ORGANIZER
  // Kept between frames: its row lookup is built once per sensor model, not once per scan.
  if (!organizer_.object) {
    organizer_.object = std::make_shared<RangeImageOrganizer<PointT>>();
    organizer_.object->setSensorModel(sensor_model_);
  }
  organizer_.object->setInputCloud(scan);
  organizer_.object->organize(*organized);
  full_turn_ = organizer_.object->isFullTurn();
  input_indices_ = organizer_.object->getIndexImage();
#else
  // Plain projection onto the sensor model's grid, nearest return per cell.
  const int rows = sensor_model_.rows(), cols = sensor_model_.columns();
  PointT nan_point;
  nan_point.x = nan_point.y = nan_point.z = std::numeric_limits<float>::quiet_NaN();
  organized->points.assign(static_cast<std::size_t>(rows) * cols, nan_point);
  organized->width = cols;
  organized->height = rows;
  organized->is_dense = false;
  full_turn_ = sensor_model_.isFullRevolution();
  std::vector<float> best(organized->size(), std::numeric_limits<float>::max());
  input_indices_.assign(organized->size(), -1);
  for (std::size_t j = 0; j < scan->size(); ++j) {
    const auto& pt = (*scan)[j];
    if (!std::isfinite(pt.x) || !std::isfinite(pt.y) || !std::isfinite(pt.z)) continue;
    const float rxy = std::hypot(pt.x, pt.y);
    const int r = sensor_model_.rowOf(std::atan2(pt.z, rxy));
    const int c = sensor_model_.columnOf(std::atan2(pt.y, pt.x));
    if (r < 0 || c < 0) continue;
    const std::size_t k = static_cast<std::size_t>(r) * cols + c;
    const float range = rxy * rxy + pt.z * pt.z;
    if (range < best[k]) {
      best[k] = range;
      organized->points[k] = pt;
      input_indices_[k] = static_cast<int>(j);
    }
  }
#endif
  return organized;
}

template <typename PointT>
pcl::IndicesPtr MoverDetector<PointT>::removeGround(const PointCloudConstPtr& organized) {
  const auto& p = parameters_;
  if (!ground_.object) ground_.object = std::make_shared<GroundPlaneFilter<PointT>>();
  GroundPlaneFilter<PointT>& ground = *ground_.object;
  ground.setInputCloud(organized);
  ground.setParameters(p.ground);
  pcl::IndicesPtr objects(new pcl::Indices);
  ground.filter(*objects);
  return objects;
}

template <typename PointT>
std::vector<pcl::PointIndices> MoverDetector<PointT>::segmentObjects(
    const PointCloudConstPtr& organized, const pcl::IndicesPtr& objects) {
  const auto& p = parameters_;
  if (!segmenter_.object) segmenter_.object = std::make_shared<RangeImageRegionGrowing<PointT>>();
  RangeImageRegionGrowing<PointT>& segmenter = *segmenter_.object;
  segmenter.setInputCloud(organized);
  segmenter.setIndices(objects);
  segmenter.setParameters(p.segment);
  // The first and last columns are neighbours only when they close a full turn: a forward-looking
  // ladar's 90° image has its two edges a quarter turn apart, and objects at either edge were
  // joined into one cluster.
  segmenter.setWrapAround(full_turn_);
  std::vector<pcl::PointIndices> clusters;
  segmenter.segment(clusters);
  return clusters;
}

template <typename PointT>
void MoverDetector<PointT>::clustersToWorld(const PointCloud& organized,
                                            const std::vector<pcl::PointIndices>& clusters,
                                            const Eigen::Isometry3d& pose, PointCloud& world,
                                            std::vector<pcl::PointIndices>& world_clusters) {
  const Eigen::Isometry3f pose_f = pose.cast<float>();
  world.clear();
  world_clusters.assign(clusters.size(), pcl::PointIndices());
  std::size_t total = 0;
  for (const auto& c : clusters) total += c.indices.size();
  world.reserve(total);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    world_clusters[c].indices.reserve(clusters[c].indices.size());
    for (const auto i : clusters[c].indices) {
      PointT q = organized[i];
      q.getVector3fMap() = pose_f * q.getVector3fMap();
      world_clusters[c].indices.push_back(static_cast<int>(world.size()));
      world.push_back(q);
    }
  }
}

template <typename PointT>
void MoverDetector<PointT>::groundFloors(const PointCloud& world,
                                         const std::vector<pcl::PointIndices>& clusters,
                                         std::vector<Observation>& observations) {
  if (!ground_.object) return;
  const std::vector<float>& height = ground_.object->getPointHeights();
  std::vector<float>& under = ground_under_;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    under.clear();
    const auto& idx = clusters[c].indices;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const auto i = static_cast<std::size_t>(idx[k]);
      if (i < height.size() && std::isfinite(height[i]))
        under.push_back(world[observations[c].indices.indices[k]].z - height[i]);
    }
    if (under.empty()) continue;
    auto mid = under.begin() + static_cast<std::ptrdiff_t>(under.size() / 2);
    std::nth_element(under.begin(), mid, under.end());
    double& floor_z = observations[c].floor_z;
    if (!(*mid >= floor_z)) floor_z = *mid;  // the lower of ground and occluder floor
  }
}

template <typename PointT>
void MoverDetector<PointT>::splitMovingParts(const PointCloud& organized,
                                             const Eigen::Isometry3d& pose,
                                             std::vector<pcl::PointIndices>& clusters,
                                             const PointCloud& world,
                                             std::vector<pcl::PointIndices>& world_clusters) {
  const auto& p = parameters_;
  // The long lag (see MotionSplitter); in a sequence's first frames the oldest scan, once it is
  // at least the short lag back.
  const int lag =
      std::min(std::max(p.free_space.long_lag, p.free_space.lag), free_space_.size() - 1);
  if (lag < p.free_space.lag || lag < 1) return;
  MotionSplitter::Parameters sp;
  sp.min_points = p.segment.min_cluster_points;
  sp.max_gap = p.segment.max_gap;
  sp.depth_step = static_cast<float>(p.segment.depth_min);
  sp.min_through_fraction = static_cast<float>(p.free_space.long_min_fraction);
  splitter_.setParameters(sp);
  // Judged in lists: the points are gathered, and the map works through them in one pass.
  const auto judge = [&](std::size_t c, const std::vector<int>& positions,
                         std::vector<FreeSpaceMap::Sight>& sights) {
    const auto& world_idx = world_clusters[c].indices;
    split_points_.resize(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i)
      split_points_[i] =
          world[static_cast<std::size_t>(world_idx[static_cast<std::size_t>(positions[i])])]
              .getVector3fMap();
    free_space_.judge(split_points_, lag, sights);
  };
  const auto ranges = [&](std::size_t c, std::vector<float>& out) {
    const auto& idx = clusters[c].indices;
    out.resize(idx.size());
    for (std::size_t k = 0; k < idx.size(); ++k)
      out[k] = organized[static_cast<std::size_t>(idx[k])].getVector3fMap().norm();
  };
  const auto splits =
      splitter_.findSplits(static_cast<int>(organized.width), static_cast<int>(organized.height),
                           clusters, judge, ranges);
  // The world points stay where they are: only which cluster each belongs to changes, as it
  // does for the cluster's cells (world_clusters[c] holds cluster c's points in its order).
  splitter_.applySplits(splits, clusters);
  splitter_.applySplits(splits, world_clusters);
}

template <typename PointT>
void MoverDetector<PointT>::process(const PointCloudConstPtr& scan,
                                    const Eigen::Isometry3d& world_pose, double time, int frame,
                                    FrameResult& result) {
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };
  // Every float quantity below is relative to the origin (UTM-sized poses lose their centimetres
  // in single precision); world outputs get it back in double.
  const Eigen::Isometry3d pose = localPose(world_pose);

  result = FrameResult();
  result.frame = frame;
  result.time = time;
  timings_.clear();
  result.blind_reason = blindReason(scan);
  if (!result.blind_reason.empty()) {
    coast(pose, time, result);
    return;
  }

  const auto t0 = Clock::now();
  const PointCloudConstPtr organized = organize(scan);
  result.organized = organized;
  if (organized != scan) result.input_indices = input_indices_;

  const auto t1 = Clock::now();
  const pcl::IndicesPtr objects = removeGround(organized);  // the non-ground points

  const auto t2 = Clock::now();
  std::vector<pcl::PointIndices> clusters = segmentObjects(organized, objects);
  result.clusters = static_cast<int>(clusters.size());

  // World frame: only the cluster points are transformed (the rest is never used again).
  const auto t3 = Clock::now();
  PointCloudPtr world(new PointCloud);
  std::vector<pcl::PointIndices> world_clusters;
  clustersToWorld(*organized, clusters, pose, *world, world_clusters);

  // Tracking; the free-space map needs the current scan first (receding-object test).
  const auto t4 = Clock::now();
  auto split_start = t4, split_end = t4;  // motion-aware segmentation, timed on its own
  if (addToFreeSpaceMap(*organized, pose)) {
    split_start = Clock::now();
    if (parameters_.free_space.split)
      splitMovingParts(*organized, pose, clusters, *world, world_clusters);
    split_end = Clock::now();
  }
  std::vector<Observation> observations =
      describeClusters(*organized, *objects, clusters, pose, *world, std::move(world_clusters));
  splitMergedClusters(*world, time, clusters, observations);
  tracker_.update(world, observations, pose.translation(), time);
  const auto t5 = Clock::now();

  const std::vector<int> owner = assignFragments(*organized, clusters, poseYaw(pose));
  writeOutputs(*organized, *objects, clusters, owner, pose, result);
  const double split_ms = ms(split_start, split_end);
  timings_ = {{"organize", ms(t0, t1)},  {"ground", ms(t1, t2)}, {"segment", ms(t2, t3)},
              {"transform", ms(t3, t4)}, {"split", split_ms},    {"track", ms(t4, t5) - split_ms},
              {"total", ms(t0, t5)}};
}

template <typename PointT>
bool MoverDetector<PointT>::addToFreeSpaceMap(const PointCloud& organized,
                                              const Eigen::Isometry3d& pose) {
  const auto& p = parameters_;
  // (Re)bound every frame: a copied detector must not point into the original's map.
  if (!(p.free_space.lag > 0)) {
    tracker_.setFreeSpaceMap(nullptr);
    return false;
  }
  free_space_.setHistory(std::max(p.free_space.lag, p.free_space.long_lag) + 1);
  free_space_.setMargin(p.free_space.margin, p.free_space.margin_per_metre);
  free_space_.setNoReturnRange(p.free_space.no_return ? p.track.max_range : 0.0);
  // The height the ground filter started from (the estimate, unless one was set).
  free_space_.setSensorHeight(ground_.object ? ground_.object->getUsedSensorHeight()
                                             : p.ground.sensor_height);
  free_space_.setPoolOnAdd(p.free_space.split);  // the split judges every cluster
  free_space_.addScan(organized, pose);
  tracker_.setFreeSpaceMap(&free_space_);
  return true;
}

template <typename PointT>
std::vector<Observation> MoverDetector<PointT>::describeClusters(
    const PointCloud& organized, const pcl::Indices& objects,
    const std::vector<pcl::PointIndices>& clusters, const Eigen::Isometry3d& pose,
    const PointCloud& world, std::vector<pcl::PointIndices> world_clusters) {
  const auto& p = parameters_;
  std::vector<Observation> observations(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c)
    observations[c].indices = std::move(world_clusters[c]);
  // One labelling of the range image's cells serves the roughness and both occlusion tests below.
  if (p.track.occluded_fraction > 0 || p.decision.standing_height ||
      p.free_space.porous_roughness > 0)
    RangeImageRegionGrowing<PointT>::cellLabels(organized, objects, clusters, cell_labels_);
  // Porous objects (foliage) are seen through wherever they stand (MoverDecision::decide()).
  if (p.free_space.porous_roughness > 0 && segmenter_.object) {
    clusterRoughness(segmenter_.object->getCellRanges(), organized.width, cell_labels_.label,
                     clusters, roughness_);
    for (std::size_t c = 0; c < clusters.size(); ++c) observations[c].roughness = roughness_[c];
  }
  // Occluded cluster sides (range image, sensor frame): measurements there can slide.
  if (p.track.occluded_fraction > 0) {
    RangeImageRegionGrowing<PointT>::occludedSides(
        organized, cell_labels_, clusters, static_cast<float>(p.segment.depth_ratio),
        static_cast<float>(p.segment.depth_min), p.segment.max_gap,
        segmenter_.object && segmenter_.object->getWrapAround(),
        static_cast<float>(p.track.occluded_fraction), occluded_sides_);
    for (std::size_t c = 0; c < clusters.size(); ++c)
      observations[c].occluded = occluded_sides_[c] != 0;
  }
  // What each cluster stands on, as a world z (the mover height test, standingHeight()): the
  // lowest point of a nearer object hiding it from below, else the ground under it.
  if (!p.decision.standing_height) return observations;
  RangeImageRegionGrowing<PointT>::occluderFloors(
      organized, cell_labels_, clusters, static_cast<float>(p.segment.depth_ratio),
      static_cast<float>(p.segment.depth_min), p.segment.max_gap, 0.5f, floors_);
  for (std::size_t c = 0; c < clusters.size(); ++c)
    if (floors_[c] >= 0)
      observations[c].floor_z =
          (pose * organized[floors_[c]].getVector3fMap().template cast<double>()).z();
  groundFloors(world, clusters, observations);
  return observations;
}

template <typename PointT>
void MoverDetector<PointT>::splitMergedClusters(const PointCloud& world, double time,
                                                std::vector<pcl::PointIndices>& clusters,
                                                std::vector<Observation>& observations) {
  // Clusters holding objects of two tracks that move differently are split between them; the
  // sensor-frame clusters (outputs) follow the same split.
  const auto parts = tracker_.splitMergedClusters(world, observations, time);
  if (parts.empty()) return;
  observations = MoverTracker<PointT>::applyParts(parts, observations);
  clusters = MoverTracker<PointT>::applyParts(parts, clusters);
}

template <typename PointT>
std::vector<int> MoverDetector<PointT>::assignFragments(
    const PointCloud& organized, const std::vector<pcl::PointIndices>& clusters, double pose_yaw) {
  // Parts of a mover that region growing split off at a range step would be labelled static
  // though they move with it (the corpus: about a tenth of all moving points).
  const auto& cluster_results = tracker_.getClusterResults();
  std::vector<bool> mover(clusters.size(), false);
  std::vector<double> yaw(clusters.size(), 0.0);
  std::vector<int> born_part_of(clusters.size(), -1);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    mover[c] = cluster_results[c].track_id >= 0 && cluster_results[c].mover;
    yaw[c] = cluster_results[c].features.yaw - pose_yaw;  // world heading -> sensor frame
  }
  for (std::size_t f = 0; f < clusters.size(); ++f) {
    const auto* track = mover[f] ? tracker_.findTrack(cluster_results[f].track_id) : nullptr;
    if (!track || track->born_part_of < 0) continue;
    for (std::size_t m = 0; m < clusters.size(); ++m)
      if (mover[m] && cluster_results[m].track_id == track->born_part_of)
        born_part_of[f] = static_cast<int>(m);
  }
  std::vector<int> owner =
      findMoverFragments(organized, clusters, mover, yaw, parameters_.segment.max_gap,
                         static_cast<float>(parameters_.segment.fragment_margin),
                         segmenter_.object && segmenter_.object->getWrapAround(), born_part_of);
  tracker_.recordBirthOwners(owner);
  return owner;
}

template <typename PointT>
void MoverDetector<PointT>::writeOutputs(const PointCloud& organized, const pcl::Indices& objects,
                                         const std::vector<pcl::PointIndices>& clusters,
                                         const std::vector<int>& owner,
                                         const Eigen::Isometry3d& pose, FrameResult& result) const {
  const std::size_t n = organized.size();
  result.labels.assign(n, kUnlabelled);
  result.track_ids.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& pt = organized[i];
    if (std::isfinite(pt.x) && std::isfinite(pt.y) && std::isfinite(pt.z))
      result.labels[i] = kGround;
  }
  for (const auto i : objects) result.labels[i] = kUnlabelled;
  const Eigen::Isometry3d world_to_sensor = pose.inverse();
  const double pose_yaw = poseYaw(pose);
  const auto& cluster_results = tracker_.getClusterResults();
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const auto& cr = cluster_results[c];
    if (cr.track_id < 0) continue;
    const std::uint8_t label = cr.mover ? kMover : kStatic;
    for (const auto i : clusters[c].indices) {
      result.labels[i] = label;
      result.track_ids[i] = cr.track_id;
    }
    result.rows.push_back(trackRow(cr, world_to_sensor, pose_yaw, result.frame, result.time));
    result.cluster_indices.push_back(clusters[c]);
  }
  labelMoverFragments(clusters, owner, result);
}

template <typename PointT>
void MoverDetector<PointT>::labelMoverFragments(const std::vector<pcl::PointIndices>& clusters,
                                                const std::vector<int>& owner,
                                                FrameResult& result) const {
  const auto& cluster_results = tracker_.getClusterResults();
  std::vector<int> row_of(clusters.size(), -1);  // as writeOutputs() added them
  for (std::size_t c = 0, r = 0; c < clusters.size(); ++c)
    if (cluster_results[c].track_id >= 0) row_of[c] = static_cast<int>(r++);
  for (std::size_t f = 0; f < clusters.size(); ++f) {
    if (owner[f] < 0) continue;
    const auto m = static_cast<std::size_t>(owner[f]);
    if (cluster_results[f].track_id >= 0 && cluster_results[f].mover) {
      // A mover's part with a track of its own moves as the mover does: its row reports the
      // mover's velocity, the better estimate (on more points; the part's, often young, slides).
      // Its points keep their own track, as its row does.
      auto& row = result.rows[static_cast<std::size_t>(row_of[f])];
      const auto& by = result.rows[static_cast<std::size_t>(row_of[m])];
      row.vx = by.vx;
      row.vy = by.vy;
      row.speed = by.speed;
      continue;
    }
    for (const auto i : clusters[f].indices) {
      result.labels[i] = kMover;
      result.track_ids[i] = cluster_results[m].track_id;
    }
  }
}

template <typename PointT>
io::TrackRow MoverDetector<PointT>::trackRow(const typename MoverTracker<PointT>::ClusterResult& cr,
                                             const Eigen::Isometry3d& world_to_sensor,
                                             double pose_yaw, int frame, double time) const {
  io::TrackRow row;
  row.frame = frame;
  row.time = time;
  row.track_id = cr.track_id;
  row.mover = cr.mover;
  row.reason = moverReasonName(cr.reason);
  const Eigen::Vector3d local = world_to_sensor * cr.features.centroid;
  row.x = local.x();
  row.y = local.y();
  row.z = local.z();
  const Eigen::Vector3d world = cr.features.centroid + origin_;
  row.wx = world.x();
  row.wy = world.y();
  row.wz = world.z();
  row.vx = cr.velocity.x();
  row.vy = cr.velocity.y();
  row.speed = cr.velocity.norm();
  row.length = cr.features.length;
  row.width = cr.features.width;
  row.height = cr.features.height;
  // Box yaw in the sensor frame, like objects.txt.
  row.yaw = std::remainder(cr.features.yaw - pose_yaw, M_PI);
  row.similarity = cr.similarity;
  row.points = cr.features.points;
  return row;
}

}  // namespace pcl_movers
