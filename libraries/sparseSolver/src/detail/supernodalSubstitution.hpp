// SPDX-License-Identifier: BSD-3-Clause
// Forward and back substitution through a supernodal Cholesky factor, with Eigen's dense
// kernels per supernode: the single-precision preconditioner's solve and CHOLMOD's
// single-column solves in double share it.
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace asyncfem::detail {

/// The arrays of a supernodal Cholesky factor P A P^T = L L^T, as CHOLMOD keeps them
/// (int indices): supernode k holds columns super[k] .. super[k+1]-1 of L as a dense
/// column-major block of (pi[k+1] - pi[k]) rows, stored from values[px[k]]; its row
/// indices are rows[pi[k]] .. (the first ones are its own columns, in order).
template <typename Scalar>
struct SupernodalArrays {
  int size = 0;
  int supernodes = 0;
  const int* super = nullptr;
  const int* pi = nullptr;
  const int* px = nullptr;
  const int* rows = nullptr;
  const Scalar* values = nullptr;
};

/// The most rows below a diagonal block over all supernodes: the length of the update
/// buffer substituteInPlace needs.
template <typename Scalar>
int widestUpdate(const SupernodalArrays<Scalar>& factor) {
  int widest = 0;
  for (int k = 0; k < factor.supernodes; ++k) {
    widest = std::max(widest, (factor.pi[k + 1] - factor.pi[k]) - (factor.super[k + 1] - factor.super[k]));
  }
  return widest;
}

/// work = L^-T L^-1 work in place (work in the factor's permuted order, factor.size
/// entries; below: at least widestUpdate(factor) entries of scratch). Supernode by
/// supernode: the diagonal block's triangle, then the update of the rows below it (forward)
/// or from them (back), as dense matrix-vector products without a BLAS call each, which is
/// what pays on the small supernodes of 3D meshes.
template <typename Scalar>
void substituteInPlace(const SupernodalArrays<Scalar>& factor, Eigen::Matrix<Scalar, Eigen::Dynamic, 1>& work,
                       Eigen::Matrix<Scalar, Eigen::Dynamic, 1>& below) {
  using Block = Eigen::Map<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>>;
  // Supernode k: its first column, column count, the rows below its diagonal block (count
  // and indices) and its dense block (all rows x its columns).
  struct Supernode {
    int first, columns, count;
    const int* rowIndex;
    Block block;
  };
  const auto supernode = [&factor](int k) {
    const int first = factor.super[k];
    const int columns = factor.super[k + 1] - first;
    const int rows = factor.pi[k + 1] - factor.pi[k];
    return Supernode{first, columns, rows - columns, factor.rows + factor.pi[k] + columns,
                     Block(factor.values + factor.px[k], rows, columns)};
  };
  for (int k = 0; k < factor.supernodes; ++k) {
    const Supernode node = supernode(k);
    auto y = work.segment(node.first, node.columns);
    node.block.topRows(node.columns).template triangularView<Eigen::Lower>().solveInPlace(y);
    if (node.count == 0) continue;
    auto update = below.head(node.count);
    update.noalias() = node.block.bottomRows(node.count) * y;
    for (int r = 0; r < node.count; ++r) work[node.rowIndex[r]] -= update[r];
  }
  for (int k = factor.supernodes - 1; k >= 0; --k) {
    const Supernode node = supernode(k);
    auto x = work.segment(node.first, node.columns);
    if (node.count > 0) {
      auto known = below.head(node.count);
      for (int r = 0; r < node.count; ++r) known[r] = work[node.rowIndex[r]];
      x.noalias() -= node.block.bottomRows(node.count).transpose() * known;
    }
    node.block.topRows(node.columns).transpose().template triangularView<Eigen::Upper>().solveInPlace(x);
  }
}

}  // namespace asyncfem::detail
