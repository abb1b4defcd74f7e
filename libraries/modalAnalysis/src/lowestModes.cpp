// SPDX-License-Identifier: BSD-3-Clause
#include <Spectra/SymGEigsShiftSolver.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <cmath>
#include <memory>
#include <string>

namespace asyncfem {

namespace {

// Spectra's operator for y = (K - sigma M)^{-1} x: set_shift() factors K - sigma M with a
// SparseSolver, perform_op() back-substitutes.
class ShiftInvertOperator {
 public:
  using Scalar = double;

  ShiftInvertOperator(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
                      SolverKind kind)
      : stiffness_(stiffness), mass_(mass), solver_(makeSparseSolver(kind)) {}

  Eigen::Index rows() const { return stiffness_.rows(); }
  Eigen::Index cols() const { return stiffness_.cols(); }

  // Factors once: a later solver built on this operator with the same shift keeps the factor.
  void set_shift(double sigma) {  // NOLINT(readability-identifier-naming): Spectra's interface
    if (factored_ && sigma == sigma_) return;
    Stopwatch watch;
    Eigen::SparseMatrix<double> shifted = stiffness_ - sigma * mass_;
    shifted.makeCompressed();
    try {
      solver_->compute(shifted);
    } catch (const NumericalError& e) {
      throw NumericalError("modal analysis: cannot factor K - sigma M with sigma = " + std::to_string(sigma) + " (" +
                           toString(solver_->kind()) +
                           "): a Cholesky solver needs a shift below the lowest eigenvalue; " + e.what());
    }
    factorSeconds_ = watch.stop();
    factored_ = true;
    sigma_ = sigma;
  }

  void perform_op(const double* in, double* out) const {  // NOLINT(readability-identifier-naming)
    const Eigen::Map<const Eigen::VectorXd> x(in, rows());
    solver_->solve(x, scratch_);
    Eigen::Map<Eigen::VectorXd>(out, rows()) = scratch_.col(0);
    ++applications_;
  }

  double factorSeconds() const { return factorSeconds_; }
  int applications() const { return applications_; }

 private:
  const Eigen::SparseMatrix<double>& stiffness_;
  const Eigen::SparseMatrix<double>& mass_;
  std::unique_ptr<SparseSolver> solver_;  // solve() is not const: the operator is used through const
  mutable Eigen::MatrixXd scratch_;
  mutable int applications_ = 0;
  double factorSeconds_ = 0.0;
  bool factored_ = false;
  double sigma_ = 0.0;
};

// Spectra's operator for y = M x (the B of the generalized problem).
class MassOperator {
 public:
  using Scalar = double;

  explicit MassOperator(const Eigen::SparseMatrix<double>& mass) : mass_(mass) {}

  Eigen::Index rows() const { return mass_.rows(); }
  Eigen::Index cols() const { return mass_.cols(); }

  void perform_op(const double* in, double* out) const {  // NOLINT(readability-identifier-naming)
    Eigen::Map<Eigen::VectorXd>(out, rows()).noalias() = mass_ * Eigen::Map<const Eigen::VectorXd>(in, cols());
  }

