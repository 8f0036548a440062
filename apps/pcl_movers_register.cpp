/*
 * pcl_movers_register — registers two object clouds with BhattacharyaRegistration, like pcl_ndt3d:
 * prints the transformation, the Bhattacharyya similarity B and the time; can save the aligned
 * source and the similarity surface as a PNG (the paper's Figure 6).
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/bhattacharya_registration.h>
#include <pcl_movers/io/sequence.h>

#include <pcl/common/io.h>
#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "tool_utils.h"

namespace fs = std::filesystem;
using pcl_movers::InputError;
using Point = pcl::PointXYZ;
using Cloud = pcl::PointCloud<Point>;
using Registration = pcl_movers::BhattacharyaRegistration<Point, Point>;

namespace {

constexpr float kPi = 3.14159265358979f;

/** Every parameter with its default, read from a default-constructed registration so the help
 * text cannot drift from the library. */
struct Options {
  float radius = Registration().getSearchRadius();
  float resolution = Registration().getResolution();
  int nx = Registration().getGridNx(), ny = Registration().getGridNy(),
      nz = Registration().getGridNz();
  float height = Registration().getGridHeight();
  int yaw_samples = Registration().getYawSamples();
  float yaw_step_deg = Registration().getYawStep() * 180.f / kPi;
  float sigma_per_metre = Registration().getSigmaPerMetre();
  float min_sigma = Registration().getMinSigma();
  float min_similarity = Registration().getMinSimilarity();
  bool search_z = Registration().getSearchZ();
  float radius_z = Registration().getSearchRadiusZ();
  std::vector<float> guess;   // tx,ty,tz[,yaw_deg]
  std::vector<float> sensor;  // x,y,z
  std::string output, surface;
  int pixels = 8;
  bool overwrite = false;
};

pcl_movers::tools::OptionTable optionTable() {
  using pcl_movers::tools::str;
  const Options d;
  return pcl_movers::tools::OptionTable(
      {{"--guess", "tx,ty,tz[,yaw]",
        "initial guess, translation [m] and yaw [deg]; centres the\nsearch window", "identity"},
       {"--radius", "M", "translation window half width [m]", str(d.radius)},
       {"--resolution", "M", "density cell size in x/y, also the search step [m]",
        str(d.resolution)},
       {"--grid", "NX,NY,NZ", "density grid in cells",
        std::to_string(d.nx) + "," + std::to_string(d.ny) + "," + std::to_string(d.nz)},
       {"--height", "M", "height covered by the grid [m]", str(d.height)},
       {"--slices", "N", "horizontal slices (grid NZ), e.g. 3", std::to_string(d.nz)},
       {"--yaw-samples", "N", "yaw layers, odd; 1 = translation only",
        std::to_string(d.yaw_samples)},
       {"--yaw-step-deg",
        "D",
        "spacing of the yaw layers [deg]",
        str(d.yaw_step_deg),
        {"--yaw-step"}},
       {"--sigma-per-metre", "S", "Gaussian sigma per metre of range", str(d.sigma_per_metre)},
       {"--min-sigma", "M", "smallest sigma [m]", str(d.min_sigma)},
       {"--min-similarity", "B", "B below this is reported as not converged",
        str(d.min_similarity)},
       {"--search-z", "", "also search vertical shifts", d.search_z ? "on" : "off"},
       {"--radius-z", "M", "vertical window half height with --search-z [m]", str(d.radius_z)},
       {"--sensor", "x,y,z", "sensor position for both clouds", "each PCD VIEWPOINT"},
       {"--output", "FILE.pcd", "write the source moved onto the target (binary PCD)"},
       {"--surface", "FILE.png",
        "write B over the searched translations, one panel per yaw layer\n(x right, y up, guess "
        "in the middle; colour = B, 0 blue .. 1 red)"},
       {"--pixels", "N", "pixels per translation step in the PNG", std::to_string(d.pixels)},
       {"--overwrite", "", "replace existing output files"}});
}

