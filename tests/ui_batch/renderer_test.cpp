// Tests on the pixels the renderer makes, not on its code paths.
#include "vproto/ui_batch/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/materials/material.h"
#include "vproto/ui_batch/colormap.h"
#include "vproto/ui_batch/plot.h"

namespace vproto::ui_batch {
namespace {

sim::Scene one_body(const geometry::TriMesh& mesh, sim::BodyKind kind = sim::BodyKind::kRigid) {
  sim::Scene scene;
  sim::Body b;
  b.name = "b";
  b.kind = kind;
  b.material = *materials::find_builtin("steel");
  b.surface = mesh;
  b.mass_properties = geometry::mass_properties(mesh);
  scene.bodies.push_back(b);
  return scene;
}

RenderOptions plain(int w, int h) {
  RenderOptions o;
  o.width = w;
  o.height = h;
  o.feature_edges = false;
  o.ground = false;
  o.caption = false;
  o.legend = false;
  return o;
}

// looking straight down at `centre`, `metres` of the scene across the image height
Camera top_view(const Eigen::Vector3d& centre, double metres) {
  Camera c;
  c.orthographic = true;
  c.ortho_height = metres;
  c.target = centre;
  c.eye = centre + Eigen::Vector3d(0, 0, 5);
  c.up = Eigen::Vector3d::UnitY();
  return c;
}

double colour_distance(const std::uint8_t* a, const std::uint8_t* b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) s += (double(a[k]) - b[k]) * (double(a[k]) - b[k]);
  return std::sqrt(s);
}

TEST(Renderer, UnitCubeCoversItsPredictedAreaOrthographically) {
  const sim::Scene scene = one_body(geometry::make_box({1, 1, 1}, true));
  Renderer r(scene, plain(400, 300));
  const Camera cam = top_view(Eigen::Vector3d::Zero(), 2.0);  // 150 px per metre
  sim::Frame frame = start_frame(scene);
  const Image with = r.render(frame, cam, -0.5);
  frame.bodies[0].position = Eigen::Vector3d(100, 100, 0);  // out of sight
  const Image without = r.render(frame, cam, -0.5);
  // fractional coverage from how far each pixel moved from the background towards the
  // face's colour (anti-aliased edges count in part)
  const std::uint8_t* face = with.at(200, 150);
  double area = 0;
  for (int y = 0; y < 300; ++y)
    for (int x = 0; x < 400; ++x) {
      const double full = colour_distance(face, without.at(x, y));
      if (full < 1) continue;
      area += std::min(1.0, colour_distance(with.at(x, y), without.at(x, y)) / full);
    }
  const double predicted = 150.0 * 150.0;
  EXPECT_NEAR(area, predicted, 0.01 * predicted);
}

TEST(Renderer, FieldExtremesAppearWhereTheFieldPeaks) {
  // a plate seen from above, with a field that peaks at (0.3, -0.2) and is least far away
  geometry::TriMesh plate = geometry::make_box({2, 2, 0.05}, true);
  // refine the top face with a grid of small boxes so the field has vertices to live on
  sim::Scene scene = one_body(geometry::make_sphere(1.0, 160));
  const Eigen::Vector3d peak(0.3, -0.2, 1.0);
  sim::Frame frame = start_frame(scene);
  frame.field = "von_mises";
  frame.field_unit = "Pa";
  const geometry::TriMesh& s = scene.bodies[0].surface;
  frame.bodies[0].field.resize(s.V.rows());
  for (Eigen::Index i = 0; i < s.V.rows(); ++i)
    frame.bodies[0].field[i] =
        5e6 * std::exp(-8 * (s.V.row(i).transpose() - peak.normalized()).squaredNorm());
  Renderer r(scene, plain(300, 300));
  const Image img = r.render(frame, top_view(Eigen::Vector3d::Zero(), 3.0), -1);
  // the most yellow pixel (viridis' top end) sits over the peak; the darkest purple far away
  const Rgb top = viridis(1.0);
  double best = 1e9;
  int bx = 0, by = 0;
  for (int y = 0; y < 300; ++y)
    for (int x = 0; x < 300; ++x) {
      const double dist = colour_distance(img.at(x, y), top.data());
      if (dist < best) best = dist, bx = x, by = y;
    }
  const Eigen::Vector3d p = peak.normalized();
  const double px = 150 + p.x() * 100, py = 150 - p.y() * 100;  // 100 px per metre
  EXPECT_LT(std::hypot(bx - px, by - py), 12) << bx << "," << by << " vs " << px << "," << py;
  EXPECT_LT(best, 80);
  // far from the peak the map's low end (dark, blue-purple) shows
  const std::uint8_t* far =
      img.at(static_cast<int>(150 - p.x() * 80), static_cast<int>(150 + p.y() * 80));
  EXPECT_LT(colour_distance(far, viridis(0.0).data()), colour_distance(far, top.data()));
  (void)plate;
}

// field=yield: a fixed scale, the yield's colour the same in every frame, red past it and
// viridis below. A sphere seen from above with a ratio growing along x passes the yield
// where x > 0.5; the same field at a tenth stays dark (the scale is not stretched to it).
TEST(Renderer, TheYieldMapIsRedPastTheYieldOnAFixedScale) {
  const sim::Scene scene = one_body(geometry::make_sphere(1.0, 160));
  const geometry::TriMesh& s = scene.bodies[0].surface;
  sim::Frame frame = start_frame(scene);
  frame.field = "yield";
  frame.bodies[0].field = (0.6 + 0.8 * s.V.col(0).array()).matrix();
  Renderer r(scene, plain(300, 300));
  const Camera cam = top_view(Eigen::Vector3d::Zero(), 3.0);  // 100 px per metre
  auto red = [](const std::uint8_t* p) { return p[0] > 100 && 2 * p[1] < p[0] && 2 * p[2] < p[0]; };
  const Image img = r.render(frame, cam, -1);
  for (double x = -0.9; x <= 0.91; x += 0.1) {
    const std::uint8_t* p = img.at(static_cast<int>(std::lround(150 + 100 * x)), 150);
    if (std::abs(x - 0.5) < 0.06) continue;  // the boundary's pixel
    EXPECT_EQ(red(p), x > 0.5) << "x = " << x << ": " << int(p[0]) << "," << int(p[1]) << ","
                               << int(p[2]);
  }
  frame.bodies[0].field *= 0.1;  // 0.14 of the yield at most
  const Image low = r.render(frame, cam, -1);
  const std::uint8_t* p = low.at(230, 150);  // x = 0.8: 0.124 of the yield
  EXPECT_FALSE(red(p));
  EXPECT_LT(colour_distance(p, viridis(0.0).data()), colour_distance(p, viridis(1.0).data()));
  EXPECT_EQ(yield_colour(0.999), viridis(0.999));
  EXPECT_EQ(yield_colour(1.0), yield_colour(7.0));
}

// A stress field whose vertices under a contact (here the cap x > 0.5 of a sphere) peak at
// 30 times the rest: the scale tops out at the body's own largest value, 1.5 at x = 0.5,
// so the rest keeps its colours; told nothing of the cap, the 99.5th percentile lands
// on the peak and the rest is one dark colour.
TEST(Renderer, TheScaleTopsOutAtTheLargestValueAwayFromConcentrations) {
  const sim::Scene scene = one_body(geometry::make_sphere(1.0, 160));
  const geometry::TriMesh& s = scene.bodies[0].surface;
  sim::Frame frame = start_frame(scene);
  frame.field = "von_mises";
  frame.field_unit = "Pa";
  sim::BodyFrame& b = frame.bodies[0];
  b.field.resize(s.V.rows());
  b.concentrated.resize(static_cast<std::size_t>(s.V.rows()));
  for (Eigen::Index v = 0; v < s.V.rows(); ++v) {
    const bool cap = s.V(v, 0) > 0.5;
    b.field[v] = cap ? 45.0 : 1 + s.V(v, 0);  // 0 to 1.5 off the cap
    b.concentrated[static_cast<std::size_t>(v)] = cap;
  }
  Renderer r(scene, plain(300, 300));
  const Camera cam = top_view(Eigen::Vector3d::Zero(), 3.0);  // 100 px per metre
  const Image img = r.render(frame, cam, -1);
  // the nearest of viridis' colours at 0, 0.1, ... 1
  auto level = [](const std::uint8_t* p) {
    int best = 0;
    for (int k = 1; k <= 10; ++k)
      if (colour_distance(p, viridis(k / 10.0).data()) <
          colour_distance(p, viridis(best / 10.0).data()))
        best = k;
    return best / 10.0;
  };
  EXPECT_NEAR(level(img.at(150, 150)), 1.0 / 1.5, 0.11);  // x = 0: 1 of 1.5
  EXPECT_NEAR(level(img.at(100, 150)), 0.5 / 1.5, 0.11);  // x = -0.5
  EXPECT_NEAR(level(img.at(190, 150)), 1.4 / 1.5, 0.11);  // x = 0.4
  EXPECT_GE(level(img.at(230, 150)), 0.9);  // on the cap: the top (shaded, turned away)
  b.concentrated.clear();
  Renderer plain_scale(scene, plain(300, 300));
  const Image dark = plain_scale.render(frame, cam, -1);
  EXPECT_LE(level(dark.at(190, 150)), 0.1);
}

TEST(Renderer, TheSameFrameGivesTheSameImage) {
  const sim::Scene scene = one_body(geometry::make_cylinder(1, 0.5, 0.3, 24, false));
  RenderOptions o;
  o.width = 320;
  o.height = 200;
  o.title = "determinism";
  const sim::Frame frame = start_frame(scene);
  const Camera cam = fit_camera("iso", frame_bounds(scene, frame), 1.6);
  Renderer a(scene, o), b(scene, o);
  const Image i1 = a.render(frame, cam, 0), i2 = a.render(frame, cam, 0),
              i3 = b.render(frame, cam, 0);
  EXPECT_EQ(i1.rgb, i2.rgb);
  EXPECT_EQ(i1.rgb, i3.rgb);
}

// A frame showing what the last one showed reuses its picture (a body at rest): only the
// caption is drawn anew; a body that moved, or a new view, is drawn afresh.
TEST(Renderer, ARepeatedSceneIsTheSamePictureAndAMovedOneIsDrawnAnew) {
  const sim::Scene scene = one_body(geometry::make_box({1, 0.6, 0.4}, false));
  RenderOptions o;
  o.width = 320;
  o.height = 200;
  sim::Frame rest = start_frame(scene);
  const Camera cam = fit_camera("iso", frame_bounds(scene, rest), 1.6);
  Renderer fresh(scene, o), reused(scene, o);
  sim::Frame later = rest, moved = rest;
  later.time = 0.25;
  moved.time = 0.25;
  moved.bodies[0].position += Eigen::Vector3d(0.05, 0, 0);
  const Image first = reused.render(rest, cam, 0);
  const Image again = reused.render(later, cam, 0);  // the picture kept, a new caption
  const Image shifted = reused.render(moved, cam, 0);
  EXPECT_EQ(again.rgb, fresh.render(later, cam, 0).rgb);
  EXPECT_EQ(shifted.rgb, fresh.render(moved, cam, 0).rgb);
  EXPECT_NE(first.rgb, again.rgb);  // the caption's time
  EXPECT_NE(again.rgb, shifted.rgb);
  // the same scene from elsewhere
  Camera other = cam;
  other.eye += Eigen::Vector3d(0.3, 0, 0);
  EXPECT_EQ(reused.render(moved, other, 0).rgb, fresh.render(moved, other, 0).rgb);
}

TEST(Renderer, CameraPresetsFrameTheWholeAssembly) {
  const sim::Scene scene = one_body(geometry::make_box({3, 1, 0.5}, false));
  const sim::Frame frame = start_frame(scene);
  RenderOptions o = plain(320, 180);
  Renderer r(scene, o);
  for (const char* preset : {"iso", "front", "side", "top"}) {
    const Image img =
        r.render(frame, fit_camera(preset, frame_bounds(scene, frame), 320.0 / 180), 0);
    // the border rows and columns show only background: nothing is cut off
    const Image bg = [&] {
      sim::Frame away = frame;
      away.bodies[0].position += Eigen::Vector3d(1000, 0, 0);
      return r.render(away, fit_camera(preset, frame_bounds(scene, frame), 320.0 / 180), 0);
    }();
    int body_pixels = 0, border_hits = 0;
    for (int y = 0; y < 180; ++y)
      for (int x = 0; x < 320; ++x) {
        const bool differs = colour_distance(img.at(x, y), bg.at(x, y)) > 10;
        body_pixels += differs;
        if (differs && (x == 0 || y == 0 || x == 319 || y == 179)) ++border_hits;
      }
    EXPECT_GT(body_pixels, 320 * 180 / 20) << preset;
    EXPECT_EQ(border_hits, 0) << preset;
  }
}

TEST(Renderer, RejectsImpossibleSizes) {
  const sim::Scene scene = one_body(geometry::make_box({1, 1, 1}, false));
  EXPECT_THROW(Renderer(scene, plain(0, 720)), InputError);
  EXPECT_THROW(Renderer(scene, plain(100000, 100000)), InputError);
}

}  // namespace
}  // namespace vproto::ui_batch

