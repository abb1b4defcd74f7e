// SPDX-License-Identifier: BSD-3-Clause
// LowestModesSolver: one factorization of K - sigma M for several mode counts, the same
// modes as lowestModes().
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>

#include "modalTestSystem.hpp"

namespace asyncfem {
namespace {

// Counts 4, 8 and 16 from one solver: bit for bit what lowestModes() gives for each count
// (the same factor, the same Lanczos start vector), with one factorization in all and one
// solve per Lanczos vector and restart, counted per call and in total.
TEST(LowestModesSolver, KeepsItsFactorAcrossCountsAndGivesLowestModesResults) {
  const TetMesh mesh = testing::boxMesh(Eigen::Vector3d(2.0, 0.5, 0.3), Eigen::Vector3i(4, 2, 2));
  const auto system = testing::modalSystem(mesh, mesh.vertexSet("xmin"), MassType::consistent);
  const LowestModesSolver solver(system.stiffness, system.mass, system.freeDofs);
  EXPECT_GT(solver.factorSeconds(), 0.0);
  EXPECT_EQ(solver.operatorApplications(), 0);
  EXPECT_EQ(solver.numFree(), system.freeDofs.numFree());
  int solves = 0;
  for (const int count : {4, 8, 16}) {
    const ModalResult kept = solver.compute(count);
    const ModalResult fresh = testing::lowestModesOf(system, count);
    ASSERT_EQ(kept.frequencies.size(), count);
    EXPECT_EQ(kept.eigenvalues, fresh.eigenvalues) << "count " << count;
    EXPECT_EQ(kept.modes, fresh.modes) << "count " << count;
    EXPECT_EQ(kept.shift, fresh.shift);
    EXPECT_EQ(kept.factorSeconds, 0.0);
    EXPECT_EQ(kept.operatorApplications, fresh.operatorApplications);
    EXPECT_GE(kept.operatorApplications, count);
    solves += kept.operatorApplications;
  }
  EXPECT_EQ(solver.operatorApplications(), solves);
  EXPECT_THROW(solver.compute(0), ValidationError);
  EXPECT_THROW(solver.compute(system.freeDofs.numFree()), ValidationError);
}

}  // namespace
}  // namespace asyncfem
