// SPDX-License-Identifier: BSD-3-Clause
// Asynchronous implicit backward Euler. Equation numbers (A1)-(A12) refer to
// docs/asynchronous-integrator.md, section "Method".
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

/// A dense q x q block scattered into a |L| x |L| sparse matrix at the listed positions,
/// every entry stored (so the pattern never depends on values).
SparseMatrix scatterDense(const Eigen::MatrixXd& block, const std::vector<int>& positions, int size) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(block.size()));
  for (Eigen::Index c = 0; c < block.cols(); ++c)
    for (Eigen::Index r = 0; r < block.rows(); ++r)
      triplets.emplace_back(positions[static_cast<std::size_t>(r)], positions[static_cast<std::size_t>(c)],
                            block(r, c));
  SparseMatrix out(size, size);
  out.setFromTriplets(triplets.begin(), triplets.end());
  return out;
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
  // Forward-substitution buffers, and whether M^{SS} and G share one pattern (fused products).
  Eigen::VectorXd runningStiffness, substepRhs;
  Eigen::MatrixXd substepSolution;
  bool massAndGSharePattern = false;
  std::unique_ptr<SparseSolver> solver;
  bool analyzed = false;
  std::vector<Eigen::MatrixXd> z;  // Z_r blocks (dense recovery only)
  bool useDenseZ = false;
  Eigen::MatrixXd correction;  // C_i = H^{IS} Z, q x q
};

/// H^{IS} x for x_1..x_m the columns of x (|S| x m or, for Z, blocks side by side): sum_i
/// E_i x_i = M^{IS} (x eM) + D^{IS} (x eD) + K^{IS} (x eK), Eq. (A7).
Eigen::MatrixXd applyInterfaceRow(const RegionBlocks& rb, bool damped, const Eigen::MatrixXd& weightedM,
                                  const Eigen::MatrixXd& weightedD, const Eigen::MatrixXd& weightedK) {
  Eigen::MatrixXd out = rb.Mis * weightedM;
  out += rb.Kis * weightedK;
  if (damped) out += rb.Dis * weightedD;
  return out;
}

/// mass = M^{SS} x and stiffness += G x for one column x (contiguous, |S| entries), in one
/// pass over the pattern the two share (they are cut from M and K, which share the
/// assembler's pattern).
void fusedColumnProducts(const RegionBlocks& rb, const double* x, double* mass, double* stiffness) {
  const int* outer = rb.Mss.outerIndexPtr();
  const int* inner = rb.Mss.innerIndexPtr();
  const double* massValues = rb.Mss.valuePtr();
  const double* stiffValues = rb.G.valuePtr();
  const Eigen::Index size = rb.Mss.outerSize();
  std::fill(mass, mass + size, 0.0);
  for (Eigen::Index column = 0; column < size; ++column) {
    const double xc = x[column];
    for (int k = outer[column]; k < outer[column + 1]; ++k) {
      mass[inner[k]] += massValues[k] * xc;
      stiffness[inner[k]] += stiffValues[k] * xc;
    }
  }
}

