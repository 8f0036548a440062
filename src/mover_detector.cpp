/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/mover_detector.h>

#ifndef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/mover_detector.hpp>

template class pcl_movers::MoverDetector<pcl::PointXYZ>;
template class pcl_movers::MoverDetector<pcl::PointXYZI>;
#endif
