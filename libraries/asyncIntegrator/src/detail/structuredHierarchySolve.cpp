// SPDX-License-Identifier: BSD-3-Clause
// Equation numbers refer to docs/asynchronous-integrator.md, "Nested and touching regions".
#include "detail/structuredHierarchySolve.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <cstdio>
#include <set>

#include "detail/sparseBlocks.hpp"

namespace asyncfem::detail {

namespace {

/// Levels of at most this many DOFs factor their Schur complement dense (as fast regions
/// of AsyncBackwardEuler do up to AsyncOptions::denseRegionDofs): the per-call work of a
/// sparse factor outweighs its savings there.
constexpr int kDenseLevelDofs = 128;
/// Z's columns are computed this many at a time (bounds the work array to cs x 64).
constexpr int kColumnsPerPass = 64;
/// Largest dense Z kept for recovery (doubles): 16M = 128 MiB per level.
constexpr double kMaxRecoveryEntries = 16.0 * 1024 * 1024;
/// Largest |S - S^T| / |S| treated as symmetric (Cholesky); round-off is about 1e-16.
constexpr double kSymmetric = 1e-10;

std::vector<int> nonZeroColumns(const SparseMatrix& m) {
  std::vector<int> out;
  for (Eigen::Index c = 0; c < m.outerSize(); ++c)
    if (m.outerIndexPtr()[c + 1] > m.outerIndexPtr()[c]) out.push_back(static_cast<int>(c));
  return out;
}

std::vector<int> nonZeroRows(const SparseMatrix& m) {
  std::vector<char> seen(static_cast<std::size_t>(m.rows()), 0);
  for (Eigen::Index c = 0; c < m.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(m, c); it; ++it) seen[static_cast<std::size_t>(it.row())] = 1;
  std::vector<int> out;
  for (std::size_t r = 0; r < seen.size(); ++r)
    if (seen[r] != 0) out.push_back(static_cast<int>(r));
  return out;
}

SparseMatrix cut(const SparseMatrix& m, Eigen::Index row, Eigen::Index column, Eigen::Index rows,
                 Eigen::Index columns) {
  SparseMatrix out = m.block(row, column, rows, columns);
  out.makeCompressed();
  return out;
}

}  // namespace

/// One level l of the chain: the blocks of a generic step (all steps have the same ones).
struct StructuredHierarchySolve::Level {
  int dofs = 0;                // n: free DOFs of this level
  int size = 0;                // unknowns of one block: childrenSize + 2 n
  int childrenSize = 0;        // unknowns of its child blocks (0 at the finest level)
  int children = 0;            // child blocks per block (c_{l+1} / c_l)
  SparseMatrix ownVV;          // own velocity rows x own v (momentum rows, Eq. N3)
  SparseMatrix ownWV;          // own position rows x own v (Eq. N5: -h_l I)
  SparseMatrix fromChildren;   // own velocity rows x children (Q)
  SparseMatrix toChildren;     // children rows x own v (R)
  SparseMatrix previous;       // this block's rows x its previous sibling's unknowns (P_l)
  std::vector<int> interface;  // own v positions R reads (I_l)
  std::vector<int> readByOwn;  // children positions Q reads
  std::vector<int> needed;     // children positions exact after a solve (N_l, Eq. N12)
  Eigen::MatrixXd zNeeded;     // rows `needed` of Z = (children)^{-1} R_I, for recovery
  bool denseRecovery = false;
  bool denseFactor = false;
  Eigen::PartialPivLU<Eigen::MatrixXd> dense;
  std::unique_ptr<SparseSolver> sparse;
  std::vector<int> patternOuter, patternInner;
  double solveFlops = 0.0;         // of one solve with the Schur complement
  double flops = 0.0;              // of one solveBlock (one column), sparse products included
  double substitutionFlops = 0.0;  // of its Schur solves alone (what SolverStats counts)
  double asymmetry = 0.0;
  Eigen::MatrixXd saved, solved, gathered, correction;
};

bool StructuredHierarchySolve::applies(const std::vector<int>& counts) {
  std::set<int> distinct(counts.begin(), counts.end());
  distinct.insert(1);
  int previous = 1;
  for (int c : distinct) {
    if (c <= 0 || c % previous != 0) return false;
    previous = c;
  }
  return true;
}

StructuredHierarchySolve::StructuredHierarchySolve(const std::vector<int>& dofCount, const std::vector<int>& offset,
                                                   int velocityUnknowns)
    : offset_(offset), velocityUnknowns_(velocityUnknowns) {
  if (!applies(dofCount)) {
    throw ValidationError(
        "nested async regions: the structured solve needs step counts that divide one another in a chain (e.g. 1, "
        "8, 32); use the LU solve for these regions");
  }
  std::set<int> distinct(dofCount.begin(), dofCount.end());
  distinct.insert(1);
  counts_.assign(distinct.begin(), distinct.end());
  dofsOf_.resize(counts_.size());
  dofLevel_.resize(dofCount.size());
  for (std::size_t d = 0; d < dofCount.size(); ++d) {
    const auto level = std::lower_bound(counts_.begin(), counts_.end(), dofCount[d]) - counts_.begin();
    dofLevel_[d] = static_cast<int>(level);
    dofsOf_[static_cast<std::size_t>(level)].push_back(static_cast<int>(d));
  }
  const int top = static_cast<int>(counts_.size()) - 1;
  levels_.resize(counts_.size());
  for (int l = top; l >= 0; --l) {
    auto level = std::make_unique<Level>();
    level->dofs = static_cast<int>(dofsOf_[static_cast<std::size_t>(l)].size());
    if (l < top) {
      level->children = counts_[static_cast<std::size_t>(l + 1)] / counts_[static_cast<std::size_t>(l)];
      level->childrenSize = level->children * levels_[static_cast<std::size_t>(l + 1)]->size;
    }
    level->size = level->childrenSize + 2 * level->dofs;
    levels_[static_cast<std::size_t>(l)] = std::move(level);
  }
  if (levels_[0]->size != 2 * velocityUnknowns_) {
    throw Error("nested async regions: the structured solve's layout does not cover the step system");
  }
  order_.resize(levels_[0]->size);
  int position = 0;
  layOut(0, 1, position);
}

StructuredHierarchySolve::~StructuredHierarchySolve() = default;

// Eq. N9: a block's children first (in time), then its own v, then its own w.
void StructuredHierarchySolve::layOut(int level, long long block, int& position) {
  const Level& here = *levels_[static_cast<std::size_t>(level)];
  for (int k = 1; k <= here.children; ++k) layOut(level + 1, (block - 1) * here.children + k, position);
  for (int d : dofsOf_[static_cast<std::size_t>(level)])
    order_.indices()[offset_[static_cast<std::size_t>(d)] + static_cast<int>(block) - 1] = position++;
  for (int d : dofsOf_[static_cast<std::size_t>(level)])
    order_.indices()[velocityUnknowns_ + offset_[static_cast<std::size_t>(d)] + static_cast<int>(block) - 1] =
        position++;
}

// Eq. N12: which children unknowns of a block must be exact when its solve returns. The
// root needs the end-of-step state; a block of level l + 1 needs what its parent's Schur
// row reads (Q), what its parent must return (N_l), and what its next sibling reads (P).
void StructuredHierarchySolve::chooseNeeded() {
  Level& root = *levels_[0];
  std::set<int> end;
  for (std::size_t d = 0; d < dofLevel_.size(); ++d) {
    if (dofLevel_[d] == 0) continue;
    const int last = offset_[d + 1] - 1;  // offset_[d] + N_d - 1
    end.insert(order_.indices()[last]);
    end.insert(order_.indices()[velocityUnknowns_ + last]);
  }
  root.needed.assign(end.begin(), end.end());
  for (std::size_t l = 0; l + 1 < levels_.size(); ++l) {
    const Level& parent = *levels_[l];
    Level& child = *levels_[l + 1];
    std::set<int> local;
    for (int c : nonZeroColumns(child.previous)) local.insert(c);
    for (const std::vector<int>* from : {&parent.readByOwn, &parent.needed})
      for (int p : *from) local.insert(p % child.size);
    child.needed.clear();
    for (int p : local)
      if (p < child.childrenSize) child.needed.push_back(p);
  }
}

void StructuredHierarchySolve::factor(const SparseMatrix& system, IntegratorStats& stats) {
  SparseMatrix tree = order_ * system * order_.transpose();
  tree.makeCompressed();
  for (std::size_t l = 0; l < levels_.size(); ++l) {
    Level& L = *levels_[l];
    const int cs = L.childrenSize, n = L.dofs;
    L.ownVV = cut(tree, cs, cs, n, n);
    L.ownWV = cut(tree, cs + n, cs, n, n);
    const SparseMatrix ownWW = cut(tree, cs + n, cs + n, n, n);
    bool identity = ownWW.nonZeros() == n;
    for (Eigen::Index c = 0; identity && c < n; ++c)
      identity = ownWW.innerIndexPtr()[c] == c && ownWW.valuePtr()[c] == 1.0;
    if (!identity || cut(tree, cs, cs + n, n, n).nonZeros() != 0 || cut(tree, 0, cs + n, cs, n).nonZeros() != 0) {
      throw Error("nested async regions: the step system does not have the layout the structured solve assumes");
    }
    L.fromChildren = cut(tree, cs, 0, n, cs);
    L.toChildren = cut(tree, 0, cs, cs, n);
    L.interface = nonZeroColumns(L.toChildren);
    L.readByOwn = nonZeroColumns(L.fromChildren);
    if (l > 0) L.previous = cut(tree, L.size, 0, L.size, L.size);
  }
  chooseNeeded();
  for (int l = static_cast<int>(levels_.size()) - 1; l >= 0; --l) factorLevel(l, stats);
  factored_ = true;
  solveFlops_ = levels_[0]->flops;
  substitutionFlops_ = levels_[0]->substitutionFlops;
}

double StructuredHierarchySolve::blockFlops(int level) const {
  const Level& L = *levels_[static_cast<std::size_t>(level)];
  if (L.children == 0) return 0.0;
  const Level& child = *levels_[static_cast<std::size_t>(level) + 1];
  return L.children * child.flops + (L.children - 1) * 2.0 * static_cast<double>(child.previous.nonZeros());
}

// Eq. N10: Z = (children)^{-1} R_I a few columns at a time; keeps Q_J Z (the correction
// on the own rows J it reaches) and, with keepZ, Z's rows N_l for recovery.
void StructuredHierarchySolve::computeZ(int level, const std::vector<int>& rows, bool keepZ, IntegratorStats& stats) {
  Level& L = *levels_[static_cast<std::size_t>(level)];
  const int cs = L.childrenSize;
  const auto q = static_cast<Eigen::Index>(L.interface.size());
  L.correction.setZero(static_cast<Eigen::Index>(rows.size()), q);
  if (keepZ) L.zNeeded.setZero(static_cast<Eigen::Index>(L.needed.size()), q);
  if (cs == 0 || q == 0) return;
  std::vector<int> rowOf(static_cast<std::size_t>(L.dofs), -1);
  for (std::size_t i = 0; i < rows.size(); ++i) rowOf[static_cast<std::size_t>(rows[i])] = static_cast<int>(i);
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index c = 0; c < L.fromChildren.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(L.fromChildren, c); it; ++it)
      t.emplace_back(rowOf[static_cast<std::size_t>(it.row())], static_cast<int>(c), it.value());
  SparseMatrix fromChildrenRows(static_cast<Eigen::Index>(rows.size()), cs);
  fromChildrenRows.setFromTriplets(t.begin(), t.end());
  Eigen::MatrixXd columns;
  for (Eigen::Index c0 = 0; c0 < q; c0 += kColumnsPerPass) {
    const Eigen::Index width = std::min<Eigen::Index>(kColumnsPerPass, q - c0);
    columns.setZero(cs, width);
    for (Eigen::Index i = 0; i < width; ++i)
      for (SparseMatrix::InnerIterator it(L.toChildren, L.interface[static_cast<std::size_t>(c0 + i)]); it; ++it)
        columns(it.row(), i) = it.value();
    forwardChildren(level, columns, false);
    L.correction.middleCols(c0, width).noalias() = fromChildrenRows * columns;
    if (keepZ)
      for (std::size_t r = 0; r < L.needed.size(); ++r)
        L.zNeeded.block(static_cast<Eigen::Index>(r), c0, 1, width) = columns.row(L.needed[r]);
  }
  stats.factorFlops += static_cast<double>(q) * blockFlops(level);
}

