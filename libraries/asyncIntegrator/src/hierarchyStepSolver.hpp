// SPDX-License-Identifier: BSD-3-Clause
// The hierarchy step solver: partitions whose regions touch or nest, or any partition with
// AsyncSolveMethod::hierarchy (docs/asynchronous-integrator.md, "Nested and touching
// regions", Eqs. N1-N14; the step system itself is detail::HierarchySystem). Private to the
// library.
#pragma once

#include <Eigen/Core>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "detail/hierarchySystem.hpp"
#include "stepSolvers.hpp"

namespace asyncfem::detail {

class HierarchyStepSolver final : public StepSolver {
 public:
  explicit HierarchyStepSolver(const StepContext& context);

  AsyncStepSolver kind() const override { return AsyncStepSolver::hierarchy; }
  void setUp() override;
  void invalidateFactors() override { factorsCurrent_ = false; }
  StepEnd step(double t0, double t1) override;
  long long factorNonZeros() const override { return stepSystem_->factorNonZeros(); }
  void reportLines(std::vector<std::string>& lines) const override;
  const HierarchySystem& system() const { return *stepSystem_; }

 private:
  void solveContact(double t0, double t1);

  bool linear_;
  bool factorsCurrent_ = false;
  std::unique_ptr<HierarchySystem> stepSystem_;
  // f_ext at each time unit where some DOF's step ends (Eq. N3; kept from step to step).
  std::map<long long, Eigen::VectorXd> unitForces_;
  Eigen::VectorXd internalForce_, newU_, newV_;
};

}  // namespace asyncfem::detail
