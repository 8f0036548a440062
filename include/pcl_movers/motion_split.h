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
 * that grow over neighbouring points that were not seen where they are (seen-through ones, and
 * hidden or unknown ones that continue the part's surface within a depth step), and a part with
 * enough seen-through points becomes a cluster of its own; what remains is the static surface.
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
    /// Fraction of a part's tested points that must be seen through
    /// (free_space.long_min_fraction).
    float min_through_fraction = 0.5f;
  };

  void setParameters(const Parameters& parameters) { parameters_ = parameters; }
  const Parameters& getParameters() const { return parameters_; }

  /** \brief Splits `clusters` (indices into a `width` × `height` range image).
   * \param[in] ranges distance from the sensor of every cell (only cluster cells are read)
   * \param[in] sights per cluster, per point (in the cluster's order): what the earlier scan saw
   * \param[out] out the clusters after the split: each input cluster's static rest in its place
   * (dropped when under min_points), the parts appended after all of them
   * \return the number of parts split off */
  int split(int width, int height, const std::vector<float>& ranges,
            const std::vector<pcl::PointIndices>& clusters,
            const std::vector<std::vector<FreeSpaceMap::Sight>>& sights,
            std::vector<pcl::PointIndices>& out);

 protected:
  /** \brief The parts of one cluster grown from its seen-through points; appends them to
   * `parts` and marks their points in part_of_ (non-zero: in an accepted part). */
  void growParts(int width, int height, const std::vector<float>& ranges,
                 const pcl::PointIndices& cluster, const std::vector<FreeSpaceMap::Sight>& sight,
                 std::vector<pcl::PointIndices>& parts);

  /** \brief Calls `visit(position)` for the cluster's points next to `cell` in the image. */
  void forEachNeighbour(int width, int height, int cell,
                        const std::function<void(int)>& visit) const;

  Parameters parameters_;
  std::vector<int> member_;   ///< per cell: position in the cluster being split, or -1
  std::vector<int> part_of_;  ///< per position of that cluster: non-zero when in a part
  std::vector<int> queue_;
};

}  // namespace pcl_movers
