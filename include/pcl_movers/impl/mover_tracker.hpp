/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/mover_tracker.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

namespace pcl_movers {

template <typename PointT>
typename MoverTracker<PointT>::ClusterFeatures MoverTracker<PointT>::computeFeatures(
    const PointCloud& cloud, const pcl::Indices& indices) {
  ClusterFeatures f;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double sxx = 0, sxy = 0, syy = 0;
  double min_z = std::numeric_limits<double>::max(), max_z = -min_z;
  int n = 0;
  for (const auto i : indices) {
    const auto& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    sum += Eigen::Vector3d(p.x, p.y, p.z);
    min_z = std::min<double>(min_z, p.z);
    max_z = std::max<double>(max_z, p.z);
    ++n;
  }
  f.points = n;
  if (n == 0) return f;
  f.centroid = sum / n;
  for (const auto i : indices) {
    const auto& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const double dx = p.x - f.centroid.x(), dy = p.y - f.centroid.y();
    sxx += dx * dx;
    sxy += dx * dy;
    syy += dy * dy;
  }
  // Principal horizontal axis: the long side of a car seen from any side dominates the spread.
  f.yaw = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  const double c = std::cos(f.yaw), s = std::sin(f.yaw);
  double min_u = std::numeric_limits<double>::max(), max_u = -min_u, min_v = min_u, max_v = -min_u;
  for (const auto i : indices) {
    const auto& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const double dx = p.x - f.centroid.x(), dy = p.y - f.centroid.y();
    const double u = c * dx + s * dy, v = -s * dx + c * dy;
    min_u = std::min(min_u, u);
    max_u = std::max(max_u, u);
    min_v = std::min(min_v, v);
    max_v = std::max(max_v, v);
  }
  f.length = max_u - min_u;
  f.width = max_v - min_v;
  f.min_z = min_z;
  f.max_z = max_z;
  f.height = max_z - min_z;
  return f;
}

template <typename PointT>
MoverTracker<PointT>::MoverTracker(const MoverTracker& other) {
  *this = other;
}

template <typename PointT>
MoverTracker<PointT>& MoverTracker<PointT>::operator=(const MoverTracker& other) {
  if (this == &other) return *this;
  // Every member but the work buffers (registration_, view_*, gate_, to_register_), which each
  // tracker keeps its own.
  parameters_ = other.parameters_;
  tracks_ = other.tracks_;
  results_ = other.results_;
  next_id_ = other.next_id_;
  registrations_ = other.registrations_;
  has_time_ = other.has_time_;
  last_time_ = other.last_time_;
  decision_ = other.decision_;
  motion_ = other.motion_;
  for (auto& t : tracks_)
    if (t.model) t.model.reset(new SurfaceDensity(*t.model));
  return *this;
}

template <typename PointT>
const typename MoverTracker<PointT>::Track* MoverTracker<PointT>::findTrack(int id) const {
  for (const auto& t : tracks_)
    if (t.id == id) return &t;
  return nullptr;
}

template <typename PointT>
void MoverTracker<PointT>::recordBirthOwners(const std::vector<int>& owner) {
  for (std::size_t c = 0; c < owner.size() && c < results_.size(); ++c) {
    if (owner[c] < 0 || results_[c].track_id < 0) continue;
    for (auto& t : tracks_)
      if (t.id == results_[c].track_id && t.age == 0)  // born in this update
        t.born_part_of = results_[static_cast<std::size_t>(owner[c])].track_id;
  }
}

template <typename PointT>
void MoverTracker<PointT>::reset() {
  tracks_.clear();
  results_.clear();
  next_id_ = 0;
  registrations_ = 0;
  has_time_ = false;
}

template <typename PointT>
void MoverTracker<PointT>::ensurePoints(const PointCloud& cloud, const pcl::PointIndices& indices,
                                        Candidate& candidate) const {
  if (candidate.points) return;
  candidate.points.reset(new PointCloud);
  // Registration cost grows with the number of points (one Gaussian each), while the density of a
  // near object is already smooth with a few hundred: keep an even subsample.
  const std::size_t n = indices.indices.size();
  const std::size_t cap =
      static_cast<std::size_t>(std::max(1, parameters_.registration.max_points));
  const double stride = n > cap ? static_cast<double>(n) / cap : 1.0;
  candidate.points->reserve(std::min(n, cap));
  for (double k = 0; k < n; k += stride) {
    const auto& p = cloud[indices.indices[static_cast<std::size_t>(k)]];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
      candidate.points->push_back(p);
  }
}

template <typename PointT>
SurfaceDensity::Ptr MoverTracker<PointT>::makeModel(const Candidate& candidate,
                                                    const Eigen::Vector3d& sensor_origin) const {
  const auto& p = parameters_;
  SurfaceDensity::Ptr model(new SurfaceDensity(p.registration.cells_xy, p.registration.cells_xy,
                                               p.registration.cells_z,
                                               static_cast<float>(p.registration.resolution),
                                               static_cast<float>(p.registration.resolution_z)));
  model->setSigmaPerMetre(static_cast<float>(p.registration.sigma_per_metre));
  model->setMinSigma(static_cast<float>(p.registration.min_sigma));
  model->compute(*candidate.points, sensor_origin.template cast<float>(),
                 candidate.features.centroid.template cast<float>());
  return model;
}

template <typename PointT>
bool MoverTracker<PointT>::registerCandidate(const Track& track, Candidate& candidate,
                                             const Eigen::Vector2d& predicted, double search_radius,
                                             const Eigen::Vector3d& sensor_origin, Match& match) {
  const auto& p = parameters_;
  ++registrations_;
  registration_.setInputSource(candidate.points);
  registration_.setTargetDensity(track.model);
  registration_.setSensorOrigin(sensor_origin.template cast<float>());
  registration_.setResolution(static_cast<float>(p.registration.resolution));
  registration_.setSearchRadius(static_cast<float>(search_radius));
  registration_.setYawSamples(p.registration.yaw_samples);
  registration_.setSigmaPerMetre(static_cast<float>(p.registration.sigma_per_metre));
  registration_.setMinSigma(static_cast<float>(p.registration.min_sigma));
  registration_.setMinSimilarity(static_cast<float>(p.registration.min_similarity));
  // Views are built for the assigned matches only (buildView()).
  registration_.setComputeSourceDensity(false);
  // The guess turns the view by the track's model yaw about the predicted reference point and
  // moves that point onto the model centre; heights stay (objects move on the ground, the grid
  // is 2.8 m tall).
  const Eigen::Vector3f centre = track.model->getCentre();
  const Eigen::Matrix2f turn = Eigen::Rotation2Df(static_cast<float>(track.model_yaw)).matrix();
  const Eigen::Vector2f from = predicted.template cast<float>();
  Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
  guess.template topLeftCorner<2, 2>() = turn;
  guess.template block<2, 1>(0, 3) = centre.template head<2>() - turn * from;
  PointCloud aligned;
  registration_.align(aligned, guess);
  bool found = registration_.hasConverged() &&
               registration_.getSimilarity() >= p.registration.min_similarity;
  // A turning vehicle's view no longer matches its model at the model's yaw (the urban van
  // turning at 60°/s was held, then lost, for 10 frames; kept, it still matched with B ≈ 0.7
  // while its reported velocity pointed 30-60° off): a mover's candidate that does not match
  // confidently (B < registration_stop_similarity) is registered again over yaw layers, and the
  // turned match wins only when it is clearly better (by turn_min_gain). Only movers, and only
  // then: yaw layers on every registration let the views' yaw noise into the positions
  // (velocity RMS worse on every set), and so did a smaller gain (0.02: wooded 0.25 → 0.40).
  double similarity = found ? registration_.getSimilarity() : 0.0;
  Eigen::Matrix4f T = registration_.getFinalTransformation();
  if (!(similarity >= p.registration.stop_similarity) && p.registration.turn_yaw_samples > 1 &&
      (track.mover || track.confirmed)) {
    ++registrations_;
    registration_.setYawSamples(p.registration.turn_yaw_samples);
    registration_.setYawStep(static_cast<float>(p.registration.turn_yaw_step_deg * M_PI / 180.0));
    registration_.align(aligned, guess);
    registration_.setYawSamples(p.registration.yaw_samples);
    if (registration_.hasConverged() &&
        registration_.getSimilarity() >= p.registration.min_similarity &&
        registration_.getSimilarity() > similarity + p.registration.turn_min_gain) {
      found = true;
      similarity = registration_.getSimilarity();
      T = registration_.getFinalTransformation();
    }
  }
  if (!found) return false;
  // The reference point is the one the registration maps onto the model centre.
  const Eigen::Vector4f ref = T.inverse() * Eigen::Vector4f(centre.x(), centre.y(), centre.z(), 1);
  match.measurement = ref.template head<3>().template cast<double>();
  match.similarity = similarity;
  match.score = similarity;
  match.transform = T;
  match.registered = true;
  return true;
}

template <typename PointT>
void MoverTracker<PointT>::buildView(const Candidate& candidate, const Eigen::Matrix4f& transform,
                                     const SurfaceDensity& model,
                                     const Eigen::Vector3d& sensor_origin) {
  // As BhattacharyaRegistration builds its source density: σ from the ranges before the motion.
  const auto& p = parameters_;
  const Eigen::Vector3f origin = sensor_origin.template cast<float>();
  const Eigen::Matrix3f r = transform.template topLeftCorner<3, 3>();
  const Eigen::Vector3f t = transform.template topRightCorner<3, 1>();
  view_points_.clear();
  view_sigmas_.clear();
  for (const auto& q : candidate.points->points) {
    const Eigen::Vector3f v(q.x, q.y, q.z);
    if (!v.allFinite()) continue;
    view_points_.push_back(r * v + t);
    view_sigmas_.push_back(
        std::max(static_cast<float>(p.registration.min_sigma),
                 static_cast<float>(p.registration.sigma_per_metre) * (v - origin).norm()));
  }
  if (view_.getNx() != model.getNx() || view_.getNy() != model.getNy() ||
      view_.getNz() != model.getNz())
    view_.setGridSize(model.getNx(), model.getNy(), model.getNz());
  view_.setResolution(model.getResolution());
  view_.setResolutionZ(model.getResolutionZ());
  view_.setSigmaPerMetre(model.getSigmaPerMetre());
  view_.setMinSigma(model.getMinSigma());
  view_.computeFromPoints(view_points_, view_sigmas_, model.getCentre());
}

template <typename PointT>
std::vector<typename MoverTracker<PointT>::ClusterPart> MoverTracker<PointT>::splitMergedClusters(
    const PointCloud& cloud, const std::vector<Observation>& observations, double time) const {
  const auto& p = parameters_;
  std::vector<ClusterPart> parts;
  if (!p.track.split_merged || !has_time_ || p.track.mode == "centroid") return parts;
  const std::vector<Claimant> claimants = findClaimants(time);
  if (claimants.size() < 2 ||
      std::none_of(claimants.begin(), claimants.end(),
                   [&](const Claimant& c) { return tracks_[c.track].confirmed; }))
    return parts;
  const auto addWhole = [&](std::size_t b) {
    ClusterPart whole;
    whole.cluster = static_cast<int>(b);
    whole.positions.resize(observations[b].indices.indices.size());
    std::iota(whole.positions.begin(), whole.positions.end(), 0);
    parts.push_back(std::move(whole));
  };
  bool any_split = false;
  for (std::size_t c = 0; c < observations.size(); ++c) {
    const pcl::Indices& idx = observations[c].indices.indices;
    std::vector<ClusterPart> pieces = cutCluster(cloud, idx, claimants);
    if (pieces.empty()) {
      if (any_split) addWhole(c);
      continue;
    }
    if (!any_split) {
      // First split: the clusters before it become whole parts.
      any_split = true;
      for (std::size_t b = 0; b < c; ++b) addWhole(b);
    }
    for (auto& piece : pieces) {
      piece.cluster = static_cast<int>(c);
      parts.push_back(std::move(piece));
    }
  }
  return parts;
}

template <typename PointT>
std::vector<typename MoverTracker<PointT>::Claimant> MoverTracker<PointT>::findClaimants(
    double time) const {
  const auto& p = parameters_;
  std::vector<Claimant> claimants;
  for (std::size_t ti = 0; ti < tracks_.size(); ++ti) {
    const Track& t = tracks_[ti];
    // Coasting for a frame or two (the walker hidden behind the one it passes) still claims.
    if (t.missed > 2 || t.large || t.hits < p.decision.min_age || t.last_view.empty()) continue;
    Claimant c;
    c.track = ti;
    c.shift = (t.filter.velocity() * std::max(0.0, time - t.last_time)).template cast<float>();
    c.lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max());
    c.hi = -c.lo;
    for (const auto& q : t.last_view) {
      c.lo = c.lo.cwiseMin(q.template head<2>() + c.shift);
      c.hi = c.hi.cwiseMax(q.template head<2>() + c.shift);
    }
    c.fit = fitVelocity(t.history, p.track.registration_sigma);
    claimants.push_back(c);
  }
  return claimants;
}