/// mass = M^{SS} x and stiffness += G x, column by column (x, mass, stiffness: |S| x k,
/// column-major and contiguous), fused when M^{SS} and G share a pattern, else by Eigen.
void massAndStiffnessProducts(const RegionBlocks& rb, const Eigen::MatrixXd& x, Eigen::MatrixXd& mass,
                              Eigen::MatrixXd& stiffness) {
  if (!rb.massAndGSharePattern) {
    mass.noalias() = rb.Mss * x;
    stiffness.noalias() += rb.G * x;
    return;
  }
  for (Eigen::Index c = 0; c < x.cols(); ++c)
    fusedColumnProducts(rb, x.col(c).data(), mass.col(c).data(), stiffness.col(c).data());
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
  double& schurAsymmetry = schurAsymmetry_;
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
    rb.massAndGSharePattern = samePattern(rb.Mss, rb.G);
    rb.coupling = couplingCoefficients(options.coupling, rb.ratio, hL);
  }
  if (options.coupling == AsyncCoupling::stable) subtractInterfaceStiffness();
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
  schurAsymmetry = 0.0;
  for (RegionBlocks& rb : d.regions) {
    detail::factorizeCounted(*rb.solver, rb.systemMatrix, rb.analyzed, stats);
    const int m = rb.ratio;
    const Eigen::Index q = rb.Msi.cols();
    const double sizeS = static_cast<double>(rb.systemMatrix.rows());
    rb.z.clear();
    // Recovery: X = y - Z Y_I (2 m |S| q flops, m |S| q doubles) or a second forward
    // substitution (m solves and 2m sparse products). Automatic picks the cheaper in flops
    // while Z fits in kMaxDenseZEntries.
    const double denseFlops = 2.0 * m * sizeS * static_cast<double>(q);
    const double substitutionFlops =
        m * (rb.solver->stats().solveFlopsPerRhs + 4.0 * static_cast<double>(rb.Kss.nonZeros()));
    rb.useDenseZ = options.recovery == RecoveryMode::denseZ ||
                   (options.recovery == RecoveryMode::automatic && denseFlops <= substitutionFlops &&
                    m * sizeS * static_cast<double>(q) <= kMaxDenseZEntries);
    if (q == 0) {
      rb.correction.resize(0, 0);
      continue;
    }
    // Z: one multi-right-hand-side solve per substep (|I| columns at once: BLAS-3 work
    // in the supernodal solve, threaded by the BLAS).
    Stopwatch zWatch;
    const Eigen::MatrixXd Msi = Eigen::MatrixXd(rb.Msi), Ksi = Eigen::MatrixXd(rb.Ksi);
    const Eigen::MatrixXd Dsi = damped ? Eigen::MatrixXd(rb.Dsi) : Eigen::MatrixXd();
    const CouplingCoefficients& k = rb.coupling;
    const Eigen::Index sizeRows = rb.systemMatrix.rows();
    // As in the step's forward substitution: G sum_{i<r} Z_i as a running sum, M^{SS} Z_{r-1}
    // and G Z_{r-1} in one pass.
    Eigen::MatrixXd runningStiffness = Eigen::MatrixXd::Zero(sizeRows, q), massProduct(sizeRows, q), prev, rhs, x;
    Eigen::MatrixXd weightedM = Eigen::MatrixXd::Zero(sizeRows, q), weightedK = weightedM, weightedD;
    if (damped) weightedD = weightedM;
    for (int r = 1; r <= m; ++r) {
      rhs = k.bM[r - 1] * Msi + k.bK[r - 1] * Ksi;
      if (damped) rhs += k.bD[r - 1] * Dsi;
      if (r >= 2) {
        massAndStiffnessProducts(rb, prev, massProduct, runningStiffness);
        rhs += massProduct - runningStiffness;
      }
      rb.solver->solve(rhs, x);
      if (k.eM[r - 1] != 0.0) weightedM += k.eM[r - 1] * x;
      weightedK += k.eK[r - 1] * x;
      if (damped) weightedD += k.eD[r - 1] * x;
      prev = x;
      if (rb.useDenseZ) rb.z.push_back(x);
    }
    // C_i = H^{IS} Z = sum_r E_r Z_r (Eq. A7).
    rb.correction = applyInterfaceRow(rb, damped, weightedM, weightedD, weightedK);
    zColumnSeconds_ += zWatch.stop();
    const double norm = rb.correction.norm();
    if (norm > 0.0) {
      schurAsymmetry = std::max(schurAsymmetry, (rb.correction - rb.correction.transpose()).norm() / norm);
    }
  }
  stats.factorizationSeconds += factor.stop();
  factor.start();
  buildSchurSolver();
  stats.factorizationSeconds += factor.stop();
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

  Stopwatch assembly;
  d.schur = d.largeSystem;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const Eigen::MatrixXd& c = d.regions[static_cast<std::size_t>(i)].correction;
    if (c.size() == 0) continue;
    const Eigen::MatrixXd applied = mode == SchurMode::symmetric ? Eigen::MatrixXd(0.5 * (c + c.transpose())) : c;
    d.schur -= scatterDense(applied, partition_.interfacePositions(i), numLarge);
  }
  d.schur.makeCompressed();
  stats_.assemblySeconds += assembly.stop();
  detail::factorizeCounted(*d.schurSolver, d.schur, d.schurAnalyzed, stats_);
}

