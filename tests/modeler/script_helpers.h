#pragma once
// Helpers that run scripts through the modeler the way the CLI does.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "vproto/modeler/compiler.h"
#include "vproto/modeler/evaluator.h"
#include "vproto/modeler/parser.h"
#include "vproto/ui_batch/mesh_io.h"

namespace vproto::testing {

inline modeler::EvaluatedScript evaluate(
    const std::string& src, const std::vector<modeler::ParamOverride>& overrides = {}) {
  const modeler::Program program = modeler::parse_program(src, "t.vp");
  return modeler::evaluate_program(program, overrides, VPROTO_TEST_DATA);
}

inline modeler::EvaluatedScript build(const std::string& src,
                                      const std::vector<modeler::ParamOverride>& overrides = {},
                                      const std::string& cache_dir = "",
                                      modeler::CompileReport* report = nullptr) {
  modeler::EvaluatedScript script = evaluate(src, overrides);
  modeler::CompileOptions options;
  options.cache_dir = cache_dir;
  options.load_mesh = ui_batch::read_mesh;
  const modeler::CompileReport r = modeler::compile_bodies(script, options);
  if (report) *report = r;
  return script;
}

/// Runs the script (evaluation and, when `compile`, geometry) and expects an InputError at
/// t.vp:line:col whose message contains `part`.
inline void expect_input_error(const std::string& src, int line, int col, const std::string& part,
                               bool compile = false,
                               const std::vector<modeler::ParamOverride>& overrides = {}) {
  try {
    if (compile)
      build(src, overrides);
    else
      evaluate(src, overrides);
    ADD_FAILURE() << "no error for:\n" << src;
  } catch (const InputError& e) {
    EXPECT_EQ(e.loc().line, line) << e.what();
    EXPECT_EQ(e.loc().column, col) << e.what();
    EXPECT_NE(e.message().find(part), std::string::npos)
        << "message: " << e.what() << "\nexpected: " << part;
    const std::string where =
        e.loc().file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": error: ";
    EXPECT_EQ(std::string(e.what()).rfind(where, 0), 0u) << e.what();
  }
}

}  // namespace vproto::testing
