// SPDX-License-Identifier: BSD-3-Clause
// Isosurface stuffing on analytic solids: validity, the dihedral-angle range, volume and
// the boundary (closed, outward by the divergence theorem).
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <numbers>
#include <string>

namespace asyncfem {
namespace {

using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;

// Labelle & Shewchuk prove dihedral angles in [10.78, 164.74] degrees for their stencils
// and alphas, which stuffIsosurface implements; the printed bound is rounded to 0.01.
constexpr double kMinDihedral = 10.78 - 0.01;
constexpr double kMaxDihedral = 164.74 + 0.01;

struct Case {
  std::string name;
  ImplicitFunction f;
  Eigen::AlignedBox3d bounds;
  double spacing;
  double exactVolume;
  double volumeTolerance;  // relative; from the chord error of a surface sampled every ~h
};

void expectGoodMesh(const Case& c) {
  SCOPED_TRACE(c.name);
  StuffingReport report;
  const TetMesh mesh = stuffIsosurface(c.f, c.bounds, c.spacing, {}, &report);
  ASSERT_GT(mesh.numElements(), 100);
  EXPECT_EQ(report.elements, mesh.numElements());
  EXPECT_EQ(report.unwarpedVertices, 0) << "smooth, well-resolved solids need no pinch repair";

  const MeshCheckReport check = checkTetMesh(mesh);
  EXPECT_TRUE(check.ok()) << check.firstProblem;
  EXPECT_EQ(check.invertedElements, 0);
  EXPECT_EQ(check.degenerateElements, 0);
  EXPECT_EQ(check.unusedVertices, 0);
  EXPECT_EQ(check.openBoundaryEdges, 0);
  EXPECT_EQ(check.nonManifoldBoundaryEdges, 0);
  EXPECT_EQ(check.misorientedBoundaryEdges, 0);
  EXPECT_EQ(check.components, 1);
  for (int e = 0; e < mesh.numElements(); ++e) ASSERT_GT(signedElementVolume(mesh, e), 0.0) << "element " << e;

  // Divergence theorem: the outward boundary encloses exactly the element volume (to
  // round-off, 1e-9 relative), and it is positive only if the normals point outward.
  const double volume = totalVolume(mesh);
  EXPECT_NEAR(check.boundaryVolume, volume, 1e-9 * volume);
  EXPECT_GT(check.boundaryVolume, 0.0);
  EXPECT_NEAR(volume, c.exactVolume, c.volumeTolerance * c.exactVolume);

  const MeshQuality quality = meshQuality(mesh);
  EXPECT_GE(quality.minDihedralDegrees, kMinDihedral);
  EXPECT_LE(quality.maxDihedralDegrees, kMaxDihedral);

  // Every boundary vertex lies on the surface (warped vertices and cut points are roots of
  // f, found to ~1e-12 h).
  for (const auto& t : boundaryTriangles(mesh))
    for (int v : t) ASSERT_NEAR(c.f(mesh.restPosition(v)), 0.0, 1e-9 * c.spacing);
}

TEST(StuffIsosurface, SphereIsValidWithBoundedAnglesAndVolume) {
  for (double spacing : {0.1, 0.137, 0.2}) {
    expectGoodMesh({"sphere h=" + std::to_string(spacing), implicitSphere(Vector3d(0.03, -0.02, 0.05), 1.0),
                    Eigen::AlignedBox3d(Vector3d::Constant(-1.1), Vector3d::Constant(1.1)), spacing, 4.0 / 3.0 * kPi,
                    0.02});
  }
}

TEST(StuffIsosurface, TorusIsValidWithBoundedAnglesAndVolume) {
  const double major = 1.0, minor = 0.4;
  expectGoodMesh({"torus", implicitTorus(Vector3d(0.01, 0.02, -0.03), Vector3d(0.2, 0.1, 1.0), major, minor),
                  Eigen::AlignedBox3d(Vector3d::Constant(-1.5), Vector3d::Constant(1.5)), 0.08,
                  2.0 * kPi * kPi * major * minor * minor, 0.02});
}

TEST(StuffIsosurface, CapsuleIsValidWithBoundedAnglesAndVolume) {
  const double radius = 0.4, length = 1.2;
  expectGoodMesh({"capsule", implicitCapsule(Vector3d(-0.6, 0.0, 0.0), Vector3d(0.6, 0.0, 0.0), radius),
                  Eigen::AlignedBox3d(Vector3d(-1.1, -0.5, -0.5), Vector3d(1.1, 0.5, 0.5)), 0.07,
                  kPi * radius * radius * length + 4.0 / 3.0 * kPi * radius * radius * radius, 0.02});
}

TEST(StuffIsosurface, VolumeConvergesWithSpacing) {
  // The boundary is a polyhedron inscribed in the surface, so the volume error shrinks
  // roughly like h^2: halving h should cut it by well over half.
  const ImplicitFunction sphere = implicitSphere(Vector3d::Zero(), 1.0);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.0), Vector3d::Constant(1.0));
  const double exact = 4.0 / 3.0 * kPi;
  const double coarse = std::abs(totalVolume(stuffIsosurface(sphere, box, 0.2)) - exact);
  const double fine = std::abs(totalVolume(stuffIsosurface(sphere, box, 0.1)) - exact);
  EXPECT_LT(fine, 0.5 * coarse);
}

