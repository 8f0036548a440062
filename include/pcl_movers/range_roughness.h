/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl/PointIndices.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pcl_movers {

/** \brief Per cluster of an organized cloud, how rough its surface is in the range image: the
 * median range step [m] between cells of the cluster that are neighbours in a row, and the same
 * between neighbours in a column, the smaller of the two (NaN with fewer than 3 pairs either
 * way).
 *
 * Foliage is porous: each ray ends at a random depth inside it, so neighbouring cells differ by
 * about the depth rays penetrate (a tree's canopy: tenths of a metre and more), along rows and
 * columns alike. A solid surface's neighbours differ by the sensor's range noise, except along
 * one direction where it is seen at a grazing angle (a car's side nearly along the line of
 * sight: its row neighbours, not its column neighbours), hence the smaller of the two.
 *
 * \param cell_range per cell of the range image (row-major): its range [m]
 * (RangeImageRegionGrowing::getCellRanges(); only the clusters' cells are read)
 * \param width the range image's width
 * \param cell_cluster per cell: the index of the cluster holding it, or a negative value
 * \param clusters the clusters
 * \param[out] roughness per cluster [m] */
inline void clusterRoughness(const std::vector<float>& cell_range, std::size_t width,
                             const std::vector<int>& cell_cluster,
                             const std::vector<pcl::PointIndices>& clusters,
                             std::vector<float>& roughness) {
  const std::size_t n = cell_range.size();
  roughness.assign(clusters.size(), std::numeric_limits<float>::quiet_NaN());
  if (cell_cluster.size() != n || width == 0) return;
  std::vector<float> along_row, along_column;
  const auto median = [](std::vector<float>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  };
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    along_row.clear();
    along_column.clear();
    for (const auto index : clusters[c].indices) {
      const auto i = static_cast<std::size_t>(index);
      const auto step = [&](std::size_t j, std::vector<float>& out) {
        if (j < n && cell_cluster[j] == static_cast<int>(c))
          out.push_back(std::abs(cell_range[j] - cell_range[i]));
      };
      if ((i + 1) % width != 0) step(i + 1, along_row);
      step(i + width, along_column);
    }
    float rough = std::numeric_limits<float>::infinity();
    if (along_row.size() >= 3) rough = std::min(rough, median(along_row));
    if (along_column.size() >= 3) rough = std::min(rough, median(along_column));
    if (std::isfinite(rough)) roughness[c] = rough;
  }
}

}  // namespace pcl_movers
