#pragma once
// What a run records step by step: history.csv's rows (cli.md, docs/contracts.md) and the
// force curves drawn from them (the reaction of each held body against its drive's travel,
// the insertion curve of each pushed FE body). The run driver's record, kept in the library
// so that `vproto run`, the benchmarks and the tests read one definition of every column.

#include <Eigen/Core>
#include <sstream>
#include <string>
#include <vector>

#include "vproto/sim/dynamics.h"
#include "vproto/sim/scene.h"

namespace vproto::sim {

/// The header row of history.csv (cli.md): the fixed columns, then each body's position,
/// each probe's displacement, and the reaction columns BODY_rx, BODY_ry, BODY_rz of the
/// `reaction_bodies` (held or gripped elastic bodies), then the contact force columns
/// BODY_cx, BODY_cy, BODY_cz of the `pushed_bodies` (FE bodies a push, not a drive, moves:
/// the force contacts apply to them, N), then BODY_corner_von_mises, BODY_corner_strain of
/// the `corner_bodies` (FE bodies with sharp inside corners: their hot-spot values now).
std::string history_header(const Scene& scene, const std::vector<int>& reaction_bodies = {},
                           const std::vector<int>& pushed_bodies = {},
                           const std::vector<int>& corner_bodies = {});

/// A force against a travel (or time): one point per recorded step.
struct ForceCurve {
  int body = -1;
  std::vector<double> x, y;
  double largest() const;   ///< 0 when empty
  double smallest() const;  ///< 0 when empty
};

/// An FE body that a push (a `force` without `region=`), not a drive, moves and that can
/// touch another body: its insertion curve is the contact force against the push, against
/// its travel along it (mm).
struct PushedBody {
  int body = -1;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  ///< of the push
  Eigen::Vector3d start = Eigen::Vector3d::Zero();       ///< its frame's origin at the start
  double push = 0;                                       ///< the push's magnitude, N
  ForceCurve curve;
};

class RunHistory {
 public:
  /// The columns and curves of the run `motion` is about to make (its bodies where the run
  /// starts): reaction columns for every body `motion` holds, contact force columns for every
  /// pushed FE body.
  RunHistory(const Scene& scene, const Dynamics& motion);

  /// Appends the row of motion's present state (and a point to every curve).
  void record(const Dynamics& motion);

  /// history.csv's text: the header and every recorded row.
  std::string csv() const { return out_.str(); }
  std::size_t rows() const { return rows_; }

  /// The first `move`'s body (-1 without one), and its direction: reaction curves run along
  /// its travel (mm); without a drive, against time (s) as the reaction's magnitude.
  int drive() const { return drive_; }
  const Eigen::Vector3d& drive_direction() const { return drive_dir_; }
  /// Per held body (reaction_bodies() order): the reaction along the drive (positive where
  /// the holders push the body along it) or its magnitude, N.
  const std::vector<int>& reaction_bodies() const { return reaction_bodies_; }
  const std::vector<ForceCurve>& reaction_curves() const { return reaction_curves_; }
  const std::vector<PushedBody>& pushed() const { return pushed_; }
  /// Per FE body with sharp inside corners whose hot-spot values are read: that strain
  /// (the largest principal, over the reads) against time (s).
  const std::vector<ForceCurve>& corner_strain_curves() const { return corner_curves_; }

 private:
  const Scene& scene_;
  int drive_ = -1;
  Eigen::Vector3d drive_dir_ = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d drive_start_ = Eigen::Vector3d::Zero();
  std::vector<int> reaction_bodies_;
  std::vector<ForceCurve> reaction_curves_;
  std::vector<PushedBody> pushed_;
  std::vector<int> corner_bodies_;  ///< FE bodies whose corners' hot-spot values are read
  std::vector<ForceCurve> corner_curves_;
  std::ostringstream out_;
  std::size_t rows_ = 0;
};

}  // namespace vproto::sim