void printHelp(const char* argv0) {
  std::printf(
      "Usage: %s SOURCE.pcd TARGET.pcd [options]\n"
      "  Registers the SOURCE object onto the TARGET object by maximising the Bhattacharyya\n"
      "  similarity B of their surface densities (pcl_movers::BhattacharyaRegistration, after\n"
      "  Morris, Colonna, Haley). Motion model: horizontal translation (+ optional z) and yaw.\n"
      "  Prints the 4x4 transformation (source -> target), its translation and yaw, B in [0,1]\n"
      "  (1 = identical densities; low B = occlusion or a different object), whether it\n"
      "  converged (peak inside the window and B >= the minimum) and the time.\n"
      "  Inputs: PCD or KITTI .bin with x y z; NaN points are skipped, Inf is an error. Point\n"
      "  spread grows with range from the sensor: the PCD VIEWPOINT origin, or --sensor.\n\n"
      "Options (-h, --help: this help):\n%s"
      "Exit status: 0 when the registration ran (converged or not, see the printout), 1 on bad\n"
      "input.\n",
      argv0, optionTable().help().c_str());
}

double parseNumber(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (text.empty() || used != text.size() || !std::isfinite(v))
    throw InputError(flag + ": expected a number, got '" + text + "'");
  return v;
}

std::vector<float> parseList(const std::string& flag, const std::string& text, std::size_t min_n,
                             std::size_t max_n) {
  std::vector<float> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(static_cast<float>(parseNumber(flag, item)));
  if (out.size() < min_n || out.size() > max_n)
    throw InputError(flag + ": expected " + std::to_string(min_n) +
                     (max_n != min_n ? " to " + std::to_string(max_n) : std::string()) +
                     " comma-separated numbers, got '" + text + "'");
  return out;
}

/** Returns the value of option `flag` if present. */
float positive(const std::string& flag, double v) {
  if (!(v > 0)) throw InputError(flag + ": must be positive");
  return static_cast<float>(v);
}

/** The shared scan check of the tools (missing file, empty, all NaN, infinite coordinates), plus
 * what a registration needs: at least two finite points. */
Cloud::Ptr readChecked(const std::string& path) {
  const auto scan = pcl_movers::tools::readScanChecked(path);
  Cloud::Ptr cloud(new Cloud);
  pcl::copyPointCloud(*scan, *cloud);
  std::size_t finite = 0;
  for (const auto& p : *cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) ++finite;
  if (finite < 2) throw InputError(path, 0, "fewer than 2 finite points");
  return cloud;
}

void refuseExisting(const std::string& path, bool overwrite) {
  if (!overwrite && fs::exists(path))
    throw InputError(path, 0, "exists; pass --overwrite to replace it");
}

/** Blue → cyan → yellow → red. */
void colour(float b, unsigned char* rgb) {
  b = std::min(std::max(b, 0.f), 1.f);
  const float r = std::min(std::max(1.5f - std::abs(4.f * b - 3.f), 0.f), 1.f);
  const float g = std::min(std::max(1.5f - std::abs(4.f * b - 2.f), 0.f), 1.f);
  const float bl = std::min(std::max(1.5f - std::abs(4.f * b - 1.f), 0.f), 1.f);
  rgb[0] = static_cast<unsigned char>(255.f * r);
  rgb[1] = static_cast<unsigned char>(255.f * g);
  rgb[2] = static_cast<unsigned char>(255.f * bl);
}

