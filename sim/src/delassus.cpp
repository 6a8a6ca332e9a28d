#include "delassus.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>

#include "two_threads.h"

namespace vproto::sim {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix36 = Eigen::Matrix<double, 3, 6>;

// An elastic body's compliance between two points of its surface: the motion at a's point
// under a unit force at b's (from b's nodes' columns, or a's where b's were solved before
// a's node had columns), in the body's axes.
Eigen::Matrix3d compliance(const NodeSide& a, const NodeSide& b) {
  const Dynamics::ElasticBody& eb = *a.body;
  Eigen::Matrix3d g = Eigen::Matrix3d::Zero();
  for (std::size_t p = 0; p < 3; ++p) {
    if (a.nodes[p] < 0) continue;
    for (std::size_t q = 0; q < 3; ++q)
      if (b.columns[q])
        g.noalias() += (a.weights[p] * b.weights[q]) *
                       eb.compliance(*b.columns[q], b.nodes[q], a.nodes[p], a.columns[p]);
  }
  return g;
}

// The frames the rows act on, and their mobilities pairwise (looked up once, before the
// threads share them).
struct FrameTable {
  std::map<int, int> index;                       // body -> its place
  std::vector<std::optional<Matrix6d>> mobility;  // (place of q) * count + place of r
  int count = 0;
  const std::optional<Matrix6d>& at(int kq, int kr) const {
    return mobility[static_cast<std::size_t>(kq * count + kr)];
  }
};

// What the blocks of W read besides the rows: the frames' mobilities pairwise (looked up
// once, before threads share them), and per row and frame side its frame's place and its
// Jacobian times its own mobility.
struct Parts {
  FrameTable frames;
  std::vector<std::array<int, 2>> place;
  std::vector<std::array<Matrix36, 2>> jac_mob;

  Parts(const std::vector<RowSides>& rows, const FrameMobility& mobility)
      : place(rows.size(), {-1, -1}), jac_mob(rows.size()) {
    for (const RowSides& row : rows)
      for (int x = 0; x < row.frame_count; ++x)
        frames.index.try_emplace(row.frames[static_cast<std::size_t>(x)].id, 0);
    for (auto& [id, k] : frames.index) k = frames.count++;
    frames.mobility.resize(static_cast<std::size_t>(frames.count * frames.count));
    for (const auto& [q, kq] : frames.index)
      for (const auto& [r, kr] : frames.index)
        frames.mobility[static_cast<std::size_t>(kq * frames.count + kr)] = mobility(q, r);
    for (std::size_t r = 0; r < rows.size(); ++r)
      for (std::size_t x = 0; x < static_cast<std::size_t>(rows[r].frame_count); ++x) {
        const FrameSide& f = rows[r].frames[x];
        const int k = frames.index.at(f.id);
        place[r][x] = k;
        if (const auto& own = frames.at(k, k))
          jac_mob[r][x] = f.jac * *own;
        else
          jac_mob[r][x].setZero();
      }
  }

