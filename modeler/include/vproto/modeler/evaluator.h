#pragma once
// Evaluates a parsed script: constants, params and overrides, units, materials, modules,
// loops and conditions, into per-body feature trees and a sim::Scene whose bodies have
// no geometry yet. All validation that needs no geometry happens here, so a bad script
// is rejected in milliseconds.

#include <map>
#include <string>
#include <vector>

#include "vproto/modeler/ast.h"
#include "vproto/modeler/feature_tree.h"
#include "vproto/sim/scene.h"

namespace vproto::modeler {

/// `--set NAME=EXPR` overrides, in command-line order.
struct ParamOverride {
  std::string name;
  std::string expression;
};

/// Work limits that keep a hostile or mistaken script from hanging or exhausting memory.
struct EvaluationLimits {
  int max_module_depth = 100;
  long max_statements = 10'000'000;  ///< statement executions
  long max_leaves = 100'000;         ///< primitives in the whole script
  long max_body_triangles = 4'000'000;
  long max_total_triangles = 10'000'000;
  int max_segments = 4096;
};

struct EvaluatedScript {
  sim::Scene scene;                           ///< bodies without geometry
  std::vector<Feature> body_trees;            ///< one union per body, in scene.bodies order
  std::vector<std::string> warnings;          ///< "FILE:LINE:COL: warning: ..."
  std::map<std::string, std::string> params;  ///< param name -> value as evaluated (for reports)
};

/// Throws InputError at the first problem. `script_dir` resolves `import` paths.
EvaluatedScript evaluate_program(const Program& program,
                                 const std::vector<ParamOverride>& overrides,
                                 const std::string& script_dir,
                                 const EvaluationLimits& limits = {});

}  // namespace vproto::modeler
