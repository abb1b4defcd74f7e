// SPDX-License-Identifier: BSD-3-Clause
#include <petscksp.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <asyncfem/petscBackend/partition.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <climits>
#include <cmath>
#include <sstream>
#include <string>

#include "detail/distributedLayout.hpp"
#include "detail/petscCall.hpp"
#include "detail/petscHandle.hpp"

namespace asyncfem {

using detail::checkPetsc;
using detail::collectively;

std::string toString(PetscIntegratorKind kind) {
  return kind == PetscIntegratorKind::backwardEuler ? "backward-euler" : "trapezoidal";
}

std::string toString(PetscForceModelKind kind) {
  return kind == PetscForceModelKind::linear ? "linear" : "corotational";
}

PetscIntegratorKind parsePetscIntegratorKind(const std::string& name) {
  for (PetscIntegratorKind kind : {PetscIntegratorKind::backwardEuler, PetscIntegratorKind::trapezoidal}) {
    if (toString(kind) == name) return kind;
  }
  throw ValidationError("unknown PETSc backend integrator '" + name + "' (expected backward-euler or trapezoidal)");
}

PetscForceModelKind parsePetscForceModelKind(const std::string& name) {
  for (PetscForceModelKind kind : {PetscForceModelKind::linear, PetscForceModelKind::corotational}) {
    if (toString(kind) == name) return kind;
  }
  throw ValidationError("unknown PETSc backend force model '" + name + "' (expected linear or corotational)");
}

namespace {

using RowMajorElementMatrix = Eigen::Matrix<double, 12, 12, Eigen::RowMajor>;

/// What a local element needs at every step (rest shape, material, cached K_e for the
/// corotational model).
struct ElementData {
  ElementPositions rest;
  Eigen::Matrix<double, 3, 4> gradients;  // shape-function gradients, rest configuration
  double volume = 0.0;                    // signed
  double density = 0.0;
  ElementMatrix stiffness;  // K_e, corotational model only
};

/// Rest data of element e; ValidationError for a degenerate element, with the same
/// criterion as the single-process assembly (|V| <= 1e-14 L^3, L the longest edge).
ElementData elementData(const TetMesh& mesh, int e, bool cacheStiffness) {
  ElementData data;
  data.rest = mesh.elementRestPositions(e);
  data.gradients = shapeFunctionGradients(data.rest, &data.volume);
  double longestSquared = 0.0;
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) {
      longestSquared = std::max(longestSquared, (data.rest.col(a) - data.rest.col(b)).squaredNorm());
    }
  }
  const double longest = std::sqrt(longestSquared);
  if (!(std::abs(data.volume) > 1e-14 * longest * longest * longest) || !std::isfinite(data.volume)) {
    std::ostringstream message;
    message << "PETSc backend: element " << e << " is degenerate (signed volume " << data.volume << ", longest edge "
            << longest << ")";
    throw ValidationError(message.str());
  }
  const Material& material = mesh.elementMaterial(e);
  data.density = material.density;
  if (cacheStiffness) data.stiffness = linearElementStiffness(data.rest, material.youngsModulus, material.poissonRatio);
  return data;
}

/// Corotated element (Mueller & Gross 2004, as CorotationalLinearFEM): F = x G^T, R its
/// polar rotation, force R K_e (R^T x - X) and simple tangent R K_e R^T.
void corotatedElement(const ElementData& data, const ElementPositions& current, ElementVector& force,
                      ElementMatrix& tangent) {
  const Eigen::Matrix3d deformationGradient = current * data.gradients.transpose();
  const Eigen::Matrix3d rotation = polarDecomposition(deformationGradient).rotation;
  const ElementPositions corotated = (rotation.transpose() * current) - data.rest;
  const ElementVector restoring = data.stiffness * Eigen::Map<const ElementVector>(corotated.data());
  Eigen::Map<ElementPositions>(force.data()).noalias() =
      rotation * Eigen::Map<const ElementPositions>(restoring.data());
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a < 4; ++a) {
      tangent.block<3, 3>(3 * a, 3 * b).noalias() =
          rotation * data.stiffness.block<3, 3>(3 * a, 3 * b) * rotation.transpose();
    }
  }
}

