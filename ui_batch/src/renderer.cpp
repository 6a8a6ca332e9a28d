#include "vproto/ui_batch/renderer.h"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <type_traits>

#include "text_overlay.h"
#include "vproto/materials/errors.h"
#include "vproto/ui_batch/colormap.h"

namespace vproto::ui_batch {
namespace {

// The colour at t in [0, 1] of the frame's scale: viridis, or for the yield ratio
// (field=yield, a scale fixed at [0, kYieldMapTop]) viridis below the yield and red past it.
Rgb field_colour(bool yield_map, double t) {
  return yield_map ? yield_colour(t * kYieldMapTop) : viridis(t);
}

constexpr double kCreaseCos = 0.8660254037844387;  // 30 degrees: sharper edges stay sharp

// Indexed arrays ready for glDrawElements: one render vertex per (surface vertex, normal)
// pair, so smooth regions share vertices and creases split them; and feature lines.
struct RenderMesh {
  std::vector<float> positions;  ///< 3 per render vertex, starting pose
  std::vector<float> normals;    ///< 3 per render vertex
  std::vector<int> source;       ///< per render vertex: its surface vertex
  std::vector<GLuint> indices;   ///< 3 per triangle
  std::vector<int> edges;        ///< pairs of surface vertices on sharp or open edges
  Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor> vertices;  ///< starting pose
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  geometry::Bounds bounds;  ///< starting pose
  std::array<float, 3> colour{0.7f, 0.7f, 0.7f};
};

// Flat-ish, CAD-like colours for the built-in materials; others get a palette colour.
std::array<float, 3> material_colour(const std::string& name, std::size_t index) {
  struct Named {
    const char* name;
    std::array<float, 3> rgb;
  };
  static const Named kNamed[] = {
      {"steel", {0.60f, 0.63f, 0.68f}}, {"aluminum", {0.78f, 0.80f, 0.84f}},
      {"abs", {0.30f, 0.45f, 0.70f}},   {"polycarbonate", {0.55f, 0.75f, 0.85f}},
      {"nylon", {0.90f, 0.88f, 0.78f}}, {"hdpe", {0.93f, 0.93f, 0.90f}},
      {"pom", {0.25f, 0.25f, 0.27f}},   {"rubber", {0.18f, 0.18f, 0.18f}},
  };
  for (const auto& n : kNamed)
    if (name == n.name) return n.rgb;
  static const std::array<float, 3> kPalette[] = {{0.95f, 0.60f, 0.25f}, {0.40f, 0.70f, 0.45f},
                                                  {0.85f, 0.40f, 0.40f}, {0.60f, 0.50f, 0.80f},
                                                  {0.45f, 0.65f, 0.85f}, {0.85f, 0.75f, 0.35f}};
  return kPalette[index % 6];
}

RenderMesh prepare(const sim::Body& body, std::size_t index) {
  const geometry::TriMesh& m = body.drawn();
  RenderMesh r;
  r.centroid = body.mass_properties.centroid;
  r.vertices = m.V.cast<float>();
  r.bounds = geometry::bounds(m);
  r.colour = material_colour(body.material.name, index);
  const Eigen::Index nf = m.F.rows(), nv = m.V.rows();
  // face normals (area-weighted) and vertex-to-face adjacency
  Eigen::MatrixX3d fn(nf, 3);
  std::vector<std::vector<int>> faces_of(static_cast<std::size_t>(nv));
  for (Eigen::Index f = 0; f < nf; ++f) {
    const Eigen::Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    fn.row(f) = (b - a).cross(c - a).transpose();
    for (int k = 0; k < 3; ++k) faces_of[m.F(f, k)].push_back(static_cast<int>(f));
  }
  // per-corner normals smoothed within the crease angle; corners of one vertex with the
  // same normal share a render vertex
  std::map<std::pair<int, std::array<float, 3>>, GLuint> shared;
  r.indices.resize(static_cast<std::size_t>(nf) * 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const Eigen::Vector3d nf_unit = fn.row(f).normalized();
    for (int k = 0; k < 3; ++k) {
      const int v = m.F(f, k);
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      for (int g : faces_of[v])
        if (fn.row(g).normalized().dot(nf_unit) > kCreaseCos) n += fn.row(g).transpose();
      if (n.norm() == 0) n = nf_unit;
      n.normalize();
      const std::array<float, 3> nn{static_cast<float>(n.x()), static_cast<float>(n.y()),
                                    static_cast<float>(n.z())};
      auto [it, added] = shared.try_emplace({v, nn}, static_cast<GLuint>(r.source.size()));
      if (added) {
        r.source.push_back(v);
        for (int i = 0; i < 3; ++i) {
          r.positions.push_back(static_cast<float>(m.V(v, i)));
          r.normals.push_back(nn[i]);
        }
      }
      r.indices[static_cast<std::size_t>(f) * 3 + k] = it->second;
    }
  }
  // feature lines: edges between faces that meet at more than the crease angle
  std::vector<std::array<int, 3>> half;  // (lo, hi, face)
  half.reserve(static_cast<std::size_t>(nf) * 3);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = m.F(f, k), b = m.F(f, (k + 1) % 3);
      half.push_back({std::min(a, b), std::max(a, b), static_cast<int>(f)});
    }
  std::sort(half.begin(), half.end());
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i + 1;
    while (j < half.size() && half[j][0] == half[i][0] && half[j][1] == half[i][1]) ++j;
    bool sharp = j - i != 2;
    if (!sharp)
      sharp = fn.row(half[i][2]).normalized().dot(fn.row(half[i + 1][2]).normalized()) < kCreaseCos;
    if (sharp) {
      r.edges.push_back(half[i][0]);
      r.edges.push_back(half[i][1]);
    }
    i = j;
  }
  return r;
}

