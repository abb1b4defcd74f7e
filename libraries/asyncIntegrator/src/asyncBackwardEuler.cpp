// SPDX-License-Identifier: BSD-3-Clause
// Asynchronous implicit backward Euler. Equation numbers (A1)-(A12) refer to
// docs/asynchronous-integrator.md, section "Method".
#include <omp.h>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include "detail/multirateSupport.hpp"

namespace asyncfem {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

/// Largest dense Z (doubles) the automatic recovery stores: 16M doubles = 128 MiB.
constexpr double kMaxDenseZEntries = 16.0 * 1024 * 1024;
/// Largest W = (A^L)^{-1} U (doubles) the low-rank Schur form stores: 64M = 512 MiB.
constexpr double kMaxLowRankEntries = 64.0 * 1024 * 1024;

using detail::gather;
using detail::updateBlock;

/// Appends the entries of block, shifted by (rowOffset, colOffset), to triplets; with a
/// column map, block column c goes to colOffset + columnMap[c] (and likewise rows).
void appendTriplets(const SparseMatrix& block, double scale, int rowOffset, int colOffset,
                    std::vector<Eigen::Triplet<double>>& triplets, const std::vector<int>* rowMap = nullptr,
                    const std::vector<int>* columnMap = nullptr) {
  for (int c = 0; c < block.outerSize(); ++c) {
    for (SparseMatrix::InnerIterator it(block, c); it; ++it) {
      const int row = rowMap ? (*rowMap)[static_cast<std::size_t>(it.row())] : static_cast<int>(it.row());
      const int col = columnMap ? (*columnMap)[static_cast<std::size_t>(c)] : c;
      triplets.emplace_back(rowOffset + row, colOffset + col, scale * it.value());
    }
  }
}

/// Address of the stored entry (row, column) of a compressed matrix, or nullptr.
double* findEntry(SparseMatrix& matrix, int row, int column) {
  const int* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column];
  const int* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column + 1];
  const int* it = std::lower_bound(begin, end, row);
  if (it == end || *it != row) return nullptr;
  return matrix.valuePtr() + (it - matrix.innerIndexPtr());
}

/// Column c of a compressed matrix dotted with x (row c of K x when K is symmetric).
double columnDot(const SparseMatrix& matrix, int column, const Eigen::VectorXd& x) {
  const int* inner = matrix.innerIndexPtr();
  const double* values = matrix.valuePtr();
  double sum = 0.0;
  for (int k = matrix.outerIndexPtr()[column]; k < matrix.outerIndexPtr()[column + 1]; ++k)
    sum += values[k] * x[inner[k]];
  return sum;
}

/// Whether x and y are compressed with identical patterns.
bool samePattern(const SparseMatrix& x, const SparseMatrix& y) {
  return x.rows() == y.rows() && x.cols() == y.cols() && x.isCompressed() && y.isCompressed() &&
         x.nonZeros() == y.nonZeros() &&
         std::equal(x.outerIndexPtr(), x.outerIndexPtr() + x.outerSize() + 1, y.outerIndexPtr()) &&
         std::equal(x.innerIndexPtr(), x.innerIndexPtr() + x.nonZeros(), y.innerIndexPtr());
}

/// out = a A + b B. When A and B share one pattern (blocks cut from M and K, which the
/// assembler builds on one pattern) only values are written, into out's storage if it
/// already has that pattern; otherwise Eigen's general sum.
void combineInto(double a, const SparseMatrix& A, double b, const SparseMatrix& B, SparseMatrix& out) {
  if (!samePattern(A, B)) {
    out = a * A + b * B;
    out.makeCompressed();
    return;
  }
  if (!samePattern(out, A)) out = A;
  const double* av = A.valuePtr();
  const double* bv = B.valuePtr();
  double* ov = out.valuePtr();
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k) ov[k] = a * av[k] + b * bv[k];
}

/// The scalar coefficients of the coupling blocks of one fast region, Eqs. (A5)-(A6) and
/// (A9)-(A10), for r, i = 1..m (entry r - 1, i - 1):
///   B_r = bM[r] M^{SI} + bD[r] D^{SI} + bK[r] K^{SI}     (S row r, coefficient of Y)
///   E_i = eM[i] M^{IS} + eD[i] D^{IS} + eK[i] K^{IS}     (L row, coefficient of X_i)
/// and interfaceWeight = (1 - theta) hL^2, the share of the interface elements' stiffness
/// taken out of A^L (Eq. A11; 0 for the paper's coupling).
struct CouplingCoefficients {
  Eigen::VectorXd bM, bD, bK, eM, eD, eK;
  double interfaceWeight = 0.0;
};

CouplingCoefficients couplingCoefficients(AsyncCoupling coupling, int m, double hL) {
  const double hS = hL / m;
  CouplingCoefficients c;
  for (Eigen::VectorXd* v : {&c.bM, &c.bD, &c.bK, &c.eM, &c.eD, &c.eK}) v->setZero(m);
  for (int r = 1; r <= m; ++r) {
    const Eigen::Index k = r - 1;
    if (coupling == AsyncCoupling::paper) {
      // L's velocity interpolated linearly, u^L_r = u^L_0 + r hS v^L_r; the interface force
      // on L taken at the end of the step (Eqs. A5, A6).
      c.bM[k] = 1.0 / m;
      c.bD[k] = r * hS / m;
      c.bK[k] = double(r) * r * hS * hS / m;
      c.eK[k] = hL * hS;
      if (r == m) {
        c.eM[k] = 1.0;
        c.eD[k] = hL;
      }
    } else {
      // L at its end-of-step velocity from the first substep on, the interface elements'
      // force on L averaged over the substeps (Eqs. A9, A10).
      c.bM[k] = r == 1 ? 1.0 : 0.0;
      c.bD[k] = hS;
      c.bK[k] = r * hS * hS;
      c.eD[k] = hS;
      c.eK[k] = (m - r + 1) * hS * hS;
      if (r == m) c.eM[k] = 1.0;
    }
  }
  if (coupling == AsyncCoupling::stable) {
    const double theta = (m + 1.0) / (2.0 * m);
    c.interfaceWeight = (1.0 - theta) * hL * hL;
  }
  return c;
}

/// One interface element of a fast region (vertices in S_i and in L): where its DOFs sit
/// among the region's interface DOFs I_i (-1 for S DOFs and fixed DOFs), and its tangent.
struct InterfaceElement {
  int element = 0;
  std::array<int, 12> interfaceIndex{};
  Eigen::Matrix<double, 12, 12> tangent;
};

/// Blocks of one fast region S_i (rows/columns named as in docs/asynchronous-integrator.md;
/// "I" is the interface subset of L, the only L DOFs the coupling blocks touch).
struct RegionBlocks {
  int ratio = 1;
  double smallStep = 0.0;  // hS
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
  bool useDenseZ = false;
  Eigen::MatrixXd zLast, zSum;  // Z_m and sum_r Z_r, |S| x q (dense recovery only)
  Eigen::MatrixXd correction;   // C_i = H^{IS} Z, q x q
  // Per-step buffers, sized once: no allocation in a steady-state step.
  Eigen::MatrixXd rhs;                   // |S| x m, column r - 1 = b_r
  Eigen::MatrixXd external;              // |S| x m, f_ext on S at the substeps
  Eigen::MatrixXd y, x;                  // forward substitutions of b and of b - H^{SL} Y
  Eigen::MatrixXd probe, probeSolution;  // H^{SL} y and its forward substitution (applySchur)
  Eigen::VectorXd runningStiffness, substepRhs, combined;
  Eigen::MatrixXd substepSolution;
  Eigen::VectorXd weightedM, weightedD, weightedK, interfaceRow;  // Eq. (A7) on y
  Eigen::VectorXd yInterface, massY, stiffY, dampY;
  Eigen::VectorXd ySum, xLast, xSum;
  bool substituted = false;  // x holds every substep (observer, substitution recovery)
  std::exception_ptr failure;
};

/// The weighted sums sum_r w_r x_r of Eq. (A7) for the columns x_1..x_m of x.
void weightedColumnSum(const Eigen::MatrixXd& x, const Eigen::VectorXd& weights, Eigen::VectorXd& out) {
  out.noalias() = x * weights;
}

/// out -= G t for one column t (|S| entries), scattered column by column.
void subtractStiffnessProduct(const RegionBlocks& rb, const double* t, double* out) {
  const int* outer = rb.G.outerIndexPtr();
  const int* inner = rb.G.innerIndexPtr();
  const double* values = rb.G.valuePtr();
  const Eigen::Index size = rb.G.outerSize();
  for (Eigen::Index column = 0; column < size; ++column) {
    const double tc = t[column];
    for (int k = outer[column]; k < outer[column + 1]; ++k) out[inner[k]] -= values[k] * tc;
  }
}

