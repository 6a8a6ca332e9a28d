// Narrow-phase speed (issue 4): distance queries per second between convex parts of 8 to
// 500 vertices, by GJK and by the seed's quadratic program, over 256 random separated
// poses per size. Target: GJK under 1 us for 50-vertex parts.
#include <benchmark/benchmark.h>

#include <random>

#include "vproto/geometry/convex_distance.h"
#include "vproto/geometry/primitives.h"

namespace {

using namespace vproto::geometry;

// a convex part with about n vertices: a box (8) or a faceted sphere
ConvexPolytope part(int n) {
  if (n <= 8) return make_polytope(make_box({1, 1, 1}, true));
  int segments = 4;
  while (true) {
    const ConvexPolytope p = make_polytope(make_sphere(0.5, segments));
    if (static_cast<int>(p.vertices.size()) >= n) return p;
    ++segments;
  }
}

std::vector<std::pair<ConvexPolytope, ConvexPolytope>> pairs(int n) {
  const ConvexPolytope base = part(n);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<std::pair<ConvexPolytope, ConvexPolytope>> out;
  while (out.size() < 256) {
    Eigen::Isometry3d pa(Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized());
    Eigen::Isometry3d pb(Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized());
    pb.pretranslate(Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * (1.2 + 0.5 * u(rng)));
    ConvexPolytope a = transformed(base, pa), b = transformed(base, pb);
    if (!gjk_distance(a, b).overlap) out.emplace_back(std::move(a), std::move(b));
  }
  return out;
}

void BM_Gjk(benchmark::State& state) {
  const auto p = pairs(static_cast<int>(state.range(0)));
  std::size_t k = 0;
  for (auto _ : state) {
    const auto& [a, b] = p[k++ % p.size()];
    benchmark::DoNotOptimize(gjk_distance(a, b).distance);
  }
  state.counters["vertices"] = static_cast<double>(p[0].first.vertices.size());
  state.counters["queries_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Gjk)->Arg(8)->Arg(50)->Arg(150)->Arg(500);

void BM_SeedQp(benchmark::State& state) {
  const auto p = pairs(static_cast<int>(state.range(0)));
  std::size_t k = 0;
  for (auto _ : state) {
    const auto& [a, b] = p[k++ % p.size()];
    benchmark::DoNotOptimize(qp_distance(a, b).distance);
  }
  state.counters["vertices"] = static_cast<double>(p[0].first.vertices.size());
  state.counters["queries_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SeedQp)->Arg(8)->Arg(50)->Arg(150)->Arg(500);

}  // namespace

BENCHMARK_MAIN();
