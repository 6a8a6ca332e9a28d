#!/usr/bin/env bash
# Fuzzes the script language (lexer, parser, evaluator) for SECONDS (default 120) with
# libFuzzer, seeded with the samples and test scripts. Needs clang (Debian clang-14).
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds="${1:-120}"
work=build/fuzz
mkdir -p "$work/corpus"
cp samples/*.vp tests/data/*.vp "$work/corpus/" 2>/dev/null || true
flags="-std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined -I materials/include -I geometry/include -I sim/include -I modeler/include -I /usr/include/eigen3"
clang++ $flags tests/fuzz/script_fuzzer.cpp materials/src/*.cpp sim/src/scene.cpp \
  modeler/src/lexer.cpp modeler/src/parser.cpp modeler/src/value.cpp modeler/src/evaluator.cpp \
  modeler/src/primitive_features.cpp modeler/src/scene_statements.cpp geometry/src/tri_mesh.cpp \
  geometry/src/segments.cpp -o "$work/script_fuzzer"
"$work/script_fuzzer" -max_total_time="$seconds" -max_len=4096 -timeout=10 -rss_limit_mb=4096 "$work/corpus"