/// The same for many columns held row-wise: outT = (G t)^T for tT = t^T (k x |S|), column c
/// of outT a sum of length-k vector updates over column c of G^T (row c of G), which
/// vectorize across the k columns.
void rowWiseStiffnessProduct(const RegionBlocks& rb, const Eigen::MatrixXd& tT, Eigen::MatrixXd& outT) {
  const int* outer = rb.GT.outerIndexPtr();
  const int* inner = rb.GT.innerIndexPtr();
  const double* values = rb.GT.valuePtr();
  outT.setZero();
  for (Eigen::Index c = 0; c < rb.GT.outerSize(); ++c)
    for (int k = outer[c]; k < outer[c + 1]; ++k) outT.col(c) += values[k] * tT.col(inner[k]);
}

}  // namespace

struct AsyncBackwardEuler::Impl {
  double largeStep = 0.0;
  bool linear = true;
  bool built = false;              // blocks and factors valid for the current timestep (linear models)
  SparseMatrix stiffness;          // full 3n x 3n tangent K(u_0)
  bool perElementTangent = false;  // interface element tangents from the force model (else cached linear ones)
  Eigen::VectorXd internalForce;
  std::vector<RegionBlocks> regions;
  SubmatrixExtractor massLL, stiffLL;
  SparseMatrix Mll, Kll;  // M^{LL} (constant), K^{LL}
  bool cutLL = false;
  SparseMatrix largeSystem;                   // A^L
  SparseMatrix schur;                         // H^{LL*} (or its symmetric part)
  std::unique_ptr<SparseSolver> schurSolver;  // of H^{LL*} (lu, symmetric) or of A^L (lowRank)
  bool schurAnalyzed = false;
  // H^{LL*} on a fixed pattern (A^L's plus every region's dense I_i x I_i block), so a
  // rebuild only writes values: where each A^L entry and each block entry sits in it.
  bool schurPatternBuilt = false;
  std::vector<int> schurFromLarge;
  std::vector<std::vector<int>> schurFromBlock;
  // Low-rank form of H^{LL*} = A^L - U C U^T.
  std::vector<int> interfaceUnion;                   // positions in L of every region's interface DOFs
  Eigen::MatrixXd unionCorrection;                   // C, q x q
  Eigen::MatrixXd lowRankBasis;                      // W = (A^L)^{-1} U, |L| x q
  Eigen::PartialPivLU<Eigen::MatrixXd> capacitance;  // I - U^T W C
  // Naive method.
  SparseMatrix naiveSystem;
  std::unique_ptr<SparseSolver> naiveSolver;
  bool naiveAnalyzed = false;
  std::vector<int> naiveOffsets;  // first row of region i's X_1; last entry = first row of Y
  // Per-step buffers (full 3n, or |L|).
  Eigen::VectorXd stiffVelocity, massVelocity, stateForce, predicted, newU, newV, work;
  // Linear forces with a symmetric K (checked at the first build): f_int(u_0) = K u_0 and
  // K v_0 are taken row by row (row i = column i) on the DOFs that need them, and L's rows
  // need only K (u_0 + (beta + hL) v_0), as in single-rate backward Euler.
  bool symmetricStiffness = false;
  bool symmetryChecked = false;
  Eigen::VectorXd rhsL, rhsSchur, Y, lowRankRhs;
  Eigen::MatrixXd schurSolution;
  // External forces at the distinct times of one large step (shared by regions whose
  // substeps fall on the same times), valid for one step.
  std::vector<double> forceTimes;
  std::vector<Eigen::VectorXd> forceValues;
  std::size_t forcesUsed = 0;
  // Lagged Schur factor (AsyncOptions::laggedSchur).
  bool lagSchur = false, schurStale = false, schurBuilt = false, refreshNext = false;
  Eigen::VectorXd schurProduct, schurResidual, schurCorrection, schurDirection;
};

namespace {

/// Interface elements of every fast region, with their constant linear stiffness when the
/// force model has no per-element tangent (linear models built from a matrix). Then the
/// model's K must be the mesh's linear FEM stiffness, which is checked on every column of
/// an interface DOF (relative 1e-10: the same element matrices summed in another order
/// differ by round-off, ~1e-15; a different material or a scaled K differs by far more).
/// Returns whether the force model gives per-element tangents (then they are recomputed at
/// every rebuild; otherwise the cached linear ones are used).
bool findInterfaceElements(const TetMesh& mesh, const RegionPartition& partition, const DynamicSystem& system,
                           std::vector<RegionBlocks>& regions) {
  const std::vector<int>& vertexRegion = partition.vertexRegion();
  std::vector<std::vector<int>> interfaceIndex(regions.size());
  for (int i = 0; i < partition.numRegions(); ++i) {
    std::vector<int>& index = interfaceIndex[static_cast<std::size_t>(i)];
    index.assign(static_cast<std::size_t>(mesh.numDofs()), -1);
    const std::vector<int>& iface = partition.interfaceDofs(i);
    for (std::size_t k = 0; k < iface.size(); ++k) index[static_cast<std::size_t>(iface[k])] = static_cast<int>(k);
  }
  Eigen::VectorXd probe = Eigen::VectorXd::Zero(mesh.numDofs());
  Eigen::Matrix<double, 12, 12> tangent;
  const bool perElement = mesh.numElements() > 0 && system.forceModel->elementTangent(probe, 0, tangent);
  if (!perElement && !system.forceModel->isLinear()) {
    throw ValidationError(
        "async integrator: the stable coupling needs the tangent of each interface element, and this nonlinear "
        "force model gives none (ForceModel::elementTangent); use the coupling \"paper\"");
  }
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i vertices = mesh.element(e);
    int fast = -1;
    bool touchesLarge = false;
    for (int a = 0; a < 4; ++a) {
      const int region = vertexRegion[static_cast<std::size_t>(vertices[a])];
      if (region >= 0) fast = region;
      if (region < 0) touchesLarge = true;
    }
    if (fast < 0 || !touchesLarge) continue;
    InterfaceElement element;
    element.element = e;
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c)
        element.interfaceIndex[static_cast<std::size_t>(3 * a + c)] =
            interfaceIndex[static_cast<std::size_t>(fast)][static_cast<std::size_t>(3 * vertices[a] + c)];
    if (!perElement) {
      const Material& material = mesh.elementMaterial(e);
      element.tangent =
          linearElementStiffness(mesh.elementRestPositions(e), material.youngsModulus, material.poissonRatio);
    }
    regions[static_cast<std::size_t>(fast)].interfaceElements.push_back(element);
  }
  if (perElement) return true;

  // Check the matrix model against the mesh on the columns of the interface DOFs.
  Eigen::SparseMatrix<double> stiffness = system.forceModel->createStiffnessMatrix();
  system.forceModel->tangentStiffness(probe, stiffness);
  std::vector<int> columnOf(static_cast<std::size_t>(mesh.numDofs()), -1);
  std::vector<int> columns;
  for (int i = 0; i < partition.numRegions(); ++i)
    for (int dof : partition.interfaceDofs(i)) {
      if (columnOf[static_cast<std::size_t>(dof)] < 0) {
        columnOf[static_cast<std::size_t>(dof)] = static_cast<int>(columns.size());
        columns.push_back(dof);
      }
    }
  if (columns.empty()) return false;
  // Sparse 3n x |columns| blocks, so the check costs O(interface elements), not O(n |I|).
  std::vector<Eigen::Triplet<double>> meshEntries, modelEntries;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i vertices = mesh.element(e);
    bool touches = false;
    for (int a = 0; a < 4 && !touches; ++a)
      for (int c = 0; c < 3; ++c) touches = touches || columnOf[static_cast<std::size_t>(3 * vertices[a] + c)] >= 0;
    if (!touches) continue;
    const Material& material = mesh.elementMaterial(e);
    const ElementMatrix ke =
        linearElementStiffness(mesh.elementRestPositions(e), material.youngsModulus, material.poissonRatio);
    for (int q = 0; q < 12; ++q) {
      const int column = columnOf[static_cast<std::size_t>(3 * vertices[q / 3] + q % 3)];
      if (column < 0) continue;
      for (int p = 0; p < 12; ++p) meshEntries.emplace_back(3 * vertices[p / 3] + p % 3, column, ke(p, q));
    }
  }
  for (std::size_t k = 0; k < columns.size(); ++k)
    for (SparseMatrix::InnerIterator it(stiffness, columns[k]); it; ++it)
      modelEntries.emplace_back(static_cast<int>(it.row()), static_cast<int>(k), it.value());
  SparseMatrix fromMesh(mesh.numDofs(), static_cast<Eigen::Index>(columns.size()));
  SparseMatrix fromModel(fromMesh.rows(), fromMesh.cols());
  fromMesh.setFromTriplets(meshEntries.begin(), meshEntries.end());
  fromModel.setFromTriplets(modelEntries.begin(), modelEntries.end());
  const SparseMatrix differenceMatrix = fromMesh - fromModel;
  const auto largest = [](const SparseMatrix& m) {
    double value = 0.0;
    for (Eigen::Index k = 0; k < m.nonZeros(); ++k) value = std::max(value, std::abs(m.valuePtr()[k]));
    return value;
  };
  const double scale = std::max(largest(fromMesh), 1e-300);
  const double difference = largest(differenceMatrix) / scale;
  if (!(difference <= 1e-10)) {
    throw ValidationError(
        "async integrator: the stable coupling needs the stiffness of each interface element; the force model "
        "gives no per-element tangent and its K differs from the mesh's linear FEM stiffness on the interface "
        "columns (relative difference " +
        std::to_string(difference) + "): build it from this mesh, or use the coupling \"paper\"");
  }
  return false;
}

}  // namespace

