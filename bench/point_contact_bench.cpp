// The frictional contact solver (sim/point_contact_solver) on the snap-fit's hardest case
// in miniature: a flat elastic face landing on a rigid plate, n x n contact points. This
// measures the solver alone, as run time against its residual, without the run around it.
//
// The Delassus matrix: the face is an incompressible elastic half-space (nu = 0.5: normal
// and tangential compliances decouple). Boussinesq gives the normal compliance (1 - nu^2) /
// (pi E r) between points r apart, and Cerruti the tangential (1 + nu) / (2 pi E r)
// (2 (1 - nu) + 2 nu x^2 / r^2) along x, and the matching cross term. A point's own
// compliance is the kernel's mean over its cell (4 ln(1 + sqrt 2) / s for 1/r). The body's
// frame adds dt^2 / m to every pair: it couples all points, as the snap-fit socket's
// frame does.
//
// The free motion: the face comes down by v dt, tilted so that part of it stays open. It
// spreads radially (as Poisson's ratio spreads a pressed face), so that the outer half of
// the pressed points slide and the inner half stick.
//
// It is easier than the landing itself: Newton converges here in 3-6 iterations from a
// cold start, and takes 15-50 there. The snap-fit's socket is a finite block whose face
// rotates with its frame, and its Delassus matrix carries the frame's inertial
// deformation, which is not symmetric. So this tracks the solver's cost per size, not the
// landing's iteration count.
//
// LDPE (E = 0.25 GPa), a 3.2 mm grid, v = 1.5 m/s, dt = 0.3 ms, m = 7.5 kg, mu = 0.3, and
// the engine's tolerance of 1e-9 of the mesh size. Counters: points, pressed and sliding
// at the solution; Newton iterations and sweeps; residual over tolerance; deepest
// penetration left (m).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "vproto/geometry/primitives.h"
#include "vproto/sim/contact_problem_io.h"
#include "vproto/sim/dynamics.h"
#include "vproto/sim/point_contact_solver.h"
#include "vproto/sim/scene.h"

namespace {

using vproto::sim::PointContactOptions;
using vproto::sim::PointContactProblem;
using vproto::sim::PointContactSolution;

constexpr double kE = 0.25e9, kNu = 0.5, kSpacing = 0.003175, kMesh = 0.00635;
constexpr double kSpeed = 1.5, kDt = 3e-4, kMass = 7.5, kMu = 0.3;

PointContactProblem landing(int n) {
  const int m = n * n;
  PointContactProblem p;
  p.w = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  p.free.resize(3 * m);
  p.mu.assign(static_cast<std::size_t>(m), kMu);
  const double normal = (1 - kNu * kNu) / (M_PI * kE);
  const double tangential = (1 + kNu) / (2 * M_PI * kE);
  const double self = 4 * std::log(1 + std::sqrt(2.0)) / kSpacing;  // mean of 1/r over a cell
  const double half = 0.5 * (n - 1) * kSpacing;
  auto at = [&](int i) {
    return Eigen::Vector2d((i % n) * kSpacing - half, (i / n) * kSpacing - half);
  };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      Eigen::Matrix3d b = Eigen::Matrix3d::Zero();
      if (i == j) {
        b(0, 0) = normal * self;
        // the mean of 2 (1 - nu) + 2 nu x^2 / r^2 over directions: 2 - nu
        b(1, 1) = b(2, 2) = tangential * (2 - kNu) * self;
      } else {
        const Eigen::Vector2d d = at(i) - at(j);
        const double r = d.norm();
        b(0, 0) = normal / r;
        b(1, 1) = tangential / r * (2 * (1 - kNu) + 2 * kNu * d.x() * d.x() / (r * r));
        b(2, 2) = tangential / r * (2 * (1 - kNu) + 2 * kNu * d.y() * d.y() / (r * r));
        b(1, 2) = b(2, 1) = tangential / r * 2 * kNu * d.x() * d.y() / (r * r);
      }
      b += (kDt * kDt / kMass) * Eigen::Matrix3d::Identity();  // the frame's mobility
      p.w.block<3, 3>(3 * i, 3 * j) = b;
    }
  const double approach = kSpeed * kDt;
  const double tilt = 1.5 * approach / (2 * half + kSpacing);  // about a third stays open
  const double spread = 0.2 * approach / half;
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector2d x = at(i);
    p.free[3 * i] = tilt * (x.x() + half) - approach;
    p.free[3 * i + 1] = spread * x.x();
    p.free[3 * i + 2] = spread * x.y();
  }
  return p;
}

