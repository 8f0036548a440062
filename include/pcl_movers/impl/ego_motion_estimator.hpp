/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>
#include <pcl_movers/ego_motion_estimator.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace pcl_movers {

template <typename PointT>
void EgoMotionEstimator<PointT>::reset() {
  keyframes_.clear();
  map_voxels_.clear();
  map_index_.clear();
  scan_voxels_.clear();
  pose_ = motion_ = keyframe_pose_ = Eigen::Isometry3d::Identity();
  frames_ = 0;
  last_fitness_ = 0.0;
  last_correspondences_ = 0;
  last_iterations_ = 0;
}

template <typename PointT>
std::int64_t EgoMotionEstimator<PointT>::keyOf(const Eigen::Vector3f& p,
                                               Eigen::Vector3i* cell) const {
  const float inv = 1.f / voxel_size_;
  const Eigen::Vector3i c(static_cast<int>(std::floor(p.x() * inv)),
                          static_cast<int>(std::floor(p.y() * inv)),
                          static_cast<int>(std::floor(p.z() * inv)));
  if (cell) *cell = c;
  return detail::VoxelHashIndex::pack(c.x(), c.y(), c.z());
}

template <typename PointT>
std::size_t EgoMotionEstimator<PointT>::summarise(const PointCloud& scan) {
  scan_voxels_.clear();
  scan_index_.clear(std::max<std::size_t>(1024, scan_index_.size()));
  std::size_t finite = 0;
  const float min2 = min_range_ * min_range_, max2 = max_range_ * max_range_;
  const float inv = 1.f / voxel_size_;
  std::int64_t last_key = detail::VoxelHashIndex::kEmpty;
  int last = -1;
  std::uint64_t rng = 0x2545F4914F6CDD1Dull;  // fixed seed: the same scan gives the same result
  for (const auto& p : scan.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    ++finite;
    const float r2 = p.x * p.x + p.y * p.y + p.z * p.z;
    if (r2 < min2 || r2 > max2) continue;
    const std::int64_t key =
        detail::VoxelHashIndex::pack(static_cast<std::int64_t>(std::floor(p.x * inv)),
                                     static_cast<std::int64_t>(std::floor(p.y * inv)),
                                     static_cast<std::int64_t>(std::floor(p.z * inv)));
    // Scanners emit points in firing order, so consecutive points mostly share a voxel: the
    // table is consulted only when the voxel changes.
    if (key != last_key) {
      last = scan_index_.insert(key, static_cast<int>(scan_voxels_.size()));
      if (last == static_cast<int>(scan_voxels_.size())) scan_voxels_.emplace_back();
      last_key = key;
    }
    ScanVoxel& sv = scan_voxels_[last];
    detail::VoxelMoments& m = sv.moments;
    const double x = p.x, y = p.y, z = p.z;
    m.n += 1.0;
    // The registered point is one of the voxel's points drawn uniformly (reservoir sampling),
    // not the voxel mean: means sit at positions fixed to the sensor's voxel grid, and matching
    // them to a map built the same way has a false optimum at zero motion (measured: on the
    // simulated urban street the first 0.5 m step was estimated as 0.001 m).
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    if ((rng >> 33) % static_cast<std::uint64_t>(m.n) == 0)
      sv.sample = Eigen::Vector3f(p.x, p.y, p.z);
    m.sum += Eigen::Vector3d(x, y, z);
    // Upper triangle only (written out: Eigen's triangular product is a call per point).
    m.outer(0, 0) += x * x;
    m.outer(0, 1) += x * y;
    m.outer(0, 2) += x * z;
    m.outer(1, 1) += y * y;
    m.outer(1, 2) += y * z;
    m.outer(2, 2) += z * z;
  }
  for (auto& v : scan_voxels_) {
    v.moments.outer.template triangularView<Eigen::StrictlyLower>() = v.moments.outer.transpose();
  }
  return finite;
}

