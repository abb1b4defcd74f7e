// SPDX-License-Identifier: BSD-3-Clause
// The graded lattice (MesherOptions::gradingLevels): near the surface the mesh must be the
// uniform lattice's mesh exactly (same boundary, same enclosed volume), the interior coarser
// (fewer elements), the angle bound must hold, and functions that are not distances (so
// that the first refinement misses the surface) must still end in the same mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "surfaces.hpp"

namespace asyncfem {
namespace {

using Eigen::Vector3d;

// The stencils' bound (Labelle & Shewchuk 2007), printed rounded to 0.01 degree.
constexpr double kBoundMin = 10.78 - 0.01;
constexpr double kBoundMax = 164.74 + 0.01;

TetMesh mesh(const ImplicitFunction& f, const Eigen::AlignedBox3d& box, double spacing, int levels,
             StuffingReport* report = nullptr) {
  MesherOptions options;
  options.gradingLevels = levels;
  options.minDihedralDegrees = 0.0;  // asserted below instead
  return stuffIsosurface(f, box, spacing, options, report);
}

std::vector<Vector3d> boundaryVertexPositions(const TetMesh& m) {
  std::vector<int> ids;
  for (const auto& t : boundaryTriangles(m)) ids.insert(ids.end(), t.begin(), t.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<Vector3d> positions;
  for (int v : ids) positions.push_back(m.restPosition(v));
  std::sort(positions.begin(), positions.end(), [](const Vector3d& a, const Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  return positions;
}

/// The graded mesh of f has the uniform mesh's boundary: the same number of boundary
/// triangles, the same boundary vertices, and the same enclosed volume. Lattice positions
/// are computed from different origins (the same points up to rounding), so positions are
/// compared to 1e-9 spacings and volumes to 1e-9 relative.
void expectSameBoundary(const TetMesh& graded, const TetMesh& uniform, double spacing) {
  EXPECT_EQ(boundaryTriangles(graded).size(), boundaryTriangles(uniform).size());
  const std::vector<Vector3d> a = boundaryVertexPositions(graded), b = boundaryVertexPositions(uniform);
  ASSERT_EQ(a.size(), b.size());
  // Both sorted by x first: the candidates for p are the run of b within the tolerance in x.
  const double tolerance = 1e-9 * spacing;
  int unmatched = 0;
  for (const Vector3d& p : a) {
    auto it =
        std::lower_bound(b.begin(), b.end(), p.x() - tolerance, [](const Vector3d& q, double x) { return q.x() < x; });
    bool found = false;
    for (; it != b.end() && it->x() <= p.x() + tolerance && !found; ++it) found = (p - *it).norm() < tolerance;
    if (!found) ++unmatched;
  }
  EXPECT_EQ(unmatched, 0) << "of " << a.size() << " boundary vertices";
  EXPECT_NEAR(totalVolume(graded), totalVolume(uniform), 1e-9 * totalVolume(uniform));
}

void expectValidAndBounded(const TetMesh& m) {
  const MeshQuality quality = meshQuality(m);
  EXPECT_GE(quality.minDihedralDegrees, kBoundMin);
  EXPECT_LE(quality.maxDihedralDegrees, kBoundMax);
  const MeshCheckReport check = checkTetMesh(m);
  EXPECT_TRUE(check.ok()) << check.firstProblem;  // closed, outward, none inverted or degenerate
}

TEST(GradedLattice, SphereKeepsTheUniformBoundaryWithFewerElements) {
  const ImplicitFunction sphere = implicitSphere(Vector3d(0.013, -0.021, 0.007), 1.0);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.1), Vector3d::Constant(1.1));
  const double spacing = 0.05;
  const TetMesh uniform = mesh(sphere, box, spacing, 0);
  for (int levels : {1, 4}) {
    SCOPED_TRACE("levels " + std::to_string(levels));
    StuffingReport report;
    const TetMesh graded = mesh(sphere, box, spacing, levels, &report);
    expectValidAndBounded(graded);
    expectSameBoundary(graded, uniform, spacing);
    EXPECT_LT(graded.numElements(), uniform.numElements());
    EXPECT_EQ(report.gradingLevels, levels);
    EXPECT_GT(report.latticeCells, 0);
    EXPECT_EQ(report.refinementRounds, 0);  // a distance: the first refinement suffices
  }
  // A radius of 20 spacings: with cubes up to 16 spacings inside, well under half the
  // uniform count (the shell within a few spacings of the surface stays fine).
  EXPECT_LT(mesh(sphere, box, spacing, 4).numElements(), uniform.numElements() / 2);
}

TEST(GradedLattice, InteriorElementsGrowAwayFromTheSurface) {
  const ImplicitFunction sphere = implicitSphere(Vector3d::Zero(), 1.0);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.1), Vector3d::Constant(1.1));
  const double spacing = 0.05;
  const TetMesh graded = mesh(sphere, box, spacing, 3);
  const Eigen::VectorXd volumes = elementVolumes(graded);
  double largestNearSurface = 0.0, largestInside = 0.0;
  for (int e = 0; e < graded.numElements(); ++e) {
    const double volume = std::abs(volumes[e]);
    const double depth = 1.0 - graded.elementRestPositions(e).rowwise().mean().norm();
    if (depth < spacing) largestNearSurface = std::max(largestNearSurface, volume);
    if (depth > 0.5) largestInside = std::max(largestInside, volume);
  }
  // A finest BCC tetrahedron has volume h^3 / 12. Near the surface elements come from
  // finest ones (warping moves a vertex by at most 0.36 h, which can enlarge one, but not to
  // the 8 h^3 / 12 of a tetrahedron of the next level). Cubes of 2^3 h inside hold
  // tetrahedra of up to (8h)^3 / 12, and at least of (4h)^3 / 12 deep inside a radius of 20 h.
  const double finest = std::pow(spacing, 3) / 12.0;
  EXPECT_LT(largestNearSurface, 8.0 * finest);
  EXPECT_GE(largestInside, 64.0 * finest * (1.0 - 1e-9));
  EXPECT_LE(largestInside, 512.0 * finest * (1.0 + 1e-9));
}

TEST(GradedLattice, ANonDistanceFunctionIsRefinedWhereItChangesSignInACoarseCube) {
  // 40 times a distance: the first refinement, which assumes |f| is at most the distance,
  // leaves coarse cubes at the surface; the check on the coarse tetrahedra must find those
  // whose vertices differ in sign and refine them, so that the mesh is valid and bounded.
  // (Where the surface crosses a coarse cube without a sign change at its vertices, such an
  // f can lose detail there, as MesherOptions::gradingLevels says; the volume must still be
  // close to the uniform mesh's.)
  const ImplicitFunction steep = [](const Vector3d& x) {
    return 40.0 * ((x - Vector3d(0.3, 0.0, 0.0)).norm() - 0.5) * (1.0 + 0.5 * std::sin(7.0 * x.y()));
  };
  const Eigen::AlignedBox3d box(Vector3d(-0.3, -0.6, -0.6), Vector3d(0.9, 0.6, 0.6));
  const double spacing = 0.04;
  StuffingReport report;
  const TetMesh graded = mesh(steep, box, spacing, 3, &report);
  EXPECT_GT(report.refinementRounds, 0);
  expectValidAndBounded(graded);
  const double uniformVolume = totalVolume(mesh(steep, box, spacing, 0));
  EXPECT_NEAR(totalVolume(graded), uniformVolume, 0.01 * uniformVolume);
}

TEST(GradedLattice, NoiseFieldsAndUnionsKeepTheBound) {
  // Sign changes at every scale down to the spacing, and smooth unions of primitives: the
  // graded mesh has the uniform boundary and the stencils' angle bound on every input.
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.2), Vector3d::Constant(1.2));
  for (int shape = 0; shape < 8; ++shape) {
    SCOPED_TRACE("shape " + std::to_string(shape));
    std::vector<ImplicitFunction> parts;
    for (int i = 0; i <= shape % 3; ++i) {
      const Vector3d c = Vector3d(unit(random), unit(random), unit(random)) - Vector3d::Constant(0.5);
      parts.push_back(shape % 2 == 0 ? implicitSphere(c, 0.2 + 0.4 * unit(random))
                                     : implicitTorus(c, Vector3d(unit(random), 1.0, 0.3).normalized(),
                                                     0.4 + 0.1 * unit(random), 0.1 + 0.1 * unit(random)));
    }
    const ImplicitFunction smooth = implicitSmoothUnion(parts, 0.05);
    // A ripple of the spacing's scale on top: thin sheets and small islands near the surface.
    const double spacing = 0.05 + 0.03 * unit(random);
    const ImplicitFunction rippled = [smooth, spacing](const Vector3d& x) {
      return smooth(x) + 0.3 * spacing * std::sin(x.x() / spacing) * std::cos(1.3 * x.z() / spacing);
    };
    const TetMesh uniform = mesh(rippled, box, spacing, 0);
    const TetMesh graded = mesh(rippled, box, spacing, 1 + shape % 4);
    expectValidAndBounded(graded);
    expectSameBoundary(graded, uniform, spacing);
    EXPECT_LE(graded.numElements(), uniform.numElements());
  }
}

