#include "learner/family/kd_tree.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <utility>

#include "absl/strings/str_cat.h"

namespace modskill::learner::family {

double KdTree::Distance2(int node, absl::Span<const double> point) const {
  const double* c = Coords(node);
  double d2 = 0;
  for (int i = 0; i < dims_; ++i) d2 += (c[i] - point[i]) * (c[i] - point[i]);
  return d2;
}

absl::Status KdTree::Insert(int64_t id, absl::Span<const double> point) {
  if (static_cast<int>(point.size()) != dims_) {
    return absl::InvalidArgumentError(absl::StrCat("k-d tree: point has ", point.size(), " values, the tree ", dims_, " dims"));
  }
  for (double v : point) {
    if (!std::isfinite(v)) return absl::InvalidArgumentError(absl::StrCat("k-d tree: point ", id, " is not finite"));
  }
  if (node_of_id_.count(id)) return absl::InvalidArgumentError(absl::StrCat("k-d tree: id ", id, " is already in the tree"));
  const int node = static_cast<int>(nodes_.size());
  int parent = root_, axis = 0;
  int* link = &root_;
  while (parent >= 0) {  // descend to the leaf the point belongs under
    const Node& p = nodes_[parent];
    axis = (p.axis + 1) % dims_;
    link = point[p.axis] < Coords(parent)[p.axis] ? &nodes_[parent].left : &nodes_[parent].right;
    parent = *link;
  }
  *link = node;  // before push_back: `link` may point into nodes_
  nodes_.push_back(Node{id, axis});
  coords_.insert(coords_.end(), point.begin(), point.end());
  node_of_id_[id] = node;
  ++live_;
  if (static_cast<int64_t>(nodes_.size()) > 2 * built_nodes_ + 16) Rebuild();
  return absl::OkStatus();
}

bool KdTree::Remove(int64_t id) {
  const auto it = node_of_id_.find(id);
  if (it == node_of_id_.end()) return false;
  nodes_[it->second].removed = true;  // lazily: the node still splits space until a rebuild
  node_of_id_.erase(it);
  --live_;
  if (static_cast<int64_t>(nodes_.size()) - live_ > live_ + 16) Rebuild();
  return true;
}

int KdTree::Build(std::vector<int>& order, int begin, int end, int depth, std::vector<Node>& nodes,
                  std::vector<double>& coords) const {
  if (begin >= end) return -1;
  const int axis = depth % dims_;
  const int mid = begin + (end - begin) / 2;
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                   [&](int a, int b) { return Coords(a)[axis] < Coords(b)[axis]; });
  const int node = static_cast<int>(nodes.size());
  nodes.push_back(Node{nodes_[order[mid]].id, axis});
  coords.insert(coords.end(), Coords(order[mid]), Coords(order[mid]) + dims_);
  // Equal coordinates may sit on either side; queries descend both sides within range.
  const int left = Build(order, begin, mid, depth + 1, nodes, coords);
  const int right = Build(order, mid + 1, end, depth + 1, nodes, coords);
  nodes[node].left = left;
  nodes[node].right = right;
  return node;
}

void KdTree::Rebuild() {
  std::vector<int> order;
  order.reserve(live_);
  for (int i = 0; i < static_cast<int>(nodes_.size()); ++i) {
    if (!nodes_[i].removed) order.push_back(i);
  }
  std::vector<Node> nodes;
  std::vector<double> coords;
  nodes.reserve(order.size());
  coords.reserve(order.size() * dims_);
  root_ = Build(order, 0, static_cast<int>(order.size()), 0, nodes, coords);
  nodes_ = std::move(nodes);
  coords_ = std::move(coords);
  node_of_id_.clear();
  for (int i = 0; i < static_cast<int>(nodes_.size()); ++i) node_of_id_[nodes_[i].id] = i;
  built_nodes_ = static_cast<int64_t>(nodes_.size());
}

std::vector<Neighbor> KdTree::WithinRadius(absl::Span<const double> point, double radius) const {
  std::vector<Neighbor> found;
  const double r2 = radius * radius;
  std::vector<int> stack;
  if (root_ >= 0) stack.push_back(root_);
  while (!stack.empty()) {
    const int n = stack.back();
    stack.pop_back();
    const Node& node = nodes_[n];
    const double d2 = Distance2(n, point);
    if (!node.removed && d2 <= r2) found.push_back({node.id, std::sqrt(d2)});
    const double diff = point[node.axis] - Coords(n)[node.axis];
    // A side is searched when the ball reaches it (both when it straddles the split).
    if (node.left >= 0 && diff <= radius) stack.push_back(node.left);
    if (node.right >= 0 && diff >= -radius) stack.push_back(node.right);
  }
  std::sort(found.begin(), found.end(), [](const Neighbor& a, const Neighbor& b) { return a.distance < b.distance; });
  return found;
}

std::vector<Neighbor> KdTree::Nearest(absl::Span<const double> point, int k) const {
  std::priority_queue<std::pair<double, int64_t>> best;  // max-heap of (d^2, id), size <= k
  // Depth-first, near side first. Each pending subtree carries a lower bound of its squared
  // distance built from the per-axis offsets of the splits crossed to reach it (Arya and
  // Mount's incremental distance), which prunes far better in 4-8 dims than the one-axis gap.
  struct Pending {
    int node;
    double bound2;
  };
  std::vector<Pending> stack;
  std::vector<double> offsets;  // [stack entry, dims]: the per-axis offsets of each entry
  if (root_ >= 0 && k > 0) {
    stack.push_back({root_, 0.0});
    offsets.assign(dims_, 0.0);
  }
  const auto full = [&] { return static_cast<int>(best.size()) == k; };
  std::vector<double> off(dims_);
  while (!stack.empty()) {
    const Pending top = stack.back();
    std::copy(offsets.end() - dims_, offsets.end(), off.begin());
    stack.pop_back();
    offsets.resize(offsets.size() - dims_);
    if (full() && top.bound2 > best.top().first) continue;
    const Node& node = nodes_[top.node];
    const double d2 = Distance2(top.node, point);
    if (!node.removed && (!full() || d2 < best.top().first)) {
      best.push({d2, node.id});
      if (static_cast<int>(best.size()) > k) best.pop();
    }
    const double diff = point[node.axis] - Coords(top.node)[node.axis];
    const int near = diff < 0 ? node.left : node.right, far = diff < 0 ? node.right : node.left;
    if (far >= 0) {
      const double far_bound2 = top.bound2 - off[node.axis] * off[node.axis] + diff * diff;
      if (!full() || far_bound2 <= best.top().first) {
        stack.push_back({far, far_bound2});
        offsets.insert(offsets.end(), off.begin(), off.end());
        offsets[offsets.size() - dims_ + node.axis] = diff;
      }
    }
    if (near >= 0) {  // pushed last, popped first: tightens `best` early
      stack.push_back({near, top.bound2});
      offsets.insert(offsets.end(), off.begin(), off.end());
    }
  }
  std::vector<Neighbor> out(best.size());
  for (int i = static_cast<int>(best.size()) - 1; i >= 0; --i, best.pop()) {
    out[i] = {best.top().second, std::sqrt(best.top().first)};
  }
  return out;
}

}  // namespace modskill::learner::family
