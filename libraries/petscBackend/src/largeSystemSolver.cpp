// SPDX-License-Identifier: BSD-3-Clause
// A replicated sparse system solved distributed by PETSc (docs/petsc-backend.md, "The
// asynchronous integrator over MPI").
#include <mpi.h>
#include <petscksp.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/petscBackend/largeSystemSolver.hpp>
#include <asyncfem/petscBackend/partition.hpp>
#include <string>

#include "detail/distributedLayout.hpp"
#include "detail/linearSolver.hpp"
#include "detail/petscCall.hpp"
#include "detail/petscHandle.hpp"

namespace asyncfem {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using detail::checkPetsc;
using detail::VecHandle;

/// Who owns which row, and PETSc's numbering: the rows rank by rank, each rank's in
/// ascending order.
struct RowNumbering {
  int rank = 0, ranks = 1, rows = 0, blockSize = 1;
  std::vector<int> owner;            // rank of each row
  std::vector<PetscInt> petscIndex;  // PETSc's index of each row
  std::vector<int> ownedRowIndex;    // this rank's rows (their indices in the matrix), ascending
  PetscInt firstRow = 0;
  bool splitsAVertex = false;  // some vertex's rows lie on two ranks (no block size 3 then)
};

/// The owned rows of a replicated CSC matrix in a PETSc MATAIJ with an exact preallocation;
/// build() once per pattern, fill() for each set of values.
struct DistributedCopy {
  detail::MatHandle matrix;
  std::vector<std::vector<PetscInt>> rowColumns;  // PETSc columns of each owned row
  std::vector<std::vector<int>> rowEntries;       // and where their values sit in the CSC arrays
  std::vector<int> outer, inner;
  long long offRankEntries = 0;

  bool matches(const SparseMatrix& m) const {
    return !outer.empty() && static_cast<std::size_t>(m.nonZeros()) == inner.size() &&
           static_cast<std::size_t>(m.outerSize()) + 1 == outer.size() &&
           std::equal(outer.begin(), outer.end(), m.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), m.innerIndexPtr());
  }

