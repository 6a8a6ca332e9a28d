#include "vproto/materials/units.h"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>

namespace vproto::units {
namespace {

bool near(double a, double b) { return std::abs(a - b) < 1e-9; }

struct NamedUnit {
  std::string_view name;
  double scale;
  Dimension dimension;
};

// SI factors; the inch and pound are exact by definition (1959), lbf = lb * g_n.
const std::array<NamedUnit, 22> kUnits = {{
    {"m", 1.0, Dimension::of_length()},
    {"cm", 1e-2, Dimension::of_length()},
    {"mm", 1e-3, Dimension::of_length()},
    {"um", 1e-6, Dimension::of_length()},
    {"in", 0.0254, Dimension::of_length()},
    {"ft", 0.3048, Dimension::of_length()},
    {"kg", 1.0, Dimension::of_mass()},
    {"g", 1e-3, Dimension::of_mass()},
    {"lb", 0.45359237, Dimension::of_mass()},
    {"s", 1.0, Dimension::of_time()},
    {"ms", 1e-3, Dimension::of_time()},
    {"us", 1e-6, Dimension::of_time()},
    {"N", 1.0, Dimension::of_force()},
    {"kN", 1e3, Dimension::of_force()},
    {"lbf", 0.45359237 * 9.80665, Dimension::of_force()},
    {"Pa", 1.0, Dimension::of_pressure()},
    {"kPa", 1e3, Dimension::of_pressure()},
    {"MPa", 1e6, Dimension::of_pressure()},
    {"GPa", 1e9, Dimension::of_pressure()},
    {"psi", 0.45359237 * 9.80665 / (0.0254 * 0.0254), Dimension::of_pressure()},
    {"ksi", 1e3 * 0.45359237 * 9.80665 / (0.0254 * 0.0254), Dimension::of_pressure()},
    {"deg", 0.017453292519943295, Dimension::of_angle()},
}};

std::string format_exponent(double e) {
  if (near(e, std::round(e))) return std::to_string(static_cast<long>(std::round(e)));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", e);
  return buf;
}

}  // namespace

bool Dimension::operator==(const Dimension& o) const {
  return near(length, o.length) && near(mass, o.mass) && near(time, o.time) && near(angle, o.angle);
}

Dimension Dimension::operator*(const Dimension& o) const {
  return {length + o.length, mass + o.mass, time + o.time, angle + o.angle};
}

Dimension Dimension::operator/(const Dimension& o) const {
  return {length - o.length, mass - o.mass, time - o.time, angle - o.angle};
}

Dimension Dimension::pow(double p) const { return {length * p, mass * p, time * p, angle * p}; }

std::string describe(const Dimension& d) {
  struct Named {
    Dimension dim;
    const char* name;
  };
  static const Named kNamed[] = {
      {Dimension::none(), "a plain number"},
      {Dimension::of_length(), "a length"},
      {Dimension::of_mass(), "a mass"},
      {Dimension::of_time(), "a time"},
      {Dimension::of_angle(), "an angle"},
      {Dimension::of_force(), "a force"},
      {Dimension::of_pressure(), "a pressure"},
      {Dimension::of_density(), "a density"},
      {Dimension::of_velocity(), "a velocity"},
      {Dimension::of_acceleration(), "an acceleration"},
      {Dimension::of_angular_velocity(), "an angular velocity"},
      {Dimension{2, 0, 0, 0}, "an area"},
      {Dimension{3, 0, 0, 0}, "a volume"},
      {Dimension{0, 0, -1, 0}, "a frequency"},
      {Dimension{2, 1, -2, 0}, "an energy or torque"},
  };
  for (const auto& n : kNamed)
    if (n.dim == d) return n.name;
  std::string out;
  auto add = [&](double e, const char* sym) {
    if (near(e, 0)) return;
    if (!out.empty()) out += "*";
    out += sym;
    if (!near(e, 1)) out += "^" + format_exponent(e);
  };
  add(d.length, "m");
  add(d.mass, "kg");
  add(d.time, "s");
  add(d.angle, "rad");
  return "a quantity in " + out;
}

std::optional<Unit> find_unit(std::string_view name) {
  if (name == "rad") return Unit{1.0, Dimension::of_angle()};
  for (const auto& u : kUnits)
    if (u.name == name) return Unit{u.scale, u.dimension};
  return std::nullopt;
}

std::optional<Unit> parse_unit(std::string_view text) {
  // grammar: NAME ('^' INT)? ( ('*' | '/') NAME ('^' INT)? )*
  Unit total{1.0, Dimension::none()};
  std::size_t i = 0;
  char op = '*';
  while (true) {
    std::size_t start = i;
    while (i < text.size() && std::isalpha(static_cast<unsigned char>(text[i]))) ++i;
    if (i == start) return std::nullopt;
    auto unit = find_unit(text.substr(start, i - start));
    if (!unit) return std::nullopt;
    double exponent = 1;
    if (i < text.size() && text[i] == '^') {
      ++i;
      std::size_t num_start = i;
      if (i < text.size() && text[i] == '-') ++i;
      while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
      if (i == num_start || (i == num_start + 1 && text[num_start] == '-')) return std::nullopt;
      exponent = std::strtod(std::string(text.substr(num_start, i - num_start)).c_str(), nullptr);
    }
    if (op == '/') exponent = -exponent;
    total.scale *= std::pow(unit->scale, exponent);
    total.dimension = total.dimension * unit->dimension.pow(exponent);
    if (i == text.size()) return total;
    op = text[i];
    if (op != '*' && op != '/') return std::nullopt;
    ++i;
  }
}

double UnitSystem::scale_for(const Dimension& d) const {
  if (d == Dimension::of_force()) return force.scale;
  if (d == Dimension::of_pressure()) return pressure.scale;
  return std::pow(length.scale, d.length) * std::pow(mass.scale, d.mass) *
         std::pow(time.scale, d.time) * std::pow(angle.scale, d.angle);
}

}  // namespace vproto::units
