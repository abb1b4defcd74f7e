// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/asyncIntegrator/partitionedIntegrator.hpp>
#include <asyncfem/core/error.hpp>
#include <memory>
#include <string>

namespace asyncfem {

namespace {
const TetMesh& meshOf(const char* integratorName, const DynamicSystem& system) {
  if (!system.mesh) {
    throw ValidationError(std::string(integratorName) +
                          " integrator: the dynamic system has no mesh (set DynamicSystem::mesh, as "
                          "Problem::dynamicSystem() does, or pass the mesh)");
  }
  return *system.mesh;
}
}  // namespace

PartitionedIntegrator::PartitionedIntegrator(const char* integratorName, DynamicSystem system, double largeTimestep,
                                             std::vector<AsyncRegion> regions, bool acceptsTouching)
    : Integrator(std::move(system), largeTimestep),
      partition_(meshOf(integratorName, system_), system_.freeDofs, std::move(regions)) {
  if (!acceptsTouching) partition_.requireSeparated(std::string(integratorName) + " integrator");
}

PartitionedIntegrator::PartitionedIntegrator(const char* integratorName, DynamicSystem system, double largeTimestep,
                                             RegionPartition partition)
    : Integrator(std::move(system), largeTimestep), partition_(std::move(partition)) {
  meshOf(integratorName, system_);
}

DynamicSystem PartitionedIntegrator::withMesh(const char* integratorName, const TetMesh& mesh, DynamicSystem system) {
  if (mesh.numDofs() != system.numDofs()) {
    throw ValidationError(std::string(integratorName) + " integrator: mesh has " + std::to_string(mesh.numDofs()) +
                          " DOFs but the dynamic system has " + std::to_string(system.numDofs()));
  }
  if (!system.mesh) system.mesh = std::make_shared<const TetMesh>(mesh);
  return system;
}

}  // namespace asyncfem