TEST(StuffIsosurface, IsDeterministic) {
  const ImplicitFunction f = implicitTorus(Vector3d::Zero(), Vector3d::UnitY(), 1.0, 0.35);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.4), Vector3d::Constant(1.4));
  MesherOptions serial;
  serial.parallel = false;
  const TetMesh a = stuffIsosurface(f, box, 0.1);
  const TetMesh b = stuffIsosurface(f, box, 0.1, serial);
  EXPECT_EQ(a.elements(), b.elements());
  EXPECT_EQ(a.restPositions(), b.restPositions());
}

TEST(StuffIsosurface, ThinGapsKeepTheAngleBoundAndAClosedBoundary) {
  // Two spheres almost touching: the gap between them is far below the lattice spacing, so
  // the boundary may be pinched along lattice edges there (a valid mesh: closed, outward),
  // and the angle bound still holds.
  const ImplicitFunction f =
      implicitUnion({implicitSphere(Vector3d(-0.5, 0.0, 0.0), 0.49), implicitSphere(Vector3d(0.5, 0.01, 0.0), 0.49)});
  const Eigen::AlignedBox3d box(Vector3d(-1.0, -0.5, -0.5), Vector3d(1.0, 0.5, 0.5));
  for (double spacing : {0.09, 0.11, 0.13}) {
    StuffingReport report;
    const TetMesh mesh = stuffIsosurface(f, box, spacing, {}, &report);  // throws if a check fails
    const MeshCheckReport check = checkTetMesh(mesh);
    EXPECT_TRUE(check.ok()) << check.firstProblem;
    EXPECT_EQ(check.pinchedBoundaryEdges, report.pinchedBoundaryEdges);
    EXPECT_GE(report.minDihedralDegrees, kMinDihedral);
    EXPECT_LE(report.maxDihedralDegrees, kMaxDihedral);
  }
}

TEST(StuffIsosurface, PinchRepairIsStillAvailable) {
  // The old behaviour on request: warps undone next to pinched edges, a manifold boundary,
  // no angle guarantee there (so the angle check is not enforced).
  const ImplicitFunction f =
      implicitUnion({implicitSphere(Vector3d(-0.5, 0.0, 0.0), 0.49), implicitSphere(Vector3d(0.5, 0.01, 0.0), 0.49)});
  const Eigen::AlignedBox3d box(Vector3d(-1.0, -0.5, -0.5), Vector3d(1.0, 0.5, 0.5));
  MesherOptions repair;
  repair.repairPinches = true;
  StuffingReport report;
  const TetMesh mesh = stuffIsosurface(f, box, 0.11, repair, &report);
  EXPECT_EQ(checkTetMesh(mesh).pinchedBoundaryEdges, 0);
  EXPECT_TRUE(checkTetMesh(mesh).ok());
}

TEST(StuffIsosurface, BadInputIsAnError) {
  const ImplicitFunction sphere = implicitSphere(Vector3d::Zero(), 1.0);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.0), Vector3d::Constant(1.0));
  try {
    stuffIsosurface(sphere, box, 0.0);
    FAIL() << "spacing 0 accepted";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("spacing"), std::string::npos) << e.what();
  }
  try {
    stuffIsosurface(implicitSphere(Vector3d::Constant(10.0), 1.0), box, 0.2);
    FAIL() << "empty solid accepted";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("no element"), std::string::npos) << e.what();
  }
  MesherOptions small;
  small.maxLatticeVertices = 1000;
  try {
    stuffIsosurface(sphere, box, 0.01, small);
    FAIL() << "oversized lattice accepted";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("larger spacing"), std::string::npos) << e.what();
  }
  const ImplicitFunction nan = [](const Vector3d&) { return std::nan(""); };
  EXPECT_THROW(stuffIsosurface(nan, box, 0.2), ValidationError);
}

TEST(StuffIsosurface, AMeshBelowTheAngleLimitIsNeverReturned) {
  // Without warping (alphas 0) marching-tetrahedra slivers appear next to the surface; the
  // mesher must refuse the mesh, naming the element and where it is.
  MesherOptions noWarp;
  noWarp.alphaLong = 0.0;
  noWarp.alphaShort = 0.0;
  const ImplicitFunction sphere = implicitSphere(Vector3d(0.013, -0.021, 0.017), 1.0);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.0), Vector3d::Constant(1.0));
  try {
    stuffIsosurface(sphere, box, 0.1, noWarp);
    FAIL() << "a mesh with slivers was returned";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("dihedral angle"), std::string::npos) << message;
    EXPECT_NE(message.find("near ("), std::string::npos) << message;
  }
  noWarp.minDihedralDegrees = 0.0;  // measured, not enforced: then it is returned
  EXPECT_LT(meshQuality(stuffIsosurface(sphere, box, 0.1, noWarp)).minDihedralDegrees, 10.0);
}