void BM_FrictionalLanding(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const PointContactProblem p = landing(n);
  PointContactOptions options;
  options.tolerance = 1e-9 * kMesh;
  PointContactSolution s;
  for (auto _ : state) {
    s = vproto::sim::solve_point_contacts(p, Eigen::VectorXd(), options);
    benchmark::DoNotOptimize(s.lambda.data());
  }
  const Eigen::VectorXd d = p.free + p.w * s.lambda;
  const Eigen::Index m = p.free.size() / 3;
  double pressed = 0, sliding = 0, deepest = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    deepest = std::max(deepest, -d[3 * i]);
    if (s.lambda[3 * i] <= 0) continue;
    ++pressed;
    if (s.lambda.segment<2>(3 * i + 1).norm() >= (1 - 1e-9) * kMu * s.lambda[3 * i]) ++sliding;
  }
  state.counters["points"] = static_cast<double>(m);
  state.counters["pressed"] = pressed;
  state.counters["sliding"] = sliding;
  state.counters["newton_iterations"] = s.newton_iterations;
  state.counters["sweeps"] = s.sweeps;
  state.counters["converged"] = s.converged ? 1 : 0;
  state.counters["residual_over_tolerance"] = s.residual / options.tolerance;
  state.counters["deepest_m"] = deepest;
}
BENCHMARK(BM_FrictionalLanding)->Arg(8)->Arg(14)->Arg(20)->Arg(26)->Unit(benchmark::kMillisecond);

// The same solver on a rigid island: one step of five 0.1 m steel boxes resting on each
// other on a held floor (mu 0.5, dt 1 ms), the stack of `vproto bench`'s contact report,
// settled for 1 s first. Its cost per step is the engine's whole step (detection, the
// island's solve, integration), dominated by fixed costs: the allocations and calls around
// a solve of 16-20 points.
void BM_RestingStackStep(benchmark::State& state) {
  using namespace vproto;
  sim::Scene scene;
  auto box = [](const Eigen::Vector3d& size, const Eigen::Vector3d& centre) {
    Eigen::Affine3d pose = Eigen::Affine3d::Identity();
    pose.translation() = centre;
    return geometry::transformed(geometry::make_box(size, true), pose);
  };
  scene.bodies.push_back(sim::make_rigid_body("floor", box({2, 2, 0.2}, {0, 0, -0.1}), 7850));
  sim::Fix hold;
  hold.body = 0;
  scene.fixes.push_back(hold);
  for (int k = 0; k < 5; ++k)
    scene.bodies.push_back(
        sim::make_rigid_body("box", box({0.1, 0.1, 0.1}, {0.003 * k, 0, 0.101 * k + 0.051}), 7850));
  scene.gravity = Eigen::Vector3d(0, 0, -9.81);
  sim::ContactSetting contact;
  contact.friction = 0.5;
  scene.contacts.push_back(contact);
  sim::Dynamics dyn(scene, 1e-3);
  dyn.advance_to(1.0);
  double t = 1.0;
  const auto before = dyn.contact()->stats();
  for (auto _ : state) {
    t += 1e-3;
    dyn.advance_to(t);
  }
  const auto& after = dyn.contact()->stats();
  const double steps = static_cast<double>(state.iterations());
  state.counters["solves_per_step"] = static_cast<double>(after.solves - before.solves) / steps;
  state.counters["sweeps_per_solve"] =
      static_cast<double>(after.sweeps - before.sweeps) /
      static_cast<double>(std::max(1L, after.solves - before.solves));
  state.counters["unconverged"] = static_cast<double>(after.unconverged - before.unconverged);
  state.counters["steps_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RestingStackStep)->Unit(benchmark::kMicrosecond);

// `--problem FILE...`: problems a run wrote (VPROTO_DUMP_CONTACT, contact_problem_io.h),
// each solved alone from its warm start with the run's options, once as a warm-up and then
// timed; a line per problem and their total.
int solve_dumped(const std::vector<std::string>& files) {
  double total = 0;
  long iterations = 0;
  int unconverged = 0;
  for (const std::string& file : files) {
    PointContactProblem problem;
    Eigen::VectorXd warm;
    PointContactOptions options;
    try {
      vproto::sim::read_contact_problem(file, &problem, &warm, &options);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "point_contact_bench: %s\n", e.what());
      return 2;
    }
    vproto::sim::solve_point_contacts(problem, warm, options);  // (pages and caches warm)
    const auto started = std::chrono::steady_clock::now();
    const PointContactSolution s = vproto::sim::solve_point_contacts(problem, warm, options);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    Eigen::Index pressed = 0;
    for (Eigen::Index i = 0; i < s.lambda.size() / 3; ++i) pressed += s.lambda[3 * i] > 0;
    std::printf(
        "%s: %ld points, %ld pressed, %d sweeps, %d Newton iterations, residual %.3g "
        "(tolerance %.3g)%s, %.3f s\n",
        file.c_str(), static_cast<long>(problem.free.size() / 3), static_cast<long>(pressed),
        s.sweeps, s.newton_iterations, s.residual, options.tolerance,
        s.converged ? "" : " UNCONVERGED", seconds);
    total += seconds;
    iterations += s.newton_iterations;
    unconverged += s.converged ? 0 : 1;
  }
  std::printf("%zu problems: %.3f s, %ld Newton iterations, %d unconverged\n", files.size(), total,
              iterations, unconverged);
  return unconverged ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "--problem") {
    if (argc < 3) {
      std::fprintf(stderr, "usage: point_contact_bench --problem FILE...\n");
      return 2;
    }
    return solve_dumped(std::vector<std::string>(argv + 2, argv + argc));
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