AsyncBackwardEuler::AsyncBackwardEuler(const TetMesh& mesh, DynamicSystem system, double largeTimestep,
                                       std::vector<AsyncRegion> regions, AsyncOptions options)
    : Integrator(std::move(system), largeTimestep),
      partition_(mesh, system_.freeDofs, std::move(regions)),
      options_(options),
      impl_(std::make_unique<Impl>()) {
  if (mesh.numDofs() != system_.numDofs()) {
    throw ValidationError("async integrator: mesh has " + std::to_string(mesh.numDofs()) +
                          " DOFs but the dynamic system has " + std::to_string(system_.numDofs()));
  }
  Impl& d = *impl_;
  d.linear = system_.forceModel->isLinear();
  d.stiffness = system_.forceModel->createStiffnessMatrix();
  d.stiffness.makeCompressed();
  const SparseMatrix& mass = system_.mass;
  const std::vector<int>& large = partition_.largeDofs();
  d.massLL = SubmatrixExtractor(mass, large, large);
  d.stiffLL = SubmatrixExtractor(d.stiffness, large, large);
  d.regions.resize(static_cast<std::size_t>(partition_.numRegions()));
  for (int i = 0; i < partition_.numRegions(); ++i) {
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    const std::vector<int>& iface = partition_.interfaceDofs(i);
    rb.ratio = partition_.ratio(i);
    rb.massSS = SubmatrixExtractor(mass, s, s);
    rb.massSI = SubmatrixExtractor(mass, s, iface);
    rb.massIS = SubmatrixExtractor(mass, iface, s);
    rb.stiffSS = SubmatrixExtractor(d.stiffness, s, s);
    rb.stiffSI = SubmatrixExtractor(d.stiffness, s, iface);
    rb.stiffIS = SubmatrixExtractor(d.stiffness, iface, s);
    rb.Mss = rb.massSS.extract(mass);
    rb.Msi = rb.massSI.extract(mass);
    rb.Mis = rb.massIS.extract(mass);
    rb.solver = makeSparseSolver(options_.regionSolver);
  }
  if (options_.coupling == AsyncCoupling::stable) {
    d.perElementTangent = findInterfaceElements(mesh, partition_, system_, d.regions);
  }
  d.naiveSolver = makeSparseSolver(SolverKind::umfpack);
  runStats_.largeDofs = static_cast<int>(large.size());
  for (int i = 0; i < partition_.numRegions(); ++i) {
    runStats_.fastDofs += static_cast<int>(partition_.regionDofs(i).size());
    runStats_.interfaceDofs += static_cast<int>(partition_.interfaceDofs(i).size());
  }
  if (!system_.damped()) stats_.skipped.push_back("damping blocks (alpha = beta = 0)");
  if (d.linear)
    stats_.skipped.push_back("per-step refactorization (linear forces: blocks, Z and H^{LL*} factored once)");
  if (options_.method == AsyncSolveMethod::naive)
    stats_.skipped.push_back("Schur complement (naive full-system solve)");
}

AsyncBackwardEuler::~AsyncBackwardEuler() = default;

void AsyncBackwardEuler::setTimestep(double timestep) {
  Integrator::setTimestep(timestep);
  if (impl_) impl_->built = false;
}

// Rebuilds every block from the current K (impl_->stiffness) and M, refactors, and
// recomputes the Schur complement. Called once for linear forces, every large step
// otherwise.
void AsyncBackwardEuler::rebuildBlocks() {
  Impl& d = *impl_;
  const DynamicSystem& system = system_;
  const RegionPartition& partition = partition_;
  const AsyncOptions& options = options_;
  const double largeStep = timestep();
  IntegratorStats& stats = stats_;
  const double alpha = system.rayleighMass, beta = system.rayleighStiffness;
  const bool damped = system.damped();
  const double hL = largeStep;
  Stopwatch assembly, factor;

  assembly.start();
  // Blocks of M are constant: cut once. Blocks of K are updated in place (values only)
  // and every combination below reuses its pattern, so a refactorization step allocates
  // nothing here.
  if (!d.cutLL) d.Mll = d.massLL.extract(system.mass);
  updateBlock(d.stiffLL, d.stiffness, d.Kll, d.cutLL);
  d.cutLL = true;
  // A^L = M^{LL} + hL D^{LL} + hL^2 K^{LL}, D = alpha M + beta K.
  combineInto(1.0 + hL * alpha, d.Mll, hL * hL + hL * beta, d.Kll, d.largeSystem);
  for (RegionBlocks& rb : d.regions) {
    const double hS = hL / rb.ratio;
    rb.smallStep = hS;
    updateBlock(rb.stiffSS, d.stiffness, rb.Kss, rb.cut);
    updateBlock(rb.stiffSI, d.stiffness, rb.Ksi, rb.cut);
    updateBlock(rb.stiffIS, d.stiffness, rb.Kis, rb.cut);
    rb.cut = true;
    if (damped) {
      combineInto(alpha, rb.Mss, beta, rb.Kss, rb.Dss);
      combineInto(alpha, rb.Msi, beta, rb.Ksi, rb.Dsi);
      combineInto(alpha, rb.Mis, beta, rb.Kis, rb.Dis);
    }
    // A^S = M^{SS} + hS D^{SS} + hS^2 K^{SS}
    combineInto(1.0 + hS * alpha, rb.Mss, hS * hS + hS * beta, rb.Kss, rb.systemMatrix);
    combineInto(0.0, rb.Mss, hS * hS, rb.Kss, rb.G);
    rb.GT = rb.G.transpose();
    rb.rhsWeight = 1.0 / (1.0 + hS * alpha);
    rb.stepWeight = (1.0 + beta / hS) / (1.0 + hS * alpha);
    rb.coupling = couplingCoefficients(options.coupling, rb.ratio, hL);
  }
  if (options.coupling == AsyncCoupling::stable) subtractInterfaceStiffness();
  if (d.linear && !d.symmetryChecked) {
    const SparseMatrix transposed = d.stiffness.transpose();
    d.symmetricStiffness = (d.stiffness - transposed).norm() <= 1e-13 * d.stiffness.norm();
    d.symmetryChecked = true;
  }
  stats.assemblySeconds += assembly.stop();

  if (options.method == AsyncSolveMethod::naive) {
    // The whole block lower-Hessenberg system (design note, rows r = 1..m and last row).
    assembly.start();
    const int numLarge = static_cast<int>(partition.largeDofs().size());
    d.naiveOffsets.assign(d.regions.size() + 1, 0);
    int offset = 0;
    for (std::size_t i = 0; i < d.regions.size(); ++i) {
      d.naiveOffsets[i] = offset;
      offset += d.regions[i].ratio * static_cast<int>(d.regions[i].Mss.rows());
    }
    d.naiveOffsets.back() = offset;
    const int size = offset + numLarge;
    std::vector<Eigen::Triplet<double>> triplets;
    for (std::size_t i = 0; i < d.regions.size(); ++i) {
      const RegionBlocks& rb = d.regions[i];
      const int m = rb.ratio;
      const int s = static_cast<int>(rb.Mss.rows());
      const std::vector<int>& ifacePos = partition.interfacePositions(static_cast<int>(i));
      const SparseMatrix C = rb.G - rb.Mss;
      const CouplingCoefficients& k = rb.coupling;
      for (int r = 1; r <= m; ++r) {
        const int row = d.naiveOffsets[i] + (r - 1) * s;
        appendTriplets(rb.systemMatrix, 1.0, row, row, triplets);
        if (r >= 2) appendTriplets(C, 1.0, row, row - s, triplets);
        for (int j = 1; j <= r - 2; ++j) appendTriplets(rb.G, 1.0, row, d.naiveOffsets[i] + (j - 1) * s, triplets);
        // B_r (Eq. A5 or A9), columns at the interface.
        SparseMatrix B = k.bM[r - 1] * rb.Msi + k.bK[r - 1] * rb.Ksi;
        if (damped) B += k.bD[r - 1] * rb.Dsi;
        appendTriplets(B, 1.0, row, offset, triplets, nullptr, &ifacePos);
      }
      // Last row: E_j on X_j (Eq. A6 or A10), rows at the interface of L.
      for (int j = 1; j <= m; ++j) {
        SparseMatrix E = k.eM[j - 1] * rb.Mis + k.eK[j - 1] * rb.Kis;
        if (damped) E += k.eD[j - 1] * rb.Dis;
        appendTriplets(E, 1.0, offset, d.naiveOffsets[i] + (j - 1) * s, triplets, &ifacePos, nullptr);
      }
    }
    appendTriplets(d.largeSystem, 1.0, offset, offset, triplets);
    d.naiveSystem.resize(size, size);
    d.naiveSystem.setFromTriplets(triplets.begin(), triplets.end());
    d.naiveSystem.makeCompressed();
    stats.assemblySeconds += assembly.stop();
    factor.start();
    detail::factorizeCounted(*d.naiveSolver, d.naiveSystem, d.naiveAnalyzed, stats);
    stats.factorizationSeconds += factor.stop();
    return;
  }

  // Structured: factor every A^S, compute Z = (H^{SS})^{-1} H^{SI} by forward
  // substitution with |I| right-hand sides, and the Schur corrections C_i = H^{IS} Z.
  factor.start();
  for (RegionBlocks& rb : d.regions) detail::factorizeCounted(*rb.solver, rb.systemMatrix, rb.analyzed, stats);
  stats.factorizationSeconds += factor.stop();
  if (d.lagSchur) {
    d.schurStale = true;  // Z and H^{LL*} kept from the last full rebuild (step() iterates)
    return;
  }
  fullSchurRebuild();
}