template <typename PointT>
const typename EgoMotionEstimator<PointT>::MapVoxel* EgoMotionEstimator<PointT>::plane(
    std::int64_t key) {
  const int idx = map_index_.find(key);
  if (idx < 0) return nullptr;
  MapVoxel& v = map_voxels_[idx];
  if (v.dirty) {
    v.dirty = false;
    v.planar = v.linear = false;
    const double n = v.moments.n;
    if (n >= std::max(3, normal_neighbours_)) {
      const Eigen::Vector3d mean = v.moments.sum / n;
      const Eigen::Matrix3d cov = v.moments.outer / n - mean * mean.transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
      es.computeDirect(cov);
      const Eigen::Vector3d ev = es.eigenvalues();  // ascending
      // Planar: the normal direction carries little of the spread. Linear: one direction
      // carries nearly all of it (poles, trunks, kerb edges): in a street these are often the
      // only surfaces that face the direction of travel, so they are kept, as lines. Anything
      // else (vegetation, corners) has no meaningful point-to-surface distance.
      if (ev(2) > 0 && ev(0) < 0.1 * ev(1)) {
        Eigen::Vector3f nrm = es.eigenvectors().col(0).template cast<float>().normalized();
        // Optionally, ground-like normals are made exactly vertical so that the ground fixes
        // only z, roll and pitch (a guard against ground artefacts that travel with the
        // sensor). Off by default: on the simulated rolling `open` terrain the gently sloping
        // ground is what pins x and y.
        if (vertical_ground_normals_ && std::abs(nrm.z()) > 0.95f)
          nrm = Eigen::Vector3f(0.f, 0.f, nrm.z() > 0 ? 1.f : -1.f);
        v.mean = mean.template cast<float>();
        v.normal = nrm;
        v.planar = nrm.allFinite();
        v.linear = false;
      } else if (ev(2) > 0 && ev(1) < 0.1 * ev(2) && std::abs(es.eigenvectors()(2, 2)) > 0.7) {
        // Only steep lines: a voxel crossed by a single scan line (a ring on the ground or on a
        // wall far away) is also "linear", but that line is where the beam happened to hit,
        // fixed to the sensor, and matching it pins the estimate to zero motion (measured on
        // the simulated urban street: the first 0.5 m step came out as 0.003 m).
        v.mean = mean.template cast<float>();
        v.normal = es.eigenvectors().col(2).template cast<float>().normalized();  // direction
        v.linear = v.planar = v.normal.allFinite();
      }
    }
  }
  return v.planar ? &v : nullptr;
}

