// PNG output checked by an independent decoder (libpng's) and by the bytes of the files.
#include "vproto/ui_batch/image.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include "png_reader.h"

namespace vproto::ui_batch {
namespace {

namespace fs = std::filesystem;

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
    const Image got = read_png((dir / file).string());
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
  EXPECT_TRUE(read_png((dir / "c.png").string()).rgb == c.rgb);
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

// YUV 4:2:0 for the video: BT.601 limited-range values of pure colours (within rounding),
// black padding to even sides, and rows kept from the last frame that convert as afresh
TEST(Yuv420, PureColoursHaveTheirBt601Values) {
  Image img;
  img.width = 8;
  img.height = 2;
  const std::uint8_t colours[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}};
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 8; ++x)
      for (int k = 0; k < 3; ++k) img.rgb.push_back(colours[x / 2][k]);
  Yuv420Frames frames;
  const std::vector<std::uint8_t>& yuv = frames.convert(img);
  ASSERT_EQ(frames.width(), 8);
  ASSERT_EQ(frames.height(), 2);
  ASSERT_EQ(yuv.size(), 8u * 2 * 3 / 2);
  // Y, Cb, Cr of red, green, blue, white (ITU-R BT.601, 16-235 / 16-240)
  const int want[4][3] = {{81, 90, 240}, {145, 54, 34}, {41, 240, 110}, {235, 128, 128}};
  for (int c = 0; c < 4; ++c) {
    for (int y = 0; y < 2; ++y)
      for (int x = 2 * c; x < 2 * c + 2; ++x) EXPECT_NEAR(yuv[y * 8 + x], want[c][0], 1) << c;
    EXPECT_NEAR(yuv[16 + c], want[c][1], 1) << c;
    EXPECT_NEAR(yuv[16 + 4 + c], want[c][2], 1) << c;
  }
}

TEST(Yuv420, OddSidesArePaddedWithBlack) {
  Image img;
  img.width = 5;
  img.height = 3;
  img.rgb.assign(5 * 3 * 3, 255);  // white
  Yuv420Frames frames;
  const std::vector<std::uint8_t>& yuv = frames.convert(img);
  ASSERT_EQ(frames.width(), 6);
  ASSERT_EQ(frames.height(), 4);
  ASSERT_EQ(yuv.size(), 6u * 4 * 3 / 2);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x)
      EXPECT_EQ(yuv[y * 6 + x], x < 5 && y < 3 ? 235 : 16) << x << "," << y;
  for (std::size_t i = 24; i < yuv.size(); ++i) EXPECT_EQ(yuv[i], 128);
}

TEST(Yuv420, KeptRowsConvertAsAFreshFrameWould) {
  const Image a = test_image(10, 8, 4);
  Image b = a;
  for (int x = 0; x < b.width; ++x) b.at(x, 5)[1] ^= 0x5a;  // row 5: pair 2 changes
  Yuv420Frames sequence;
  sequence.convert(a);
  const std::vector<std::uint8_t> got = sequence.convert(b);
  EXPECT_EQ(sequence.pairs_converted(), 4 + 1);
  EXPECT_EQ(sequence.pairs_kept(), 3);
  Yuv420Frames fresh;
  EXPECT_TRUE(got == fresh.convert(b));
  EXPECT_FALSE(got == Yuv420Frames().convert(a));
}

}  // namespace
}  // namespace vproto::ui_batch