// Z, the Schur corrections and the H^{LL*} factor from the current blocks.
void AsyncBackwardEuler::fullSchurRebuild() {
  Impl& d = *impl_;
  IntegratorStats& stats = stats_;
  Stopwatch factor;
  factor.start();
  computeCorrections(system_.damped());
  const double zSeconds = factor.stop();
  zColumnSeconds_ += zSeconds;
  stats.factorizationSeconds += zSeconds;
  (runStats_.rebuilds == 0 && runStats_.steps == 0 ? runStats_.setupZSeconds : runStats_.rebuildZSeconds) += zSeconds;
  schurAsymmetry_ = 0.0;
  for (const RegionBlocks& rb : d.regions) {
    const double norm = rb.correction.norm();
    if (norm > 0.0) {
      schurAsymmetry_ = std::max(schurAsymmetry_, (rb.correction - rb.correction.transpose()).norm() / norm);
    }
  }
  factor.start();
  buildSchurSolver();
  const double schurSeconds = factor.stop();
  stats.factorizationSeconds += schurSeconds;
  if (runStats_.rebuilds == 0 && runStats_.steps == 0) runStats_.setupSchurSeconds += schurSeconds;
  d.schurStale = false;
  d.schurBuilt = true;
}

namespace {

/// Fewest Z columns worth a thread of their own (below, the copy of the A^S factor costs
/// more than the columns it takes over).
constexpr Eigen::Index kMinZColumnsPerThread = 24;

/// Columns [first, first + width) of Z = (H^{SS})^{-1} H^{SI} by forward substitution with
/// `solver` (a factor of A^S), and from them the same columns of C_i = H^{IS} Z (Eq. A7),
/// and of Z_m and sum_r Z_r when the region recovers X densely.
void correctionColumns(RegionBlocks& rb, SparseSolver& solver, bool damped, Eigen::Index first, Eigen::Index width) {
  const Eigen::Index size = rb.systemMatrix.rows();
  const CouplingCoefficients& k = rb.coupling;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(size, width), x, combinedT(width, size), productT(width, size);
  Eigen::MatrixXd runningT = Eigen::MatrixXd::Zero(width, size);  // (sum_{i<r} Z_i)^T
  Eigen::MatrixXd weightedM = Eigen::MatrixXd::Zero(size, width), weightedK = weightedM, weightedD, sum;
  if (damped) weightedD = weightedM;
  if (rb.useDenseZ) sum = weightedM;
  // rhs += scale * block(:, first .. first + width), for a sparse block of H^{SI}.
  const auto addColumns = [&](const SparseMatrix& block, double scale) {
    if (scale == 0.0) return;
    for (Eigen::Index c = 0; c < width; ++c)
      for (SparseMatrix::InnerIterator it(block, first + c); it; ++it) rhs(it.row(), c) += scale * it.value();
  };
  for (int r = 1; r <= rb.ratio; ++r) {
    // Row r of H^{SS} Z = H^{SI}: A^S Z_r = B_r + M^{SS} Z_{r-1} - G sum_{i<r} Z_i, with
    // M^{SS} Z_{r-1} from the previous right-hand side (see RegionBlocks::rhsWeight).
    if (r >= 2) {
      runningT += x.transpose();
      combinedT = runningT;
      combinedT += rb.stepWeight * x.transpose();
      rowWiseStiffnessProduct(rb, combinedT, productT);
      rhs *= rb.rhsWeight;
      rhs -= productT.transpose();
    }
    addColumns(rb.Msi, k.bM[r - 1]);
    addColumns(rb.Ksi, k.bK[r - 1]);
    if (damped) addColumns(rb.Dsi, k.bD[r - 1]);
    solver.solve(rhs, x);
    if (k.eM[r - 1] != 0.0) weightedM += k.eM[r - 1] * x;
    weightedK += k.eK[r - 1] * x;
    if (damped) weightedD += k.eD[r - 1] * x;
    if (rb.useDenseZ) sum += x;
  }
  if (rb.useDenseZ) {
    rb.zLast.middleCols(first, width) = x;
    rb.zSum.middleCols(first, width) = sum;
  }
  Eigen::MatrixXd columns = rb.Mis * weightedM;
  columns += rb.Kis * weightedK;
  if (damped) columns += rb.Dis * weightedD;
  rb.correction.middleCols(first, width) = columns;
}

int threadBudget(int requested) { return requested > 0 ? requested : std::max(1, omp_get_max_threads()); }

/// Runs body(t) for t = 0..count-1 on up to `threads` OpenMP threads and rethrows the first
/// exception a task threw (an exception must not leave an OpenMP region).
template <class Body>
void parallelTasks(int count, int threads, const Body& body) {
  std::vector<std::exception_ptr> failures(static_cast<std::size_t>(std::max(count, 0)));
#pragma omp parallel for schedule(dynamic) num_threads(std::max(1, std::min(threads, count))) if (count > 1)
  for (int t = 0; t < count; ++t) {
    try {
      body(t);
    } catch (...) {
      failures[static_cast<std::size_t>(t)] = std::current_exception();
    }
  }
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
}

}  // namespace