// A "nice" grid spacing: 1, 2 or 5 times a power of ten, about span / 12.
double nice_step(double span) {
  const double raw = span / 12;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

std::string format_value(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

Eigen::Matrix4d look_matrix(const Camera& c) {
  const Eigen::Vector3d f = (c.target - c.eye).normalized();
  Eigen::Vector3d up = c.up;
  if (std::abs(f.dot(up.normalized())) > 0.999) up = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d s = f.cross(up).normalized();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(c.eye);
  m(1, 3) = -u.dot(c.eye);
  m(2, 3) = f.dot(c.eye);
  return m;
}

}  // namespace

struct Renderer::Impl {
  RenderOptions options;
  int width = 0, height = 0;  ///< render buffer (supersampled)
  OSMesaContext context = nullptr;
  std::vector<GLubyte> buffer;
  std::vector<RenderMesh> meshes;
  geometry::Bounds start_bounds;
  TextPainter text{18};
  TextPainter small_text{14};
  std::vector<float> scratch_positions, scratch_colours, scratch_edges;
  GLuint colour_map_texture = 0;
  bool texture_is_yield_map = false;  ///< which map colour_map_texture holds
  /// The last frame's picture before its legend and caption, and what it showed: a frame
  /// that shows the same (a body at rest, seen from where it was) reuses it.
  struct Shown {
    std::vector<sim::BodyFrame> bodies;
    Camera camera;
    double ground_z = 0, field_min = 0, field_max = 0;
    Image picture;
  };
  std::optional<Shown> last;
  Image picture(const sim::Frame& frame, const Camera& camera, double ground_z, bool has_field,
                double fmin, double fmax);
};

namespace {

bool same_body(const sim::BodyFrame& a, const sim::BodyFrame& b) {
  auto same = [](const auto& x, const auto& y) {
    return x.rows() == y.rows() && x.cols() == y.cols() && (x.size() == 0 || x == y);
  };
  return a.position == b.position && a.rotation.coeffs() == b.rotation.coeffs() &&
         same(a.deformed, b.deformed) && same(a.deformation, b.deformation) &&
         same(a.field, b.field);
}

bool same_view(const Camera& a, const Camera& b) {
  return a.eye == b.eye && a.target == b.target && a.up == b.up &&
         a.orthographic == b.orthographic && a.fov_y == b.fov_y && a.ortho_height == b.ortho_height;
}

}  // namespace

Renderer::Renderer(const sim::Scene& scene, const RenderOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.options = options;
  if (options.width < 16 || options.height < 16 || options.width > 8192 || options.height > 8192)
    throw InputError("image size " + std::to_string(options.width) + "x" +
                     std::to_string(options.height) +
                     " is out of range: each side must be 16 to 8192 pixels");
  int ss = std::max(1, options.supersample);
  // keep the supersampled buffer below 1 GiB
  while (ss > 1 && static_cast<double>(options.width) * ss * options.height * ss * 4 > (1u << 30))
    --ss;
  d.options.supersample = ss;
  d.width = options.width * ss;
  d.height = options.height * ss;
  d.buffer.resize(static_cast<std::size_t>(d.width) * d.height * 4);
  d.context = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (!d.context) throw SimulationError("OSMesa could not create a rendering context");
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    d.meshes.push_back(prepare(scene.bodies[i], i));
    d.start_bounds.extend(geometry::bounds(scene.bodies[i].surface));
  }
}