template <typename PointT>
void EgoMotionEstimator<PointT>::addKeyframe(const Eigen::Isometry3d& pose) {
  Keyframe kf;
  kf.keys.reserve(scan_voxels_.size());
  kf.moments.reserve(scan_voxels_.size());
  const Eigen::Matrix3d r = pose.linear();
  const Eigen::Vector3d t = pose.translation();
  if (map_index_.size() == 0) map_index_.clear(4 * scan_voxels_.size());
  for (const auto& sv : scan_voxels_) {
    // Moments move exactly with a rigid transform: sum(Rp+t) and sum((Rp+t)(Rp+t)^T).
    const detail::VoxelMoments& m = sv.moments;
    detail::VoxelMoments w;
    w.n = m.n;
    w.sum = r * m.sum + m.n * t;
    const Eigen::Vector3d rs = r * m.sum;
    w.outer = r * m.outer * r.transpose() + rs * t.transpose() + t * rs.transpose() +
              m.n * t * t.transpose();
    // The whole scan voxel goes to the map voxel of its mean: one update per scan voxel instead
    // of one per point (the planes see a patch smeared by at most one voxel, along itself).
    const std::int64_t key = keyOf((w.sum / w.n).template cast<float>());
    const int idx = map_index_.insert(key, static_cast<int>(map_voxels_.size()));
    if (idx == static_cast<int>(map_voxels_.size())) map_voxels_.emplace_back();
    MapVoxel& mv = map_voxels_[idx];
    mv.moments.n += w.n;
    mv.moments.sum += w.sum;
    mv.moments.outer += w.outer;
    mv.dirty = true;
    kf.keys.push_back(key);
    kf.moments.push_back(w);
  }
  keyframes_.push_back(std::move(kf));
  keyframe_pose_ = pose;

  // Sliding window: subtract what the oldest keyframes added.
  while (static_cast<int>(keyframes_.size()) > std::max(1, local_map_size_)) {
    const Keyframe& old = keyframes_.front();
    for (std::size_t i = 0; i < old.keys.size(); ++i) {
      const int idx = map_index_.find(old.keys[i]);
      if (idx < 0) continue;
      MapVoxel& mv = map_voxels_[idx];
      mv.moments.n -= old.moments[i].n;
      mv.moments.sum -= old.moments[i].sum;
      mv.moments.outer -= old.moments[i].outer;
      if (mv.moments.n < 0.5) mv.moments = detail::VoxelMoments();  // no rounding residue
      mv.dirty = true;
    }
    keyframes_.pop_front();
  }

  // Emptied voxels stay in the table (it cannot erase); rebuild it once they are the majority,
  // so that memory follows the local map rather than the whole trajectory.
  std::size_t live = 0;
  for (const auto& v : map_voxels_) live += v.moments.n > 0.5;
  if (map_voxels_.size() > 2 * live + 4096) {
    // Every live voxel holds a contribution of a keyframe still in the window, under the key
    // it was added with: copy the live voxels in that order into a fresh table.
    detail::VoxelHashIndex rekey;
    rekey.clear(2 * live);
    std::vector<MapVoxel> kept;
    kept.reserve(live);
    for (const auto& kf : keyframes_)
      for (const std::int64_t key : kf.keys) {
        const int old = map_index_.find(key);
        if (old < 0 || !(map_voxels_[old].moments.n > 0.5)) continue;
        if (rekey.find(key) >= 0) continue;
        rekey.insert(key, static_cast<int>(kept.size()));
        kept.push_back(map_voxels_[old]);
      }
    map_voxels_.swap(kept);
    map_index_ = std::move(rekey);
  }
}