  // W's block (r, s) but for the floating bodies' terms of low rank (r <= s, as the dense
  // assembly forms them)
  Eigen::Matrix3d block(const std::vector<RowSides>& rows, std::size_t ri, std::size_t si) const {
    const RowSides &a = rows[ri], &b = rows[si];
    Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
    for (int x = 0; x < a.node_count; ++x)
      for (int y = 0; y < b.node_count; ++y) {
        const NodeSide &na = a.nodes[static_cast<std::size_t>(x)],
                       &nb = b.nodes[static_cast<std::size_t>(y)];
        if (na.body != nb.body) continue;
        const Eigen::Matrix3d g = compliance(na, nb);
        if (na.sign * nb.sign > 0)
          block.noalias() += na.basis.transpose() * g * nb.basis;
        else
          block.noalias() -= na.basis.transpose() * g * nb.basis;
      }
    for (int x = 0; x < a.frame_count; ++x)
      for (int y = 0; y < b.frame_count; ++y) {
        const auto xi = static_cast<std::size_t>(x), yi = static_cast<std::size_t>(y);
        const FrameSide &fa = a.frames[xi], &fb = b.frames[yi];
        const double sign = fa.sign * fb.sign;
        if (fa.id == fb.id) {
          if (sign > 0)
            block.noalias() += jac_mob[ri][xi] * fb.jac.transpose();
          else
            block.noalias() -= jac_mob[ri][xi] * fb.jac.transpose();
        } else if (const auto& c = frames.at(place[ri][xi], place[si][yi])) {
          if (sign > 0)
            block.noalias() += fa.jac * *c * fb.jac.transpose();
          else
            block.noalias() -= fa.jac * *c * fb.jac.transpose();
        }
      }
    return block;
  }
};

// The floating bodies' terms of W, of low rank: W -= left right (false: none).
bool low_rank(const std::vector<RowSides>& rows, const std::vector<FloatingSide>& floating,
              const Parts& table, double dt, Eigen::MatrixXd* left, Eigen::MatrixXd* right) {
  const auto m = static_cast<Eigen::Index>(rows.size());
  // Terms of low rank, W -= sum_k lefts_k rights_k, taken in one product: per floating
  // elastic body, the deformation its frame's acceleration under the rows' forces causes.
  // A row r's point on it moves by -sign_r basis_r' (sum_a w_a Psi_a) R6' a, Psi the
  // deformation per unit frame acceleration (ElasticBody::inertia_response), a = sum_s
  // (sum over s's frame sides y) sign_y M(body, y) J_y' lambda_s / dt^2 the frame's
  // acceleration: a term of rank six, not symmetric (the frame carries the inertia, the
  // deformation none). In mean axes, less the rigid part of the deformation: the rows move by
  // -Phi_r c, c = (Phi' M Phi)^-1 (S' C' lambda - Phi' M K^^-1 M Phi a)
  // (ElasticBody::rigid_part_of).
  std::vector<Eigen::MatrixXd> lefts, rights;
  for (const FloatingSide& fl : floating) {
    const Dynamics::ElasticBody& eb = *fl.body;
    Eigen::MatrixXd psi = Eigen::MatrixXd::Zero(3 * m, 6), jm = Eigen::MatrixXd::Zero(6, 3 * m);
    Eigen::MatrixXd modes, part;
    if (eb.mean_axes) modes.setZero(3 * m, 6), part.setZero(6, 3 * m);
    bool any = false;
    const auto k = table.frames.index.find(fl.id);
    for (Eigen::Index r = 0; r < m; ++r) {
      const RowSides& row = rows[static_cast<std::size_t>(r)];
      for (int x = 0; x < row.node_count; ++x) {
        const NodeSide& ns = row.nodes[static_cast<std::size_t>(x)];
        if (ns.body != fl.body) continue;
        any = true;
        Matrix36 at, rigid;
        eb.point_frame_rows(ns.nodes, ns.weights, *fl.mesh, fl.centroid, &at, &rigid);
        psi.middleRows<3>(3 * r) += ns.sign * (ns.basis.transpose() * at * fl.rt6);
        if (eb.mean_axes) {
          modes.middleRows<3>(3 * r) += ns.sign * (ns.basis.transpose() * rigid);
          part.middleCols<3>(3 * r) += ns.sign * (at.transpose() * ns.basis);
        }
      }
      if (k == table.frames.index.end()) continue;
      for (int y = 0; y < row.frame_count; ++y) {
        const auto yi = static_cast<std::size_t>(y);
        const FrameSide& f = row.frames[yi];
        const int y_place = table.place[static_cast<std::size_t>(r)][yi];
        if (y_place == k->second && fl.jump_mobility)
          jm.middleCols<3>(3 * r) += f.sign * ((*fl.jump_mobility * f.jac.transpose()) / (dt * dt));
        else if (const auto& c = table.frames.at(k->second, y_place))
          jm.middleCols<3>(3 * r) += f.sign * ((*c * f.jac.transpose()) / (dt * dt));
      }
    }
    if (!any) continue;
    if (eb.mean_axes) part.noalias() -= eb.inertia_coupling * (fl.rt6 * jm);
    lefts.push_back(std::move(psi));
    rights.push_back(std::move(jm));
    if (eb.mean_axes) {
      lefts.push_back(modes * eb.rigid_mass_inverse);
      rights.push_back(std::move(part));
    }
  }
  if (lefts.empty()) return false;
  Eigen::Index rank = 0;
  for (const Eigen::MatrixXd& l : lefts) rank += l.cols();
  left->resize(3 * m, rank);
  right->resize(rank, 3 * m);
  for (std::size_t k = 0, at = 0; k < lefts.size();
       at += static_cast<std::size_t>(lefts[k].cols()), ++k) {
    left->middleCols(static_cast<Eigen::Index>(at), lefts[k].cols()) = lefts[k];
    right->middleRows(static_cast<Eigen::Index>(at), rights[k].rows()) = rights[k];
  }
  return true;
}

}  // namespace

