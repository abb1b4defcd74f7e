// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/collision/collisionSurface.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <string>

namespace asyncfem {
namespace {

TEST(CollisionSurface, BoundaryOfABoxIsAClosedOutwardSurface) {
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i(2, 2, 2);
  const TetMesh mesh = makeBoxMesh(spec);
  const CollisionSurface surface = boundarySurface(mesh);
  // 6 sides of 2 x 2 squares, two triangles each; 3^3 - 1 lattice vertices on the boundary;
  // Euler's formula V - E + F = 2 for a closed surface of genus 0 gives the edges.
  EXPECT_EQ(surface.numTriangles(), 48);
  EXPECT_EQ(surface.numSurfaceVertices(), 26);
  EXPECT_EQ(surface.numEdges(), 26 + 48 - 2);
  EXPECT_EQ(surface.numMeshVertices, mesh.numVertices());
  // Outward orientation: the divergence theorem gives +volume (1 m^3), exact up to round-off.
  double volume = 0.0;
  for (int t = 0; t < surface.numTriangles(); ++t) {
    const Eigen::Vector3d a = mesh.restPosition(surface.triangles(0, t));
    const Eigen::Vector3d b = mesh.restPosition(surface.triangles(1, t));
    const Eigen::Vector3d c = mesh.restPosition(surface.triangles(2, t));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  EXPECT_NEAR(volume, 1.0, 1e-14);
  for (int e = 0; e < surface.numEdges(); ++e) EXPECT_LT(surface.edges(0, e), surface.edges(1, e));
}

TEST(CollisionSurface, TriangleIdOutOfRangeNamesTheTriangle) {
  Eigen::Matrix3Xi triangles(3, 2);
  triangles << 0, 1, 1, 2, 2, 7;
  try {
    triangleSurface(triangles, 4);
    FAIL() << "expected ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("triangle 1 has vertex id 7"), std::string::npos) << error.what();
  }
  triangles << 0, 1, 1, 2, 2, 1;
  EXPECT_THROW(triangleSurface(triangles, 4), ValidationError);
}

TEST(CollisionSurface, PositionsMustMatchTheMeshAndBeFinite) {
  Eigen::Matrix3Xi triangles(3, 1);
  triangles << 0, 1, 2;
  const CollisionSurface surface = triangleSurface(triangles, 3);
  EXPECT_THROW(checkPositions(surface, Eigen::Matrix3Xd::Zero(3, 2), "test"), ValidationError);
  Eigen::Matrix3Xd positions = Eigen::Matrix3Xd::Zero(3, 3);
  positions(1, 2) = std::numeric_limits<double>::quiet_NaN();
  try {
    checkPositions(surface, positions, "test");
    FAIL() << "expected ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("vertex 2"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace asyncfem
