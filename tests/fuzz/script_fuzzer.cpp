// libFuzzer target: any bytes as a feature script must parse and evaluate to a result or
// an InputError, never a crash, hang or sanitizer report. Build and run with
// tests/fuzz/run.sh (clang, -fsanitize=fuzzer,address,undefined).
#include <cstddef>
#include <cstdint>
#include <string>

#include "vproto/materials/errors.h"
#include "vproto/modeler/evaluator.h"
#include "vproto/modeler/parser.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  vproto::modeler::EvaluationLimits limits;
  limits.max_statements = 200'000;  // keep each input fast
  try {
    const auto program = vproto::modeler::parse_program(text, "fuzz.vp");
    (void)vproto::modeler::evaluate_program(program, {}, "/nonexistent", limits);
  } catch (const vproto::InputError&) {
  }
  return 0;
}
