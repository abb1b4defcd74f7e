// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/asyncIntegrator/stepSolver.hpp>
#include <string>

namespace asyncfem {

std::string toString(AsyncStepSolver solver) {
  switch (solver) {
    case AsyncStepSolver::naiveLU:
      return "naive LU";
    case AsyncStepSolver::hierarchy:
      return "hierarchy";
    case AsyncStepSolver::structuredSchur:
      break;
  }
  return "structured Schur";
}

std::string toString(NestedSolve solve) {
  switch (solve) {
    case NestedSolve::structured:
      return "structured";
    case NestedSolve::lu:
      return "lu";
    case NestedSolve::automatic:
      break;
  }
  return "automatic";
}

NestedSolve parseNestedSolve(const std::string& name) {
  for (NestedSolve s : {NestedSolve::automatic, NestedSolve::structured, NestedSolve::lu})
    if (toString(s) == name) return s;
  throw ValidationError("unknown nested solve '" + name + "' (expected automatic, structured or lu)");
}

namespace {

// Options that hold for every solver.
void checkCommonOptions(const AsyncOptions& options) {
  const AsyncOptions::Processes::RegionDistribution& distribution = options.processes.regionDistribution;
  if (static_cast<bool>(distribution.ownedRegions) != static_cast<bool>(distribution.sum)) {
    throw AsyncOptionError("regionDistribution", "needs both ownedRegions and sum");
  }
  if (!(options.contact.tolerance > 0.0 && options.contact.tolerance < 1.0)) {
    throw AsyncOptionError("contactTolerance",
                           "must be in (0, 1) (got " + std::to_string(options.contact.tolerance) + ")");
  }
  if (options.contact.iterations < 1) {
    throw AsyncOptionError("contactIterations",
                           "must be >= 1 (got " + std::to_string(options.contact.iterations) + ")");
  }
  const bool stableStructured =
      options.coupling == AsyncCoupling::stable && options.method == AsyncSolveMethod::structured;
  if (options.processes.largeSystemSolver && !stableStructured) {
    throw AsyncOptionError("largeSystemSolver",
                           "an external solver of L's system needs the stable coupling and the structured method (it "
                           "is given the symmetric H^{LL*})");
  }
  if (distribution.sum && !stableStructured) {
    throw AsyncOptionError("regionDistribution",
                           "regions owned by one process need the stable coupling and the structured method");
  }
}

// The hierarchy solve has its own factor and no Schur complement: every option of the
// two-level solve is refused unless it is at its default (nothing is silently ignored).
void checkHierarchyOptions(const AsyncOptions& options, const std::string& why) {
  const AsyncOptions defaults;
  const auto refuse = [&why](const char* key, const std::string& what) {
    throw AsyncOptionError(key, what + " is not available with the hierarchy solve (" + why + ")");
  };
  if (options.coupling != AsyncCoupling::stable) refuse("coupling", "the paper's coupling");
  if (options.keptFactors.quickSetUp) refuse("quickSetUp", "the quick set-up");
  if (options.contact.substepStatePrediction)
    refuse("substepStatePrediction", "contact at the substeps' predicted states");
  if (options.processes.largeSystemSolver)
    refuse("largeSystemSolver", "an external solver of L's system (the PETSc backend)");
  if (options.processes.regionDistribution.sum) refuse("regionDistribution", "regions owned by one process");
  if (options.schur != defaults.schur) refuse("schur", "a Schur mode");
  if (options.recovery != defaults.recovery) refuse("recovery", "a recovery mode");
  if (options.zSolve != defaults.zSolve) refuse("zSolve", "a choice of how Z is computed");
  if (options.regionSolver != defaults.regionSolver) refuse("regionSolver", "a region solver");
  if (options.denseRegionDofs != defaults.denseRegionDofs) refuse("denseRegionDofs", "dense region factors");
}

}  // namespace

void requireHierarchyComposes(const AsyncOptions& options, const std::string& why) {
  checkHierarchyOptions(options, why);
}

AsyncStepSolver chooseStepSolver(const AsyncOptions& options, const RegionPartition& partition,
                                 const DynamicSystem& system) {
  checkCommonOptions(options);
  const bool hierarchy = partition.touching() || options.method == AsyncSolveMethod::hierarchy;
  if (hierarchy) {
    const std::string why = partition.touching() ? "the regions given touch or nest" : "\"method\": \"hierarchy\"";
    if (options.method == AsyncSolveMethod::naive) {
      throw AsyncOptionError("method",
                             "the naive solve method couples each region only to L, but the regions given touch or "
                             "nest (\"hierarchy\" with \"nestedSolve\": \"lu\" is the reference there)");
    }
    requireHierarchyComposes(options, why);
    if (system.externalForceOfRank) {
      // Its steps take each vertex's external force at the vertex's own rate: exact for
      // per-vertex loads, not for a surface pair between rates (its impulses would not
      // balance: docs/asynchronous-integrator.md, "Contact between regions").
      throw AsyncOptionError("regions",
                             "surface contact (contact.surfaces) is not available with the hierarchy solve (" + why +
                                 "): keep the fast regions apart, or make them one region");
    }
    return AsyncStepSolver::hierarchy;
  }
  if (options.nestedSolve != NestedSolve::automatic) {
    throw AsyncOptionError("nestedSolve",
                           "only meaningful for regions that touch or nest, or with \"method\": \"hierarchy\"");
  }
  return options.method == AsyncSolveMethod::naive ? AsyncStepSolver::naiveLU : AsyncStepSolver::structuredSchur;
}

}  // namespace asyncfem
