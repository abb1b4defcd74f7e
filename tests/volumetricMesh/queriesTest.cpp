// SPDX-License-Identifier: BSD-3-Clause
// Mesh queries: volumes, mass, boundary orientation, adjacency, bounding box, quality.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>

namespace asyncfem {
namespace {

BoxMeshSpec oddBox() {
  BoxMeshSpec spec;
  spec.origin = Eigen::Vector3d(0.1, -0.2, 0.3);
  spec.size = Eigen::Vector3d(1.5, 0.7, 2.0);
  spec.cells = Eigen::Vector3i(3, 4, 5);
  return spec;
}

TetMesh regularTet() {
  Eigen::Matrix3Xd x(3, 4);
  x << 1, 1, -1, -1,  //
      1, -1, 1, -1,   //
      1, -1, -1, 1;
  Eigen::Matrix4Xi t(4, 1);
  t << 0, 1, 2, 3;
  return TetMesh(x, t, {Material{"m", 1000, 1e6, 0.3}}, {0});
}

// Every element volume is a 3x3 determinant with relative rounding error of a few ulps;
// summing 360 of them adds at most ~360 ulps, about 1e-13 relative, so 1e-12 is a bound
// with margin that still catches any missing or double-counted element.
constexpr double kSumTolerance = 1e-12;

// A set of either kind names vertices: a vertex set as it is, an element set as the sorted,
// unique vertices of its elements (Vega meshes carry element sets only); a vertex set of
// the same name wins; an unknown name lists the sets of both kinds.
TEST(MeshQueries, SetVerticesResolvesVertexAndElementSets) {
  TetMesh mesh = makeBoxMesh(oddBox());
  mesh.setElementSet("pair", {3, 0});
  std::vector<int> expected;
  for (const int e : {0, 3})
    for (int a = 0; a < 4; ++a) expected.push_back(mesh.element(e)[a]);
  std::sort(expected.begin(), expected.end());
  expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
  EXPECT_EQ(mesh.setVertices("pair"), expected);
  EXPECT_EQ(mesh.setVertices("xmin"), mesh.vertexSet("xmin"));
  mesh.setVertexSet("pair", {7});
  EXPECT_EQ(mesh.setVertices("pair"), std::vector<int>{7});
  try {
    (void)mesh.setVertices("nowhere");
    FAIL() << "expected an error";
  } catch (const ValidationError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("unknown set 'nowhere'"), std::string::npos) << message;
    EXPECT_NE(message.find("vertex sets: pair, xmax"), std::string::npos) << message;
    EXPECT_NE(message.find("element sets: pair"), std::string::npos) << message;
  }
}

TEST(MeshQueries, BoxVolumesSumToTheBoxVolume) {
  const BoxMeshSpec spec = oddBox();
  const TetMesh mesh = makeBoxMesh(spec);
  const double expected = spec.size.prod();
  EXPECT_NEAR(totalVolume(mesh), expected, kSumTolerance * expected);
  EXPECT_NEAR(elementVolumes(mesh).sum(), expected, kSumTolerance * expected);
  for (int e = 0; e < mesh.numElements(); ++e) EXPECT_GT(signedElementVolume(mesh, e), 0.0);
}

TEST(MeshQueries, MassIsDensityTimesVolume) {
  BeamSpec spec;
  spec.cellsAlongLength = 10;
  const TetMesh beam = makeBeamMesh(spec);
  // The tip is the last 20% of the 1 x 0.2 x 0.2 beam.
  const double tipVolume = 0.2 * 0.2 * 0.2, bodyVolume = 0.8 * 0.2 * 0.2;
  const double expected = spec.body.density * bodyVolume + spec.tip.density * tipVolume;
  EXPECT_NEAR(totalMass(beam), expected, kSumTolerance * expected);
}

TEST(MeshQueries, BoundaryTrianglesCountAndOutwardOrientation) {
  const BoxMeshSpec spec = oddBox();
  const TetMesh mesh = makeBoxMesh(spec);
  const auto triangles = boundaryTriangles(mesh);
  const Eigen::Vector3i c = spec.cells;
  EXPECT_EQ(triangles.size(), static_cast<std::size_t>(4 * (c.x() * c.y() + c.y() * c.z() + c.z() * c.x())));
  // Divergence theorem with F(x) = x / 3: V = sum over boundary of (centroid . n) area / 3,
  // exact for flat triangles. Inward-facing triangles would flip the sign.
  double volume = 0.0;
  for (const auto& t : triangles) {
    const Eigen::Vector3d a = mesh.restPosition(t[0]), b = mesh.restPosition(t[1]), cc = mesh.restPosition(t[2]);
    const Eigen::Vector3d areaNormal = 0.5 * (b - a).cross(cc - a);
    volume += ((a + b + cc) / 3.0).dot(areaNormal) / 3.0;
  }
  const double expected = spec.size.prod();
  EXPECT_NEAR(volume, expected, kSumTolerance * expected);
}

TEST(MeshQueries, BoundaryOfNegativelyStoredElementStillFacesOut) {
  Eigen::Matrix3Xd x(3, 4);
  x << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  Eigen::Matrix4Xi t(4, 1);
  t << 0, 2, 1, 3;  // negative orientation
  const TetMesh mesh(x, t, {Material{"m", 1, 1, 0}}, {0});
  ASSERT_LT(signedElementVolume(mesh, 0), 0.0);
  const auto triangles = boundaryTriangles(mesh);
  ASSERT_EQ(triangles.size(), 4u);
  const Eigen::Vector3d centroid(0.25, 0.25, 0.25);
  for (const auto& f : triangles) {
    const Eigen::Vector3d a = x.col(f[0]), b = x.col(f[1]), c = x.col(f[2]);
    EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3.0 - centroid), 0.0);
  }
}

