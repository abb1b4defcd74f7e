// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/centralDifferences.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/integrator/symplecticEuler.hpp>
#include <asyncfem/integrator/trapezoidal.hpp>

namespace asyncfem {

std::vector<std::string> integratorNames() {
  return {"backward-euler", "trapezoidal", "central-differences", "symplectic-euler"};
}

std::unique_ptr<Integrator> makeIntegrator(const std::string& name, DynamicSystem system, double timestep,
                                           const IntegratorOptions& options) {
  if (name == "backward-euler") return std::make_unique<BackwardEuler>(std::move(system), timestep, options);
  if (name == "trapezoidal") return std::make_unique<Trapezoidal>(std::move(system), timestep, options);
  if (name == "central-differences") {
    return std::make_unique<CentralDifferences>(std::move(system), timestep, options);
  }
  if (name == "symplectic-euler") return std::make_unique<SymplecticEuler>(std::move(system), timestep, options);
  std::string valid;
  for (const std::string& known : integratorNames()) valid += (valid.empty() ? "" : ", ") + known;
  throw Error("unknown integrator \"" + name + "\" (valid: " + valid + ")");
}

}  // namespace asyncfem
