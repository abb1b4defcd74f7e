// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

// Force on one vertex at unit strain: E h^2 with h the cell size.
double forceScale(int cells) { return test::kYoungsModulus * test::cellSize(cells) * test::cellSize(cells); }

using test::finiteDifferenceTangent;
using test::forces;
using test::tangent;

template <class Vector>
bool bitIdentical(const Vector& a, const Vector& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

bool bitIdentical(const SparseMatrix& a, const SparseMatrix& b) {
  return a.nonZeros() == b.nonZeros() &&
         std::memcmp(a.valuePtr(), b.valuePtr(), sizeof(double) * static_cast<std::size_t>(a.nonZeros())) == 0;
}

class ThreadCountGuard {
 public:
  ThreadCountGuard() : saved_(omp_get_max_threads()) {}
  ~ThreadCountGuard() { omp_set_num_threads(saved_); }
  ThreadCountGuard(const ThreadCountGuard&) = delete;
  ThreadCountGuard& operator=(const ThreadCountGuard&) = delete;

 private:
  int saved_;
};

TEST(CorotationalLinearFEM, RigidMotionsGiveNoForceAndNoEnergy) {
  const int cells = 2;
  const TetMesh mesh = test::smallBox(cells);
  CorotationalLinearFEM model(mesh);
  std::mt19937 random(1);
  std::vector<Eigen::Matrix3d> rotations = {
      Eigen::Matrix3d::Identity(),
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
      Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix(),
      Eigen::AngleAxisd(M_PI, Eigen::Vector3d(1, 1, 1).normalized()).toRotationMatrix(),
  };
  for (int k = 0; k < 6; ++k) rotations.push_back(test::randomRotation(random));
  std::uniform_real_distribution<double> shift(-2.0, 2.0);
  for (const Eigen::Matrix3d& q : rotations) {
    const Eigen::Vector3d t(shift(random), shift(random), shift(random));
    const Eigen::VectorXd u = test::rigidDisplacement(mesh, q, t);
    // R^T x - X cancels positions of size |x| ~ 3 to rounding (1e-16 |x| / h ~ 1e-15
    // strain), so forces are ~1e-15 E h^2; 1e-9 of the unit-strain force is far above
    // that and far below the force of any real strain.
    EXPECT_LE(forces(model, u).cwiseAbs().maxCoeff(), 1e-9 * forceScale(cells));
    // Energy is quadratic in that rounding; compared with E V at unit strain.
    EXPECT_LE(std::abs(model.elasticEnergy(u)), 1e-9 * test::kYoungsModulus * 0.48);
    for (const Eigen::Matrix3d& r : model.rotations()) EXPECT_LE((r - q).norm(), 1e-12);
  }
}

TEST(CorotationalLinearFEM, TinyDisplacementsGiveLinearForces) {
  const TetMesh mesh = test::smallBox(2);
  CorotationalLinearFEM model(mesh);
  const MatrixAssembler assembler(mesh);
  const SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  std::mt19937 random(2);
  std::uniform_real_distribution<double> offset(-1e-7, 1e-7);
  Eigen::VectorXd u(mesh.numDofs());
  for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = offset(random);
  const Eigen::VectorXd linear = k * u;
  // R = I + O(|grad u|) = I + O(1e-7): the corotated forces differ from K u by a relative
  // O(1e-7), plus rounding 1e-16 / 1e-7 from R^T x - X; 1e-5 bounds both with margin.
  EXPECT_LE((forces(model, u) - linear).norm(), 1e-5 * linear.norm());
}

TEST(CorotationalLinearFEM, ExactTangentMatchesFiniteDifferencesAndSimpleDoesNot) {
  const int cells = 2;
  const TetMesh mesh = test::smallBox(cells);
  CorotationalLinearFEM model(mesh, TangentKind::exact);
  std::mt19937 random(3);
  // 60 degrees about a random axis, strains of about 0.1.
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.8, 0.5).normalized();
  const Eigen::Matrix3d q = Eigen::AngleAxisd(M_PI / 3, axis).toRotationMatrix();
  const Eigen::VectorXd u =
      test::deformedDisplacement(mesh, q, Eigen::Vector3d(0.1, 0.2, -0.3), 0.05 * test::cellSize(cells), random);

  // Step 1e-6 h: truncation ~ (1e-6)^2 relative, rounding ~ 1e-16 |f| / (1e-6 h |K|)
  // ~ 1e-10 relative; 1e-5 of the largest entry leaves a wide margin.
  const double step = 1e-6 * test::cellSize(cells);
  const Eigen::MatrixXd reference = finiteDifferenceTangent(model, u, step);
  const double scale = reference.cwiseAbs().maxCoeff();
  const double tolerance = 1e-5;
  const Eigen::MatrixXd exact = tangent(model, u);
  EXPECT_LE((exact - reference).cwiseAbs().maxCoeff(), tolerance * scale);
  EXPECT_LE((exact - exact.transpose()).cwiseAbs().maxCoeff(), 1e-14 * scale);

  // The simple tangent R K R^T misses the dR/dx terms, which are of the size of the
  // stress (strain 0.1 times K): it must miss the reference by far more than the test
  // tolerance, or the comparison above could not detect a missing term.
  model.setTangentKind(TangentKind::simple);
  const Eigen::MatrixXd simple = tangent(model, u);
  EXPECT_GT((simple - reference).cwiseAbs().maxCoeff(), 100.0 * tolerance * scale);
}