template <typename PointT>
bool MoverTracker<PointT>::claimantsDiffer(const Claimant& a, const Claimant& b) const {
  const auto& p = parameters_;
  // Moving differently, beyond doubt: fragments of one object share its velocity and are left
  // merged, and so are tracks whose velocities are too uncertain to tell. Each velocity is the
  // line through the track's last positions with σ from their scatter, as in the mover votes
  // (fast_from_fit): young fragment tracks of one wooded car differed by 1-4 m/s, but their
  // sliding positions scattered as much, while two walkers passing each other had precise lines
  // 1.9 m/s apart. And one of them must be a confirmed mover: a static object and a young track
  // that a few registrations made look fast would otherwise keep splitting each other (KITTI).
  if (!a.fit.valid || !b.fit.valid) return false;
  if (!tracks_[a.track].confirmed && !tracks_[b.track].confirmed) return false;
  // The other one a confirmed mover too, or static: an unconfirmed moving track next to a
  // mover is usually a fragment of it (KITTI van) whose velocity has drifted.
  const auto settled = [&](const Claimant& c) {
    return tracks_[c.track].confirmed || c.fit.velocity.norm() < 0.5 * p.decision.speed;
  };
  if (!settled(a) || !settled(b)) return false;
  const double dv = (a.fit.velocity - b.fit.velocity).norm();
  const double sigma = std::sqrt(a.fit.sigma_v * a.fit.sigma_v + b.fit.sigma_v * b.fit.sigma_v);
  return dv >= p.track.split_min_speed_difference && dv > p.track.gate_sigmas * sigma;
}

