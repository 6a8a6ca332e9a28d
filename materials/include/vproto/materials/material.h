#pragma once
// Material records and the built-in library (spec "Materials").

#include <optional>
#include <string>
#include <vector>

namespace vproto::materials {

/// A linear-elastic isotropic material, SI units.
struct Material {
  std::string name;
  double youngs_modulus = 0;             ///< Pa
  double poisson_ratio = 0;              ///< -1 < nu < 0.5
  double density = 0;                    ///< kg/m^3
  std::optional<double> yield_strength;  ///< Pa
  std::optional<double> yield_strain;    ///< dimensionless
  std::optional<double> friction;        ///< default Coulomb coefficient against any body
  std::optional<double> restitution;     ///< 0..1
  std::string source;                    ///< where the values come from (built-ins) or "script"
};

/// Why `m` is not a usable material, or an empty string when it is. Checks E > 0,
/// density > 0, -1 < nu < 0.5 and the ranges of the optional values.
std::string validation_error(const Material& m);

/// Whether `m` says where it yields (a yield strength, a yield strain or both).
bool has_yield(const Material& m);

/// How far a stress state is towards the material's yield: the larger of the von Mises
/// stress over `yield_strength` and the largest principal strain over `yield_strain`, of
/// those the material has (1 = at the yield; 0 when it has neither).
double yield_ratio(const Material& m, double von_mises, double principal_strain);

/// The built-in library: steel, aluminum, abs, polycarbonate, nylon, hdpe, pom, rubber.
const std::vector<Material>& builtin_materials();

/// A built-in material by name, or nullptr.
const Material* find_builtin(const std::string& name);

}  // namespace vproto::materials
