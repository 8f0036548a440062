/*
 * Shared plumbing of the pcl_movers_* tools (not installed). No global state: every tool passes
 * what it needs explicitly.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/common.h>
#include <pcl_movers/ground_parameters.h>
#include <pcl_movers/parameter_io.h>
#include <pcl_movers/segmentation_parameters.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <exception>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace pcl_movers {
namespace tools {

/** \brief True when -h or --help is among the arguments. */
inline bool wantsHelp(int argc, char** argv) {
  return pcl::console::find_switch(argc, argv, "-h") ||
         pcl::console::find_switch(argc, argv, "--help");
}

/** \brief One command-line option of a tool's OptionTable. */
struct Option {
  std::string name;   ///< --kebab-case; "" makes `help` a heading line of the help text
  std::string value;  ///< name of its value in the help ("M", "FILE"); "" = a flag
  std::string help;   ///< what it does; '\n' continues on an indented line
  std::string def;    ///< default shown in the help; "" = none
  std::vector<std::string> aliases = {};  ///< older spellings, accepted with a warning
};

/** \brief The arguments a tool was given (OptionTable::parse()): options by their name. */
struct Arguments {
  std::vector<std::string> positional;       ///< in order
  std::map<std::string, std::string> given;  ///< option -> value (the last one; "" for flags)
  std::vector<std::pair<std::string, std::string>> list;  ///< every option given, in order
  bool has(const std::string& name) const { return given.count(name) > 0; }
  /** \brief Sets `value` to the option's value when it was given. */
  bool get(const std::string& name, std::string& value) const;
  /** \brief The finite number given to `name` (InputError naming it otherwise), or `fallback`. */
  double number(const std::string& name, double fallback) const;
  /** \brief Every value given to `name`, in order (a repeatable option). */
  std::vector<std::string> all(const std::string& name) const;
};

/** \brief A tool's options, declared once: the argument check, the split into options and
 * positional arguments and the help text all come from it, so the help cannot drift from what
 * the tool accepts. -h/--help is always accepted. Spellings with '_' for '-' (--sensor_height)
 * and an option's aliases are accepted with a deprecation warning on stderr. */
class OptionTable {
 public:
  explicit OptionTable(std::vector<Option> options = {}) : options_(std::move(options)) {}
  void add(Option option) { options_.push_back(std::move(option)); }
  void add(const std::vector<Option>& options);
  /** \brief Splits argv; an unknown option or one without its value throws InputError naming
   * it. Negative numbers are positional arguments or values. */
  Arguments parse(int argc, char** argv) const;
  /** \brief "  --name VALUE  help (default: X)" lines, aligned. */
  std::string help() const;

 private:
  const Option* find(const std::string& name) const;
  std::vector<Option> options_;
};

/** \brief A number as the help shows it (%g, `digits` significant digits). */
std::string str(double value, int digits = 6);

/** \brief Input scans of a tool that takes "file or folder": a single .pcd/.bin/.ply file, or the
 * frames of a sequence folder (see io::SequenceReader), sorted numerically. Throws InputError. */
std::vector<std::string> listScanInputs(const std::string& file_or_folder);

/** \brief Output paths of a "file or folder" tool: for a folder INPUT, OUTPUT is prepared as a
 * folder (see io::prepareOutputDirectory) holding one `<stem>.pcd` per input scan; for a single
 * scan, OUTPUT is a .pcd file that must not exist unless `overwrite`. Throws InputError. */
std::vector<std::string> planScanOutputs(const std::string& input,
                                         const std::vector<std::string>& inputs,
                                         const std::string& output, bool overwrite);

/** \brief Parses a finite number given to `flag`; throws InputError naming the flag. */
double parseNumber(const std::string& flag, const std::string& text);

/** \brief Reads a scan and rejects what cannot be processed (empty, all NaN, infinite
 * coordinates), naming the file and the problem; warns about NaN points of unorganized clouds. */
pcl::PointCloud<pcl::PointXYZI>::Ptr readScanChecked(const std::string& path);