// Z and the Schur corrections of every region. The columns of Z are independent: each
// region's are split into blocks of at least kMinZColumnsPerThread, one per thread, each
// block solved (many right-hand sides at once: BLAS-3 work in the supernodal solve) with
// its own copy of the A^S factor, since one solver object is not thread-safe.
void AsyncBackwardEuler::computeCorrections(bool damped) {
  Impl& d = *impl_;
  const int threads = threadBudget(options_.threads);
  struct Task {
    int region = 0;
    int block = 0;  // 0: the region's own solver, j > 0: helperSolvers[j - 1]
    Eigen::Index first = 0, width = 0;
  };
  std::vector<Task> tasks;
  std::vector<std::pair<int, int>> helpers;  // (region, helper) factorizations to run
  long long zColumns = 0;
  int usedThreads = 1;
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    RegionBlocks& rb = d.regions[i];
    const int m = rb.ratio;
    const Eigen::Index q = rb.Msi.cols();
    const Eigen::Index sizeS = rb.systemMatrix.rows();
    // Recovery: the end state needs X_m = y_m - Z_m Y_I and sum_r X_r = sum_r y_r -
    // (sum_r Z_r) Y_I (4 |S| q flops, 2 |S| q doubles), or a second forward substitution
    // (m solves and 2m sparse products). Automatic picks the cheaper in flops while the two
    // blocks fit in kMaxDenseZEntries.
    const double denseFlops = 4.0 * static_cast<double>(sizeS) * static_cast<double>(q);
    const double substitutionFlops =
        m * (rb.solver->stats().solveFlopsPerRhs + 4.0 * static_cast<double>(rb.Kss.nonZeros()));
    rb.useDenseZ = options_.recovery == RecoveryMode::denseZ ||
                   (options_.recovery == RecoveryMode::automatic && denseFlops <= substitutionFlops &&
                    2.0 * static_cast<double>(sizeS) * static_cast<double>(q) <= kMaxDenseZEntries);
    rb.correction.resize(q, q);
    if (rb.useDenseZ) {
      rb.zLast.resize(sizeS, q);
      rb.zSum.resize(sizeS, q);
    } else {
      rb.zLast.resize(0, 0);
      rb.zSum.resize(0, 0);
    }
    if (q == 0) continue;
    zColumns += static_cast<long long>(m) * q;
    const int blocks =
        static_cast<int>(std::max<Eigen::Index>(1, std::min<Eigen::Index>(threads, q / kMinZColumnsPerThread)));
    usedThreads = std::max(usedThreads, blocks);
    while (static_cast<int>(rb.helperSolvers.size()) < blocks - 1) {
      rb.helperSolvers.push_back(makeSparseSolver(options_.regionSolver));
      rb.helperAnalyzed.push_back(0);
    }
    for (int j = 1; j < blocks; ++j) helpers.emplace_back(static_cast<int>(i), j - 1);
    for (int j = 0; j < blocks; ++j) {
      const Eigen::Index first = q * j / blocks, last = q * (j + 1) / blocks;
      tasks.push_back({static_cast<int>(i), j, first, last - first});
    }
  }
  parallelTasks(static_cast<int>(helpers.size()), threads, [&](int t) {
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(helpers[static_cast<std::size_t>(t)].first)];
    const auto j = static_cast<std::size_t>(helpers[static_cast<std::size_t>(t)].second);
    if (!rb.helperAnalyzed[j]) {
      rb.helperSolvers[j]->analyzePattern(rb.systemMatrix);
      rb.helperAnalyzed[j] = 1;
    }
    rb.helperSolvers[j]->factorize(rb.systemMatrix);
  });
  stats_.factorizations += static_cast<long long>(helpers.size());
  parallelTasks(static_cast<int>(tasks.size()), threads, [&](int t) {
    const Task& task = tasks[static_cast<std::size_t>(t)];
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(task.region)];
    SparseSolver& solver = task.block == 0 ? *rb.solver : *rb.helperSolvers[static_cast<std::size_t>(task.block - 1)];
    correctionColumns(rb, solver, damped, task.first, task.width);
  });
  runStats_.zThreads = usedThreads;
  runStats_.zColumns = zColumns;
}

// Stable coupling: A^L becomes Â^L = A^L - sum_i (1 - theta_i) hL^2 K_{I_i}^{II} (Eq. A11),
// with K_{I_i} the tangent of region i's interface elements at u_0. The change lies on
// entries of interface-vertex pairs that share an element, so A^L's pattern holds them.
void AsyncBackwardEuler::subtractInterfaceStiffness() {
  Impl& d = *impl_;
  const std::vector<int>& large = partition_.largeDofs();
  for (int i = 0; i < partition_.numRegions(); ++i) {
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    const auto q = static_cast<Eigen::Index>(pos.size());
    rb.interfaceStiffness.setZero(q, q);
    for (InterfaceElement& element : rb.interfaceElements) {
      if (d.perElementTangent) system_.forceModel->elementTangent(displacement_, element.element, element.tangent);
      for (int b = 0; b < 12; ++b) {
        const int column = element.interfaceIndex[static_cast<std::size_t>(b)];
        if (column < 0) continue;
        for (int a = 0; a < 12; ++a) {
          const int row = element.interfaceIndex[static_cast<std::size_t>(a)];
          if (row >= 0) rb.interfaceStiffness(row, column) += element.tangent(a, b);
        }
      }
    }
    for (Eigen::Index b = 0; b < q; ++b) {
      for (Eigen::Index a = 0; a < q; ++a) {
        if (rb.interfaceStiffness(a, b) == 0.0) continue;
        const int row = pos[static_cast<std::size_t>(a)], column = pos[static_cast<std::size_t>(b)];
        double* entry = findEntry(d.largeSystem, row, column);
        if (entry == nullptr) {
          throw Error("async integrator: interface DOFs " + std::to_string(large[static_cast<std::size_t>(row)]) +
                      " and " + std::to_string(large[static_cast<std::size_t>(column)]) +
                      " share an element but not an entry of A^L (the mass and stiffness patterns differ)");
        }
        *entry -= rb.coupling.interfaceWeight * rb.interfaceStiffness(a, b);
      }
    }
  }
}

void AsyncBackwardEuler::buildSchurSolver() {
  Impl& d = *impl_;
  const int numLarge = static_cast<int>(d.largeSystem.rows());
  if (numLarge == 0) return;
  // Interface positions of all regions (inside L), and each region's place among them.
  std::vector<int> all;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const std::vector<int>& pos = partition_.interfacePositions(i);
    all.insert(all.end(), pos.begin(), pos.end());
  }
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  const Eigen::Index q = static_cast<Eigen::Index>(all.size());

  SchurMode mode = options_.schur;
  if (mode == SchurMode::lowRank && options_.coupling == AsyncCoupling::stable) {
    // The stable coupling's H^{LL*} is symmetric (to round-off): its own Cholesky factor
    // is exact and costs one sparse solve per step, where the low-rank form adds a dense
    // |L| x q product per step and q solves with A^L per rebuild.
    mode = schurAsymmetry_ <= 1e-10 ? SchurMode::symmetric : SchurMode::lu;
  }
  if (mode == SchurMode::lowRank && static_cast<double>(numLarge) * static_cast<double>(q) > kMaxLowRankEntries) {
    mode = SchurMode::lu;  // A^{-1} U would not fit: factor H^{LL*} itself
  }
  if (mode != schurModeUsed_ || !d.schurSolver) {
    d.schurSolver = makeSparseSolver(mode == SchurMode::lu ? SolverKind::umfpack : SolverKind::cholmod);
    d.schurAnalyzed = false;
  }
  schurModeUsed_ = mode;

  if (mode == SchurMode::lowRank) {
    // H^{LL*} = A^L - U C U^T with U the interface columns and C the sum of the regions'
    // corrections. With W = (A^L)^{-1} U: x = y + W C z, y = (A^L)^{-1} b and
    // (I - U^T W C) z = U^T y (see solveSchur). A^L is SPD: Cholesky.
    detail::factorizeCounted(*d.schurSolver, d.largeSystem, d.schurAnalyzed, stats_);
    d.interfaceUnion = all;
    if (q == 0) return;
    std::vector<int> place(static_cast<std::size_t>(numLarge), -1);
    for (Eigen::Index k = 0; k < q; ++k)
      place[static_cast<std::size_t>(all[static_cast<std::size_t>(k)])] = static_cast<int>(k);
    d.unionCorrection.setZero(q, q);
    for (int i = 0; i < partition_.numRegions(); ++i) {
      const std::vector<int>& pos = partition_.interfacePositions(i);
      const Eigen::MatrixXd& c = d.regions[static_cast<std::size_t>(i)].correction;
      for (std::size_t b = 0; b < pos.size(); ++b)
        for (std::size_t a = 0; a < pos.size(); ++a)
          d.unionCorrection(place[static_cast<std::size_t>(pos[a])], place[static_cast<std::size_t>(pos[b])]) +=
              c(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
    }
    Eigen::MatrixXd selector = Eigen::MatrixXd::Zero(numLarge, q);
    for (Eigen::Index k = 0; k < q; ++k) selector(all[static_cast<std::size_t>(k)], k) = 1.0;
    d.schurSolver->solve(selector, d.lowRankBasis);  // W
    Eigen::MatrixXd interfaceRows(q, q);
    for (Eigen::Index k = 0; k < q; ++k) interfaceRows.row(k) = d.lowRankBasis.row(all[static_cast<std::size_t>(k)]);
    d.capacitance.compute(Eigen::MatrixXd::Identity(q, q) - interfaceRows * d.unionCorrection);
    return;
  }

  // H^{LL*} = A^L - sum_i C_i on the I_i x I_i blocks, on a pattern built once (every
  // block entry stored, so a rebuild writes values only and the analysis is kept).
  Stopwatch assembly;
  if (!d.schurPatternBuilt) {
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(static_cast<std::size_t>(d.largeSystem.nonZeros()));
    appendTriplets(d.largeSystem, 1.0, 0, 0, triplets);
    for (int i = 0; i < partition_.numRegions(); ++i) {
      const std::vector<int>& pos = partition_.interfacePositions(i);
      for (int column : pos)
        for (int row : pos) triplets.emplace_back(row, column, 0.0);
    }
    d.schur.resize(numLarge, numLarge);
    d.schur.setFromTriplets(triplets.begin(), triplets.end());
    d.schur.makeCompressed();
    d.schurFromLarge.resize(static_cast<std::size_t>(d.largeSystem.nonZeros()));
    for (int c = 0; c < numLarge; ++c)
      for (int k = d.largeSystem.outerIndexPtr()[c]; k < d.largeSystem.outerIndexPtr()[c + 1]; ++k)
        d.schurFromLarge[static_cast<std::size_t>(k)] =
            static_cast<int>(findEntry(d.schur, d.largeSystem.innerIndexPtr()[k], c) - d.schur.valuePtr());
    d.schurFromBlock.assign(static_cast<std::size_t>(partition_.numRegions()), {});
    for (int i = 0; i < partition_.numRegions(); ++i) {
      const std::vector<int>& pos = partition_.interfacePositions(i);
      std::vector<int>& index = d.schurFromBlock[static_cast<std::size_t>(i)];
      index.reserve(pos.size() * pos.size());
      for (int column : pos)
        for (int row : pos) index.push_back(static_cast<int>(findEntry(d.schur, row, column) - d.schur.valuePtr()));
    }
    d.schurPatternBuilt = true;
  }
  double* values = d.schur.valuePtr();
  std::fill(values, values + d.schur.nonZeros(), 0.0);
  for (std::size_t k = 0; k < d.schurFromLarge.size(); ++k) values[d.schurFromLarge[k]] += d.largeSystem.valuePtr()[k];
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const Eigen::MatrixXd& c = d.regions[static_cast<std::size_t>(i)].correction;
    const std::vector<int>& index = d.schurFromBlock[static_cast<std::size_t>(i)];
    const Eigen::Index qi = c.rows();
    for (Eigen::Index b = 0; b < qi; ++b)
      for (Eigen::Index a = 0; a < qi; ++a) {
        const double entry = mode == SchurMode::symmetric ? 0.5 * (c(a, b) + c(b, a)) : c(a, b);
        values[index[static_cast<std::size_t>(b * qi + a)]] -= entry;
      }
  }
  stats_.assemblySeconds += assembly.stop();
  detail::factorizeCounted(*d.schurSolver, d.schur, d.schurAnalyzed, stats_);
}

