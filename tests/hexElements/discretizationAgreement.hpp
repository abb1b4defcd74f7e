// SPDX-License-Identifier: BSD-3-Clause
// The check that a cantilever's compliance on cubes and on their 6-tetrahedra split agree
// only to discretization, shared by the hexElements and problem tests.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace asyncfem::test {

/// Compliances f . u of the coarse (4 x 1 x 1 cubes) and fine (8 x 2 x 2) bar of hexBar(),
/// on hexahedra and on the tetrahedra of the same cubes.
struct BarCompliances {
  double hexCoarse = 0.0;
  double hexFine = 0.0;
  double tetCoarse = 0.0;
  double tetFine = 0.0;
};

/// Records the four values (--gtest_output=xml lists them) and checks what the theory says.
inline void expectAgreementOnlyToDiscretization(const BarCompliances& c) {
  ::testing::Test::RecordProperty("hexCoarse", std::to_string(c.hexCoarse));
  ::testing::Test::RecordProperty("hexFine", std::to_string(c.hexFine));
  ::testing::Test::RecordProperty("tetCoarse", std::to_string(c.tetCoarse));
  ::testing::Test::RecordProperty("tetFine", std::to_string(c.tetFine));
  // Conforming displacement FEM with the exact load functional: the compliance is the
  // strain energy of the Galerkin solution, which grows under refinement of nested spaces
  // (trilinear on halved cubes contains trilinear on the cubes; the Kuhn split of the halved
  // lattice refines that of the lattice) towards the exact compliance.
  EXPECT_GT(c.hexFine, c.hexCoarse);
  EXPECT_GT(c.tetFine, c.tetCoarse);
  // The two spaces differ (neither contains the other), so neither value bounds the other.
  // Agreement to discretization: each fine value's distance to the common limit C is
  // estimated by Richardson from its own refinement step, (C_fine - C_coarse) / (2^p - 1)
  // with p = 2 for the energy of a smooth solution; the clamped edge's singularity lowers
  // p, so the bound takes p = 1 (a factor 3 safer): |C_hex - C_tet| <= sum of the two
  // estimates.
  const double bound = (c.hexFine - c.hexCoarse) + (c.tetFine - c.tetCoarse);
  EXPECT_LE(std::abs(c.hexFine - c.tetFine), bound) << "hex " << c.hexFine << " tet " << c.tetFine;
  // And they approach each other: the gap shrinks under refinement.
  EXPECT_LT(std::abs(c.hexFine - c.tetFine), std::abs(c.hexCoarse - c.tetCoarse))
      << "coarse: hex " << c.hexCoarse << " tet " << c.tetCoarse << "; fine: hex " << c.hexFine << " tet " << c.tetFine;
}

}  // namespace asyncfem::test