template <typename PointT>
std::pair<std::size_t, float> MoverTracker<PointT>::nearestView(
    const PointT& q, const std::vector<Claimant>& claimants,
    const std::vector<std::size_t>& ids) const {
  std::pair<std::size_t, float> nearest(0, std::numeric_limits<float>::max());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const Claimant& cl = claimants[ids[k]];
    for (const auto& v : tracks_[cl.track].last_view) {
      const float dx = q.x - (v.x() + cl.shift.x()), dy = q.y - (v.y() + cl.shift.y());
      const float d2 = dx * dx + dy * dy;
      if (d2 < nearest.second) nearest = {k, d2};
    }
  }
  return nearest;
}

template <typename PointT>
std::vector<typename MoverTracker<PointT>::ClusterPart> MoverTracker<PointT>::cutCluster(
    const PointCloud& cloud, const pcl::Indices& idx,
    const std::vector<Claimant>& claimants) const {
  const auto& p = parameters_;
  const float claim = static_cast<float>(p.track.split_claim_distance);
  // Cheap rejection by bounding boxes, of an even subsample of at most 64 points (this runs on
  // every cluster of the frame; the claim margin covers what the subsample misses).
  Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  const std::size_t step = std::max<std::size_t>(1, idx.size() / 64);
  for (std::size_t j = 0; j < idx.size(); j += step) {
    const auto& q = cloud[idx[j]];
    if (!std::isfinite(q.x) || !std::isfinite(q.y)) continue;
    lo = lo.cwiseMin(Eigen::Vector2f(q.x, q.y));
    hi = hi.cwiseMax(Eigen::Vector2f(q.x, q.y));
  }
  // Structures longer than any mover are not split (and would cost the most to test).
  if (!((hi - lo).maxCoeff() <= p.decision.max_length + 2 * claim)) return {};
  std::vector<std::size_t> near;
  for (std::size_t k = 0; k < claimants.size(); ++k) {
    const auto& cl = claimants[k];
    if ((cl.lo.array() - claim <= hi.array()).all() && (lo.array() <= cl.hi.array() + claim).all())
      near.push_back(k);
  }
  // Some pair of the tracks nearby moves differently (the cheap test first: most clusters near
  // two tracks are static neighbours), and those that claim the cluster do too.
  const auto anyPairDiffers = [&](const std::vector<std::size_t>& ids) {
    for (std::size_t a = 0; a < ids.size(); ++a)
      for (std::size_t b = a + 1; b < ids.size(); ++b)
        if (claimantsDiffer(claimants[ids[a]], claimants[ids[b]])) return true;
    return false;
  };
  if (!anyPairDiffers(near) || static_cast<int>(idx.size()) < 2 * kMinSplitPoints) return {};
  // Claims, on an even subsample of at most 128 points (each counts for `sample` points): each
  // point to the nearest moved view among the nearby tracks, counted when within
  // split_claim_distance of it.
  const std::size_t sample = std::max<std::size_t>(1, idx.size() / 128);
  std::vector<int> claimed(near.size(), 0);
  for (std::size_t j = 0; j < idx.size(); j += sample) {
    const auto& q = cloud[idx[j]];
    if (!std::isfinite(q.x) || !std::isfinite(q.y)) continue;
    const auto nearest = nearestView(q, claimants, near);
    if (nearest.second <= claim * claim) claimed[nearest.first] += static_cast<int>(sample);
  }
  std::vector<std::size_t> claimers;
  for (std::size_t k = 0; k < near.size(); ++k)
    if (claimed[k] >= kMinSplitPoints) claimers.push_back(near[k]);
  if (claimers.size() < 2 || !anyPairDiffers(claimers)) return {};
  // Points go to the nearest claimer only (views of non-claimers do not compete).
  std::vector<ClusterPart> pieces(claimers.size());
  for (std::size_t j = 0; j < idx.size(); ++j) {
    const auto& q = cloud[idx[j]];
    const std::size_t arg =
        std::isfinite(q.x) && std::isfinite(q.y) ? nearestView(q, claimants, claimers).first : 0;
    pieces[arg].positions.push_back(static_cast<int>(j));
  }
  const bool all_large_enough =
      std::all_of(pieces.begin(), pieces.end(), [&](const ClusterPart& piece) {
        return static_cast<int>(piece.positions.size()) >= kMinSplitPoints;
      });
  if (!all_large_enough) return {};
  return pieces;
}

template <typename PointT>
std::vector<pcl::PointIndices> MoverTracker<PointT>::applyParts(
    const std::vector<ClusterPart>& parts, const std::vector<pcl::PointIndices>& clusters) {
  std::vector<pcl::PointIndices> out(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const auto& source = clusters[static_cast<std::size_t>(parts[k].cluster)].indices;
    out[k].indices.reserve(parts[k].positions.size());
    for (const int j : parts[k].positions)
      out[k].indices.push_back(source[static_cast<std::size_t>(j)]);
  }
  return out;
}

template <typename PointT>
std::vector<Observation> MoverTracker<PointT>::applyParts(
    const std::vector<ClusterPart>& parts, const std::vector<Observation>& observations) {
  std::vector<Observation> cut(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const Observation& whole = observations[static_cast<std::size_t>(parts[k].cluster)];
    const auto& positions = parts[k].positions;
    if (positions.size() == whole.indices.indices.size()) {
      cut[k] = whole;
      continue;
    }
    // A part's side along the cut is not the object's extent; it stands where the whole did.
    cut[k].split_part = true;
    cut[k].occluded = true;
    cut[k].floor_z = whole.floor_z;
    cut[k].indices.header = whole.indices.header;
    cut[k].indices.indices.reserve(positions.size());
    for (const int i : positions)
      cut[k].indices.indices.push_back(whole.indices.indices[static_cast<std::size_t>(i)]);
  }
  return cut;
}

