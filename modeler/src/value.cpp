#include "vproto/modeler/value.h"

#include <cmath>

namespace vproto::modeler {
namespace {

using units::Dimension;

[[noreturn]] void fail(const SourceLoc& loc, const std::string& msg) { throw InputError(loc, msg); }

const Value& number_arg(const Value& v, const SourceLoc& loc, const std::string& fn) {
  if (!v.is_number()) fail(loc, fn + "() expects a number, got " + describe(v));
  return v;
}

// Gives a bare number the unit of the other operand's dimension.
void reconcile(Value& a, Value& b, const units::UnitSystem& sys) {
  if (a.dim.dimensionless() && !b.dim.dimensionless()) {
    a.number *= sys.scale_for(b.dim);
    a.dim = b.dim;
  } else if (b.dim.dimensionless() && !a.dim.dimensionless()) {
    b.number *= sys.scale_for(a.dim);
    b.dim = a.dim;
  }
}

Value checked(double x, Dimension d, const SourceLoc& loc, const char* what) {
  if (!std::isfinite(x)) fail(loc, std::string(what) + " gives a non-finite value");
  return Value::make_number(x, d);
}

bool equal(const Value& a, const Value& b) {
  if (a.type != b.type) return false;
  switch (a.type) {
    case Value::Type::kUndef:
      return true;
    case Value::Type::kNumber:
      return a.dim == b.dim && a.number == b.number;
    case Value::Type::kBool:
      return a.boolean == b.boolean;
    case Value::Type::kString:
      return a.text == b.text;
    case Value::Type::kVector: {
      if (a.items->size() != b.items->size()) return false;
      for (std::size_t i = 0; i < a.items->size(); ++i)
        if (!equal((*a.items)[i], (*b.items)[i])) return false;
      return true;
    }
    case Value::Type::kRange:
      return a.number == b.number && a.step == b.step && a.end == b.end && a.dim == b.dim;
  }
  return false;
}

// Element-wise application of a binary operation on vectors.
template <typename F>
Value elementwise(const Value& a, const Value& b, const SourceLoc& loc, const std::string& op,
                  F f) {
  if (a.items->size() != b.items->size())
    fail(loc, "'" + op + "' needs vectors of the same length, got " +
                  std::to_string(a.items->size()) + " and " + std::to_string(b.items->size()));
  std::vector<Value> out;
  out.reserve(a.items->size());
  for (std::size_t i = 0; i < a.items->size(); ++i) out.push_back(f((*a.items)[i], (*b.items)[i]));
  return Value::make_vector(std::move(out));
}

}  // namespace

std::pair<double, double> exact_sin_cos(double radians) {
  const double quarter = radians / (3.14159265358979323846 / 2);
  const double k = std::round(quarter);
  if (std::abs(quarter - k) < 1e-12) {
    static constexpr double kSin[4] = {0, 1, 0, -1};
    const int i = static_cast<int>(((static_cast<long long>(k) % 4) + 4) % 4);
    return {kSin[i], kSin[(i + 1) % 4]};
  }
  return {std::sin(radians), std::cos(radians)};
}

std::string describe(const Value& v) {
  switch (v.type) {
    case Value::Type::kUndef:
      return "an undefined value";
    case Value::Type::kNumber:
      return units::describe(v.dim);
    case Value::Type::kBool:
      return "a boolean";
    case Value::Type::kString:
      return "a string";
    case Value::Type::kVector:
      return "a vector of " + std::to_string(v.items->size()) + " values";
    case Value::Type::kRange:
      return "a range";
  }
  return "a value";
}

std::vector<Value> elements(const Value& v, const SourceLoc& loc) {
  if (v.type == Value::Type::kVector) return *v.items;
  if (v.type != Value::Type::kRange) fail(loc, "expected a vector or a range, got " + describe(v));
  if (v.step == 0) fail(loc, "a range's step must not be zero");
  const double count = std::floor((v.end - v.number) / v.step + 1e-9) + 1;
  if (!(count <= static_cast<double>(kMaxVectorSize)))
    fail(loc, "range has more than " + std::to_string(kMaxVectorSize) + " elements");
  std::vector<Value> out;
  for (long i = 0; i < static_cast<long>(count); ++i)
    out.push_back(Value::make_number(v.number + static_cast<double>(i) * v.step, v.dim));
  return out;
}

bool truthy(const Value& v) {
  switch (v.type) {
    case Value::Type::kUndef:
      return false;
    case Value::Type::kNumber:
      return v.number != 0;
    case Value::Type::kBool:
      return v.boolean;
    case Value::Type::kString:
      return !v.text.empty();
    case Value::Type::kVector:
      return !v.items->empty();
    case Value::Type::kRange:
      return true;
  }
  return false;
}

Value unary_op(const std::string& op, const Value& a, const SourceLoc& loc) {
  if (op == "!") return Value::make_bool(!truthy(a));
  if (a.is_number()) return Value::make_number(op == "-" ? -a.number : a.number, a.dim);
  if (a.is_vector()) {
    std::vector<Value> out;
    for (const auto& x : *a.items) out.push_back(unary_op(op, x, loc));
    return Value::make_vector(std::move(out));
  }
  fail(loc, "'" + op + "' needs a number or a vector, got " + describe(a));
}

Value binary_op(const std::string& op, const Value& a0, const Value& b0,
                const units::UnitSystem& sys, const SourceLoc& loc) {
  if (op == "&&") return Value::make_bool(truthy(a0) && truthy(b0));
  if (op == "||") return Value::make_bool(truthy(a0) || truthy(b0));
  if (op == "==" || op == "!=") {
    Value a = a0, b = b0;
    if (a.is_number() && b.is_number()) reconcile(a, b, sys);
    const bool eq = equal(a, b);
    return Value::make_bool(op == "==" ? eq : !eq);
  }
  auto rec = [&](const Value& x, const Value& y) { return binary_op(op, x, y, sys, loc); };

  if (a0.is_vector() && b0.is_vector()) {
    if (op == "+" || op == "-") return elementwise(a0, b0, loc, op, rec);
    if (op == "*") {
      // dot product
      if (a0.items->size() != b0.items->size())
        fail(loc, "'*' of two vectors (a dot product) needs equal lengths");
      if (a0.items->empty()) return Value::make_number(0);
      Value sum = rec((*a0.items)[0], (*b0.items)[0]);
      for (std::size_t i = 1; i < a0.items->size(); ++i)
        sum = binary_op("+", sum, rec((*a0.items)[i], (*b0.items)[i]), sys, loc);
      return sum;
    }
    fail(loc, "'" + op + "' is not defined for two vectors");
  }
  if (a0.is_vector() && b0.is_number() && (op == "*" || op == "/")) {
    std::vector<Value> out;
    for (const auto& x : *a0.items) out.push_back(rec(x, b0));
    return Value::make_vector(std::move(out));
  }
  if (a0.is_number() && b0.is_vector() && op == "*") {
    std::vector<Value> out;
    for (const auto& x : *b0.items) out.push_back(rec(a0, x));
    return Value::make_vector(std::move(out));
  }
  if (!a0.is_number() || !b0.is_number())
    fail(loc, "'" + op + "' needs numbers, got " + describe(a0) + " and " + describe(b0));

  Value a = a0, b = b0;
  if (op == "*") return checked(a.number * b.number, a.dim * b.dim, loc, "'*'");
  if (op == "/") {
    if (b.number == 0) fail(loc, "division by zero");
    return checked(a.number / b.number, a.dim / b.dim, loc, "'/'");
  }
  if (op == "^") {
    if (!b.dim.dimensionless()) fail(loc, "an exponent must be a plain number, got " + describe(b));
    return checked(std::pow(a.number, b.number), a.dim.pow(b.number), loc, "'^'");
  }
  reconcile(a, b, sys);
  if (a.dim != b.dim)
    fail(loc, "'" + op + "' of " + units::describe(a.dim) + " and " + units::describe(b.dim) +
                  ": the dimensions differ");
  if (op == "%") {
    if (b.number == 0) fail(loc, "remainder of a division by zero");
    return checked(std::fmod(a.number, b.number), a.dim, loc, "'%'");
  }
  if (op == "+") return checked(a.number + b.number, a.dim, loc, "'+'");
  if (op == "-") return checked(a.number - b.number, a.dim, loc, "'-'");
  if (op == "<") return Value::make_bool(a.number < b.number);
  if (op == "<=") return Value::make_bool(a.number <= b.number);
  if (op == ">") return Value::make_bool(a.number > b.number);
  if (op == ">=") return Value::make_bool(a.number >= b.number);
  fail(loc, "unknown operator '" + op + "'");
}

bool call_builtin(const std::string& name, const std::vector<Value>& args,
                  const units::UnitSystem& sys, const SourceLoc& loc, Value* result) {
  auto want = [&](std::size_t n) {
    if (args.size() != n)
      fail(loc, name + "() takes " + std::to_string(n) + " argument" + (n == 1 ? "" : "s") +
                    ", got " + std::to_string(args.size()));
  };
  // an angle in radians: bare numbers take the default angle unit
  auto angle = [&](const Value& v) {
    number_arg(v, loc, name);
    if (v.dim.dimensionless()) return v.number * sys.angle.scale;
    if (v.dim != Dimension::of_angle()) fail(loc, name + "() expects an angle, got " + describe(v));
    return v.number;
  };
  auto plain = [&](const Value& v) {
    number_arg(v, loc, name);
    if (!v.dim.dimensionless()) fail(loc, name + "() expects a plain number, got " + describe(v));
    return v.number;
  };
  auto out_angle = [&](double rad) {
    *result = checked(rad, Dimension::of_angle(), loc, name.c_str());
  };

  if (name == "sin" || name == "cos" || name == "tan") {
    want(1);
    const double a = angle(args[0]);
    const auto [sa, ca] = exact_sin_cos(a);
    if (name == "tan" && ca == 0) fail(loc, "tan() of an odd multiple of 90 degrees is infinite");
    const double r = name == "sin" ? sa : name == "cos" ? ca : sa / ca;
    *result = checked(r, {}, loc, name.c_str());
    return true;
  }
  if (name == "asin" || name == "acos" || name == "atan") {
    want(1);
    const double x = plain(args[0]);
    if (name != "atan" && (x < -1 || x > 1)) fail(loc, name + "() needs a value in [-1, 1]");
    out_angle(name == "asin" ? std::asin(x) : name == "acos" ? std::acos(x) : std::atan(x));
    return true;
  }
  if (name == "atan2") {
    want(2);
    number_arg(args[0], loc, name);
    number_arg(args[1], loc, name);
    Value y = args[0], x = args[1];
    reconcile(y, x, sys);
    if (y.dim != x.dim) fail(loc, "atan2() needs two values of the same dimension");
    out_angle(std::atan2(y.number, x.number));
    return true;
  }
  if (name == "sqrt") {
    want(1);
    number_arg(args[0], loc, name);
    if (args[0].number < 0) fail(loc, "sqrt() of a negative number");
    *result = Value::make_number(std::sqrt(args[0].number), args[0].dim.pow(0.5));
    return true;
  }
  if (name == "abs" || name == "floor" || name == "ceil" || name == "round") {
    want(1);
    const Value& v = number_arg(args[0], loc, name);
    if (name != "abs" && !v.dim.dimensionless())
      fail(loc, name + "() expects a plain number, got " + describe(v) +
                    " (divide by a unit first, e.g. floor(w / 1mm))");
    const double x = name == "abs"     ? std::abs(v.number)
                     : name == "floor" ? std::floor(v.number)
                     : name == "ceil"  ? std::ceil(v.number)
                                       : std::round(v.number);
    *result = Value::make_number(x, v.dim);
    return true;
  }
  if (name == "min" || name == "max") {
    std::vector<Value> vals = args;
    if (args.size() == 1 && args[0].is_vector()) vals = *args[0].items;
    if (vals.empty()) fail(loc, name + "() needs at least one value");
    Value best = number_arg(vals[0], loc, name);
    for (std::size_t i = 1; i < vals.size(); ++i) {
      Value v = number_arg(vals[i], loc, name);
      const bool less = truthy(binary_op("<", v, best, sys, loc));
      const bool more = truthy(binary_op(">", v, best, sys, loc));
      if (name == "min" ? less : more) best = v;
    }
    *result = best;
    return true;
  }
  if (name == "len") {
    want(1);
    if (args[0].type == Value::Type::kString)
      *result = Value::make_number(static_cast<double>(args[0].text.size()));
    else
      *result = Value::make_number(static_cast<double>(elements(args[0], loc).size()));
    return true;
  }
  if (name == "norm") {
    want(1);
    if (!args[0].is_vector()) fail(loc, "norm() expects a vector, got " + describe(args[0]));
    Value sum = Value::make_number(0);
    for (const auto& x : *args[0].items) {
      number_arg(x, loc, name);
      sum = binary_op("+", sum, binary_op("*", x, x, sys, loc), sys, loc);
    }
    *result = Value::make_number(std::sqrt(sum.number), sum.dim.pow(0.5));
    return true;
  }
  return false;
}

}  // namespace vproto::modeler
