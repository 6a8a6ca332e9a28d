#pragma once
// Colour maps for scalar fields: viridis (perceptually uniform, for magnitudes such as
// von Mises stress and displacement) and a blue-white-red diverging map for signed fields.

#include <array>
#include <cstdint>

namespace vproto::ui_batch {

using Rgb = std::array<std::uint8_t, 3>;

/// Viridis at t in [0, 1] (clamped).
Rgb viridis(double t);

/// Diverging blue (t = 0) - white (0.5) - red (1), clamped.
Rgb diverging(double t);

}  // namespace vproto::ui_batch