TEST(CorotationalLinearFEM, ElementTangentsSumToTheAssembledTangent) {
  // The per-element tangent (used by the asynchronous integrator's fast regions) is
  // computed by its own code path; scattered and summed over the elements it must equal the
  // assembled tangent for both kinds, on a rotated mesh where R K R^T differs from K.
  const TetMesh mesh = test::smallBox(2);
  std::mt19937 random(11);
  const Eigen::VectorXd u =
      test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d(0.1, -0.2, 0.3), 0.02, random);
  for (const TangentKind kind : {TangentKind::simple, TangentKind::exact}) {
    SCOPED_TRACE(kind == TangentKind::simple ? "simple" : "exact");
    CorotationalLinearFEM model(mesh, kind);
    Eigen::MatrixXd summed = Eigen::MatrixXd::Zero(mesh.numDofs(), mesh.numDofs());
    ElementMatrix element;
    for (int e = 0; e < mesh.numElements(); ++e) {
      ASSERT_TRUE(model.elementTangent(u, e, element));
      const Eigen::Vector4i vertices = mesh.element(e);
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) {
          summed.block<3, 3>(3 * vertices[a], 3 * vertices[b]) += element.block<3, 3>(3 * a, 3 * b);
        }
      }
    }
    const Eigen::MatrixXd assembled = tangent(model, u);
    // Same products summed in another order: round-off of the largest entry.
    EXPECT_LE((summed - assembled).cwiseAbs().maxCoeff(), 1e-12 * assembled.cwiseAbs().maxCoeff());
  }
}

TEST(CorotationalLinearFEM, ExactTangentOfInvertedElementsMatchesFiniteDifferences) {
  // Large random displacements (half a cell) invert some elements; away from the
  // clamped singular set the exact tangent is still the derivative.
  const int cells = 2;
  const TetMesh mesh = test::smallBox(cells);
  CorotationalLinearFEM model(mesh, TangentKind::exact);
  std::mt19937 random(13);
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d::Zero(),
                                                       0.5 * test::cellSize(cells), random);
  int inverted = 0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    Eigen::Matrix<double, 3, 4> x = mesh.elementRestPositions(e);
    for (int a = 0; a < 4; ++a) x.col(a) += u.segment<3>(3 * mesh.element(e)[a]);
    const double volume = (x.col(1) - x.col(0)).cross(x.col(2) - x.col(0)).dot(x.col(3) - x.col(0));
    inverted += volume < 0.0 ? 1 : 0;
  }
  ASSERT_GT(inverted, 0);
  // Same step and tolerance as above; strains of order 1 make the third derivative
  // larger, still far inside 1e-5 with a step of 1e-6 h.
  const Eigen::MatrixXd reference = finiteDifferenceTangent(model, u, 1e-6 * test::cellSize(cells));
  const double scale = reference.cwiseAbs().maxCoeff();
  EXPECT_LE((tangent(model, u) - reference).cwiseAbs().maxCoeff(), 1e-5 * scale);
}

TEST(CorotationalLinearFEM, ForcesAreTheEnergyGradient) {
  const int cells = 2;
  const TetMesh mesh = test::smallBox(cells);
  CorotationalLinearFEM model(mesh);
  std::mt19937 random(4);
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d(1, 0, 0),
                                                       0.1 * test::cellSize(cells), random);
  const Eigen::VectorXd f = forces(model, u);
  // Step 1e-5 h: truncation (1e-5)^2 = 1e-10 relative; rounding eps E / (1e-5 h) with
  // E ~ E_young V strain^2 gives ~1e-10 of |f|; 1e-6 is the requested bound, with margin.
  const double step = 1e-5 * test::cellSize(cells);
  Eigen::VectorXd gradient(u.size());
  for (Eigen::Index j = 0; j < u.size(); ++j) {
    Eigen::VectorXd plus = u;
    Eigen::VectorXd minus = u;
    plus[j] += step;
    minus[j] -= step;
    gradient[j] = (model.elasticEnergy(plus) - model.elasticEnergy(minus)) / (2.0 * step);
  }
  EXPECT_LE(test::maxAbsDifference(gradient, f), 1e-6 * f.cwiseAbs().maxCoeff());
}