TEST(MeshChecks, DetectInvertedElementsAndOpenBoundaries) {
  // One tetrahedron stored with negative orientation.
  Eigen::Matrix3Xd x(3, 4);
  x << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  Eigen::Matrix4Xi inverted(4, 1);
  inverted << 0, 2, 1, 3;
  const MeshCheckReport report = checkTetMesh(TetMesh(x, inverted, {Material{}}, {0}));
  EXPECT_EQ(report.invertedElements, 1);
  EXPECT_FALSE(report.ok());
  EXPECT_NE(report.firstProblem.find("inverted"), std::string::npos) << report.firstProblem;

  // A flat (degenerate) element.
  Eigen::Matrix3Xd flat = x;
  flat(2, 3) = 0.0;
  flat(0, 3) = 0.3;
  flat(1, 3) = 0.3;
  Eigen::Matrix4Xi one(4, 1);
  one << 0, 1, 2, 3;
  EXPECT_EQ(checkTetMesh(TetMesh(flat, one, {Material{}}, {0})).degenerateElements, 1);
  EXPECT_THROW(validateTetMesh(TetMesh(flat, one, {Material{}}, {0}), "test"), ValidationError);

  // An unused vertex.
  Eigen::Matrix3Xd extra(3, 5);
  extra << x, Eigen::Vector3d(5, 5, 5);
  EXPECT_EQ(checkTetMesh(TetMesh(extra, one, {Material{}}, {0})).unusedVertices, 1);

  // Two tetrahedra sharing only an edge: a pinched boundary edge (four boundary triangles,
  // two each way), which is a valid mesh of two solids touching along an edge.
  Eigen::Matrix3Xd bowtie(3, 6);
  bowtie << 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 0, 0, 0, 0, 1, 0, -1;
  Eigen::Matrix4Xi two(4, 2);
  two << 0, 0, 1, 1, 2, 5, 3, 4;
  TetMesh pair(bowtie, two, {Material{}}, {0, 0});
  for (int e = 0; e < 2; ++e)
    if (signedElementVolume(pair, e) < 0) {
      Eigen::Vector4i t = pair.element(e);
      std::swap(t[2], t[3]);
      pair.setElement(e, t);
    }
  const MeshCheckReport edgeReport = checkTetMesh(pair);
  EXPECT_EQ(edgeReport.pinchedBoundaryEdges, 1);
  EXPECT_EQ(edgeReport.nonManifoldBoundaryEdges, 0);
  EXPECT_TRUE(edgeReport.ok()) << edgeReport.firstProblem;
  EXPECT_EQ(edgeReport.components, 2);
}

TEST(ImplicitPrimitives, SignsAndDistances) {
  EXPECT_NEAR(implicitSphere(Vector3d::Zero(), 1.0)(Vector3d(2, 0, 0)), 1.0, 1e-15);
  EXPECT_NEAR(implicitCapsule(Vector3d::Zero(), Vector3d::UnitX(), 0.5)(Vector3d(0.5, 0.0, 0.0)), -0.5, 1e-15);
  EXPECT_NEAR(implicitBox(Vector3d::Zero(), Vector3d::Ones(), 0.0)(Vector3d(0.0, 0.0, 3.0)), 2.0, 1e-15);
  EXPECT_NEAR(implicitBox(Vector3d::Zero(), Vector3d::Ones(), 0.0)(Vector3d(0.5, 0.0, 0.0)), -0.5, 1e-15);
  EXPECT_NEAR(implicitTorus(Vector3d::Zero(), Vector3d::UnitZ(), 1.0, 0.25)(Vector3d(1.0, 0.0, 0.0)), -0.25, 1e-15);
  EXPECT_NEAR(implicitEllipsoid(Vector3d::Zero(), Vector3d(2, 1, 1))(Vector3d(2, 0, 0)), 0.0, 1e-15);
  EXPECT_NEAR(implicitTaperedCapsule(Vector3d::Zero(), Vector3d::UnitX(), 0.4, 0.2)(Vector3d(1.0, 0.2, 0.0)), 0.0,
              1e-15);
  const ImplicitFunction smooth =
      implicitSmoothUnion({implicitSphere(Vector3d(-1, 0, 0), 1.0), implicitSphere(Vector3d(1, 0, 0), 1.0)}, 0.2);
  EXPECT_LT(smooth(Vector3d::Zero()), -0.04);  // blended below the sharp union's 0
  EXPECT_GT(implicitDifference(implicitSphere(Vector3d::Zero(), 1.0),
                               implicitSphere(Vector3d::Zero(), 0.5))(Vector3d::Zero()),
            0.0);
  EXPECT_THROW(implicitSphere(Vector3d::Zero(), -1.0), ValidationError);
  EXPECT_THROW(implicitBox(Vector3d::Zero(), Vector3d::Ones(), 1.0), ValidationError);
}

}  // namespace
}  // namespace asyncfem
