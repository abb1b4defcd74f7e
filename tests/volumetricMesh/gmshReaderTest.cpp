// SPDX-License-Identifier: BSD-3-Clause
// Gmsh ASCII 2.2 and 4.1: arbitrary node tags, physical groups, mixed element types.
#include <gtest/gtest.h>

#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <string>

#include "testFiles.hpp"

namespace asyncfem {
namespace {

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  // Built by concatenation: GCC 12 warns (-Wrestrict) on std::string::replace at -O3.
  return text.substr(0, at) + to + text.substr(at + from.size());
}

// Line numbers matter for the error tests below.
const std::string kMsh22 =
    "$MeshFormat\n"            // 1
    "2.2 0 8\n"                // 2
    "$EndMeshFormat\n"         // 3
    "$PhysicalNames\n"         // 4
    "3\n"                      // 5
    "2 3 \"skin\"\n"           // 6
    "3 7 \"solid part\"\n"     // 7
    "3 9 \"unused\"\n"         // 8
    "$EndPhysicalNames\n"      // 9
    "$Nodes\n"                 // 10
    "5\n"                      // 11
    "10 0 0 0\n"               // 12
    "20 1 0 0\n"               // 13
    "30 0 1 0\n"               // 14
    "40 0 0 1\n"               // 15
    "55 1 1 1\n"               // 16
    "$EndNodes\n"              // 17
    "$Elements\n"              // 18
    "5\n"                      // 19
    "1 15 2 0 1 10\n"          // 20 point
    "2 1 2 0 1 10 20\n"        // 21 line
    "3 2 2 3 1 10 20 30\n"     // 22 triangle in physical surface 3
    "4 4 2 7 1 10 30 20 40\n"  // 23 tet, inverted, physical "solid part"
    "5 4 2 8 1 20 30 40 55\n"  // 24 tet, physical 8 without a name
    "$EndElements\n";          // 25

const std::string kMsh41 =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    "$PhysicalNames\n2\n2 5 \"skin\"\n3 7 \"solid\"\n$EndPhysicalNames\n"
    "$Entities\n"
    "0 0 1 1\n"
    "3 0 0 0 1 1 1 1 5 0\n"    // surface 3 in physical 5
    "1 0 0 0 1 1 1 1 7 1 3\n"  // volume 1 in physical 7, bounded by surface 3
    "$EndEntities\n"
    "$Nodes\n"
    "2 5 10 50\n"
    "2 3 0 2\n10\n20\n0 0 0\n1 0 0\n"
    "3 1 0 3\n30\n40\n50\n0 1 0\n0 0 1\n1 1 1\n"
    "$EndNodes\n"
    "$Elements\n"
    "2 3 1 3\n"
    "2 3 2 1\n1 10 20 30\n"
    "3 1 4 2\n2 10 20 30 40\n3 20 30 40 50\n"
    "$EndElements\n";

TEST(GmshReader, Version22MixedElementsAndPhysicalGroups) {
  test::ScratchDir dir;
  MeshReadReport report;
  const TetMesh mesh = readMesh(dir.write("m.msh", kMsh22), {}, &report);
  EXPECT_EQ(report.format, "gmsh 2.2");
  EXPECT_EQ(mesh.numVertices(), 5);
  EXPECT_EQ(mesh.numElements(), 2);
  EXPECT_EQ(report.ignoredElements, 3);
  EXPECT_EQ(report.reorientedElements, 1);
  EXPECT_EQ(mesh.elementSet("solid part"), std::vector<int>{0});
  EXPECT_EQ(mesh.elementSet("physical_8"), std::vector<int>{1});
  EXPECT_EQ(mesh.elementSets().count("unused"), 0u);
  // The triangle in physical surface 3 ("skin"): its nodes 10 20 30 are vertices 0 1 2.
  EXPECT_EQ(mesh.vertexSet("skin"), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(mesh.vertexSets().size(), 1u);  // the point and line are in no group (tag 0)
  // Tags 20 30 40 55 map to vertices 1 2 3 4.
  EXPECT_EQ(mesh.element(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_EQ(mesh.restPosition(4), Eigen::Vector3d(1, 1, 1));
  EXPECT_GT(signedElementVolume(mesh, 0), 0.0);
  bool ignoredWarning = false, defaultWarning = false;
  for (const auto& w : report.warnings) {
    ignoredWarning = ignoredWarning || w.find("ignored 3") != std::string::npos;
    defaultWarning = defaultWarning || w.find("default material") != std::string::npos;
  }
  EXPECT_TRUE(ignoredWarning);
  EXPECT_TRUE(defaultWarning);
}

TEST(GmshReader, Version41EntityBlocks) {
  test::ScratchDir dir;
  MeshReadReport report;
  const TetMesh mesh = readGmsh(dir.write("m.msh", kMsh41), {}, &report);
  EXPECT_EQ(report.format, "gmsh 4.1");
  EXPECT_EQ(mesh.numVertices(), 5);
  EXPECT_EQ(mesh.numElements(), 2);
  EXPECT_EQ(report.ignoredElements, 1);
  EXPECT_EQ(report.reorientedElements, 0);
  EXPECT_EQ(mesh.elementSet("solid"), (std::vector<int>{0, 1}));
  EXPECT_EQ(mesh.element(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_DOUBLE_EQ(totalVolume(mesh), 0.5);
  // The triangle of surface entity 3, in physical surface 5 ("skin").
  EXPECT_EQ(mesh.vertexSet("skin"), (std::vector<int>{0, 1, 2}));
}

// Physical points, curves and surfaces become vertex sets (the nodes of their elements),
// named from $PhysicalNames or physical_point_<tag>, physical_curve_<tag>,
// physical_surface_<tag>; tags are per dimension, so surface 7 and volume 7 differ.
TEST(GmshReader, LowerDimensionalPhysicalGroupsBecomeVertexSets) {
  test::ScratchDir dir;
  std::string text = replaced(kMsh22, "1 15 2 0 1 10\n", "1 15 2 4 1 55\n");
  text = replaced(text, "2 1 2 0 1 10 20\n", "2 1 2 6 1 10 40\n");
  text = replaced(text, "3 2 2 3 1 10 20 30\n", "3 2 2 7 1 10 20 30\n");
  const TetMesh mesh = readGmsh(dir.write("m.msh", text));
  EXPECT_EQ(mesh.vertexSet("physical_point_4"), std::vector<int>{4});
  EXPECT_EQ(mesh.vertexSet("physical_curve_6"), (std::vector<int>{0, 3}));
  EXPECT_EQ(mesh.vertexSet("physical_surface_7"), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(mesh.elementSet("solid part"), std::vector<int>{0});  // volume 7 is still the tet
  // 4.1: a point entity carries its physical tags after x y z.
  std::string text41 = replaced(kMsh41, "0 0 1 1\n", "1 0 1 1\n9 1 1 1 1 2\n");
  text41 = replaced(text41, "2 3 1 3\n", "3 4 1 4\n0 9 15 1\n4 50\n");
  const TetMesh mesh41 = readGmsh(dir.write("m41.msh", text41));
  EXPECT_EQ(mesh41.vertexSet("physical_point_2"), std::vector<int>{4});
  EXPECT_EQ(mesh41.vertexSet("skin"), (std::vector<int>{0, 1, 2}));
}

TEST(GmshReader, Version41UnnamedPhysicalGroup) {
  test::ScratchDir dir;
  const std::string text = replaced(kMsh41, "3 7 \"solid\"", "3 70 \"elsewhere\"");
  EXPECT_EQ(readGmsh(dir.write("m.msh", text)).elementSet("physical_7"), (std::vector<int>{0, 1}));
}

TEST(GmshReader, BinaryIsRejectedWithAdvice) {
  test::ScratchDir dir;
  const auto path = dir.write("b.msh", replaced(kMsh22, "2.2 0 8", "2.2 1 8"));
  test::expectParseError([&] { readGmsh(path); }, "b.msh", 2, {"binary", "ASCII"});
}

TEST(GmshReader, UnsupportedVersion) {
  test::ScratchDir dir;
  const auto path = dir.write("v.msh", replaced(kMsh22, "2.2 0 8", "3.0 0 8"));
  test::expectParseError([&] { readGmsh(path); }, "v.msh", 2, {"version '3.0'", "2.2 and 4.1"});
}

TEST(GmshReader, UndefinedNodeTag) {
  test::ScratchDir dir;
  const auto path = dir.write("n.msh", replaced(kMsh22, "5 4 2 8 1 20 30 40 55", "5 4 2 8 1 20 30 40 99"));
  test::expectParseError([&] { readGmsh(path); }, "n.msh", 24, {"element 5", "node 99"});
}

TEST(GmshReader, DuplicateNodeTag) {
  test::ScratchDir dir;
  const auto path = dir.write("d.msh", replaced(kMsh22, "40 0 0 1", "30 0 0 1"));
  test::expectParseError([&] { readGmsh(path); }, "d.msh", 15, {"duplicate node tag 30"});
}

TEST(GmshReader, FewerNodesThanHeader) {
  test::ScratchDir dir;
  const auto path = dir.write("f.msh", replaced(kMsh22, "$Nodes\n5\n", "$Nodes\n6\n"));
  test::expectParseError([&] { readGmsh(path); }, "f.msh", 11, {"6 nodes", "only 5"});
}

TEST(GmshReader, MoreElementsThanHeader) {
  test::ScratchDir dir;
  const auto path = dir.write("f.msh", replaced(kMsh22, "$Elements\n5\n", "$Elements\n4\n"));
  test::expectParseError([&] { readGmsh(path); }, "f.msh", 24, {"more element lines"});
}

TEST(GmshReader, NonNumericCoordinate) {
  test::ScratchDir dir;
  const auto path = dir.write("c.msh", replaced(kMsh22, "30 0 1 0", "30 0 1e 0"));
  test::expectParseError([&] { readGmsh(path); }, "c.msh", 14, {"node 30", "'1e'"});
}

TEST(GmshReader, AbsurdNodeCountFailsFast) {
  test::ScratchDir dir;
  const auto path = dir.write("a.msh", replaced(kMsh41, "2 5 10 50", "2 1000000000000 10 50"));
  test::expectParseError([&] { readGmsh(path); }, "a.msh", 15, {"1000000000000"});
}

TEST(GmshReader, SurfaceMeshHasNoTetrahedra) {
  test::ScratchDir dir;
  std::string text = replaced(kMsh22, "$Elements\n5\n", "$Elements\n3\n");
  text = replaced(text, "4 4 2 7 1 10 30 20 40\n5 4 2 8 1 20 30 40 55\n", "");
  const auto path = dir.write("s.msh", text);
  test::expectParseError([&] { readGmsh(path); }, "s.msh", 0, {"no tetrahedral elements"});
}

TEST(GmshReader, NotAGmshFile) {
  test::ScratchDir dir;
  const auto path = dir.write("x.msh", "solid stl\nendsolid\n");
  test::expectParseError([&] { readGmsh(path); }, "x.msh", 1, {"$MeshFormat"});
}

}  // namespace
}  // namespace asyncfem