void AsyncBackwardEuler::solveSchur(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  Impl& d = *impl_;
  d.schurSolver->solve(rhs, d.schurSolution);
  solution = d.schurSolution.col(0);
  if (schurModeUsed_ != SchurMode::lowRank || d.interfaceUnion.empty()) return;
  const Eigen::VectorXd yInterface = gather(solution, d.interfaceUnion);
  const Eigen::VectorXd z = d.capacitance.solve(yInterface);
  solution.noalias() += d.lowRankBasis * (d.unionCorrection * z);
}

namespace {

/// Forward substitution with H^{SS} (Eq. A13): A^S x_r = b_r + M^{SS} x_{r-1} - G sum_{i<r} x_i,
/// into x (|S| x m). G sum_{i<r} x_i is a running sum; M^{SS} x_{r-1} and G x_{r-1} are
/// taken in one pass over their shared pattern, into the region's buffers.
void forwardSubstitute(RegionBlocks& rb, const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
  const Eigen::Index size = b.rows();
  x.resize(size, b.cols());
  rb.runningStiffness.setZero(size);  // w = sum_{i<r} x_i
  rb.combined.resize(size);
  for (int r = 1; r <= rb.ratio; ++r) {
    if (r == 1) {
      rb.substepRhs = b.col(0);
    } else {
      // rhs_r = rhsWeight rhs_{r-1} + b_r - G (stepWeight x_{r-1} + w) (RegionBlocks::rhsWeight).
      rb.runningStiffness += x.col(r - 2);
      rb.combined = rb.runningStiffness + rb.stepWeight * x.col(r - 2);
      rb.substepRhs *= rb.rhsWeight;
      rb.substepRhs += b.col(r - 1);
      subtractStiffnessProduct(rb, rb.combined.data(), rb.substepRhs.data());
    }
    rb.solver->solve(rb.substepRhs, rb.substepSolution);
    x.col(r - 1) = rb.substepSolution.col(0);
  }
}

}  // namespace

