// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/integrator/integratorOptions.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// The names makeIntegrator() accepts: "backward-euler", "trapezoidal",
/// "central-differences", "symplectic-euler".
std::vector<std::string> integratorNames();

/// Creates the single-rate integrator called name for system with timestep h. Throws
/// asyncfem::Error listing the valid names for an unknown name, and whatever the
/// integrator's constructor throws (e.g. ValidationError for an explicit method above its
/// stable timestep).
std::unique_ptr<Integrator> makeIntegrator(const std::string& name, DynamicSystem system, double timestep,
                                           const IntegratorOptions& options = {});

}  // namespace asyncfem