Renderer::~Renderer() {
  // the display lists die with the context
  if (impl_->context) OSMesaDestroyContext(impl_->context);
}

long Renderer::triangles() const {
  long n = 0;
  for (const auto& m : impl_->meshes) n += static_cast<long>(m.indices.size() / 3);
  return n;
}

// The frame's picture before its legend and caption: the bodies (colour-mapped over
// [fmin, fmax] when the frame has a field), their feature lines, the ground and its shadow,
// supersampled and downsampled over the background.
Image Renderer::Impl::picture(const sim::Frame& frame, const Camera& camera, double ground_z,
                              bool has_field, double fmin, double fmax) {
  Impl& d = *this;
  if (!OSMesaMakeCurrent(d.context, d.buffer.data(), GL_UNSIGNED_BYTE, d.width, d.height))
    throw SimulationError("OSMesa could not bind its frame buffer");
  const int ss = d.options.supersample;
  const double aspect = static_cast<double>(d.width) / d.height;
  glViewport(0, 0, d.width, d.height);
  Image img;
  // everything is drawn over a transparent black buffer with premultiplied alpha; the
  // background gradient is composited under it while downsampling (no full-screen pass)
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_LIGHTING);
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);

  // camera
  const geometry::Bounds& sb = d.start_bounds;
  const double radius = 0.5 * (sb.hi - sb.lo).norm() + 1e-12;
  const double dist = (camera.eye - camera.target).norm();
  const double z_near = std::max(dist * 1e-3, dist - 4 * radius);
  const double z_far = dist + 6 * radius;
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  if (camera.orthographic) {
    const double h = camera.ortho_height / 2;
    glOrtho(-h * aspect, h * aspect, -h, h, z_near, z_far);
  } else {
    const double t = z_near * std::tan(camera.fov_y / 2);
    glFrustum(-t * aspect, t * aspect, -t, t, z_near, z_far);
  }
  glMatrixMode(GL_MODELVIEW);
  const Eigen::Matrix4d view = look_matrix(camera);
  glLoadMatrixd(view.data());

  // poses: start -> current, per body
  std::vector<Eigen::Matrix4d> poses(d.meshes.size(), Eigen::Matrix4d::Identity());
  for (std::size_t i = 0; i < d.meshes.size() && i < frame.bodies.size(); ++i) {
    const sim::BodyFrame& b = frame.bodies[i];
    Eigen::Affine3d t = Eigen::Translation3d(b.position) * b.rotation.normalized() *
                        Eigen::Translation3d(-d.meshes[i].centroid);
    poses[i] = t.matrix();
  }

  // a body's vertex positions: its starting pose (moved by the modelview), or the
  // deformed surface of an elastic body (already in world coordinates)
  auto deformed = [&](std::size_t i) {
    return i < frame.bodies.size() && frame.bodies[i].deformed.rows() > 0;
  };
  auto positions_of = [&](std::size_t i) -> const float* {
    const RenderMesh& m = d.meshes[i];
    if (!deformed(i)) return m.positions.data();
    d.scratch_positions.resize(m.positions.size());
    for (std::size_t c = 0; c < m.source.size(); ++c)
      for (int k = 0; k < 3; ++k)
        d.scratch_positions[c * 3 + k] =
            static_cast<float>(frame.bodies[i].deformed(m.source[c], k));
    return d.scratch_positions.data();
  };

  auto draw_body = [&](std::size_t i) {
    const RenderMesh& m = d.meshes[i];
    const sim::BodyFrame* b = i < frame.bodies.size() ? &frame.bodies[i] : nullptr;
    const float* pos = positions_of(i);
    glPushMatrix();
    if (!deformed(i)) glMultMatrixd(poses[i].data());
    glEnableClientState(GL_VERTEX_ARRAY);
    glVertexPointer(3, GL_FLOAT, 0, pos);
    glEnableClientState(GL_NORMAL_ARRAY);
    glNormalPointer(GL_FLOAT, 0, m.normals.data());
    const bool field_colours = has_field && b && b->field.size();
    if (field_colours) {
      // the field is interpolated across each triangle and mapped per pixel through a
      // 1-D texture of the colour map (interpolating colours would mix through brown)
      const bool yield_map = frame.field == "yield";
      if (d.colour_map_texture != 0 && d.texture_is_yield_map != yield_map) {
        glDeleteTextures(1, &d.colour_map_texture);
        d.colour_map_texture = 0;
      }
      if (d.colour_map_texture == 0) {
        std::vector<GLubyte> texels(256 * 3);
        for (int t = 0; t < 256; ++t) {
          const Rgb c = field_colour(yield_map, t / 255.0);
          for (int k = 0; k < 3; ++k) texels[t * 3 + k] = c[k];
        }
        d.texture_is_yield_map = yield_map;
        glGenTextures(1, &d.colour_map_texture);
        glBindTexture(GL_TEXTURE_1D, d.colour_map_texture);
        glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexImage1D(GL_TEXTURE_1D, 0, GL_RGB8, 256, 0, GL_RGB, GL_UNSIGNED_BYTE, texels.data());
      }
      d.scratch_colours.resize(m.source.size());
      for (std::size_t c = 0; c < m.source.size(); ++c) {
        double t = (b->field[m.source[c]] - fmin) / (fmax - fmin);
        t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
        d.scratch_colours[c] = static_cast<float>((0.5 + 255 * t) / 256);  // texel centres
      }
      glBindTexture(GL_TEXTURE_1D, d.colour_map_texture);
      glEnable(GL_TEXTURE_1D);
      glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE);
      glEnableClientState(GL_TEXTURE_COORD_ARRAY);
      glTexCoordPointer(1, GL_FLOAT, 0, d.scratch_colours.data());
      glColor3f(1, 1, 1);
    } else {
      glColor3fv(m.colour.data());
    }
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(m.indices.size()), GL_UNSIGNED_INT,
                   m.indices.data());
    glDisableClientState(GL_TEXTURE_COORD_ARRAY);
    glDisable(GL_TEXTURE_1D);
    glDisableClientState(GL_NORMAL_ARRAY);
    glDisableClientState(GL_VERTEX_ARRAY);
    glPopMatrix();
  };

  // ground: grid lines and a soft shadow cast straight down
  if (d.options.ground) {
    const double span = std::max(sb.hi.x() - sb.lo.x(), sb.hi.y() - sb.lo.y()) * 1.8 + 1e-9;
    const double step = nice_step(span);
    const Eigen::Vector2d c(0.5 * (sb.lo.x() + sb.hi.x()), 0.5 * (sb.lo.y() + sb.hi.y()));
    const double x0 = std::floor((c.x() - span / 2) / step) * step, x1 = c.x() + span / 2;
    const double y0 = std::floor((c.y() - span / 2) / step) * step, y1 = c.y() + span / 2;
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    // the bodies' shadow, cast straight down onto the ground: their geometry flattened,
    // each pixel darkened once (stencil)
    glDepthMask(GL_FALSE);
    // a closed body's upward and downward faces flatten onto the same area: one set will do
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glEnable(GL_STENCIL_TEST);
    glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
    glStencilFunc(GL_EQUAL, 0, 0xff);
    glColor4f(0.1f, 0.12f, 0.16f, 0.2f);
    {
      Eigen::Matrix4d flatten = Eigen::Matrix4d::Identity();
      flatten(2, 2) = 0;
      flatten(2, 3) = ground_z;
      for (std::size_t i = 0; i < d.meshes.size(); ++i) {
        const RenderMesh& m = d.meshes[i];
        glPushMatrix();
        glMultMatrixd(flatten.data());
        if (!deformed(i)) glMultMatrixd(poses[i].data());
        glEnableClientState(GL_VERTEX_ARRAY);
        glVertexPointer(3, GL_FLOAT, 0, positions_of(i));
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(m.indices.size()), GL_UNSIGNED_INT,
                       m.indices.data());
        glDisableClientState(GL_VERTEX_ARRAY);
        glPopMatrix();
      }
    }
    glDisable(GL_STENCIL_TEST);
    glDisable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
    glLineWidth(static_cast<float>(ss));
    glColor4f(0.45f, 0.5f, 0.58f, 0.35f);
    glBegin(GL_LINES);
    for (double x = x0; x <= x1 + 1e-9 * step; x += step) {
      glVertex3d(x, y0, ground_z);
      glVertex3d(x, y1, ground_z);
    }
    for (double y = y0; y <= y1 + 1e-9 * step; y += step) {
      glVertex3d(x0, y, ground_z);
      glVertex3d(x1, y, ground_z);
    }
    glEnd();
    glDisable(GL_BLEND);
  }

  // bodies: two lights fixed to the camera, colour from material or field
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glEnable(GL_LIGHTING);
  glEnable(GL_NORMALIZE);
  glEnable(GL_COLOR_MATERIAL);
  glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  glShadeModel(GL_SMOOTH);
  {
    glPushMatrix();
    glLoadIdentity();
    const GLfloat key_dir[] = {-0.4f, 0.6f, 1.0f, 0.0f}, key[] = {0.75f, 0.75f, 0.75f, 1};
    const GLfloat fill_dir[] = {0.6f, -0.3f, 0.5f, 0.0f}, fill[] = {0.25f, 0.25f, 0.28f, 1};
    const GLfloat ambient[] = {0.22f, 0.22f, 0.24f, 1}, spec[] = {0.25f, 0.25f, 0.25f, 1};
    glLightfv(GL_LIGHT0, GL_POSITION, key_dir);
    glLightfv(GL_LIGHT0, GL_DIFFUSE, key);
    glLightfv(GL_LIGHT0, GL_SPECULAR, spec);
    glLightfv(GL_LIGHT1, GL_POSITION, fill_dir);
    glLightfv(GL_LIGHT1, GL_DIFFUSE, fill);
    glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
    glEnable(GL_LIGHT0);
    glEnable(GL_LIGHT1);
    glPopMatrix();
    const GLfloat mspec[] = {0.3f, 0.3f, 0.3f, 1};
    glMaterialfv(GL_FRONT_AND_BACK, GL_SPECULAR, mspec);
    glMaterialf(GL_FRONT_AND_BACK, GL_SHININESS, 40);
  }
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  // bodies are closed and outward-oriented: their back faces are never seen
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  for (std::size_t i = 0; i < d.meshes.size(); ++i) draw_body(i);
  glDisable(GL_CULL_FACE);
  glDisable(GL_POLYGON_OFFSET_FILL);
  glDisable(GL_LIGHTING);

  // feature lines
  if (d.options.feature_edges) {
    glLineWidth(static_cast<float>(ss));
    glColor3f(0.12f, 0.13f, 0.15f);
    glEnableClientState(GL_VERTEX_ARRAY);
    for (std::size_t i = 0; i < d.meshes.size(); ++i) {
      const RenderMesh& m = d.meshes[i];
      const bool moved = deformed(i);
      d.scratch_edges.resize(m.edges.size() * 3);
      for (std::size_t e = 0; e < m.edges.size(); ++e)
        for (int k = 0; k < 3; ++k)
          d.scratch_edges[e * 3 + k] =
              moved ? static_cast<float>(frame.bodies[i].deformed(m.edges[e], k))
                    : m.vertices(m.edges[e], k);
      glPushMatrix();
      if (!moved) glMultMatrixd(poses[i].data());
      glVertexPointer(3, GL_FLOAT, 0, d.scratch_edges.data());
      glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(m.edges.size()));
      glPopMatrix();
    }
    glDisableClientState(GL_VERTEX_ARRAY);
  }
  glFinish();

  // 2x2 (or n x n) box filter down to the output size, flipped to top-down rows
  img.width = d.options.width;
  img.height = d.options.height;
  img.rgb.resize(static_cast<std::size_t>(img.width) * img.height * 3);
  const int area = ss * ss;
  std::vector<int> sums(static_cast<std::size_t>(img.width) * 4);
  for (int y = 0; y < img.height; ++y) {
    // average the ss x ss premultiplied samples of each pixel, then lay them over the
    // background gradient (light grey-blue at the top to near white at the bottom)
    if (ss == 2) {
      // the usual 2x2, in one pass over both rows (the compiler vectorizes it; the general
      // loop below took 7 ms a frame, a fifth of a moving frame's time)
      const GLubyte* r0 =
          &d.buffer[static_cast<std::size_t>((img.height - 1 - y) * 2) * d.width * 4];
      const GLubyte* r1 = r0 + static_cast<std::size_t>(d.width) * 4;
      int* acc = sums.data();
      for (int x = 0; x < img.width; ++x)
        for (int k = 0; k < 4; ++k)
          acc[x * 4 + k] = r0[x * 8 + k] + r0[x * 8 + 4 + k] + r1[x * 8 + k] + r1[x * 8 + 4 + k];
    } else {
      std::fill(sums.begin(), sums.end(), 0);
      for (int j = 0; j < ss; ++j) {
        const GLubyte* row =
            &d.buffer[static_cast<std::size_t>((img.height - 1 - y) * ss + j) * d.width * 4];
        for (int x = 0; x < img.width; ++x) {
          int* acc = &sums[static_cast<std::size_t>(x) * 4];
          for (int i = 0; i < ss; ++i) {
            const GLubyte* p = row + static_cast<std::size_t>(x * ss + i) * 4;
            acc[0] += p[0];
            acc[1] += p[1];
            acc[2] += p[2];
            acc[3] += p[3];
          }
        }
      }
    }
    const double t = static_cast<double>(y) / std::max(1, img.height - 1);  // 0 top, 1 bottom
    const int bg[3] = {static_cast<int>(std::lround(255 * (0.80 + 0.17 * t))),
                       static_cast<int>(std::lround(255 * (0.84 + 0.13 * t))),
                       static_cast<int>(std::lround(255 * (0.90 + 0.08 * t)))};
    std::uint8_t* out_row = img.at(0, y);
    // the division by 255 * area with the divisor known to the compiler for the usual
    // supersampling (a multiply and a shift instead of a division: a third of a frame's time)
    auto blend = [&](auto divisor) {
      for (int x = 0; x < img.width; ++x) {
        const int* acc = &sums[static_cast<std::size_t>(x) * 4];
        const unsigned uncovered =
            255u * static_cast<unsigned>(area) - static_cast<unsigned>(acc[3]);
        for (int k = 0; k < 3; ++k) {
          const unsigned v = (static_cast<unsigned>(acc[k]) * 255u +
                              static_cast<unsigned>(bg[k]) * uncovered + divisor / 2) /
                             divisor;
          out_row[x * 3 + k] = static_cast<std::uint8_t>(std::min(255u, v));
        }
      }
    };
    switch (area) {
      case 1:
        blend(std::integral_constant<unsigned, 255u>());
        break;
      case 4:
        blend(std::integral_constant<unsigned, 4u * 255u>());
        break;
      case 9:
        blend(std::integral_constant<unsigned, 9u * 255u>());
        break;
      case 16:
        blend(std::integral_constant<unsigned, 16u * 255u>());
        break;
      default:
        blend(255u * static_cast<unsigned>(area));
        break;
    }
  }

  return img;
}

