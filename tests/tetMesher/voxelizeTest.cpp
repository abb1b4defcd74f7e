// SPDX-License-Identifier: BSD-3-Clause
// Cube meshes from closed surfaces and implicit solids (voxelize.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/exampleModels.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/tetMesher/voxelize.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <map>
#include <numbers>
#include <string>

#include "surfaces.hpp"

namespace asyncfem {
namespace {

using FaceKey = std::array<int, 4>;

/// How many cubes use each quadrilateral face (keyed by its sorted vertices).
std::map<FaceKey, int> faceUses(const TetMesh& mesh) {
  std::map<FaceKey, int> uses;
  for (int e = 0; e < mesh.numElements(); ++e) {
    for (const auto& face : hexahedron::kFaces) {
      FaceKey key{};
      for (std::size_t c = 0; c < 4; ++c) key[c] = mesh.elementVertex(e, face[c]);
      std::sort(key.begin(), key.end());
      ++uses[key];
    }
  }
  return uses;
}

/// Every cube is an axis-aligned cube of edge h with a positive Jacobian at all corners, and
/// the mesh is conforming: no face is used by more than two cubes, and a face used by one
/// cube only lies on the boundary (the grid cell beyond it is outside, f >= 0 at its centre).
void expectConformingCubes(const TetMesh& mesh, double h, const ImplicitFunction& f) {
  ASSERT_TRUE(mesh.isHexahedral());
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Matrix<double, 3, 8> x = mesh.hexahedronRestPositions(e);
    // Corner Jacobians are h^3 exactly up to rounding of the grid coordinates.
    EXPECT_NEAR(hexahedron::cornerJacobians(x).minCoeff(), h * h * h, 1e-9 * h * h * h) << "cube " << e;
  }
  const HexahedronQualitySummary quality = summarizeHexahedronQuality(mesh);
  EXPECT_TRUE(quality.invertedElements.empty());
  EXPECT_NEAR(quality.minScaledJacobian, 1.0, 1e-9);  // right angles everywhere
  int boundaryFaces = 0;
  for (const auto& [key, count] : faceUses(mesh)) {
    EXPECT_LE(count, 2);
    if (count != 1) continue;
    ++boundaryFaces;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int v : key) centre += mesh.restPosition(v) / 4.0;
    // The face's one cube lies on one side; the cell centre on the other side is outside.
    for (int e = 0; e < mesh.numElements(); ++e) {
      Eigen::Vector3d cubeCentre = mesh.hexahedronRestPositions(e).rowwise().mean();
      if ((cubeCentre - centre).norm() > 0.51 * h) continue;
      EXPECT_GE(f(2.0 * centre - cubeCentre), 0.0) << "boundary face at cube " << e << " has a cube beyond it";
      break;
    }
  }
  EXPECT_GT(boundaryFaces, 0);
}

TEST(Voxelize, AxisAlignedBoxIsFilledExactly) {
  // A 2 x 1 x 1 box at (0.1, 0.2, 0.3), spacing 0.25: 8 x 4 x 4 cubes, 9 x 5 x 5 vertices,
  // 2 (8 x 4 + 8 x 4 + 4 x 4) boundary faces, the box's volume to rounding.
  TriangleSurface box = test::splitCube(Eigen::Vector3d(0.05, 0.2, 0.3), 1.0);
  box.vertices.row(0) *= 2.0;
  const SignedDistance distance(box);
  VoxelReport report;
  const TetMesh mesh = voxelize(distance.function(), box.bounds(), 0.25, {}, &report);
  EXPECT_EQ(mesh.numElements(), 128);
  EXPECT_EQ(mesh.numVertices(), 225);
  EXPECT_EQ(report.cubes, 128);
  EXPECT_EQ(report.gridCells, Eigen::Vector3i(8, 4, 4));
  EXPECT_NEAR(totalVolume(mesh), 2.0, 1e-12);
  EXPECT_NEAR(relativeVolumeError(report.cubeVolume, 2.0), 0.0, 1e-12);
  int boundaryFaces = 0;
  for (const auto& [key, count] : faceUses(mesh)) boundaryFaces += count == 1 ? 1 : 0;
  EXPECT_EQ(boundaryFaces, 160);
  expectConformingCubes(mesh, 0.25, distance.function());
}

