#include <cmath>
#include <cstdio>
#include <filesystem>

#include "evaluator_impl.h"
#include "vproto/geometry/primitives.h"
#include "vproto/modeler/parser.h"

namespace vproto::modeler {
namespace detail {
namespace {

using units::Dimension;
constexpr double kPi = 3.14159265358979323846;

const std::vector<std::string> kPrimitives = {"box",   "cylinder", "sphere", "wedge",
                                              "prism", "fillet",   "import"};
const std::vector<std::string> kTransforms = {"translate", "rotate", "scale", "mirror"};
const std::vector<std::string> kBooleans = {"union", "difference", "intersection"};
const std::vector<std::string> kFunctions = {"sin",   "cos",   "tan", "asin", "acos", "atan",
                                             "atan2", "sqrt",  "abs", "min",  "max",  "floor",
                                             "ceil",  "round", "len", "norm"};

bool contains(const std::vector<std::string>& list, const std::string& s) {
  for (const auto& x : list)
    if (x == s) return true;
  return false;
}

std::string join(const std::vector<std::string>& list) {
  std::string out;
  for (const auto& x : list) out += (out.empty() ? "" : ", ") + x;
  return out;
}

std::string format_value(const Value& v) {
  switch (v.type) {
    case Value::Type::kNumber: {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.12g", v.number);
      return v.dim.dimensionless() ? buf
                                   : std::string(buf) + " (SI, " + units::describe(v.dim) + ")";
    }
    case Value::Type::kBool:
      return v.boolean ? "true" : "false";
    case Value::Type::kString:
      return "\"" + v.text + "\"";
    default:
      return describe(v);
  }
}

// Rotation by `angle` about the unit `axis`, exact for multiples of 90 degrees so that
// rotated faces stay exactly coplanar with unrotated ones (cos(pi) is -1, sin(pi) is 0).
Eigen::Matrix3d axis_rotation(double angle, const Eigen::Vector3d& axis) {
  const auto [s, c] = exact_sin_cos(angle);
  const Eigen::Matrix3d k =
      (Eigen::Matrix3d() << 0, -axis.z(), axis.y(), axis.z(), 0, -axis.x(), -axis.y(), axis.x(), 0)
          .finished();
  return Eigen::Matrix3d::Identity() + s * k + (1 - c) * k * k;
}

}  // namespace

Evaluator::Evaluator(const Program& program, const std::vector<ParamOverride>& overrides,
                     std::string script_dir, const EvaluationLimits& limits)
    : program_(program), script_dir_(std::move(script_dir)), limits_(limits) {
  for (const auto& o : overrides) {
    overrides_[o.name] = o.expression;
    override_used_[o.name] = false;
  }
  for (const auto& m : materials::builtin_materials()) materials_[m.name] = m;
}

EvaluatedScript Evaluator::run() {
  Scope global;
  global.vars["pi"] = Value::make_number(kPi);
  top_statements(program_.statements, global);
  for (const auto& [name, used] : override_used_) {
    if (used) continue;
    std::vector<std::string> params;
    for (const auto& p : out_.params) params.push_back(p.first);
    throw InputError(
        SourceLoc{"--set", 1, 1},
        "'" + name + "' is not a param of " + program_.filename +
            (params.empty() ? " (it declares no params)" : " (its params: " + join(params) + ")"));
  }
  resolve_body_references();
  return std::move(out_);
}

void Evaluator::count_statement(const SourceLoc& loc) {
  if (++statements_ > limits_.max_statements)
    throw InputError(loc, "the script executes more than " +
                              std::to_string(limits_.max_statements) +
                              " statements: a loop runs too long");
}

// --- expressions ---

Value Evaluator::eval(const Expr& e, const Scope& scope) {
  switch (e.kind) {
    case Expr::Kind::kNumber: {
      if (e.text.empty()) return Value::make_number(e.number);
      const auto unit = units::parse_unit(e.text);
      if (!unit) throw InputError(e.loc, "unknown unit '" + e.text + "'");
      return Value::make_number(e.number * unit->scale, unit->dimension);
    }
    case Expr::Kind::kString:
      return Value::make_string(e.text);
    case Expr::Kind::kBool:
      return Value::make_bool(e.boolean);
    case Expr::Kind::kIdent: {
      if (const Value* v = scope.find(e.text)) return *v;
      if (materials_.count(e.text))
        throw InputError(e.loc, "'" + e.text +
                                    "' is a material; it can only be named in a body's "
                                    "material=...");
      throw InputError(e.loc, "unknown name '" + e.text + "': define it with 'let " + e.text +
                                  " = ...;' before this line");
    }
    case Expr::Kind::kVector: {
      if (e.items.size() > kMaxVectorSize)
        throw InputError(e.loc,
                         "vector has more than " + std::to_string(kMaxVectorSize) + " elements");
      std::vector<Value> items;
      items.reserve(e.items.size());
      for (const auto& x : e.items) items.push_back(eval(*x, scope));
      return Value::make_vector(std::move(items));
    }
    case Expr::Kind::kRange: {
      Value start = eval(*e.items[0], scope);
      Value step = e.items.size() == 3 ? eval(*e.items[1], scope) : Value::make_number(1);
      Value end = eval(*e.items.back(), scope);
      for (const Value* v : {&start, &step, &end})
        if (!v->is_number()) throw InputError(e.loc, "a range needs numbers, got " + describe(*v));
      // a common dimension: bare numbers take the others' dimension
      Dimension dim;
      for (const Value* v : {&start, &step, &end})
        if (!v->dim.dimensionless()) dim = v->dim;
      for (Value* v : {&start, &step, &end}) {
        if (v->dim.dimensionless() && !dim.dimensionless()) {
          v->number *= units_.scale_for(dim);
        } else if (v->dim != dim) {
          throw InputError(
              e.loc, "a range mixes " + units::describe(v->dim) + " and " + units::describe(dim));
        }
      }
      if (step.number == 0) throw InputError(e.loc, "a range's step must not be zero");
      if (step.number < 0)
        throw InputError(e.loc,
                         "a range's step must be positive (write [end : step : start] "
                         "and reverse the order instead)");
      Value r;
      r.type = Value::Type::kRange;
      r.number = start.number;
      r.step = step.number;
      r.end = end.number;
      r.dim = dim;
      elements(r, e.loc);  // rejects ranges that are too long, here
      return r;
    }
    case Expr::Kind::kComprehension: {
      std::vector<Value> out;
      const Value over = eval(*e.items[0], scope);
      for (const Value& x : elements(over, e.items[0]->loc)) {
        count_statement(e.loc);
        Scope inner;
        inner.parent = &scope;
        inner.vars[e.text] = x;
        Value v = eval(*e.items[1], inner);
        if (e.items[1]->kind == Expr::Kind::kComprehension) {
          for (const auto& y : *v.items) out.push_back(y);  // nested 'for' flattens
        } else {
          out.push_back(std::move(v));
        }
        if (out.size() > kMaxVectorSize)
          throw InputError(e.loc, "list comprehension makes more than " +
                                      std::to_string(kMaxVectorSize) + " elements");
      }
      return Value::make_vector(std::move(out));
    }
    case Expr::Kind::kUnary:
      return unary_op(e.text, eval(*e.items[0], scope), e.loc);
    case Expr::Kind::kBinary: {
      if (e.text == "&&" || e.text == "||") {
        const bool lhs = truthy(eval(*e.items[0], scope));
        if (e.text == "&&" && !lhs) return Value::make_bool(false);
        if (e.text == "||" && lhs) return Value::make_bool(true);
        return Value::make_bool(truthy(eval(*e.items[1], scope)));
      }
      return binary_op(e.text, eval(*e.items[0], scope), eval(*e.items[1], scope), units_, e.loc);
    }
    case Expr::Kind::kTernary:
      return truthy(eval(*e.items[0], scope)) ? eval(*e.items[1], scope) : eval(*e.items[2], scope);
    case Expr::Kind::kIndex: {
      const Value base = eval(*e.items[0], scope);
      const Value index = eval(*e.items[1], scope);
      if (!index.is_number() || !index.dim.dimensionless() ||
          index.number != std::floor(index.number))
        throw InputError(e.items[1]->loc,
                         "an index must be a whole plain number, got " + describe(index));
      const std::vector<Value> items = elements(base, e.loc);
      if (index.number < 0 || index.number >= static_cast<double>(items.size()))
        throw InputError(e.items[1]->loc, "index " +
                                              std::to_string(static_cast<long>(index.number)) +
                                              " is out of range (the vector has " +
                                              std::to_string(items.size()) + " elements)");
      return items[static_cast<std::size_t>(index.number)];
    }
    case Expr::Kind::kCall: {
      std::vector<Value> args;
      for (const auto& a : e.args) {
        if (!a.name.empty()) throw InputError(a.loc, e.text + "() takes no named arguments");
        args.push_back(eval(*a.value, scope));
      }
      Value result;
      if (call_builtin(e.text, args, units_, e.loc, &result)) return result;
      if (contains(kPrimitives, e.text) || contains(kTransforms, e.text) ||
          contains(kBooleans, e.text) || modules_.count(e.text))
        throw InputError(e.loc, "'" + e.text +
                                    "' is a solid, not a value: use it as a statement "
                                    "inside a body");
      throw InputError(e.loc,
                       "unknown function '" + e.text + "' (built-ins: " + join(kFunctions) + ")");
    }
  }
  throw InternalError("unhandled expression kind");
}

BoundArgs Evaluator::bind(const std::string& callee, const std::vector<Arg>& args,
                          const Scope& scope, const std::vector<std::string>& positional,
                          const std::vector<std::string>& named_only, const SourceLoc& loc) {
  BoundArgs out;
  std::size_t next_positional = 0;
  for (const auto& a : args) {
    std::string name = a.name;
    if (name.empty()) {
      if (next_positional >= positional.size())
        throw InputError(a.loc, callee + "() takes at most " + std::to_string(positional.size()) +
                                    " positional argument" + (positional.size() == 1 ? "" : "s") +
                                    "; name the others (name=value)");
      name = positional[next_positional++];
    } else if (!contains(positional, name) && !contains(named_only, name)) {
      std::vector<std::string> all = positional;
      all.insert(all.end(), named_only.begin(), named_only.end());
      throw InputError(a.loc,
                       callee + "() has no argument '" + name + "'" +
                           (all.empty() ? " (it takes none)" : " (it takes: " + join(all) + ")"));
    }
    if (out.values.count(name))
      throw InputError(a.loc, callee + "(): argument '" + name + "' is given twice");
    out.values[name] = {eval(*a.value, scope), a.loc};
  }
  (void)loc;
  return out;
}

// --- conversions ---

double Evaluator::quantity(const Value& v, const Dimension& d, const SourceLoc& loc,
                           const std::string& what) const {
  if (!v.is_number())
    throw InputError(loc, what + " must be " + units::describe(d) + ", got " + describe(v));
  double x = v.number;
  if (v.dim.dimensionless()) {
    x *= units_.scale_for(d);
  } else if (v.dim != d) {
    throw InputError(loc, what + " must be " + units::describe(d) + ", got " + describe(v));
  }
  // energies square speeds, stiffnesses square lengths: beyond 1e100 (SI) they overflow to
  // infinity (issue 13: a speed of 1e300 ended "ok" with inf in the outputs)
  if (!(std::abs(x) <= 1e100)) {
    char shown[32];
    std::snprintf(shown, sizeof shown, "%g", x);
    throw InputError(loc, what + " = " + shown +
                              " (SI units) is out of range: vproto squares such values "
                              "(energies, stiffnesses), which overflow; give a magnitude below "
                              "1e100");
  }
  return x;
}

double Evaluator::positive(const Value& v, const Dimension& d, const SourceLoc& loc,
                           const std::string& what) const {
  const double x = quantity(v, d, loc, what);
  if (!(x > 0)) throw InputError(loc, what + " must be positive");
  return x;
}

Eigen::Vector3d Evaluator::vec3(const Value& v, const Dimension& d, const SourceLoc& loc,
                                const std::string& what) const {
  if (!v.is_vector() || v.items->size() != 3)
    throw InputError(loc, what + " must be a vector of 3 values [x, y, z], got " + describe(v));
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i)
    out[i] = quantity((*v.items)[i], d, loc, what + " component " + "xyz"[i]);
  return out;
}

int Evaluator::count(const Value& v, const SourceLoc& loc, const std::string& what, int lo,
                     int hi) const {
  if (!v.is_number() || !v.dim.dimensionless() || v.number != std::floor(v.number))
    throw InputError(loc, what + " must be a whole number, got " + describe(v));
  if (v.number < lo || v.number > hi)
    throw InputError(
        loc, what + " must lie between " + std::to_string(lo) + " and " + std::to_string(hi));
  return static_cast<int>(v.number);
}

bool Evaluator::flag(const Value& v, const SourceLoc& loc, const std::string& what) const {
  if (v.type != Value::Type::kBool)
    throw InputError(loc, what + " must be true or false, got " + describe(v));
  return v.boolean;
}

std::string Evaluator::symbol(const Expr& e, const Scope& scope,
                              const std::vector<std::string>& allowed, const std::string& what) {
  std::string word;
  if (e.kind == Expr::Kind::kIdent && !scope.find(e.text)) {
    word = e.text;
  } else {
    const Value v = eval(e, scope);
    if (v.type != Value::Type::kString)
      throw InputError(e.loc, what + " must be one of " + join(allowed) + ", got " + describe(v));
    word = v.text;
  }
  if (!allowed.empty() && !contains(allowed, word))
    throw InputError(e.loc, what + " must be one of " + join(allowed) + ", got '" + word + "'");
  return word;
}

sim::Region Evaluator::region(const Expr& e, const Scope& scope, const std::string& what) {
  if (e.kind != Expr::Kind::kCall || e.text != "box" || e.args.size() != 2 ||
      !e.args[0].name.empty() || !e.args[1].name.empty())
    throw InputError(e.loc, what + " must be box([xmin,ymin,zmin], [xmax,ymax,zmax])");
  sim::Region r;
  r.lo = vec3(eval(*e.args[0].value, scope), Dimension::of_length(), e.args[0].loc,
              what + " minimum corner");
  r.hi = vec3(eval(*e.args[1].value, scope), Dimension::of_length(), e.args[1].loc,
              what + " maximum corner");
  if (!(r.lo.array() < r.hi.array()).all())
    throw InputError(e.loc, what + ": every minimum coordinate must be below its maximum");
  return r;
}

// --- statements ---

void Evaluator::top_statements(const std::vector<Stmt>& stmts, Scope& scope) {
  for (const Stmt& s : stmts) {
    count_statement(s.loc);
    switch (s.kind) {
      case Stmt::Kind::kEmpty:
        break;
      case Stmt::Kind::kLet:
      case Stmt::Kind::kParam: {
        if (scope.vars.count(s.name))
          throw InputError(s.loc, "'" + s.name + "' is already defined; pick another name");
        if (s.kind == Stmt::Kind::kParam && scope.parent)
          throw InputError(s.loc, "a param must be at the top level of the script, not in a block");
        Value v = eval(*s.value, scope);
        if (s.kind == Stmt::Kind::kParam) {
          auto it = overrides_.find(s.name);
          if (it != overrides_.end()) {
            const std::string origin = "--set " + s.name;
            ExprPtr expr = parse_expression(it->second, origin);
            Value o = eval(*expr, scope);
            if (o.type != v.type || (o.is_number() && !o.dim.dimensionless() &&
                                     !v.dim.dimensionless() && o.dim != v.dim))
              throw InputError(SourceLoc{origin, 1, 1},
                               "'" + s.name + "' is " + describe(v) + " in the script (line " +
                                   std::to_string(s.loc.line) + "), got " + describe(o));
            v = o;
            override_used_[s.name] = true;
          }
          out_.params[s.name] = format_value(v);
        }
        scope.vars[s.name] = std::move(v);
        break;
      }
      case Stmt::Kind::kUnits:
        for (const Arg& a : s.args) {
          static const std::map<std::string, std::pair<units::Unit units::UnitSystem::*, Dimension>>
              kKeys = {{"length", {&units::UnitSystem::length, Dimension::of_length()}},
                       {"mass", {&units::UnitSystem::mass, Dimension::of_mass()}},
                       {"time", {&units::UnitSystem::time, Dimension::of_time()}},
                       {"force", {&units::UnitSystem::force, Dimension::of_force()}},
                       {"pressure", {&units::UnitSystem::pressure, Dimension::of_pressure()}},
                       {"angle", {&units::UnitSystem::angle, Dimension::of_angle()}}};
          auto key = kKeys.find(a.name);
          if (key == kKeys.end())
            throw InputError(a.loc, "unknown quantity '" + a.name +
                                        "': expected length, mass, time, force, pressure or angle");
          const auto unit = units::find_unit(a.value->text);
          if (!unit) throw InputError(a.value->loc, "unknown unit '" + a.value->text + "'");
          if (unit->dimension != key->second.second)
            throw InputError(a.value->loc, "'" + a.value->text + "' is not a unit of " + a.name);
          units_.*(key->second.first) = *unit;
        }
        break;
      case Stmt::Kind::kFacets:
        facets_ = count(eval(*s.value, scope), s.value->loc, "facets", 3, limits_.max_segments);
        break;
      case Stmt::Kind::kMaterial:
        material_statement(s, scope);
        break;
      case Stmt::Kind::kModule: {
        if (scope.parent)
          throw InputError(s.loc, "a module must be defined at the top level of the script");
        if (contains(kPrimitives, s.name) || contains(kTransforms, s.name) ||
            contains(kBooleans, s.name) || contains(kFunctions, s.name) || s.name == "simulate" ||
            s.name == "render" || s.name == "export")
          throw InputError(s.loc, "'" + s.name + "' is built in; name the module differently");
        if (modules_.count(s.name))
          throw InputError(s.loc, "module '" + s.name + "' is already defined at line " +
                                      std::to_string(modules_[s.name]->loc.line));
        modules_[s.name] = &s;
        module_scope_ = &scope;
        break;
      }
      case Stmt::Kind::kBody:
        body_statement(s, scope);
        break;
      case Stmt::Kind::kScene:
        scene_statement(s, scope);
        break;
      case Stmt::Kind::kFor: {
        const Value over = eval(*s.value, scope);
        for (const Value& x : elements(over, s.value->loc)) {
          Scope inner;
          inner.parent = &scope;
          inner.vars[s.name] = x;
          top_statements(s.children, inner);
        }
        break;
      }
      case Stmt::Kind::kIf: {
        Scope inner;
        inner.parent = &scope;
        top_statements(truthy(eval(*s.value, scope)) ? s.children : s.else_children, inner);
        break;
      }
      case Stmt::Kind::kBlock: {
        Scope inner;
        inner.parent = &scope;
        top_statements(s.children, inner);
        break;
      }
      case Stmt::Kind::kCall:
        throw InputError(s.loc, "'" + s.name +
                                    "' must be inside a body: wrap it in "
                                    "'rigid body NAME (material=steel) { ... }'");
    }
  }
}

std::vector<Feature> Evaluator::solids(const std::vector<Stmt>& stmts, const Scope& parent,
                                       const Eigen::Affine3d& placement, int depth) {
  Scope local;
  local.parent = &parent;
  std::vector<Feature> out;
  for (const Stmt& s : stmts) solid_statement(s, local, placement, depth, out);
  return out;
}

void Evaluator::solid_statement(const Stmt& s, Scope& local, const Eigen::Affine3d& placement,
                                int depth, std::vector<Feature>& out) {
  auto append = [&](std::vector<Feature> more) {
    for (auto& f : more) out.push_back(std::move(f));
  };
  count_statement(s.loc);
  switch (s.kind) {
    case Stmt::Kind::kEmpty:
      return;
    case Stmt::Kind::kLet:
      if (local.vars.count(s.name))
        throw InputError(s.loc, "'" + s.name + "' is already defined in this block");
      local.vars[s.name] = eval(*s.value, local);
      return;
    case Stmt::Kind::kCall:
      append(call(s, local, placement, depth));
      return;
    case Stmt::Kind::kFor: {
      const Value over = eval(*s.value, local);
      for (const Value& x : elements(over, s.value->loc)) {
        Scope inner;
        inner.parent = &local;
        inner.vars[s.name] = x;
        append(solids(s.children, inner, placement, depth));
      }
      return;
    }
    case Stmt::Kind::kIf:
      append(solids(truthy(eval(*s.value, local)) ? s.children : s.else_children, local, placement,
                    depth));
      return;
    case Stmt::Kind::kBlock:
      append(solids(s.children, local, placement, depth));
      return;
    default: {
      static const char* kNames[] = {"let",    "param", "units", "facets", "material",
                                     "module", "body",  "call",  "for",    "if",
                                     "block",  "",      ""};
      const std::string what =
          s.kind == Stmt::Kind::kScene ? s.name : kNames[static_cast<int>(s.kind)];
      throw InputError(s.loc, "'" + what +
                                  "' is not allowed inside a body or module; put it at "
                                  "the top level of the script");
    }
  }
}

int Evaluator::segments_for(const BoundArgs& args, const SourceLoc& loc) {
  if (const Value* v = args.get("segments"))
    return count(*v, args.loc_of("segments", loc), "segments", 3, limits_.max_segments);
  if (body_segments_ > 0) return body_segments_;
  if (facets_ > 0) return facets_;
  return geometry::default_segments();
}

std::vector<Feature> Evaluator::call(const Stmt& s, const Scope& scope,
                                     const Eigen::Affine3d& placement, int depth) {
  if (contains(kPrimitives, s.name)) {
    if (!s.children.empty())
      throw InputError(s.children.front().loc,
                       s.name + "() takes no child statements: end it with ';'");
    return {primitive(s, scope, placement)};
  }
  if (contains(kTransforms, s.name)) {
    if (s.children.empty())
      throw InputError(s.loc, s.name + "() applies to the solid or block after it; none follows");
    Eigen::Affine3d m = Eigen::Affine3d::Identity();
    if (s.name == "translate") {
      const BoundArgs a = bind(s.name, s.args, scope, {"v"}, {}, s.loc);
      if (!a.get("v")) throw InputError(s.loc, "translate() needs a vector [x, y, z]");
      m.translate(vec3(*a.get("v"), Dimension::of_length(), a.loc_of("v", s.loc), "translate()"));
    } else if (s.name == "rotate") {
      const BoundArgs a = bind(s.name, s.args, scope, {"a", "axis"}, {"v"}, s.loc);
      const Value* angle = a.get("a");
      if (!angle)
        throw InputError(s.loc, "rotate() needs angles [ax, ay, az] or an angle and axis=");
      const SourceLoc aloc = a.loc_of("a", s.loc);
      const Value* axis = a.get("axis") ? a.get("axis") : a.get("v");
      if (angle->is_vector()) {
        if (axis) throw InputError(aloc, "rotate() with axis= takes one angle, not a vector");
        const Eigen::Vector3d r = vec3(*angle, Dimension::of_angle(), aloc, "rotate() angles");
        m.linear() = axis_rotation(r.z(), Eigen::Vector3d::UnitZ()) *
                     axis_rotation(r.y(), Eigen::Vector3d::UnitY()) *
                     axis_rotation(r.x(), Eigen::Vector3d::UnitX());
      } else {
        const double t = quantity(*angle, Dimension::of_angle(), aloc, "rotate() angle");
        Eigen::Vector3d ax = Eigen::Vector3d::UnitZ();
        if (axis) {
          const SourceLoc xloc = a.loc_of(a.get("axis") ? "axis" : "v", s.loc);
          if (!axis->is_vector() || axis->items->size() != 3)
            throw InputError(xloc, "rotate() axis must be a vector [x, y, z]");
          for (int i = 0; i < 3; ++i) {
            const Value& c = (*axis->items)[i];
            if (!c.is_number()) throw InputError(xloc, "rotate() axis must hold numbers");
            ax[i] = c.number;
          }
          if (!(ax.norm() > 0) || !ax.allFinite())
            throw InputError(xloc, "rotate() axis must not be zero");
        }
        m.linear() = axis_rotation(t, ax.normalized());
      }
    } else if (s.name == "scale") {
      const BoundArgs a = bind(s.name, s.args, scope, {"v"}, {}, s.loc);
      const Value* v = a.get("v");
      if (!v) throw InputError(s.loc, "scale() needs factors [sx, sy, sz]");
      const SourceLoc vloc = a.loc_of("v", s.loc);
      Eigen::Vector3d f;
      if (v->is_number()) {
        f.setConstant(quantity(*v, {}, vloc, "scale() factor"));
      } else {
        f = vec3(*v, {}, vloc, "scale() factors");
      }
      if ((f.array() == 0).any() || !f.allFinite())
        throw InputError(vloc, "scale() by zero flattens the solid; every factor must be non-zero");
      m.scale(f);
    } else {
      const BoundArgs a = bind(s.name, s.args, scope, {"v"}, {}, s.loc);
      const Value* v = a.get("v");
      if (!v || !v->is_vector() || v->items->size() != 3)
        throw InputError(s.loc, "mirror() needs the normal of the mirror plane [nx, ny, nz]");
      Eigen::Vector3d n;
      for (int i = 0; i < 3; ++i) {
        const Value& c = (*v->items)[i];
        if (!c.is_number())
          throw InputError(a.loc_of("v", s.loc), "mirror() normal must hold numbers");
        n[i] = c.number;
      }
      if (!(n.norm() > 0))
        throw InputError(a.loc_of("v", s.loc), "mirror() normal must not be zero");
      n.normalize();
      m.linear() = Eigen::Matrix3d::Identity() - 2 * n * n.transpose();
    }
    return solids(s.children, scope, placement * m, depth);
  }
  if (contains(kBooleans, s.name)) {
    if (!s.args.empty()) throw InputError(s.args.front().loc, s.name + "() takes no arguments");
    // one operand per child statement; a child that makes several solids is their union
    Scope local;
    local.parent = &scope;
    std::vector<Feature> operands;
    for (const Stmt& child : s.children) {
      std::vector<Feature> made;
      solid_statement(child, local, placement, depth, made);
      if (made.empty()) continue;
      if (made.size() == 1) {
        operands.push_back(std::move(made.front()));
      } else {
        Feature u;
        u.kind = Feature::Kind::kUnion;
        u.loc = child.loc;
        u.children = std::move(made);
        operands.push_back(std::move(u));
      }
    }
    if (operands.empty()) return {};
    Feature node;
    node.loc = s.loc;
    node.kind = s.name == "union"        ? Feature::Kind::kUnion
                : s.name == "difference" ? Feature::Kind::kDifference
                                         : Feature::Kind::kIntersection;
    if (operands.size() == 1) return operands;
    node.children = std::move(operands);
    return {std::move(node)};
  }
  auto module = modules_.find(s.name);
  if (module == modules_.end()) {
    if (contains(kFunctions, s.name))
      throw InputError(s.loc, "'" + s.name + "' is a function that gives a value, not a solid");
    throw InputError(
        s.loc, "unknown solid or module '" + s.name + "' (solids: " + join(kPrimitives) +
                   "; transforms: " + join(kTransforms) + "; Booleans: " + join(kBooleans) + ")");
  }
  if (!s.children.empty())
    throw InputError(s.children.front().loc, "module '" + s.name + "' takes no child statements");
  if (depth >= limits_.max_module_depth)
    throw InputError(s.loc, "modules call each other more than " +
                                std::to_string(limits_.max_module_depth) + " levels deep: does '" +
                                s.name + "' call itself without end?");
  const Stmt& def = *module->second;
  std::vector<std::string> params;
  for (const Arg& p : def.args) params.push_back(p.name);
  const BoundArgs bound = bind(s.name, s.args, scope, params, {}, s.loc);
  Scope mscope;
  mscope.parent = module_scope_;
  for (const Arg& p : def.args) {
    if (const Value* v = bound.get(p.name)) {
      mscope.vars[p.name] = *v;
    } else if (p.value) {
      mscope.vars[p.name] = eval(*p.value, mscope);
    } else {
      throw InputError(s.loc, "module '" + s.name + "' needs argument '" + p.name +
                                  "' (defined at line " + std::to_string(def.loc.line) + ")");
    }
  }
  return solids(def.children, mscope, placement, depth + 1);
}

}  // namespace detail

EvaluatedScript evaluate_program(const Program& program,
                                 const std::vector<ParamOverride>& overrides,
                                 const std::string& script_dir, const EvaluationLimits& limits) {
  return detail::Evaluator(program, overrides, script_dir, limits).run();
}

}  // namespace vproto::modeler