TEST(GradedLattice, OpenSurfaceThroughTheWindingNumber) {
  // The winding number's sign flips across holes where |f| (the distance to the triangles)
  // is not small: refinement by |f| alone would miss those places.
  TriangleSurface sphere = test::uvSphere(Vector3d::Zero(), 1.0, 32, 16);
  std::vector<int> keep;
  for (int t = 0; t < sphere.numTriangles(); ++t)
    if (t % 23 != 5) keep.push_back(t);
  selectTriangles(sphere, keep);
  const SignedDistance distance(sphere, SignMode::WindingNumber);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.1), Vector3d::Constant(1.1));
  const double spacing = 0.06;
  const TetMesh graded = mesh(distance.function(), box, spacing, 3);
  expectValidAndBounded(graded);
  expectSameBoundary(graded, mesh(distance.function(), box, spacing, 0), spacing);
}

TEST(GradedLattice, IsDeterministicWhateverTheThreads) {
  const ImplicitFunction f = implicitSmoothUnion(
      {implicitSphere(Vector3d(-0.3, 0.0, 0.0), 0.5), implicitCapsule(Vector3d::Zero(), Vector3d(0.7, 0.4, 0.1), 0.2)},
      0.1);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.0), Vector3d::Constant(1.0));
  MesherOptions parallel, serial;
  parallel.gradingLevels = serial.gradingLevels = 3;
  serial.parallel = false;
  const TetMesh a = stuffIsosurface(f, box, 0.05, parallel), b = stuffIsosurface(f, box, 0.05, serial);
  ASSERT_EQ(a.numElements(), b.numElements());
  EXPECT_EQ(a.elements(), b.elements());
  EXPECT_EQ(a.restPositions(), b.restPositions());
}

