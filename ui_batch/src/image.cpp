#include "vproto/ui_batch/image.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>

#include "vproto/materials/errors.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch {

// The PNG file is written here, not by libpng: libpng compresses every row of every frame,
// and an animation's frames repeat most of their rows (the snap-fit's last 80 frames show
// the socket at rest and differ in their caption only). Each band of kBandRows rows is a
// deflate segment of its own (the compressor reset at its start, flushed to a byte boundary
// at its end), so a band's bytes depend only on its pixels and are kept for the next
// frame; the segments in a row make one zlib stream (RFC 1950/1951), its Adler-32 combined
// from theirs. Rows use the Sub filter (one fast filter: libpng's adaptive choice per row
// cost more than it saved) at deflate level 3.

namespace {

constexpr int kBandRows = 16;
constexpr int kLevel = 3;

void put32(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 24);
  p[1] = static_cast<std::uint8_t>(v >> 16);
  p[2] = static_cast<std::uint8_t>(v >> 8);
  p[3] = static_cast<std::uint8_t>(v);
}

}  // namespace

struct PngSequence::Impl {
  struct Band {
    std::vector<std::uint8_t> pixels;  // the rows' RGB bytes it was compressed from
    std::vector<std::uint8_t> packed;  // its deflate segment
    uLong adler = 0;                   // Adler-32 of its filtered rows
    uLong filtered_size = 0;
  };
  z_stream z{};
  bool ready = false;
  int width = 0, height = 0;
  std::vector<Band> bands;
  std::vector<std::uint8_t> filtered;

  Impl() {
    // raw deflate (no zlib header: the file's one stream is put together from the bands)
    ready = deflateInit2(&z, kLevel, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) == Z_OK;
  }
  ~Impl() {
    if (ready) deflateEnd(&z);
  }

  // the band's rows Sub-filtered and deflated into band.packed
  void compress(const Image& image, int first, int rows, Band* band) {
    const std::size_t stride = static_cast<std::size_t>(image.width) * 3;
    filtered.resize((stride + 1) * static_cast<std::size_t>(rows));
    std::uint8_t* out = filtered.data();
    for (int y = first; y < first + rows; ++y) {
      const std::uint8_t* row = image.at(0, y);
      *out++ = 1;  // Sub
      for (std::size_t i = 0; i < std::min<std::size_t>(3, stride); ++i) *out++ = row[i];
      for (std::size_t i = 3; i < stride; ++i)
        *out++ = static_cast<std::uint8_t>(row[i] - row[i - 3]);
    }
    band->filtered_size = static_cast<uLong>(filtered.size());
    band->adler = adler32(adler32(0, nullptr, 0), filtered.data(), band->filtered_size);
    if (deflateReset(&z) != Z_OK) throw InternalError("zlib could not reset its compressor");
    band->packed.resize(deflateBound(&z, band->filtered_size) + 16);
    z.next_in = filtered.data();
    z.avail_in = band->filtered_size;
    z.next_out = band->packed.data();
    z.avail_out = static_cast<uInt>(band->packed.size());
    // a sync flush ends the segment on a byte boundary with the stream left open
    if (deflate(&z, Z_SYNC_FLUSH) != Z_OK || z.avail_in != 0)
      throw InternalError("zlib could not compress a PNG band");
    band->packed.resize(band->packed.size() - z.avail_out);
  }
};

PngSequence::PngSequence() : impl_(std::make_unique<Impl>()) {}
PngSequence::~PngSequence() = default;

