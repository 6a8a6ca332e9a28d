#pragma once
// Values of the feature-script language: numbers with a dimension, booleans, strings,
// vectors and ranges; arithmetic with dimension checks; the built-in functions.

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "vproto/materials/errors.h"
#include "vproto/materials/units.h"

namespace vproto::modeler {

/// The most elements a vector or an expanded range may have.
inline constexpr std::size_t kMaxVectorSize = 1'000'000;

struct Value {
  enum class Type { kUndef, kNumber, kBool, kString, kVector, kRange };
  Type type = Type::kUndef;
  double number = 0;  ///< SI value (number); start (range)
  units::Dimension dim;
  bool boolean = false;
  std::string text;
  std::shared_ptr<const std::vector<Value>> items;  ///< vector elements
  double step = 1, end = 0;                         ///< range

  static Value make_number(double v, units::Dimension d = {}) {
    Value x;
    x.type = Type::kNumber;
    x.number = v;
    x.dim = d;
    return x;
  }
  static Value make_bool(bool b) {
    Value x;
    x.type = Type::kBool;
    x.boolean = b;
    return x;
  }
  static Value make_string(std::string s) {
    Value x;
    x.type = Type::kString;
    x.text = std::move(s);
    return x;
  }
  static Value make_vector(std::vector<Value> v) {
    Value x;
    x.type = Type::kVector;
    x.items = std::make_shared<const std::vector<Value>>(std::move(v));
    return x;
  }
  bool is_number() const { return type == Type::kNumber; }
  bool is_vector() const { return type == Type::kVector; }
};

/// "a length", "a vector of 3 values", "a string", ... for messages.
std::string describe(const Value& v);

/// The elements of a vector or the numbers of a range (bounded by kMaxVectorSize).
std::vector<Value> elements(const Value& v, const SourceLoc& loc);

/// Operator semantics; `sys` gives bare numbers a unit when the other operand of + - and
/// comparisons has a dimension (`x + 1` with x = 2in and length=mm is 2in + 1mm).
Value unary_op(const std::string& op, const Value& a, const SourceLoc& loc);
Value binary_op(const std::string& op, const Value& a, const Value& b, const units::UnitSystem& sys,
                const SourceLoc& loc);

/// Calls a built-in function (sin cos tan asin acos atan atan2 sqrt abs min max floor
/// ceil round len norm); returns false when `name` is not one.
bool call_builtin(const std::string& name, const std::vector<Value>& args,
                  const units::UnitSystem& sys, const SourceLoc& loc, Value* result);

/// sin and cos of an angle in radians, exact (0, 1, -1) at multiples of 90 degrees.
std::pair<double, double> exact_sin_cos(double radians);

/// Truthiness: false, 0, "", [] and undef are false.
bool truthy(const Value& v);

}  // namespace vproto::modeler
