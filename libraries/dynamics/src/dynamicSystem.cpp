// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <cmath>
#include <string>

namespace asyncfem {

void DynamicSystem::validate() const {
  if (!forceModel) throw ValidationError("dynamic system has no force model");
  const int n = forceModel->numDofs();
  if (mass.rows() != n || mass.cols() != n) {
    throw ValidationError("mass matrix is " + std::to_string(mass.rows()) + " x " + std::to_string(mass.cols()) +
                          " but the force model has " + std::to_string(n) + " DOFs");
  }
  if (freeDofs.numDofs() != n) {
    throw ValidationError("free-DOF map covers " + std::to_string(freeDofs.numDofs()) + " DOFs, expected " +
                          std::to_string(n));
  }
  if (mesh && mesh->numDofs() != n) {
    throw ValidationError("the dynamic system's mesh has " + std::to_string(mesh->numDofs()) +
                          " DOFs but the force model has " + std::to_string(n));
  }
  if (externalForceJacobian && !externalForce) {
    throw ValidationError("the dynamic system has an external-force Jacobian but no external force");
  }
  if (!(rayleighMass >= 0.0) || !(rayleighStiffness >= 0.0) || !std::isfinite(rayleighMass) ||
      !std::isfinite(rayleighStiffness)) {
    throw ValidationError("Rayleigh damping coefficients must be finite and >= 0 (alpha " +
                          std::to_string(rayleighMass) + ", beta " + std::to_string(rayleighStiffness) + ")");
  }
}

}  // namespace asyncfem