  void build(const SparseMatrix& m, const RowNumbering& n) {
    std::vector<int> localRow(static_cast<std::size_t>(n.rows), -1);
    for (std::size_t k = 0; k < n.ownedRowIndex.size(); ++k) {
      localRow[static_cast<std::size_t>(n.ownedRowIndex[k])] = static_cast<int>(k);
    }
    rowColumns.assign(n.ownedRowIndex.size(), {});
    rowEntries.assign(n.ownedRowIndex.size(), {});
    std::vector<PetscInt> diagonal(n.ownedRowIndex.size(), 0), offDiagonal(n.ownedRowIndex.size(), 0);
    for (int c = 0; c < n.rows; ++c) {
      for (int k = m.outerIndexPtr()[c]; k < m.outerIndexPtr()[c + 1]; ++k) {
        const int local = localRow[static_cast<std::size_t>(m.innerIndexPtr()[k])];
        if (local < 0) continue;
        rowColumns[static_cast<std::size_t>(local)].push_back(n.petscIndex[static_cast<std::size_t>(c)]);
        rowEntries[static_cast<std::size_t>(local)].push_back(k);
        (n.owner[static_cast<std::size_t>(c)] == n.rank ? diagonal : offDiagonal)[static_cast<std::size_t>(local)]++;
      }
    }
    offRankEntries = 0;
    for (const PetscInt count : offDiagonal) offRankEntries += count;
    const auto owned = static_cast<PetscInt>(n.ownedRowIndex.size());
    checkPetsc(MatCreate(PETSC_COMM_WORLD, matrix.out()), "MatCreate");
    checkPetsc(MatSetSizes(matrix.get(), owned, owned, n.rows, n.rows), "MatSetSizes");
    checkPetsc(MatSetType(matrix.get(), MATAIJ), "MatSetType");
    if (n.blockSize == 3 && !n.splitsAVertex) checkPetsc(MatSetBlockSize(matrix.get(), 3), "MatSetBlockSize");
    checkPetsc(MatSeqAIJSetPreallocation(matrix.get(), 0, diagonal.data()), "MatSeqAIJSetPreallocation");
    checkPetsc(MatMPIAIJSetPreallocation(matrix.get(), 0, diagonal.data(), 0, offDiagonal.data()),
               "MatMPIAIJSetPreallocation");
    checkPetsc(MatSetOption(matrix.get(), MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "MatSetOption");
    outer.assign(m.outerIndexPtr(), m.outerIndexPtr() + m.outerSize() + 1);
    inner.assign(m.innerIndexPtr(), m.innerIndexPtr() + m.nonZeros());
  }

  void fill(const SparseMatrix& m, const RowNumbering& n) {
    checkPetsc(MatZeroEntries(matrix.get()), "MatZeroEntries");
    const double* values = m.valuePtr();
    std::vector<PetscScalar> row;
    for (std::size_t r = 0; r < rowEntries.size(); ++r) {
      row.resize(rowEntries[r].size());
      for (std::size_t k = 0; k < row.size(); ++k) row[k] = values[rowEntries[r][k]];
      const PetscInt global = n.firstRow + static_cast<PetscInt>(r);
      checkPetsc(MatSetValues(matrix.get(), 1, &global, static_cast<PetscInt>(rowColumns[r].size()),
                              rowColumns[r].data(), row.data(), INSERT_VALUES),
                 "MatSetValues");
    }
    checkPetsc(MatAssemblyBegin(matrix.get(), MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
    checkPetsc(MatAssemblyEnd(matrix.get(), MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
  }
};

class PetscSparseSolver final : public SparseSolver {
 public:
  PetscSparseSolver(const PetscSolverSettings& settings, std::vector<int> rowVertex,
                    std::shared_ptr<const std::vector<int>> vertexOwner,
                    std::shared_ptr<const Eigen::Matrix3Xd> coordinates, std::shared_ptr<PetscSolveCounts> totals)
      : settings_(settings),
        rowVertex_(std::move(rowVertex)),
        vertexOwner_(std::move(vertexOwner)),
        coordinates_(std::move(coordinates)),
        totals_(std::move(totals)) {
    MPI_Comm_rank(PETSC_COMM_WORLD, &numbering_.rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &numbering_.ranks);
  }

  void analyzePattern(const SparseMatrix& matrix) override {
    Stopwatch watch;
    checkShape(matrix, "analyzePattern");
    numbering_.rows = static_cast<int>(matrix.rows());
    if (!rowVertex_.empty() && rowVertex_.size() != static_cast<std::size_t>(numbering_.rows)) {
      throw Error("PETSc solver: " + std::to_string(rowVertex_.size()) + " row vertices for a matrix of " +
                  std::to_string(numbering_.rows) + " rows");
    }
    number();
    system_ = DistributedCopy{};
    preconditioner_ = DistributedCopy{};
    system_.build(matrix, numbering_);
    counts_.offRankEntries = system_.offRankEntries;
    if (totals_) totals_->offRankEntries = counts_.offRankEntries;
    checkPetsc(MatCreateVecs(system_.matrix.get(), x_.out(), b_.out()), "MatCreateVecs");
    checkPetsc(VecScatterCreateToAll(x_.get(), toAll_.out(), all_.out()), "VecScatterCreateToAll");
    makeRigidBodyModes();
    options_ = detail::makeSolverOptions(settings_.options);
    solver_ = std::make_unique<detail::LinearSolver>(PETSC_COMM_WORLD, options_.get(), settings_, "", nullptr);
    factored_ = false;
    ++stats_.analyses;
    stats_.analyzeSeconds += watch.stop();
  }

  // CG + AMG: an algebraic multigrid coarsens badly through the dense interface blocks of
  // H^{LL*} (rows of |I| entries); it is built on the sparse part the caller gives instead.
  bool usesPreconditionerMatrix() const override { return settings_.kind != PetscSolverKind::mumps; }
  void setPreconditionerMatrix(const SparseMatrix& matrix) override {
    checkShape(matrix, "setPreconditionerMatrix");  // its size is checked against the system in factorize()
    preconditionerValues_ = matrix;
  }

  void factorize(const SparseMatrix& matrix) override {
    if (!solver_) throw Error("PETSc solver: factorize() before analyzePattern()");
    checkShape(matrix, "factorize");
    if (matrix.rows() != numbering_.rows || !system_.matches(matrix)) {
      throw Error("PETSc solver: factorize() with a pattern other than the analysed one; call analyzePattern() again");
    }
    Stopwatch watch;
    system_.fill(matrix, numbering_);
    attachRigidBodyModes(system_.matrix.get());
    if (preconditionerValues_.rows() > 0) {
      if (preconditionerValues_.rows() != numbering_.rows) {
        throw Error("PETSc solver: a preconditioning matrix of " + std::to_string(preconditionerValues_.rows()) +
                    " rows for a system of " + std::to_string(numbering_.rows));
      }
      if (!preconditioner_.matches(preconditionerValues_)) {
        preconditioner_ = DistributedCopy{};
        preconditioner_.build(preconditionerValues_, numbering_);
      }
      preconditioner_.fill(preconditionerValues_, numbering_);
      attachRigidBodyModes(preconditioner_.matrix.get());
      solver_->setOperators(system_.matrix.get(), preconditioner_.matrix.get());
    } else {
      solver_->setOperator(system_.matrix.get());
    }
    solver_->setUp();
    factored_ = true;
    ++stats_.factorizations;
    stats_.factorSeconds += watch.stop();
  }

  void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    solveColumns(rhs, solution, false);
  }
  // One application of the KSP's preconditioner (a GAMG cycle; MUMPS: its exact solve).
  void solveApproximately(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    solveColumns(rhs, solution, true);
  }

  void solveColumns(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution, bool approximately) {
    const int rows = numbering_.rows;
    if (!factored_) throw Error("PETSc solver: solve() before a factorization");
    if (rhs.rows() != rows) {
      throw Error("PETSc solver: right-hand side of " + std::to_string(rhs.rows()) + " rows for a matrix of " +
                  std::to_string(rows));
    }
    Stopwatch watch;
    solution.resize(rows, rhs.cols());
    const std::vector<int>& owned = numbering_.ownedRowIndex;
    for (Eigen::Index j = 0; j < rhs.cols(); ++j) {
      PetscScalar* local = nullptr;
      checkPetsc(VecGetArray(b_.get(), &local), "VecGetArray");
      for (std::size_t r = 0; r < owned.size(); ++r) local[r] = rhs(owned[r], j);
      checkPetsc(VecRestoreArray(b_.get(), &local), "VecRestoreArray");
      checkPetsc(VecZeroEntries(x_.get()), "VecZeroEntries");  // a linear map: the same start each time
      detail::SolveOutcome outcome;
      if (approximately) {
        solver_->applyPreconditioner(b_.get(), x_.get());
        outcome.converged = true;
        outcome.iterations = 1;
      } else {
        outcome = solver_->solve(b_.get(), x_.get());
      }
      for (PetscSolveCounts* counts : {&counts_, totals_.get()}) {
        if (counts == nullptr) continue;
        counts->lastIterations = outcome.iterations;
        counts->iterations += outcome.iterations;
        ++counts->solves;
      }
      if (!outcome.converged) {
        throw NumericalError("PETSc solver: the solve of a " + std::to_string(rows) + "-row system did not converge (" +
                             outcome.reason + " after " + std::to_string(outcome.iterations) + " iterations)");
      }
      checkPetsc(VecScatterBegin(toAll_.get(), x_.get(), all_.get(), INSERT_VALUES, SCATTER_FORWARD),
                 "VecScatterBegin");
      checkPetsc(VecScatterEnd(toAll_.get(), x_.get(), all_.get(), INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
      const PetscScalar* gathered = nullptr;
      checkPetsc(VecGetArrayRead(all_.get(), &gathered), "VecGetArrayRead");
      for (int r = 0; r < rows; ++r) solution(r, j) = gathered[numbering_.petscIndex[static_cast<std::size_t>(r)]];
      checkPetsc(VecRestoreArrayRead(all_.get(), &gathered), "VecRestoreArrayRead");
    }
    stats_.solvedRightHandSides += rhs.cols();
    stats_.solveSeconds += watch.stop();
  }

  SolverKind kind() const override { return SolverKind::external; }
  std::string ordering() const override {
    return solver_ ? "petsc " + solver_->kspType() + "/" + solver_->pcType() : "none";
  }
  const PetscSolveCounts& counts() const { return counts_; }

 private:
  static void checkShape(const SparseMatrix& matrix, const char* what) {
    if (matrix.rows() != matrix.cols() || !matrix.isCompressed()) {
      throw Error(std::string("PETSc solver: ") + what + " needs a square, compressed matrix");
    }
  }

  int ownerOf(int row) const {
    if (!rowVertex_.empty() && vertexOwner_) {
      return (*vertexOwner_)[static_cast<std::size_t>(rowVertex_[static_cast<std::size_t>(row)])];
    }
    // Contiguous ranges, split at vertex boundaries when the rows come in threes.
    const long long unit = numbering_.blockSize;
    const long long units = numbering_.rows / unit;
    return static_cast<int>(
        std::min<long long>(numbering_.ranks - 1, (row / unit) * numbering_.ranks / std::max(units, 1LL)));
  }

  void number() {
    RowNumbering& n = numbering_;
    n.blockSize = 1;
    if (!rowVertex_.empty() && n.rows % 3 == 0) {
      bool triples = true;
      for (int r = 0; r < n.rows && triples; r += 3) {
        const auto k = static_cast<std::size_t>(r);
        triples = rowVertex_[k + 1] == rowVertex_[k] && rowVertex_[k + 2] == rowVertex_[k];
      }
      if (triples) n.blockSize = 3;
    }
    n.owner.resize(static_cast<std::size_t>(n.rows));
    std::vector<PetscInt> perRank(static_cast<std::size_t>(n.ranks) + 1, 0);
    for (int r = 0; r < n.rows; ++r) {
      n.owner[static_cast<std::size_t>(r)] = ownerOf(r);
      ++perRank[static_cast<std::size_t>(n.owner[static_cast<std::size_t>(r)]) + 1];
    }
    for (int p = 0; p < n.ranks; ++p) perRank[static_cast<std::size_t>(p) + 1] += perRank[static_cast<std::size_t>(p)];
    std::vector<PetscInt> next(perRank.begin(), perRank.end() - 1);
    n.petscIndex.resize(static_cast<std::size_t>(n.rows));
    n.ownedRowIndex.clear();
    for (int r = 0; r < n.rows; ++r) {
      const int p = n.owner[static_cast<std::size_t>(r)];
      n.petscIndex[static_cast<std::size_t>(r)] = next[static_cast<std::size_t>(p)]++;
      if (p == n.rank) n.ownedRowIndex.push_back(r);
    }
    n.firstRow = perRank[static_cast<std::size_t>(n.rank)];
    n.splitsAVertex = false;
    for (int r = 0; r + 2 < n.rows; r += 3) {
      const auto k = static_cast<std::size_t>(r);
      if (n.owner[k] != n.owner[k + 1] || n.owner[k] != n.owner[k + 2]) n.splitsAVertex = true;
    }
    counts_.ownedRows = static_cast<int>(n.ownedRowIndex.size());
    if (totals_) totals_->ownedRows = counts_.ownedRows;
  }

  // GAMG's near null space: the six rigid-body modes of the rows' vertices.
  void makeRigidBodyModes() {
    nearNullSpace_.reset();
    if (!coordinates_ || numbering_.blockSize != 3 || numbering_.splitsAVertex) return;
    VecHandle positions;
    checkPetsc(MatCreateVecs(system_.matrix.get(), positions.out(), nullptr), "MatCreateVecs");
    checkPetsc(VecSetBlockSize(positions.get(), 3), "VecSetBlockSize");
    PetscScalar* values = nullptr;
    checkPetsc(VecGetArray(positions.get(), &values), "VecGetArray");
    for (std::size_t k = 0; k < numbering_.ownedRowIndex.size(); ++k) {
      const int row = numbering_.ownedRowIndex[k];
      values[k] = (*coordinates_)(row % 3, rowVertex_[static_cast<std::size_t>(row)]);
    }
    checkPetsc(VecRestoreArray(positions.get(), &values), "VecRestoreArray");
    checkPetsc(MatNullSpaceCreateRigidBody(positions.get(), nearNullSpace_.out()), "MatNullSpaceCreateRigidBody");
  }

  void attachRigidBodyModes(Mat matrix) {
    if (nearNullSpace_.get() != nullptr) {
      checkPetsc(MatSetNearNullSpace(matrix, nearNullSpace_.get()), "MatSetNearNullSpace");
    }
  }

  PetscSolverSettings settings_;
  std::vector<int> rowVertex_;
  std::shared_ptr<const std::vector<int>> vertexOwner_;
  std::shared_ptr<const Eigen::Matrix3Xd> coordinates_;
  std::shared_ptr<PetscSolveCounts> totals_;
  RowNumbering numbering_;
  DistributedCopy system_, preconditioner_;
  SparseMatrix preconditionerValues_;
  detail::OptionsHandle options_;
  detail::VecHandle x_, b_, all_;
  detail::ScatterHandle toAll_;
  detail::NullSpaceHandle nearNullSpace_;
  std::unique_ptr<detail::LinearSolver> solver_;
  bool factored_ = false;
  PetscSolveCounts counts_;
};

}  // namespace

std::unique_ptr<SparseSolver> makePetscSparseSolver(const PetscSolverSettings& settings, std::vector<int> rowVertex,
                                                    std::shared_ptr<const std::vector<int>> vertexOwner,
                                                    std::shared_ptr<const Eigen::Matrix3Xd> coordinates,
                                                    std::shared_ptr<PetscSolveCounts> totals) {
  return std::make_unique<PetscSparseSolver>(settings, std::move(rowVertex), std::move(vertexOwner),
                                             std::move(coordinates), std::move(totals));
}

const PetscSolveCounts* petscSolveCounts(const SparseSolver& solver) {
  const auto* petsc = dynamic_cast<const PetscSparseSolver*>(&solver);
  return petsc != nullptr ? &petsc->counts() : nullptr;
}

namespace {

/// Union-find over the groups of keepTogether: groups that share a vertex get one root.
std::vector<int> mergeGroups(const std::vector<std::vector<int>>& groups, int numVertices) {
  std::vector<int> root(groups.size());
  for (std::size_t g = 0; g < groups.size(); ++g) root[g] = static_cast<int>(g);
  const auto find = [&root](int g) {
    while (root[static_cast<std::size_t>(g)] != g)
      g = root[static_cast<std::size_t>(g)] = root[static_cast<std::size_t>(root[static_cast<std::size_t>(g)])];
    return g;
  };
  std::vector<int> firstGroup(static_cast<std::size_t>(numVertices), -1);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    for (const int v : groups[g]) {
      if (v < 0 || v >= numVertices) {
        throw Error("assignVertexOwners: vertex " + std::to_string(v) + " of group " + std::to_string(g) +
                    " is not a vertex of the mesh (" + std::to_string(numVertices) + " vertices)");
      }
      int& first = firstGroup[static_cast<std::size_t>(v)];
      if (first < 0) {
        first = static_cast<int>(g);
      } else {
        root[static_cast<std::size_t>(find(static_cast<int>(g)))] = find(first);
      }
    }
  }
  for (std::size_t g = 0; g < groups.size(); ++g) root[g] = find(static_cast<int>(g));
  return root;
}

/// The rank owning most of vertices by owner (ties: the lowest); votes is scratch of the
/// rank count.
int majorityRank(const std::vector<int>& vertices, const std::vector<int>& owner, std::vector<int>& votes) {
  std::fill(votes.begin(), votes.end(), 0);
  for (const int v : vertices) ++votes[static_cast<std::size_t>(owner[static_cast<std::size_t>(v)])];
  return static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
}

}  // namespace

VertexOwners assignVertexOwners(const TetMesh& mesh, const std::vector<int>& elementParts, int ranks,
                                const std::vector<std::vector<int>>& keepTogether, int maxGroupVertices) {
  if (elementParts.size() != static_cast<std::size_t>(mesh.numElements())) {
    throw Error("assignVertexOwners: " + std::to_string(elementParts.size()) + " element parts for " +
                std::to_string(mesh.numElements()) + " elements");
  }
  VertexOwners result;
  const int numVertices = mesh.numVertices();
  result.owner.assign(static_cast<std::size_t>(numVertices), ranks);
  for (int e = 0; e < mesh.numElements(); ++e) {
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      int& o = result.owner[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      o = std::min(o, elementParts[static_cast<std::size_t>(e)]);
    }
  }
  for (int& o : result.owner) o = std::min(o, ranks - 1);  // vertices of no element (no rows reach them)
  // Each merged group's distinct vertices, then its majority rank.
  const std::vector<int> root = mergeGroups(keepTogether, numVertices);
  std::vector<std::vector<int>> merged(keepTogether.size());
  for (std::size_t g = 0; g < keepTogether.size(); ++g) {
    std::vector<int>& into = merged[static_cast<std::size_t>(root[g])];
    into.insert(into.end(), keepTogether[g].begin(), keepTogether[g].end());
  }
  std::vector<int> votes(static_cast<std::size_t>(ranks));
  for (std::vector<int>& group : merged) {
    std::sort(group.begin(), group.end());
    group.erase(std::unique(group.begin(), group.end()), group.end());
    if (group.empty()) continue;
    if (static_cast<int>(group.size()) > maxGroupVertices) {
      ++result.groupsSplit;
      continue;
    }
    const int keeper = majorityRank(group, result.owner, votes);
    for (const int v : group) result.owner[static_cast<std::size_t>(v)] = keeper;
    ++result.groupsKept;
  }
  return result;
}

std::vector<int> regionOwners(const TetMesh& mesh, const std::vector<int>& elementParts, int ranks,
                              const std::vector<std::vector<int>>& regionVertices,
                              const std::vector<std::vector<int>>& interfaceVertices, int maxGroupVertices) {
  const std::vector<int> byPart = assignVertexOwners(mesh, elementParts, ranks, {}, 0).owner;
  const std::vector<int> kept =
      assignVertexOwners(mesh, elementParts, ranks, interfaceVertices, maxGroupVertices).owner;
  std::vector<int> owners(regionVertices.size(), 0);
  std::vector<int> votes(static_cast<std::size_t>(ranks));
  for (std::size_t i = 0; i < regionVertices.size(); ++i) {
    const std::vector<int> none;
    const std::vector<int>& ring = i < interfaceVertices.size() ? interfaceVertices[i] : none;
    const bool oneRank = !ring.empty() && std::all_of(ring.begin(), ring.end(), [&](int v) {
      return kept[static_cast<std::size_t>(v)] == kept[static_cast<std::size_t>(ring.front())];
    });
    if (oneRank) {
      owners[i] = kept[static_cast<std::size_t>(ring.front())];
      continue;
    }
    for (const int v : regionVertices[i]) {
      if (v < 0 || v >= mesh.numVertices()) {
        throw Error("regionOwners: vertex " + std::to_string(v) + " of region " + std::to_string(i) +
                    " is not a vertex of the mesh");
      }
    }
    owners[i] = majorityRank(regionVertices[i], byPart, votes);
  }
  return owners;
}

namespace {

/// Vertex ids of DOF lists (3 v + c), each list's vertices once, ascending.
std::vector<std::vector<int>> verticesOf(const std::vector<std::vector<int>>& dofLists) {
  std::vector<std::vector<int>> vertices(dofLists.size());
  for (std::size_t i = 0; i < dofLists.size(); ++i) {
    for (const int dof : dofLists[i]) vertices[i].push_back(dof / 3);
    std::sort(vertices[i].begin(), vertices[i].end());
    vertices[i].erase(std::unique(vertices[i].begin(), vertices[i].end()), vertices[i].end());
  }
  return vertices;
}

/// A group of vertices kept on one rank may hold at most one rank's share of the mesh's.
int groupLimit(const TetMesh& mesh, int ranks) { return std::max(1, mesh.numVertices() / std::max(ranks, 1)); }

}  // namespace

PetscRegionDistribution makePetscRegionDistribution(const TetMesh& mesh, std::shared_ptr<PetscSolveCounts> totals) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &ranks);
  auto parts = std::make_shared<const std::vector<int>>(detail::elementPartsOnEveryRank(mesh, PETSC_COMM_WORLD));
  auto meshShared = std::make_shared<const TetMesh>(mesh);
  PetscRegionDistribution distribution;
  distribution.ownedRegions = [parts, meshShared, rank, ranks, totals](
                                  const std::vector<std::vector<int>>& regionDofs,
                                  const std::vector<std::vector<int>>& interfaceDofs) {
    const std::vector<int> owners = regionOwners(*meshShared, *parts, ranks, verticesOf(regionDofs),
                                                 verticesOf(interfaceDofs), groupLimit(*meshShared, ranks));
    std::vector<char> owned(owners.size());
    for (std::size_t i = 0; i < owners.size(); ++i) owned[i] = owners[i] == rank ? 1 : 0;
    if (totals) {
      totals->regionsComputed = static_cast<int>(std::count(owned.begin(), owned.end(), 1));
      totals->regions = static_cast<int>(owned.size());
    }
    return owned;
  };
  distribution.sum = [](double* values, std::size_t count) { detail::sumOverRanks(PETSC_COMM_WORLD, values, count); };
  return distribution;
}

std::function<std::unique_ptr<SparseSolver>(const std::vector<int>& largeDofs,
                                            const std::vector<std::vector<int>>& interfaceDofs)>
makePetscLargeSystemSolver(const TetMesh& mesh, const PetscSolverSettings& settings,
                           std::shared_ptr<PetscSolveCounts> totals) {
  int ranks = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &ranks);
  std::vector<int> parts = detail::elementPartsOnEveryRank(mesh, PETSC_COMM_WORLD);
  auto coordinates = std::make_shared<Eigen::Matrix3Xd>(mesh.restPositions());
  auto meshShared = std::make_shared<TetMesh>(mesh);
  return [settings, parts = std::move(parts), meshShared, coordinates, totals, ranks](
             const std::vector<int>& largeDofs,
             const std::vector<std::vector<int>>& interfaceDofs) -> std::unique_ptr<SparseSolver> {
    std::vector<int> rowVertex(largeDofs.size());
    for (std::size_t k = 0; k < largeDofs.size(); ++k) rowVertex[k] = largeDofs[k] / 3;
    VertexOwners owners =
        assignVertexOwners(*meshShared, parts, ranks, verticesOf(interfaceDofs), groupLimit(*meshShared, ranks));
    if (totals) {
      totals->regionsOnOneRank = owners.groupsKept;
      totals->regionsSplit = owners.groupsSplit;
    }
    auto owner = std::make_shared<const std::vector<int>>(std::move(owners.owner));
    return makePetscSparseSolver(settings, std::move(rowVertex), std::move(owner), coordinates, totals);
  };
}

}  // namespace asyncfem
