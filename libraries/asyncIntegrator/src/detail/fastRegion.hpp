// SPDX-License-Identifier: BSD-3-Clause
// One fast region S_i of the asynchronous integrator: its blocks, the factor of A^S, the
// forward substitution with H^{SS}, Z and the Schur correction C_i. Names as in
// docs/asynchronous-integrator.md ("I" is the interface subset of L, the only L DOFs the
// coupling blocks touch). Private to the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <asyncfem/asyncIntegrator/asyncOptions.hpp>
#include <asyncfem/asyncIntegrator/detail/coupling.hpp>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <memory>
#include <utility>
#include <vector>

#include "detail/sparseBlocks.hpp"

namespace asyncfem::detail {

/// One interface element of a fast region (vertices in S_i and in L): where its DOFs sit
/// among the region's interface DOFs I_i (-1 for S DOFs and fixed DOFs), and its tangent.
struct InterfaceElement {
  int element = 0;
  std::vector<int> interfaceIndex;  ///< per element-local DOF (12 on tetrahedra, 24 on hexahedra)
  Eigen::MatrixXd tangent;
};

/// The time-step-independent description of a region: its DOFs and its interface.
struct RegionLayout {
  const std::vector<int>* dofs = nullptr;           ///< free DOFs of S_i (global, ascending)
  const std::vector<int>* interfaceDofs = nullptr;  ///< I_i (global, ascending)
  int ratio = 1;                                    ///< m_i
};

class FastRegion {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double>;

  /// Cuts the mass blocks (constant) and prepares the stiffness blocks on the pattern of
  /// stiffnessPattern (3n x 3n, the force model's); solverKind factors A^S, or the dense
  /// Cholesky when the region has at most denseDofs free DOFs (AsyncOptions::denseRegionDofs).
  FastRegion(const SparseMatrix& mass, const SparseMatrix& stiffnessPattern, const RegionLayout& layout,
             SolverKind solverKind, int denseDofs = 0);

  /// K^{SS}, K^{SI}, K^{IS} of the current tangent K (3n x 3n): cut the first time, values
  /// only after.
  void updateStiffnessBlocks(const SparseMatrix& stiffness);
  /// The blocks of the current tangent K (3n x 3n, values only after the first call), the
  /// damping blocks D = alpha M + beta K, A^S = M + hS D + hS^2 K and the coupling
  /// coefficients for large step hL (seconds).
  void updateBlocks(const SparseMatrix& stiffness, double largeStep, double alpha, double beta, bool damped,
                    AsyncCoupling coupling);
  /// Numeric factorization of A^S (symbolic analysis, and the choice of a dense factor, the
  /// first time only).
  void factorize(IntegratorStats& stats);
  /// Implicit contact (docs/asynchronous-integrator.md, Eq. C2): per contacting vertex of S
  /// (positions: its three rows of S, -1 for a fixed DOF) the block P = hS^2 K_c + hS C_c
  /// in A^S and hS^2 K_c in G, in place of the blocks set before (values kept and restored
  /// exactly). Returns whether A^S changed (then it needs factorize, and Z is stale).
  /// updateBlocks drops them (it rebuilds A^S and G from K).
  bool setContactBlocks(const std::vector<std::array<int, 3>>& positions, const std::vector<Eigen::Matrix3d>& blocks,
                        const std::vector<Eigen::Matrix3d>& stiffness);
  bool hasContactBlocks() const { return !contactPositions.empty(); }
  /// y += J z for the contact blocks, J the linearized contact force's part of the step
  /// operator on S (hS^2 K_c on every substep's running sum, hS C_c on its own): column r of
  /// y gets hS^2 K_c sum_{j<=r} z_j + hS C_c z_r.
  void addContactProduct(const Eigen::MatrixXd& z, Eigen::MatrixXd& y) const;

