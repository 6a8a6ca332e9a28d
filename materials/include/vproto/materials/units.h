#pragma once
// Physical dimensions and units of the feature-script language (spec "Units and
// dimensions"). Everything inside vproto is SI (m, kg, s, N, Pa, rad); units exist only
// in scripts and messages.

#include <optional>
#include <string>
#include <string_view>

namespace vproto::units {

/// Exponents of length, mass, time and angle. Angle is kept as a dimension of its own so
/// that `sin(2in)` and `rotate([0,0,2N])` are caught; exponents may be fractional
/// (`sqrt(area)` is a length).
struct Dimension {
  double length = 0, mass = 0, time = 0, angle = 0;

  bool operator==(const Dimension& o) const;
  bool operator!=(const Dimension& o) const { return !(*this == o); }
  Dimension operator*(const Dimension& o) const;
  Dimension operator/(const Dimension& o) const;
  Dimension pow(double p) const;
  bool dimensionless() const { return *this == Dimension{}; }

  static Dimension none() { return {}; }
  static Dimension of_length() { return {1, 0, 0, 0}; }
  static Dimension of_mass() { return {0, 1, 0, 0}; }
  static Dimension of_time() { return {0, 0, 1, 0}; }
  static Dimension of_angle() { return {0, 0, 0, 1}; }
  static Dimension of_force() { return {1, 1, -2, 0}; }
  static Dimension of_pressure() { return {-1, 1, -2, 0}; }
  static Dimension of_density() { return {-3, 1, 0, 0}; }
  static Dimension of_velocity() { return {1, 0, -1, 0}; }
  static Dimension of_acceleration() { return {1, 0, -2, 0}; }
  static Dimension of_angular_velocity() { return {0, 0, -1, 1}; }
};

/// A human name: "length", "force", "angular velocity", or a formula such as "m^2*kg".
std::string describe(const Dimension& d);

/// One unit: multiply a number in this unit by `scale` to get SI.
struct Unit {
  double scale = 1;
  Dimension dimension;
};

/// A simple unit by name (`in`, `lbf`, `GPa`, ...); nullopt when unknown.
std::optional<Unit> find_unit(std::string_view name);

/// A compound unit such as `kg/m^3`, `in/s`, `m/s^2`, `lb/in^3`; nullopt when any part is
/// unknown or the text is malformed.
std::optional<Unit> parse_unit(std::string_view text);

/// The units a bare number takes where a dimension is expected (`units length=in;`).
/// Defaults: SI, angles in degrees.
struct UnitSystem {
  Unit length{1, Dimension::of_length()};
  Unit mass{1, Dimension::of_mass()};
  Unit time{1, Dimension::of_time()};
  Unit force{1, Dimension::of_force()};
  Unit pressure{1, Dimension::of_pressure()};
  Unit angle{0.017453292519943295, Dimension::of_angle()};

  /// SI per bare number for a value that must have dimension `d`: force and pressure use
  /// their own default unit, any other dimension is composed from the length, mass, time
  /// and angle defaults.
  double scale_for(const Dimension& d) const;
};

}  // namespace vproto::units
