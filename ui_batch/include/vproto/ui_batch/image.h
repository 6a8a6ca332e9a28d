#pragma once
// An 8-bit RGB image and PNG output (libpng), written atomically.

#include <cstdint>
#include <string>
#include <vector>

namespace vproto::ui_batch {

/// Row-major RGB pixels, row 0 at the top.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3

  std::uint8_t* at(int x, int y) { return &rgb[(static_cast<std::size_t>(y) * width + x) * 3]; }
  const std::uint8_t* at(int x, int y) const {
    return &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
  }
};

/// Writes `image` as a PNG file; throws InputError naming the file when it cannot.
void write_png(const Image& image, const std::string& path);

}  // namespace vproto::ui_batch