template <typename PointT>
void MoverTracker<PointT>::update(const PointCloudConstPtr& cloud,
                                  const std::vector<Observation>& observations,
                                  const Eigen::Vector3d& sensor_origin, double time) {
  const auto& p = parameters_;
  results_.assign(observations.size(), ClusterResult());
  registrations_ = 0;
  const double dt = has_time_ ? std::max(0.0, time - last_time_) : 0.0;
  has_time_ = true;
  last_time_ = time;
  const Frame frame{
      *cloud,
      observations,
      sensor_origin,
      time,
      dt,
      p.track.mode != "centroid",
      SurfaceDensity::halfLifeWeight(static_cast<float>(p.registration.model_half_life))};

  predictTracks(dt);
  std::vector<Candidate> candidates = makeCandidates(frame);
  const Association association =
      associate(frame, candidates, findStillClusters(frame, candidates));

  // Greedy assignment, best score first.
  std::vector<char> track_used(tracks_.size(), 0), cluster_used(candidates.size(), 0);
  for (const auto& m : association.matches) {
    if (track_used[m.track] || cluster_used[m.cluster]) continue;
    track_used[m.track] = cluster_used[m.cluster] = 1;
    if (m.cheap)
      seeStill(tracks_[m.track], candidates[m.cluster], results_[m.cluster]);
    else
      updateTrack(m, frame, candidates);
  }
  if (p.track.hold_confirmed)
    holdClusters(frame, association, candidates, track_used, cluster_used);
  dropLostTracks(track_used);
  bearTracks(frame, candidates, cluster_used);
}

template <typename PointT>
void MoverTracker<PointT>::predictTracks(double dt) {
  for (auto& t : tracks_) {
    t.filter.predict(dt);
    if (t.velocity_filter.isInitialized()) t.velocity_filter.predict(dt);
    ++t.age;
  }
}

template <typename PointT>
std::vector<typename MoverTracker<PointT>::Candidate> MoverTracker<PointT>::makeCandidates(
    const Frame& frame) {
  const auto& p = parameters_;
  std::vector<Candidate> candidates(frame.observations.size());
  for (std::size_t c = 0; c < frame.observations.size(); ++c) {
    const Observation& observation = frame.observations[c];
    auto& cand = candidates[c];
    cand.features = computeFeatures(frame.cloud, observation.indices.indices);
    const double range =
        (cand.features.centroid.template head<2>() - frame.sensor_origin.template head<2>()).norm();
    // A part split off a merged cluster belongs to an established track: it is tracked down to
    // kMinSplitPoints (a walker half hidden behind the one it passes).
    cand.usable = (cand.features.points >= p.segment.min_cluster_points ||
                   (observation.split_part && cand.features.points >= kMinSplitPoints)) &&
                  range <= p.track.max_range;
    cand.features.large = cand.features.length > p.decision.max_length ||
                          cand.features.height > p.decision.max_height;
    cand.features.occluded = observation.occluded || observation.split_part;
    cand.features.floor_z = observation.floor_z;
    cand.features.roughness = observation.roughness;
    results_[c].features = cand.features;
  }
  return candidates;
}

template <typename PointT>
std::vector<int> MoverTracker<PointT>::findStillClusters(
    const Frame& frame, const std::vector<Candidate>& candidates) const {
  const auto& p = parameters_;
  // Cheap frames for established static tracks (see static_refresh_frames): the track's nearest
  // usable cluster's centroid lies within static_shift of the last measured one, and no
  // other cluster is within static_clearance. cheap[ti] is that cluster (-1: register as usual).
  std::vector<int> cheap(tracks_.size(), -1);
  if (!frame.use_registration || p.track.static_refresh_frames <= 1) return cheap;
  for (std::size_t ti = 0; ti < tracks_.size(); ++ti) {
    const Track& track = tracks_[ti];
    if (!track.model || track.hits < p.decision.min_age || track.mover ||
        track.filter.speed() > 0.5 * p.decision.speed ||
        track.since_registration + 1 >= p.track.static_refresh_frames)
      continue;
    double nearest = std::numeric_limits<double>::max(), second = nearest;
    int nearest_cluster = -1;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const auto& cand = candidates[c];
      if (!cand.usable) continue;
      // From where the track was last measured, not from the last still frame's cluster: an
      // object creeping off (a car leaving its slot, 0.1 m a frame) stays within static_shift of
      // the frame before and was measured only every static_refresh_frames frames, its velocity
      // lagging its motion (tune split: parking hit 65.1 -> 65.8 %, vel. RMS 0.508 -> 0.494).
      const double d = (cand.features.centroid - track.measured_centroid).template head<2>().norm();
      if (d < nearest) {
        second = nearest;
        nearest = d;
        nearest_cluster = static_cast<int>(c);
      } else if (d < second) {
        second = d;
      }
    }
    if (nearest_cluster < 0 || !(nearest < p.track.static_shift)) continue;
    // Another cluster this close would make the association ambiguous: register then.
    if (second <= p.track.static_clearance) continue;
    if (second <= 2 * p.track.gate_margin) {
      // A neighbour within the old two-gate-margin bound (it was always registered then): the
      // cluster must also have kept its size, so a split or merge with that neighbour (which
      // moves the centroid little when the other part is small) is registered.
      const auto& f = candidates[nearest_cluster].features;
      const double points_ratio =
          static_cast<double>(f.points) / std::max(1, track.features.points);
      if (points_ratio < 0.8 || points_ratio > 1.25 ||
          std::abs(f.height - track.features.height) > 0.3 ||
          std::abs(f.length - track.features.length) > 0.3)
        continue;
    }
    cheap[ti] = nearest_cluster;
  }
  return cheap;
}

template <typename PointT>
typename MoverTracker<PointT>::Association MoverTracker<PointT>::associate(
    const Frame& frame, std::vector<Candidate>& candidates, const std::vector<int>& still) {
  Association association;
  association.held_distance.assign(tracks_.size(), std::numeric_limits<double>::max());
  association.held_cluster.assign(tracks_.size(), -1);
  // Tracks seen in the last frame are scored first; a cluster one of them matched with
  // B ≥ registration_stop_similarity (or saw unregistered, static) is "claimed". A coasting
  // track that is not a mover does not register claimed clusters: it could only take one with an
  // even better match, and coasting tracks (mostly clutter and fragments that lost their
  // cluster) ran a third of all registrations on KITTI while winning a quarter of theirs.
  // Movers and moving tracks register everything, so an occluded (future) mover still
  // re-acquires its object.
  std::vector<std::size_t> order;
  order.reserve(tracks_.size());
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t ti = 0; ti < tracks_.size(); ++ti)
      if ((tracks_[ti].missed > 0) == (pass == 1)) order.push_back(ti);
  std::vector<char> claimed(candidates.size(), 0);
  for (const std::size_t ti : order) gateTrack(ti, frame, candidates, still, claimed, association);
  std::sort(association.matches.begin(), association.matches.end(),
            [](const Match& a, const Match& b) { return a.score > b.score; });
  return association;
}

