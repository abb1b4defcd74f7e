// SPDX-License-Identifier: BSD-3-Clause
// The sparse shift-invert eigensolver against a dense generalized eigendecomposition, its
// normalisation, rigid modes and errors.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <string>

#include "modalTestSystem.hpp"

namespace asyncfem {
namespace {

using testing::denseModes;
using testing::modalSystem;

// A 2 x 0.5 x 0.3 bar of 4 x 2 x 2 cells (45 vertices), clamped at x = 0: 108 free DOFs,
// small enough for a dense reference, and a rectangular cross-section so that the bending
// pairs are not degenerate.
TetMesh smallBar() { return testing::boxMesh(Eigen::Vector3d(2.0, 0.5, 0.3), Eigen::Vector3i(4, 2, 2)); }

TEST(LowestModes, MatchDenseGeneralizedEigendecomposition) {
  const TetMesh mesh = smallBar();
  for (const MassType massType : {MassType::consistent, MassType::lumped}) {
    const auto system = modalSystem(mesh, mesh.vertexSet("xmin"), massType);
    const ModalResult sparse = testing::lowestModesOf(system, 10);
    const ModalResult dense = denseModes(system);
    ASSERT_EQ(sparse.frequencies.size(), 10);
    for (int j = 0; j < 10; ++j) {
      // Lanczos stops when the Ritz values of (K - sigma M)^{-1} M are accurate to 1e-10
      // relative; the dense solver's error is about eps * lambda_max / lambda_j (< 1e-11
      // here). 1e-8 on omega leaves room for both.
      EXPECT_NEAR(sparse.frequencies[j], dense.frequencies[j], 1e-8 * dense.frequencies[j]) << "mode " << j;
      if (j > 0) {
        EXPECT_GE(sparse.frequencies[j], sparse.frequencies[j - 1]);
      }
      // Modes agree up to sign (and rotation inside a cluster of equal frequencies): the part
      // of the sparse mode outside the span of the dense modes with the same eigenvalue is
      // small in the M-norm. Eigenvector error ~ eigenvalue error / gap, hence 1e-6.
      Eigen::VectorXd rest = sparse.modes.col(j);
      for (Eigen::Index k = 0; k < dense.modes.cols(); ++k) {
        if (std::abs(dense.eigenvalues[k] - sparse.eigenvalues[j]) <= 1e-6 * sparse.eigenvalues[j]) {
          rest -= dense.modes.col(k) * dense.modes.col(k).dot(system.mass * sparse.modes.col(j));
        }
      }
      EXPECT_LE(std::sqrt(rest.dot(system.mass * rest)), 1e-6) << "mode " << j;
    }
  }
}

TEST(LowestModes, AreMassOrthonormalResidualFreeAndZeroOnFixedDofs) {
  const TetMesh mesh = smallBar();
  const auto system = modalSystem(mesh, mesh.vertexSet("xmin"), MassType::consistent);
  const ModalResult result = testing::lowestModesOf(system, 8);
  const Eigen::MatrixXd gram = result.modes.transpose() * (system.mass * result.modes);
  // Lanczos keeps its basis M-orthonormal to round-off (full reorthogonalisation).
  EXPECT_LE((gram - Eigen::MatrixXd::Identity(8, 8)).cwiseAbs().maxCoeff(), 1e-10);
  for (int j = 0; j < 8; ++j) {
    const Eigen::VectorXd residual = system.freeDofs.restrict(
        system.stiffness * result.modes.col(j) - result.eigenvalues[j] * (system.mass * result.modes.col(j)));
    const double scale = result.eigenvalues[j] * system.freeDofs.restrict(system.mass * result.modes.col(j)).norm();
    EXPECT_LE(residual.norm(), 1e-7 * scale) << "mode " << j;
  }
  for (int v : mesh.vertexSet("xmin")) EXPECT_EQ(result.modes.row(3 * v).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(result.shift, 0.0);
  EXPECT_GT(result.operatorApplications, 0);
}

TEST(LowestModes, FreeBodyHasSixRigidModes) {
  const TetMesh mesh = smallBar();
  const auto system = modalSystem(mesh, {}, MassType::lumped);
  const ModalResult result = testing::lowestModesOf(system, 8);
  // Rigid modes have lambda = 0 up to the round-off of K (about eps * lambda_max), so
  // omega ~ 1e-8 omega_max; the first elastic mode of the bar is a few percent of omega_max.
  const double firstElastic = result.frequencies[6];
  EXPECT_GT(firstElastic, 0.0);
  for (int j = 0; j < 6; ++j) EXPECT_LT(result.frequencies[j], 1e-4 * firstElastic) << "mode " << j;
  EXPECT_GT(result.frequencies[7], 0.0);
}

TEST(LowestModes, RejectsBadArguments) {
  const TetMesh mesh = smallBar();
  const auto system = modalSystem(mesh, mesh.vertexSet("xmin"), MassType::lumped);
  const auto expectError = [&](const ModalOptions& options, const std::string& expected) {
    try {
      lowestModes(system.stiffness, system.mass, system.freeDofs, options);
      ADD_FAILURE() << "no error for " << expected;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  ModalOptions options;
  options.count = 0;
  expectError(options, "number of modes must be in [1, 107]");
  options.count = system.freeDofs.numFree();
  expectError(options, "got 108");
  options.count = 4;
  options.shift = 1e12;  // above most of the spectrum: K - sigma M is indefinite
  expectError(options, "cannot factor K - sigma M");
  options.shift = std::numeric_limits<double>::quiet_NaN();
  options.maxIterations = 1;
  options.tolerance = 1e-300;
  expectError(options, "converged for");
  EXPECT_THROW(lowestModes(system.stiffness, system.mass, FreeDofs::fromFixedVertices(3, {}), {}), ValidationError);
}

}  // namespace
}  // namespace asyncfem
