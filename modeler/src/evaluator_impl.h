#pragma once
// Internal: the evaluator's state and helpers, shared by evaluator.cpp (expressions and
// solids) and scene_statements.cpp (materials, bodies and scene statements).

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "vproto/materials/units.h"
#include "vproto/modeler/evaluator.h"
#include "vproto/modeler/value.h"

namespace vproto::modeler::detail {

/// A lexical scope: variables, and the scope it is nested in.
struct Scope {
  std::map<std::string, Value> vars;
  const Scope* parent = nullptr;

  const Value* find(const std::string& name) const {
    for (const Scope* s = this; s; s = s->parent) {
      auto it = s->vars.find(name);
      if (it != s->vars.end()) return &it->second;
    }
    return nullptr;
  }
};

/// A call's arguments matched to parameter names.
struct BoundArgs {
  std::map<std::string, std::pair<Value, SourceLoc>> values;
  const Value* get(const std::string& name) const {
    auto it = values.find(name);
    return it == values.end() ? nullptr : &it->second.first;
  }
  SourceLoc loc_of(const std::string& name, const SourceLoc& fallback) const {
    auto it = values.find(name);
    return it == values.end() ? fallback : it->second.second;
  }
};

class Evaluator {
 public:
  Evaluator(const Program& program, const std::vector<ParamOverride>& overrides,
            std::string script_dir, const EvaluationLimits& limits);
  EvaluatedScript run();

  // --- expressions (evaluator.cpp) ---
  Value eval(const Expr& e, const Scope& scope);
  BoundArgs bind(const std::string& callee, const std::vector<Arg>& args, const Scope& scope,
                 const std::vector<std::string>& positional,
                 const std::vector<std::string>& named_only, const SourceLoc& loc);

  // --- conversions to SI with dimension checks ---
  double quantity(const Value& v, const units::Dimension& d, const SourceLoc& loc,
                  const std::string& what) const;
  double positive(const Value& v, const units::Dimension& d, const SourceLoc& loc,
                  const std::string& what) const;
  Eigen::Vector3d vec3(const Value& v, const units::Dimension& d, const SourceLoc& loc,
                       const std::string& what) const;
  int count(const Value& v, const SourceLoc& loc, const std::string& what, int lo, int hi) const;
  bool flag(const Value& v, const SourceLoc& loc, const std::string& what) const;
  /// A word such as `dynamic` or `tet10`: a bare name that is no variable, or a string.
  std::string symbol(const Expr& e, const Scope& scope, const std::vector<std::string>& allowed,
                     const std::string& what);
  sim::Region region(const Expr& e, const Scope& scope, const std::string& what);

  // --- statements (evaluator.cpp) ---
  void top_statements(const std::vector<Stmt>& stmts, Scope& scope);
  std::vector<Feature> solids(const std::vector<Stmt>& stmts, const Scope& parent,
                              const Eigen::Affine3d& placement, int depth);

  // --- scene (scene_statements.cpp) ---
  void material_statement(const Stmt& s, const Scope& scope);
  void body_statement(const Stmt& s, const Scope& scope);
  void scene_statement(const Stmt& s, const Scope& scope);
  void resolve_body_references();

 private:
  void solid_statement(const Stmt& s, Scope& local, const Eigen::Affine3d& placement, int depth,
                       std::vector<Feature>& out);
  std::vector<Feature> call(const Stmt& s, const Scope& scope, const Eigen::Affine3d& placement,
                            int depth);
  Feature primitive(const Stmt& s, const Scope& scope, const Eigen::Affine3d& placement);
  void count_statement(const SourceLoc& loc);
  int segments_for(const BoundArgs& args, const SourceLoc& loc);
  /// Resolves a body name once all bodies are known; `need_elastic` names the statement
  /// that only applies to elastic bodies, or is empty.
  void body_ref(const std::string& name, const SourceLoc& loc, std::function<void(int)> set,
                const std::string& need_elastic = {});

  const Program& program_;
  std::map<std::string, std::string> overrides_;
  std::map<std::string, bool> override_used_;
  std::string script_dir_;
  EvaluationLimits limits_;

  units::UnitSystem units_;
  int facets_ = 0;         ///< `facets N;`, 0 = chordal default
  int body_segments_ = 0;  ///< the current body's `segments=`, 0 = none
  std::map<std::string, materials::Material> materials_;
  std::map<std::string, const Stmt*> modules_;
  const Scope* module_scope_ = nullptr;  ///< the global scope modules see
  long statements_ = 0;
  long leaves_ = 0;
  long body_triangles_ = 0;
  long total_triangles_ = 0;

  struct PendingRef {
    std::string name;
    SourceLoc loc;
    std::function<void(int)> set;
    std::string need_elastic;
  };
  std::vector<PendingRef> pending_;
  EvaluatedScript out_;
};

}  // namespace vproto::modeler::detail
