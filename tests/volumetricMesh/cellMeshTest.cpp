// SPDX-License-Identifier: BSD-3-Clause
// makeCellMesh (unions of lattice cells) and the two models built with it, the antenna on
// a block and the snail: counts, sets, conformity (tests/tetMesher/modelsTest.cpp checks
// the shipped files against them).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace asyncfem {
namespace {

/// Area of the boundary: for a conforming union of cells it is the area of the union's
/// surface; a non-conforming seam would add its faces twice.
double boundaryArea(const TetMesh& mesh) {
  double area = 0.0;
  for (const auto& t : boundaryTriangles(mesh)) {
    const Eigen::Vector3d a = mesh.restPosition(t[0]), b = mesh.restPosition(t[1]), c = mesh.restPosition(t[2]);
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

/// Triangles shared by an element of set a and an element of set b.
int sharedFaces(const TetMesh& mesh, const std::vector<int>& a, const std::vector<int>& b) {
  std::map<std::array<int, 3>, int> faceOwner;  // sorted face -> 1 (a) or 2 (b)
  int shared = 0;
  auto visit = [&](const std::vector<int>& set, int tag) {
    for (int e : set)
      for (int skip = 0; skip < 4; ++skip) {
        std::array<int, 3> face{};
        for (int k = 0, f = 0; k < 4; ++k)
          if (k != skip) face[static_cast<std::size_t>(f++)] = mesh.elements()(k, e);
        std::sort(face.begin(), face.end());
        auto [it, inserted] = faceOwner.emplace(face, tag);
        if (!inserted && it->second != tag) ++shared;
      }
  };
  visit(a, 1);
  visit(b, 2);
  return shared;
}

void expectPositiveVolumes(const TetMesh& mesh, double cellSize) {
  // Each Freudenthal tet of a cube of edge s has volume s^3 / 6 exactly (up to round-off
  // of a few ulps of s^3: tolerance 1e-9 relative).
  for (int e = 0; e < mesh.numElements(); ++e) {
    EXPECT_NEAR(signedElementVolume(mesh, e), std::pow(cellSize, 3) / 6.0, 1e-9 * std::pow(cellSize, 3)) << e;
  }
}

TEST(CellMesh, UnionOfBlocksIsConformingWithPerNameSets) {
  // An L of two blocks plus a one-cell post on top; the post is claimed twice (the later
  // block wins its cell).
  CellMeshSpec spec;
  spec.cellSize = 0.5;
  spec.origin = Eigen::Vector3d(1, 2, 3);
  const Material soft{"soft", 1000, 1e5, 0.3}, hard{"hard", 100, 1e7, 0.3};
  spec.blocks = {
      {"base", {0, 0, 0}, {3, 1, 2}, soft}, {"base", {0, 0, 2}, {1, 1, 3}, soft}, {"post", {1, 0, 0}, {2, 3, 1}, hard}};
  spec.vertexRings = {{"postRing", {"post"}, 1}};
  const TetMesh mesh = makeCellMesh(spec);
  // Cells: 6 + 1 in "base", of which "post" takes (1, 0, 0), plus 2 above: 6 + 3.
  EXPECT_EQ(mesh.numElements(), 6 * 9);
  EXPECT_EQ(mesh.elementSet("base").size(), 6u * 6u);
  EXPECT_EQ(mesh.elementSet("post").size(), 6u * 3u);
  // Lattice points: 4 x 2 x 3 under the base's first block, 2 x 2 more for the second,
  // 2 x 2 x 2 above the base for the post.
  EXPECT_EQ(mesh.numVertices(), 24 + 4 + 8);
  EXPECT_TRUE(unusedVertices(mesh).empty());
  expectPositiveVolumes(mesh, 0.5);
  ASSERT_EQ(mesh.materials().size(), 2u);
  EXPECT_EQ(mesh.elementMaterial(mesh.elementSet("post").front()), hard);
  // The lowest layer (y = 2) holds the bottom set.
  EXPECT_EQ(mesh.vertexSet("bottom").size(), 4u * 3u + 2u);
  for (int v : mesh.vertexSet("bottom")) EXPECT_EQ(mesh.restPosition(v).y(), 2.0);
  // Surface, in cell faces of 0.25: the 3 x 1 x 2 box (22) plus the tab (6 faces, one
  // glued: +4) plus the 1 x 2 x 1 column on top (10 faces' worth, one glued: +8). Exact
  // up to round-off.
  EXPECT_NEAR(boundaryArea(mesh), 0.25 * (22 + 4 + 8), 1e-12);
}

TEST(CellMesh, BadSpecsAreErrors) {
  CellMeshSpec spec;
  EXPECT_THROW(makeCellMesh(spec), ValidationError);  // no blocks
  spec.blocks = {{"a", {0, 0, 0}, {1, 0, 1}, {}}};
  EXPECT_THROW(makeCellMesh(spec), ValidationError);  // empty block
  spec.blocks = {{"a", {0, 0, 0}, {1, 1, 1}, {"m", 1000, 1e6, 0.3}}, {"b", {1, 0, 0}, {2, 1, 1}, {"m", 500, 1e6, 0.3}}};
  EXPECT_THROW(makeCellMesh(spec), ValidationError);  // one material name, two values
  spec.blocks.pop_back();
  spec.vertexRings = {{"ring", {"nothing"}, 1}};
  EXPECT_THROW(makeCellMesh(spec), ValidationError);  // ring around an unknown set
  spec.vertexRings.clear();
  spec.cellSize = 0.0;
  EXPECT_THROW(makeCellMesh(spec), ValidationError);
}

TEST(CellMesh, AntennaOnABlock) {
  const TetMesh mesh = makeAntennaMesh();
  // Block 10 x 4 x 10 cells (11 x 5 x 11 points), rod 1 x 8 x 1 cells (8 layers of 4 more).
  EXPECT_EQ(mesh.numVertices(), 11 * 5 * 11 + 8 * 4);
  EXPECT_EQ(mesh.numElements(), 6 * (10 * 4 * 10 + 8));
  EXPECT_EQ(mesh.elementSet("block").size(), 6u * 400u);
  EXPECT_EQ(mesh.elementSet("rod").size(), 6u * 8u);
  EXPECT_EQ(mesh.vertexSet("bottom").size(), 121u);
  // 1,548 free DOFs: the size the shared design note's scene uses.
  EXPECT_EQ(3 * (mesh.numVertices() - static_cast<int>(mesh.vertexSet("bottom").size())), 1548);
  expectPositiveVolumes(mesh, 0.05);
  // Conforming: the rod's foot square (two triangles) is shared with the block, and the
  // boundary is the union's surface: block 2 (0.25 + 0.1 + 0.1) plus the rod's four sides.
  EXPECT_EQ(sharedFaces(mesh, mesh.elementSet("rod"), mesh.elementSet("block")), 2);
  EXPECT_NEAR(boundaryArea(mesh), 0.9 + 4 * 0.05 * 0.4, 1e-12);
  // The rod stands on the centre cell (5, 5) of the top face, 0.2 m up, 0.4 m tall.
  for (int v : mesh.vertexSet("rodTip")) {
    EXPECT_NEAR(mesh.restPosition(v).y(), 0.6, 1e-12);
    EXPECT_GE(mesh.restPosition(v).x(), 0.25 - 1e-12);
    EXPECT_LE(mesh.restPosition(v).x(), 0.30 + 1e-12);
  }
  EXPECT_EQ(mesh.vertexSet("rodTip").size(), 4u);
  // The fast region: the rod's 36 vertices plus one ring of block vertices around its foot
  // (4 x 4 on the top layer, 4 x 4 on the one below, the foot's 4 counted once): 64.
  const std::vector<int>& region = mesh.vertexSet("rodAndRing");
  EXPECT_EQ(mesh.vertexSet("rod").size(), 36u);
  EXPECT_EQ(region.size(), 64u);
  EXPECT_TRUE(std::includes(region.begin(), region.end(), mesh.vertexSet("rod").begin(), mesh.vertexSet("rod").end()));
  for (int v : region) EXPECT_GE(mesh.restPosition(v).y(), 0.15 - 1e-12);
  EXPECT_EQ(mesh.elementMaterial(mesh.elementSet("rod").front()), (Material{"rod", 100.0, 1e6, 0.3}));
  EXPECT_EQ(mesh.elementMaterial(mesh.elementSet("block").front()), (Material{"block", 1000.0, 1e6, 0.3}));
}

// The whip: the rod's top cells in their own lighter material, the nested regions' sets.
TEST(CellMesh, AntennaWithAWhip) {
  AntennaSpec spec;
  spec.whipCells = 4;
  const TetMesh mesh = makeAntennaMesh(spec);
  const TetMesh plain = makeAntennaMesh();
  EXPECT_EQ(mesh.numVertices(), plain.numVertices());
  EXPECT_EQ(mesh.elementSet("whip").size(), 6u * 4u);
  EXPECT_EQ(mesh.elementSet("rod").size(), 6u * 4u);
  EXPECT_EQ(mesh.elementMaterial(mesh.elementSet("whip").front()), (Material{"whip", 10.0, 1e6, 0.3}));
  // The whip's 5 layers of 4 vertices; its foot layer is shared with the rod.
  EXPECT_EQ(mesh.vertexSet("whip").size(), 20u);
  EXPECT_EQ(mesh.vertexSet("rodTip"), plain.vertexSet("rodTip"));
  EXPECT_EQ(mesh.vertexSet("rodAndRing"), plain.vertexSet("rodAndRing"));
  const std::vector<int>& below = mesh.vertexSet("rodAndRingBelowWhip");
  EXPECT_EQ(below.size(), 64u - 20u);
  for (int v : mesh.vertexSet("whip")) EXPECT_FALSE(std::binary_search(below.begin(), below.end(), v));
  spec.whipCells = spec.rodCells;
  EXPECT_THROW(makeAntennaMesh(spec), ValidationError);
}

TEST(CellMesh, SnailHasTwoSeparateTentaclesOnItsHead) {
  const TetMesh mesh = makeSnailMesh();
  EXPECT_LE(mesh.numVertices(), 1000);  // the dense modal reference stays affordable
  expectPositiveVolumes(mesh, 0.05);
  EXPECT_TRUE(unusedVertices(mesh).empty());
  // Each tentacle: 6 cells of one-cell cross-section, sharing its foot square with the head.
  EXPECT_EQ(mesh.elementSet("tentacles").size(), 2u * 6u * 6u);
  EXPECT_EQ(sharedFaces(mesh, mesh.elementSet("tentacles"), mesh.elementSet("head")), 4);
  EXPECT_EQ(sharedFaces(mesh, mesh.elementSet("tentacles"), mesh.elementSet("shell")), 0);
  EXPECT_EQ(mesh.vertexSet("tentacleTips").size(), 8u);
  const std::vector<int>& region = mesh.vertexSet("tentaclesAndRing");
  const std::vector<int>& tentacles = mesh.vertexSet("tentacles");
  EXPECT_TRUE(std::includes(region.begin(), region.end(), tentacles.begin(), tentacles.end()));
  // |S| much smaller than n, and no fixed vertex in S.
  EXPECT_LT(5 * region.size(), static_cast<std::size_t>(mesh.numVertices()));
  for (int v : mesh.vertexSet("bottom")) EXPECT_FALSE(std::binary_search(region.begin(), region.end(), v));
  // The region is the tentacles plus head vertices only: its ring stays off the shell.
  const std::set<int> shell(mesh.vertexSet("shell").begin(), mesh.vertexSet("shell").end());
  for (int v : region) EXPECT_EQ(shell.count(v), 0u) << v;
}

}  // namespace
}  // namespace asyncfem
