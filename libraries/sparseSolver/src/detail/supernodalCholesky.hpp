// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "detail/supernodalSubstitution.hpp"

namespace asyncfem::detail {

/// The numeric supernodal Cholesky factorization P A P^T = L L^T on a symbolic structure
/// CHOLMOD analysed (SupernodalArrays' layout), right-looking with LAPACK's and BLAS's
/// dense kernels (the ones CHOLMOD calls): per supernode the diagonal block's L L^T
/// (dpotrf), the rows below it by a triangular solve (dtrsm), and their outer product
/// (dsyrk) subtracted from the ancestors' blocks through a row map.
///
/// What it is for: CHOLMOD's numeric factorization opens an OpenMP region per supernode
/// and per descendant update whatever the sizes, each ending in a system call to wake the
/// team (a few microseconds on a virtual machine), which on the small factors of fast
/// regions costs several times the arithmetic and on meshes of 10^4 unknowns still about a
/// third of the time (docs/benchmarks.md, "Factorizations without OpenMP regions").
/// CholmodSolver factors with it whenever the outer-product buffer (the most rows below
/// one supernode, squared) holds at most kMaxUpdateEntries doubles.
class SupernodalCholesky {
 public:
  /// Largest outer-product buffer (doubles, 128 MiB: a widest update of 4,096 rows) this
  /// factorization allocates. Past it CHOLMOD factors, with its BLAS on one thread (so that
  /// the factor does not depend on the thread count): a 45k-DOF box (widest update above
  /// 2,048 rows) factors in 0.55 s here against 0.67 s through CHOLMOD on one thread.
  static constexpr double kMaxUpdateEntries = 16.0 * 1024 * 1024;
  /// Whether factor's largest outer product fits kMaxUpdateEntries.
  static bool fits(const SupernodalArrays<double>& factor) {
    const double widest = widestUpdate(factor);
    return widest * widest <= kMaxUpdateEntries;
  }

  /// Prepares for matrices with a's pattern (square, compressed; the upper triangle is
  /// read, as CHOLMOD reads a symmetric matrix with stype 1): where each of its entries
  /// lands in L's values. perm: P (row i of P A P^T is row perm[i] of A). The factor's
  /// arrays must stay valid while factor() is used.
  void prepare(const SupernodalArrays<double>& factor, const int* perm, const Eigen::SparseMatrix<double>& a);
  /// Whether prepare() ran for this structure (the same arrays: CHOLMOD keeps a factor's
  /// symbolic arrays in place across factorizations, but a new analysis replaces them).
  bool preparedFor(const SupernodalArrays<double>& factor) const {
    return prepared_ && factor.supernodes == structure_.supernodes && factor.super == structure_.super &&
           factor.pi == structure_.pi && factor.px == structure_.px && factor.rows == structure_.rows;
  }
  void clear() { prepared_ = false; }

  /// Factors a (the prepared pattern) into values (the factor's value array, valueCount
  /// entries). False, with values partly overwritten, when a pivot is not positive.
  bool factor(const Eigen::SparseMatrix<double>& a, double* values, std::size_t valueCount);

 private:
  /// Subtracts the lower triangle of update_ (the outer product of the rows below supernode
  /// s, column-major with leading dimension their count) from the blocks of s's ancestors.
  void subtractUpdate(int s, double* values);

  SupernodalArrays<double> structure_;
  bool prepared_ = false;
  std::vector<int> columnSupernode_;  // supernode of each column of L
  std::vector<int> target_;           // entry k of a's values -> index into L's values (-1: lower triangle)
  std::vector<int> rowPosition_;      // row -> its position in the current target supernode
  std::unique_ptr<double[]> update_;  // the outer product of one supernode's rows below it
};

}  // namespace asyncfem::detail