template <typename PointT>
void MoverTracker<PointT>::gateTrack(std::size_t ti, const Frame& frame,
                                     std::vector<Candidate>& candidates,
                                     const std::vector<int>& still, std::vector<char>& claimed,
                                     Association& association) {
  TrackGate& gate = gate_;  // a work buffer: its candidate list keeps its capacity
  setGate(ti, frame, gate);
  gateCandidates(gate, frame, candidates, association);
  const Track& track = tracks_[ti];
  const bool centroid_only = !frame.use_registration || track.large || !track.model;
  if (centroid_only)
    scoreByCentroid(gate, candidates, association);
  else if (still[ti] >= 0)
    scoreStill(gate, static_cast<std::size_t>(still[ti]), claimed, association);
  else
    scoreByRegistration(gate, frame, candidates, claimed, association);
}

template <typename PointT>
void MoverTracker<PointT>::setGate(std::size_t ti, const Frame& frame, TrackGate& gate) const {
  const auto& p = parameters_;
  const Track& track = tracks_[ti];
  gate.track = ti;
  gate.predicted = track.filter.position();
  const double meas_sigma =
      track.large || !frame.use_registration ? p.track.centroid_sigma : p.track.registration_sigma;
  const Eigen::Matrix2d S =
      track.filter.innovationCovariance(Eigen::Matrix2d::Identity() * meas_sigma * meas_sigma);
  const double sigma = std::sqrt(
      std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(S, Eigen::EigenvaluesOnly)
                        .eigenvalues()
                        .maxCoeff()));
  const double accel_term = 0.5 * p.track.acceleration_limit * frame.dt * frame.dt;
  gate.prior_search = std::min(p.track.max_gate_radius, p.track.gate_sigmas * sigma + accel_term);
  // A registered track seen once may be as fast as traffic: its second view is searched as far
  // as any track's, whatever its velocity prior (a 33 m/s car moves 3.3 m a frame), but a view
  // beyond the prior's gate is taken only when it registers confidently onto the model
  // (scoreByRegistration()); startsFast() then takes the velocity from the two views. Not a
  // re-acquired track: it starts with the velocity of the mover it continues, whose gate is the
  // right one.
  const bool search_fast =
      frame.use_registration && track.model && track.hits < 2 && !track.reacquired;
  gate.search = search_fast ? p.track.max_gate_radius : gate.prior_search;
}

template <typename PointT>
void MoverTracker<PointT>::gateCandidates(TrackGate& gate, const Frame& frame,
                                          const std::vector<Candidate>& candidates,
                                          Association& association) const {
  const auto& p = parameters_;
  const std::size_t ti = gate.track;
  const Track& track = tracks_[ti];
  const bool centroid_only = !frame.use_registration || track.large || !track.model;
  gate.candidates.clear();
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const auto& cand = candidates[c];
    if (!cand.usable) continue;
    // Centroids are compared with the predicted centroid, not the predicted reference point:
    // a car first seen head-on at 80 m has its reference point at its front, 1.5-2 m from the
    // centroid of its side view when it passes (open scene: the track was lost and re-born).
    const double distance =
        (cand.features.centroid.template head<2>() - gate.predicted - track.centroid_offset).norm();
    // A track with a model is only ever updated by registration: mixing centroid measurements
    // into its reference-point track would fake motion.
    if (frame.use_registration && track.model && !registrable(cand.features)) {
      // But a confirmed mover may hold it (see holdClusters()): a walker passing behind a
      // parked car shows only its head and shoulders, too low to register.
      if (track.confirmed && !cand.features.large &&
          distance <= std::min(p.track.max_gate_radius, gate.search) + p.track.gate_margin &&
          distance < association.held_distance[ti]) {
        association.held_distance[ti] = distance;
        association.held_cluster[ti] = static_cast<int>(c);
      }
      continue;
    }
    // Big structures: their centroid moves a lot as they come into view, gate generously.
    const double margin = centroid_only && (track.large || cand.features.large)
                              ? 0.5 * std::max(track.features.length, cand.features.length)
                              : p.track.gate_margin;
    if (distance > std::min(p.track.max_gate_radius + margin, gate.search + margin)) continue;
    if (std::abs(cand.features.centroid.z() - track.features.centroid.z()) > 1.5) continue;
    gate.candidates.emplace_back(distance, c);
  }
}

template <typename PointT>
void MoverTracker<PointT>::scoreByCentroid(const TrackGate& gate,
                                           const std::vector<Candidate>& candidates,
                                           Association& association) const {
  for (const auto& dc : gate.candidates) {
    Match m;
    m.track = gate.track;
    m.cluster = dc.second;
    m.measurement = candidates[dc.second].features.centroid;
    m.score = -dc.first;  // below every B, so registered matches are assigned first
    m.similarity = 0;
    association.matches.push_back(std::move(m));
  }
}

template <typename PointT>
void MoverTracker<PointT>::scoreStill(const TrackGate& gate, std::size_t still_cluster,
                                      std::vector<char>& claimed, Association& association) const {
  // Established static track whose nearest cluster did not move: seen, no registration; its
  // other gated clusters are left to the other tracks.
  const Track& track = tracks_[gate.track];
  for (const auto& dc : gate.candidates) {
    if (dc.second != still_cluster) continue;
    Match m;
    m.track = gate.track;
    m.cluster = dc.second;
    m.cheap = true;
    m.measurement = Eigen::Vector3d(gate.predicted.x(), gate.predicted.y(), track.z);
    m.score = track.similarity;
    m.similarity = track.similarity;
    if (track.missed == 0) claimed[dc.second] = 1;
    association.matches.push_back(std::move(m));
  }
}