TEST(GradedLattice, ASpacingFarTooSmallIsAnErrorNotAnExhaustedMachine) {
  // The cube count is held to the lattice vertex limit while refining, before any large
  // allocation (a real spacing 1e-4 against a 1 m model would hit the default 2e8).
  MesherOptions options;
  options.gradingLevels = 4;
  options.maxLatticeVertices = 20'000;
  try {
    stuffIsosurface(implicitSphere(Vector3d::Zero(), 1.0),
                    Eigen::AlignedBox3d(Vector3d::Constant(-1.1), Vector3d::Constant(1.1)), 0.01, options);
    ADD_FAILURE() << "a lattice far over the limit was built";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("cubes at spacing"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("use a larger spacing"), std::string::npos) << e.what();
  }
}

TEST(GradedLattice, MoreRootCubesThanAnIntHoldsIsAnErrorNamingTheCount) {
  // 2502 root cubes of 8e-4 per side (the bounds and a cube of margin each side): 1.57e10 of them,
  // beyond 32 bits, are refused before any allocation, with the count in the message.
  MesherOptions options;
  options.gradingLevels = 3;
  try {
    stuffIsosurface(implicitSphere(Vector3d::Zero(), 0.5),
                    Eigen::AlignedBox3d(Vector3d::Constant(-1.0), Vector3d::Constant(1.0)), 1e-4, options);
    ADD_FAILURE() << "a lattice of 1.57e10 root cubes was accepted";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("15662530008 root cubes"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("use a larger spacing"), std::string::npos) << e.what();
  }
}

TEST(GradedLattice, BadLevelsAreErrors) {
  const ImplicitFunction sphere = implicitSphere(Vector3d::Zero(), 1.0);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.1), Vector3d::Constant(1.1));
  for (int levels : {-1, kMaxGradingLevels + 1}) {
    MesherOptions options;
    options.gradingLevels = levels;
    try {
      stuffIsosurface(sphere, box, 0.2, options);
      ADD_FAILURE() << "levels " << levels << " accepted";
    } catch (const ValidationError& e) {
      EXPECT_NE(std::string(e.what()).find("gradingLevels"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace asyncfem