void PngSequence::write(const Image& image, const std::string& path) {
  Impl& d = *impl_;
  if (!d.ready) throw InternalError("zlib could not start its compressor");
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != static_cast<std::size_t>(image.width) * image.height * 3)
    throw InternalError("an image to write as '" + path + "' has no pixels or the wrong size");
  if (d.width != image.width || d.height != image.height) {
    d.bands.clear();
    d.width = image.width;
    d.height = image.height;
  }
  const std::size_t stride = static_cast<std::size_t>(image.width) * 3;
  const int count = (image.height + kBandRows - 1) / kBandRows;
  d.bands.resize(static_cast<std::size_t>(count));
  std::size_t packed = 0;
  uLong adler = adler32(0, nullptr, 0);
  for (int b = 0; b < count; ++b) {
    Impl::Band& band = d.bands[static_cast<std::size_t>(b)];
    const int first = b * kBandRows, rows = std::min(kBandRows, image.height - first);
    const std::uint8_t* pixels = image.at(0, first);
    const std::size_t size = stride * static_cast<std::size_t>(rows);
    if (band.pixels.size() == size && std::memcmp(band.pixels.data(), pixels, size) == 0) {
      ++reused_;
    } else {
      band.pixels.clear();  // kept only once its segment is whole
      d.compress(image, first, rows, &band);
      band.pixels.assign(pixels, pixels + size);
      ++compressed_;
    }
    packed += band.packed.size();
    adler = adler32_combine(adler, band.adler, static_cast<z_off_t>(band.filtered_size));
  }

  // IDAT's data: a zlib header (deflate, 32 KB window, no dictionary), the bands, a final
  // empty fixed-Huffman block, the Adler-32
  const std::array<std::uint8_t, 2> header{0x78, 0x01};
  const std::array<std::uint8_t, 2> last_block{0x03, 0x00};
  std::array<std::uint8_t, 4> adler_bytes{};
  put32(adler_bytes.data(), static_cast<std::uint32_t>(adler));
  const std::size_t idat = header.size() + packed + last_block.size() + adler_bytes.size();
  if (idat > 0x7fffffffu) throw InternalError("a PNG frame's data exceeds one chunk");

  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f)
      throw InputError("cannot write '" + path + "': check the folder exists and is writable");
    bool ok = true;
    auto put = [&](const void* data, std::size_t n) {
      ok = ok && (n == 0 || std::fwrite(data, 1, n, f) == n);
    };
    // a chunk: length, type, data in pieces, CRC-32 of type and data
    auto chunk = [&](const char* type, std::size_t length, auto&& pieces) {
      std::array<std::uint8_t, 8> head{};
      put32(head.data(), static_cast<std::uint32_t>(length));
      std::memcpy(head.data() + 4, type, 4);
      put(head.data(), head.size());
      uLong crc = crc32(crc32(0, nullptr, 0), head.data() + 4, 4);
      pieces([&](const std::uint8_t* data, std::size_t n) {
        put(data, n);
        crc = crc32(crc, data, static_cast<uInt>(n));
      });
      std::array<std::uint8_t, 4> tail{};
      put32(tail.data(), static_cast<std::uint32_t>(crc));
      put(tail.data(), tail.size());
    };
    const std::array<std::uint8_t, 8> signature{0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
    put(signature.data(), signature.size());
    std::array<std::uint8_t, 13> ihdr{};
    put32(ihdr.data(), static_cast<std::uint32_t>(image.width));
    put32(ihdr.data() + 4, static_cast<std::uint32_t>(image.height));
    ihdr[8] = 8;  // bits per sample
    ihdr[9] = 2;  // RGB; deflate, adaptive filtering, no interlace: the zeros after
    chunk("IHDR", ihdr.size(), [&](auto&& emit) { emit(ihdr.data(), ihdr.size()); });
    chunk("IDAT", idat, [&](auto&& emit) {
      emit(header.data(), header.size());
      for (const Impl::Band& band : d.bands) emit(band.packed.data(), band.packed.size());
      emit(last_block.data(), last_block.size());
      emit(adler_bytes.data(), adler_bytes.size());
    });
    chunk("IEND", 0, [](auto&&) {});
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) throw InputError("cannot write '" + path + "'");
  });
}

void write_png(const Image& image, const std::string& path) {
  PngSequence png;
  png.write(image, path);
}

// Written here rather than left to ffmpeg's swscale, which converted rgb24 at 2.5 ms a
// 1280x720 frame (a third of what the encoder took per frame) and redid the rows of a frame
// at rest that had not changed. Integer BT.601 with limited range, as swscale's default.
const std::vector<std::uint8_t>& Yuv420Frames::convert(const Image& image) {
  const int w = image.width, h = image.height;
  const bool same_size = last_.width == w && last_.height == h && !yuv_.empty();
  width_ = w + (w & 1);
  height_ = h + (h & 1);
  const std::size_t luma = static_cast<std::size_t>(width_) * height_,
                    chroma_width = static_cast<std::size_t>(width_ / 2);
  if (!same_size) {
    // black (16, 128, 128) where the even size pads the picture
    yuv_.assign(luma * 3 / 2, 128);
    std::fill(yuv_.begin(), yuv_.begin() + static_cast<std::ptrdiff_t>(luma), 16);
  }
  std::uint8_t* const y_plane = yuv_.data();
  std::uint8_t* const u_plane = y_plane + luma;
  std::uint8_t* const v_plane = u_plane + luma / 4;
  const std::size_t row_bytes = static_cast<std::size_t>(w) * 3;
  auto luma_of = [](int r, int g, int b) {
    return static_cast<std::uint8_t>(((66 * r + 129 * g + 25 * b + 128) >> 8) + 16);
  };
  for (int y0 = 0; y0 < h; y0 += 2) {
    const int rows = std::min(2, h - y0);
    const std::uint8_t* src[2] = {image.at(0, y0), image.at(0, y0 + rows - 1)};
    if (same_size && std::memcmp(src[0], last_.at(0, y0), row_bytes * rows) == 0) {
      ++kept_;
      continue;
    }
    ++converted_;
    for (int k = 0; k < rows; ++k) {
      std::uint8_t* out = y_plane + static_cast<std::size_t>(y0 + k) * width_;
      const std::uint8_t* p = src[k];
      for (int x = 0; x < w; ++x, p += 3) out[x] = luma_of(p[0], p[1], p[2]);
    }
    std::uint8_t* u = u_plane + static_cast<std::size_t>(y0 / 2) * chroma_width;
    std::uint8_t* v = v_plane + static_cast<std::size_t>(y0 / 2) * chroma_width;
    for (int x0 = 0; x0 < w; x0 += 2) {
      const int x1 = std::min(x0 + 1, w - 1);
      // sums over the 2x2 block (a missing row or column counts its neighbour twice)
      int r = 0, g = 0, b = 0;
      for (const std::uint8_t* row : src)
        for (const int x : {x0, x1}) {
          r += row[x * 3];
          g += row[x * 3 + 1];
          b += row[x * 3 + 2];
        }
      u[x0 / 2] = static_cast<std::uint8_t>(((-38 * r - 74 * g + 112 * b + 512) >> 10) + 128);
      v[x0 / 2] = static_cast<std::uint8_t>(((112 * r - 94 * g - 18 * b + 512) >> 10) + 128);
    }
  }
  last_ = image;
  return yuv_;
}

}  // namespace vproto::ui_batch