template <typename PointT>
void MoverTracker<PointT>::scoreByRegistration(const TrackGate& gate, const Frame& frame,
                                               std::vector<Candidate>& candidates,
                                               std::vector<char>& claimed,
                                               Association& association) {
  const auto& p = parameters_;
  const std::size_t ti = gate.track;
  const Track& track = tracks_[ti];
  // A coasting track that is not a mover does not register clusters claimed by a track seen in
  // the last frame (see associate()).
  const bool skip_claimed = track.missed > 0 && !track.mover && !track.confirmed &&
                            track.filter.speed() < 0.5 * p.decision.speed;
  auto& to_register = to_register_;
  to_register.clear();
  for (const auto& dc : gate.candidates)
    if (!(skip_claimed && claimed[dc.second])) to_register.push_back(dc);
  // Registrations, nearest centroid first. Once one reaches registration_stop_similarity the
  // farther candidates are not registered: they would have to match the model even better to
  // win this track, which they rarely do (on KITTI ~1 in 30 of them won, mostly against
  // fragments of the same object), and the farther candidates are most of the cost where
  // objects stand close together (parked cars, vegetation).
  std::stable_sort(to_register.begin(), to_register.end(),
                   [](const std::pair<double, std::size_t>& a,
                      const std::pair<double, std::size_t>& b) { return a.first < b.first; });
  for (const auto& dc : to_register) {
    const double distance = dc.first;
    const std::size_t c = dc.second;
    auto& cand = candidates[c];
    Match m;
    m.track = ti;
    m.cluster = c;
    ensurePoints(frame.cloud, frame.observations[c].indices, cand);
    // A track seen once has no velocity yet: its prediction is vague and the search would
    // have to cover every possible speed. Its centroid shift is a good enough first guess
    // for a small search window instead.
    Eigen::Vector2d guess = gate.predicted;
    double radius = std::max(gate.search, 2 * p.registration.resolution);
    if (track.hits < 2) {
      guess = track.history.back().template head<2>() +
              (cand.features.centroid - track.features.centroid).template head<2>();
      radius = p.registration.young_search_radius;
    }
    if (!registerCandidate(track, cand, guess, radius, frame.sensor_origin, m)) {
      // Remember the nearest gated candidate a confirmed mover failed to register (turning,
      // half occluded): it may still be that mover (see holdClusters()).
      if ((track.confirmed || track.mover) && distance < association.held_distance[ti]) {
        association.held_distance[ti] = distance;
        association.held_cluster[ti] = static_cast<int>(c);
      }
      continue;
    }
    const bool confident = m.similarity >= p.registration.stop_similarity;
    if (!confident && distance > gate.prior_search + p.track.gate_margin) continue;
    if (confident && track.missed == 0) claimed[c] = 1;
    association.matches.push_back(std::move(m));
    // A fragment of the object (a walker's legs cut from the body by a dropped row) can match
    // the model well and lie nearest, and the rest, the better match, would never be tried
    // (urban pedestrian 6: its track took an 8-point leg part at B 0.88 and the 29-point rest
    // became a new track). Only a candidate of at least half the last view's points stops.
    if (confident && 2 * cand.features.points >= track.features.points) break;
  }
}

template <typename PointT>
void MoverTracker<PointT>::seeStill(Track& t, const Candidate& cand, ClusterResult& r) {
  t.missed = 0;
  t.last_time = last_time_;
  t.features = cand.features;
  ++t.since_registration;
  report(t, t.similarity, r);
}

template <typename PointT>
std::vector<Eigen::Vector3f> MoverTracker<PointT>::fullView(const Frame& frame, int cluster) const {
  const auto& indices = frame.observations[cluster].indices.indices;
  std::vector<Eigen::Vector3f> view;
  view.reserve(indices.size());
  for (const auto k : indices) {
    const auto& q = frame.cloud[k];
    if (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z))
      view.emplace_back(q.x, q.y, q.z);
  }
  return view;
}

template <typename PointT>
bool MoverTracker<PointT>::measureSweptEdge(const Track& t,
                                            const std::vector<Eigen::Vector3f>& view, Match& m) {
  const FreeSpaceMap* map = getFreeSpaceMap();
  // The previous view and position must be the previous frame's: the swept strips are judged
  // against the scan one frame back.
  if (!parameters_.track.swept_edges || !map || !m.registered || t.missed != 0 ||
      t.since_registration != 0 || t.full_view.empty() || view.empty() || t.history.empty())
    return false;
  const SweptEdges edges = sweptEdgeShift(t.full_view, view, *map, parameters_.track.swept);
  if (!edges.measured) return false;
  // Only the displacement along the view's length is replaced: across it the registration
  // is not ambiguous.
  const Eigen::Vector2d registered =
      m.measurement.template head<2>() - t.history.back().template head<2>();
  const Eigen::Vector2d correction = (edges.shift - edges.axis.dot(registered)) * edges.axis;
  m.measurement.template head<2>() += correction;
  // The cluster → model motion follows: a cluster point lies `correction` further on.
  Eigen::Matrix4f back = Eigen::Matrix4f::Identity();
  back.template block<2, 1>(0, 3) = -correction.template cast<float>();
  m.transform = m.transform * back;
  return true;
}

template <typename PointT>
void MoverTracker<PointT>::updateTrack(const Match& match, const Frame& frame,
                                       std::vector<Candidate>& candidates) {
  const auto& p = parameters_;
  Track& t = tracks_[match.track];
  Match m = match;
  // The extents must be those of the whole view: the extremes of a sample wander by tenths of
  // a metre from frame to frame.
  std::vector<Eigen::Vector3f> view;
  if (p.track.swept_edges && getFreeSpaceMap() && !t.large) view = fullView(frame, m.cluster);
  // A view whose moving edge was measured is no longer ambiguous where it is bounded.
  const bool occluded = !measureSweptEdge(t, view, m) && candidates[m.cluster].features.occluded;
  const Candidate& cand = candidates[m.cluster];
  auto& r = results_[m.cluster];
  const bool registered = m.registered;
  t.since_registration = 0;
  t.measured_centroid = cand.features.centroid;
  if (registered) motion_.turn(t, std::atan2(m.transform(1, 0), m.transform(0, 0)));
  const double range = (cand.features.centroid - frame.sensor_origin).template head<2>().norm();
  const double meas_sigma =
      motion_.measure(t, m.measurement, registered, occluded, m.similarity, range, frame.time);
  t.z = m.measurement.z();
  t.last_time = frame.time;
  ++t.hits;
  // Re-acquired after coasting: the association is the least certain here, so earlier points
  // may belong to another object; the receding test only uses points from this run of updates.
  if (t.missed > 0) {
    t.past_points.clear();
    t.past_views.clear();
  }
  t.missed = 0;
  t.held_from.setConstant(std::numeric_limits<double>::quiet_NaN());
  t.similarity = m.similarity;
  t.features = cand.features;
  t.centroid_offset = (cand.features.centroid - m.measurement).template head<2>();
  if (!cand.features.large) {
    t.max_height = std::max(t.max_height, cand.features.height);
    t.max_standing_height =
        std::max(t.max_standing_height, decision_.standingHeight(cand.features));
    t.max_length = std::max(t.max_length, cand.features.length);
  }
  // Not latched: a far vehicle merged with a hedge for a while must become a candidate again.
  t.large = cand.features.large;
  t.history.emplace_back(m.measurement.x(), m.measurement.y(), frame.time);
  while (static_cast<int>(t.history.size()) > p.decision.window + 1) t.history.pop_front();
  t.long_history.emplace_back(m.measurement.x(), m.measurement.y(), frame.time);
  while (!t.long_history.empty() &&
         t.long_history.front().z() < frame.time - p.decision.slow_window - 1e-6)
    t.long_history.pop_front();
  motion_.refit(t, m.measurement, registered, occluded, meas_sigma, frame.time);
  decision_.voteFast(t, registered);
  updateModel(t, m, frame, candidates, meas_sigma);
  decideAndRemember(t, m, frame, candidates);
  t.full_view = std::move(view);
  report(t, t.similarity, r);
}

