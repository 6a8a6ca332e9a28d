#pragma once
// Colour maps for scalar fields: viridis (perceptually uniform, for magnitudes such as
// von Mises stress and displacement), the same below the yield and red past it for the
// yield ratio, and a blue-white-red diverging map for signed fields.

#include <array>
#include <cstdint>

namespace vproto::ui_batch {

using Rgb = std::array<std::uint8_t, 3>;

/// Viridis at t in [0, 1] (clamped).
Rgb viridis(double t);

/// The yield-ratio map (render field=yield): viridis from 0 to 1 (the yield), one red
/// above it, so what passes the yield stands out at a glance; `ratio` is the field's value.
Rgb yield_colour(double ratio);
/// The top of the yield map's scale: it spans [0, kYieldMapTop] of the yield, the part
/// above 1 red.
inline constexpr double kYieldMapTop = 1.25;

/// Diverging blue (t = 0) - white (0.5) - red (1), clamped.
Rgb diverging(double t);

}  // namespace vproto::ui_batch
