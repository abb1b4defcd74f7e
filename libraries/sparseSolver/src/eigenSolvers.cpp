// SPDX-License-Identifier: BSD-3-Clause
// Eigen's SimplicialLDLT and SparseLU behind SparseSolver (no SuiteSparse at run time).
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <string>

#include "detail/solverBase.hpp"

namespace asyncfem::detail {
namespace {

using LDLTFactorization = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Upper, Eigen::AMDOrdering<int>>;
using LUFactorization = Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>>;

/// Factor statistics of a successful factorization (Eigen reports no flop counts, so
/// the flops are estimates from the factor's column counts).
struct FactorCosts {
  long long nonZeros = 0;
  double flops = 0.0;
  double solveFlopsPerRhs = 0.0;
};

/// Throws NumericalError unless every pivot of D is positive (SimplicialLDLT succeeds on
/// indefinite matrices; positive definiteness is D > 0). Names the caller's column.
void requirePositivePivots(const LDLTFactorization& ldlt) {
  const Eigen::VectorXd& d = ldlt.vectorD();
  for (Eigen::Index step = 0; step < d.size(); ++step) {
    if (!(d[step] > 0.0)) {
      // Step `step` of P A P^T eliminates the caller's column Pinv(step).
      const int column = ldlt.permutationPinv().indices()[step];
      throw NumericalError("eigen-ldlt: matrix is not positive definite: pivot " + std::to_string(d[step]) +
                           " at column " + std::to_string(column) + " (elimination step " + std::to_string(step) +
                           " of " + std::to_string(d.size()) + ")");
    }
  }
}

/// L stores the strictly lower part (unit diagonal implied). Column k with c_k entries
/// costs c_k divisions and a symmetric rank-1 update of c_k (c_k + 1) / 2 entries (one
/// multiply and one add each): sum_k c_k^2 + 2 c_k, the count CHOLMOD reports as Common->fl.
FactorCosts ldltCosts(const LDLTFactorization& ldlt) {
  const SparseMatrix& strictlyLower = ldlt.matrixL().nestedExpression();
  FactorCosts costs;
  for (Eigen::Index k = 0; k < strictlyLower.outerSize(); ++k) {
    const double count = strictlyLower.outerIndexPtr()[k + 1] - strictlyLower.outerIndexPtr()[k];
    costs.flops += count * count + 2.0 * count;
  }
  // Count the diagonal (where D lives) like CHOLMOD's lnz does.
  costs.nonZeros = strictlyLower.nonZeros() + strictlyLower.rows();
  costs.solveFlopsPerRhs = 4.0 * static_cast<double>(costs.nonZeros);
  return costs;
}

/// SparseLU's nnzL() and nnzU() both include the diagonal. Step k with l_k entries below
/// the pivot in L and u_k right of it in U costs l_k divisions and a rank-1 update of
/// l_k u_k entries: sum_k l_k + 2 l_k u_k. The l_k come from L's supernodes (the public
/// m_mapL of matrixL()); SparseLU does not expose U's row counts, so u_k is taken as
/// l_k scaled by the ratio of U's to L's off-diagonal entries, exact for a structurally
/// symmetric factorization and an estimate otherwise.
FactorCosts luCosts(const LUFactorization& lu) {
  const auto& supernodalL = lu.matrixL().m_mapL;
  const double n = static_cast<double>(lu.rows());
  const double offDiagonalL = static_cast<double>(lu.nnzL()) - n;
  const double offDiagonalU = static_cast<double>(lu.nnzU()) - n;
  const double ratio = offDiagonalL > 0.0 ? offDiagonalU / offDiagonalL : 0.0;
  FactorCosts costs;
  for (Eigen::Index s = 0; s <= supernodalL.nsuper(); ++s) {
    const Eigen::Index firstColumn = supernodalL.supToCol()[s];
    const Eigen::Index endColumn = supernodalL.supToCol()[s + 1];
    // Every column of a supernode shares the rows of the first; column j starts j - first lower.
    const Eigen::Index rows = supernodalL.rowIndexPtr()[firstColumn + 1] - supernodalL.rowIndexPtr()[firstColumn];
    for (Eigen::Index j = firstColumn; j < endColumn; ++j) {
      const double below = static_cast<double>(rows - (j - firstColumn) - 1);
      costs.flops += below + 2.0 * below * (below * ratio);
    }
  }
  costs.nonZeros = lu.nnzL() + lu.nnzU();
  costs.solveFlopsPerRhs = 2.0 * static_cast<double>(costs.nonZeros);
  return costs;
}

template <class Factorization, SolverKind Kind>
class EigenSolver final : public SolverBase {
 public:
  SolverKind kind() const override { return Kind; }
  std::string ordering() const override {
    if (!signature_.analysed()) return "none";
    return Kind == SolverKind::eigenLDLT ? "amd" : "colamd";
  }

  void analyzePattern(const SparseMatrix& a) override {
    Stopwatch watch;  // runs from construction
    beginAnalyze(a, name());
    factorization_.analyzePattern(a);
    ++stats_.analyses;
    stats_.analyzeSeconds += watch.stop();
  }

  void factorize(const SparseMatrix& a) override {
    Stopwatch watch;  // runs from construction
    beginFactorize(a, name());
    factorization_.factorize(a);
    FactorCosts costs;
    if constexpr (Kind == SolverKind::eigenLDLT) {
      if (factorization_.info() != Eigen::Success) {
        throw NumericalError("eigen-ldlt: matrix is not positive definite (a zero pivot was found)");
      }
      requirePositivePivots(factorization_);
      costs = ldltCosts(factorization_);
    } else {
      if (factorization_.info() != Eigen::Success) {
        // Eigen's message counts columns in its permuted order; say so.
        throw NumericalError(
            "eigen-lu: matrix is singular (SparseLU, permuted numbering: " + factorization_.lastErrorMessage() + ")");
      }
      costs = luCosts(factorization_);
    }
    stats_.factorNonZeros = costs.nonZeros;
    stats_.factorFlops = costs.flops;
    stats_.solveFlopsPerRhs = costs.solveFlopsPerRhs;
    endFactorize(watch);
  }

  void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    Stopwatch watch;  // runs from construction
    beginSolve(rhs, name());
    solution = factorization_.solve(rhs);
    if (factorization_.info() != Eigen::Success) throw NumericalError(std::string(name()) + ": solve failed");
    endSolve(rhs.cols(), watch);
  }

 private:
  static std::string name() { return Kind == SolverKind::eigenLDLT ? "eigen-ldlt" : "eigen-lu"; }

  Factorization factorization_;
};

}  // namespace

std::unique_ptr<SparseSolver> makeEigenLDLTSolver() {
  return std::make_unique<EigenSolver<LDLTFactorization, SolverKind::eigenLDLT>>();
}
std::unique_ptr<SparseSolver> makeEigenLUSolver() {
  return std::make_unique<EigenSolver<LUFactorization, SolverKind::eigenLU>>();
}

}  // namespace asyncfem::detail
