// Google Benchmark: frames per second of the OSMesa renderer at 1280 x 720 for 10k, 100k
// and 1M triangles (issue 5), with and without PNG encoding.
#include <benchmark/benchmark.h>

#include <cmath>

#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/materials/material.h"
#include "vproto/ui_batch/image.h"
#include "vproto/ui_batch/renderer.h"

namespace {

using namespace vproto;

// one sphere of about `triangles` triangles
sim::Scene sphere_scene(long triangles) {
  const int n = static_cast<int>(std::sqrt(static_cast<double>(triangles)));
  sim::Scene scene;
  sim::Body body;
  body.name = "ball";
  body.material = *materials::find_builtin("steel");
  body.surface = geometry::make_sphere(0.1, n);
  body.mass_properties = geometry::mass_properties(body.surface);
  scene.bodies.push_back(body);
  return scene;
}

void BM_RenderFrame(benchmark::State& state) {
  const sim::Scene scene = sphere_scene(state.range(0));
  ui_batch::RenderOptions options;
  options.supersample = static_cast<int>(state.range(1));
  ui_batch::Renderer renderer(scene, options);
  const sim::Frame frame = ui_batch::start_frame(scene);
  const geometry::Bounds b = ui_batch::frame_bounds(scene, frame);
  const ui_batch::Camera cam = ui_batch::fit_camera("iso", b, 1280.0 / 720);
  for (auto _ : state) {
    ui_batch::Image img = renderer.render(frame, cam, b.lo.z());
    benchmark::DoNotOptimize(img.rgb.data());
  }
  state.counters["triangles"] = static_cast<double>(renderer.triangles());
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
// second argument: supersampling (2 = 2x2 anti-aliasing, the default; 1 = none)
BENCHMARK(BM_RenderFrame)
    ->Args({10'000, 2})
    ->Args({100'000, 2})
    ->Args({1'000'000, 2})
    ->Args({100'000, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_WritePng(benchmark::State& state) {
  ui_batch::Image img;
  img.width = 1280;
  img.height = 720;
  img.rgb.assign(1280 * 720 * 3, 200);
  for (int i = 0; i < 1280 * 720; i += 7) img.rgb[i * 3] = static_cast<std::uint8_t>(i);
  for (auto _ : state) ui_batch::write_png(img, "/tmp/vproto_bench.png");
}
BENCHMARK(BM_WritePng)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