TEST(MeshQueries, VertexElementAdjacency) {
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i(2, 1, 1);
  const TetMesh mesh = makeBoxMesh(spec);
  const VertexElementAdjacency adjacency = vertexElementAdjacency(mesh);
  ASSERT_EQ(adjacency.offsets.size(), static_cast<std::size_t>(mesh.numVertices()) + 1);
  EXPECT_EQ(adjacency.offsets.back(), 4 * mesh.numElements());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const auto begin = adjacency.elements.begin() + adjacency.offsets[static_cast<std::size_t>(v)];
    const auto end = adjacency.elements.begin() + adjacency.offsets[static_cast<std::size_t>(v) + 1];
    EXPECT_TRUE(std::is_sorted(begin, end));
    for (int e = 0; e < mesh.numElements(); ++e) {
      const bool incident = (mesh.element(e).array() == v).any();
      EXPECT_EQ(std::find(begin, end, e) != end, incident) << "vertex " << v << " element " << e;
    }
  }
  // Vertex 0 (the low corner of the first cube) lies on the shared diagonal of all six tets.
  EXPECT_EQ(adjacency.offsets[1] - adjacency.offsets[0], 6);
}

TEST(MeshQueries, BoundingBoxWithAndWithoutDisplacement) {
  const BoxMeshSpec spec = oddBox();
  const TetMesh mesh = makeBoxMesh(spec);
  const BoundingBox rest = boundingBox(mesh);
  EXPECT_TRUE(rest.min.isApprox(spec.origin));
  EXPECT_TRUE(rest.max.isApprox(spec.origin + spec.size));
  Eigen::VectorXd shift(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) shift.segment<3>(3 * v) = Eigen::Vector3d(1, 2, 3);
  const BoundingBox moved = boundingBox(mesh, shift);
  EXPECT_TRUE(moved.min.isApprox(spec.origin + Eigen::Vector3d(1, 2, 3)));
  EXPECT_THROW(boundingBox(mesh, Eigen::VectorXd::Zero(5)), ValidationError);
}

