// SPDX-License-Identifier: BSD-3-Clause
// Triangle surfaces: welding, topology errors, the signed distance and its two signs, and
// meshing a surface through SignedDistance.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/elementSets.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <numbers>
#include <string>

#include "surfaces.hpp"

namespace asyncfem {
namespace {

using Eigen::Vector3d;

TEST(TriangleSurface, WeldingJoinsSeamVerticesAndClosesTheCube) {
  TriangleSurface cube = test::splitCube(Vector3d::Zero(), 1.0);
  EXPECT_EQ(cube.numVertices(), 24);
  EXPECT_FALSE(surfaceTopology(cube).closed());
  EXPECT_EQ(weldVertices(cube, 1e-9), 16);
  EXPECT_EQ(cube.numVertices(), 8);
  const SurfaceTopology topology = surfaceTopology(cube);
  EXPECT_TRUE(topology.closed());
  EXPECT_NEAR(topology.signedVolume, 1.0, 1e-12);
  EXPECT_NO_THROW(requireClosedSurface(cube, "cube"));
}

TEST(TriangleSurface, OpenAndNonManifoldSurfacesAreClearErrors) {
  TriangleSurface open = test::splitCube(Vector3d::Zero(), 1.0);
  weldVertices(open, 1e-9);
  open.triangles.conservativeResize(3, open.numTriangles() - 1);
  open.triangleParts.pop_back();
  const SurfaceTopology topology = surfaceTopology(open);
  EXPECT_EQ(topology.boundaryEdges, 3);
  try {
    requireClosedSurface(open, "open.obj");
    FAIL() << "open surface accepted";
  } catch (const ValidationError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("open.obj"), std::string::npos) << message;
    EXPECT_NE(message.find("3 open boundary edges"), std::string::npos) << message;
    EXPECT_NE(message.find("edge ("), std::string::npos) << message;  // an example edge's positions
    EXPECT_NE(message.find("--repair"), std::string::npos) << message;
  }

