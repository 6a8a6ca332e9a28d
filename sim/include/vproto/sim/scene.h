#pragma once
// The compiled assembly that the simulator takes (DESIGN.md "Scene"): plain data, SI
// units, bodies referred to by index. Nothing here knows the script language; every
// statement keeps its source place so later stages can report errors where they arose.

#include <optional>
#include <string>
#include <vector>

#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/tet_mesh.h"
#include "vproto/geometry/tri_mesh.h"
#include "vproto/materials/errors.h"
#include "vproto/materials/material.h"
#include "vproto/sim/linear_solver.h"

namespace vproto::sim {

enum class BodyKind { kRigid, kElastic };
enum class ElementType { kTet4, kTet10 };

/// One body: geometry in assembly coordinates (where it starts), material, mass.
struct Body {
  std::string name;
  BodyKind kind = BodyKind::kRigid;
  materials::Material material;
  double mesh_size = 0;  ///< m; 0 = the default (about 10 elements across the thinnest part)
  ElementType element = ElementType::kTet10;
  SourceLoc loc;

  geometry::TriMesh surface;  ///< closed, outward-oriented
  geometry::MassProperties mass_properties;
  double mass = 0;                                    ///< kg
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  ///< kg m^2 about the centroid, world axes
  std::vector<geometry::TriMesh> convex_parts;        ///< empty until asked for
  bool convex_parts_computed = false;
  geometry::TetMesh tet_mesh;  ///< elastic bodies, when asked for
  geometry::TetQuality tet_quality;
  /// A meshed body's thinnest wall (geometry::thinnest_wall), m; 0 when not measured.
  double thinnest_wall = 0;
  bool meshed = false;
  /// Meshed bodies: the FE mesh's boundary (its nodes, tet10 faces split in four), which
  /// frames, pictures and exported meshes show, so the surface bends as the elements do.
  geometry::TriMesh display;
  /// What is drawn and exported: `display` when there is one, else `surface`.
  const geometry::TriMesh& drawn() const { return display.F.rows() > 0 ? display : surface; }
};

/// An axis-aligned box in assembly coordinates selecting mesh nodes.
struct Region {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  }
};

/// A rigid body of this surface (assembly coordinates) and density, with its mass
/// properties filled in (for scenes built in code: benchmarks and tests).
Body make_rigid_body(const std::string& name, const geometry::TriMesh& surface, double density);

inline constexpr int kGround = -1;

/// Newmark's gamma - 1/2 for an elastic body with inertia that can touch another, unless
/// the scene sets numerical_damping: contact rows excite the average-acceleration rule's
/// undamped two-step mode (a paw pressed on a floor and held: its contact force flipped by
/// 1.7e-4 of itself every step, for ever, stiffness damping or not); 0.05 settles it to
/// 2e-7 within 10 ms and damps a mode resolved with the step's period error (w h of
/// 0.035) by a damping ratio of about 1e-3.
inline constexpr double kContactNumericalDamping = 0.05;

struct Fix {
  int body = 0;
  std::optional<Region> region;  ///< none: the whole reference frame is fixed
  SourceLoc loc;
};

struct Grip {
  int body = 0;
  Region region;
  SourceLoc loc;
};

enum class JointType { kSlider, kRevolute, kSpherical, kFixed };

struct Joint {
  JointType type = JointType::kFixed;
  int body = 0;
  int other = kGround;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit vector (slider, revolute)
  Eigen::Vector3d at = Eigen::Vector3d::Zero();     ///< m (revolute, spherical)
  SourceLoc loc;
};

struct Force {
  int body = 0;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  ///< N
  std::optional<Eigen::Vector3d> at;                ///< m; none: at the centroid
  std::optional<Region> region;                     ///< spread over these nodes (elastic)
  double ramp = 0;                                  ///< s; 0: applied at once
  SourceLoc loc;
};

struct Torque {
  int body = 0;
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  ///< N m
  double ramp = 0;
  SourceLoc loc;
};

struct Move {
  int body = 0;
  Eigen::Vector3d by = Eigen::Vector3d::Zero();  ///< m
  double over = 0;                               ///< s
  SourceLoc loc;
};

struct InitialVelocity {
  int body = 0;
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();   ///< m/s, world axes
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();  ///< rad/s, world axes
  SourceLoc loc;
};

/// Contact settings for every pair (both bodies kGround) or for one pair.
struct ContactSetting {
  int body_a = kGround;
  int body_b = kGround;
  std::optional<double> friction;
  std::optional<double> restitution;
  SourceLoc loc;
};

struct NoContact {
  int body_a = 0;
  int body_b = 0;
  SourceLoc loc;
};

struct Probe {
  std::string name;
  int body = 0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< m, where the material point starts
  SourceLoc loc;
};

enum class SimulationMode { kStatic, kQuasistatic, kDynamic };

struct SimulationSettings {
  SimulationMode mode = SimulationMode::kDynamic;
  double duration = 1.0;            ///< s
  std::optional<double> time_step;  ///< s; none: adaptive to `tolerance`
  double tolerance = 1e-3;
  int frames = 60;
  double mass_damping = 0;       ///< Rayleigh alpha, 1/s (elastic bodies)
  double stiffness_damping = 0;  ///< Rayleigh beta, s (elastic bodies)
  /// Newmark gamma - 1/2 (0: average acceleration). Not given: 0, but
  /// kContactNumericalDamping for an elastic body that can touch another and has inertia.
  std::optional<double> numerical_damping;
  /// The FE solver backend (linear_solver.h); `--solver` overrides it.
  SolverChoice solver = SolverChoice::kAuto;
  bool given = false;  ///< a simulate(...) statement was present
  SourceLoc loc;       ///< of the simulate(...) statement, when given
};

/// The most steps a run may take: beyond, it would run for hours and its history.csv
/// (a row per step) grow past a gigabyte.
inline constexpr double kMaxSteps = 5e6;

/// Throws InputError (at the simulate statement, or `where`) when `duration` at steps of
/// `dt` exceeds kMaxSteps, naming the step, why it is that small, and the fix.
void check_step_count(const SimulationSettings& st, double dt, const std::string& why,
                      const SourceLoc& where);

struct RenderSettings {
  int width = 1280;
  int height = 720;
  std::string field = "none";                        ///< none | displacement | von_mises
  std::string camera = "iso";                        ///< iso | front | side | top | custom
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();     ///< m, camera == "custom"
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  ///< m, camera == "custom"
  /// Elastic deformation drawn this many times larger (ParaView's warp by vector); the
  /// exported meshes and all figures stay at true scale.
  double deform_scale = 1;
};

struct ExportSettings {
  std::string format = "stl";  ///< stl | obj | vtu | none
  int every = 1;
};

/// Everything one script describes.
struct Scene {
  std::vector<Body> bodies;
  std::vector<Fix> fixes;
  std::vector<Grip> grips;
  std::vector<Joint> joints;
  std::vector<Force> forces;
  std::vector<Torque> torques;
  std::vector<Move> moves;
  std::optional<Eigen::Vector3d> gravity;  ///< m/s^2
  std::vector<InitialVelocity> velocities;
  std::vector<ContactSetting> contacts;
  std::vector<NoContact> nocontacts;
  std::vector<Probe> probes;
  SimulationSettings simulation;
  RenderSettings render;
  ExportSettings output;

  /// Index of the body with this name, or -1.
  int find_body(const std::string& name) const;
};

}  // namespace vproto::sim
