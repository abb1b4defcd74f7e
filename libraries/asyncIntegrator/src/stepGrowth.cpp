// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <asyncfem/asyncIntegrator/stepGrowth.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <chrono>
#include <cmath>
#include <complex>
#include <random>
#include <vector>

namespace asyncfem {

namespace {

Eigen::SparseMatrix<double> restStiffness(ForceModel& forceModel, int numDofs) {
  Eigen::SparseMatrix<double> stiffness = forceModel.createStiffnessMatrix();
  forceModel.tangentStiffness(Eigen::VectorXd::Zero(numDofs), stiffness);
  return stiffness;
}

/// The energy inner product on stacked states [u; v] (size 2n).
class EnergyProduct {
 public:
  EnergyProduct(const DynamicSystem& system, double timestep)
      : n_(system.numDofs()), mass_(system.mass), stiffness_(restStiffness(*system.forceModel, system.numDofs())) {
    // A rigid displacement of an unfixed body has no elastic energy; weight it as a
    // spring of frequency 1e-5 / h, far below any mode a step resolves.
    const double frequency = 1e-5 / timestep;
    stiffness_ += frequency * frequency * mass_;
  }
  double operator()(const Eigen::VectorXd& x, const Eigen::VectorXd& y) const {
    return x.tail(n_).dot(mass_ * y.tail(n_)) + x.head(n_).dot(stiffness_ * y.head(n_));
  }
  double norm(const Eigen::VectorXd& x) const { return std::sqrt(std::max(0.0, (*this)(x, x))); }

 private:
  int n_;
  Eigen::SparseMatrix<double> mass_;
  Eigen::SparseMatrix<double> stiffness_;
};

/// A random start, its u and v parts scaled to equal energy so that neither dominates.
Eigen::VectorXd randomStart(const DynamicSystem& system, const EnergyProduct& product, unsigned seed) {
  const int n = system.numDofs();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd u(n), v(n);
  for (int i = 0; i < n; ++i) u[i] = uniform(rng);
  for (int i = 0; i < n; ++i) v[i] = uniform(rng);
  for (int i = 0; i < n; ++i) {
    if (system.freeDofs.isFixed(i)) u[i] = v[i] = 0.0;
  }
  Eigen::VectorXd zero = Eigen::VectorXd::Zero(n), state(2 * n);
  state << u, zero;
  const double displacementNorm = product.norm(state);
  state << zero, v;
  const double velocityNorm = product.norm(state);
  if (!(displacementNorm > 0.0) || !(velocityNorm > 0.0)) throw Error("estimateStepGrowth: the system has no free DOF");
  state << u / displacementNorm, v / velocityNorm;
  return state;
}

/// The Arnoldi factorization of the step map from start, in the energy product.
struct Arnoldi {
  Eigen::MatrixXd hessenberg;    // (k + 1) x k
  int used = 0;                  // columns filled
  double lastSubdiagonal = 0.0;  // 0 when the Krylov space is invariant
};

/// Arnoldi with classical Gram-Schmidt applied twice (orthogonal to round-off), up to k
/// columns, stopping early when the Krylov space is invariant (its Ritz values are then
/// eigenvalues).
template <class Apply>
Arnoldi arnoldi(const Apply& apply, const EnergyProduct& product, const Eigen::VectorXd& start, int k) {
  Arnoldi result;
  result.hessenberg = Eigen::MatrixXd::Zero(k + 1, k);
  std::vector<Eigen::VectorXd> basis;
  basis.push_back(start / product.norm(start));
  for (int j = 0; j < k; ++j) {
    Eigen::VectorXd w = apply(basis[static_cast<std::size_t>(j)]);
    const double imageNorm = product.norm(w);
    for (int pass = 0; pass < 2; ++pass) {
      for (int i = 0; i <= j; ++i) {
        const double coefficient = product(basis[static_cast<std::size_t>(i)], w);
        result.hessenberg(i, j) += coefficient;
        w -= coefficient * basis[static_cast<std::size_t>(i)];
      }
    }
    result.used = j + 1;
    result.lastSubdiagonal = product.norm(w);
    result.hessenberg(j + 1, j) = result.lastSubdiagonal;
    if (result.lastSubdiagonal <= 1e-12 * imageNorm) {
      result.lastSubdiagonal = 0.0;
      break;
    }
    basis.push_back(w / result.lastSubdiagonal);
  }
  return result;
}

/// The dominant Ritz value of the factorization: spectral radius and its residual.
void dominantRitzValue(const Arnoldi& factorization, double tolerance, StepGrowthEstimate& estimate) {
  const int used = factorization.used;
  const Eigen::EigenSolver<Eigen::MatrixXd> eigen(factorization.hessenberg.topLeftCorner(used, used));
  if (eigen.info() != Eigen::Success) throw NumericalError("estimateStepGrowth: the Hessenberg eigenproblem failed");
  Eigen::Index dominant = 0;
  eigen.eigenvalues().cwiseAbs().maxCoeff(&dominant);
  const std::complex<double> ritzValue = eigen.eigenvalues()[dominant];
  const Eigen::VectorXcd ritzVector = eigen.eigenvectors().col(dominant).normalized();
  estimate.spectralRadius = std::abs(ritzValue);
  estimate.residual = estimate.spectralRadius > 0.0
                          ? factorization.lastSubdiagonal * std::abs(ritzVector[used - 1]) / estimate.spectralRadius
                          : factorization.lastSubdiagonal;
  estimate.converged = estimate.residual <= tolerance;
  estimate.krylovDimension = used;
}

}  // namespace

StepGrowthEstimate estimateStepGrowth(Integrator& integrator, const StepGrowthOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const DynamicSystem& system = integrator.system();
  if (system.externalForce || !system.forceModel->isLinear()) {
    throw Error("estimateStepGrowth: the " + integrator.name() +
                " integrator's system has an external force or a nonlinear force model, so its step is not a linear "
                "map of the state (use homogeneousLinearSystem())");
  }
  if (options.krylovDimension < 1) throw Error("estimateStepGrowth: krylovDimension must be >= 1");
  const int n = system.numDofs();
  const Eigen::VectorXd savedDisplacement = integrator.displacement(), savedVelocity = integrator.velocity();
  const Eigen::VectorXd savedInternal = integrator.internalState();
  const double savedTime = integrator.time();
  const EnergyProduct product(system, integrator.timestep());

  StepGrowthEstimate estimate;
  auto apply = [&](const Eigen::VectorXd& state) {
    integrator.setState(state.head(n), state.tail(n), savedTime);
    integrator.step();
    ++estimate.steps;
    Eigen::VectorXd out(2 * n);
    out << integrator.displacement(), integrator.velocity();
    return out;
  };
  const Arnoldi factorization =
      arnoldi(apply, product, randomStart(system, product, options.seed), options.krylovDimension);
  integrator.setState(savedDisplacement, savedVelocity, savedTime);
  integrator.setInternalState(savedInternal);
  dominantRitzValue(factorization, options.tolerance, estimate);
  estimate.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return estimate;
}

DynamicSystem homogeneousLinearSystem(const DynamicSystem& system) {
  DynamicSystem out = system;
  out.externalForce = nullptr;
  out.externalForceJacobian = nullptr;
  out.externalForceAt = nullptr;
  out.externalForceOfRank = nullptr;
  out.externalForceJacobianAt = nullptr;
  out.stateDependentOnlyInContact = false;
  if (!system.forceModel->isLinear()) {
    out.forceModel = std::make_shared<LinearForceModel>(restStiffness(*system.forceModel, system.numDofs()));
  }
  return out;
}

}  // namespace asyncfem
