#pragma once
// A dense contact problem of the one solver (point_contact_solver.h) written to a file and
// read back: the engine writes the problems it solves where VPROTO_DUMP_CONTACT asks
// (docs/contracts.md), and `point_contact_bench --problem FILE...` solves them alone, so a
// change to the solver can be measured on a run's real problems (the snap-fit's landing:
// 1,175 points) without the run around them.
//
// The format: one text line
//   vproto-contact-problem 1 points=M warm=0|1 max_sweeps=.. tolerance=.. newton_after=..
//   newton_unknowns=.. block_stick=0|1 newton_tries=.. newton_damping=..
//   newton_damping_floor=..
// then, as little-endian doubles, W (3M x 3M by columns), free (3M), mu (M) and, when
// warm=1, the warm start (3M).

#include <Eigen/Core>
#include <string>

#include "vproto/sim/point_contact_solver.h"

namespace vproto::sim {

/// Writes `problem` (its dense W: `problem.columns` null) with its warm start (3m, or
/// empty) and options to `path`, through a temporary file renamed into place. Throws
/// std::runtime_error naming the path when it cannot be written.
void write_contact_problem(const std::string& path, const PointContactProblem& problem,
                           const Eigen::VectorXd& warm, const PointContactOptions& options);

/// Reads what write_contact_problem wrote. Throws std::runtime_error naming the path and
/// what is wrong (not such a file, another version, cut short).
void read_contact_problem(const std::string& path, PointContactProblem* problem,
                          Eigen::VectorXd* warm, PointContactOptions* options);

}  // namespace vproto::sim
