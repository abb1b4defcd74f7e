// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <bindings.hpp>

namespace asyncfem::python {

/// DynamicSystem as Python sees it: the C++ struct, plus the Python callable behind
/// externalForce (to hand it back from the getter).
struct PythonDynamicSystem {
  DynamicSystem system;
  py::object externalForce = py::none();
};

/// Checks that the system's parts fit (ValueError naming the field) before an integrator
/// copies it.
DynamicSystem checkedSystem(const PythonDynamicSystem& system);

}  // namespace asyncfem::python