template <typename PointT>
void MoverTracker<PointT>::updateModel(Track& t, const Match& m, const Frame& frame,
                                       std::vector<Candidate>& candidates, double meas_sigma) {
  const auto& p = parameters_;
  const Candidate& cand = candidates[m.cluster];
  const bool registered = m.registered;
  if (registered && t.model) {
    try {
      buildView(cand, m.transform, *t.model, frame.sensor_origin);
      t.model->accumulate(view_, frame.model_weight);
    } catch (const std::exception&) {
      // Grids always match (same parameters); keep the old model if they ever do not.
    }
  }
  // A track born too low (e.g. half hidden) gets its model once it is seen tall enough.
  // Its velocity so far came from centroids of a partial view, which jump when the rest of
  // the object appears: the registered track starts afresh (position and age are kept).
  if (frame.use_registration && !t.model && !t.large && registrable(cand.features)) {
    ensurePoints(frame.cloud, frame.observations[m.cluster].indices, candidates[m.cluster]);
    t.model = makeModel(candidates[m.cluster], frame.sensor_origin);
    // A re-acquired track keeps the velocity it inherited, not what its filter made of the
    // partial views' centroids since (a wooded car's front emerging past a trunk: a jump to
    // another fragment gave it 2 m/s across its path, reported for the next 7 frames).
    // A mover already confirmed (from views hidden from below, standingHeight()) keeps its
    // velocity too: it is reported, and restarting it from zero reported a walker emerging
    // from behind a parked car as standing still for three frames (urban pedestrian 8).
    const bool keep_velocity = t.reacquired || t.confirmed;
    const Eigen::Vector2d v_keep =
        t.reacquired ? t.inherited_velocity : Eigen::Vector2d(t.filter.velocity());
    t.filter.initialize(
        cand.features.centroid.template head<2>(),
        Eigen::Matrix2d::Identity() * meas_sigma * meas_sigma,
        keep_velocity ? v_keep : Eigen::Vector2d::Zero(),
        keep_velocity ? p.track.reacquire_velocity_sigma : p.track.initial_velocity_sigma);
    t.centroid_offset.setZero();
    t.velocity_filter = KalmanFilterCV();
    t.registered.clear();
    t.unoccluded_positions.clear();
    t.seen_occluded = cand.features.occluded;
    t.z = cand.features.centroid.z();
    t.hits = 1;
    t.fast.assign(1, 0);
    t.history.assign(
        1, Eigen::Vector3d(cand.features.centroid.x(), cand.features.centroid.y(), frame.time));
    t.long_history = t.history;
  }
}

template <typename PointT>
void MoverTracker<PointT>::decideAndRemember(Track& t, const Match& m, const Frame& frame,
                                             std::vector<Candidate>& candidates) {
  const auto& p = parameters_;
  std::vector<Eigen::Vector3f> world_points;
  if (getFreeSpaceMap() && p.free_space.lag > 0 && !t.large) {
    ensurePoints(frame.cloud, frame.observations[m.cluster].indices, candidates[m.cluster]);
    const auto& pts = *candidates[m.cluster].points;
    world_points.reserve(pts.size());
    for (const auto& q : pts) world_points.emplace_back(q.x, q.y, q.z);
  }
  decision_.decide(t, world_points, tracks_);
  if (const auto& pts = candidates[m.cluster].points) {
    const std::size_t n = pts->size();
    const std::size_t stride =
        std::max<std::size_t>(1, (n + kLastViewPoints - 1) / kLastViewPoints);
    t.last_view.clear();
    for (std::size_t k = 0; k < n; k += stride)
      t.last_view.emplace_back((*pts)[k].x, (*pts)[k].y, (*pts)[k].z);
  }
  if (!world_points.empty()) {
    t.past_views.push_back(t.last_view);
    while (static_cast<int>(t.past_views.size()) > std::max(p.free_space.long_lag, 1))
      t.past_views.pop_front();
    t.past_points.push_back(std::move(world_points));
    while (static_cast<int>(t.past_points.size()) > p.free_space.lag + 1) t.past_points.pop_front();
  }
}

template <typename PointT>
void MoverTracker<PointT>::report(const Track& t, double similarity, ClusterResult& r) {
  r.track_id = t.id;
  r.mover = t.mover;
  r.reason = t.reason;
  r.similarity = similarity;
  r.velocity = t.reportedVelocity();
}

template <typename PointT>
void MoverTracker<PointT>::holdClusters(const Frame& frame, const Association& association,
                                        std::vector<Candidate>& candidates,
                                        std::vector<char>& track_used,
                                        std::vector<char>& cluster_used) {
  const auto& p = parameters_;
  // Held clusters: a confirmed mover whose only gated candidates registered with B below
  // min_similarity (or were too low to register) is not updated (low B is not a measurement: no
  // Kalman update, no model accumulation, the track coasts), but a cluster nobody else took near
  // its prediction is reported as that track instead of starting a new one. Otherwise each such
  // frame would be a missed mover plus a fresh unconfirmed track, and identities would churn.
  {
    for (std::size_t ti = 0; ti < tracks_.size(); ++ti) {
      const int c = association.held_cluster[ti];
      if (track_used[ti] || c < 0 || cluster_used[c]) continue;
      Track& t = tracks_[ti];
      const Eigen::Vector2d centroid = candidates[c].features.centroid.template head<2>();
      if (!std::isfinite(t.held_from.z())) t.held_from << centroid, frame.time;
      // Held while it may coast; then re-anchored on the held view, or it dies and the cluster
      // is born.
      const bool coasted_out = t.missed + 1 > p.track.max_missed_frames;
      if (coasted_out &&
          !(frame.use_registration && t.model && heldAlongItsPath(t, centroid, frame.time)))
        continue;
      track_used[ti] = 1;
      cluster_used[c] = 1;
      if (coasted_out)
        reanchorTrack(t, frame, candidates, c);
      else
        ++t.missed;
      t.features = candidates[c].features;
      report(t, 0, results_[c]);
    }
  }
}