 private:
  const Eigen::SparseMatrix<double>& mass_;
};

double defaultShift(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass) {
  double largest = 0.0;
  for (Eigen::Index i = 0; i < stiffness.rows(); ++i) {
    const double m = mass.coeff(i, i);
    if (m > 0.0) largest = std::max(largest, stiffness.coeff(i, i) / m);
  }
  return largest > 0.0 ? -1e-8 * largest : -1.0;
}

// Throws ValidationError unless K and M are square over the DOFs of freeDofs and the
// options ask for 1 to numFree - 1 modes with a positive tolerance and iteration cap.
void checkModalProblem(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
                       const FreeDofs& freeDofs, const ModalOptions& options) {
  const int numDofs = freeDofs.numDofs();
  if (stiffness.rows() != numDofs || stiffness.cols() != numDofs || mass.rows() != numDofs || mass.cols() != numDofs) {
    throw ValidationError("modal analysis: K is " + std::to_string(stiffness.rows()) + "x" +
                          std::to_string(stiffness.cols()) + " and M " + std::to_string(mass.rows()) + "x" +
                          std::to_string(mass.cols()) + ", expected " + std::to_string(numDofs) + "x" +
                          std::to_string(numDofs) + " (the DOFs of FreeDofs)");
  }
  if (!(options.tolerance > 0.0) || options.maxIterations < 1) {
    throw ValidationError("modal analysis: the tolerance must be > 0 and maxIterations >= 1");
  }
}

void checkModeCount(int count, int numFree) {
  if (count <= 0 || count >= numFree) {
    throw ValidationError("modal analysis: the number of modes must be in [1, " + std::to_string(numFree - 1) +
                          "] (fewer than the " + std::to_string(numFree) + " free DOFs), got " + std::to_string(count));
  }
}

// Modes over all DOFs (numDofs x count, zero at fixed DOFs) from the free-DOF Lanczos
// vectors, each scaled to unit M-norm: they are M-orthonormal already, normalising
// again removes round-off.
Eigen::MatrixXd massNormalizedModes(const Eigen::MatrixXd& freeModes, const Eigen::SparseMatrix<double>& massFree,
                                    const FreeDofs& freeDofs) {
  Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(freeDofs.numDofs(), freeModes.cols());
  for (Eigen::Index j = 0; j < freeModes.cols(); ++j) {
    const double norm = std::sqrt(freeModes.col(j).dot(massFree * freeModes.col(j)));
    modes.col(j) = freeDofs.expand(freeModes.col(j) / norm);
  }
  return modes;
}

}  // namespace

VibrationMatrices vibrationMatrices(const TetMesh& mesh, MassType massType) {
  if (mesh.isHexahedral()) return {hexLinearStiffnessMatrix(mesh), hexMassMatrix(mesh, massType)};
  const MatrixAssembler assembler(mesh);
  VibrationMatrices matrices;
  matrices.stiffness = linearStiffnessMatrix(mesh, assembler);
  matrices.mass = massMatrix(mesh, assembler, massType);
  return matrices;
}

struct LowestModesSolver::State {
  State(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass, const FreeDofs& dofs,
        const ModalOptions& modalOptions)
      : options(modalOptions),
        freeDofs(dofs),
        stiffnessFree(SubmatrixExtractor(stiffness, dofs.freeToFull(), dofs.freeToFull()).extract(stiffness)),
        massFree(SubmatrixExtractor(mass, dofs.freeToFull(), dofs.freeToFull()).extract(mass)),
        sigma(std::isnan(modalOptions.shift) ? defaultShift(stiffnessFree, massFree) : modalOptions.shift),
        shiftInvert(stiffnessFree, massFree, modalOptions.solver),
        massProduct(massFree) {}
  ModalOptions options;
  FreeDofs freeDofs;
  Eigen::SparseMatrix<double> stiffnessFree, massFree;
  double sigma;
  ShiftInvertOperator shiftInvert;
  MassOperator massProduct;
};

LowestModesSolver::LowestModesSolver(const Eigen::SparseMatrix<double>& stiffness,
                                     const Eigen::SparseMatrix<double>& mass, const FreeDofs& freeDofs,
                                     const ModalOptions& options) {
  checkModalProblem(stiffness, mass, freeDofs, options);
  state_ = std::make_unique<State>(stiffness, mass, freeDofs, options);
  if (!std::isfinite(state_->sigma)) throw ValidationError("modal analysis: the shift must be finite");
  state_->shiftInvert.set_shift(state_->sigma);
}

LowestModesSolver::~LowestModesSolver() = default;

int LowestModesSolver::numFree() const { return state_->freeDofs.numFree(); }
double LowestModesSolver::shift() const { return state_->sigma; }
double LowestModesSolver::factorSeconds() const { return state_->shiftInvert.factorSeconds(); }
int LowestModesSolver::operatorApplications() const { return state_->shiftInvert.applications(); }

ModalResult LowestModesSolver::compute(int count) const {
  const int numFree = state_->freeDofs.numFree();
  checkModeCount(count, numFree);
  Stopwatch total;
  const int applicationsBefore = state_->shiftInvert.applications();
  // Lanczos basis: at least 2K + 1 vectors (Spectra's advice) and some slack for clusters
  // such as the six rigid modes, never more than the problem size.
  const int basisSize = std::min(numFree, std::max(2 * count + 1, count + 20));
  using Solver = Spectra::SymGEigsShiftSolver<ShiftInvertOperator, MassOperator, Spectra::GEigsMode::ShiftInvert>;
  // The operator is factored already at this shift: set_shift() keeps the factor.
  Solver eigs(state_->shiftInvert, state_->massProduct, count, basisSize, state_->sigma);
  eigs.init();  // Spectra's fixed-seed start vector: results are reproducible
  const Eigen::Index converged = eigs.compute(Spectra::SortRule::LargestMagn, state_->options.maxIterations,
                                              state_->options.tolerance, Spectra::SortRule::SmallestAlge);
  if (eigs.info() != Spectra::CompInfo::Successful) {
    throw NumericalError("modal analysis: the Lanczos iteration converged for " + std::to_string(converged) + " of " +
                         std::to_string(count) + " modes after " + std::to_string(eigs.num_iterations()) +
                         " restarts (shift " + std::to_string(state_->sigma) +
                         "); ask for fewer modes, more iterations or a looser tolerance");
  }
  ModalResult result;
  result.shift = state_->sigma;
  result.eigenvalues = eigs.eigenvalues();
  result.frequencies = result.eigenvalues.cwiseMax(0.0).cwiseSqrt();
  result.modes = massNormalizedModes(eigs.eigenvectors(), state_->massFree, state_->freeDofs);
  result.iterations = static_cast<int>(eigs.num_iterations());
  result.operatorApplications = state_->shiftInvert.applications() - applicationsBefore;
  result.solveSeconds = total.stop();
  return result;
}

ModalResult lowestModes(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
                        const FreeDofs& freeDofs, const ModalOptions& options) {
  checkModalProblem(stiffness, mass, freeDofs, options);
  checkModeCount(options.count, freeDofs.numFree());
  Stopwatch total;
  const LowestModesSolver solver(stiffness, mass, freeDofs, options);
  ModalResult result = solver.compute(options.count);
  result.factorSeconds = solver.factorSeconds();
  result.solveSeconds = total.stop();
  return result;
}

}  // namespace asyncfem
