/*
 * Helpers shared by the benchmarks in this folder.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <ctime>

namespace pcl_movers_bench {

/** \brief CPU time of the calling thread [ms]. The benchmark machine is shared: unlike wall-clock
 * time, thread CPU time is not inflated when other processes hold the cores. */
inline double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

}  // namespace pcl_movers_bench
