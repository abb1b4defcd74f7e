// SPDX-License-Identifier: BSD-3-Clause
// SurfaceEmbedding: the tet boundary, embedded render meshes read through assimp.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/core/error.hpp>
#include <asyncfem/render/surfaceEmbedding.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <utility>

#include "renderTestHelpers.hpp"

namespace {

using namespace asyncfem;
using namespace asyncfem::renderTesting;

TEST(SurfaceEmbedding, BoundaryFollowsTheMeshExactly) {
  const TetMesh mesh = renderTestBar();
  const SurfaceEmbedding surface = SurfaceEmbedding::boundary(mesh);
  EXPECT_EQ(surface.triangles().size(), boundaryTriangles(mesh).size());
  EXPECT_EQ(surface.numOutsideVertices(), 0);
  const Eigen::VectorXd u = bentBar(mesh);
  const Eigen::Matrix3Xd x = surface.positions(u);
  for (int k = 0; k < surface.numSurfaceVertices(); ++k) {
    const int v = surface.tetVertices()(0, k);
    EXPECT_EQ(x.col(k), Eigen::Vector3d(mesh.restPosition(v) + u.segment<3>(3 * v)));
  }
  EXPECT_THROW(surface.positions(Eigen::VectorXd::Zero(4)), Error);
}

/// A small closed octahedron centred in the bar plus one vertex 0.05 outside it.
SurfaceMesh octahedronWithOutlier() {
  SurfaceMesh s;
  s.vertices.resize(3, 7);
  const Eigen::Vector3d c(0.93, 0.21, 0.17);
  s.vertices << c.x() + 0.15, c.x() - 0.15, c.x(), c.x(), c.x(), c.x(), 2.05,  //
      c.y(), c.y(), c.y() + 0.15, c.y() - 0.15, c.y(), c.y(), 0.3,             //
      c.z(), c.z(), c.z(), c.z(), c.z() + 0.15, c.z() - 0.15, 0.1;
  s.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}, {0, 6, 2}};
  return s;
}

TEST(SurfaceEmbedding, EmbeddedMeshReadFromObjFollowsATranslationExactly) {
  const TetMesh mesh = renderTestBar();
  const auto folder = freshFolder("embedding");
  writeObj(folder / "shape.obj", octahedronWithOutlier());
  const SurfaceMesh loaded = loadSurfaceMesh(folder / "shape.obj");
  ASSERT_EQ(loaded.vertices.cols(), 7);
  ASSERT_EQ(loaded.triangles.size(), 9U);

  const SurfaceEmbedding surface = SurfaceEmbedding::embed(mesh, loaded);
  EXPECT_EQ(surface.numOutsideVertices(), 1);
  // assimp stores coordinates as float: 0.05 to about 1e-7.
  EXPECT_NEAR(surface.maxOutsideDistance(), 0.05, 1e-6);
  // Inside vertices: convex weights summing to 1 that reproduce the position.
  for (int k = 0; k < 6; ++k) {
    EXPECT_GE(surface.weights().col(k).minCoeff(), -1e-12);
    EXPECT_NEAR(surface.weights().col(k).sum(), 1.0, 1e-14);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) {
      p += surface.weights()(a, k) * mesh.restPosition(surface.tetVertices()(a, k));
    }
    EXPECT_LE((p - loaded.vertices.col(k)).norm(), 1e-14);
  }

  const Eigen::Vector3d t(0.4, -1.25, 3.0);
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    u.segment<3>(3 * v) = t;
  }
  const Eigen::Matrix3Xd x = surface.positions(u);
  // x = p + sum_a w_a t = p + t (sum_a w_a = 1 to rounding), also for the outside vertex.
  for (int k = 0; k < 7; ++k) {
    EXPECT_LE((x.col(k) - (loaded.vertices.col(k) + t)).cwiseAbs().maxCoeff(), 1e-14) << "vertex " << k;
  }
  EXPECT_EQ(surface.positions(Eigen::VectorXd::Zero(mesh.numDofs())), loaded.vertices);
  std::filesystem::remove_all(folder);
}

TEST(SurfaceEmbedding, EmbeddedMeshFollowsAnAffineMotion) {
  // Barycentric weights reproduce every affine field, inside and outside.
  const TetMesh mesh = renderTestBar();
  const SurfaceMesh shape = octahedronWithOutlier();
  const SurfaceEmbedding surface = SurfaceEmbedding::embed(mesh, shape);
  Eigen::Matrix3d a;
  a << 0.1, -0.3, 0.2, 0.05, 0.0, -0.1, 0.3, 0.2, -0.05;
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    u.segment<3>(3 * v) = a * mesh.restPosition(v);
  }
  const Eigen::Matrix3Xd x = surface.positions(u);
  for (int k = 0; k < 7; ++k) {
    EXPECT_LE((x.col(k) - (shape.vertices.col(k) + a * shape.vertices.col(k))).norm(), 1e-13);
  }
}