void writeSurface(const std::string& path, const pcl_movers::SimilaritySurface& s, int pixels) {
  const int layers = static_cast<int>(s.yaws.size());
  const int gap = layers > 1 ? 4 : 0;
  const int w = layers * s.nx * pixels + (layers - 1) * gap, h = s.ny * pixels;
  vtkNew<vtkImageData> image;
  image->SetDimensions(w, h, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* data = static_cast<unsigned char*>(image->GetScalarPointer());
  std::fill(data, data + static_cast<std::size_t>(w) * h * 3, static_cast<unsigned char>(255));
  for (int l = 0; l < layers; ++l)
    for (int iy = 0; iy < s.ny; ++iy)
      for (int ix = 0; ix < s.nx; ++ix) {
        unsigned char rgb[3];
        colour(s.at(ix, iy, l), rgb);
        for (int py = 0; py < pixels; ++py)
          for (int px = 0; px < pixels; ++px) {
            // VTK image rows go bottom-up, so +y (iy increasing) is up in the PNG.
            const int x = l * (s.nx * pixels + gap) + ix * pixels + px;
            const int y = iy * pixels + py;
            unsigned char* dst = data + (static_cast<std::size_t>(y) * w + x) * 3;
            dst[0] = rgb[0];
            dst[1] = rgb[1];
            dst[2] = rgb[2];
          }
      }
  // Written next to the target and renamed, so no half-written PNG is left behind.
  const std::string tmp = path + ".tmp.png";
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(tmp.c_str());
  writer->SetInputData(image);
  writer->Write();
  std::error_code ec;
  if (writer->GetErrorCode() != 0 || !fs::exists(tmp)) {
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot write the PNG");
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot write (" + ec.message() + ")");
  }
}

int run(int argc, char** argv) {
  const auto args = optionTable().parse(argc, argv);
  const auto& pos = args.positional;
  if (pos.size() != 2)
    throw InputError("expected SOURCE and TARGET clouds, got " + std::to_string(pos.size()) +
                     " positional argument(s); see -h");
  Options o;
  std::string v;
  if (args.get("--radius", v)) o.radius = positive("--radius", parseNumber("--radius", v));
  if (args.get("--resolution", v))
    o.resolution = positive("--resolution", parseNumber("--resolution", v));
  if (args.get("--grid", v)) {
    const auto g = parseList("--grid", v, 3, 3);
    for (float x : g)
      if (!(x >= 1.f && x <= 1000.f && std::floor(x) == x))
        throw InputError("--grid: cell counts must be integers in 1..1000");
    o.nx = static_cast<int>(g[0]);
    o.ny = static_cast<int>(g[1]);
    o.nz = static_cast<int>(g[2]);
  }
  if (args.get("--height", v)) o.height = positive("--height", parseNumber("--height", v));
  if (args.get("--slices", v)) {
    const double s = parseNumber("--slices", v);
    if (!(s >= 1 && s <= 1000 && std::floor(s) == s))
      throw InputError("--slices: must be an integer in 1..1000");
    o.nz = static_cast<int>(s);
  }
  if (args.get("--yaw-samples", v)) {
    const double s = parseNumber("--yaw-samples", v);
    if (!(s >= 1 && s <= 181 && std::floor(s) == s && static_cast<int>(s) % 2 == 1))
      throw InputError("--yaw-samples: must be an odd integer in 1..181");
    o.yaw_samples = static_cast<int>(s);
  }
  if (args.get("--yaw-step-deg", v))
    o.yaw_step_deg = positive("--yaw-step-deg", parseNumber("--yaw-step-deg", v));
  if (args.get("--sigma-per-metre", v)) {
    o.sigma_per_metre = static_cast<float>(parseNumber("--sigma-per-metre", v));
    if (o.sigma_per_metre < 0.f) throw InputError("--sigma-per-metre: must not be negative");
  }
  if (args.get("--min-sigma", v))
    o.min_sigma = positive("--min-sigma", parseNumber("--min-sigma", v));
  if (args.get("--min-similarity", v)) {
    o.min_similarity = static_cast<float>(parseNumber("--min-similarity", v));
    if (o.min_similarity < 0.f || o.min_similarity > 1.f)
      throw InputError("--min-similarity: must be in [0,1]");
  }
  if (args.get("--radius-z", v)) o.radius_z = positive("--radius-z", parseNumber("--radius-z", v));
  o.search_z = o.search_z || args.has("--search-z");
  if (args.get("--guess", v)) o.guess = parseList("--guess", v, 3, 4);
  if (args.get("--sensor", v)) o.sensor = parseList("--sensor", v, 3, 3);
  if (args.get("--output", v)) o.output = v;
  if (args.get("--surface", v)) o.surface = v;
  if (args.get("--pixels", v)) {
    const double p = parseNumber("--pixels", v);
    if (!(p >= 1 && p <= 64 && std::floor(p) == p))
      throw InputError("--pixels: must be an integer in 1..64");
    o.pixels = static_cast<int>(p);
  }
  o.overwrite = args.has("--overwrite");
  if (!o.output.empty()) refuseExisting(o.output, o.overwrite);
  if (!o.surface.empty()) refuseExisting(o.surface, o.overwrite);
  const long window = 2L * static_cast<long>(std::ceil(o.radius / o.resolution)) + 1;
  if (window > 2001 || static_cast<long>(o.nx) * o.ny * o.nz > 50000000L)
    throw InputError("--radius/--resolution/--grid: search window or grid too large");

  const Cloud::Ptr source = readChecked(pos[0]);
  const Cloud::Ptr target = readChecked(pos[1]);

  Registration reg;
  reg.setSearchRadius(o.radius);
  reg.setResolution(o.resolution);
  reg.setGridSize(o.nx, o.ny, o.nz);
  reg.setGridHeight(o.height);
  reg.setYawSamples(o.yaw_samples);
  reg.setYawStep(o.yaw_step_deg * kPi / 180.f);
  reg.setSigmaPerMetre(o.sigma_per_metre);
  reg.setMinSigma(o.min_sigma);
  reg.setMinSimilarity(o.min_similarity);
  reg.setSearchZ(o.search_z);
  reg.setSearchRadiusZ(o.radius_z);
  reg.setFullYawWindow(!o.surface.empty());
  if (!o.sensor.empty())
    reg.setSensorOrigin(Eigen::Vector3f(o.sensor[0], o.sensor[1], o.sensor[2]));
  Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
  if (!o.guess.empty()) {
    const float yaw = o.guess.size() > 3 ? o.guess[3] * kPi / 180.f : 0.f;
    guess.block<3, 3>(0, 0) = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    guess.block<3, 1>(0, 3) = Eigen::Vector3f(o.guess[0], o.guess[1], o.guess[2]);
  }
  reg.setInputSource(source);
  reg.setInputTarget(target);
  Cloud aligned;
  const auto start = std::chrono::steady_clock::now();
  reg.align(aligned, guess);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  const Eigen::Matrix4f t = reg.getFinalTransformation();
  pcl::console::print_info("Transformation (source -> target):\n");
  for (int r = 0; r < 4; ++r)
    pcl::console::print_value("  %10.6f %10.6f %10.6f %10.6f\n", t(r, 0), t(r, 1), t(r, 2),
                              t(r, 3));
  pcl::console::print_info("translation: ");
  pcl::console::print_value("%.4f %.4f %.4f", t(0, 3), t(1, 3), t(2, 3));
  pcl::console::print_info(" m   yaw: ");
  pcl::console::print_value("%.3f", std::atan2(t(1, 0), t(0, 0)) * 180.f / kPi);
  pcl::console::print_info(" deg\nsimilarity B: ");
  pcl::console::print_value("%.4f", reg.getSimilarity());
  pcl::console::print_info("   converged: ");
  pcl::console::print_value("%s", reg.hasConverged() ? "yes" : "no");
  pcl::console::print_info("   time: ");
  pcl::console::print_value("%.2f", ms);
  pcl::console::print_info(" ms (%zu source, %zu target points)\n", source->size(), target->size());
  if (!reg.hasConverged())
    pcl::console::print_warn(
        "not converged: the peak is on the edge of the search window (enlarge --radius or give a "
        "better --guess) or B is below --min-similarity\n");

  if (!o.surface.empty()) {
    if (reg.getSimilaritySurface().empty())
      throw InputError(o.surface, 0, "no similarity surface (registration did not run)");
    writeSurface(o.surface, reg.getSimilaritySurface(), o.pixels);
    pcl::console::print_info("wrote %s\n", o.surface.c_str());
  }
  if (!o.output.empty()) {
    const std::string tmp = o.output + ".tmp";
    pcl::PCDWriter writer;
    if (writer.writeBinary(tmp, aligned) != 0) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw InputError(o.output, 0, "cannot write");
    }
    std::error_code ec;
    fs::rename(tmp, o.output, ec);
    if (ec) {
      fs::remove(tmp, ec);
      throw InputError(o.output, 0, "cannot write (" + ec.message() + ")");
    }
    pcl::console::print_info("wrote %s\n", o.output.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (pcl_movers::tools::wantsHelp(argc, argv)) {
    printHelp(argv[0]);
    return 0;
  }
  return pcl_movers::tools::runTool("pcl_movers_register", [&] { return run(argc, argv); });
}