void setKspType(KSP ksp, const PetscSolverSettings& settings) {
  PC pc = nullptr;
  checkPetsc(KSPGetPC(ksp, &pc), "KSPGetPC");
  switch (settings.kind) {
    case PetscSolverKind::cgGamg:
      checkPetsc(KSPSetType(ksp, KSPCG), "KSPSetType");
      checkPetsc(PCSetType(pc, PCGAMG), "PCSetType(gamg)");
      break;
    case PetscSolverKind::cgHypre:
      checkPetsc(KSPSetType(ksp, KSPCG), "KSPSetType");
      checkPetsc(PCSetType(pc, PCHYPRE), "PCSetType(hypre)");
      checkPetsc(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
      break;
    case PetscSolverKind::mumps:
      checkPetsc(KSPSetType(ksp, KSPPREONLY), "KSPSetType");
      checkPetsc(PCSetType(pc, PCCHOLESKY), "PCSetType(cholesky)");
      checkPetsc(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "PCFactorSetMatSolverType(mumps)");
      break;
  }
  const PetscReal absolute = settings.absoluteTolerance > 0.0 ? settings.absoluteTolerance : 0.0;
  checkPetsc(KSPSetTolerances(ksp, settings.relativeTolerance, absolute, PETSC_DEFAULT, settings.maxIterations),
             "KSPSetTolerances");
  checkPetsc(KSPSetFromOptions(ksp), "KSPSetFromOptions");
  // CG measures the unpreconditioned residual, so relativeTolerance bounds |b - A x| /
  // |b| whatever the preconditioner (unless the options chose a norm or another KSP).
  KSPType type = nullptr;
  checkPetsc(KSPGetType(ksp, &type), "KSPGetType");
  const char* prefix = nullptr;
  checkPetsc(KSPGetOptionsPrefix(ksp, &prefix), "KSPGetOptionsPrefix");
  PetscOptions options = nullptr;
  checkPetsc(PetscObjectGetOptions(reinterpret_cast<PetscObject>(ksp), &options), "PetscObjectGetOptions");
  PetscBool normChosen = PETSC_FALSE;
  checkPetsc(PetscOptionsHasName(options, prefix, "-ksp_norm_type", &normChosen), "PetscOptionsHasName");
  PetscBool isCg = PETSC_FALSE;
  checkPetsc(PetscStrcmp(type, KSPCG, &isCg), "PetscStrcmp");
  if (isCg == PETSC_TRUE && normChosen == PETSC_FALSE) {
    checkPetsc(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
  }
  // The previous step's increment (acceleration) starts the iterations.
  PetscBool isPreonly = PETSC_FALSE;
  checkPetsc(PetscStrcmp(type, KSPPREONLY, &isPreonly), "PetscStrcmp");
  if (isPreonly == PETSC_FALSE) checkPetsc(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE), "KSPSetInitialGuessNonzero");
}

}  // namespace

struct PetscSimulation::Impl {
  MPI_Comm comm = PETSC_COMM_WORLD;
  PetscSimulationSettings settings;
  bool corotational = false;
  bool trapezoidal = false;
  int numDofs = 0;  // 3n
  detail::DistributedLayout layout;
  std::vector<ElementData> elements;  // per local element

  detail::OptionsHandle options;  // declared first: destroyed after the solvers using it
  detail::MatHandle mass, stiffness, system;
  detail::KspHandle solver, massSolver;
  detail::NullSpaceHandle nearNullSpace;
  detail::VecHandle displacement;  // ghosted
  detail::VecHandle velocity, acceleration, staticForce, externalForce, internalForce, rhs, increment, work, product;
  detail::ScatterHandle toRoot;
  detail::VecHandle rootVector;

  bool systemStale = true;        // system matrix coefficients or K changed
  bool accelerationStale = true;  // trapezoidal a_k
  double timeOrigin = 0.0;
  long long stepIndex = 0;
  PetscRunStats stats;
  Stopwatch assemblyWatch, solveWatch;

  PetscInt ownedDofs() const { return 3 * layout.ownedBlocks; }
  PetscInt globalDofs() const { return 3 * layout.numBlocks; }
  double time() const { return timeOrigin + (static_cast<double>(stepIndex) * settings.timestep); }
  double stepEndTime() const { return timeOrigin + (static_cast<double>(stepIndex + 1) * settings.timestep); }

  void createVector(detail::VecHandle& vector) const {
    checkPetsc(VecCreateMPI(comm, ownedDofs(), globalDofs(), vector.out()), "VecCreateMPI");
    checkPetsc(VecSetBlockSize(vector.get(), 3), "VecSetBlockSize");
    // Element scatters pass -1 for fixed DOFs, as MatSetValues accepts.
    checkPetsc(VecSetOption(vector.get(), VEC_IGNORE_NEGATIVE_INDICES, PETSC_TRUE), "VecSetOption");
  }

