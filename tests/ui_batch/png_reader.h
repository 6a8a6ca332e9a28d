#pragma once
// PNG files read back with an independent decoder (libpng's), for tests on what vproto
// wrote.

#include <gtest/gtest.h>
#include <png.h>

#include <string>

#include "vproto/ui_batch/image.h"

namespace vproto::ui_batch {

inline Image read_png(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  EXPECT_NE(png_image_begin_read_from_file(&png, path.c_str()), 0) << png.message;
  png.format = PNG_FORMAT_RGB;
  Image img;
  img.width = static_cast<int>(png.width);
  img.height = static_cast<int>(png.height);
  img.rgb.resize(PNG_IMAGE_SIZE(png));
  EXPECT_NE(png_image_finish_read(&png, nullptr, img.rgb.data(), 0, nullptr), 0) << png.message;
  png_image_free(&png);
  return img;
}

}  // namespace vproto::ui_batch