// One tetrahedron with vertex 3 at height `height` above the face (0, 1, 2) (rest: 1).
TetMesh singleTet() {
  Eigen::Matrix3Xd x(3, 4);
  x << 0.0, 1.0, 0.0, 0.2, 0.0, 0.0, 1.0, 0.3, 0.0, 0.0, 0.0, 1.0;
  Eigen::Matrix4Xi elements(4, 1);
  elements << 0, 1, 2, 3;
  return TetMesh(x, elements, {Material{"m", 1000.0, test::kYoungsModulus, 0.3}}, {0});
}

TEST(CorotationalLinearFEM, FlatAndInvertedElementsGiveFiniteRestoringForces) {
  const TetMesh mesh = singleTet();
  for (const TangentKind kind : {TangentKind::simple, TangentKind::exact}) {
    CorotationalLinearFEM model(mesh, kind);
    for (const double height : {1e-8, 0.0, -1e-8, -0.5, -2.0}) {
      Eigen::VectorXd u = Eigen::VectorXd::Zero(12);
      u[11] = height - 1.0;  // vertex 3's z
      Eigen::VectorXd f;
      SparseMatrix k = model.createStiffnessMatrix();
      model.forcesAndTangent(u, f, k);
      EXPECT_TRUE(f.allFinite()) << "height " << height;
      EXPECT_TRUE(Eigen::MatrixXd(k).allFinite()) << "height " << height;
      const Eigen::Matrix3d& r = model.rotations()[0];
      // R comes from an orthogonal SVD: det and orthogonality hold to rounding.
      EXPECT_NEAR(r.determinant(), 1.0, 1e-12) << "height " << height;
      EXPECT_LE((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-12);
      // f_int opposes the deformation: pushing vertex 3 down (towards and through the
      // opposite face) meets a force whose reaction -f_int pushes it back up.
      if (height < 0.5) {
        EXPECT_LT(f[11], 0.0) << "height " << height;
      }
      EXPECT_TRUE(std::isfinite(model.elasticEnergy(u)));
    }
  }
}

TEST(CorotationalLinearFEM, InternalForcesHaveNoNetForceOrTorque) {
  const int cells = 2;
  const TetMesh mesh = test::smallBox(cells);
  CorotationalLinearFEM model(mesh);
  std::mt19937 random(6);
  for (const double amplitude : {0.01, 0.2, 0.8}) {  // up to heavily inverted
    const Eigen::VectorXd u = test::deformedDisplacement(
        mesh, test::randomRotation(random), Eigen::Vector3d(0.5, -1, 2), amplitude * test::cellSize(cells), random);
    const Eigen::VectorXd f = forces(model, u);
    Eigen::Vector3d netForce = Eigen::Vector3d::Zero();
    Eigen::Vector3d netTorque = Eigen::Vector3d::Zero();
    double forceSum = 0.0;
    double torqueSum = 0.0;
    for (int v = 0; v < mesh.numVertices(); ++v) {
      const Eigen::Vector3d x = mesh.restPosition(v) + u.segment<3>(3 * v);
      const Eigen::Vector3d fv = f.segment<3>(3 * v);
      netForce += fv;
      netTorque += x.cross(fv);
      forceSum += fv.norm();
      torqueSum += x.norm() * fv.norm();
    }
    // Each sum cancels terms bounded by forceSum (torqueSum); exact cancellation in
    // theory, so only rounding (~1e-15 of the sums, times a few elements) remains.
    EXPECT_LE(netForce.norm(), 1e-10 * forceSum) << "amplitude " << amplitude;
    EXPECT_LE(netTorque.norm(), 1e-10 * torqueSum) << "amplitude " << amplitude;
  }
}

TEST(CorotationalLinearFEM, ResultsAreBitIdenticalForOneAndTwoThreads) {
  ThreadCountGuard guard;
  const int cells = 6;
  const TetMesh mesh = test::smallBox(cells);
  std::mt19937 random(8);
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d::Zero(),
                                                       0.1 * test::cellSize(cells), random);
  for (const TangentKind kind : {TangentKind::simple, TangentKind::exact}) {
    std::vector<Eigen::VectorXd> f(2);
    std::vector<SparseMatrix> k(2);
    std::vector<double> energy(2);
    for (int threads = 1; threads <= 2; ++threads) {
      omp_set_num_threads(threads);
      CorotationalLinearFEM model(mesh, kind);
      const auto i = static_cast<std::size_t>(threads - 1);
      k[i] = model.createStiffnessMatrix();
      model.forcesAndTangent(u, f[i], k[i]);
      energy[i] = model.elasticEnergy(u);
    }
    EXPECT_TRUE(bitIdentical(f[0], f[1]));
    EXPECT_TRUE(bitIdentical(k[0], k[1]));
    EXPECT_EQ(std::memcmp(&energy[0], &energy[1], sizeof(double)), 0);
  }
}

