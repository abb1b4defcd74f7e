// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <limits>
#include <string>
#include <vector>

namespace asyncfem {

/// An external force that is constant between breakpoints, plus impulses: the loads scenes
/// can describe (gravity, pulls with windows, impulses; docs/scene-format.md).
struct PiecewiseConstantLoad {
  /// Times at which the force changes, strictly ascending, all > 0.
  std::vector<double> breakpoints;
  /// breakpoints.size() + 1 full (3n) force vectors: forces[0] acts on [0, breakpoints[0]),
  /// forces[k] on [breakpoints[k-1], breakpoints[k]), the last one for ever. Empty vectors
  /// (size 0) stand for zero.
  std::vector<Eigen::VectorXd> forces;
  /// An instantaneous change of momentum: the velocity jumps by M^{-1} impulse at time.
  struct Impulse {
    double time = 0.0;
    Eigen::VectorXd impulse;  ///< full (3n), force x time
  };
  std::vector<Impulse> impulses;
};

/// Advances one damped oscillator q'' + c q' + lambda q = p (p constant) by duration
/// tau >= 0, exactly: with x = q - p / lambda the homogeneous state (x, q') evolves by
/// exp(A tau), A = [0 1; -lambda -c], evaluated in closed form as
///
///     exp(A tau) = e^{-mu tau} ( cosh(g tau) I + sinh(g tau) / g (A + mu I) ),
///     mu = c / 2,  g^2 = mu^2 - lambda,
///
/// which covers underdamped (g imaginary: cos, sin(w tau)/w), critically damped (g = 0:
/// 1, tau) and overdamped (g real; e^{-mu tau} cosh and sinh are formed as sums of
/// e^{(g - mu) tau} and e^{-(g + mu) tau} with g - mu = -lambda / (mu + g), so heavily
/// damped modes neither overflow nor lose their slow root). lambda <= 0 is treated as a
/// rigid mode (lambda = 0): q' = q'_0 e^{-c tau} + p (1 - e^{-c tau}) / c and its integral
/// (c = 0: uniform acceleration). Units: lambda in 1/s^2, c in 1/s, p in units of q/s^2.
void advanceDampedOscillator(double lambda, double damping, double force, double duration, double& position,
                             double& rate);

/// The exact solution of a linear FEM body with Rayleigh damping,
///
///     M u'' + (alpha M + beta K) u' + K u = f(t),   fixed DOFs held at 0,
///
/// by modal decomposition on the free DOFs: the dense generalized eigenproblem
/// K phi = lambda M phi (M-orthonormal phi) decouples it into oscillators
/// q_j'' + (alpha + beta lambda_j) q_j' + lambda_j q_j = phi_j^T f(t), each advanced exactly
/// between breakpoints of a PiecewiseConstantLoad by advanceDampedOscillator (impulses add
/// phi_j^T I to q_j'). Exact up to the round-off of the eigendecomposition; no modal
/// truncation.
///
/// Cost: O(n^3) time and O(n^2) memory for n free DOFs (4410 DOFs: about 10 s with
/// LAPACK, several minutes with the Eigen fallback; 150 MB per dense matrix): intended for meshes up to a few thousand
/// free DOFs. Not covered: nonlinear (corotational) forces, state-dependent forces (contact), loads that vary
/// continuously in time; use a fine-step reference run for those.
class ModalReference {
 public:
  /// mass, stiffness: full 3n x 3n symmetric (M positive definite on the free DOFs);
  /// alpha, beta >= 0. Throws asyncfem::NumericalError when the eigendecomposition fails
  /// (M not positive definite on the free DOFs).
  ModalReference(const Eigen::SparseMatrix<double>& mass, const Eigen::SparseMatrix<double>& stiffness,
                 const FreeDofs& freeDofs, double alpha, double beta);

  /// The dense eigensolver in use: "LAPACK dsygvd" when the build found LAPACK, else
  /// "Eigen GeneralizedSelfAdjointEigenSolver".
  static std::string backend();

  int numFree() const { return static_cast<int>(eigenvalues_.size()); }
  /// lambda_j = omega_j^2, ascending (1/s^2).
  const Eigen::VectorXd& eigenvalues() const { return eigenvalues_; }

  /// Full (3n) displacements at the given times (ascending, >= 0), starting at t = 0 from
  /// (initialDisplacement, initialVelocity) (full vectors; empty means zero). Throws
  /// asyncfem::Error for unsorted or negative times or wrong sizes. An impulse at exactly a
  /// requested time is applied after that time's displacement is recorded.
  std::vector<Eigen::VectorXd> displacements(const PiecewiseConstantLoad& load, const std::vector<double>& times,
                                             const Eigen::VectorXd& initialDisplacement = {},
                                             const Eigen::VectorXd& initialVelocity = {}) const;

  /// Modal coordinates q = Phi^T M u of a full (3n) displacement (its free part): the
  /// amplitude of every mode, in the order of eigenvalues(). Throws asyncfem::Error for a
  /// wrong size.
  Eigen::VectorXd modalCoordinates(const Eigen::VectorXd& displacement) const;

 private:
  FreeDofs freeDofs_;
  Eigen::SparseMatrix<double> freeMass_;
  Eigen::VectorXd eigenvalues_;
  Eigen::MatrixXd modes_;  // free x free, columns M-orthonormal
  double alpha_ = 0.0, beta_ = 0.0;
};

/// Motion kept per frequency band: for the modes with omega_j = sqrt(lambda_j) in
/// [bandEdges[b], bandEdges[b + 1]) (the last band is open above), the RMS over frames and
/// modes of the run's modal coordinates divided by the reference's,
///
///     sqrt( sum_k sum_{j in band} q_j(u_k)^2 ) / sqrt( sum_k sum_{j in band} q_j(r_k)^2 ),
///
/// on frames 0 .. min(run, reference) - 1. 1 means the band keeps the exact amount of
/// motion; below 1 is artificial damping, above 1 spurious excitation. Insensitive to
/// phase, so it complements relativeL2Error: it measures what the paper calls retained
/// motion. A band without modes or without reference motion gives NaN. bandEdges:
/// ascending, first >= 0.
struct ModalBand {
  double lowOmega = 0.0, highOmega = 0.0;  ///< rad/s; highOmega = inf for the last band
  int modes = 0;
  double kept = 0.0;  ///< run / reference RMS (NaN when undefined)
};
std::vector<ModalBand> motionKeptPerBand(const ModalReference& modal, const std::vector<Eigen::VectorXd>& run,
                                         const std::vector<Eigen::VectorXd>& reference,
                                         const std::vector<double>& bandEdges);

/// The same from modal coordinates already computed (modalTrajectory), so a reference
/// compared with many runs is projected once; eigenvalues: ModalReference::eigenvalues().
std::vector<ModalBand> motionKeptPerBand(const Eigen::VectorXd& eigenvalues,
                                         const std::vector<Eigen::VectorXd>& runModal,
                                         const std::vector<Eigen::VectorXd>& referenceModal,
                                         const std::vector<double>& bandEdges);

/// modalCoordinates of every frame of a trajectory.
std::vector<Eigen::VectorXd> modalTrajectory(const ModalReference& modal, const std::vector<Eigen::VectorXd>& run);

}  // namespace asyncfem