TEST(SurfaceEmbedding, HexahedraReproduceAnAffineMotionInsideAndOutside) {
  // Trilinear shape functions reproduce affine fields: with the rest map inverted exactly
  // (Newton, hexahedron::referenceCoordinates) every embedded point follows x -> (I + A) x + b,
  // including the outside vertex, which extrapolates its nearest hexahedron. Tolerance: Newton
  // stops below 1e-13 in reference units (about 1e-14 in length for cubes of 0.2), then
  // rounding in sums of eight terms.
  for (const double wobble : {0.0, 0.03}) {
    const TetMesh mesh = renderTestCubeBar(wobble);
    const SurfaceMesh shape = octahedronWithOutlier();
    const SurfaceEmbedding surface = SurfaceEmbedding::embed(mesh, shape);
    ASSERT_EQ(surface.tetVertices().rows(), 8);
    EXPECT_EQ(surface.numOutsideVertices(), 1);
    EXPECT_NEAR(surface.maxOutsideDistance(), 0.45, 1e-12);  // the bar's end face x = 1.6 is flat
    for (int k = 0; k < 6; ++k) {
      // Inside: the eight weights are convex and give back the point.
      EXPECT_GE(surface.weights().col(k).minCoeff(), -1e-12) << "vertex " << k;
      EXPECT_NEAR(surface.weights().col(k).sum(), 1.0, 1e-14);
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      for (int a = 0; a < 8; ++a) p += surface.weights()(a, k) * mesh.restPosition(surface.tetVertices()(a, k));
      EXPECT_LE((p - shape.vertices.col(k)).norm(), 1e-13) << "vertex " << k;
    }
    Eigen::Matrix3d a;
    a << 0.1, -0.3, 0.2, 0.05, 0.0, -0.1, 0.3, 0.2, -0.05;
    const Eigen::Vector3d b(0.4, -1.25, 3.0);
    Eigen::VectorXd u(mesh.numDofs());
    for (int v = 0; v < mesh.numVertices(); ++v) u.segment<3>(3 * v) = a * mesh.restPosition(v) + b;
    const Eigen::Matrix3Xd x = surface.positions(u);
    for (int k = 0; k < 7; ++k) {
      const Eigen::Vector3d expected = shape.vertices.col(k) + a * shape.vertices.col(k) + b;
      EXPECT_LE((x.col(k) - expected).norm(), 1e-12) << "wobble " << wobble << ", vertex " << k;
    }
  }
}

TEST(SurfaceEmbedding, ReadsOtherFormatsAndWeldsSeams) {
  const auto folder = freshFolder("formats");
  // ASCII STL stores every triangle's corners separately: welding joins them.
  std::ofstream(folder / "two.stl") << "solid two\n"
                                       "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                                       "endloop\nendfacet\n"
                                       "facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n"
                                       "endloop\nendfacet\nendsolid two\n";
  const SurfaceMesh stl = loadSurfaceMesh(folder / "two.stl");
  EXPECT_EQ(stl.triangles.size(), 2U);
  EXPECT_EQ(stl.vertices.cols(), 4);
  // ASCII PLY with a quad: triangulated.
  std::ofstream(folder / "quad.ply") << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                        "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                        "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
  const SurfaceMesh ply = loadSurfaceMesh(folder / "quad.ply");
  EXPECT_EQ(ply.triangles.size(), 2U);
  EXPECT_EQ(ply.vertices.cols(), 4);
  try {
    loadSurfaceMesh(folder / "missing.obj");
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.obj"), std::string::npos) << e.what();
  }
  std::ofstream(folder / "garbage.obj") << "this is not\na mesh\n";
  EXPECT_THROW(loadSurfaceMesh(folder / "garbage.obj"), Error);
  std::filesystem::remove_all(folder);
}

TEST(SurfaceEmbedding, BadSurfaceIsAnError) {
  const TetMesh mesh = renderTestBar();
  SurfaceMesh bad = octahedronWithOutlier();
  bad.triangles.push_back({0, 1, 7});
  try {
    SurfaceEmbedding::embed(mesh, bad);
    FAIL() << "expected ValidationError";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 7"), std::string::npos) << e.what();
  }
}

// sphereSurface (a scene's contact spheres as frameRenderer draws them): a closed,
// outward-oriented triangle surface on the sphere. Vertices on the sphere to 1e-12 of the
// radius (round-off of one normalisation); the enclosed volume below the ball's and within
// 1% of it at 4 refinements (an inscribed polyhedron with 5,120 faces loses about 0.3%).
TEST(SphereSurface, ClosedOutwardAndOnTheSphere) {
  const Eigen::Vector3d center(0.3, -1.2, 2.0);
  const double radius = 0.7;
  for (const int refinements : {0, 2, 4}) {
    const SurfaceMesh s = sphereSurface(center, radius, refinements);
    const int faces = 20 << (2 * refinements);
    ASSERT_EQ(static_cast<int>(s.triangles.size()), faces);
    EXPECT_EQ(s.vertices.cols(), (faces / 2) + 2);  // Euler: V - E + F = 2 with E = 3F/2
    for (Eigen::Index v = 0; v < s.vertices.cols(); ++v) {
      EXPECT_NEAR((s.vertices.col(v) - center).norm(), radius, 1e-12 * radius);
    }
    std::map<std::pair<int, int>, int> directedEdges;  // closed and consistently oriented: each once
    double volume = 0.0;
    for (const auto& t : s.triangles) {
      for (int e = 0; e < 3; ++e) ++directedEdges[{t[e], t[(e + 1) % 3]}];
      const Eigen::Vector3d a = s.vertices.col(t[0]) - center;
      volume += a.dot((s.vertices.col(t[1]) - center).cross(s.vertices.col(t[2]) - center)) / 6.0;
    }
    for (const auto& [edge, count] : directedEdges) {
      EXPECT_EQ(count, 1);
      EXPECT_EQ(directedEdges.count({edge.second, edge.first}), 1U);
    }
    const double ball = 4.0 / 3.0 * M_PI * radius * radius * radius;
    EXPECT_GT(volume, 0.0);  // counter-clockwise from outside
    EXPECT_LT(volume, ball);
    if (refinements == 4) EXPECT_GT(volume, 0.99 * ball);
  }
  EXPECT_THROW(sphereSurface(center, 0.0), Error);
  EXPECT_THROW(sphereSurface(center, std::nan("")), Error);
  EXPECT_THROW(sphereSurface(center, 1.0, 7), Error);
}

}  // namespace