  void createMatrix(detail::MatHandle& matrix) const {
    checkPetsc(MatCreate(comm, matrix.out()), "MatCreate");
    checkPetsc(MatSetSizes(matrix.get(), ownedDofs(), ownedDofs(), globalDofs(), globalDofs()), "MatSetSizes");
    checkPetsc(MatSetType(matrix.get(), MATAIJ), "MatSetType");
    checkPetsc(MatSetBlockSize(matrix.get(), 3), "MatSetBlockSize");
    checkPetsc(MatXAIJSetPreallocation(matrix.get(), 3, layout.diagonalBlocks.data(), layout.offDiagonalBlocks.data(),
                                       nullptr, nullptr),
               "MatXAIJSetPreallocation");
    // Re-assembly hits the same slots every time: let PETSc reuse the communication
    // pattern of the off-rank entries and refuse any entry outside the preallocation.
    checkPetsc(MatSetOption(matrix.get(), MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "MatSetOption");
    checkPetsc(MatSetOption(matrix.get(), MAT_SUBSET_OFF_PROC_ENTRIES, PETSC_TRUE), "MatSetOption");
  }

  /// Zeroes matrix (keeping its pattern) and adds every local element's 12x12 matrix.
  template <class ElementFunction>
  void assembleMatrix(Mat matrix, const ElementFunction& elementMatrix) {
    checkPetsc(MatZeroEntries(matrix), "MatZeroEntries");
    collectively(comm, [&] {
      ElementMatrix local;
      RowMajorElementMatrix rowMajor;
      for (std::size_t k = 0; k < elements.size(); ++k) {
        elementMatrix(k, local);
        rowMajor = local;
        const PetscInt* dofs = layout.elementDofs[k].data();
        checkPetsc(MatSetValues(matrix, 12, dofs, 12, dofs, rowMajor.data(), ADD_VALUES), "MatSetValues");
      }
    });
    checkPetsc(MatAssemblyBegin(matrix, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
    checkPetsc(MatAssemblyEnd(matrix, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
  }

  /// The current positions x = X + u of local element k (u read from the ghosted form).
  ElementPositions currentPositions(std::size_t k, const PetscScalar* localDisplacement) const {
    ElementPositions x = elements[k].rest;
    for (int i = 0; i < 12; ++i) {
      const PetscInt local = layout.elementLocalDofs[k][static_cast<std::size_t>(i)];
      if (local >= 0) x(i % 3, i / 3) += localDisplacement[local];
    }
    return x;
  }

  /// Corotated f_int(u) and simple tangent K(u), one polar decomposition per element.
  void assembleCorotated() {
    checkPetsc(VecGhostUpdateBegin(displacement.get(), INSERT_VALUES, SCATTER_FORWARD), "VecGhostUpdateBegin");
    checkPetsc(VecGhostUpdateEnd(displacement.get(), INSERT_VALUES, SCATTER_FORWARD), "VecGhostUpdateEnd");
    Vec localForm = nullptr;
    checkPetsc(VecGhostGetLocalForm(displacement.get(), &localForm), "VecGhostGetLocalForm");
    const PetscScalar* values = nullptr;
    checkPetsc(VecGetArrayRead(localForm, &values), "VecGetArrayRead");
    checkPetsc(MatZeroEntries(stiffness.get()), "MatZeroEntries");
    checkPetsc(VecSet(internalForce.get(), 0.0), "VecSet");
    collectively(comm, [&] {
      ElementVector force;
      ElementMatrix tangent;
      RowMajorElementMatrix rowMajor;
      for (std::size_t k = 0; k < elements.size(); ++k) {
        corotatedElement(elements[k], currentPositions(k, values), force, tangent);
        if (!force.allFinite()) {
          throw NumericalError("PETSc backend: non-finite corotated force in element " +
                               std::to_string(layout.localElements[k]) + " at t = " + std::to_string(time()));
        }
        rowMajor = tangent;
        const PetscInt* dofs = layout.elementDofs[k].data();
        checkPetsc(MatSetValues(stiffness.get(), 12, dofs, 12, dofs, rowMajor.data(), ADD_VALUES), "MatSetValues");
        checkPetsc(VecSetValues(internalForce.get(), 12, dofs, force.data(), ADD_VALUES), "VecSetValues");
      }
    });
    checkPetsc(VecRestoreArrayRead(localForm, &values), "VecRestoreArrayRead");
    checkPetsc(VecGhostRestoreLocalForm(displacement.get(), &localForm), "VecGhostRestoreLocalForm");
    checkPetsc(MatAssemblyBegin(stiffness.get(), MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
    checkPetsc(VecAssemblyBegin(internalForce.get()), "VecAssemblyBegin");
    checkPetsc(MatAssemblyEnd(stiffness.get(), MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
    checkPetsc(VecAssemblyEnd(internalForce.get()), "VecAssemblyEnd");
    systemStale = true;
  }

  /// Copies the owned entries of a full (3n, original numbering) vector into vector.
  void scatterOwned(const Eigen::VectorXd& full, Vec vector) const {
    PetscScalar* values = nullptr;
    checkPetsc(VecGetArray(vector, &values), "VecGetArray");
    for (PetscInt row = 0; row < layout.ownedBlocks; ++row) {
      const auto vertex =
          static_cast<Eigen::Index>(layout.blockVertex[static_cast<std::size_t>(layout.firstBlock + row)]);
      for (int c = 0; c < 3; ++c) values[(3 * row) + c] = full[(3 * vertex) + c];
    }
    checkPetsc(VecRestoreArray(vector, &values), "VecRestoreArray");
  }

  /// fext(t) = M g + constant force + the time-dependent force at t.
  void evaluateExternalForce(double t) {
    checkPetsc(VecCopy(staticForce.get(), externalForce.get()), "VecCopy");
    if (!settings.timeDependentForce) return;
    Eigen::VectorXd full;
    collectively(comm, [&] {
      full.setZero(numDofs);
      settings.timeDependentForce(t, full);
      if (full.size() != numDofs) {
        throw ValidationError("PETSc backend: the time-dependent force returned " + std::to_string(full.size()) +
                              " values, expected " + std::to_string(numDofs));
      }
      for (Eigen::Index i = 0; i < full.size(); ++i) {
        if (!std::isfinite(full[i])) {
          throw NumericalError("PETSc backend: the time-dependent force is not finite at t = " + std::to_string(t) +
                               " (vertex " + std::to_string(i / 3) + ", coordinate " + std::to_string(i % 3) + ")");
        }
      }
    });
    detail::VecHandle timeForce;
    createVector(timeForce);
    scatterOwned(full, timeForce.get());
    checkPetsc(VecAXPY(externalForce.get(), 1.0, timeForce.get()), "VecAXPY");
  }

  /// system = massCoefficient M + stiffnessCoefficient K; hands it to the solver.
  void buildSystem(double massCoefficient, double stiffnessCoefficient) {
    checkPetsc(MatCopy(mass.get(), system.get(), SAME_NONZERO_PATTERN), "MatCopy");
    checkPetsc(MatScale(system.get(), massCoefficient), "MatScale");
    checkPetsc(MatAXPY(system.get(), stiffnessCoefficient, stiffness.get(), SAME_NONZERO_PATTERN), "MatAXPY");
    checkPetsc(MatSetOption(system.get(), MAT_SPD, PETSC_TRUE), "MatSetOption(MAT_SPD)");
    checkPetsc(KSPSetOperators(solver.get(), system.get(), system.get()), "KSPSetOperators");
    systemStale = false;
  }

  void solve(KSP ksp, Vec right, Vec solution, const char* what) {
    ScopedTimer timer(solveWatch);
    checkPetsc(KSPSolve(ksp, right, solution), "KSPSolve");
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    checkPetsc(KSPGetConvergedReason(ksp, &reason), "KSPGetConvergedReason");
    PetscInt iterations = 0;
    checkPetsc(KSPGetIterationNumber(ksp, &iterations), "KSPGetIterationNumber");
    if (reason < 0) {
      const char* text = nullptr;
      KSPGetConvergedReasonString(ksp, &text);
      throw NumericalError("PETSc backend: the " + std::string(what) + " solve of step " +
                           std::to_string(stepIndex + 1) + " (t = " + std::to_string(stepEndTime()) + ") failed: " +
                           (text ? text : "diverged") + " after " + std::to_string(iterations) + " iterations");
    }
    ++stats.solves;
    stats.lastIterations = std::max<int>(1, static_cast<int>(iterations));
    stats.solverIterations += stats.lastIterations;
  }

  /// Throws NumericalError on every rank naming the lowest vertex with a non-finite u
  /// or v after the step that ends at t.
  void checkFinite() const {
    int badVertex = INT_MAX;
    for (Vec vector : {displacement.get(), velocity.get()}) {
      const PetscScalar* values = nullptr;
      checkPetsc(VecGetArrayRead(vector, &values), "VecGetArrayRead");
      for (PetscInt i = 0; i < ownedDofs(); ++i) {
        if (!std::isfinite(values[i])) {
          badVertex = std::min(badVertex, layout.blockVertex[static_cast<std::size_t>(layout.firstBlock + (i / 3))]);
        }
      }
      checkPetsc(VecRestoreArrayRead(vector, &values), "VecRestoreArrayRead");
    }
    int globalBad = INT_MAX;
    MPI_Allreduce(&badVertex, &globalBad, 1, MPI_INT, MPI_MIN, comm);
    if (globalBad != INT_MAX) {
      throw NumericalError("PETSc backend: non-finite displacement or velocity at vertex " + std::to_string(globalBad) +
                           " after step " + std::to_string(stepIndex + 1) + " (t = " + std::to_string(stepEndTime()) +
                           ")");
    }
  }

  void computeAcceleration();
  void stepBackwardEuler();
  void stepTrapezoidal();
  Eigen::VectorXd gather(Vec vector) const;
};

PetscSimulation::PetscSimulation(const TetMesh& mesh, const PetscSimulationSettings& settings)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  Stopwatch setup;
  s.settings = settings;
  s.corotational = settings.forceModel == PetscForceModelKind::corotational;
  s.trapezoidal = settings.integrator == PetscIntegratorKind::trapezoidal;
  s.numDofs = mesh.numDofs();
  int rank = 0;
  int numRanks = 1;
  MPI_Comm_rank(s.comm, &rank);
  MPI_Comm_size(s.comm, &numRanks);

  collectively(s.comm, [&] {
    if (!(settings.timestep > 0.0) || !std::isfinite(settings.timestep)) {
      throw ValidationError("PETSc backend: the timestep must be finite and > 0 (got " +
                            std::to_string(settings.timestep) + ")");
    }
    if (!(settings.rayleighMass >= 0.0) || !(settings.rayleighStiffness >= 0.0)) {
      throw ValidationError("PETSc backend: Rayleigh damping coefficients must be >= 0");
    }
    if (!settings.gravity.allFinite()) throw ValidationError("PETSc backend: gravity is not finite");
    if (settings.constantForce.size() != 0 && settings.constantForce.size() != mesh.numDofs()) {
      throw ValidationError("PETSc backend: the constant force has " + std::to_string(settings.constantForce.size()) +
                            " values, expected 3 x " + std::to_string(mesh.numVertices()));
    }
    for (Eigen::Index i = 0; i < settings.constantForce.size(); ++i) {
      if (!std::isfinite(settings.constantForce[i])) {
        throw ValidationError("PETSc backend: the constant force is not finite at vertex " + std::to_string(i / 3));
      }
    }
    if (!(settings.solver.relativeTolerance >= 0.0) || settings.solver.maxIterations < 1) {
      throw ValidationError("PETSc backend: the solver needs a relative tolerance >= 0 and maxIterations >= 1");
    }
  });
  // Every rank must hold the same mesh: a cheap signature check before any collective
  // call that depends on its size.
  {
    long long signature[2] = {mesh.numVertices(), mesh.numElements()};
    long long low[2] = {0, 0};
    long long high[2] = {0, 0};
    MPI_Allreduce(signature, low, 2, MPI_LONG_LONG, MPI_MIN, s.comm);
    MPI_Allreduce(signature, high, 2, MPI_LONG_LONG, MPI_MAX, s.comm);
    if (low[0] != high[0] || low[1] != high[1]) {
      throw ValidationError("PETSc backend: the ranks hold different meshes (vertices " + std::to_string(low[0]) +
                            ".." + std::to_string(high[0]) + ", elements " + std::to_string(low[1]) + ".." +
                            std::to_string(high[1]) + "); every rank must pass the same mesh");
    }
  }
  // The solvers read a private options database: settings.solver.options, then every
  // global option (command line, PetscRuntime's string) on top, so the command line has
  // the last word and one simulation's options do not leak into the next one.
  checkPetsc(PetscOptionsCreate(s.options.out()), "PetscOptionsCreate");
  checkPetsc(PetscOptionsInsertString(s.options.get(), settings.solver.options.c_str()), "PetscOptionsInsertString");
  {
    char* global = nullptr;
    checkPetsc(PetscOptionsGetAll(nullptr, &global), "PetscOptionsGetAll");
    const PetscErrorCode code = PetscOptionsInsertString(s.options.get(), global);
    PetscFree(global);
    checkPetsc(code, "PetscOptionsInsertString");
  }

  // Partition on rank 0, broadcast (identical on every rank whatever METIS does).
  std::vector<int> parts(static_cast<std::size_t>(mesh.numElements()), 0);
  collectively(s.comm, [&] {
    if (rank == 0) parts = partitionElements(mesh, numRanks);
  });
  if (!parts.empty()) MPI_Bcast(parts.data(), static_cast<int>(parts.size()), MPI_INT, 0, s.comm);
  collectively(s.comm, [&] {
    s.layout = detail::buildDistributedLayout(mesh, settings.fixedVertices, parts, rank, numRanks);
    if (s.layout.numBlocks == 0) throw ValidationError("PETSc backend: every vertex is fixed, nothing to simulate");
    s.elements.reserve(s.layout.localElements.size());
    for (int e : s.layout.localElements) s.elements.push_back(elementData(mesh, e, s.corotational));
  });

  // Matrices: M and K share the pattern; the system matrix is a value-wise combination.
  s.createMatrix(s.mass);
  s.createMatrix(s.stiffness);
  const bool lumped = settings.massType == MassType::lumped;
  s.assembleMatrix(s.mass.get(), [&](std::size_t k, ElementMatrix& out) {
    const ElementData& data = s.elements[k];
    out = lumped ? lumpedElementMass(data.volume, data.density) : consistentElementMass(data.volume, data.density);
  });
  s.assembleMatrix(s.stiffness.get(), [&](std::size_t k, ElementMatrix& out) {
    if (s.corotational) {
      out = s.elements[k].stiffness;  // the tangent at rest (R = I)
    } else {
      const Material& material = mesh.elementMaterial(s.layout.localElements[k]);
      out = linearElementStiffness(s.elements[k].rest, material.youngsModulus, material.poissonRatio);
    }
  });
  checkPetsc(MatDuplicate(s.mass.get(), MAT_COPY_VALUES, s.system.out()), "MatDuplicate");
  checkPetsc(MatSetOption(s.system.get(), MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "MatSetOption");

  // Vectors; the displacement carries ghosts for the corotated element loop.
  checkPetsc(VecCreateGhost(s.comm, s.ownedDofs(), s.globalDofs(), static_cast<PetscInt>(s.layout.ghostDofs.size()),
                            s.layout.ghostDofs.data(), s.displacement.out()),
             "VecCreateGhost");
  for (detail::VecHandle* vector : {&s.velocity, &s.acceleration, &s.staticForce, &s.externalForce, &s.internalForce,
                                    &s.rhs, &s.increment, &s.work, &s.product}) {
    s.createVector(*vector);
  }
  checkPetsc(VecSet(s.displacement.get(), 0.0), "VecSet");
  for (Vec vector : {s.velocity.get(), s.acceleration.get(), s.staticForce.get(), s.increment.get()}) {
    checkPetsc(VecSet(vector, 0.0), "VecSet");
  }

  // Static external force: M g element by element (this includes the coupling of
  // free and fixed DOFs, as the restriction of the full M * stacked g does) plus the
  // owned entries of the constant force.
  if (!settings.gravity.isZero(0.0)) {
    collectively(s.comm, [&] {
      ElementVector stackedGravity;
      for (int a = 0; a < 4; ++a) stackedGravity.segment<3>(3 * a) = settings.gravity;
      for (std::size_t k = 0; k < s.elements.size(); ++k) {
        const ElementData& data = s.elements[k];
        const ElementVector force =
            (lumped ? lumpedElementMass(data.volume, data.density) : consistentElementMass(data.volume, data.density)) *
            stackedGravity;
        checkPetsc(VecSetValues(s.staticForce.get(), 12, s.layout.elementDofs[k].data(), force.data(), ADD_VALUES),
                   "VecSetValues");
      }
    });
  }
  checkPetsc(VecAssemblyBegin(s.staticForce.get()), "VecAssemblyBegin");
  checkPetsc(VecAssemblyEnd(s.staticForce.get()), "VecAssemblyEnd");
  if (settings.constantForce.size() != 0) {
    detail::VecHandle constant;
    s.createVector(constant);
    s.scatterOwned(settings.constantForce, constant.get());
    checkPetsc(VecAXPY(s.staticForce.get(), 1.0, constant.get()), "VecAXPY");
  }

  // Near null space for GAMG: the six rigid-body modes from the free vertices' rest
  // positions (harmless for the other preconditioners, which ignore it).
  {
    detail::VecHandle coordinates;
    s.createVector(coordinates);
    PetscScalar* values = nullptr;
    checkPetsc(VecGetArray(coordinates.get(), &values), "VecGetArray");
    for (PetscInt row = 0; row < s.layout.ownedBlocks; ++row) {
      const int vertex = s.layout.blockVertex[static_cast<std::size_t>(s.layout.firstBlock + row)];
      for (int c = 0; c < 3; ++c) values[(3 * row) + c] = mesh.restPositions()(c, vertex);
    }
    checkPetsc(VecRestoreArray(coordinates.get(), &values), "VecRestoreArray");
    checkPetsc(MatNullSpaceCreateRigidBody(coordinates.get(), s.nearNullSpace.out()), "MatNullSpaceCreateRigidBody");
    checkPetsc(MatSetNearNullSpace(s.system.get(), s.nearNullSpace.get()), "MatSetNearNullSpace");
    checkPetsc(MatSetNearNullSpace(s.mass.get(), s.nearNullSpace.get()), "MatSetNearNullSpace");
  }

  checkPetsc(KSPCreate(s.comm, s.solver.out()), "KSPCreate");
  checkPetsc(PetscObjectSetOptions(reinterpret_cast<PetscObject>(s.solver.get()), s.options.get()),
             "PetscObjectSetOptions");
  setKspType(s.solver.get(), settings.solver);
  if (s.trapezoidal) {
    // M a_0 = ...: its own solver (options prefix "mass_"), M never changes.
    checkPetsc(KSPCreate(s.comm, s.massSolver.out()), "KSPCreate");
    checkPetsc(PetscObjectSetOptions(reinterpret_cast<PetscObject>(s.massSolver.get()), s.options.get()),
               "PetscObjectSetOptions");
    checkPetsc(KSPSetOptionsPrefix(s.massSolver.get(), "mass_"), "KSPSetOptionsPrefix");
    checkPetsc(MatSetOption(s.mass.get(), MAT_SPD, PETSC_TRUE), "MatSetOption(MAT_SPD)");
    checkPetsc(KSPSetOperators(s.massSolver.get(), s.mass.get(), s.mass.get()), "KSPSetOperators");
    setKspType(s.massSolver.get(), settings.solver);
  }
  checkPetsc(VecScatterCreateToZero(s.displacement.get(), s.toRoot.out(), s.rootVector.out()),
             "VecScatterCreateToZero");

  // Stats.
  s.stats.ranks = numRanks;
  s.stats.elementsPerRank = s.layout.elementsPerRank;
  for (int r = 0; r < numRanks; ++r) {
    const auto i = static_cast<std::size_t>(r);
    s.stats.freeDofsPerRank.push_back(static_cast<int>(3 * (s.layout.blockStart[i + 1] - s.layout.blockStart[i])));
  }
  s.stats.freeDofs = s.globalDofs();
  MatInfo info;
  checkPetsc(MatGetInfo(s.system.get(), MAT_GLOBAL_SUM, &info), "MatGetInfo");
  s.stats.matrixNonZeros = static_cast<long long>(info.nz_used);
  KSPType kspType = nullptr;
  checkPetsc(KSPGetType(s.solver.get(), &kspType), "KSPGetType");
  PC pc = nullptr;
  checkPetsc(KSPGetPC(s.solver.get(), &pc), "KSPGetPC");
  PCType pcType = nullptr;
  checkPetsc(PCGetType(pc, &pcType), "PCGetType");
  s.stats.kspType = kspType ? kspType : "";
  s.stats.pcType = pcType ? pcType : "";
  s.stats.setupSeconds = setup.stop();
}

PetscSimulation::~PetscSimulation() = default;

void PetscSimulation::Impl::computeAcceleration() {
  // M a = fext(t) - f_int(u) - alpha M v - beta K(u) v
  const double alpha = settings.rayleighMass;
  const double beta = settings.rayleighStiffness;
  evaluateExternalForce(time());
  {
    ScopedTimer timer(assemblyWatch);
    if (corotational) assembleCorotated();
  }
  checkPetsc(VecCopy(externalForce.get(), rhs.get()), "VecCopy");
  if (corotational) {
    checkPetsc(VecAXPY(rhs.get(), -1.0, internalForce.get()), "VecAXPY");
    checkPetsc(VecCopy(velocity.get(), work.get()), "VecCopy");
    checkPetsc(VecScale(work.get(), beta), "VecScale");
  } else {
    checkPetsc(VecWAXPY(work.get(), beta, velocity.get(), displacement.get()), "VecWAXPY");
  }
  checkPetsc(MatMult(stiffness.get(), work.get(), product.get()), "MatMult");
  checkPetsc(VecAXPY(rhs.get(), -1.0, product.get()), "VecAXPY");
  if (alpha != 0.0) {
    checkPetsc(MatMult(mass.get(), velocity.get(), product.get()), "MatMult");
    checkPetsc(VecAXPY(rhs.get(), -alpha, product.get()), "VecAXPY");
  }
  solve(massSolver.get(), rhs.get(), acceleration.get(), "mass");
  accelerationStale = false;
}

void PetscSimulation::Impl::stepBackwardEuler() {
  // (M + h D + h^2 K) dv = h (fext(t_{k+1}) - f_int(u) - D v - h K v), D = alpha M + beta K;
  // v += dv, u += h v (single-process BackwardEuler, linearized step).
  const double h = settings.timestep;
  const double alpha = settings.rayleighMass;
  const double beta = settings.rayleighStiffness;
  evaluateExternalForce(stepEndTime());
  {
    ScopedTimer timer(assemblyWatch);
    if (corotational) assembleCorotated();
    if (systemStale) buildSystem(1.0 + (h * alpha), (h * beta) + (h * h));
  }
  checkPetsc(VecCopy(externalForce.get(), rhs.get()), "VecCopy");
  if (corotational) {
    checkPetsc(VecAXPY(rhs.get(), -1.0, internalForce.get()), "VecAXPY");
    checkPetsc(VecCopy(velocity.get(), work.get()), "VecCopy");
    checkPetsc(VecScale(work.get(), beta + h), "VecScale");
  } else {
    checkPetsc(VecWAXPY(work.get(), beta + h, velocity.get(), displacement.get()), "VecWAXPY");
  }
  checkPetsc(MatMult(stiffness.get(), work.get(), product.get()), "MatMult");
  checkPetsc(VecAXPY(rhs.get(), -1.0, product.get()), "VecAXPY");
  if (alpha != 0.0) {
    checkPetsc(MatMult(mass.get(), velocity.get(), product.get()), "MatMult");
    checkPetsc(VecAXPY(rhs.get(), -alpha, product.get()), "VecAXPY");
  }
  checkPetsc(VecScale(rhs.get(), h), "VecScale");
  solve(solver.get(), rhs.get(), increment.get(), "backward Euler");
  checkPetsc(VecAXPY(velocity.get(), 1.0, increment.get()), "VecAXPY");
  checkPetsc(VecAXPY(displacement.get(), h, velocity.get()), "VecAXPY");
}

void PetscSimulation::Impl::stepTrapezoidal() {
  // (M + h/2 D + h^2/4 K) a_{k+1} = fext - f_int(u) - D (v + h/2 a) - K (h v + h^2/4 a);
  // u += h v + h^2/4 (a + a_{k+1}), v += h/2 (a + a_{k+1}) (single-process Trapezoidal).
  const double h = settings.timestep;
  const double alpha = settings.rayleighMass;
  const double beta = settings.rayleighStiffness;
  if (accelerationStale) computeAcceleration();
  evaluateExternalForce(stepEndTime());
  {
    ScopedTimer timer(assemblyWatch);
    if (corotational) assembleCorotated();
    if (systemStale) buildSystem(1.0 + (0.5 * h * alpha), (0.5 * h * beta) + (0.25 * h * h));
  }
  checkPetsc(VecCopy(externalForce.get(), rhs.get()), "VecCopy");
  // work = (beta + h) v + (h beta / 2 + h^2 / 4) a (+ u for the linear model)
  checkPetsc(VecCopy(velocity.get(), work.get()), "VecCopy");
  checkPetsc(VecScale(work.get(), beta + h), "VecScale");
  checkPetsc(VecAXPY(work.get(), (0.5 * h * beta) + (0.25 * h * h), acceleration.get()), "VecAXPY");
  if (corotational) {
    checkPetsc(VecAXPY(rhs.get(), -1.0, internalForce.get()), "VecAXPY");
  } else {
    checkPetsc(VecAXPY(work.get(), 1.0, displacement.get()), "VecAXPY");
  }
  checkPetsc(MatMult(stiffness.get(), work.get(), product.get()), "MatMult");
  checkPetsc(VecAXPY(rhs.get(), -1.0, product.get()), "VecAXPY");
  if (alpha != 0.0) {
    checkPetsc(VecWAXPY(work.get(), 0.5 * h, acceleration.get(), velocity.get()), "VecWAXPY");
    checkPetsc(MatMult(mass.get(), work.get(), product.get()), "MatMult");
    checkPetsc(VecAXPY(rhs.get(), -alpha, product.get()), "VecAXPY");
  }
  // The previous acceleration is the initial guess of the iterative solvers.
  checkPetsc(VecCopy(acceleration.get(), increment.get()), "VecCopy");
  solve(solver.get(), rhs.get(), increment.get(), "trapezoidal");
  checkPetsc(VecWAXPY(work.get(), 1.0, acceleration.get(), increment.get()), "VecWAXPY");  // a + a_{k+1}
  checkPetsc(VecAXPY(displacement.get(), h, velocity.get()), "VecAXPY");
  checkPetsc(VecAXPY(displacement.get(), 0.25 * h * h, work.get()), "VecAXPY");
  checkPetsc(VecAXPY(velocity.get(), 0.5 * h, work.get()), "VecAXPY");
  checkPetsc(VecCopy(increment.get(), acceleration.get()), "VecCopy");
}

void PetscSimulation::step() {
  Impl& s = *impl_;
  if (s.trapezoidal) {
    s.stepTrapezoidal();
  } else {
    s.stepBackwardEuler();
  }
  s.checkFinite();
  ++s.stepIndex;
  ++s.stats.steps;
  s.stats.assemblySeconds = s.assemblyWatch.totalSeconds();
  s.stats.solveSeconds = s.solveWatch.totalSeconds();
}

void PetscSimulation::setState(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity, double time) {
  Impl& s = *impl_;
  collectively(s.comm, [&] {
    if (displacement.size() != s.numDofs || velocity.size() != s.numDofs) {
      throw ValidationError("PETSc backend: setState needs 3n = " + std::to_string(s.numDofs) +
                            " values for u and v (got " + std::to_string(displacement.size()) + " and " +
                            std::to_string(velocity.size()) + ")");
    }
    if (!displacement.allFinite() || !velocity.allFinite() || !std::isfinite(time)) {
      throw ValidationError("PETSc backend: setState got non-finite values");
    }
  });
  s.scatterOwned(displacement, s.displacement.get());
  s.scatterOwned(velocity, s.velocity.get());
  s.timeOrigin = time;
  s.stepIndex = 0;
  s.accelerationStale = true;
}

Eigen::VectorXd PetscSimulation::Impl::gather(Vec vector) const {
  checkPetsc(VecScatterBegin(toRoot.get(), vector, rootVector.get(), INSERT_VALUES, SCATTER_FORWARD),
             "VecScatterBegin");
  checkPetsc(VecScatterEnd(toRoot.get(), vector, rootVector.get(), INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  if (layout.rank != 0) return {};
  Eigen::VectorXd full = Eigen::VectorXd::Zero(numDofs);
  const PetscScalar* values = nullptr;
  checkPetsc(VecGetArrayRead(rootVector.get(), &values), "VecGetArrayRead");
  for (PetscInt block = 0; block < layout.numBlocks; ++block) {
    const auto vertex = static_cast<Eigen::Index>(layout.blockVertex[static_cast<std::size_t>(block)]);
    for (int c = 0; c < 3; ++c) full[(3 * vertex) + c] = values[(3 * block) + c];
  }
  checkPetsc(VecRestoreArrayRead(rootVector.get(), &values), "VecRestoreArrayRead");
  return full;
}

Eigen::VectorXd PetscSimulation::gatherDisplacement() const { return impl_->gather(impl_->displacement.get()); }
Eigen::VectorXd PetscSimulation::gatherVelocity() const { return impl_->gather(impl_->velocity.get()); }
double PetscSimulation::time() const { return impl_->time(); }
double PetscSimulation::timestep() const { return impl_->settings.timestep; }
int PetscSimulation::rank() const { return impl_->layout.rank; }
int PetscSimulation::numRanks() const { return impl_->layout.numRanks; }
const std::vector<int>& PetscSimulation::localElements() const { return impl_->layout.localElements; }
const PetscRunStats& PetscSimulation::stats() const { return impl_->stats; }

PetscTrajectory runPetscSimulation(const TetMesh& mesh, const PetscSimulationSettings& settings, int numSteps) {
  if (numSteps < 0)
    throw ValidationError("PETSc backend: numSteps must be >= 0 (got " + std::to_string(numSteps) + ")");
  PetscSimulation simulation(mesh, settings);
  PetscTrajectory trajectory;
  for (int k = 0; k < numSteps; ++k) {
    simulation.step();
    Eigen::VectorXd displacement = simulation.gatherDisplacement();
    if (simulation.rank() == 0) trajectory.displacements.push_back(std::move(displacement));
  }
  trajectory.stats = simulation.stats();
  return trajectory;
}

}  // namespace asyncfem
