#include "vproto/ui_batch/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "text_overlay.h"
#include "vproto/ui_batch/image.h"

namespace vproto::ui_batch {

std::vector<double> nice_ticks(double lo, double hi, int count) {
  std::vector<double> out;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi) || count < 1) return out;
  const double raw = (hi - lo) / count;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  double step = power;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw) {
      step = m * power;
      break;
    }
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
    out.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  return out;
}

namespace {

void blend(Image& im, int x, int y, Rgb c, double alpha) {
  if (x < 0 || y < 0 || x >= im.width || y >= im.height || alpha <= 0) return;
  alpha = std::min(alpha, 1.0);
  std::uint8_t* p = im.at(x, y);
  for (int k = 0; k < 3; ++k)
    p[k] = static_cast<std::uint8_t>(std::lround(p[k] * (1 - alpha) + c[k] * alpha));
}

// an anti-aliased line of about `width` pixels: the coverage of each pixel by a band
// around the segment, from the pixel centre's distance to it
void line(Image& im, double x0, double y0, double x1, double y1, Rgb c, double width) {
  const double half = 0.5 * width;
  const int xa = static_cast<int>(std::floor(std::min(x0, x1) - half - 1));
  const int xb = static_cast<int>(std::ceil(std::max(x0, x1) + half + 1));
  const int ya = static_cast<int>(std::floor(std::min(y0, y1) - half - 1));
  const int yb = static_cast<int>(std::ceil(std::max(y0, y1) + half + 1));
  const double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
  for (int y = std::max(ya, 0); y <= std::min(yb, im.height - 1); ++y)
    for (int x = std::max(xa, 0); x <= std::min(xb, im.width - 1); ++x) {
      const double px = x + 0.5, py = y + 0.5;
      double t = len2 > 0 ? ((px - x0) * dx + (py - y0) * dy) / len2 : 0.0;
      t = std::clamp(t, 0.0, 1.0);
      const double ex = px - (x0 + t * dx), ey = py - (y0 + t * dy);
      const double dist = std::sqrt(ex * ex + ey * ey);
      blend(im, x, y, c, half + 0.5 - dist);
    }
}

std::string tick_text(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%g", v);
  return s;
}

}  // namespace

Rgb series_colour(int k) {
  static const Rgb cycle[] = {{31, 119, 180},  {230, 97, 1},  {44, 160, 44},
                              {148, 103, 189}, {140, 86, 75}, {23, 190, 207}};
  return cycle[static_cast<std::size_t>(k) % (sizeof cycle / sizeof cycle[0])];
}