void assemble_delassus(const std::vector<RowSides>& rows, const FrameMobility& mobility,
                       const std::vector<FloatingSide>& floating, double dt, Eigen::MatrixXd* w) {
  const auto m = static_cast<Eigen::Index>(rows.size());
  w->resize(3 * m, 3 * m);  // (every block written below)
  const Parts table(rows, mobility);

  // The blocks (r <= s, s), column by column: a column's blocks read the compliance columns
  // of its own nodes, not another node's for each block (the snap-fit landing's assembly 8 %
  // faster); on two threads, the first columns (to 1/sqrt(2) of them: half the blocks) on
  // one, the rest on the other (each block is written by one, and is the same whichever).
  // Their mirror images follow tile by tile (written here, each block's transpose went across
  // three columns of a matrix of up to 100 MB: the landing's assembly 1.6-1.8 s -> 1.05 s).
  auto blocks = [&](int part, int parts) {
    const auto split = static_cast<Eigen::Index>(std::sqrt(0.5) * static_cast<double>(m));
    const Eigen::Index from = parts == 1 || part == 0 ? 0 : split,
                       to = parts == 1 || part == 1 ? m : split;
    for (Eigen::Index s = from; s < to; ++s) {
      const auto si = static_cast<std::size_t>(s);
      const RowSides& b = rows[si];
      for (Eigen::Index r = 0; r <= s; ++r) {
        const auto ri = static_cast<std::size_t>(r);
        if (r + 8 <= s && b.node_count > 0) {
          // the blocks a few rows ahead fetched while this one is summed
          const RowSides& ahead = rows[ri + 8];
          if (ahead.node_count > 0 && ahead.nodes[0].body == b.nodes[0].body)
            for (int p = 0; p < 3; ++p)
              if (ahead.nodes[0].nodes[p] >= 0)
                for (int q = 0; q < 3; ++q)
                  if (b.nodes[0].columns[q]) {
                    // (from the ahead node's own columns where b's lack its block)
                    const NodeSide &nb = b.nodes[0], &na = ahead.nodes[0];
                    const double* data = nb.body->block_data(*nb.columns[q], na.nodes[p]);
                    if (!data && na.columns[p])
                      data = nb.body->block_data(*na.columns[p], nb.nodes[q]);
                    if (data) __builtin_prefetch(data);
                  }
        }
        const Eigen::Matrix3d block = table.block(rows, ri, si);
        w->block<3, 3>(3 * r, 3 * s) = block;
      }
    }
  };
  in_two_threads(m > 64, blocks);
  in_two_threads(m > 64, [&](int part, int parts) {
    // the blocks below the diagonal, the transposes of those above, in tiles of 48 rows and
    // columns (both tiles in the first-level cache)
    const Eigen::Index n = 3 * m;
    constexpr Eigen::Index kTile = 48;
    const Eigen::Index tiles = (n + kTile - 1) / kTile;
    double* const data = w->data();
    for (Eigen::Index tj = part; tj < tiles; tj += parts) {
      const Eigen::Index j0 = tj * kTile, j1 = std::min(n, j0 + kTile);
      for (Eigen::Index ti = tj; ti < tiles; ++ti) {
        const Eigen::Index i0 = ti * kTile, i1 = std::min(n, i0 + kTile);
        for (Eigen::Index j = j0; j < j1; ++j)
          for (Eigen::Index i = std::max(i0, 3 * (j / 3) + 3); i < i1; ++i)
            data[j * n + i] = data[i * n + j];
      }
    }
  });

  Eigen::MatrixXd left, right;
  if (!low_rank(rows, floating, table, dt, &left, &right)) return;
  // (one product of 3m x k by k x 3m: its columns in two halves on two threads)
  in_two_threads(m > 64, [&](int p, int parts) {
    const Eigen::Index half = (3 * m / 2 / 3) * 3, c0 = parts == 1 || p == 0 ? 0 : half,
                       c1 = parts == 1 || p == 1 ? 3 * m : half;
    w->middleCols(c0, c1 - c0).noalias() -= left * right.middleCols(c0, c1 - c0);
  });
}

