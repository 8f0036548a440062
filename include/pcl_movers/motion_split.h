/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/free_space_map.h>

#include <pcl/PointIndices.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace pcl_movers {

/** \brief Splits the moving part of a cluster off the static surface it was joined to.
 *
 * Region growing joins range-image neighbours by depth alone, so a person walking 0.3 m from a
 * wall, a hedge or a parked car becomes part of that surface's cluster and is never tracked on
 * its own. What tells the two apart is not their shape but their history: the space the walker
 * occupies now was seen empty by an earlier scan (FreeSpaceMap::Sight::kThrough), while the wall
 * was seen where it is (kAt). A cluster holding both is cut: its seen-through points seed parts
 * that grow over neighbouring points not seen where they are and continuing the part's surface
 * within a depth step (a walker is smooth, porous foliage is not); touching parts are merged (a
 * car's side and back); a part with enough seen-through points becomes a cluster of its own when
 * the parts hold most of the cluster's seen-through points (foliage is seen through here and
 * there all over); what remains is the static surface.
 * A sample of each cluster is judged first (Parameters::sample_stride): most are static, and
 * judging every point of every cluster would cost more than the rest of the evidence.
 *
 * The earlier scan is one long lag back (free_space.long_lag, 1.5 s): by then even a 0.5 m/s
 * walker has moved further than its own width, so its trailing side is not taken for a static
 * surface that its own earlier body occupied.
 */
class MotionSplitter {
 public:
  /** \brief The settings; the detector takes them from its keys (named per member). */
  struct Parameters {
    /// Points of a part, of its seen-through points and of the static rest of its cluster
    /// (segment.min_cluster_points).
    int min_points = 8;
    /// Empty range-image cells bridged along a row, as region growing does (segment.max_gap).
    int max_gap = 2;
    /// Depth step [m] a part grows over to a point not seen through (segment.depth_min):
    /// a walker's surface is continuous within centimetres, the wall behind it is a step away.
    float depth_step = 0.1f;
    /// Fraction of a part's points that must be seen through, and of the cluster's seen-through
    /// points that its parts must hold (free_space.long_min_fraction).
    float min_through_fraction = 0.5f;
    /// One point in sample_stride of a cluster (on image diagonals) is judged first, and the
    /// rest only when they show min_points / sample_stride points of each kind: most clusters
    /// are static throughout, and a walker of 8 points still holds two samples.
    int sample_stride = 4;
  };

  /** \brief What the earlier scan saw along points of cluster c: `sights[i]` for its point at
   * position `positions[i]` of its indices (sights is resized). Called at most twice per cluster,
   * for a sample and then for the rest of a cluster the sample shows mixed: whole lists, so that
   * a judge can work through them in one pass. */
  using Judge = std::function<void(std::size_t cluster, const std::vector<int>& positions,
                                   std::vector<FreeSpaceMap::Sight>& sights)>;
  /** \brief The distance from the sensor of each point of cluster c (`ranges[k]` for its k-th
   * point; ranges is resized). Asked only of the clusters whose parts are grown. */
  using Ranges = std::function<void(std::size_t cluster, std::vector<float>& ranges)>;

  /** \brief The moving parts found in one cluster. */
  struct ClusterSplit {
    std::size_t cluster = 0;
    /// Per part, the positions (into the cluster's indices) of its points, in the order of
    /// their cells. The rest of the cluster is its static surface.
    std::vector<std::vector<int>> parts;
  };

  void setParameters(const Parameters& parameters) { parameters_ = parameters; }
  const Parameters& getParameters() const { return parameters_; }

  /** \brief The clusters (indices into a `width` × `height` range image) that hold both a
   * moving part and a static surface, and their parts; in the order of the clusters.
   * \param[in] judge what the earlier scan saw along a cluster's points
   * \param[in] ranges distances from the sensor of a cluster's points */
  std::vector<ClusterSplit> findSplits(int width, int height,
                                       const std::vector<pcl::PointIndices>& clusters,
                                       const Judge& judge, const Ranges& ranges);

  /** \brief Applies `splits` (of findSplits() on the same clusters, or on a list whose indices
   * correspond to theirs position by position, as a cluster's world points do) in place: a
   * split cluster keeps its static rest in its place (removed when under min_points), the parts
   * are appended after all clusters, in the order of `splits`.
   * \return the number of parts split off */
  int applySplits(const std::vector<ClusterSplit>& splits,
                  std::vector<pcl::PointIndices>& clusters);

  /** \brief findSplits() and applySplits() on `clusters`.
   * \return the number of parts split off (0: `clusters` unchanged) */
  int split(int width, int height, std::vector<pcl::PointIndices>& clusters, const Judge& judge,
            const Ranges& ranges) {
    return applySplits(findSplits(width, height, clusters, judge, ranges), clusters);
  }

 protected:
  /** \brief The parts of one cluster grown from its seen-through points (positions ordered by
   * cell); empty unless they hold half of the cluster's `through_all` seen-through points.
   * Reads sight_ and ranges_. */
  std::vector<std::vector<int>> growParts(int width, int height, const pcl::PointIndices& cluster,
                                          int through_all);

  /** \brief Judges the points at positions_ of `cluster` into sight_ (marking them judged_)
   * and adds the seen-through and seen-where-they-are ones to `through` and `at`. */
  void judgePositions(std::size_t cluster, const Judge& judge, int& through, int& at);

  /** \brief `cell` is one of the points judged first (and a seed of the parts). */
  bool sampled(int width, int cell) const;
  /** \brief sampled() of every cell of a width x height image into sampled_cells_, when the
   * size or the stride changed: a byte read per point then, not two integer divisions (about a
   * quarter of the split's time on a KITTI frame went to them). */
  void indexSampledCells(int width, int height);
  /** \brief Calls `visit(position)` for the cluster's points next to `cell` in the image (a
   * template, not a std::function: it is called for every neighbour of every grown point). */
  template <typename Visit>
  void forEachNeighbour(int width, int height, int cell, const Visit& visit) const;

  Parameters parameters_;
  std::vector<int> member_;   ///< per cell: position in the cluster being split, or -1
  std::vector<int> part_of_;  ///< per position of that cluster: non-zero when in a part
  std::vector<int> queue_;
  std::vector<FreeSpaceMap::Sight> sight_;  ///< per point of the cluster being split, once judged
  std::vector<std::uint8_t> judged_;        ///< per point of that cluster: sight_ is set
  std::vector<int> positions_;              ///< points of that cluster to be judged
  std::vector<FreeSpaceMap::Sight> judged_sights_;  ///< the judge's answer for positions_
  std::vector<float> ranges_;                       ///< per point of that cluster: its distance
  std::vector<std::uint8_t> in_part_;               ///< applySplits(): per position, in a part
  std::vector<std::uint8_t> sampled_cells_;         ///< sampled() per cell (indexSampledCells())
  int sampled_width_ = 0, sampled_stride_ = 0;
};

}  // namespace pcl_movers
