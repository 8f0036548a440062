/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/range_image_region_growing.h>

#ifndef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/range_image_region_growing.hpp>

PCL_MOVERS_INSTANTIATE_RangeImageRegionGrowing(pcl::PointXYZ)
    PCL_MOVERS_INSTANTIATE_RangeImageRegionGrowing(pcl::PointXYZI)
#endif  // PCL_NO_PRECOMPILE
