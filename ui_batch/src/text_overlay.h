#pragma once
// Private to ui_batch: anti-aliased text drawn into an Image with FreeType (DejaVu Sans).

#include <memory>
#include <string>

#include "vproto/ui_batch/colormap.h"
#include "vproto/ui_batch/image.h"

namespace vproto::ui_batch {

class TextPainter {
 public:
  /// `pixel_height` is the font's em size in pixels. When no font is installed the
  /// painter draws nothing (text is decoration, never a reason to fail a run).
  explicit TextPainter(int pixel_height);
  ~TextPainter();
  TextPainter(const TextPainter&) = delete;
  TextPainter& operator=(const TextPainter&) = delete;

  bool available() const;
  /// Width in pixels of `text` as drawn.
  int width(const std::string& text);
  /// Draws `text` with its baseline at y, starting at x.
  void draw(Image& image, int x, int baseline, const std::string& text, Rgb colour);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vproto::ui_batch
