// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/asyncIntegrator/asyncOptions.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <string>

// Which solver AsyncBackwardEuler runs for a partition, and the one check of its options
// against the partition and the system (docs/asynchronous-integrator.md, "The step solvers").
namespace asyncfem {

/// The step solvers of AsyncBackwardEuler.
enum class AsyncStepSolver {
  /// Two levels per region (each S_i coupled only to L): forward substitution per region
  /// and the Schur complement H^{LL*} on L (Eqs. A13-A15).
  structuredSchur,
  /// Two levels per region: one LU of the whole block system (the reference).
  naiveLU,
  /// Any partition whose ratios divide one another across each element, regions that touch
  /// or nest included: the time-local step system (Eqs. N5-N12), level by level or one LU.
  hierarchy,
};
/// "structured Schur", "naive LU", "hierarchy".
std::string toString(AsyncStepSolver solver);

/// An AsyncOptions value that the partition, the system or the other options refuse.
/// key() is the option's scene key (docs/scene-format.md), so a scene reader can name it.
class AsyncOptionError : public ValidationError {
 public:
  AsyncOptionError(std::string key, std::string reason)
      : ValidationError("async integrator option \"" + key + "\": " + reason),
        key_(std::move(key)),
        reason_(std::move(reason)) {}
  const std::string& key() const { return key_; }
  /// The message without the option's name.
  const std::string& reason() const { return reason_; }

 private:
  std::string key_, reason_;
};

/// The solver for options on partition, after checking every option against the partition,
/// the system and the other options: the one place that decides what composes. Throws
/// AsyncOptionError naming the refused option and why. Regions that touch or nest (and
/// AsyncSolveMethod::hierarchy) take the hierarchy solve, which refuses the paper's coupling,
/// the quick set-up, substep contact prediction, an external solver of L's system, region
/// distribution, any non-default setting of the two-level solve (schur, recovery,
/// regionSolver, denseRegionDofs) and a system with surface contact (externalForceOfRank,
/// named as "regions"); the two-level solvers refuse a nestedSolve other than
/// automatic. An external large-system solver and region distribution need the stable
/// coupling and the structured method.
AsyncStepSolver chooseStepSolver(const AsyncOptions& options, const RegionPartition& partition,
                                 const DynamicSystem& system);

namespace detail {
/// The structured Schur solve's reports kept across partitions (AsyncBackwardEuler's
/// schurAsymmetry(), zColumnSeconds(), schurModeUsed()).
struct SchurReport {
  double asymmetry = 0.0;
  double zColumnSeconds = 0.0;
  SchurMode modeUsed = SchurMode::lowRank;
};
}  // namespace detail

/// What chooseStepSolver() checks for the hierarchy solve, ahead of any partition: for
/// run-time regions that may nest (RunTimeRegionOptions::nest), so that a refusal comes
/// before the run rather than at the step where regions first touch. why: the reason the
/// hierarchy solve would run, for the message.
void requireHierarchyComposes(const AsyncOptions& options, const std::string& why);

}  // namespace asyncfem
