/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <string>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief Name of the per-point time field of the PCD at `path` as drivers write it (`time`,
 * `t`, `timestamp`, first found in this order), or "" when it has none. Reads the header only;
 * throws InputError when the file cannot be read. */
std::string pointTimeField(const std::string& path);

/** \brief Per-point times of the PCD at `path` in the file's point order, in seconds after the
 * start of the scan; empty when the file has no time field (see pointTimeField()).
 *
 * - `time` (Velodyne driver, float seconds relative to the scan's stamp): taken as it is, or
 *   shifted by its smallest finite value when some are negative (a scan stamped at its end);
 * - `t` (Ouster driver, integer nanoseconds from the scan's start): converted to seconds;
 * - `timestamp` (Hesai, Livox; absolute seconds, or nanoseconds when above 1e12): the smallest
 *   finite value is subtracted (kept in double precision until then).
 *
 * Throws InputError naming the file when it cannot be read. */
std::vector<float> readPointTimes(const std::string& path);

}  // namespace io
}  // namespace pcl_movers