void AsyncBackwardEuler::step() {
  Impl& d = *impl_;
  Stopwatch whole;
  const double rebuildBefore = runStats_.setupSeconds + runStats_.rebuildSeconds;
  const double hL = timestep();
  // Step times come from the step index (t0 = k hL, t1 = (k + 1) hL); substep r of a
  // region is at t0 + r hS, and its last one (r = m) at exactly t1.
  const double t0 = time();
  const double t1 = stepEndTime();
  const auto substepTime = [t0, t1](int r, int ratio, double smallStep) {
    return r == ratio ? t1 : t0 + (r * smallStep);
  };
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  const bool damped = system_.damped();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  const int threads = threadBudget(options_.threads);

  if (!d.linear || !d.built || !d.symmetricStiffness) {
    detail::evaluateForces(system_, d.linear, d.built, u0, d.internalForce, d.stiffness, stats_);
  }
  Stopwatch solve;
  if (!d.linear || !d.built) {
    Stopwatch rebuild;
    const bool first = runStats_.rebuilds == 0 && runStats_.steps == 0;
    d.lagSchur = options_.laggedSchur && !d.linear && d.schurBuilt && !d.refreshNext &&
                 options_.method == AsyncSolveMethod::structured;
    d.refreshNext = false;
    rebuildBlocks();
    d.built = true;
    const double seconds = rebuild.stop();
    if (first) {
      runStats_.setupSeconds += seconds;
    } else {
      runStats_.rebuildSeconds += seconds;
      ++runStats_.rebuilds;
    }
  }

  solve.start();
  const std::vector<int>& large = partition_.largeDofs();
  const int numRegions = partition_.numRegions();
  // Right-hand sides (A4): b_r = hS (f_ext(t) - f_int(u_0) - (D + t K) v_0), t = r hS.
  const bool rowProducts = d.linear && d.symmetricStiffness;
  if (damped && alpha != 0.0) {
    d.massVelocity.resize(u0.size());
    d.massVelocity.noalias() = system_.mass * v0;
  }
  if (!rowProducts) {
    d.stiffVelocity.resize(u0.size());
    d.stiffVelocity.noalias() = d.stiffness * v0;
    // The state-dependent part, once per large step: f_int(u_0) + D v_0.
    d.stateForce = d.internalForce;
    if (damped) {
      if (alpha != 0.0) d.stateForce += alpha * d.massVelocity;
      d.stateForce += beta * d.stiffVelocity;
    }
  } else {
    d.work = u0 + (beta + hL) * v0;
  }
  // External forces, evaluated in this thread (the callback need not be thread-safe): once
  // per distinct time of the step, shared by regions whose substeps fall on it; with the
  // substep state prediction, once per substep and region.
  d.forcesUsed = 0;
  const auto forceAt = [&](double time, const Eigen::VectorXd& u) -> const Eigen::VectorXd& {
    if (&u == &u0) {
      for (std::size_t k = 0; k < d.forcesUsed; ++k)
        if (d.forceTimes[k] == time) return d.forceValues[k];
    }
    if (d.forcesUsed == d.forceValues.size()) {
      d.forceValues.emplace_back();
      d.forceTimes.push_back(0.0);
    }
    Eigen::VectorXd& f = d.forceValues[d.forcesUsed];
    d.forceTimes[d.forcesUsed] = &u == &u0 ? time : std::nan("");  // predicted states are never shared
    ++d.forcesUsed;
    f.setZero(u0.size());
    system_.externalForce(time, u, v0, f);
    return f;
  };
  const bool hasExternal = static_cast<bool>(system_.externalForce);
  for (int i = 0; i < numRegions; ++i) {
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    const auto sizeS = static_cast<Eigen::Index>(s.size());
    rb.external.resize(sizeS, rb.ratio);
    if (!hasExternal) {
      rb.external.setZero();
      continue;
    }
    for (int r = 1; r <= rb.ratio; ++r) {
      const double time = substepTime(r, rb.ratio, rb.smallStep);
      const Eigen::VectorXd* f = nullptr;
      if (options_.substepStatePrediction) {
        d.predicted = u0 + (r * rb.smallStep) * v0;
        f = &forceAt(time, d.predicted);
      } else {
        f = &forceAt(time, u0);
      }
      for (Eigen::Index k = 0; k < sizeS; ++k) rb.external(k, r - 1) = (*f)[s[static_cast<std::size_t>(k)]];
    }
  }
  const Eigen::VectorXd* externalL = hasExternal ? &forceAt(t1, u0) : nullptr;
  d.rhsL.resize(static_cast<Eigen::Index>(large.size()));
  for (std::size_t k = 0; k < large.size(); ++k) {
    const int dof = large[k];
    const double external = externalL ? (*externalL)[dof] : 0.0;
    // hL (f_ext - f_int(u_0) - D v_0) - hL^2 K v_0; linear: hL (f_ext - alpha M v_0 - K (u_0 + (beta + hL) v_0)).
    const double state =
        rowProducts ? columnDot(d.stiffness, dof, d.work) + (damped && alpha != 0.0 ? alpha * d.massVelocity[dof] : 0.0)
                    : d.stateForce[dof] + hL * d.stiffVelocity[dof];
    d.rhsL[static_cast<Eigen::Index>(k)] = hL * (external - state);
  }
  // Stable coupling: b^L += (1 - theta) hL^2 (K^{IS} v^S_0 + K_I^{II} v^I_0) (Eq. A12).
  for (int i = 0; i < numRegions && options_.coupling == AsyncCoupling::stable; ++i) {
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    if (pos.empty()) continue;
    const std::vector<int>& s = partition_.regionDofs(i);
    const std::vector<int>& iface = partition_.interfaceDofs(i);
    rb.xSum.resize(static_cast<Eigen::Index>(s.size()));  // scratch: v^S_0
    for (std::size_t k = 0; k < s.size(); ++k) rb.xSum[static_cast<Eigen::Index>(k)] = v0[s[k]];
    rb.yInterface.resize(static_cast<Eigen::Index>(iface.size()));  // scratch: v^I_0
    for (std::size_t k = 0; k < iface.size(); ++k) rb.yInterface[static_cast<Eigen::Index>(k)] = v0[iface[k]];
    rb.interfaceRow.resize(static_cast<Eigen::Index>(pos.size()));
    rb.interfaceRow.noalias() = rb.Kis * rb.xSum;
    rb.interfaceRow.noalias() += rb.interfaceStiffness * rb.yInterface;
    for (std::size_t k = 0; k < pos.size(); ++k)
      d.rhsL[pos[k]] += rb.coupling.interfaceWeight * rb.interfaceRow[static_cast<Eigen::Index>(k)];
  }
  // Every region's b^S (|S| x m) from its DOFs only.
  parallelTasks(numRegions, threads, [&](int i) {
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    rb.rhs.resize(static_cast<Eigen::Index>(s.size()), rb.ratio);
    for (std::size_t k = 0; k < s.size(); ++k) {
      const int dof = s[k];
      const auto row = static_cast<Eigen::Index>(k);
      double state = 0.0, stiffVelocity = 0.0;  // (f_int(u_0) + D v_0)_dof and (K v_0)_dof
      if (rowProducts) {
        stiffVelocity = columnDot(d.stiffness, dof, v0);
        state = columnDot(d.stiffness, dof, u0) + beta * stiffVelocity +
                (damped && alpha != 0.0 ? alpha * d.massVelocity[dof] : 0.0);
      } else {
        stiffVelocity = d.stiffVelocity[dof];
        state = d.stateForce[dof];
      }
      for (int r = 1; r <= rb.ratio; ++r) {
        const double tau = r * rb.smallStep;
        rb.rhs(row, r - 1) = rb.smallStep * (rb.external(row, r - 1) - state - tau * stiffVelocity);
      }
    }
  });

  if (options_.method == AsyncSolveMethod::naive) {
    Eigen::VectorXd rhs(d.naiveSystem.rows());
    for (int i = 0; i < numRegions; ++i) {
      const Eigen::MatrixXd& b = d.regions[static_cast<std::size_t>(i)].rhs;
      rhs.segment(d.naiveOffsets[static_cast<std::size_t>(i)], b.size()) =
          Eigen::Map<const Eigen::VectorXd>(b.data(), b.size());
    }
    rhs.tail(d.rhsL.size()) = d.rhsL;
    const Eigen::VectorXd sol = d.naiveSolver->solve(rhs);
    for (int i = 0; i < numRegions; ++i) {
      RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
      rb.x = Eigen::Map<const Eigen::MatrixXd>(sol.data() + d.naiveOffsets[static_cast<std::size_t>(i)], rb.rhs.rows(),
                                               rb.rhs.cols());
      rb.substituted = true;
    }
    d.Y = sol.tail(d.rhsL.size());
  } else {
    // Forward substitution y = (H^{SS})^{-1} b^S per region (in parallel: each region owns
    // its solver), and the region's term of b^{L*} = b^L - H^{LS} y on its interface rows:
    // sum_r E_r y_r = M^{IS} (y eM) + D^{IS} (y eD) + K^{IS} (y eK) (Eq. A7).
    parallelTasks(numRegions, threads, [&](int i) {
      RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
      forwardSubstitute(rb, rb.rhs, rb.y);
      if (rb.Mis.rows() == 0) return;
      const CouplingCoefficients& k = rb.coupling;
      weightedColumnSum(rb.y, k.eM, rb.weightedM);
      weightedColumnSum(rb.y, k.eK, rb.weightedK);
      rb.interfaceRow.resize(rb.Mis.rows());
      rb.interfaceRow.noalias() = rb.Mis * rb.weightedM;
      rb.interfaceRow.noalias() += rb.Kis * rb.weightedK;
      if (damped) {
        weightedColumnSum(rb.y, k.eD, rb.weightedD);
        rb.interfaceRow.noalias() += rb.Dis * rb.weightedD;
      }
    });
    d.rhsSchur = d.rhsL;
    for (int i = 0; i < numRegions; ++i) {
      const RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
      const std::vector<int>& pos = partition_.interfacePositions(i);
      for (std::size_t k = 0; k < pos.size(); ++k) d.rhsSchur[pos[k]] -= rb.interfaceRow[static_cast<Eigen::Index>(k)];
    }
    if (large.empty()) {
      d.Y.resize(0);
    } else if (!d.schurStale) {
      solveSchur(d.rhsSchur, d.Y);
    } else if (!iterativeSchur(d.rhsSchur, d.Y)) {
      // The old factor no longer preconditions well enough: rebuild now (exact solve).
      Stopwatch rebuild;
      fullSchurRebuild();
      runStats_.rebuildSeconds += rebuild.stop();
      solveSchur(d.rhsSchur, d.Y);
    }
    // Recovery per region (in parallel): X_m and sum_r X_r from the stored Z_m, sum_r Z_r,
    // or every X_r by a second forward substitution with b^S - H^{SL} Y.
    parallelTasks(numRegions, threads, [&](int i) {
      RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
      const std::vector<int>& pos = partition_.interfacePositions(i);
      if (pos.empty()) {
        std::swap(rb.x, rb.y);
        rb.substituted = true;
        return;
      }
      rb.yInterface.resize(static_cast<Eigen::Index>(pos.size()));
      for (std::size_t k = 0; k < pos.size(); ++k) rb.yInterface[static_cast<Eigen::Index>(k)] = d.Y[pos[k]];
      if (rb.useDenseZ && !observer_ && !d.schurStale) {
        rb.xLast = rb.y.col(rb.ratio - 1);
        rb.xLast.noalias() -= rb.zLast * rb.yInterface;
        rb.xSum = rb.y.rowwise().sum();
        rb.xSum.noalias() -= rb.zSum * rb.yInterface;
        rb.substituted = false;
        return;
      }
      // X = (H^{SS})^{-1} (b^S - H^{SL} Y), block r of H^{SL} Y = B_r Y_I.
      const CouplingCoefficients& k = rb.coupling;
      rb.massY.noalias() = rb.Msi * rb.yInterface;
      rb.stiffY.noalias() = rb.Ksi * rb.yInterface;
      if (damped) rb.dampY.noalias() = rb.Dsi * rb.yInterface;
      for (int r = 1; r <= rb.ratio; ++r) {
        rb.rhs.col(r - 1) -= k.bM[r - 1] * rb.massY + k.bK[r - 1] * rb.stiffY;
        if (damped) rb.rhs.col(r - 1) -= k.bD[r - 1] * rb.dampY;
      }
      forwardSubstitute(rb, rb.rhs, rb.x);
      rb.substituted = true;
    });
  }

  // New state: v^S_r = v^S_0 + X_r, u^S_m = u^S_0 + hS sum_r v^S_r; v^L = v^L_0 + Y, u^L = u^L_0 + hL v^L.
  d.newU = u0;
  d.newV = v0;
  for (int i = 0; i < numRegions; ++i) {
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    const int m = rb.ratio;
    if (rb.substituted) {
      rb.xLast = rb.x.col(m - 1);
      rb.xSum = rb.x.rowwise().sum();
    }
    for (std::size_t k = 0; k < s.size(); ++k) {
      const auto row = static_cast<Eigen::Index>(k);
      d.newV[s[k]] = v0[s[k]] + rb.xLast[row];
      d.newU[s[k]] = u0[s[k]] + rb.smallStep * (m * v0[s[k]] + rb.xSum[row]);
    }
    if (observer_) {
      // Substep states, only for an installed observer (x then holds every substep).
      const Eigen::VectorXd vS0 = gather(v0, s), uS0 = gather(u0, s);
      Eigen::VectorXd running = Eigen::VectorXd::Zero(rb.x.rows());
      for (int r = 1; r <= m; ++r) {
        running += rb.x.col(r - 1);
        const Eigen::VectorXd uS = uS0 + rb.smallStep * (double(r) * vS0 + running);
        const Eigen::VectorXd vS = vS0 + rb.x.col(r - 1);
        observer_(i, r, substepTime(r, m, rb.smallStep), uS, vS);
      }
    }
  }
  for (std::size_t k = 0; k < large.size(); ++k) {
    d.newV[large[k]] = v0[large[k]] + d.Y[static_cast<Eigen::Index>(k)];
    d.newU[large[k]] = u0[large[k]] + hL * d.newV[large[k]];
  }
  stats_.solveSeconds += solve.stop();

  detail::checkFiniteState("async", d.newU, d.newV, t1);
  std::swap(displacement_, d.newU);
  std::swap(velocity_, d.newV);
  advanceTime();
  ++stats_.steps;
  // Solve counts and flops, totalled over the solvers (Z columns included).
  stats_.solvedRightHandSides = 0;
  stats_.solveFlops = 0.0;
  detail::addSolveCounts(*d.naiveSolver, stats_);
  if (d.schurSolver) detail::addSolveCounts(*d.schurSolver, stats_);
  for (const RegionBlocks& rb : d.regions) {
    detail::addSolveCounts(*rb.solver, stats_);
    for (const auto& helper : rb.helperSolvers) detail::addSolveCounts(*helper, stats_);
  }
  ++runStats_.steps;
  runStats_.stepSeconds += whole.stop() - (runStats_.setupSeconds + runStats_.rebuildSeconds - rebuildBefore);
}