void write_line_plot(const std::vector<PlotSeries>& series, const PlotOptions& o,
                     const std::string& path) {
  Image im;
  im.width = o.width;
  im.height = o.height;
  im.rgb.assign(static_cast<std::size_t>(o.width) * o.height * 3, 255);
  const Rgb ink{30, 30, 30}, grid{225, 225, 225};

  // the axes' coordinates: the values, or their decimal logarithms
  auto ax = [&](double x) { return o.log_x ? (x > 0 ? std::log10(x) : NAN) : x; };
  auto ay = [&](double y) { return o.log_y ? (y > 0 ? std::log10(y) : NAN) : y; };
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  double y_lo = x_lo, y_hi = -x_lo;
  for (const PlotSeries& s : series)
    for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
      const double x = ax(s.x[k]), y = ay(s.y[k]);
      if (std::isfinite(x) && std::isfinite(y)) {
        x_lo = std::min(x_lo, x);
        x_hi = std::max(x_hi, x);
        y_lo = std::min(y_lo, y);
        y_hi = std::max(y_hi, y);
      }
    }
  if (!std::isfinite(x_lo)) x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  if (!o.log_y) {
    y_lo = std::min(y_lo, 0.0);  // forces read against zero
    y_hi = std::max(y_hi, 0.0);
  }
  auto widen = [](double& lo, double& hi, bool log) {
    if (log) {  // whole decades
      lo = std::floor(lo);
      hi = std::max(std::ceil(hi), lo + 1);
      return;
    }
    const double span = hi - lo, pad = span > 0 ? 0.04 * span : std::max(1.0, std::abs(lo));
    lo -= pad;
    hi += pad;
  };
  widen(x_lo, x_hi, o.log_x);
  widen(y_lo, y_hi, o.log_y);

  const int left = 96, right = 28, top = 68, bottom = 72;
  const double pw = o.width - left - right, ph = o.height - top - bottom;
  auto sx = [&](double x) { return left + (x - x_lo) / (x_hi - x_lo) * pw; };
  auto sy = [&](double y) { return top + (y_hi - y) / (y_hi - y_lo) * ph; };
  // decades on a log axis (every other one when there are many), nice steps on a linear one
  auto ticks = [](double lo, double hi, bool log) {
    if (!log) return nice_ticks(lo, hi, 8);
    std::vector<double> out;
    const int every = hi - lo > 8 ? 2 : 1;
    for (double t = lo; t <= hi + 1e-9; t += every) out.push_back(t);
    return out;
  };
  auto label = [](double t, bool log) {
    if (!log) return tick_text(t);
    char s[32];
    std::snprintf(s, sizeof s, "1e%d", static_cast<int>(std::lround(t)));
    return std::string(s);
  };

  TextPainter small(15), big(19);
  for (double t : ticks(x_lo, x_hi, o.log_x)) {
    line(im, sx(t), top, sx(t), top + ph, grid, 1);
    const std::string s = label(t, o.log_x);
    small.draw(im, static_cast<int>(sx(t)) - small.width(s) / 2, top + static_cast<int>(ph) + 22, s,
               ink);
  }
  for (double t : ticks(y_lo, y_hi, o.log_y)) {
    line(im, left, sy(t), left + pw, sy(t), t == 0 && !o.log_y ? Rgb{150, 150, 150} : grid, 1);
    const std::string s = label(t, o.log_y);
    small.draw(im, left - 8 - small.width(s), static_cast<int>(sy(t)) + 5, s, ink);
  }
  line(im, left, top, left, top + ph, ink, 1.2);
  line(im, left, top + ph, left + pw, top + ph, ink, 1.2);
  big.draw(im, left, 28, o.title, ink);
  small.draw(im, left + static_cast<int>(pw) / 2 - small.width(o.x_label) / 2, o.height - 18,
             o.x_label, ink);
  small.draw(im, 8, top - 14, o.y_label, ink);

  for (const PlotSeries& s : series) {
    bool pen_down = false;
    double px = 0, py = 0;
    for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
      const double vx = ax(s.x[k]), vy = ay(s.y[k]);
      if (!std::isfinite(vx) || !std::isfinite(vy)) {
        pen_down = false;
        continue;
      }
      const double x = sx(vx), y = sy(vy);
      if (pen_down) line(im, px, py, x, y, s.colour, 2.2);
      if (s.markers) line(im, x, y, x, y, s.colour, 7);  // a round dot
      px = x;
      py = y;
      pen_down = true;
    }
  }
  // the legend, top right, on white over the lines it may cover, as wide as its longest label
  int widest = 0, entries = 0;
  for (const PlotSeries& s : series)
    if (!s.label.empty()) widest = std::max(widest, small.width(s.label)), ++entries;
  if (series.size() > 1 && entries > 0) {
    const int lx = left + static_cast<int>(pw) - widest - 36 - 12;
    const int box_top = top + 6, box_bottom = top + 12 + 22 * entries;
    for (int y = std::max(box_top, 0); y < std::min(box_bottom, im.height); ++y)
      for (int x = std::max(lx - 8, 0); x < std::min(left + static_cast<int>(pw) - 2, im.width);
           ++x) {
        std::uint8_t* p = &im.rgb[3 * (static_cast<std::size_t>(y) * im.width + x)];
        p[0] = p[1] = p[2] = 255;
      }
    int legend_y = top + 22;
    for (const PlotSeries& s : series) {
      if (s.label.empty()) continue;
      line(im, lx, legend_y - 5, lx + 28, legend_y - 5, s.colour, 2.2);
      small.draw(im, lx + 36, legend_y, s.label, ink);
      legend_y += 22;
    }
  }
  write_png(im, path);
}

}  // namespace vproto::ui_batch