// S_l = A_l - Q Z, on A_l's pattern plus the dense J x I block: dense LU for small levels,
// Cholesky when symmetric, LU otherwise (symbolic analysis kept while the pattern stays).
void StructuredHierarchySolve::factorSchur(int level, const std::vector<int>& rows, IntegratorStats& stats) {
  Level& L = *levels_[static_cast<std::size_t>(level)];
  const int n = L.dofs;
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index c = 0; c < L.ownVV.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(L.ownVV, c); it; ++it)
      t.emplace_back(static_cast<int>(it.row()), static_cast<int>(c), it.value());
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (Eigen::Index i = 0; i < L.correction.cols(); ++i)
      t.emplace_back(rows[r], L.interface[static_cast<std::size_t>(i)], -L.correction(static_cast<Eigen::Index>(r), i));
  SparseMatrix schur(n, n);
  schur.setFromTriplets(t.begin(), t.end());
  schur.makeCompressed();
  const SparseMatrix transposed = schur.transpose();
  L.asymmetry = largestMagnitude(SparseMatrix(schur - transposed)) / std::max(largestMagnitude(schur), 1e-300);
  L.denseFactor = n <= kDenseLevelDofs;
  if (L.denseFactor) {
    L.dense.compute(Eigen::MatrixXd(schur));
    const double pivot = L.dense.matrixLU().diagonal().cwiseAbs().minCoeff();
    if (!(pivot > 0.0) || !std::isfinite(pivot)) {
      throw NumericalError("nested async regions: the Schur complement of level " +
                           std::to_string(counts_[static_cast<std::size_t>(level)]) + " is singular");
    }
    L.solveFlops = 2.0 * n * n;
    stats.factorFlops += 2.0 / 3.0 * n * static_cast<double>(n) * n;
  } else {
    const SolverKind kind = L.asymmetry <= kSymmetric ? SolverKind::cholmod : SolverKind::umfpack;
    const std::vector<int> outer(schur.outerIndexPtr(), schur.outerIndexPtr() + n + 1);
    const std::vector<int> inner(schur.innerIndexPtr(), schur.innerIndexPtr() + schur.nonZeros());
    if (!L.sparse || L.sparse->kind() != kind || outer != L.patternOuter || inner != L.patternInner) {
      L.sparse = makeSparseSolver(kind);
      L.sparse->analyzePattern(schur);
      L.patternOuter = outer;
      L.patternInner = inner;
    }
    L.sparse->factorize(schur);
    L.solveFlops = L.sparse->stats().solveFlopsPerRhs;
    stats.factorFlops += L.sparse->stats().factorFlops;
  }
  ++stats.factorizations;
}