  TriangleSurface fin = test::splitCube(Vector3d::Zero(), 1.0);
  weldVertices(fin, 1e-9);
  // A fin: one more triangle on an existing edge makes it non-manifold.
  fin.vertices.conservativeResize(3, fin.numVertices() + 1);
  fin.vertices.col(fin.numVertices() - 1) = Vector3d(0.5, 2.0, 0.5);
  fin.triangles.conservativeResize(3, fin.numTriangles() + 1);
  fin.triangles.col(fin.numTriangles() - 1) =
      Eigen::Vector3i(fin.triangles(0, 0), fin.triangles(1, 0), fin.numVertices() - 1);
  fin.triangleParts.push_back(0);
  const SurfaceTopology finTopology = surfaceTopology(fin);
  EXPECT_EQ(finTopology.nonManifoldEdges, 1);
  EXPECT_THROW(requireClosedSurface(fin, "fin"), ValidationError);
}

TEST(SignedDistance, MatchesTheCubeAndASphere) {
  TriangleSurface cube = test::splitCube(Vector3d::Zero(), 2.0);
  weldVertices(cube, 1e-9);
  const SignedDistance pseudo(cube, SignMode::Pseudonormal);
  const SignedDistance winding(cube, SignMode::WindingNumber);
  // Inside (face, edge and corner regions) and outside points with known distances.
  const std::vector<std::pair<Vector3d, double>> samples{{Vector3d(1.0, 1.0, 1.0), -1.0},
                                                         {Vector3d(0.3, 1.0, 1.0), -0.3},
                                                         {Vector3d(3.0, 1.0, 1.0), 1.0},
                                                         {Vector3d(3.0, 3.0, 1.0), std::sqrt(2.0)},
                                                         {Vector3d(-1.0, -1.0, -1.0), std::sqrt(3.0)},
                                                         {Vector3d(1.0, 2.5, 1.0), 0.5}};
  for (const auto& [x, expected] : samples) {
    EXPECT_NEAR(pseudo(x), expected, 1e-12) << x.transpose();
    EXPECT_NEAR(winding(x), expected, 1e-12) << x.transpose();
  }
  EXPECT_NEAR(winding.windingNumber(Vector3d(1.0, 1.0, 1.0)), 1.0, 1e-9);
  EXPECT_NEAR(winding.windingNumber(Vector3d(5.0, 1.0, 1.0)), 0.0, 1e-3);  // far field: first order

  const TriangleSurface sphere = test::uvSphere(Vector3d::Zero(), 1.0, 32, 16);
  const SignedDistance sphereDistance(sphere);
  EXPECT_NEAR(sphereDistance(Vector3d::Zero()), -1.0, 0.01);
  EXPECT_NEAR(sphereDistance(Vector3d(2.0, 0.0, 0.0)), 1.0, 0.01);
}

TEST(SignedDistance, MeshesATriangulatedSphere) {
  const TriangleSurface sphere = test::uvSphere(Vector3d::Zero(), 1.0, 48, 24);
  ASSERT_TRUE(surfaceTopology(sphere).closed());
  const SignedDistance distance(sphere);
  const TetMesh mesh = stuffIsosurface(distance.function(), sphere.bounds(), 0.12);
  EXPECT_TRUE(checkTetMesh(mesh).ok());
  // The faceted sphere encloses slightly less than the round one; 3% covers both facets.
  EXPECT_NEAR(totalVolume(mesh), std::abs(surfaceTopology(sphere).signedVolume), 0.03 * 4.19);
  const MeshQuality quality = meshQuality(mesh);
  EXPECT_GE(quality.minDihedralDegrees, 9.0);
}

TEST(SignedDistance, WindingNumberMeshesASurfaceWithAHole) {
  TriangleSurface cube = test::splitCube(Vector3d::Zero(), 1.0);
  weldVertices(cube, 1e-9);
  cube.triangles.conservativeResize(3, cube.numTriangles() - 1);  // a hole: half a face missing
  cube.triangleParts.pop_back();
  ASSERT_FALSE(surfaceTopology(cube).closed());
  const SignedDistance distance(cube, SignMode::WindingNumber);
  const TetMesh mesh = stuffIsosurface(distance.function(), cube.bounds(), 0.1);
  EXPECT_TRUE(checkTetMesh(mesh).ok());
  // Stuffing rounds the cube's edges and corners: a few percent less than 1 at h = 0.1.
  EXPECT_NEAR(totalVolume(mesh), 1.0, 0.08);
}

TEST(ElementSets, BoxesAndNamedParts) {
  TriangleSurface twoBoxes = test::splitCube(Vector3d::Zero(), 1.0);
  TriangleSurface upper = test::splitCube(Vector3d(0.0, 1.0, 0.0), 1.0);
  twoBoxes = test::concatenate(twoBoxes, "bottom", upper, "top");
  weldVertices(twoBoxes, 1e-9);
  // The shared face makes the soup non-manifold; the winding number still sees one solid.
  const SignedDistance distance(twoBoxes, SignMode::WindingNumber);
  TetMesh mesh = stuffIsosurface(distance.function(), twoBoxes.bounds(), 0.12);
  const std::vector<int> counts = addNearestPartSets(mesh, distance);
  ASSERT_EQ(counts.size(), 2u);
  EXPECT_GT(counts[0], 0);
  EXPECT_GT(counts[1], 0);
  EXPECT_EQ(counts[0] + counts[1], mesh.numElements());
  const Eigen::Matrix3Xd centroids = elementCentroids(mesh);
  // Near the shared inner face (y = 1, in both parts) either part is nearest.
  for (int e : mesh.elementSet("top")) EXPECT_GT(centroids(1, e), 0.5);
  for (int e : mesh.elementSet("bottom")) EXPECT_LT(centroids(1, e), 1.5);

  const int inBox = addBoxSet(mesh, "lower", Eigen::AlignedBox3d(Vector3d(-1, -1, -1), Vector3d(2, 0.5, 2)));
  EXPECT_GT(inBox, 0);
  EXPECT_FALSE(mesh.vertexSet("lower").empty());
  assignSetMaterial(mesh, "top", Material{"hard", 500.0, 1e8, 0.3});
  for (int e : mesh.elementSet("top")) EXPECT_EQ(mesh.elementMaterial(e).name, "hard");
  EXPECT_THROW(assignSetMaterial(mesh, "nope", Material{"x", 1.0, 1.0, 0.3}), ValidationError);
}

}  // namespace
}  // namespace asyncfem
