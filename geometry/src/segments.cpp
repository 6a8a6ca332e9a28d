// The default faceting of round solids (no CGAL here: the language fuzzer links it alone).
#include <cmath>

#include "vproto/geometry/primitives.h"

namespace vproto::geometry {

int default_segments(double relative_error) {
  // 1 - cos(pi/N) <= e  <=>  N >= pi / acos(1 - e)
  const int n =
      static_cast<int>(std::ceil(3.14159265358979323846 / std::acos(1.0 - relative_error)));
  const int rounded = ((n + 3) / 4) * 4;
  return rounded < 8 ? 8 : rounded;
}

}  // namespace vproto::geometry
