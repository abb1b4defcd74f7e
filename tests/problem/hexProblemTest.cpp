// SPDX-License-Identifier: BSD-3-Clause
// A Problem on a hexahedral mesh: linear FEM with the trilinear elements of library
// hexElements, StVK and corotational FEM; the other force models and the tetrahedral
// assembler are refused by name.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/hexToTets.hpp>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "../hexElements/discretizationAgreement.hpp"
#include "../hexElements/hexBar.hpp"

namespace asyncfem {
namespace {

std::vector<int> rootVertices(const TetMesh& mesh) {
  std::vector<int> root;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (mesh.restPosition(v).x() == 0.0) root.push_back(v);
  return root;
}

// The static deflection K u = M g on the free DOFs, solved here from the element library's
// matrices: the oracle the damped run must settle to.
Eigen::VectorXd staticDeflection(const TetMesh& mesh, const FreeDofs& dofs, const Eigen::Vector3d& gravity) {
  const Eigen::SparseMatrix<double> full = hexLinearStiffnessMatrix(mesh);
  const Eigen::SparseMatrix<double> stiffness =
      SubmatrixExtractor(full, dofs.freeToFull(), dofs.freeToFull()).extract(full);
  const Eigen::VectorXd load = dofs.restrict(
      Eigen::VectorXd(hexMassMatrix(mesh, MassType::consistent) * gravity.replicate(mesh.numVertices(), 1)));
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(stiffness);
  EXPECT_EQ(solver.info(), Eigen::Success);
  return dofs.expand(solver.solve(load));
}

TEST(HexahedralProblem, BackwardEulerSettlesOnTheStaticDeflection) {
  auto mesh = std::make_shared<const TetMesh>(test::hexBar(1));
  ProblemSettings settings;
  settings.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  settings.rayleighAlpha = 2.0;
  const Problem problem(mesh, rootVertices(*mesh), settings);
  // Mass of the bar: rho V = 1000 * 1 * 0.25 * 0.25, whatever the element.
  const Eigen::VectorXd ones = Eigen::Vector3d::UnitX().replicate(mesh->numVertices(), 1);
  EXPECT_NEAR(ones.dot(problem.massMatrix() * ones), 62.5, 1e-10);

  BackwardEuler integrator(problem.dynamicSystem(), 0.1);
  for (int i = 0; i < 300; ++i) integrator.step();
  const Eigen::VectorXd expected = staticDeflection(*mesh, problem.freeDofs(), settings.gravity);
  // The lowest bending mode (about 8 rad/s) shrinks by at least 1 / |1 + i omega h| = 0.78
  // per step, and by more with the damping: after 300 steps only round-off of the solves
  // (condition number about 1e4) remains.
  EXPECT_LE((integrator.displacement() - expected).norm(), 1e-9 * expected.norm());
  EXPECT_LT(expected.minCoeff(), -1e-3);  // it does bend: the tip sinks by millimetres
  for (const int v : problem.fixedVertices()) EXPECT_EQ(integrator.displacement().segment<3>(3 * v).norm(), 0.0);
}

TEST(HexahedralProblem, OtherModelsAndTheTetrahedralAssemblerAreRefused) {
  auto mesh = std::make_shared<const TetMesh>(test::hexBar(1));
  for (const ForceModelType type : {ForceModelType::neoHookean, ForceModelType::mooneyRivlin}) {
    ProblemSettings settings;
    settings.forceModel = type;
    try {
      const Problem problem(mesh, rootVertices(*mesh), settings);
      ADD_FAILURE() << toString(type) << " accepted on hexahedra";
    } catch (const ValidationError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(toString(type)), std::string::npos) << message;
      EXPECT_NE(message.find("4 hexahedra"), std::string::npos) << message;
      EXPECT_NE(message.find("--hex-to-tets"), std::string::npos) << message;
    }
  }
  const Problem linear(mesh, rootVertices(*mesh), ProblemSettings{});
  EXPECT_THROW((void)linear.assembler(), ValidationError);
  // StVK runs in its Green-strain form only: an option it would ignore is refused.
  ProblemSettings threshold;
  threshold.forceModel = ForceModelType::stvk;
  threshold.hyperelastic.inversionThreshold = 0.5;
  EXPECT_THROW(Problem(mesh, rootVertices(*mesh), threshold), ValidationError);
}

// StVK's and corotational FEM's forces are K u + O(|u|^2), so their static deflection
// differs from linear FEM's by O(sag^2): relative to the deflection O(sag / length), in
// proportion to the load while the load is small. Gravity 0.5 and 1 (m/s^2) sag the 1 m bar
// by about 1 to 2 cm.
TEST(HexahedralProblem, NonlinearModelsDepartFromLinearInProportionToTheLoad) {
  auto mesh = std::make_shared<const TetMesh>(test::hexBar(1));
  for (const ForceModelType model : {ForceModelType::stvk, ForceModelType::corotational}) {
    SCOPED_TRACE(toString(model));
    const auto relativeDifference = [&](double gravity, double& sag) {
      ProblemSettings settings;
      settings.gravity = Eigen::Vector3d(0.0, -gravity, 0.0);
      settings.rayleighAlpha = 2.0;
      settings.forceModel = model;
      const Problem problem(mesh, rootVertices(*mesh), settings);
      BackwardEuler integrator(problem.dynamicSystem(), 0.1);
      EXPECT_FALSE(integrator.system().forceModel->isLinear());
      for (int i = 0; i < 300; ++i) integrator.step();
      EXPECT_TRUE(integrator.displacement().allFinite());
      const Eigen::VectorXd linear = staticDeflection(*mesh, problem.freeDofs(), settings.gravity);
      sag = -linear.minCoeff();
      return (integrator.displacement() - linear).norm() / linear.norm();
    };
    double sagHalf = 0.0;
    double sagFull = 0.0;
    const double half = relativeDifference(0.5, sagHalf);
    const double full = relativeDifference(1.0, sagFull);
    RecordProperty(toString(model) + "RelativeDifferenceHalf", std::to_string(half));
    RecordProperty(toString(model) + "RelativeDifferenceFull", std::to_string(full));
    // Leading order: the ratio is 2; the next order (relative sag^2, about 1e-4) moves it by
    // far less than the 0.5 allowed. A linear model (difference at round-off) or a wrong
    // stress factor (a difference of order 1 that does not scale) fails it.
    EXPECT_NEAR(full / half, 2.0, 0.5);
    EXPECT_LE(full, 2.0 * sagFull);  // an O(1) coefficient per unit of sag / length
  }
}

// The compliance f . u with f = M g after the damped cantilever has settled under gravity
// (the consistent mass makes f the exact load functional of gravity for either element).
double settledCompliance(const TetMesh& mesh, ForceModelType model) {
  ProblemSettings settings;
  settings.gravity = Eigen::Vector3d(0.0, -1.0, 0.0);
  settings.rayleighAlpha = 2.0;
  settings.forceModel = model;
  const Problem problem(std::make_shared<const TetMesh>(mesh), rootVertices(mesh), settings);
  BackwardEuler integrator(problem.dynamicSystem(), 0.1);
  for (int i = 0; i < 300; ++i) integrator.step();
  const Eigen::VectorXd load = problem.massMatrix() * settings.gravity.replicate(mesh.numVertices(), 1);
  return load.dot(integrator.displacement());
}

TEST(HexahedralProblem, StvkOnCubesAndOnTheirTetrahedraAgreeOnlyToDiscretization) {
  // The same argument as HexVersusTets.CantileverAgreesOnlyToDiscretization, for StVK run
  // through Problem and backward Euler: under gravity 1 m/s^2 StVK differs from linear FEM
  // by about 1% (StvkDepartsFromLinearInProportionToTheLoad), far below the 30% and 89% the
  // hexahedra's and the tetrahedra's compliance change by under refinement, so the linear
  // theory's bounds apply: the compliance grows under nested refinement, and the
  // hexahedra's and the tetrahedra's values approach each other within the sum of their own
  // refinement steps.
  const TetMesh coarse = test::hexBar(1);
  const TetMesh fine = test::hexBar(2);
  test::expectAgreementOnlyToDiscretization({settledCompliance(coarse, ForceModelType::stvk),
                                             settledCompliance(fine, ForceModelType::stvk),
                                             settledCompliance(hexahedraToTetrahedra(coarse), ForceModelType::stvk),
                                             settledCompliance(hexahedraToTetrahedra(fine), ForceModelType::stvk)});
}

}  // namespace
}  // namespace asyncfem
