#include "vproto/ui_batch/colormap.h"

#include <algorithm>
#include <cmath>

namespace vproto::ui_batch {
namespace {

// viridis (van der Walt & Smith, CC0) sampled at 17 evenly spaced points, read from
// matplotlib's table; linear interpolation between them stays within 1/255 of it.
constexpr std::uint8_t kViridis[17][3] = {
    {68, 1, 84},    {72, 24, 106},  {71, 45, 123},  {66, 64, 134},  {59, 82, 139},  {51, 99, 141},
    {44, 114, 142}, {38, 130, 142}, {33, 145, 140}, {31, 160, 136}, {40, 174, 128}, {63, 188, 115},
    {94, 201, 98},  {132, 212, 75}, {173, 220, 48}, {216, 226, 25}, {253, 231, 37}};

// Moreland's cool-warm end points with a light neutral middle.
constexpr std::uint8_t kDiverging[3][3] = {{59, 76, 192}, {221, 221, 221}, {180, 4, 38}};

template <std::size_t N>
Rgb sample(const std::uint8_t (&table)[N][3], double t) {
  if (!(t >= 0)) t = 0;  // NaN maps to the low end
  t = std::min(t, 1.0);
  const double x = t * (N - 1);
  const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(x), N - 2);
  const double f = x - static_cast<double>(i);
  Rgb out;
  for (int k = 0; k < 3; ++k)
    out[k] = static_cast<std::uint8_t>(std::lround(table[i][k] * (1 - f) + table[i + 1][k] * f));
  return out;
}

}  // namespace

Rgb viridis(double t) { return sample(kViridis, t); }
Rgb diverging(double t) { return sample(kDiverging, t); }
Rgb yield_colour(double ratio) { return ratio < 1 ? viridis(ratio) : Rgb{214, 39, 40}; }

}  // namespace vproto::ui_batch