/** \brief x y z intensity label (uint32), in the cloud's order and layout. */
void labelledBlob(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                  const std::vector<std::uint32_t>& labels, pcl::PCLPointCloud2& blob);

/** \brief Writes a PCD next to `path` with `write`, then renames it into place, so a failure
 * never leaves a half-written file. Throws InputError. */
void writeAtomically(const std::string& path,
                     const std::function<int(pcl::PCDWriter&, const std::string&)>& write);

/** \brief The options of one stage's parameter struct (GroundParameters,
 * SegmentationParameters) for a tool: `--kebab-name VALUE` for every setting, with the struct's
 * own defaults and descriptions, so pcl_movers_ground, pcl_movers_segment,
 * pcl_movers_eval_segmentation and the detector cannot drift apart. */
template <typename Parameters>
struct StageOptions {
  Parameters parameters;  ///< the struct's defaults until parse()
  /// Older spellings of an option (setting key -> option names), accepted with a warning.
  std::map<std::string, std::vector<std::string>> aliases;

  /** \brief The options, with the current values as defaults, for a tool's OptionTable. */
  std::vector<Option> options() const {
    std::vector<Option> out;
    Parameters copy = parameters;
    copy.forEachParameter([&](const char* key, const auto& value, const char* doc) {
      const auto alias = aliases.find(key);
      out.push_back({detail::parameterName("--", key), valueName(value), doc,
                     detail::formatValue(value),
                     alias != aliases.end() ? alias->second : std::vector<std::string>{}});
    });
    return out;
  }
  /** \brief Reads the options given, then checks the ranges; throws InputError naming the
   * option. */
  void parse(const Arguments& args) {
    parameters.forEachParameter([&](const char* key, auto& value, const char*) {
      const std::string name = detail::parameterName("--", key);
      std::string text;
      if (args.get(name, text)) detail::parseValue(text, value, name, "option");
    });
    parameters.validate("--");
  }

 private:
  static const char* valueName(double) { return "X"; }
  static const char* valueName(int) { return "N"; }
  static const char* valueName(bool) { return "0|1"; }
};

/** \brief The ground options of the tools that remove the ground; --tilt-deg is the older
 * spelling of --max-slope-deg. */
inline StageOptions<GroundParameters> groundOptions() {
  return {GroundParameters(), {{"max_slope_deg", {"--tilt-deg"}}}};
}
/** \brief The segmentation options; --k, --floor, --gap and --min-size are older
 * spellings. */
inline StageOptions<SegmentationParameters> segmentationOptions() {
  return {SegmentationParameters(),
          {{"depth_ratio", {"--k"}},
           {"depth_min", {"--floor"}},
           {"max_gap", {"--gap"}},
           {"min_cluster_points", {"--min-size"}}}};
}

/** \brief Runs `body`, turns exceptions into a clear "[tool] error: ..." and exit code 1. */
int runTool(const char* tool_name, const std::function<int()>& body);

/** \brief Leaves nothing half-written behind: remembers whether an output file or folder existed
 * before the run and which files the run wrote; unless commit() is called (the run succeeded),
 * the destructor removes those files and, when the run created the output, the output itself. */
class OutputCleanup {
 public:
  explicit OutputCleanup(std::string output);
  ~OutputCleanup();
  OutputCleanup(const OutputCleanup&) = delete;
  OutputCleanup& operator=(const OutputCleanup&) = delete;
  /** \brief A file this run wrote (removed on failure). */
  void track(const std::string& path) { written_.push_back(path); }
  void commit() { committed_ = true; }

 private:
  std::string output_;
  bool existed_;
  bool committed_ = false;
  std::vector<std::string> written_;
};

/** \brief A one-line progress bar on stderr ("[=====>     ] 42/77 frames"), only on a terminal
 * unless `force`. */
class ProgressBar {
 public:
  ProgressBar(std::size_t total, std::string unit = "frames", bool force = false);
  void update(std::size_t done);
  void finish();

 private:
  std::size_t total_;
  std::string unit_;
  bool enabled_;
};

}  // namespace tools
}  // namespace pcl_movers