Eigen::VectorXd AsyncBackwardEuler::solveSchur(const Eigen::VectorXd& rhs) {
  Impl& d = *impl_;
  Eigen::VectorXd y = d.schurSolver->solve(rhs);
  if (schurModeUsed_ != SchurMode::lowRank || d.interfaceUnion.empty()) return y;
  const Eigen::VectorXd yInterface = gather(y, d.interfaceUnion);
  const Eigen::VectorXd z = d.capacitance.solve(yInterface);
  y.noalias() += d.lowRankBasis * (d.unionCorrection * z);
  return y;
}

void AsyncBackwardEuler::step() {
  Impl& d = *impl_;
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

  detail::evaluateForces(system_, d.linear, d.built, u0, d.internalForce, d.stiffness, stats_);
  Stopwatch solve;
  if (!d.linear || !d.built) {
    rebuildBlocks();
    d.built = true;
  }

  solve.start();
  // Right-hand sides (design note): b_r = h (f_ext(t) - f_int(u_0) - (D + t K) v_0), t = r hS.
  const Eigen::VectorXd stiffVelocity = d.stiffness * v0;
  Eigen::VectorXd dampVelocity;
  if (damped) dampVelocity = alpha * (system_.mass * v0) + beta * stiffVelocity;
  // The state-dependent part, once per large step: f_int(u_0) + D v_0 (full vector).
  Eigen::VectorXd stateForce = d.internalForce;
  if (damped) stateForce += dampVelocity;
  Eigen::VectorXd externalForce, predicted;
  const std::vector<int>& large = partition_.largeDofs();
  const int numRegions = partition_.numRegions();
  std::vector<Eigen::MatrixXd> rhsS(static_cast<std::size_t>(numRegions));  // |S| x m, column r-1 = b_r
  for (int i = 0; i < numRegions; ++i) {
    const RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    Eigen::MatrixXd& b = rhsS[static_cast<std::size_t>(i)];
    b.resize(static_cast<Eigen::Index>(s.size()), rb.ratio);
    for (int r = 1; r <= rb.ratio; ++r) {
      const double tau = r * rb.smallStep;
      if (options_.substepStatePrediction && system_.externalForce) {
        predicted = u0 + tau * v0;
        externalForce.setZero(u0.size());
        system_.externalForce(substepTime(r, rb.ratio, rb.smallStep), predicted, v0, externalForce);
      } else {
        evaluateExternalForce(substepTime(r, rb.ratio, rb.smallStep), externalForce);
      }
      for (std::size_t k = 0; k < s.size(); ++k) {
        const int dof = s[k];
        b(static_cast<Eigen::Index>(k), r - 1) =
            rb.smallStep * (externalForce[dof] - stateForce[dof] - tau * stiffVelocity[dof]);
      }
    }
  }
  evaluateExternalForce(t1, externalForce);
  Eigen::VectorXd rhsL(static_cast<Eigen::Index>(large.size()));
  for (std::size_t k = 0; k < large.size(); ++k) {
    const int dof = large[k];
    rhsL[static_cast<Eigen::Index>(k)] = hL * (externalForce[dof] - stateForce[dof] - hL * stiffVelocity[dof]);
  }
  // Stable coupling: b^L += (1 - theta) hL^2 (K^{IS} v^S_0 + K_I^{II} v^I_0) (Eq. A12).
  for (int i = 0; i < numRegions && options_.coupling == AsyncCoupling::stable; ++i) {
    const RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    if (pos.empty()) continue;
    const Eigen::VectorXd correction =
        rb.coupling.interfaceWeight * (rb.Kis * gather(v0, partition_.regionDofs(i)) +
                                       rb.interfaceStiffness * gather(v0, partition_.interfaceDofs(i)));
    for (std::size_t k = 0; k < pos.size(); ++k) rhsL[pos[k]] += correction[static_cast<Eigen::Index>(k)];
  }

  // Solve for X (per region, |S| x m) and Y.
  std::vector<Eigen::MatrixXd> X(static_cast<std::size_t>(numRegions));
  Eigen::VectorXd Y;
  if (options_.method == AsyncSolveMethod::naive) {
    Eigen::VectorXd rhs(d.naiveSystem.rows());
    for (int i = 0; i < numRegions; ++i) {
      const Eigen::MatrixXd& b = rhsS[static_cast<std::size_t>(i)];
      rhs.segment(d.naiveOffsets[static_cast<std::size_t>(i)], b.size()) =
          Eigen::Map<const Eigen::VectorXd>(b.data(), b.size());
    }
    rhs.tail(rhsL.size()) = rhsL;
    const Eigen::VectorXd sol = d.naiveSolver->solve(rhs);
    for (int i = 0; i < numRegions; ++i) {
      const Eigen::MatrixXd& b = rhsS[static_cast<std::size_t>(i)];
      X[static_cast<std::size_t>(i)] = Eigen::Map<const Eigen::MatrixXd>(
          sol.data() + d.naiveOffsets[static_cast<std::size_t>(i)], b.rows(), b.cols());
    }
    Y = sol.tail(rhsL.size());
  } else {
    // Forward substitution with H^{SS} (Eq. A13): A^S x_r = b_r + M^{SS} x_{r-1} - G sum_{i<r} x_i.
    // G sum_{i<r} x_i is a running sum; M^{SS} x_{r-1} and G x_{r-1} are taken in one pass
    // over their shared pattern, into buffers kept across steps (no allocation per substep).
    auto forwardSubstitute = [&](RegionBlocks& rb, const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
      const Eigen::Index size = b.rows();
      x.resize(size, b.cols());
      rb.runningStiffness.setZero(size);
      rb.substepRhs.resize(size);
      for (int r = 1; r <= rb.ratio; ++r) {
        if (r == 1) {
          rb.substepRhs = b.col(0);
        } else {
          if (rb.massAndGSharePattern) {
            fusedColumnProducts(rb, x.col(r - 2).data(), rb.substepRhs.data(), rb.runningStiffness.data());
          } else {
            rb.substepRhs.noalias() = rb.Mss * x.col(r - 2);
            rb.runningStiffness.noalias() += rb.G * x.col(r - 2);
          }
          rb.substepRhs += b.col(r - 1) - rb.runningStiffness;
        }
        rb.solver->solve(rb.substepRhs, rb.substepSolution);
        x.col(r - 1) = rb.substepSolution.col(0);
      }
    };
    std::vector<Eigen::MatrixXd> y(static_cast<std::size_t>(numRegions));
    Eigen::VectorXd rhsSchur = rhsL;
    for (int i = 0; i < numRegions; ++i) {
      RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
      Eigen::MatrixXd& yi = y[static_cast<std::size_t>(i)];
      forwardSubstitute(rb, rhsS[static_cast<std::size_t>(i)], yi);
      if (rb.Mis.rows() == 0) continue;
      // b^{L*} = b^L - H^{LS} y = b^L - sum_r E_r y_r on the interface rows (Eq. A7).
      const CouplingCoefficients& k = rb.coupling;
      const Eigen::VectorXd coupling =
          applyInterfaceRow(rb, damped, yi * k.eM, damped ? Eigen::VectorXd(yi * k.eD) : Eigen::VectorXd(), yi * k.eK);
      const std::vector<int>& pos = partition_.interfacePositions(i);
      for (std::size_t k = 0; k < pos.size(); ++k) rhsSchur[pos[k]] -= coupling[static_cast<Eigen::Index>(k)];
    }
    Y = large.empty() ? Eigen::VectorXd() : solveSchur(rhsSchur);
    for (int i = 0; i < numRegions; ++i) {
      RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
      Eigen::MatrixXd& xi = X[static_cast<std::size_t>(i)];
      const std::vector<int>& pos = partition_.interfacePositions(i);
      if (pos.empty()) {
        xi = y[static_cast<std::size_t>(i)];
        continue;
      }
      Eigen::VectorXd yInterface(static_cast<Eigen::Index>(pos.size()));
      for (std::size_t k = 0; k < pos.size(); ++k) yInterface[static_cast<Eigen::Index>(k)] = Y[pos[k]];
      if (rb.useDenseZ) {
        xi = y[static_cast<std::size_t>(i)];
        for (int r = 1; r <= rb.ratio; ++r) xi.col(r - 1) -= rb.z[static_cast<std::size_t>(r - 1)] * yInterface;
      } else {
        // X = (H^{SS})^{-1} (b^S - H^{SL} Y), block r of H^{SL} Y = B_r Y_I.
        const CouplingCoefficients& k = rb.coupling;
        const Eigen::VectorXd mY = rb.Msi * yInterface, kY = rb.Ksi * yInterface;
        Eigen::VectorXd dY;
        if (damped) dY = rb.Dsi * yInterface;
        Eigen::MatrixXd b = rhsS[static_cast<std::size_t>(i)];
        for (int r = 1; r <= rb.ratio; ++r) {
          b.col(r - 1) -= k.bM[r - 1] * mY + k.bK[r - 1] * kY;
          if (damped) b.col(r - 1) -= k.bD[r - 1] * dY;
        }
        forwardSubstitute(rb, b, xi);
      }
    }
  }

  // New state: v^S_r = v^S_0 + X_r, u^S_m = u^S_0 + hS sum_r v^S_r; v^L = v^L_0 + Y, u^L = u^L_0 + hL v^L.
  Eigen::VectorXd newU = u0, newV = v0;
  for (int i = 0; i < numRegions; ++i) {
    const RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    const Eigen::MatrixXd& xi = X[static_cast<std::size_t>(i)];
    const Eigen::VectorXd vS0 = gather(v0, s), uS0 = gather(u0, s);
    Eigen::VectorXd xSum = Eigen::VectorXd::Zero(xi.rows());
    for (int r = 1; r <= rb.ratio; ++r) {
      xSum += xi.col(r - 1);
      if (observer_) {
        const Eigen::VectorXd uS = uS0 + rb.smallStep * (double(r) * vS0 + xSum);
        const Eigen::VectorXd vS = vS0 + xi.col(r - 1);
        observer_(i, r, substepTime(r, rb.ratio, rb.smallStep), uS, vS);
      }
    }
    const Eigen::VectorXd vS = vS0 + xi.col(rb.ratio - 1);
    const Eigen::VectorXd uS = uS0 + rb.smallStep * (double(rb.ratio) * vS0 + xSum);
    for (std::size_t k = 0; k < s.size(); ++k) {
      newV[s[k]] = vS[static_cast<Eigen::Index>(k)];
      newU[s[k]] = uS[static_cast<Eigen::Index>(k)];
    }
  }
  for (std::size_t k = 0; k < large.size(); ++k) {
    newV[large[k]] = v0[large[k]] + Y[static_cast<Eigen::Index>(k)];
    newU[large[k]] = u0[large[k]] + hL * newV[large[k]];
  }
  stats_.solveSeconds += solve.stop();

  detail::checkFiniteState("async", newU, newV, t1);
  displacement_ = std::move(newU);
  velocity_ = std::move(newV);
  advanceTime();
  ++stats_.steps;
  // Solve counts and flops, totalled over the solvers (Z columns included).
  stats_.solvedRightHandSides = 0;
  stats_.solveFlops = 0.0;
  detail::addSolveCounts(*d.naiveSolver, stats_);
  if (d.schurSolver) detail::addSolveCounts(*d.schurSolver, stats_);
  for (const RegionBlocks& rb : d.regions) detail::addSolveCounts(*rb.solver, stats_);
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
        const int solves = rb.useDenseZ ? rb.ratio : 2 * rb.ratio;
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

}  // namespace asyncfem