namespace vproto::ui_batch {
namespace {

TEST(Plot, TicksStepByOneTwoOrFiveTimesAPowerOfTen) {
  EXPECT_EQ(nice_ticks(0, 9.3, 6), (std::vector<double>{0, 2, 4, 6, 8}));
  EXPECT_EQ(nice_ticks(-4.9, 8.8, 8), (std::vector<double>{-4, -2, 0, 2, 4, 6, 8}));
  EXPECT_EQ(nice_ticks(-4.9, 8.8, 6), (std::vector<double>{0, 5}));  // 2.3 rounds up to 5
  const std::vector<double> small = nice_ticks(0.0012, 0.0049, 4);
  ASSERT_EQ(small.size(), 3u);
  EXPECT_NEAR(small[0], 0.002, 1e-15);
  EXPECT_NEAR(small[1] - small[0], 0.001, 1e-15);
  EXPECT_TRUE(nice_ticks(1, 1, 5).empty());  // no range, no ticks
  EXPECT_TRUE(nice_ticks(0, std::numeric_limits<double>::infinity(), 5).empty());
}

TEST(Plot, WritesAPngAndSkipsNonFinitePoints) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "vproto_plot_test.png").string();
  PlotSeries s;
  s.x = {0, 1, 2, std::nan(""), 4};
  s.y = {0, 1, 0, 5, -1};
  PlotOptions o;
  o.width = 320;
  o.height = 200;
  o.title = "test";
  write_line_plot({s}, o, path);
  std::ifstream f(path, std::ios::binary);
  char head[8] = {};
  f.read(head, 8);
  EXPECT_EQ(std::string(head + 1, 3), "PNG");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace vproto::ui_batch
