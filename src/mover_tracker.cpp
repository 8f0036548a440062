/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/mover_tracker.h>

#ifndef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/mover_tracker.hpp>

template class pcl_movers::MoverTracker<pcl::PointXYZ>;
template class pcl_movers::MoverTracker<pcl::PointXYZI>;
#endif