template <typename PointT>
void MoverTracker<PointT>::reanchorTrack(Track& t, const Frame& frame,
                                         std::vector<Candidate>& candidates, std::size_t c) {
  // The object now looks unlike its model (a truck far behind seen by one beam, a car turning
  // or half hidden), so no view registered for max_missed_frames while it held clusters at its
  // prediction. A new track there would start the decision over ("new", "young", votes); the
  // same object keeps its track: its model restarts from the held view and its reference point
  // moves to that view's centroid, and the positions it remembers move with it, so its line
  // stays the line it was.
  Candidate& cand = candidates[c];
  ensurePoints(frame.cloud, frame.observations[c].indices, cand);
  const Eigen::Vector2d shift = cand.features.centroid.template head<2>() - t.filter.position();
  const auto moveBy = [&](KalmanFilterCV& filter) {
    if (!filter.isInitialized()) return;
    KalmanFilterCV::State state = filter.getState();
    state.template head<2>() += shift;
    filter.setState(state);
  };
  moveBy(t.filter);
  moveBy(t.velocity_filter);
  for (auto* positions : {&t.history, &t.long_history, &t.unoccluded_positions})
    for (auto& q : *positions) q.template head<2>() += shift;
  t.model = makeModel(cand, frame.sensor_origin);
  t.model_yaw = 0;
  t.centroid_offset.setZero();
  t.missed = 0;
  t.past_points.clear();
  t.past_views.clear();
  t.held_from.setConstant(std::numeric_limits<double>::quiet_NaN());
}

template <typename PointT>
bool MoverTracker<PointT>::heldAlongItsPath(const Track& t, const Eigen::Vector2d& centroid,
                                            double time) const {
  // The clusters a track held moved as the track did, within the shift of a changing view, and
  // more like it than like a static object: a static neighbour held by a passing mover stays
  // behind its prediction by the distance the mover covers (a walker's 0.75 m in 0.5 s is within
  // the margin, but nearer standing still than walking).
  const double since = time - t.held_from.z();
  if (!(since > 0)) return false;
  const Eigen::Vector2d moved = centroid - t.held_from.template head<2>();
  const double off_path = (moved - t.filter.velocity() * since).norm();
  return off_path <= parameters_.track.gate_margin && off_path < moved.norm();
}

template <typename PointT>
bool MoverTracker<PointT>::registrable(const ClusterFeatures& features) const {
  // Objects far too low to be movers and big structures are not worth a registration, nor a
  // model. Half the mover height is used so that a vehicle whose visible height fluctuates
  // around min_height keeps its registered track.
  return !features.large && features.height >= 0.5 * parameters_.decision.min_height;
}

template <typename PointT>
void MoverTracker<PointT>::dropLostTracks(const std::vector<char>& track_used) {
  const auto& p = parameters_;
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (std::size_t ti = 0; ti < tracks_.size(); ++ti) {
    Track& t = tracks_[ti];
    if (!track_used[ti]) ++t.missed;
    // A track seen only once is likely clutter: it does not coast.
    if (t.missed > p.track.max_missed_frames || (t.hits < 2 && t.missed > 1)) continue;
    kept.push_back(std::move(t));
  }
  tracks_ = std::move(kept);
}

template <typename PointT>
void MoverTracker<PointT>::bearTracks(const Frame& frame, std::vector<Candidate>& candidates,
                                      const std::vector<char>& cluster_used) {
  const auto& p = parameters_;
  tracks_.reserve(tracks_.size() + candidates.size());
  const std::size_t existing = tracks_.size();
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    auto& cand = candidates[c];
    if (cluster_used[c] || !cand.usable) continue;
    if (static_cast<int>(tracks_.size()) >= p.track.max_tracks) break;
    Track t;
    t.id = next_id_++;
    t.filter.setAccelerationNoise(p.track.acceleration_noise);
    const double sigma = cand.features.large || !frame.use_registration
                             ? p.track.centroid_sigma
                             : p.track.registration_sigma;
    // Re-acquisition after occlusion: a mover that passed behind an occluder comes back as a
    // cluster its track cannot take (another part of the object, far from the predicted
    // centroid, or one that does not register against the model of the part seen before). Its
    // new track would start at rest and its first velocities, measured while the object emerges
    // (positions sliding with the growing visible part), were 1-3 m/s for 8 (urban car 4, lost
    // and re-born four times). The coasting mover's prediction says where that object is and how
    // fast it goes: a cluster overlapping its predicted extent inherits its velocity.
    Eigen::Vector2d v0 = Eigen::Vector2d::Zero();
    double v0_sigma = p.track.initial_velocity_sigma;
    // Registration mode only: centroid mode's speed votes read the tracking filter's velocity,
    // which an inherited velocity would vote for without any evidence (centroid urban: 2 → 8
    // false alarms).
    if (p.track.reacquire_velocity && frame.use_registration && p.decision.fast_from_fit &&
        !cand.features.large) {
      double best = std::numeric_limits<double>::max();
      for (std::size_t ti = 0; ti < existing; ++ti) {
        const Track& lost = tracks_[ti];
        // A moving mover still tracked counts too when the new cluster is occluded: an object
        // split by an occluder (a wooded car's front emerging past a trunk while its track keeps
        // the hiding rear) is a second part of it, not a new object at rest. Not a latched mover
        // standing still: a van turning past a car waiting at the junction took its zero velocity.
        const bool split_by_occluder = cand.features.occluded && lost.confirmed &&
                                       lost.reportedVelocity().norm() > p.decision.speed;
        if ((lost.missed < 1 && !split_by_occluder) || lost.large ||
            !(lost.mover || lost.confirmed))
          continue;
        const double d = (cand.features.centroid.template head<2>() - lost.filter.position() -
                          lost.centroid_offset)
                             .norm();
        // The cluster may be another part of the object than the one last seen (the front
        // emerging on one side of the occluder after the rear hid on the other).
        const double reach = std::max(lost.max_length, lost.features.length) +
                             0.5 * cand.features.length + p.track.gate_margin;
        if (d <= reach && d < best) {
          best = d;
          v0 = lost.reportedVelocity();
          v0_sigma = p.track.reacquire_velocity_sigma;
          t.reacquired = true;
          t.inherited_velocity = v0;
        }
      }
    }
    t.filter.initialize(cand.features.centroid.template head<2>(),
                        Eigen::Matrix2d::Identity() * sigma * sigma, v0, v0_sigma);
    t.z = cand.features.centroid.z();
    t.last_time = frame.time;
    t.hits = 1;
    t.features = cand.features;
    t.large = cand.features.large;
    t.max_height = cand.features.large ? 0.0 : cand.features.height;
    t.max_standing_height = cand.features.large ? 0.0 : decision_.standingHeight(cand.features);
    t.max_length = cand.features.large ? 0.0 : cand.features.length;
    t.fast.push_back(0);
    t.seen_occluded = cand.features.occluded;
    t.history.emplace_back(cand.features.centroid.x(), cand.features.centroid.y(), frame.time);
    t.long_history = t.history;
    if (frame.use_registration && !t.large && registrable(cand.features)) {
      ensurePoints(frame.cloud, frame.observations[c].indices, cand);
      t.model = makeModel(cand, frame.sensor_origin);
    }
    auto& r = results_[c];
    r.track_id = t.id;
    tracks_.push_back(std::move(t));
  }
}

}  // namespace pcl_movers