  /// Forward substitution with H^{SS} (Eq. A13): A^S x_r = b_r + M^{SS} x_{r-1} - G sum_{i<r} x_i
  /// for the columns b_r of b (|S| x m), into x (|S| x m).
  void forwardSubstitute(const Eigen::MatrixXd& b, Eigen::MatrixXd& x);
  /// interfaceRow = sum_r E_r x_r (Eq. A7) for the columns x_r of x (|S| x m): the
  /// region's rows of H^{LS} x on its interface.
  void interfaceRowOf(const Eigen::MatrixXd& x, bool damped);
  /// massY, stiffY (and dampY) = M^{SI}, K^{SI} (D^{SI}) times yInterface.
  void couplingProducts(bool damped);
  /// Columns [first, first + width) of Z = (H^{SS})^{-1} H^{SI} with `solver` (a factor of
  /// A^S), and the same columns of C_i = H^{IS} Z (Eq. A7), of Z_m and of sum_r Z_r
  /// (dense recovery).
  /// block: which of the concurrent column blocks (its own scratch, kept between rebuilds).
  void correctionColumns(SparseSolver& solver, bool damped, Eigen::Index first, Eigen::Index width, int block);
  /// C_i (and Z_m, sum_r Z_r with dense recovery) from the region's modes instead of m |I_i|
  /// substitutions: with K^{SS} Phi = M^{SS} Phi Lambda (Phi^T M^{SS} Phi = I, one dense
  /// generalized eigendecomposition), A^S, M^{SS} and G are diagonal in Phi, so each mode's
  /// substeps follow a scalar recurrence, and Z = Phi (W_M Phi^T M^{SI} + W_K Phi^T K^{SI})
  /// with per-mode weights W (docs/asynchronous-integrator.md, "Z from the region's modes").
  /// Returns false, changing nothing, where that does not hold or fails: contact blocks in
  /// A^S, K^{SS} not symmetric to 1e-13, the eigensolver's failure.
  bool correctionFromModes(bool damped);
  /// The price, in flops, of Z by substitution (m |I| solves with A^S and products with G)
  /// and from the modes (the eigendecomposition, about 9 |S|^3, and the dense products).
  double substitutionPrice() const;
  double modalPrice() const;
  /// K_I^{II}: the interface elements' tangent on I x I (dense), with each element's
  /// tangent from the force model at u when perElement (else the cached linear ones).
  void assembleInterfaceStiffness(const ForceModel& forceModel, const Eigen::VectorXd& u, bool perElement);

  int ratio = 1;
  double smallStep = 0.0;  // hS
  // AsyncOptions::Processes::regionDistribution: whether this process computes the region (its
  // factor, Z, C_i, substitutions, recovery); the blocks are cut on every process.
  bool owned = true;
  // Flops of one forward substitution (m solves with A^S and m products with G), from the
  // owner's factor: what the rent-or-buy rules price.
  double substitutionFlops = 0.0;
  SubmatrixExtractor massSS, massSI, massIS, stiffSS, stiffSI, stiffIS;
  SparseMatrix Mss, Kss, Dss, Msi, Ksi, Dsi, Mis, Kis, Dis;
  bool cut = false;           // K blocks extracted once; later only their values are updated
  SparseMatrix systemMatrix;  // A^S = M + hS D + hS^2 K
  SparseMatrix G;             // hS^2 K^{SS}
  CouplingCoefficients coupling;
  // Stable coupling: the interface elements and K_I^{II}, their stiffness on I x I (dense).
  std::vector<InterfaceElement> interfaceElements;
  Eigen::MatrixXd interfaceStiffness;
  SparseMatrix GT;  // G^T, for products with many columns held row-wise
  // Where the region works dense rather than sparse.
  struct DenseChoices {
    bool factor = false;      // the region is small: A^S factored dense, G multiplied dense
    bool recovery = false;    // RecoveryMode::denseZ: Z_m and sum_r Z_r stored (zLast, zSum)
    bool trackReach = false;  // with recovery: the certificate's reach of Z (below)
  } dense;
  Eigen::MatrixXd Gdense;  // G (dense.factor only)
  // Implicit contact's blocks (setContactBlocks): positions in S, P = hS^2 K_c + hS C_c,
  // Gc = hS^2 K_c, and what the substitution's M^{SS} x_{r-1} shortcut misses with them in
  // A^S and G: Q = rhsWeight (beta / hS Gc - (P - Gc)), added as Q x_{r-1}.
  std::vector<std::array<int, 3>> contactPositions;
  std::vector<Eigen::Matrix3d> contactBlocks, contactStiffness, contactShortcut;
  // The previous substep's solve gives M^{SS} x_{r-1} for free: A^S = (1 + hS alpha) M^{SS}
  // + (1 + beta / hS) G, so M^{SS} x_{r-1} = (rhs_{r-1} - (1 + beta / hS) G x_{r-1}) / (1 +
  // hS alpha), and substep r's right-hand side b_r + M^{SS} x_{r-1} - G sum_{i<r} x_i needs
  // one product with G: rhsWeight rhs_{r-1} + b_r - G (stepWeight x_{r-1} + sum_{i<r} x_i).
  double rhsWeight = 1.0, stepWeight = 1.0;
  std::unique_ptr<SparseSolver> solver;
  bool analyzed = false;
  // Copies of the A^S factor for the column blocks of Z computed on other threads.
  std::vector<std::unique_ptr<SparseSolver>> helperSolvers;
  std::vector<char> helperAnalyzed;
  Eigen::MatrixXd zLast, zSum;  // Z_m and sum_r Z_r, |S| x q (dense recovery only)
  // Implicit contact's certificate (Eq. C6), with dense recovery: reach(k) bounds row k of
  // hS sum_{j<=r} Z_j in 2-norm over every r, so that a substep's displacement differs
  // from the substitution of b^S alone by at most reach(k) |Y_I|_2 in that DOF
  // (dense.trackReach).
  Eigen::VectorXd reach;
  Eigen::MatrixXd correction;  // C_i = H^{IS} Z, q x q
  // Per-step buffers, sized once: no allocation in a steady-state step.
  Eigen::MatrixXd rhs;                   // |S| x m, column r - 1 = b_r
  Eigen::MatrixXd external;              // |S| x m, f_ext on S at the substeps
  Eigen::MatrixXd y, x;                  // forward substitutions of b and of b - H^{SL} Y
  Eigen::MatrixXd probe, probeSolution;  // H^{SL} y and its forward substitution (applySchur)
  Eigen::MatrixXd probeSum;              // the substitution of H^{SL} Y, summed along a lagged solve
  Eigen::VectorXd runningStiffness, substepRhs, combined;
  Eigen::MatrixXd substepSolution;
  Eigen::VectorXd weightedM, weightedD, weightedK, interfaceRow;  // Eq. (A7)
  Eigen::VectorXd yInterface, massY, stiffY, dampY;
  Eigen::VectorXd ySum, xLast, xSum;
  bool substituted = false;  // x holds every substep (observer, substitution recovery)
  /// Work matrices of one column block of Z (|S| x width or width x |S|), kept between
  /// rebuilds: a nonlinear run rebuilds every few steps, and fresh ones of several MiB each
  /// time cost page faults (8% of the dinosaur's corotational steps).
  struct ColumnScratch {
    Eigen::MatrixXd rhsColumns, z, combinedT, productT, runningT, sumM, sumK, sumD, sum, columns;
    Eigen::VectorXd reach;  // max over r of the squared row norms of this block's sum_{j<=r} Z_j
  };
  std::vector<ColumnScratch> columnScratch;  // one per column block

