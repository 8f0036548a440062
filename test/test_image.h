/*
 * The viewer's images for the tests that check them (test_viewer, test_live_input): binary PPM
 * (P6) files as `pcl_movers_viewer --format ppm` writes them, and the mover red of SceneStyle.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace test_util {

/** \brief A binary PPM (P6) as written by `--format ppm`. */
struct Image {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  const unsigned char* at(int x, int y) const {
    return &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
  }
};

inline bool readPpm(const std::filesystem::path& path, Image& image) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  int maxval = 0;
  in >> magic >> image.width >> image.height >> maxval;
  if (magic != "P6" || image.width <= 0 || image.height <= 0 || maxval != 255) return false;
  in.get();
  image.rgb.resize(static_cast<std::size_t>(image.width) * image.height * 3);
  in.read(reinterpret_cast<char*>(image.rgb.data()),
          static_cast<std::streamsize>(image.rgb.size()));
  return static_cast<bool>(in);
}

/** \brief The mover colour of SceneStyle (strong red), with tolerance for blending at edges. */
inline bool isMoverRed(const unsigned char* p) {
  return p[0] > 200 && p[1] < 90 && p[2] < 90;
}

/** \brief Mover-red pixels within `radius` (a square) of pixel (cx, cy). */
inline int countRed(const Image& im, int cx, int cy, int radius) {
  int n = 0;
  for (int y = std::max(0, cy - radius); y <= std::min(im.height - 1, cy + radius); ++y)
    for (int x = std::max(0, cx - radius); x <= std::min(im.width - 1, cx + radius); ++x)
      n += isMoverRed(im.at(x, y));
  return n;
}

/** \brief Mover-red pixels in the whole image. */
inline int countRed(const Image& im) {
  return countRed(im, im.width / 2, im.height / 2, 1 << 20);
}

}  // namespace test_util