template <typename PointT>
bool EgoMotionEstimator<PointT>::registerToMap(Eigen::Isometry3d& pose) {
  last_correspondences_ = 0;
  last_iterations_ = 0;
  last_fitness_ = 0.0;
  std::vector<int> source;
  source.reserve(scan_voxels_.size());
  const double min_points = std::max(1, normal_neighbours_);
  for (std::size_t i = 0; i < scan_voxels_.size(); ++i)
    if (scan_voxels_[i].moments.n >= min_points) source.push_back(static_cast<int>(i));
  if (map_voxels_.empty() || source.size() < 10) return false;
  const int min_correspondences = 30;
  struct Match {
    Eigen::Vector3d p, n;
    double r;
  };
  std::vector<Match> matches;
  matches.reserve(source.size());
  std::vector<double> abs_r;
  // A few thousand voxel means spread over the scan pin the pose as well as all of them; the
  // coarse phase, which searches 27 voxels per point, uses fewer still.
  auto strideFor = [&](int budget) {
    return budget > 0 ? std::max<std::size_t>(1, (source.size() + budget - 1) / budget)
                      : std::size_t(1);
  };
  const std::size_t fine_stride = strideFor(max_source_points_);
  const std::size_t coarse_stride =
      strideFor(max_source_points_ > 0 ? std::max(1, max_source_points_ / 4) : 0);
  bool ok = false;
  const int iterations = std::max(2, max_iterations_);
  // Two phases. Coarse: wide gate, wide kernel, no trimming — while the guess is off, the large
  // residuals are exactly the informative ones (in a street the few surfaces facing the direction
  // of travel), and trimming or a tight kernel would pin the estimate to the guess. Fine: once
  // converged, the plane of the voxel each point falls in, a shrinking gate, trimming and the
  // Cauchy kernel reject movers and clutter.
  const int coarse_iterations = iterations / 2;
  bool fine = false;
  int fine_start = 0;
  const float gate_max = max_correspondence_distance_;
  for (int it = 0; it < iterations; ++it) {
    if (!fine && it >= coarse_iterations) {
      fine = true;
      fine_start = it;
    }
    double gate = gate_max, kernel = gate_max;
    double trim = 1.0;
    if (fine) {
      const int fine_total = std::max(1, iterations - fine_start - 1);
      const double frac = std::min(1.0, double(it - fine_start) / fine_total);
      gate = gate_max * (1.0 - frac * 2.0 / 3.0);
      kernel = kernel_scale_;
      trim = std::clamp(double(trim_ratio_), 0.05, 1.0);
    }
    const Eigen::Isometry3f posef = pose.cast<float>();
    matches.clear();
    const std::size_t stride = fine ? fine_stride : coarse_stride;
    for (std::size_t s = 0; s < source.size(); s += stride) {
      const Eigen::Vector3f q = posef * scan_voxels_[source[s]].sample;
      Eigen::Vector3i cell;
      const MapVoxel* best = nullptr;
      // Fine: the plane of the voxel the point falls in (one lookup). Coarse, and in the fine
      // phase when that voxel has no plane: the nearest plane centre among the 27 surrounding
      // voxels. Without that fallback, points that are still off (typically on the few static
      // surfaces facing the direction of travel, when the guess is wrong) lose their
      // correspondences while a mover keeping pace with the sensor keeps its own, and the
      // estimate locks onto the mover (measured on the simulated urban street).
      if (fine) best = plane(keyOf(q, &cell));
      if (!best) {
        keyOf(q, &cell);
        float best_d2 = float(gate * gate);
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              // Fine phase: the 6 face neighbours suffice (the point is within a voxel).
              if (fine && std::abs(dx) + std::abs(dy) + std::abs(dz) != 1) continue;
              const MapVoxel* v =
                  plane(detail::VoxelHashIndex::pack(cell.x() + dx, cell.y() + dy, cell.z() + dz));
              if (!v) continue;
              const float d2 = (v->mean - q).squaredNorm();
              if (d2 <= best_d2) {
                best_d2 = d2;
                best = v;
              }
            }
      }
      if (!best) continue;
      Eigen::Vector3f nrm = best->normal;
      double r = nrm.dot(q - best->mean);
      if (best->linear) {
        // Point-to-line: the residual is the distance to the line, along the perpendicular
        // from it (the gradient of that distance).
        const Eigen::Vector3f v = q - best->mean;
        const Eigen::Vector3f perp = v - v.dot(best->normal) * best->normal;
        const float d = perp.norm();
        if (!(d > 1e-6f)) continue;
        nrm = perp / d;
        r = d;
      }
      if (std::abs(r) > gate) continue;
      matches.push_back({q.template cast<double>(), nrm.template cast<double>(), r});
    }
    if (static_cast<int>(matches.size()) < min_correspondences) break;
    // Trim: keep the smallest residuals.
    abs_r.resize(matches.size());
    for (std::size_t i = 0; i < matches.size(); ++i) abs_r[i] = std::abs(matches[i].r);
    const std::size_t keep =
        std::max<std::size_t>(min_correspondences, static_cast<std::size_t>(trim * matches.size()));
    double threshold = std::numeric_limits<double>::infinity();
    if (keep < matches.size()) {
      std::nth_element(abs_r.begin(), abs_r.begin() + keep - 1, abs_r.end());
      threshold = abs_r[keep - 1];
    }
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    double sum_r2 = 0;
    int used = 0;
    const double c2 = kernel * kernel;
    for (const auto& m : matches) {
      if (std::abs(m.r) > threshold) continue;
      Eigen::Matrix<double, 6, 1> J;
      J.head<3>() = m.p.cross(m.n);
      J.tail<3>() = m.n;
      const double w = 1.0 / (1.0 + m.r * m.r / c2);
      H.template selfadjointView<Eigen::Upper>().rankUpdate(J, w);
      g += w * J * m.r;
      sum_r2 += m.r * m.r;
      ++used;
    }
    H.template triangularView<Eigen::StrictlyLower>() = H.transpose();
    last_correspondences_ = used;
    last_fitness_ = std::sqrt(sum_r2 / std::max(1, used));
    last_iterations_ = it + 1;
    Eigen::Matrix<double, 6, 1> delta = Eigen::Matrix<double, 6, 1>::Zero();
    if (planar_motion_) {
      // Unknowns: yaw rate (index 2), tx (3), ty (4).
      const int sel[3] = {2, 3, 4};
      Eigen::Matrix3d h;
      Eigen::Vector3d gg;
      for (int a = 0; a < 3; ++a) {
        gg(a) = g(sel[a]);
        for (int b = 0; b < 3; ++b) h(a, b) = H(sel[a], sel[b]);
      }
      h += 1e-6 * Eigen::Matrix3d::Identity();
      const Eigen::Vector3d x = -h.ldlt().solve(gg);
      for (int a = 0; a < 3; ++a) delta(sel[a]) = x(a);
    } else {
      H += 1e-6 * Eigen::Matrix<double, 6, 6>::Identity();
      delta = -H.ldlt().solve(g);
    }
    if (!delta.allFinite()) break;
    const Eigen::Vector3d w = delta.head<3>();
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    if (w.norm() > 0) step.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).matrix();
    step.translation() = delta.tail<3>();
    pose = step * pose;
    ok = true;
    // The coarse phase only has to bring the points within reach of the fine phase's one-voxel
    // search, so it stops at a ten times looser tolerance.
    if (delta.norm() < (fine ? 1.0 : 10.0) * transformation_epsilon_) {
      if (fine) break;
      fine = true;  // coarse phase converged early: refine
      fine_start = it + 1;
    }
  }
  // Re-orthonormalize: many small products drift off SO(3).
  pose.linear() = Eigen::Quaterniond(pose.linear()).normalized().toRotationMatrix();
  return ok;
}