TEST(Voxelize, SphereVolumeErrorShrinksUnderRefinement) {
  // The 48 x 24 UV sphere of radius 1 (enclosed volume V from the divergence theorem).
  // Guaranteed bound: a point of the cubes' union on the wrong side of the surface lies within
  // sqrt(3) h / 2 (half a cube diagonal) of it, so |error| <= 2 (sqrt(3) h / 2) A / V with A the
  // area (4 pi, slightly more than the polyhedron's). On this sequence the error also
  // decreases strictly (+6.2%, +1.6%, -0.1%), which a wrong inside test would not.
  const TriangleSurface sphere = test::uvSphere(Eigen::Vector3d::Zero(), 1.0, 48, 24);
  const double enclosed = std::abs(surfaceTopology(sphere).signedVolume);
  const SignedDistance distance(sphere);
  double previous = INFINITY;
  for (const double h : {0.2, 0.1, 0.05}) {
    VoxelReport report;
    const TetMesh mesh = voxelize(distance.function(), sphere.bounds(), h, {}, &report);
    const double error = std::abs(relativeVolumeError(report.cubeVolume, enclosed));
    EXPECT_LE(error, std::sqrt(3.0) * h * 4.0 * std::numbers::pi / enclosed) << "h = " << h;
    EXPECT_LT(error, previous) << "h = " << h;
    previous = error;
    EXPECT_NEAR(totalVolume(mesh), report.cubeVolume, 1e-12 * report.cubeVolume);
    if (h >= 0.1) expectConformingCubes(mesh, h, distance.function());
  }
  EXPECT_LT(previous, 0.01);
}

TEST(Voxelize, WindingNumberAndImplicitSolidsGiveTheSameCubes) {
  // A sphere given implicitly and as a 96 x 48 polyhedron with the winding-number sign. The
  // polyhedron lies within 1 - cos(pi / 96) = 5.4e-4 of the sphere and the nearest cell centre
  // of this grid is 3.4e-3 from it, so both inside tests must pick the same cells.
  const ImplicitFunction ball = implicitSphere(Eigen::Vector3d::Zero(), 1.0);
  const Eigen::AlignedBox3d bounds(Eigen::Vector3d::Constant(-1.05), Eigen::Vector3d::Constant(1.05));
  const TetMesh exact = voxelize(ball, bounds, 0.15);
  expectConformingCubes(exact, 0.15, ball);
  const SignedDistance winding(test::uvSphere(Eigen::Vector3d::Zero(), 1.0, 96, 48), SignMode::WindingNumber);
  const TetMesh fromSurface = voxelize(winding.function(), bounds, 0.15);
  EXPECT_EQ(fromSurface.numElements(), exact.numElements());
}

TEST(Voxelize, ExampleModelCubesKeepPartSetsAndMaterials) {
  VoxelReport report;
  const TetMesh mesh = makeExampleModelCubes(ExampleModel::Dinosaur, 0.0, &report);
  EXPECT_TRUE(mesh.isHexahedral());
  EXPECT_EQ(report.cubes, mesh.numElements());
  EXPECT_FALSE(mesh.elementSet("head").empty());
  EXPECT_FALSE(mesh.elementSet("tail").empty());
  EXPECT_GE(mesh.findMaterial("head"), 0);
}

TEST(Voxelize, RefusesZeroCubesTooManyCubesAndBadSpacings) {
  const ImplicitFunction ball = implicitSphere(Eigen::Vector3d::Zero(), 1.0);
  const Eigen::AlignedBox3d bounds(Eigen::Vector3d::Constant(-1.0), Eigen::Vector3d::Constant(1.0));
  auto message = [&](double h, long long maxCubes) {
    VoxelOptions options;
    options.maxCubes = maxCubes;
    try {
      voxelize(ball, bounds, h, options);
    } catch (const ValidationError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  // One cell of edge 10 whose centre (4, 4, 4) is outside.
  EXPECT_NE(message(10.0, 1000).find("no cube centre at spacing 10 lies inside"), std::string::npos);
  EXPECT_NE(message(0.1, 1000).find("4224 cubes, more than the cap of 1000; a spacing of about"), std::string::npos)
      << message(0.1, 1000);
  EXPECT_NE(message(0.01, 1000).find("more than 8000 (8 x the cap of 1000 cubes)"), std::string::npos)
      << message(0.01, 1000);
  EXPECT_NE(message(1e-300, 1000).find("cells along one axis"), std::string::npos) << message(1e-300, 1000);
  EXPECT_NE(message(0.0, 1000).find("must be positive and finite"), std::string::npos);
  EXPECT_NE(message(NAN, 1000).find("must be positive and finite"), std::string::npos);
  EXPECT_THROW(relativeVolumeError(1.0, 0.0), ValidationError);
}

}  // namespace
}  // namespace asyncfem
