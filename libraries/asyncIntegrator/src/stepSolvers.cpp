// SPDX-License-Identifier: BSD-3-Clause
// What the step solvers share: when the options allow implicit contact, and the run
// summary's lines on the steady step and on implicit contact.
#include "stepSolvers.hpp"

#include <cstdio>
#include <string>

namespace asyncfem {

namespace detail {

bool asyncLinearizesContact(const AsyncOptions& options) {
  return options.coupling == AsyncCoupling::stable && options.method != AsyncSolveMethod::naive &&
         !options.processes.largeSystemSolver && !options.processes.regionDistribution.sum;
}

bool StepSolver::implicitContact() const {
  return static_cast<bool>(system_.externalForceJacobian) && asyncLinearizesContact(options_);
}

std::string steadyStepLine(const AsyncRunStats& r) {
  char line[256];
  std::snprintf(line, sizeof(line), "async steady large step %.3f ms over %lld steps; rebuilds %lld (%.3f s)",
                1000.0 * r.meanStepSeconds(), r.steps, r.rebuilds, r.rebuildSeconds);
  return line;
}

std::string contactLine(const AsyncRunStats& r, const char* perStep, const char* stopped, int limit,
                        const std::string& refactored) {
  char line[256];
  std::snprintf(line, sizeof(line),
                "async implicit contact: %lld solves over %lld steps (%.2f per step%s); %lld steps stopped at %d %s "
                "unconverged (largest relative residual %.2e); ",
                r.contactIterations, r.contactSteps,
                static_cast<double>(r.contactIterations) / static_cast<double>(r.contactSteps), perStep,
                r.unconvergedContactSteps, limit, stopped, r.largestContactResidual);
  return line + refactored;
}

}  // namespace detail

}  // namespace asyncfem
