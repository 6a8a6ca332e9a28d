#include "vproto/geometry/aabb_tree.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace vproto::geometry {

AabbTree::AabbTree(const std::vector<Bounds>& boxes) : boxes_(boxes) {
  if (boxes_.empty()) return;
  std::vector<int> items(boxes_.size());
  for (std::size_t i = 0; i < items.size(); ++i) items[i] = static_cast<int>(i);
  nodes_.reserve(2 * boxes_.size());
  root_ = build(items, 0, static_cast<int>(items.size()));
}

void AabbTree::refit(const std::vector<Bounds>& boxes) {
  if (boxes.size() != boxes_.size())
    throw std::invalid_argument("AabbTree::refit: " + std::to_string(boxes.size()) +
                                " boxes for a tree over " + std::to_string(boxes_.size()));
  boxes_ = boxes;
  // nodes are stored parent first (build is a pre-order walk): children before parents here
  for (auto n = nodes_.rbegin(); n != nodes_.rend(); ++n) {
    if (n->item >= 0) {
      n->box = boxes_[static_cast<std::size_t>(n->item)];
    } else {
      n->box = nodes_[static_cast<std::size_t>(n->left)].box;
      n->box.extend(nodes_[static_cast<std::size_t>(n->right)].box);
    }
  }
}

int AabbTree::build(std::vector<int>& items, int begin, int end) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Bounds box;
  for (int k = begin; k < end; ++k) {
    box.lo = box.lo.cwiseMin(boxes_[items[k]].lo);
    box.hi = box.hi.cwiseMax(boxes_[items[k]].hi);
  }
  nodes_[index].box = box;
  if (end - begin == 1) {
    nodes_[index].item = items[begin];
    return index;
  }
  // split at the median centre along the longest axis
  int axis = 0;
  (box.hi - box.lo).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(
      items.begin() + begin, items.begin() + mid, items.begin() + end, [&](int a, int b) {
        return boxes_[a].lo[axis] + boxes_[a].hi[axis] < boxes_[b].lo[axis] + boxes_[b].hi[axis];
      });
  const int left = build(items, begin, mid);
  const int right = build(items, mid, end);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

void AabbTree::pairs(int a, int b, std::vector<std::pair<int, int>>& out) const {
  const Node& na = nodes_[a];
  const Node& nb = nodes_[b];
  if (!overlap(na.box, nb.box)) return;
  if (na.item >= 0 && nb.item >= 0) {
    out.emplace_back(std::min(na.item, nb.item), std::max(na.item, nb.item));
    return;
  }
  // descend into the larger node
  const bool split_a = nb.item >= 0 || (na.item < 0 && (na.box.hi - na.box.lo).squaredNorm() >=
                                                           (nb.box.hi - nb.box.lo).squaredNorm());
  if (split_a) {
    pairs(na.left, b, out);
    pairs(na.right, b, out);
  } else {
    pairs(a, nb.left, out);
    pairs(a, nb.right, out);
  }
}

void AabbTree::self_pairs(int node, std::vector<std::pair<int, int>>& out) const {
  const Node& n = nodes_[node];
  if (n.item >= 0) return;
  self_pairs(n.left, out);
  self_pairs(n.right, out);
  pairs(n.left, n.right, out);
}

std::vector<std::pair<int, int>> AabbTree::overlapping_pairs() const {
  std::vector<std::pair<int, int>> out;
  if (root_ >= 0) self_pairs(root_, out);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<int> AabbTree::overlapping(const Bounds& box) const {
  std::vector<int> out;
  if (root_ < 0) return out;
  std::vector<int> stack{root_};
  while (!stack.empty()) {
    const Node& n = nodes_[stack.back()];
    stack.pop_back();
    if (!overlap(n.box, box)) continue;
    if (n.item >= 0) {
      out.push_back(n.item);
    } else {
      stack.push_back(n.left);
      stack.push_back(n.right);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace vproto::geometry
