// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "detail/supernodalSubstitution.hpp"

namespace asyncfem::detail {

/// A supernodal Cholesky factor P A P^T = L L^T in double (supernodalSubstitution.hpp)
/// and its fill-reducing permutation: row i of P A P^T is row perm[i] of A.
struct SupernodalFactorView : SupernodalArrays<double> {
  const int* perm = nullptr;
};

/// A copy of a supernodal Cholesky factor in single precision, applied as a
/// preconditioner: solve(b) = P^T L^-T L^-1 P b with every entry of L rounded to float
/// (relative error about 6e-8 of A^-1 b). The forward and back substitutions read half the
/// bytes of the double factor, and run as Eigen's dense kernels per supernode without a
/// BLAS call each, which is what makes them faster on the small supernodes of 3D meshes up
/// to some 10^5 unknowns (docs/benchmarks.md, "The kept factor in single precision").
/// Deterministic and single-threaded.
class SinglePrecisionFactor {
 public:
  /// Copies (and rounds) the factor; the view's arrays are not kept.
  void assign(const SupernodalFactorView& factor);
  bool empty() const { return size_ == 0; }
  /// solution = the approximate A^-1 rhs (sizes: the factor's).
  void solve(const Eigen::Ref<const Eigen::VectorXd>& rhs, Eigen::VectorXd& solution);
  /// Whether this copy may stand in for the double factor as a preconditioner: its solve
  /// of a fixed vector is finite and within 1e-2 relatively of exactSolve's.
  bool agreesWith(const std::function<void(const Eigen::VectorXd&, Eigen::VectorXd&)>& exactSolve);

 private:
  int size_ = 0;
  int supernodes_ = 0;
  std::vector<int> super_, pi_, px_, rows_, perm_;
  std::vector<float> values_;
  Eigen::VectorXf work_, below_;
};

/// Implemented by direct solvers whose factor SinglePrecisionFactor can copy.
class SupernodalFactorSource {
 public:
  virtual ~SupernodalFactorSource() = default;
  /// Copies the last numeric factor into out; false (out untouched) when there is none
  /// or it is not a supernodal L L^T with int indices.
  virtual bool copyFactor(SinglePrecisionFactor& out) const = 0;

 protected:
  SupernodalFactorSource() = default;
  SupernodalFactorSource(const SupernodalFactorSource&) = default;
  SupernodalFactorSource& operator=(const SupernodalFactorSource&) = default;
};

}  // namespace asyncfem::detail
