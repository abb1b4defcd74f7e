// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/modalAnalysis/generalizedEigen.hpp>
#include <vector>

extern "C" {
// LAPACK (Fortran calling convention): generalized symmetric-definite eigenproblem,
// divide and conquer.
void dsygvd_(const int* itype, const char* jobz, const char* uplo, const int* n, double* a, const int* lda, double* b,
             const int* ldb, double* w, double* work, const int* lwork, int* iwork, const int* liwork, int* info);
}

namespace asyncfem {

bool solveGeneralizedEigen(Eigen::MatrixXd& stiffness, Eigen::MatrixXd& mass, Eigen::VectorXd& eigenvalues) {
  const int n = static_cast<int>(stiffness.rows());
  eigenvalues.resize(n);
  if (n == 0) return true;
  const int itype = 1;  // A x = lambda B x
  const char jobz = 'V', uplo = 'L';
  int info = 0;
  // One BLAS thread: the blocked reductions sum in an order that depends on the thread
  // count, and a region's modes must not depend on the machine's load.
  const ScopedBlasThreads blas(1);
  // Workspace query first.
  int lwork = -1, liwork = -1, iworkSize = 0;
  double workSize = 0.0;
  dsygvd_(&itype, &jobz, &uplo, &n, stiffness.data(), &n, mass.data(), &n, eigenvalues.data(), &workSize, &lwork,
          &iworkSize, &liwork, &info);
  if (info != 0) return false;
  lwork = std::max(1, static_cast<int>(workSize));
  liwork = std::max(1, iworkSize);
  std::vector<double> work(static_cast<std::size_t>(lwork));
  std::vector<int> iwork(static_cast<std::size_t>(liwork));
  dsygvd_(&itype, &jobz, &uplo, &n, stiffness.data(), &n, mass.data(), &n, eigenvalues.data(), work.data(), &lwork,
          iwork.data(), &liwork, &info);
  return info == 0;
}

std::string generalizedEigenBackend() { return "LAPACK dsygvd"; }

}  // namespace asyncfem
