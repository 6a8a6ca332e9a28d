// Google Benchmark: CSG and language throughput (issue 2). Run: build/release/bench/csg_bench
#include <benchmark/benchmark.h>

#include <fstream>
#include <sstream>

#include "vproto/geometry/csg.h"
#include "vproto/geometry/primitives.h"
#include "vproto/modeler/evaluator.h"
#include "vproto/modeler/parser.h"

namespace {

using namespace vproto;

// the 49-hole plate (100 x 100 x 10 mm, r = 4 mm, 64 segments) as one difference
void BM_Plate49Csg(benchmark::State& state) {
  const int holes_per_side = static_cast<int>(state.range(0));
  geometry::CsgNode tree;
  tree.op = geometry::BooleanOp::kDifference;
  tree.children.push_back(
      geometry::CsgNode::make_leaf(geometry::make_box({0.1, 0.1, 0.01}, false)));
  const double pitch = 0.08 / std::max(1, holes_per_side - 1);
  for (int i = 0; i < holes_per_side; ++i)
    for (int j = 0; j < holes_per_side; ++j)
      tree.children.push_back(geometry::CsgNode::make_leaf(geometry::transformed(
          geometry::make_cylinder(0.012, 0.004, 0.004, 64, false),
          Eigen::Affine3d(Eigen::Translation3d(0.01 + pitch * i, 0.01 + pitch * j, -0.001)))));
  for (auto _ : state) {
    geometry::TriMesh out = geometry::evaluate_csg(tree);
    benchmark::DoNotOptimize(out.F.data());
  }
  state.counters["holes"] = holes_per_side * holes_per_side;
}
BENCHMARK(BM_Plate49Csg)->Arg(1)->Arg(3)->Arg(7)->Unit(benchmark::kMillisecond);

// parse and evaluate the snap-fit sample (no geometry)
void BM_EvaluateSnapfit(benchmark::State& state) {
  std::ifstream in(VPROTO_SAMPLES "/snapfit.vp");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  for (auto _ : state) {
    const modeler::Program p = modeler::parse_program(text, "snapfit.vp");
    benchmark::DoNotOptimize(modeler::evaluate_program(p, {}, VPROTO_SAMPLES).scene.bodies.size());
  }
}
BENCHMARK(BM_EvaluateSnapfit)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
