#pragma once
// Line plots as PNG (curves such as the insertion force against the drive's travel),
// drawn with the frames' own text and PNG path: no plotting package to install.

#include <string>
#include <vector>

#include "vproto/ui_batch/colormap.h"

namespace vproto::ui_batch {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;  ///< equal lengths; non-finite points break the line
  Rgb colour{31, 119, 180};
  bool markers = false;  ///< a dot at each point (measurements, not a curve)
};

struct PlotOptions {
  int width = 960;
  int height = 600;
  std::string title, x_label, y_label;
  /// Logarithmic axes (decades; points at or below zero are left out), as work-precision
  /// plots want; linear axes include zero on y.
  bool log_x = false, log_y = false;
};

/// Writes the series as one line plot (axes with 1-2-5 ticks, grid, legend) to `path`,
/// atomically. Throws InputError when the file cannot be written; series with no
/// finite point draw nothing.
void write_line_plot(const std::vector<PlotSeries>& series, const PlotOptions& options,
                     const std::string& path);

/// The colour of the k-th series of a plot (a fixed, colour-blind-safe cycle).
Rgb series_colour(int k);

/// "Nice" tick positions (steps of 1, 2 or 5 times a power of ten) covering [lo, hi],
/// about `count` of them.
std::vector<double> nice_ticks(double lo, double hi, int count);

}  // namespace vproto::ui_batch
