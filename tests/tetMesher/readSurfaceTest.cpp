// SPDX-License-Identifier: BSD-3-Clause
// Surfaces read through assimp (built only with ASYNCFEM_WITH_ASSIMP): OBJ files written
// here are read, welded, meshed and checked.
#include <gtest/gtest.h>
#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/elementSets.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "surfaces.hpp"

namespace asyncfem {
namespace {

using Eigen::Vector3d;

std::filesystem::path writeTemp(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / ("asyncfem-tetMesher-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

TEST(ReadSurface, ObjCubeWithSeamsMeshesCorrectly) {
  ASSERT_TRUE(surfaceReaderAvailable());
  const auto path = writeTemp("cube.obj", test::toObj(test::splitCube(Vector3d(1.0, 2.0, 3.0), 2.0)));
  TriangleSurface surface = readSurface(path);
  EXPECT_EQ(surface.numTriangles(), 12);
  weldVertices(surface, 1e-9);
  EXPECT_EQ(surface.numVertices(), 8);
  ASSERT_NO_THROW(requireClosedSurface(surface, path.string()));
  EXPECT_NEAR(surfaceTopology(surface).signedVolume, 8.0, 1e-9);

  const SignedDistance distance(surface);
  const TetMesh mesh = stuffIsosurface(distance.function(), surface.bounds(), 0.2);
  const MeshCheckReport check = checkTetMesh(mesh);
  EXPECT_TRUE(check.ok()) << check.firstProblem;
  EXPECT_EQ(check.components, 1);
  // Edges and corners are rounded off by about a cut-point distance: a few percent of 8.
  EXPECT_NEAR(totalVolume(mesh), 8.0, 0.08 * 8.0);
  const BoundingBox box = boundingBox(mesh);
  EXPECT_NEAR(box.min.x(), 1.0, 0.1);
  EXPECT_NEAR(box.max.z(), 5.0, 0.1);
  EXPECT_GE(meshQuality(mesh).minDihedralDegrees, 9.0);
}

TEST(ReadSurface, ObjSphereAndNamedParts) {
  const TriangleSurface sphere = test::uvSphere(Vector3d::Zero(), 1.0, 40, 20);
  const auto spherePath = writeTemp("sphere.obj", test::toObj(sphere));
  TriangleSurface read = readSurface(spherePath);
  weldVertices(read, 1e-9);
  ASSERT_TRUE(surfaceTopology(read).closed());
  const SignedDistance distance(read);
  const TetMesh mesh = stuffIsosurface(distance.function(), read.bounds(), 0.15);
  EXPECT_TRUE(checkTetMesh(mesh).ok());
  EXPECT_NEAR(totalVolume(mesh), std::abs(surfaceTopology(read).signedVolume), 0.04 * 4.19);

  const TriangleSurface parts = test::concatenate(test::uvSphere(Vector3d(-1.2, 0, 0), 1.0, 24, 12), "left",
                                                  test::uvSphere(Vector3d(1.2, 0, 0), 1.0, 24, 12), "right");
  TriangleSurface twoParts = readSurface(writeTemp("parts.obj", test::toObj(parts)));
  ASSERT_EQ(twoParts.partNames.size(), 2u);
  weldVertices(twoParts, 1e-9);
  const SignedDistance twoDistance(twoParts);
  TetMesh twoMesh = stuffIsosurface(twoDistance.function(), twoParts.bounds(), 0.2);
  addNearestPartSets(twoMesh, twoDistance);
  EXPECT_EQ(checkTetMesh(twoMesh).components, 2);
  const std::vector<std::string> names = twoParts.partNames;
  const Eigen::Matrix3Xd centroids = elementCentroids(twoMesh);
  const int leftIndex = names[0] == "left" ? 0 : 1;
  for (int e : twoMesh.elementSet(names[static_cast<std::size_t>(leftIndex)])) EXPECT_LT(centroids(0, e), 0.0);
}

TEST(ReadSurface, MissingOrEmptyFilesAreErrors) {
  EXPECT_THROW(readSurface("/nonexistent/surface.obj"), Error);
  EXPECT_THROW(readSurface(writeTemp("empty.obj", "# nothing\n")), Error);
}

}  // namespace
}  // namespace asyncfem

namespace asyncfem {
namespace {

TEST(ReadSurface, ObjGroupsAndMaterialsLabelTriangles) {
  // Two tetrahedra in groups "left" and "right"; "left" has two materials.
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 3 0 0\nv 4 0 0\nv 3 1 0\nv 3 0 1\n"
      "g left\nusemtl red\nf 1 3 2\nf 1 2 4\nusemtl blue\nf 1 4 3\nf 2 3 4\n"
      "g right\nusemtl blue\nf 5 7 6\nf 5 6 8\nf 5 8 7\nf 6 7 8\n";
  TriangleSurface surface = readSurface(writeTemp("groups.obj", obj));
  weldVertices(surface, 1e-9);
  ASSERT_EQ(surface.numTriangles(), 8);
  ASSERT_EQ(surface.triangleGroups.size(), 8u);
  ASSERT_EQ(surface.triangleMaterials.size(), 8u);
  auto count = [](const std::vector<int>& labels, const std::vector<std::string>& names, const std::string& name) {
    int n = 0;
    for (int label : labels) n += names[static_cast<std::size_t>(label)] == name ? 1 : 0;
    return n;
  };
  EXPECT_EQ(count(surface.triangleGroups, surface.groupNames, "left"), 4);
  EXPECT_EQ(count(surface.triangleGroups, surface.groupNames, "right"), 4);
  EXPECT_EQ(count(surface.triangleMaterials, surface.materialNames, "red"), 2);
  EXPECT_EQ(count(surface.triangleMaterials, surface.materialNames, "blue"), 6);
  // Group sets by containment: every element of a tetrahedron goes to its group.
  const SignedDistance distance(surface, SignMode::WindingNumber);
  TetMesh mesh = stuffIsosurface(distance.function(), surface.bounds(), 0.1);
  const std::vector<int> counts = addSurfaceLabelSets(mesh, distance, SurfaceLabel::Group);
  int total = 0;
  for (int c : counts) total += c;
  EXPECT_EQ(total, mesh.numElements());
  for (int e : mesh.elementSet("left")) EXPECT_LT(mesh.elementRestPositions(e).row(0).mean(), 2.0) << e;
  for (int e : mesh.elementSet("right")) EXPECT_GT(mesh.elementRestPositions(e).row(0).mean(), 2.0) << e;
}

}  // namespace
}  // namespace asyncfem