// out = H^{LL*} y for the current blocks: A-hat^L y minus, per region, the interface rows
// of H^{LS} (H^{SS})^{-1} H^{SL} y (one forward substitution per region).
void AsyncBackwardEuler::applySchur(const Eigen::VectorXd& y, Eigen::VectorXd& out) {
  Impl& d = *impl_;
  const bool damped = system_.damped();
  out.resize(y.size());
  out.noalias() = d.largeSystem * y;
  const int numRegions = partition_.numRegions();
  parallelTasks(numRegions, threadBudget(options_.threads), [&](int i) {
    RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    if (pos.empty()) return;
    rb.yInterface.resize(static_cast<Eigen::Index>(pos.size()));
    for (std::size_t k = 0; k < pos.size(); ++k) rb.yInterface[static_cast<Eigen::Index>(k)] = y[pos[k]];
    const CouplingCoefficients& k = rb.coupling;
    rb.massY.noalias() = rb.Msi * rb.yInterface;
    rb.stiffY.noalias() = rb.Ksi * rb.yInterface;
    if (damped) rb.dampY.noalias() = rb.Dsi * rb.yInterface;
    rb.probe.resize(rb.massY.size(), rb.ratio);
    for (int r = 1; r <= rb.ratio; ++r) {
      rb.probe.col(r - 1) = k.bM[r - 1] * rb.massY + k.bK[r - 1] * rb.stiffY;
      if (damped) rb.probe.col(r - 1) += k.bD[r - 1] * rb.dampY;
    }
    forwardSubstitute(rb, rb.probe, rb.probeSolution);
    weightedColumnSum(rb.probeSolution, k.eM, rb.weightedM);
    weightedColumnSum(rb.probeSolution, k.eK, rb.weightedK);
    rb.interfaceRow.noalias() = rb.Mis * rb.weightedM;
    rb.interfaceRow.noalias() += rb.Kis * rb.weightedK;
    if (damped) {
      weightedColumnSum(rb.probeSolution, k.eD, rb.weightedD);
      rb.interfaceRow.noalias() += rb.Dis * rb.weightedD;
    }
  });
  for (int i = 0; i < numRegions; ++i) {
    const std::vector<int>& pos = partition_.interfacePositions(i);
    const RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    for (std::size_t k = 0; k < pos.size(); ++k) out[pos[k]] -= rb.interfaceRow[static_cast<Eigen::Index>(k)];
  }
}

// H^{LL*} Y = rhs with the factor of the last full rebuild as preconditioner
// (AsyncOptions::laggedSchur): conjugate gradients for the stable coupling, whose H^{LL*}
// is symmetric, iterative refinement for the paper's. Returns false when it did not reach
// the tolerance.
bool AsyncBackwardEuler::iterativeSchur(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  Impl& d = *impl_;
  const double scale = rhs.norm();
  solveSchur(rhs, solution);
  if (scale == 0.0) return true;
  const bool conjugate = options_.coupling == AsyncCoupling::stable;
  applySchur(solution, d.schurProduct);
  d.schurResidual = rhs - d.schurProduct;  // r
  Eigen::VectorXd& direction = d.schurDirection;
  double rz = 0.0;
  for (int iteration = 1; iteration <= options_.laggedSchurIterations; ++iteration) {
    const double residual = d.schurResidual.norm() / scale;
    if (!std::isfinite(residual)) return false;
    if (residual <= options_.laggedSchurTolerance) {
      ++runStats_.laggedSteps;
      runStats_.largestSchurResidual = std::max(runStats_.largestSchurResidual, residual);
      d.refreshNext = iteration > options_.laggedSchurIterations / 2;  // slow: the next step rebuilds
      return true;
    }
    ++runStats_.schurIterations;
    solveSchur(d.schurResidual, d.schurCorrection);  // z = P^{-1} r
    if (!conjugate) {
      solution += d.schurCorrection;
      applySchur(solution, d.schurProduct);
      d.schurResidual = rhs - d.schurProduct;
      continue;
    }
    const double rzNew = d.schurResidual.dot(d.schurCorrection);
    if (iteration == 1) {
      direction = d.schurCorrection;
    } else {
      direction = d.schurCorrection + (rzNew / rz) * direction;
    }
    rz = rzNew;
    applySchur(direction, d.schurProduct);
    const double curvature = direction.dot(d.schurProduct);
    if (!(curvature > 0.0)) return false;
    const double step = rz / curvature;
    solution += step * direction;
    d.schurResidual -= step * d.schurProduct;
  }
  return false;
}

double AsyncBackwardEuler::solveFloorSeconds(int repeats) {
  Impl& d = *impl_;
  if (!d.built) throw Error("solveFloorSeconds: take one step first (the factors are built lazily)");
  std::vector<double> samples;
  for (int k = 0; k < std::max(1, repeats); ++k) {
    Stopwatch watch;
    if (options_.method == AsyncSolveMethod::naive) {
      d.naiveSolver->solve(Eigen::VectorXd::Random(d.naiveSystem.rows()));
    } else {
      for (RegionBlocks& rb : d.regions) {
        const bool dense = rb.useDenseZ || rb.Msi.cols() == 0;
        const int solves = dense ? rb.ratio : 2 * rb.ratio;
        const Eigen::VectorXd rhs = Eigen::VectorXd::Random(rb.systemMatrix.rows());
        for (int r = 0; r < solves; ++r) rb.solver->solve(rhs);
      }
      if (d.largeSystem.rows() > 0) d.schurSolver->solve(Eigen::VectorXd::Random(d.largeSystem.rows()));
    }
    samples.push_back(watch.stop());
  }
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

long long AsyncBackwardEuler::factorNonZeros() const {
  const Impl& d = *impl_;
  long long total = 0;
  if (options_.method == AsyncSolveMethod::naive) return d.naiveSolver->stats().factorNonZeros;
  for (const RegionBlocks& rb : d.regions) total += rb.solver->stats().factorNonZeros;
  return total + (d.schurSolver ? d.schurSolver->stats().factorNonZeros : 0);
}

std::vector<std::string> AsyncBackwardEuler::runReport() const {
  const AsyncRunStats& r = runStats_;
  char line[256];
  std::vector<std::string> lines;
  std::snprintf(line, sizeof(line),
                "async set-up %.3f s (Z %.3f s over %lld right-hand sides on %d threads, H^LL* %.3f s); |S| %d, "
                "|I| %d, |L| %d DOFs",
                r.setupSeconds, r.setupZSeconds, r.zColumns, r.zThreads, r.setupSchurSeconds, r.fastDofs,
                r.interfaceDofs, r.largeDofs);
  lines.emplace_back(line);
  std::snprintf(line, sizeof(line), "async steady large step %.3f ms over %lld steps; rebuilds %lld (%.3f s)",
                1000.0 * r.meanStepSeconds(), r.steps, r.rebuilds, r.rebuildSeconds);
  lines.emplace_back(line);
  if (r.laggedSteps > 0) {
    std::snprintf(line, sizeof(line), "async lagged Schur: %lld steps, %lld iterations, largest relative residual %.2e",
                  r.laggedSteps, r.schurIterations, r.largestSchurResidual);
    lines.emplace_back(line);
  }
  return lines;
}

}  // namespace asyncfem
