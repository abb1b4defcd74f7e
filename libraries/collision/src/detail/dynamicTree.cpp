// SPDX-License-Identifier: BSD-3-Clause
// Bullet's dynamic AABB tree, double-precision build (BT_USE_DOUBLE_PRECISION), so box
// corners are stored without rounding.
#include <BulletCollision/BroadphaseCollision/btDbvt.h>

#include <algorithm>
#include <cstdint>
#include <detail/boxPairs.hpp>
#include <numeric>
#include <random>
#include <vector>

namespace asyncfem::detail {

namespace {

/// A tree over one box set; leaf data holds the box index.
class BoxTree {
 public:
  explicit BoxTree(const BoxSet& boxes) {
    // Inserted in a fixed pseudo-random order: inserted in mesh order (spatially coherent),
    // the tree made queries about 2 times slower on the benchmark surfaces of 10k and 100k
    // triangles (docs/collision.md).
    std::vector<int> order(static_cast<std::size_t>(boxes.size()));
    std::iota(order.begin(), order.end(), 0);
    std::mt19937 generator(20261207);
    std::shuffle(order.begin(), order.end(), generator);
    for (const int i : order) {
      const btVector3 low(boxes.min(0, i), boxes.min(1, i), boxes.min(2, i));
      const btVector3 high(boxes.max(0, i), boxes.max(1, i), boxes.max(2, i));
      tree_.insert(btDbvtVolume::FromMM(low, high), reinterpret_cast<void*>(static_cast<std::intptr_t>(i)));
    }
    // No rebuild afterwards: rebuilding top-down (optimizeTopDown) made each query 3 to 5
    // times slower on the benchmark surfaces.
  }
  BoxTree(const BoxTree&) = delete;
  BoxTree& operator=(const BoxTree&) = delete;

  btDbvt& tree() { return tree_; }

 private:
  btDbvt tree_;
};

int leafIndex(const btDbvtNode* node) { return static_cast<int>(reinterpret_cast<std::intptr_t>(node->data)); }

struct PairCollector : btDbvt::ICollide {
  BoxPairs pairs;
  bool ordered = false;  // self-collision: report (min, max)
  void Process(const btDbvtNode* a, const btDbvtNode* b) override {
    int i = leafIndex(a);
    int j = leafIndex(b);
    if (ordered && i > j) std::swap(i, j);
    pairs.emplace_back(i, j);
  }
};

}  // namespace

BoxPairs dynamicTreePairs(const BoxSet& first, const BoxSet& second) {
  BoxTree firstTree(first);
  BoxTree secondTree(second);
  PairCollector collector;
  firstTree.tree().collideTT(firstTree.tree().m_root, secondTree.tree().m_root, collector);
  return std::move(collector.pairs);
}

BoxPairs dynamicTreeSelfPairs(const BoxSet& boxes) {
  BoxTree tree(boxes);
  PairCollector collector;
  collector.ordered = true;
  // Traversing a tree against itself visits each unordered pair of distinct leaves once.
  tree.tree().collideTT(tree.tree().m_root, tree.tree().m_root, collector);
  return std::move(collector.pairs);
}

}  // namespace asyncfem::detail
