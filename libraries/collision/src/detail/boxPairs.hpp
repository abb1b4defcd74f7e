// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/collision/broadPhase.hpp>
#include <utility>
#include <vector>

/// The broad-phase methods behind overlappingBoxes, on validated box sets. Each returns
/// every overlapping pair once, in any order.
namespace asyncfem::detail {

using BoxPairs = std::vector<std::pair<int, int>>;

/// Whether boxes i of `first` and j of `second` overlap (closed boxes).
inline bool boxesOverlap(const BoxSet& first, int i, const BoxSet& second, int j) {
  return (first.min.col(i).array() <= second.max.col(j).array()).all() &&
         (second.min.col(j).array() <= first.max.col(i).array()).all();
}

BoxPairs dynamicTreePairs(const BoxSet& first, const BoxSet& second);
/// Pairs (i, j) with i < j.
BoxPairs dynamicTreeSelfPairs(const BoxSet& boxes);

BoxPairs spatialHashPairs(const BoxSet& first, const BoxSet& second);
/// Pairs (i, j) with i < j.
BoxPairs spatialHashSelfPairs(const BoxSet& boxes);

}  // namespace asyncfem::detail
