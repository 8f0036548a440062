/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

namespace pcl_movers {
/** \brief Text in and out for the settings of the stage parameter structs (GroundParameters,
 * DetectorParameters, ...): the config file, the tools' options and summary.json. */
namespace detail {
/** \brief How an error names the setting `key` of a stage: "--" + kebab-case for a tool's
 * option (--max-slope-deg), else prefix + key ("parameter ground." + "max_slope_deg"). */
inline std::string parameterName(const std::string& prefix, std::string key) {
  if (prefix == "--")
    for (char& c : key)
      if (c == '_') c = '-';
  return prefix + key;
}
inline std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}
inline void parseValue(const std::string& text, double& v, const std::string& key,
                       const std::string& where) {
  char* end = nullptr;
  const double d = std::strtod(text.c_str(), &end);
  if (text.empty() || end == text.c_str() || *end != '\0' || !std::isfinite(d))
    throw InputError(where + ": " + key + ": '" + text + "' is not a finite number");
  v = d;
}
inline void parseValue(const std::string& text, int& v, const std::string& key,
                       const std::string& where) {
  char* end = nullptr;
  const long l = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || end == text.c_str() || *end != '\0' || l < -1000000000L || l > 1000000000L)
    throw InputError(where + ": " + key + ": '" + text + "' is not an integer");
  v = static_cast<int>(l);
}
inline void parseValue(const std::string& text, bool& v, const std::string& key,
                       const std::string& where) {
  if (text == "1" || text == "true" || text == "on") {
    v = true;
  } else if (text == "0" || text == "false" || text == "off") {
    v = false;
  } else {
    throw InputError(where + ": " + key + ": '" + text +
                     "' is not a switch (1/0, true/false, on/off)");
  }
}
inline void parseValue(const std::string& text, std::string& v, const std::string& key,
                       const std::string& where) {
  if (text.empty()) throw InputError(where + ": " + key + ": empty value");
  v = text;
}
inline std::string formatValue(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}
inline std::string formatValue(bool v) {
  return v ? "true" : "false";
}
inline std::string formatValue(int v) {
  return std::to_string(v);
}
inline std::string formatValue(const std::string& v) {
  return v;
}
inline std::string jsonValue(double v) {
  return formatValue(v);
}
inline std::string jsonValue(bool v) {
  return formatValue(v);
}
inline std::string jsonValue(int v) {
  return formatValue(v);
}
inline std::string jsonValue(const std::string& v) {
  return "\"" + v + "\"";
}
}  // namespace detail

}  // namespace pcl_movers
