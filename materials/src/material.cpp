#include "vproto/materials/material.h"

#include <algorithm>
#include <cmath>

namespace vproto::materials {
namespace {

Material make(const char* name, double e, double nu, double rho, double sy, double ey, double mu,
              const char* source) {
  Material m;
  m.name = name;
  m.youngs_modulus = e;
  m.poisson_ratio = nu;
  m.density = rho;
  m.yield_strength = sy;
  m.yield_strain = ey;
  m.friction = mu;
  m.source = source;
  return m;
}

std::vector<Material> make_library() {
  // Typical room-temperature values. Metals: ASM/MatWeb data sheets (minimum yield).
  // Plastics: MatWeb generic-grade averages; yield strains for the plastics are the
  // permissible short-term strains of the Bayer MaterialScience snap-fit design guide
  // where it lists the material (references.md). Friction: dry, against steel.
  return {
      make("steel", 210e9, 0.30, 7850, 250e6, 250e6 / 210e9, 0.5,
           "structural steel, ASTM A36 (ASM/MatWeb)"),
      make("aluminum", 68.9e9, 0.33, 2700, 276e6, 276e6 / 68.9e9, 0.45,
           "aluminum 6061-T6 (ASM/MatWeb)"),
      make("abs", 2.3e9, 0.35, 1040, 43e6, 0.025, 0.4,
           "ABS, generic (MatWeb); yield strain: Bayer snap-fit guide"),
      make("polycarbonate", 2.35e9, 0.37, 1200, 62e6, 0.04, 0.35,
           "polycarbonate, generic (MatWeb); yield strain: Bayer snap-fit guide"),
      make("nylon", 2.8e9, 0.39, 1140, 80e6, 0.04, 0.3,
           "polyamide 6, dry as molded (MatWeb); yield strain: Bayer snap-fit guide"),
      make("hdpe", 0.9e9, 0.42, 950, 26e6, 0.08, 0.25,
           "HDPE, generic (MatWeb); values used in references.md"),
      make("pom", 3.1e9, 0.35, 1420, 70e6, 0.06, 0.2, "acetal homopolymer (MatWeb)"),
      make("rubber", 2.0e6, 0.49, 930, 15e6, 1.0, 0.8,
           "natural rubber, unfilled, small-strain modulus (MatWeb)"),
  };
}

}  // namespace

std::string validation_error(const Material& m) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(m.youngs_modulus) || m.youngs_modulus <= 0)
    return "E (Young's modulus) must be a positive pressure";
  if (!finite(m.poisson_ratio) || m.poisson_ratio <= -1 || m.poisson_ratio >= 0.5)
    return "nu (Poisson's ratio) must lie strictly between -1 and 0.5";
  if (!finite(m.density) || m.density <= 0) return "density must be positive";
  if (m.yield_strength && (!finite(*m.yield_strength) || *m.yield_strength <= 0))
    return "yield_strength must be a positive pressure";
  if (m.yield_strain && (!finite(*m.yield_strain) || *m.yield_strain <= 0))
    return "yield_strain must be a positive number";
  if (m.friction && (!finite(*m.friction) || *m.friction < 0))
    return "friction must be zero or positive";
  if (m.restitution && (!finite(*m.restitution) || *m.restitution < 0 || *m.restitution > 1))
    return "restitution must lie between 0 and 1";
  return {};
}

bool has_yield(const Material& m) { return m.yield_strength || m.yield_strain; }

double yield_ratio(const Material& m, double von_mises, double principal_strain) {
  double r = 0;
  if (m.yield_strength) r = std::max(r, von_mises / *m.yield_strength);
  if (m.yield_strain) r = std::max(r, principal_strain / *m.yield_strain);
  return r;
}

const std::vector<Material>& builtin_materials() {
  static const std::vector<Material> kLibrary = make_library();
  return kLibrary;
}

const Material* find_builtin(const std::string& name) {
  for (const auto& m : builtin_materials())
    if (m.name == name) return &m;
  return nullptr;
}

}  // namespace vproto::materials