// Eqs. N10-N12 for one level, its children already factored: Z, S_l and its factor, and
// how the children are recovered (y - Z_N v_I, or a second forward pass: fewer flops wins).
void StructuredHierarchySolve::factorLevel(int level, IntegratorStats& stats) {
  Level& L = *levels_[static_cast<std::size_t>(level)];
  const auto q = static_cast<double>(L.interface.size());
  const auto needed = static_cast<double>(L.needed.size());
  const std::vector<int> rows = nonZeroRows(L.fromChildren);  // J
  const bool keepZ = needed > 0 && needed * q <= kMaxRecoveryEntries;
  computeZ(level, rows, keepZ, stats);
  if (L.dofs > 0) factorSchur(level, rows, stats);
  const double forward = blockFlops(level);
  const double denseCost = 2.0 * needed * q;
  const double substitution = 2.0 * static_cast<double>(L.toChildren.nonZeros()) + forward;
  L.denseRecovery = keepZ && q > 0 && denseCost <= substitution;
  if (!L.denseRecovery) L.zNeeded.resize(0, 0);
  const bool recovers = q > 0 && needed > 0;
  const double recovery = !recovers ? 0.0 : (L.denseRecovery ? denseCost : substitution);
  L.flops = forward + 2.0 * static_cast<double>(L.fromChildren.nonZeros()) + L.solveFlops +
            2.0 * static_cast<double>(L.ownWV.nonZeros()) + recovery;
  const int passes = recovers && !L.denseRecovery ? 2 : 1;
  L.substitutionFlops =
      (L.dofs > 0 ? L.solveFlops : 0.0) +
      (L.children > 0 ? passes * L.children * levels_[static_cast<std::size_t>(level) + 1]->substitutionFlops : 0.0);
}

