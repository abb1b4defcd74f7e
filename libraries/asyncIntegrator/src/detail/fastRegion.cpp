// SPDX-License-Identifier: BSD-3-Clause
// A fast region's blocks and solves. Equation numbers refer to docs/asynchronous-integrator.md.
#include "detail/fastRegion.hpp"

#include <algorithm>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/integrator/stepFormula.hpp>
#include <asyncfem/modalAnalysis/generalizedEigen.hpp>

#include "detail/multirateSupport.hpp"
#include "detail/parallelTasks.hpp"
#include "detail/sparseBlocks.hpp"

extern "C" {
// BLAS (Fortran calling convention): C = alpha op(A) op(B) + beta C.
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* b, const int* ldb, const double* beta, double* c,
            const int* ldc);
}

namespace asyncfem::detail {

namespace {

/// out = a b through the BLAS's dgemm, on factorBlasThreads() (dgemm's bits depend on the
/// thread count): several times Eigen's speed on the dense products of the modal Z, since
/// the BLAS picks the machine's vector instructions at run time.
void denseProduct(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, Eigen::MatrixXd& out) {
  out.resize(a.rows(), b.cols());
  const int m = static_cast<int>(a.rows()), n = static_cast<int>(b.cols()), k = static_cast<int>(a.cols());
  if (m == 0 || n == 0) return;
  if (k == 0) {
    out.setZero();
    return;
  }
  const double one = 1.0, zero = 0.0;
  const ScopedBlasThreads blas(factorBlasThreads());
  dgemm_("N", "N", &m, &n, &k, &one, a.data(), &m, b.data(), &k, &zero, out.data(), &m);
}

}  // namespace

FastRegion::FastRegion(const SparseMatrix& mass, const SparseMatrix& stiffnessPattern, const RegionLayout& layout,
                       SolverKind solverKind, int denseDofs)
    : ratio(layout.ratio), denseDofs_(denseDofs) {
  const std::vector<int>& s = *layout.dofs;
  const std::vector<int>& iface = *layout.interfaceDofs;
  massSS = SubmatrixExtractor(mass, s, s);
  massSI = SubmatrixExtractor(mass, s, iface);
  massIS = SubmatrixExtractor(mass, iface, s);
  stiffSS = SubmatrixExtractor(stiffnessPattern, s, s);
  stiffSI = SubmatrixExtractor(stiffnessPattern, s, iface);
  stiffIS = SubmatrixExtractor(stiffnessPattern, iface, s);
  Mss = massSS.extract(mass);
  Msi = massSI.extract(mass);
  Mis = massIS.extract(mass);
  // Fast regions are analysed at every (re-)partition: AMD where it is the cheaper analysis.
  solver = makeSparseSolver(solverKind, FillOrdering::automatic);
}

void FastRegion::updateStiffnessBlocks(const SparseMatrix& stiffness) {
  updateBlock(stiffSS, stiffness, Kss, cut);
  updateBlock(stiffSI, stiffness, Ksi, cut);
  updateBlock(stiffIS, stiffness, Kis, cut);
  cut = true;
}

void FastRegion::updateBlocks(const SparseMatrix& stiffness, double largeStep, double alpha, double beta, bool damped,
                              AsyncCoupling couplingKind) {
  const double hS = largeStep / ratio;
  smallStep = hS;
  alpha_ = damped ? alpha : 0.0;
  beta_ = damped ? beta : 0.0;
  // A^S and G are rebuilt from K below: contact blocks in them go with their old values.
  contactSaved_.clear();
  contactPositions.clear();
  contactBlocks.clear();
  contactStiffness.clear();
  contactShortcut.clear();
  updateStiffnessBlocks(stiffness);
  if (damped) {
    combineInto(alpha, Mss, beta, Kss, Dss);
    combineInto(alpha, Msi, beta, Ksi, Dsi);
    combineInto(alpha, Mis, beta, Kis, Dis);
  }
  // A^S = M^{SS} + hS D^{SS} + hS^2 K^{SS}: backward Euler's matrix at hS (Eq. A1).
  const stepFormula::MatrixWeights weights = stepFormula::backwardEuler::systemMatrix(hS, alpha, beta);
  combineInto(weights.mass, Mss, weights.stiffness, Kss, systemMatrix);
  massWeight_ = weights.mass;
  stiffnessWeight_ = weights.stiffness;
  combineInto(0.0, Mss, hS * hS, Kss, G);
  refreshTranspose();
  if (dense.factor) Gdense = G;
  rhsWeight = 1.0 / (1.0 + hS * alpha);
  stepWeight = (1.0 + beta / hS) / (1.0 + hS * alpha);
  coupling = couplingCoefficients(couplingKind, ratio, largeStep);
}

void FastRegion::factorize(IntegratorStats& stats) {
  if (!analyzed && !denseDecided_) chooseDenseFactor();
  factorizeCounted(*solver, systemMatrix, analyzed, stats);
}

bool FastRegion::setContactBlocks(const std::vector<std::array<int, 3>>& positions,
                                  const std::vector<Eigen::Matrix3d>& blocks,
                                  const std::vector<Eigen::Matrix3d>& stiffness) {
  if (positions == contactPositions && blocks == contactBlocks && stiffness == contactStiffness) return false;
  restoreEntries(contactSaved_);
  contactPositions = positions;
  contactBlocks = blocks;
  contactStiffness = stiffness;
  contactShortcut.clear();
  for (std::size_t k = 0; k < positions.size(); ++k) {
    contactShortcut.push_back(rhsWeight * (((beta_ / smallStep) * stiffness[k]) - (blocks[k] - stiffness[k])));
    forBlockEntries(positions[k], [&](int r, int c, int row, int column) {
      addKeepingEntry(systemMatrix, row, column, blocks[k](r, c), contactSaved_, "a fast region's A^S");
      addKeepingEntry(G, row, column, stiffness[k](r, c), contactSaved_, "a fast region's G");
    });
  }
  refreshTranspose();
  if (dense.factor) Gdense = G;
  return true;
}

void FastRegion::addShortcutCorrection(const double* t, double* out) const {
  for (std::size_t k = 0; k < contactPositions.size(); ++k) {
    forBlockEntries(contactPositions[k],
                    [&](int r, int c, int row, int column) { out[row] += contactShortcut[k](r, c) * t[column]; });
  }
}

void FastRegion::addContactProduct(const Eigen::MatrixXd& z, Eigen::MatrixXd& y) const {
  for (std::size_t k = 0; k < contactPositions.size(); ++k) {
    const Eigen::Matrix3d damping = contactBlocks[k] - contactStiffness[k];  // hS C_c
    forBlockEntries(contactPositions[k], [&](int r, int c, int row, int column) {
      double running = 0.0;
      for (Eigen::Index j = 0; j < z.cols(); ++j) {
        running += z(column, j);
        y(row, j) += (contactStiffness[k](r, c) * running) + (damping(r, c) * z(column, j));
      }
    });
  }
}

// A region of at most denseDofs_ free DOFs is factored dense, and G multiplied dense: there
// the dense substitutions cost less than a sparse factor's indexed ones plus its per-call
// work (callgrind, one thread: 40k against 50k instructions per solve on the shipped
// dragon's 111-DOF jaw; on the antenna's 192-DOF rod and ring the sparse one costs less).
// regionSolver = dense asks for it at any size.
void FastRegion::chooseDenseFactor() {
  denseDecided_ = true;
  if (solver->kind() != SolverKind::dense) {
    if (systemMatrix.rows() == 0 || systemMatrix.rows() > denseDofs_) return;
    solver = makeSparseSolver(SolverKind::dense);
  }
  dense.factor = true;
  Gdense = G;
}

namespace {

/// The 3 x 3 block rows of a matrix given by its transpose's columns (see
/// FastRegion::BlockRows); false where it has none.
bool layOutBlockRows(const SparseMatrix& transposed, std::vector<int>& start, std::vector<int>& column) {
  const int* outer = transposed.outerIndexPtr();
  const int* inner = transposed.innerIndexPtr();
  const Eigen::Index rows = transposed.outerSize();
  start.assign(1, 0);
  column.clear();
  if (rows % 3 != 0) return false;
  for (Eigen::Index b = 0; b < rows / 3; ++b) {
    const int first = outer[3 * b], length = outer[(3 * b) + 1] - first;
    if (length % 3 != 0) return false;
    for (int i = 1; i < 3; ++i) {
      const int other = outer[(3 * b) + i];
      if (outer[(3 * b) + i + 1] - other != length || !std::equal(inner + first, inner + first + length, inner + other))
        return false;
    }
    for (int k = first; k < first + length; k += 3) {
      if (inner[k] % 3 != 0 || inner[k + 1] != inner[k] + 1 || inner[k + 2] != inner[k] + 2) return false;
      column.push_back(inner[k] / 3);
    }
    start.push_back(static_cast<int>(column.size()));
  }
  return true;
}

}  // namespace

void FastRegion::refreshTranspose() {
  BlockRows& blocks = blockG_;
  if (transposeInto(G, GT, gtPattern_)) {
    if (!layOutBlockRows(GT, blocks.start, blocks.column)) blocks.column.clear();
    blocks.values.resize(9 * blocks.column.size());
  }
  if (blocks.column.empty()) return;
  // Block k of block row b holds, row by row, entries 3 t .. 3 t + 2 of G^T's columns
  // 3 b, 3 b + 1, 3 b + 2 (t = k - start[b]).
  const int* outer = GT.outerIndexPtr();
  const double* values = GT.valuePtr();
  for (std::size_t b = 0; b + 1 < blocks.start.size(); ++b) {
    for (int k = blocks.start[b]; k < blocks.start[b + 1]; ++k) {
      const int offset = 3 * (k - blocks.start[b]);
      for (int i = 0; i < 3; ++i)
        for (int c = 0; c < 3; ++c)
          blocks.values[(9 * static_cast<std::size_t>(k)) + (3 * i) + c] = values[outer[(3 * b) + i] + offset + c];
    }
  }
}

void FastRegion::subtractStiffnessProduct(const double* t, double* out) const {
  if (dense.factor) {
    const Eigen::Index size = Gdense.rows();
    Eigen::Map<Eigen::VectorXd>(out, size).noalias() -= Gdense * Eigen::Map<const Eigen::VectorXd>(t, size);
    return;
  }
  if (!blockG_.column.empty()) {
    const int* start = blockG_.start.data();
    const int* column = blockG_.column.data();
    const double* values = blockG_.values.data();
    const auto blockRows = static_cast<Eigen::Index>(blockG_.start.size()) - 1;
    for (Eigen::Index b = 0; b < blockRows; ++b) {
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (int k = start[b]; k < start[b + 1]; ++k) {
        const double* x = t + (3 * static_cast<std::ptrdiff_t>(column[k]));
        const double* a = values + (9 * static_cast<std::ptrdiff_t>(k));
        s0 += a[0] * x[0];
        s0 += a[1] * x[1];
        s0 += a[2] * x[2];
        s1 += a[3] * x[0];
        s1 += a[4] * x[1];
        s1 += a[5] * x[2];
        s2 += a[6] * x[0];
        s2 += a[7] * x[1];
        s2 += a[8] * x[2];
      }
      out[3 * b] -= s0;
      out[(3 * b) + 1] -= s1;
      out[(3 * b) + 2] -= s2;
    }
    return;
  }
  // Row by row through G^T's columns: one gathered dot product and one write per row,
  // instead of a scattered update per entry.
  const int* outer = GT.outerIndexPtr();
  const int* inner = GT.innerIndexPtr();
  const double* values = GT.valuePtr();
  const Eigen::Index size = GT.outerSize();
  for (Eigen::Index row = 0; row < size; ++row) {
    double sum = 0.0;
    for (int k = outer[row]; k < outer[row + 1]; ++k) sum += values[k] * t[inner[k]];
    out[row] -= sum;
  }
}

// Column c of outT is a sum of length-k vector updates over column c of G^T (row c of G).
void FastRegion::rowWiseStiffnessProduct(const Eigen::MatrixXd& tT, Eigen::MatrixXd& outT) const {
  if (dense.factor) {
    outT.noalias() = tT * Gdense.transpose();
    return;
  }
  const int* outer = GT.outerIndexPtr();
  const int* inner = GT.innerIndexPtr();
  const double* values = GT.valuePtr();
  outT.setZero();
  for (Eigen::Index c = 0; c < GT.outerSize(); ++c)
    for (int k = outer[c]; k < outer[c + 1]; ++k) outT.col(c) += values[k] * tT.col(inner[k]);
}

// G sum_{i<r} x_i is a running sum; M^{SS} x_{r-1} comes from the previous right-hand side.
void FastRegion::forwardSubstitute(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
  const Eigen::Index size = b.rows();
  x.resize(size, b.cols());
  runningStiffness.setZero(size);  // w = sum_{i<r} x_i
  combined.resize(size);
  for (int r = 1; r <= ratio; ++r) {
    if (r == 1) {
      substepRhs = b.col(0);
    } else {
      // rhs_r = rhsWeight rhs_{r-1} + b_r - G (stepWeight x_{r-1} + w).
      runningStiffness += x.col(r - 2);
      combined = runningStiffness + stepWeight * x.col(r - 2);
      substepRhs *= rhsWeight;
      substepRhs += b.col(r - 1);
      subtractStiffnessProduct(combined.data(), substepRhs.data());
      if (!contactPositions.empty()) addShortcutCorrection(x.col(r - 2).data(), substepRhs.data());
    }
    solver->solve(substepRhs, substepSolution);
    x.col(r - 1) = substepSolution.col(0);
  }
}

void FastRegion::interfaceRowOf(const Eigen::MatrixXd& columns, bool damped) {
  weightedM.noalias() = columns * coupling.eM;
  weightedK.noalias() = columns * coupling.eK;
  interfaceRow.resize(Mis.rows());
  interfaceRow.noalias() = Mis * weightedM;
  interfaceRow.noalias() += Kis * weightedK;
  if (damped) {
    weightedD.noalias() = columns * coupling.eD;
    interfaceRow.noalias() += Dis * weightedD;
  }
}

void FastRegion::couplingProducts(bool damped) {
  massY.noalias() = Msi * yInterface;
  stiffY.noalias() = Ksi * yInterface;
  if (damped) dampY.noalias() = Dsi * yInterface;
}

void FastRegion::correctionColumns(SparseSolver& columnSolver, bool damped, Eigen::Index first, Eigen::Index width,
                                   int block) {
  const Eigen::Index size = systemMatrix.rows();
  const CouplingCoefficients& k = coupling;
  ColumnScratch& w = columnScratch[static_cast<std::size_t>(block)];
  w.rhsColumns.setZero(size, width);
  w.combinedT.resize(width, size);
  w.productT.resize(width, size);
  w.runningT.setZero(width, size);  // (sum_{i<r} Z_i)^T
  w.sumM.setZero(size, width);
  w.sumK.setZero(size, width);
  if (damped) w.sumD.setZero(size, width);
  if (dense.recovery) w.sum.setZero(size, width);
  const bool reachToo = dense.recovery && dense.trackReach;
  if (reachToo) w.reach.setZero(size);
  // rhsColumns += scale * block(:, first .. first + width), for a sparse block of H^{SI}.
  const auto addColumns = [&](const SparseMatrix& matrix, double scale) {
    if (scale == 0.0) return;
    for (Eigen::Index c = 0; c < width; ++c)
      for (SparseMatrix::InnerIterator it(matrix, first + c); it; ++it) w.rhsColumns(it.row(), c) += scale * it.value();
  };
  for (int r = 1; r <= ratio; ++r) {
    // Row r of H^{SS} Z = H^{SI}: A^S Z_r = B_r + M^{SS} Z_{r-1} - G sum_{i<r} Z_i.
    if (r >= 2) {
      w.runningT += w.z.transpose();
      w.combinedT = w.runningT;
      w.combinedT += stepWeight * w.z.transpose();
      rowWiseStiffnessProduct(w.combinedT, w.productT);
      w.rhsColumns *= rhsWeight;
      w.rhsColumns -= w.productT.transpose();
      for (Eigen::Index c = 0; c < width && !contactPositions.empty(); ++c)
        addShortcutCorrection(w.z.col(c).data(), w.rhsColumns.col(c).data());
    }
    addColumns(Msi, k.bM[r - 1]);
    addColumns(Ksi, k.bK[r - 1]);
    if (damped) addColumns(Dsi, k.bD[r - 1]);
    columnSolver.solve(w.rhsColumns, w.z);
    if (k.eM[r - 1] != 0.0) w.sumM += k.eM[r - 1] * w.z;
    w.sumK += k.eK[r - 1] * w.z;
    if (damped) w.sumD += k.eD[r - 1] * w.z;
    if (dense.recovery) w.sum += w.z;
    if (reachToo) w.reach = w.reach.cwiseMax(w.sum.rowwise().squaredNorm());
  }
  if (dense.recovery) {
    zLast.middleCols(first, width) = w.z;
    zSum.middleCols(first, width) = w.sum;
  }
  w.columns.noalias() = Mis * w.sumM;
  w.columns.noalias() += Kis * w.sumK;
  if (damped) w.columns.noalias() += Dis * w.sumD;
  correction.middleCols(first, width) = w.columns;
}

bool FastRegion::correctionFromModes(bool damped) {
  if (!contactPositions.empty()) return false;
  const auto sizeS = static_cast<Eigen::Index>(Mss.rows());
  Eigen::MatrixXd modes = Kss.toDense();  // Phi once solved
  if ((modes - modes.transpose()).cwiseAbs().maxCoeff() > 1e-13 * modes.cwiseAbs().maxCoeff()) return false;
  Eigen::MatrixXd mass = Mss.toDense();
  Eigen::VectorXd lambda;
  if (!solveGeneralizedEigen(modes, mass, lambda)) return false;
  // In modal coordinates A^S, M^{SS} and G are diagonal: a = massWeight + stiffnessWeight
  // lambda, 1 and hS^2 lambda. B_r = bM_r M^{SI} + bK_r K^{SI} + bD_r (alpha M^{SI} + beta
  // K^{SI}), so Phi^T Z_r = cM_r Phi^T M^{SI} + cK_r Phi^T K^{SI} with per-mode scalars from
  // a cM_r = (bM_r + alpha bD_r) + cM_{r-1} - hS^2 lambda sum_{i<r} cM_i (cK_r likewise).
  // weights(k, j): mode k's sum over r of (eM, eK, eD)[j / 2] times (cM, cK)[j % 2]; then the
  // last substep's and the plain sums (dense recovery).
  const CouplingCoefficients& k = coupling;
  Eigen::MatrixXd weights = Eigen::MatrixXd::Zero(sizeS, 10);
  for (Eigen::Index mode = 0; mode < sizeS; ++mode) {
    const double a = massWeight_ + stiffnessWeight_ * lambda[mode];
    const double g = smallStep * smallStep * lambda[mode];
    double c[2] = {0.0, 0.0}, running[2] = {0.0, 0.0};
    for (int r = 1; r <= ratio; ++r) {
      const double input[2] = {k.bM[r - 1] + (damped ? alpha_ * k.bD[r - 1] : 0.0),
                               k.bK[r - 1] + (damped ? beta_ * k.bD[r - 1] : 0.0)};
      for (int j = 0; j < 2; ++j) {
        c[j] = (input[j] + c[j] - g * running[j]) / a;
        running[j] += c[j];
        weights(mode, j) += k.eM[r - 1] * c[j];
        weights(mode, 2 + j) += k.eK[r - 1] * c[j];
        if (damped) weights(mode, 4 + j) += k.eD[r - 1] * c[j];
      }
    }
    for (int j = 0; j < 2; ++j) {
      weights(mode, 6 + j) = c[j];
      weights(mode, 8 + j) = running[j];
    }
  }
  const auto q = static_cast<Eigen::Index>(Msi.cols());
  const Eigen::MatrixXd projectedM = modes.transpose() * Msi, projectedK = modes.transpose() * Ksi;  // |S| x q
  // C_i = [M^{IS} Phi, K^{IS} Phi, D^{IS} Phi] [W_M; W_K; W_D], W_X = Phi^T (sum_r e^X_r Z_r)
  // (column pair 2x of weights), and with dense recovery [Z_m, sum_r Z_r] = Phi [Phi^T Z_m,
  // Phi^T sum_r Z_r] (pairs 3 and 4): one product each, through the BLAS (dgemm).
  const int blocks = damped ? 3 : 2;
  Eigen::MatrixXd projectedInterface(q, blocks * sizeS), combined(blocks * sizeS, q);
  const SparseMatrix* interfaceRows[3] = {&Mis, &Kis, &Dis};
  for (int x = 0; x < blocks; ++x) {
    projectedInterface.middleCols(x * sizeS, sizeS).noalias() = *interfaceRows[x] * modes;
    combined.middleRows(x * sizeS, sizeS) =
        weights.col(2 * x).asDiagonal() * projectedM + weights.col((2 * x) + 1).asDiagonal() * projectedK;
  }
  denseProduct(projectedInterface, combined, correction);
  if (dense.recovery) {
    Eigen::MatrixXd ends(sizeS, 2 * q), both;
    for (int x = 0; x < 2; ++x) {
      ends.middleCols(x * q, q) =
          weights.col(6 + (2 * x)).asDiagonal() * projectedM + weights.col(7 + (2 * x)).asDiagonal() * projectedK;
    }
    denseProduct(modes, ends, both);
    zLast = both.leftCols(q);
    zSum = both.rightCols(q);
  }
  return true;
}

double FastRegion::substitutionPrice() const {
  const double sizeS = static_cast<double>(Mss.rows());
  const double perColumn = solver->stats().solveFlopsPerRhs + (4.0 * static_cast<double>(Kss.nonZeros())) +
                           (12.0 * sizeS);  // the solve, the product with G, the running sums
  return static_cast<double>(ratio) * static_cast<double>(Msi.cols()) * perColumn;
}

double FastRegion::modalPrice() const {
  const double sizeS = static_cast<double>(Mss.rows()), q = static_cast<double>(Msi.cols());
  // dsygvd with vectors about 9 n^3; the three products of C_i 2 q^2 n each; Z_m and
  // sum_r Z_r (dense recovery) 2 n^2 q each.
  return (9.0 * sizeS * sizeS * sizeS) + (6.0 * q * q * sizeS) + (dense.recovery ? 4.0 * sizeS * sizeS * q : 0.0);
}

void FastRegion::assembleInterfaceStiffness(const ForceModel& forceModel, const Eigen::VectorXd& u, bool perElement) {
  const auto q = static_cast<Eigen::Index>(Mis.rows());
  interfaceStiffness.setZero(q, q);
  for (InterfaceElement& element : interfaceElements) {
    if (perElement) forceModel.elementTangentOfAnyKind(u, element.element, element.tangent);
    const auto size = static_cast<int>(element.interfaceIndex.size());
    for (int b = 0; b < size; ++b) {
      const int column = element.interfaceIndex[static_cast<std::size_t>(b)];
      if (column < 0) continue;
      for (int a = 0; a < size; ++a) {
        const int row = element.interfaceIndex[static_cast<std::size_t>(a)];
        if (row >= 0) interfaceStiffness(row, column) += element.tangent(a, b);
      }
    }
  }
}

namespace {

/// Largest dense Z (doubles) the automatic recovery stores: 16M doubles = 128 MiB.
constexpr double kMaxDenseZEntries = 16.0 * 1024 * 1024;
/// Fewest Z columns worth a thread of their own (below, the copy of the A^S factor costs
/// more than the columns it takes over).
constexpr Eigen::Index kMinZColumnsPerThread = 24;

/// Recovery: the end state needs X_m = y_m - Z_m Y_I and sum_r X_r = sum_r y_r - (sum_r Z_r)
/// Y_I (4 |S| q flops, 2 |S| q doubles), or a second forward substitution (m solves and 2m
/// sparse products). Automatic picks the cheaper in flops while the two blocks fit.
bool chooseDenseZ(const FastRegion& region, RecoveryMode mode) {
  const Eigen::Index q = region.Msi.cols();
  const Eigen::Index sizeS = region.systemMatrix.rows();
  const double denseFlops = 4.0 * static_cast<double>(sizeS) * static_cast<double>(q);
  const double substitutionFlops =
      region.ratio * (region.solver->stats().solveFlopsPerRhs + 4.0 * static_cast<double>(region.Kss.nonZeros()));
  return mode == RecoveryMode::denseZ ||
         (mode == RecoveryMode::automatic && denseFlops <= substitutionFlops &&
          2.0 * static_cast<double>(sizeS) * static_cast<double>(q) <= kMaxDenseZEntries);
}

/// A dense flop of the modal path (BLAS 3, LAPACK) against a flop of the substitutions
/// (sparse solves with a small factor and sparse products, of a few columns at a time):
/// what one costs in time against the other, measured in the set-ups of
/// docs/benchmarks.md ("Z from the region's modes").
constexpr double kDenseFlopAdvantage = 4.0;

/// Whether region takes Z from its modes (ZSolve), before trying.
bool wantsModes(const FastRegion& region, ZSolve mode) {
  if (mode == ZSolve::substitution || region.hasContactBlocks() || (region.dense.recovery && region.dense.trackReach))
    return false;
  return mode == ZSolve::modes || region.modalPrice() < kDenseFlopAdvantage * region.substitutionPrice();
}

struct ColumnTask {
  int region = 0;
  int block = 0;  // 0: the region's own solver, j > 0: helperSolvers[j - 1]
  Eigen::Index first = 0, width = 0;
};

}  // namespace

CorrectionRun computeCorrections(std::vector<FastRegion>& regions, const AsyncOptions& options, bool damped) {
  const int threads = threadBudget(options.threads);
  std::vector<ColumnTask> tasks;
  std::vector<std::pair<int, int>> helpers;  // (region, helper) factorizations to run
  CorrectionRun run;
  // Regions whose modes are cheaper than their substitutions first (one task each; the
  // eigensolver runs on one BLAS thread).
  std::vector<int> modal;
  std::vector<char> fromModes(regions.size(), 0);
  for (std::size_t i = 0; i < regions.size(); ++i) {
    FastRegion& rb = regions[i];
    const Eigen::Index q = rb.Msi.cols();
    const Eigen::Index sizeS = rb.systemMatrix.rows();
    rb.dense.recovery = rb.owned && chooseDenseZ(rb, options.recovery);
    rb.correction.resize(q, q);
    rb.zLast.resize(rb.dense.recovery ? sizeS : 0, rb.dense.recovery ? q : 0);
    rb.zSum.resize(rb.dense.recovery ? sizeS : 0, rb.dense.recovery ? q : 0);
    if (!rb.owned) rb.correction.setZero();  // the owner's C_i arrives by the sum over processes
    if (q > 0 && rb.owned && wantsModes(rb, options.zSolve)) modal.push_back(static_cast<int>(i));
  }
  parallelTasks(static_cast<int>(modal.size()), threads, [&](int t) {
    const auto i = static_cast<std::size_t>(modal[static_cast<std::size_t>(t)]);
    fromModes[i] = regions[i].correctionFromModes(damped) ? 1 : 0;
  });
  for (std::size_t i = 0; i < regions.size(); ++i) {
    FastRegion& rb = regions[i];
    const Eigen::Index q = rb.Msi.cols();
    if (fromModes[i]) ++run.modalRegions;
    if (q == 0 || !rb.owned || fromModes[i]) continue;
    run.columns += static_cast<long long>(rb.ratio) * q;
    const int blocks =
        static_cast<int>(std::max<Eigen::Index>(1, std::min<Eigen::Index>(threads, q / kMinZColumnsPerThread)));
    run.threads = std::max(run.threads, blocks);
    while (static_cast<int>(rb.helperSolvers.size()) < blocks - 1) {
      rb.helperSolvers.push_back(makeSparseSolver(rb.solver->kind(), FillOrdering::automatic));
      rb.helperAnalyzed.push_back(0);
    }
    if (static_cast<int>(rb.columnScratch.size()) < blocks) rb.columnScratch.resize(static_cast<std::size_t>(blocks));
    for (int j = 1; j < blocks; ++j) helpers.emplace_back(static_cast<int>(i), j - 1);
    for (int j = 0; j < blocks; ++j) {
      const Eigen::Index first = q * j / blocks, last = q * (j + 1) / blocks;
      tasks.push_back({static_cast<int>(i), j, first, last - first});
    }
  }
  parallelTasks(static_cast<int>(helpers.size()), threads, [&](int t) {
    FastRegion& rb = regions[static_cast<std::size_t>(helpers[static_cast<std::size_t>(t)].first)];
    const auto j = static_cast<std::size_t>(helpers[static_cast<std::size_t>(t)].second);
    if (!rb.helperAnalyzed[j]) {
      rb.helperSolvers[j]->analyzePattern(rb.systemMatrix);
      rb.helperAnalyzed[j] = 1;
    }
    rb.helperSolvers[j]->factorize(rb.systemMatrix);
  });
  run.helperFactorizations = static_cast<long long>(helpers.size());
  parallelTasks(static_cast<int>(tasks.size()), threads, [&](int t) {
    const ColumnTask& task = tasks[static_cast<std::size_t>(t)];
    FastRegion& rb = regions[static_cast<std::size_t>(task.region)];
    SparseSolver& solver = task.block == 0 ? *rb.solver : *rb.helperSolvers[static_cast<std::size_t>(task.block - 1)];
    rb.correctionColumns(solver, damped, task.first, task.width, task.block);
  });
  // Each block's squared row norms summed: the sum over blocks of each block's maximum over
  // r bounds the maximum over r of the whole rows' squared norms.
  for (FastRegion& rb : regions)
    rb.reach.setZero(rb.dense.recovery && rb.dense.trackReach ? rb.systemMatrix.rows() : 0);
  for (const ColumnTask& task : tasks) {
    FastRegion& rb = regions[static_cast<std::size_t>(task.region)];
    if (rb.reach.size() > 0) rb.reach += rb.columnScratch[static_cast<std::size_t>(task.block)].reach;
  }
  for (FastRegion& rb : regions) rb.reach = rb.smallStep * rb.reach.cwiseSqrt();
  return run;
}

}  // namespace asyncfem::detail
