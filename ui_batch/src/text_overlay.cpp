#include "text_overlay.h"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>

namespace vproto::ui_batch {

struct TextPainter::Impl {
  FT_Library library = nullptr;
  FT_Face face = nullptr;
};

TextPainter::TextPainter(int pixel_height) : impl_(std::make_unique<Impl>()) {
  if (FT_Init_FreeType(&impl_->library) != 0) return;
  for (const char* path :
       {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "/usr/share/fonts/TTF/DejaVuSans.ttf"}) {
    if (FT_New_Face(impl_->library, path, 0, &impl_->face) == 0) break;
    impl_->face = nullptr;
  }
  if (impl_->face) FT_Set_Pixel_Sizes(impl_->face, 0, static_cast<FT_UInt>(pixel_height));
}

TextPainter::~TextPainter() {
  if (impl_->face) FT_Done_Face(impl_->face);
  if (impl_->library) FT_Done_FreeType(impl_->library);
}

bool TextPainter::available() const { return impl_->face != nullptr; }

int TextPainter::width(const std::string& text) {
  if (!available()) return 0;
  long pen = 0;
  for (unsigned char c : text) {
    if (FT_Load_Char(impl_->face, c, FT_LOAD_DEFAULT) != 0) continue;
    pen += impl_->face->glyph->advance.x >> 6;
  }
  return static_cast<int>(pen);
}

void TextPainter::draw(Image& image, int x, int baseline, const std::string& text, Rgb colour) {
  if (!available()) return;
  int pen = x;
  for (unsigned char c : text) {
    if (FT_Load_Char(impl_->face, c, FT_LOAD_RENDER) != 0) continue;
    const FT_GlyphSlot g = impl_->face->glyph;
    const FT_Bitmap& bm = g->bitmap;
    // blend the glyph's coverage over the image
    for (unsigned row = 0; row < bm.rows; ++row) {
      const int y = baseline - g->bitmap_top + static_cast<int>(row);
      if (y < 0 || y >= image.height) continue;
      for (unsigned col = 0; col < bm.width; ++col) {
        const int px = pen + g->bitmap_left + static_cast<int>(col);
        if (px < 0 || px >= image.width) continue;
        const int a = bm.buffer[row * static_cast<unsigned>(bm.pitch) + col];
        std::uint8_t* p = image.at(px, y);
        for (int k = 0; k < 3; ++k)
          p[k] = static_cast<std::uint8_t>((colour[k] * a + p[k] * (255 - a)) / 255);
      }
    }
    pen += static_cast<int>(g->advance.x >> 6);
  }
}

}  // namespace vproto::ui_batch
