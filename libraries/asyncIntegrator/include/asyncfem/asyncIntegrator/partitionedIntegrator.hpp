// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// A multirate integrator whose regions are a RegionPartition of its system's mesh (the
/// asynchronous and the uncoupled multirate integrators): builds and owns the partition
/// and answers the region queries from it.
class PartitionedIntegrator : public Integrator, public MultirateIntegrator {
 public:
  /// system.mesh must be set; the partition is built on it and system.freeDofs. Throws
  /// asyncfem::ValidationError (naming the integrator) without a mesh, for whatever
  /// RegionPartition rejects and, unless acceptsTouching, for regions that touch or nest.
  PartitionedIntegrator(const char* integratorName, DynamicSystem system, double largeTimestep,
                        std::vector<AsyncRegion> regions, bool acceptsTouching);
  /// The same with a partition built already (on system.mesh and system.freeDofs).
  PartitionedIntegrator(const char* integratorName, DynamicSystem system, double largeTimestep,
                        RegionPartition partition);

  const RegionPartition& partition() const { return partition_; }
  std::vector<RegionSummary> regionSummaries() const override { return summarizeRegions(partition_); }
  int regionOfVertex(int vertex) const override { return partition_.regionOfVertex(vertex); }
  const MultirateIntegrator* multirate() const override { return this; }

  /// system with mesh attached (a copy) when it has none; throws asyncfem::ValidationError
  /// if their sizes differ. For systems assembled by hand without their mesh.
  static DynamicSystem withMesh(const char* integratorName, const TetMesh& mesh, DynamicSystem system);

 protected:
  RegionPartition partition_;
};

}  // namespace asyncfem
