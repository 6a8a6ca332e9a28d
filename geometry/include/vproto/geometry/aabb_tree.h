#pragma once
// The broad phase: a bounding-volume hierarchy over axis-aligned boxes (bodies, or their
// convex parts) that reports every pair of overlapping boxes. Built top-down by splitting
// at the median of the longest axis, so its depth is log2(n) and a query costs
// O(n log n + pairs) instead of the n^2 / 2 box tests of a double loop; rebuilding each
// step costs O(n log n) too, so a pile of 1,000 bodies stays cheap. A surface that deforms
// keeps its hierarchy and refits it (O(n)): its triangles keep their neighbours.

#include <utility>
#include <vector>

#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry {

class AabbTree {
 public:
  explicit AabbTree(const std::vector<Bounds>& boxes);

  /// The same hierarchy over new boxes for the same items (as many as it was built with):
  /// every node's box is recomputed from its children's, in O(n). Queries stay exact; they
  /// only slow down when the items move far relative to each other.
  void refit(const std::vector<Bounds>& boxes);

  /// Every pair (i < j) of boxes that overlap (strictly: boxes that only touch do not).
  std::vector<std::pair<int, int>> overlapping_pairs() const;

  /// The boxes that overlap `box`.
  std::vector<int> overlapping(const Bounds& box) const;

 private:
  struct Node {
    Bounds box;
    int left = -1, right = -1;  ///< children, or -1 for a leaf
    int item = -1;              ///< the box of a leaf
  };
  int build(std::vector<int>& items, int begin, int end);
  void pairs(int a, int b, std::vector<std::pair<int, int>>& out) const;
  void self_pairs(int node, std::vector<std::pair<int, int>>& out) const;

  std::vector<Bounds> boxes_;
  std::vector<Node> nodes_;
  int root_ = -1;
};

/// Strict overlap of two boxes.
inline bool overlap(const Bounds& a, const Bounds& b) {
  return (a.lo.array() < b.hi.array()).all() && (b.lo.array() < a.hi.array()).all();
}

}  // namespace vproto::geometry