TEST(MeshQueries, RegularTetQuality) {
  const ElementQuality q = elementQuality(regularTet(), 0);
  const double dihedral = std::acos(1.0 / 3.0);
  EXPECT_NEAR(q.minDihedralAngle, dihedral, 1e-14);
  EXPECT_NEAR(q.maxDihedralAngle, dihedral, 1e-14);
  EXPECT_NEAR(q.aspectRatio, 1.0, 1e-14);
}

TEST(MeshQueries, FlattenedTetHasWorseQuality) {
  Eigen::Matrix3Xd x(3, 4);
  x << 0, 1, 0, 0.3, 0, 0, 1, 0.3, 0, 0, 0, 0.01;
  Eigen::Matrix4Xi t(4, 1);
  t << 0, 1, 2, 3;
  const TetMesh mesh(x, t, {Material{"m", 1, 1, 0}}, {0});
  const ElementQuality q = elementQualities(mesh).front();
  EXPECT_GT(q.aspectRatio, 10.0);
  EXPECT_LT(q.minDihedralAngle, 0.1);
  EXPECT_GT(q.maxDihedralAngle, 3.0);
}

TEST(MeshQueries, QualitySummarySpansTheElements) {
  // The regular tet and a flattened one: the smallest dihedral angle is the flattened
  // one's smallest, the largest its largest (not the largest of the elements' smallest
  // angles, which is the regular tet's acos(1/3)); the mean of the elements' smallest
  // angles lies halfway; only the flattened one is below 10 degrees. Tolerances: a few
  // ulps of the per-element values.
  Eigen::Matrix3Xd x(3, 8);
  x << 1, 1, -1, -1, 10, 11, 10, 10.3,  //
      1, -1, 1, -1, 0, 0, 1, 0.3,       //
      1, -1, -1, 1, 0, 0, 0, 0.01;
  Eigen::Matrix4Xi t(4, 2);
  t << 0, 4, 1, 5, 2, 6, 3, 7;
  const TetMesh mesh(x, t, {Material{"m", 1, 1, 0}}, {0, 0});
  const std::vector<ElementQuality> each = elementQualities(mesh);
  const double toDegrees = 180.0 / std::acos(-1.0);
  const QualitySummary s = summarizeQuality(mesh);
  const double regular = std::acos(1.0 / 3.0) * toDegrees;
  EXPECT_NEAR(s.minDihedralDegrees, each[1].minDihedralAngle * toDegrees, 1e-12);
  EXPECT_NEAR(s.maxDihedralDegrees, each[1].maxDihedralAngle * toDegrees, 1e-12);
  EXPECT_GT(s.maxDihedralDegrees, 170.0);
  EXPECT_NEAR(s.meanMinDihedralDegrees, 0.5 * (s.minDihedralDegrees + regular), 1e-12);
  EXPECT_EQ(s.thresholdDegrees, 10.0);
  EXPECT_EQ(s.elementsBelowThreshold, 1);
  EXPECT_EQ(summarizeQuality(mesh, regular + 1.0).elementsBelowThreshold, 2);
  EXPECT_EQ(summarizeQuality(mesh, 0.0).elementsBelowThreshold, 0);
  EXPECT_DOUBLE_EQ(s.worstAspectRatio, each[1].aspectRatio);
  const QualitySummary none = summarizeQuality(TetMesh());
  EXPECT_EQ(none.minDihedralDegrees, 0.0);
  EXPECT_EQ(none.maxDihedralDegrees, 0.0);
  EXPECT_EQ(none.worstAspectRatio, 0.0);
}

TEST(MeshQueries, UnusedVertices) {
  Eigen::Matrix3Xd x(3, 5);
  x << 0, 1, 0, 0, 5, 0, 0, 1, 0, 5, 0, 0, 0, 1, 5;
  Eigen::Matrix4Xi t(4, 1);
  t << 0, 1, 2, 3;
  const TetMesh mesh(x, t, {Material{"m", 1, 1, 0}}, {0});
  EXPECT_EQ(unusedVertices(mesh), std::vector<int>{4});
}

}  // namespace
}  // namespace asyncfem
