/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/ego_motion_estimator.h>

#ifndef PCL_NO_PRECOMPILE
#include <pcl_movers/impl/ego_motion_estimator.hpp>

PCL_MOVERS_INSTANTIATE_EgoMotionEstimator(pcl::PointXYZ)
    PCL_MOVERS_INSTANTIATE_EgoMotionEstimator(pcl::PointXYZI)
#endif  // PCL_NO_PRECOMPILE