void StructuredHierarchySolve::forwardChildren(int level, Eigen::Ref<Eigen::MatrixXd> x, bool all) {
  const Level& L = *levels_[static_cast<std::size_t>(level)];
  const Level& child = *levels_[static_cast<std::size_t>(level) + 1];
  const Eigen::Index s = child.size;
  for (int k = 0; k < L.children; ++k) {
    if (k > 0) x.middleRows(k * s, s).noalias() -= child.previous * x.middleRows((k - 1) * s, s);
    solveBlock(level + 1, x.middleRows(k * s, s), all);
  }
}

// Eq. N11: children with the own unknowns zero, the own Schur row, then the children
// corrected for the own velocities the interface sees.
void StructuredHierarchySolve::solveBlock(int level, Eigen::Ref<Eigen::MatrixXd> x, bool all) {
  Level& L = *levels_[static_cast<std::size_t>(level)];
  const int cs = L.childrenSize, n = L.dofs;
  const bool substitute = all || !L.denseRecovery;
  const bool recover = cs > 0 && n > 0 && !L.interface.empty() && (all || !L.needed.empty());
  if (cs > 0) {
    if (recover && substitute) L.saved = x.topRows(cs);
    forwardChildren(level, x.topRows(cs), all);
  }
  if (n == 0) return;
  auto v = x.middleRows(cs, n);
  if (cs > 0) v.noalias() -= L.fromChildren * x.topRows(cs);
  if (L.denseFactor) {
    L.solved.noalias() = L.dense.solve(v);
  } else {
    L.sparse->solve(v, L.solved);
  }
  v = L.solved;
  x.middleRows(cs + n, n).noalias() -= L.ownWV * v;
  if (!recover) return;
  if (!substitute) {
    const auto q = static_cast<Eigen::Index>(L.interface.size());
    L.gathered.resize(q, x.cols());
    for (Eigen::Index i = 0; i < q; ++i) L.gathered.row(i) = v.row(L.interface[static_cast<std::size_t>(i)]);
    L.solved.noalias() = L.zNeeded * L.gathered;
    for (std::size_t r = 0; r < L.needed.size(); ++r) x.row(L.needed[r]) -= L.solved.row(static_cast<Eigen::Index>(r));
    return;
  }
  L.saved.noalias() -= L.toChildren * v;
  x.topRows(cs) = L.saved;
  forwardChildren(level, x.topRows(cs), all);
}