Image Renderer::render(const sim::Frame& frame_in, const Camera& camera, double ground_z) {
  Impl& d = *impl_;
  // the deformation magnified for the picture only
  sim::Frame magnified;
  const bool magnify = d.options.deform_scale != 1;
  if (magnify) {
    magnified = frame_in;
    for (sim::BodyFrame& b : magnified.bodies)
      if (b.deformed.rows() > 0 && b.deformation.rows() == b.deformed.rows())
        b.deformed += (d.options.deform_scale - 1) * b.deformation;
  }
  const sim::Frame& frame = magnify ? magnified : frame_in;

  // field range over the frame, unless fixed by the options
  const bool has_field = frame.field != "none" && !frame.field.empty();
  double fmin = d.options.field_min, fmax = d.options.field_max;
  bool clipped = false;
  const bool yield_map = frame.field == "yield";
  if (yield_map) {  // a fixed scale: the yield is always the same colour
    fmin = 0;
    fmax = kYieldMapTop;
  } else if (has_field && fmin < fmax) {  // a fixed range: does the frame pass its top?
    for (const auto& b : frame.bodies)
      clipped = clipped || (b.field.size() && b.field.maxCoeff() > fmax);
  } else if (has_field && !(fmin < fmax)) {
    fmin = std::numeric_limits<double>::infinity();
    fmax = -fmin;
    std::vector<double> all;
    // the largest value away from local concentrations (under contacts, at sharp inside
    // corners), where the frame says which vertices those are
    double own_top = -std::numeric_limits<double>::infinity();
    bool concentrations_known = false;
    for (const auto& b : frame.bodies)
      if (b.field.size()) {
        fmin = std::min(fmin, b.field.minCoeff());
        fmax = std::max(fmax, b.field.maxCoeff());
        all.insert(all.end(), b.field.data(), b.field.data() + b.field.size());
        const bool masked = b.concentrated.size() == static_cast<std::size_t>(b.field.size());
        concentrations_known = concentrations_known || masked;
        for (Eigen::Index v = 0; v < b.field.size(); ++v)
          if (!masked || !b.concentrated[static_cast<std::size_t>(v)])
            own_top = std::max(own_top, b.field[v]);
      }
    if (!(fmin <= fmax)) fmin = fmax = 0;
    if (concentrations_known && own_top > fmin) {
      // the scale tops out at the bodies' own largest value: a contact's or a sharp
      // corner's peak (the snap-fit's hooks under the base part's edges) past it shows as
      // the top colour and the legend says ">="
      if (own_top < fmax) {
        fmax = own_top;
        clipped = true;
      }
    } else if (all.size() >= 200) {
      // else at the 99.5th percentile of the vertices' values: a stress peak at one sharp
      // contact corner would otherwise leave everything else one colour
      const auto at = all.begin() + static_cast<std::ptrdiff_t>(0.995 * (all.size() - 1));
      std::nth_element(all.begin(), at, all.end());
      if (*at > fmin && *at < fmax) {
        fmax = *at;
        clipped = true;
      }
    }
  }
  // a constant field maps to the low colour and is labelled with its one value
  const bool constant_field = has_field && !(fmax - fmin > 1e-300);
  const double label_max = fmax;
  if (constant_field) fmax = fmin + 1;

  // the same scene as the last frame's (every body where it was, the same field and view):
  // its picture again, only the caption changes (the snap-fit's socket at rest: 82 of its
  // 120 frames)
  const bool again =
      d.last && same_view(d.last->camera, camera) && d.last->ground_z == ground_z &&
      d.last->field_min == fmin && d.last->field_max == fmax &&
      d.last->bodies.size() == frame.bodies.size() &&
      std::equal(frame.bodies.begin(), frame.bodies.end(), d.last->bodies.begin(), same_body);
  Image img;
  if (again) {
    img = d.last->picture;
  } else {
    img = d.picture(frame, camera, ground_z, has_field, fmin, fmax);
    d.last = Impl::Shown{frame.bodies, camera, ground_z, fmin, fmax, img};
  }

  // legend and caption, drawn at output resolution so the text is crisp
  const Rgb ink{30, 34, 40};
  if (has_field && d.options.legend) {
    const int bar_w = std::max(8, img.width / 64), bar_h = img.height * 2 / 5;
    // the bar sits far enough from the right edge for its labels to fit
    const std::string top_label =
        (clipped ? ">= " : "") + format_value(constant_field ? fmin : label_max);
    const std::string bottom_label = format_value(fmin);
    const int label_w = std::max(d.small_text.width(top_label), d.small_text.width(bottom_label));
    const int x0 = img.width - bar_w - std::max(label_w + 14, img.width / 12), y0 = img.height / 6;
    for (int y = 0; y < bar_h; ++y) {
      const Rgb c = field_colour(yield_map, 1.0 - static_cast<double>(y) / (bar_h - 1));
      for (int x = 0; x < bar_w; ++x) {
        std::uint8_t* p = img.at(x0 + x, y0 + y);
        p[0] = c[0], p[1] = c[1], p[2] = c[2];
      }
    }
    const std::string name = frame.field == "von_mises"
                                 ? "von Mises stress [" + frame.field_unit + "]"
                             : frame.field == "strain" ? std::string("largest principal strain")
                             : yield_map               ? std::string("fraction of the yield")
                                         : frame.field + " [" + frame.field_unit + "]";
    const int w = d.text.width(name);
    d.text.draw(img, std::max(4, std::min(x0 + bar_w / 2 - w / 2, img.width - w - 8)), y0 - 12,
                name, ink);
    if (yield_map) {
      // 0 at the bottom, 1 where the red starts, and what the red means
      const int at_yield = y0 + static_cast<int>(std::lround((1 - 1 / kYieldMapTop) * (bar_h - 1)));
      d.small_text.draw(img, x0 + bar_w + 6, y0 + 10, "past it", ink);
      d.small_text.draw(img, x0 + bar_w + 6, at_yield + 5, "1", ink);
    } else {
      d.small_text.draw(img, x0 + bar_w + 6, y0 + 10, top_label, ink);
    }
    d.small_text.draw(img, x0 + bar_w + 6, y0 + bar_h, bottom_label, ink);
  }
  if (d.options.caption) {
    char t[48];
    std::snprintf(t, sizeof t, "t = %.4f s", frame.time);
    d.text.draw(img, 16, img.height - 16, t, ink);
    if (!d.options.title.empty()) d.text.draw(img, 16, 30, d.options.title, ink);
  }
  return img;
}

