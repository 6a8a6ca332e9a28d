// Pieces of volume and surface meshes (a mesh that does not hold together is singular).

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#include "vproto/geometry/tet_mesh.h"

namespace vproto::geometry {
namespace {

// union-find with path halving
struct Pieces {
  explicit Pieces(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int root(int i) {
    while (parent[static_cast<std::size_t>(i)] != i)
      i = parent[static_cast<std::size_t>(i)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  }
  void join(int a, int b) { parent[static_cast<std::size_t>(root(a))] = root(b); }
  std::vector<int> parent;
};

}  // namespace

std::vector<TetPiece> tet_pieces(const Eigen::MatrixX3d& nodes, const Eigen::MatrixXi& elements) {
  const Eigen::Index count = elements.rows();
  // each element's four faces by their sorted corner nodes; a face two elements share joins
  // them (a shared edge or corner does not: the elements could turn about it freely)
  std::vector<std::pair<std::array<int, 3>, int>> faces;
  faces.reserve(static_cast<std::size_t>(4 * count));
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (Eigen::Index e = 0; e < count; ++e)
    for (const auto& f : kFaces) {
      std::array<int, 3> key{elements(e, f[0]), elements(e, f[1]), elements(e, f[2])};
      std::sort(key.begin(), key.end());
      faces.emplace_back(key, static_cast<int>(e));
    }
  std::sort(faces.begin(), faces.end());
  Pieces pieces(static_cast<std::size_t>(count));
  for (std::size_t k = 1; k < faces.size(); ++k)
    if (faces[k].first == faces[k - 1].first) pieces.join(faces[k].second, faces[k - 1].second);
  std::vector<int> slot(static_cast<std::size_t>(count), -1);
  std::vector<TetPiece> out;
  for (Eigen::Index e = 0; e < count; ++e) {
    int& s = slot[static_cast<std::size_t>(pieces.root(static_cast<int>(e)))];
    if (s < 0) {
      s = static_cast<int>(out.size());
      out.emplace_back();
    }
    TetPiece& p = out[static_cast<std::size_t>(s)];
    ++p.elements;
    for (int k = 0; k < 4; ++k) {
      p.box.lo = p.box.lo.cwiseMin(nodes.row(elements(e, k)).transpose());
      p.box.hi = p.box.hi.cwiseMax(nodes.row(elements(e, k)).transpose());
    }
  }
  std::sort(out.begin(), out.end(),
            [](const TetPiece& a, const TetPiece& b) { return a.elements > b.elements; });
  return out;
}

int surface_pieces(const TriMesh& surface) {
  Pieces pieces(static_cast<std::size_t>(surface.V.rows()));
  for (Eigen::Index t = 0; t < surface.F.rows(); ++t) {
    pieces.join(surface.F(t, 0), surface.F(t, 1));
    pieces.join(surface.F(t, 0), surface.F(t, 2));
  }
  std::vector<char> used(static_cast<std::size_t>(surface.V.rows()), 0), root(used.size(), 0);
  for (Eigen::Index t = 0; t < surface.F.rows(); ++t)
    for (int k = 0; k < 3; ++k) used[static_cast<std::size_t>(surface.F(t, k))] = 1;
  int count = 0;
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) continue;
    char& r = root[static_cast<std::size_t>(pieces.root(static_cast<int>(v)))];
    if (!r) {
      r = 1;
      ++count;
    }
  }
  return count;
}

}  // namespace vproto::geometry
