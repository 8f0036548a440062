/*
 * Helpers shared by the tests: files, temporary folders and running the pcl_movers_* tools as a
 * user does (a separate process).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace test_util {

/** \brief The whole file (binary), "" when it cannot be read. */
inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/** \brief Writes (replaces) the file with `text`, byte for byte. */
inline void writeFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

/** \brief A new empty folder /tmp/PREFIX_XXXXXX (mkdtemp), left in place. */
inline std::string makeTempDir(const std::string& prefix) {
  std::string tmpl = (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
  if (!mkdtemp(tmpl.data())) return "";
  return tmpl;
}

/** \brief A new empty folder, removed with everything in it when this goes out of scope. */
class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "pcl_movers_test") : path_(makeTempDir(prefix)) {}
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string str() const { return path_.string(); }
  std::filesystem::path path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/** \brief pcl_movers_NAME of this build; PCL_MOVERS_TOOLS_DIR overrides the folder. */
inline std::string toolPath(const std::string& name) {
  const char* dir = std::getenv("PCL_MOVERS_TOOLS_DIR");
  return std::string(dir && *dir ? dir : PCL_MOVERS_BINARY_DIR "/apps") + "/pcl_movers_" + name;
}

inline bool toolBuilt(const std::string& name) {
  return access(toolPath(name).c_str(), X_OK) == 0;
}

/** \brief What a tool run gave: exit code (-1 when killed by a signal), stdout, stderr. */
struct ToolResult {
  int exit_code = -1;
  std::string out, err;
};

/** \brief Runs pcl_movers_NAME with `args` (each quoted), stdin from /dev/null, at most 120 s. */
inline ToolResult runTool(const std::string& name, const std::vector<std::string>& args) {
  auto quote = [](const std::string& s) {
    std::string q = "'";
    for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  const TempDir logs("pcl_movers_tool_log");
  std::string command = "timeout -k 5 120 " + quote(toolPath(name));
  for (const auto& a : args) command += " " + quote(a);
  command += " >" + quote(logs.str() + "/out") + " 2>" + quote(logs.str() + "/err") + " </dev/null";
  const int status = std::system(command.c_str());
  ToolResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readFile(logs.path() / "out");
  r.err = readFile(logs.path() / "err");
  return r;
}

}  // namespace test_util
