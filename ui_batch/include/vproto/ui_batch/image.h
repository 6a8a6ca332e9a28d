#pragma once
// An 8-bit RGB image and PNG output, written atomically.

#include <cstdint>
#include <memory>
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

/// Writes a sequence of PNG frames (an animation's), each compressed in bands of rows that
/// are compressed on their own: a band whose pixels are those of the last frame's (the
/// background, the ground, a body at rest; all but the caption of a frame at rest) reuses
/// that frame's compressed bytes. The files are what write_png writes, frame by frame.
class PngSequence {
 public:
  PngSequence();
  ~PngSequence();
  PngSequence(const PngSequence&) = delete;
  PngSequence& operator=(const PngSequence&) = delete;

  /// Writes `image` as a PNG file, as write_png does.
  void write(const Image& image, const std::string& path);
  /// Bands compressed and bands reused so far.
  long bands_compressed() const { return compressed_; }
  long bands_reused() const { return reused_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  long compressed_ = 0, reused_ = 0;
};

/// Converts an animation's RGB frames to the planar YUV 4:2:0 a video encoder takes (BT.601,
/// limited range, each 2x2 block's chroma from its mean colour), each side rounded up to
/// even with black. A pair of rows that is the last frame's keeps its conversion (all but
/// the caption of a frame at rest).
class Yuv420Frames {
 public:
  /// The frame's Y plane, then U, then V: width() * height() * 3 / 2 bytes.
  const std::vector<std::uint8_t>& convert(const Image& image);
  int width() const { return width_; }
  int height() const { return height_; }
  /// Row pairs converted and kept so far.
  long pairs_converted() const { return converted_; }
  long pairs_kept() const { return kept_; }

 private:
  Image last_;
  std::vector<std::uint8_t> yuv_;
  int width_ = 0, height_ = 0;
  long converted_ = 0, kept_ = 0;
};

}  // namespace vproto::ui_batch
