#include "vproto/ui_batch/image.h"

#include <png.h>

#include <cstdio>

#include "vproto/materials/errors.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch {

void write_png(const Image& image, const std::string& path) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f)
      throw InputError("cannot write '" + path + "': check the folder exists and is writable");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    bool ok = png && info;
    if (ok && setjmp(png_jmpbuf(png)) == 0) {
      png_init_io(png, f);
      // one fast filter and light compression: frames are written while the run goes on.
      // libpng's adaptive choice of filter per row cost more than the compression; with the
      // Sub filter alone the snap-fit's 120 frames at 1280x720 render in 4.8-5.3 s instead
      // of 6.9 s, for 9.0 MB of PNGs instead of 8.8 MB
      png_set_compression_level(png, 3);
      png_set_filter(png, 0, PNG_FILTER_SUB);
      png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
                   static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB,
                   PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
      png_write_info(png, info);
      for (int y = 0; y < image.height; ++y)
        png_write_row(png, const_cast<png_bytep>(image.at(0, y)));
      png_write_end(png, nullptr);
    } else {
      ok = false;
    }
    png_destroy_write_struct(&png, &info);
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) throw InputError("cannot write '" + path + "'");
  });
}

}  // namespace vproto::ui_batch
