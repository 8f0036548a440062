/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/range_image_organizer.h>

#ifndef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/range_image_organizer.hpp>

#include <pcl/point_types.h>

template class pcl_movers::RangeImageOrganizer<pcl::PointXYZ>;
template class pcl_movers::RangeImageOrganizer<pcl::PointXYZI>;
#endif
