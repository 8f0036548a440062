/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/ground_plane_filter.h>

#ifndef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/ground_plane_filter.hpp>

PCL_MOVERS_INSTANTIATE_GroundPlaneFilter(pcl::PointXYZ)
    PCL_MOVERS_INSTANTIATE_GroundPlaneFilter(pcl::PointXYZI)
#endif  // PCL_NO_PRECOMPILE