struct LazyDelassus::Impl {
  const std::vector<RowSides>& rows;
  Parts table;
  Eigen::MatrixXd left, right;  // the terms of low rank (none: empty)
  std::vector<Eigen::Matrix3d> diagonal;
  std::vector<std::unique_ptr<double[]>> columns;
  std::function<void(double)> demand;
  Eigen::Index formed = 0;
  double seconds = 0;

  Impl(const std::vector<RowSides>& r, const FrameMobility& mobility,
       const std::vector<FloatingSide>& floating, double dt, std::function<void(double)> d)
      : rows(r), table(r, mobility), demand(std::move(d)) {
    const auto m = static_cast<Eigen::Index>(rows.size());
    if (!low_rank(rows, floating, table, dt, &left, &right)) left.resize(0, 0);
    diagonal.resize(rows.size());
    columns.resize(rows.size());
    for (Eigen::Index i = 0; i < m; ++i) {
      Eigen::Matrix3d& d = diagonal[static_cast<std::size_t>(i)];
      d = table.block(rows, static_cast<std::size_t>(i), static_cast<std::size_t>(i));
      if (left.size() > 0) d.noalias() -= left.middleRows<3>(3 * i) * right.middleCols<3>(3 * i);
    }
  }

  // Point j's columns: the blocks (r, j) as the dense assembly forms them (r <= j) or
  // mirrors them (r > j), less the terms of low rank.
  void form(Eigen::Index j, double* out) const {
    const auto m = static_cast<Eigen::Index>(rows.size());
    Eigen::Map<Eigen::MatrixXd> column(out, 3 * m, 3);
    const auto jj = static_cast<std::size_t>(j);
    for (Eigen::Index r = 0; r < m; ++r) {
      const auto rr = static_cast<std::size_t>(r);
      column.middleRows<3>(3 * r) =
          r <= j ? table.block(rows, rr, jj) : table.block(rows, jj, rr).transpose();
    }
    if (left.size() > 0) column.noalias() -= left * right.middleCols<3>(3 * j);
  }
};

LazyDelassus::LazyDelassus(const std::vector<RowSides>& rows, const FrameMobility& mobility,
                           const std::vector<FloatingSide>& floating, double dt,
                           std::function<void(double)> demand)
    : impl_(std::make_unique<Impl>(rows, mobility, floating, dt, std::move(demand))) {}

LazyDelassus::~LazyDelassus() = default;

Eigen::Index LazyDelassus::points() const { return static_cast<Eigen::Index>(impl_->rows.size()); }

void LazyDelassus::prepare(const std::vector<Eigen::Index>& which) {
  Impl& x = *impl_;
  std::vector<Eigen::Index> fresh;
  for (const Eigen::Index j : which)
    if (!x.columns[static_cast<std::size_t>(j)]) fresh.push_back(j);
  std::sort(fresh.begin(), fresh.end());
  fresh.erase(std::unique(fresh.begin(), fresh.end()), fresh.end());
  if (fresh.empty()) return;
  const auto started = std::chrono::steady_clock::now();
  const auto m = static_cast<double>(x.rows.size());
  if (x.demand)
    x.demand(72.0 * m * static_cast<double>(x.formed + static_cast<Eigen::Index>(fresh.size())));
  x.formed += static_cast<Eigen::Index>(fresh.size());
  for (const Eigen::Index j : fresh)
    x.columns[static_cast<std::size_t>(j)] =
        std::make_unique<double[]>(static_cast<std::size_t>(9) * x.rows.size());
  in_two_threads(static_cast<double>(fresh.size()) * m >= 2e4, [&](int part, int parts) {
    for (std::size_t k = static_cast<std::size_t>(part); k < fresh.size();
         k += static_cast<std::size_t>(parts))
      x.form(fresh[k], x.columns[static_cast<std::size_t>(fresh[k])].get());
  });
  x.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
}

const double* LazyDelassus::column(Eigen::Index j) const {
  return impl_->columns[static_cast<std::size_t>(j)].get();
}

const Eigen::Matrix3d& LazyDelassus::diagonal(Eigen::Index i) const {
  return impl_->diagonal[static_cast<std::size_t>(i)];
}

Eigen::Index LazyDelassus::formed() const { return impl_->formed; }

double LazyDelassus::seconds() const { return impl_->seconds; }

}  // namespace vproto::sim
