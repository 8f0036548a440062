/*
 * pcl_movers — mover detection in LiDAR sequences from a moving vehicle, after
 * D. Morris, B. Colonna, P. Haley, "Ladar-based mover detection from moving vehicles".
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <stdexcept>
#include <string>

namespace pcl_movers {

/** \brief Thrown for bad user input: missing or malformed files, mismatched counts, bad parameters.
 * The message always names the file (and line, where there is one) and the reason, so tools can
 * print it as is and exit non-zero.
 */
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
  /** \brief "file:line: reason" (line omitted when 0). */
  InputError(const std::string& file, std::size_t line, const std::string& reason)
      : std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " +
                           reason) {}
};

}  // namespace pcl_movers
