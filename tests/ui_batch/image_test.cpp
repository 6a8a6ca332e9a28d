// PNG output checked by an independent decoder (libpng's) and by the bytes of the files.
#include "vproto/ui_batch/image.h"

#include <gtest/gtest.h>
#include <png.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

namespace vproto::ui_batch {
namespace {

namespace fs = std::filesystem;

Image read_back(const std::string& path) {
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

std::string bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// a gradient with noise in it: rows that compress to neither nothing nor everything
Image test_image(int width, int height, unsigned seed) {
  Image img;
  img.width = width;
  img.height = height;
  img.rgb.resize(static_cast<std::size_t>(width) * height * 3);
  std::mt19937 rng(seed);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      std::uint8_t* p = img.at(x, y);
      p[0] = static_cast<std::uint8_t>(x * 255 / width);
      p[1] = static_cast<std::uint8_t>(y * 255 / height);
      p[2] = static_cast<std::uint8_t>(rng() % 8 == 0 ? rng() : 200);
    }
  return img;
}

TEST(Png, ASequenceReusesUnchangedBandsAndEveryFrameDecodesToItsPixels) {
  const fs::path dir = fs::temp_directory_path() / "vproto_png_test";
  fs::create_directories(dir);
  // 37 rows: two whole bands of 16 and a short one
  Image a = test_image(53, 37, 1);
  PngSequence seq;
  seq.write(a, (dir / "a.png").string());
  EXPECT_EQ(seq.bands_compressed(), 3);
  EXPECT_EQ(seq.bands_reused(), 0);
  // one pixel changed in the middle band: that band alone is compressed again
  Image b = a;
  b.at(20, 20)[1] ^= 0x5a;
  seq.write(b, (dir / "b.png").string());
  EXPECT_EQ(seq.bands_compressed(), 4);
  EXPECT_EQ(seq.bands_reused(), 2);
  for (const auto& [file, want] : {std::pair{"a.png", &a}, std::pair{"b.png", &b}}) {
    const Image got = read_back((dir / file).string());
    EXPECT_EQ(got.width, want->width);
    EXPECT_EQ(got.height, want->height);
    EXPECT_TRUE(got.rgb == want->rgb) << file;
  }
  // a frame written in a sequence is the same file as one written on its own
  write_png(b, (dir / "b_alone.png").string());
  EXPECT_EQ(bytes_of(dir / "b.png"), bytes_of(dir / "b_alone.png"));
  // a new size starts afresh
  const Image c = test_image(8, 3, 2);
  seq.write(c, (dir / "c.png").string());
  EXPECT_TRUE(read_back((dir / "c.png").string()).rgb == c.rgb);
  fs::remove_all(dir);
}

TEST(Png, AnUnwritableFolderIsAnErrorNamingTheFile) {
  const Image a = test_image(4, 4, 3);
  try {
    write_png(a, "/nonexistent_folder_for_vproto/x.png");
    FAIL() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("x.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vproto::ui_batch
