// A dynamic k-d tree over points in R^k (the elite set's normalized parameters): insert, remove,
// radius and k-nearest queries. Our own rather than nanoflann: Debian's libnanoflann-dev is not
// among the project's dependencies (deploy/setup.sh, CI), the elite set needs insertion and
// removal interleaved with queries at 10^4-10^5 points of 1-8 dims, and that fits in this file.
// Inserts descend to a leaf; the tree is rebuilt balanced (median splits) when it has doubled
// since the last build or when removed nodes outnumber live ones, so both stay amortized
// O(log n).
#ifndef MODSKILL_LEARNER_FAMILY_KD_TREE_H_
#define MODSKILL_LEARNER_FAMILY_KD_TREE_H_

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "absl/status/status.h"
#include "absl/types/span.h"

namespace modskill::learner::family {

struct Neighbor {
  int64_t id = 0;
  double distance = 0;  // Euclidean
};

class KdTree {
 public:
  explicit KdTree(int dims) : dims_(dims) {}

  int dims() const { return dims_; }
  int64_t size() const { return live_; }

  // INVALID_ARGUMENT for a point of the wrong size or non-finite, or an id already present.
  absl::Status Insert(int64_t id, absl::Span<const double> point);
  // False when the id is not in the tree.
  bool Remove(int64_t id);
  // Every point within `radius` (inclusive) of `point`, nearest first. `point` has dims() values.
  std::vector<Neighbor> WithinRadius(absl::Span<const double> point, double radius) const;
  // The min(k, size()) nearest points, nearest first.
  std::vector<Neighbor> Nearest(absl::Span<const double> point, int k) const;

 private:
  struct Node {
    int64_t id;
    int axis;
    int left = -1, right = -1;
    bool removed = false;
  };
  const double* Coords(int node) const { return &coords_[static_cast<size_t>(node) * dims_]; }
  double Distance2(int node, absl::Span<const double> point) const;
  void Rebuild();
  int Build(std::vector<int>& order, int begin, int end, int depth, std::vector<Node>& nodes,
            std::vector<double>& coords) const;

  int dims_;
  std::vector<Node> nodes_;
  std::vector<double> coords_;  // [nodes, dims]
  std::unordered_map<int64_t, int> node_of_id_;
  int root_ = -1;
  int64_t live_ = 0;
  int64_t built_nodes_ = 0;  // nodes_.size() after the last rebuild
};

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_KD_TREE_H_