TEST(CorotationalLinearFEM, ForcesAndTangentEqualsSeparateCalls) {
  const TetMesh mesh = test::smallBox(3);
  std::mt19937 random(9);
  const Eigen::VectorXd u =
      test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d::Zero(), 0.02, random);
  for (const TangentKind kind : {TangentKind::simple, TangentKind::exact}) {
    CorotationalLinearFEM model(mesh, kind);
    Eigen::VectorXd fTogether;
    SparseMatrix kTogether;  // empty: replaced by the assembler's pattern
    model.forcesAndTangent(u, fTogether, kTogether);
    const std::vector<Eigen::Matrix3d> rotationsTogether = model.rotations();
    Eigen::VectorXd fAlone;
    model.internalForces(u, fAlone);
    SparseMatrix kAlone = model.createStiffnessMatrix();
    model.tangentStiffness(u, kAlone);
    EXPECT_TRUE(bitIdentical(fTogether, fAlone));
    EXPECT_TRUE(bitIdentical(kTogether, kAlone));
    ASSERT_EQ(rotationsTogether.size(), static_cast<std::size_t>(mesh.numElements()));
    for (std::size_t e = 0; e < rotationsTogether.size(); ++e) EXPECT_EQ(rotationsTogether[e], model.rotations()[e]);
  }
}

TEST(CorotationalLinearFEM, AtRestTheTangentIsTheLinearStiffness) {
  const TetMesh mesh = test::smallBox(2);
  const auto assembler = std::make_shared<const MatrixAssembler>(mesh);
  const SparseMatrix linear = linearStiffnessMatrix(mesh, *assembler);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.numDofs());
  for (const TangentKind kind : {TangentKind::simple, TangentKind::exact}) {
    CorotationalLinearFEM model(mesh, assembler, kind);
    EXPECT_FALSE(model.isLinear());
    EXPECT_EQ(model.numDofs(), mesh.numDofs());
    SparseMatrix k = model.createStiffnessMatrix();
    model.tangentStiffness(zero, k);
    // Same pattern (shared assembler), values equal up to R = I rounding.
    ASSERT_EQ(k.nonZeros(), linear.nonZeros());
    const Eigen::Map<const Eigen::VectorXd> values(k.valuePtr(), k.nonZeros());
    const Eigen::Map<const Eigen::VectorXd> linearValues(linear.valuePtr(), linear.nonZeros());
    EXPECT_LE((values - linearValues).cwiseAbs().maxCoeff(), 1e-12 * linearValues.cwiseAbs().maxCoeff());
    for (const Eigen::Matrix3d& r : model.rotations()) EXPECT_EQ(r, Eigen::Matrix3d::Identity());
  }
}

TEST(CorotationalLinearFEM, RotationsAreIdentitiesBeforeTheFirstEvaluation) {
  const TetMesh mesh = test::smallBox(1);
  const CorotationalLinearFEM model(mesh);
  ASSERT_EQ(model.rotations().size(), static_cast<std::size_t>(mesh.numElements()));
  for (const Eigen::Matrix3d& r : model.rotations()) EXPECT_EQ(r, Eigen::Matrix3d::Identity());
}

TEST(CorotationalLinearFEM, WrongDisplacementSizeIsRejected) {
  const TetMesh mesh = test::smallBox(1);
  CorotationalLinearFEM model(mesh);
  Eigen::VectorXd f;
  try {
    model.internalForces(Eigen::VectorXd::Zero(5), f);
    FAIL() << "no exception";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("displacement has size 5, expected " + std::to_string(mesh.numDofs())),
              std::string::npos)
        << error.what();
  }
  EXPECT_THROW(model.elasticEnergy(Eigen::VectorXd::Zero(5)), Error);
}

TEST(CorotationalLinearFEM, DegenerateElementIsRejectedByName) {
  Eigen::Matrix3Xd x(3, 5);
  x << 0, 1, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 0, 1, 0;  // vertex 4 lies in the plane z = 0
  Eigen::Matrix4Xi elements(4, 2);
  elements << 0, 0, 1, 1, 2, 2, 3, 4;
  const TetMesh mesh(x, elements, {Material{}}, {0, 0});
  try {
    const CorotationalLinearFEM model(mesh);
    FAIL() << "no exception";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("element 1 is degenerate"), std::string::npos) << error.what();
  }
}

TEST(CorotationalLinearFEM, AssemblerOfAnotherMeshIsRejected) {
  const auto assembler = std::make_shared<const MatrixAssembler>(test::smallBox(1));
  EXPECT_THROW(CorotationalLinearFEM(test::smallBox(2), assembler), Error);
  EXPECT_THROW(CorotationalLinearFEM(test::smallBox(1), nullptr), Error);
}

}  // namespace
}  // namespace asyncfem