 private:
  /// Replaces the sparse solver by the dense one where that is cheaper (see factorize).
  void chooseDenseFactor();
  /// out -= G t for one column t (|S| entries), row by row through G^T (by 3 x 3 blocks
  /// where blockG_ holds them).
  void subtractStiffnessProduct(const double* t, double* out) const;
  /// G^T again after transposeInto: blockG_ taken anew where G's pattern changed, its
  /// values copied always.
  void refreshTranspose();
  /// outT = (G t)^T for tT = t^T (k x |S|), vectorized across the k columns.
  void rowWiseStiffnessProduct(const Eigen::MatrixXd& tT, Eigen::MatrixXd& outT) const;

  /// out += Q t (the contact blocks' correction of the substitution shortcut) for one column.
  void addShortcutCorrection(const double* t, double* out) const;

  int denseDofs_ = 0;
  double alpha_ = 0.0, beta_ = 0.0;
  // A^S = massWeight_ M^{SS} + stiffnessWeight_ K^{SS} (without contact blocks).
  double massWeight_ = 1.0, stiffnessWeight_ = 0.0;
  KeptEntries contactSaved_;  // A^S and G entries the contact blocks changed, and their values before
  bool denseDecided_ = false;
  TransposePattern gtPattern_;  // G's pattern and where GT's entries come from
  /// G by 3 x 3 blocks, when every row triple 3b, 3b + 1, 3b + 2 of G has one pattern made
  /// of column triples (a region whose vertices have all three DOFs free): per block row b
  /// its blocks start[b] .. start[b + 1] - 1, each at column triple column[k], values row by
  /// row. The product then reads each index once per block instead of once per entry, and
  /// sums every row in the order of G^T's entries (the same result to the bit). Empty
  /// otherwise.
  struct BlockRows {
    std::vector<int> start, column;
    std::vector<double> values;
  } blockG_;
};

/// What one computation of Z over every region did.
struct CorrectionRun {
  int threads = 1;        ///< most A^S factor copies one region used
  long long columns = 0;  ///< right-hand sides: sum_i m_i |I_i| over the regions substituted
  int modalRegions = 0;   ///< regions whose C_i came from their modes (FastRegion::correctionFromModes)
  long long helperFactorizations = 0;
};

/// Z and the Schur corrections of every region (recovery mode chosen per region). The
/// columns of Z are independent: each region's are split into blocks, one per thread, each
/// solved with its own copy of the A^S factor, since one solver object is not thread-safe.
/// Regions this process does not own get C_i = 0 (their owner's is summed in later).
CorrectionRun computeCorrections(std::vector<FastRegion>& regions, const AsyncOptions& options, bool damped);

}  // namespace asyncfem::detail
