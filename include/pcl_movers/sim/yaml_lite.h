/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>

#include <string>
#include <utility>
#include <vector>

namespace pcl_movers {
namespace sim {

/** \brief A node of the small YAML subset the scenario files use.
 *
 * The subset (documented in data/scenarios/README.md): `#` comments, block mappings
 * (`key: value`, nested by indentation with spaces), block sequences (`- item`, including
 * `- key: value` mappings), flow sequences `[1, 2, [3, 4]]`, flow mappings `{a: 1, b: 2}`, plain
 * and quoted scalars. No anchors, tags, multi-line strings or multiple documents: scenario files
 * are short and written by hand, so a strict, small parser with exact line numbers in its errors
 * serves users better than a full YAML dependency.
 */
struct YamlNode {
  enum class Kind { Null, Scalar, Map, Sequence };
  Kind kind = Kind::Null;
  std::string scalar;                                 ///< for Scalar
  std::vector<std::pair<std::string, YamlNode>> map;  ///< for Map, in file order
  std::vector<YamlNode> sequence;                     ///< for Sequence
  std::size_t line = 0;                               ///< 1-based line where the node starts
  bool quoted = false;                                ///< scalar was quoted ("..." or '...')

  bool isMap() const { return kind == Kind::Map; }
  bool isSequence() const { return kind == Kind::Sequence; }
  bool isScalar() const { return kind == Kind::Scalar; }
  /** \brief The value of `key` in a map, or nullptr. */
  const YamlNode* find(const std::string& key) const;
};

/** \brief Parses `text`; errors throw InputError("file:line: reason") using `file_name`. */
YamlNode parseYaml(const std::string& text, const std::string& file_name);

}  // namespace sim
}  // namespace pcl_movers