template <typename PointT>
Eigen::Isometry3d EgoMotionEstimator<PointT>::estimate(const PointCloud& scan) {
  if (summarise(scan) == 0)
    throw InputError("EgoMotionEstimator: the scan has no finite point (" +
                     std::string(scan.empty() ? "empty" : "all NaN/inf") +
                     "); cannot estimate its pose");
  if (frames_ == 0) {
    pose_ = motion_ = Eigen::Isometry3d::Identity();
    addKeyframe(pose_);
    ++frames_;
    return pose_;
  }
  const Eigen::Isometry3d previous = pose_;
  Eigen::Isometry3d guess = constant_velocity_ ? previous * motion_ : previous;
  if (registerToMap(guess)) {
    pose_ = guess;
  } else {
    pose_ = constant_velocity_ ? previous * motion_ : previous;
  }
  motion_ = previous.inverse() * pose_;
  ++frames_;
  const Eigen::Isometry3d since = keyframe_pose_.inverse() * pose_;
  const double angle = Eigen::AngleAxisd(since.linear()).angle();
  if (keyframes_.empty() || since.translation().norm() >= keyframe_distance_ ||
      angle >= keyframe_angle_ || keyframes_.back().keys.size() < 10)
    addKeyframe(pose_);
  return pose_;
}

}  // namespace pcl_movers

#define PCL_MOVERS_INSTANTIATE_EgoMotionEstimator(T) \
  template class pcl_movers::EgoMotionEstimator<T>;