Camera fit_camera(const std::string& preset, const geometry::Bounds& b, double aspect) {
  Camera c;
  const Eigen::Vector3d centre = 0.5 * (b.lo + b.hi);
  const double radius = std::max(0.5 * (b.hi - b.lo).norm(), 1e-9);
  Eigen::Vector3d dir(1.0, -1.3, 0.9);  // iso: from the front-right, above
  if (preset == "front") dir = Eigen::Vector3d(0, -1, 0);
  if (preset == "side") dir = Eigen::Vector3d(1, 0, 0);
  if (preset == "top") {
    dir = Eigen::Vector3d(0, 0, 1);
    c.up = Eigen::Vector3d::UnitY();
  }
  dir.normalize();
  // the nearest eye distance at which every corner of the bounds lies inside the view
  // (with a 6 % margin): corner i at right r, up u, towards the eye f needs
  // d >= f + |r| / tan(fov_x / 2) and d >= f + |u| / tan(fov_y / 2)
  const double tan_y = std::tan(c.fov_y / 2) / 1.06, tan_x = aspect * tan_y;
  Eigen::Vector3d up = c.up;
  if (std::abs(dir.dot(up)) > 0.999) up = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d right = (-dir).cross(up).normalized();
  const Eigen::Vector3d true_up = right.cross(-dir);
  double dist = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p((corner & 1) ? b.hi.x() : b.lo.x(), (corner & 2) ? b.hi.y() : b.lo.y(),
                            (corner & 4) ? b.hi.z() : b.lo.z());
    const Eigen::Vector3d q = p - centre;
    const double f = q.dot(dir);
    dist =
        std::max({dist, f + std::abs(q.dot(right)) / tan_x, f + std::abs(q.dot(true_up)) / tan_y});
  }
  dist = std::max(dist, 1e-3 * radius);
  c.target = centre;
  c.eye = centre + dist * dir;
  return c;
}

Camera look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  Camera c;
  c.eye = eye;
  c.target = target;
  return c;
}

sim::Frame start_frame(const sim::Scene& scene) {
  sim::Frame f;
  f.field = "none";
  for (const auto& b : scene.bodies) {
    sim::BodyFrame bf;
    bf.position = b.mass_properties.centroid;
    f.bodies.push_back(bf);
  }
  return f;
}

geometry::Bounds frame_bounds(const sim::Scene& scene, const sim::Frame& frame) {
  geometry::Bounds out;
  for (std::size_t i = 0; i < scene.bodies.size() && i < frame.bodies.size(); ++i) {
    const sim::BodyFrame& b = frame.bodies[i];
    if (b.deformed.rows() > 0) {
      geometry::TriMesh m;
      m.V = b.deformed;
      out.extend(geometry::bounds(m));
      continue;
    }
    const Eigen::Affine3d t = Eigen::Translation3d(b.position) * b.rotation.normalized() *
                              Eigen::Translation3d(-scene.bodies[i].mass_properties.centroid);
    out.extend(geometry::bounds(geometry::transformed(scene.bodies[i].surface, t)));
  }
  return out;
}

}  // namespace vproto::ui_batch