void StructuredHierarchySolve::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution, bool allUnknowns) {
  work_.resize(rhs.size(), 1);
  work_.col(0) = order_ * rhs;
  solveBlock(0, work_, allUnknowns);
  solution = order_.transpose() * work_.col(0);
}

double StructuredHierarchySolve::checkEndState(const SparseMatrix& system) {
  Eigen::VectorXd exact(system.rows());
  for (Eigen::Index i = 0; i < exact.size(); ++i) exact[i] = 1.0 + 0.5 * std::sin(0.7 * static_cast<double>(i));
  const Eigen::VectorXd rhs = system * exact;
  Eigen::VectorXd solved;
  solve(rhs, solved, false);
  double error = 0.0;
  for (std::size_t d = 0; d + 1 < offset_.size(); ++d) {
    const int last = offset_[d + 1] - 1;
    for (int row : {last, velocityUnknowns_ + last}) error = std::max(error, std::abs(solved[row] - exact[row]));
  }
  return error / exact.cwiseAbs().maxCoeff();
}

long long StructuredHierarchySolve::storedEntries() const {
  long long total = 0;
  for (const auto& L : levels_) {
    if (L->denseFactor) {
      total += static_cast<long long>(L->dofs) * L->dofs;
    } else if (L->sparse) {
      total += L->sparse->stats().factorNonZeros;
    }
    total += static_cast<long long>(L->zNeeded.size());
  }
  return total;
}

std::string StructuredHierarchySolve::describe() const {
  std::string out;
  if (!factored_) {
    for (int count : counts_) out += (out.empty() ? "step counts " : ", ") + std::to_string(count);
    return out + "; not factored yet";
  }
  for (std::size_t l = 0; l < levels_.size(); ++l) {
    const Level& L = *levels_[l];
    char line[256];
    std::snprintf(line, sizeof line, "%sstep count %d: %d DOFs, interface %zu, %s Schur factor, %s recovery",
                  out.empty() ? "" : "; ", counts_[l], L.dofs, L.interface.size(),
                  L.dofs == 0 ? "no" : (L.denseFactor || !L.sparse ? "dense" : toString(L.sparse->kind()).c_str()),
                  L.interface.empty() || L.needed.empty() ? "no" : (L.denseRecovery ? "dense-Z" : "substitution"));
    out += line;
  }
  char total[160];
  std::snprintf(total, sizeof total, "; %.3g Mflop per large step (%.3g in substitutions)", solveFlops_ * 1e-6,
                substitutionFlops_ * 1e-6);
  return out + total;
}

}  // namespace asyncfem::detail
