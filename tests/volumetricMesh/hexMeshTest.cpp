// SPDX-License-Identifier: BSD-3-Clause
// Hexahedral meshes: Vega CUBIC and Gmsh type-5 readers (good and bad files), the writers,
// the queries and the conversion into tetrahedra.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/hexToTets.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <fstream>
#include <sstream>
#include <string>

#include "testFiles.hpp"

namespace asyncfem {
namespace {

const std::filesystem::path kData = std::filesystem::path(ASYNCFEM_TEST_DATA_DIR) / "volumetricMesh";

/// Volume enclosed by the boundary triangles (divergence theorem): equals the mesh volume
/// only if the triangles close the surface and all point outward.
double enclosedVolume(const TetMesh& mesh) {
  double volume = 0.0;
  for (const auto& t : boundaryTriangles(mesh)) {
    volume += mesh.restPosition(t[0]).dot(mesh.restPosition(t[1]).cross(mesh.restPosition(t[2]))) / 6.0;
  }
  return volume;
}

TEST(HexMesh, ReadsVegaCubesWithIncludeSetsAndRegions) {
  MeshReadReport report;
  const TetMesh mesh = readMesh(kData / "cubes.veg", {}, &report);
  ASSERT_TRUE(mesh.isHexahedral());
  EXPECT_EQ(mesh.verticesPerElement(), 8);
  EXPECT_EQ(mesh.numVertices(), 18);
  EXPECT_EQ(mesh.numElements(), 4);
  EXPECT_EQ(report.reorientedElements, 0);
  EXPECT_EQ(mesh.elementSet("right"), (std::vector<int>{1, 3}));
  EXPECT_EQ(mesh.elementMaterial(0).name, "soft");
  EXPECT_EQ(mesh.elementMaterial(1).name, "stiff");
  EXPECT_EQ(mesh.elementMaterial(3).name, "stiff");
  // Element 1 of the file: vertices 1 2 5 4 10 11 14 13, 0-based.
  EXPECT_EQ(mesh.hexahedron(0), (Vector8i() << 0, 1, 4, 3, 9, 10, 13, 12).finished());
  // Cubes of side 0.5: volumes 0.125 each (2x2x2 Gauss is exact for det J); masses 1000
  // and 2000 per unit volume. Tolerances: a few roundings of numbers of order 1.
  EXPECT_NEAR(totalVolume(mesh), 0.5, 1e-14);
  EXPECT_NEAR(totalMass(mesh), 0.25 * 1000.0 + 0.25 * 2000.0, 1e-10);
  // 16 boundary quadrilaterals, two triangles each, closed and outward.
  EXPECT_EQ(boundaryTriangles(mesh).size(), 32U);
  EXPECT_NEAR(enclosedVolume(mesh), 0.5, 1e-14);
  EXPECT_EQ(mesh.setVertices("right").size(), 12U);
  EXPECT_TRUE(unusedVertices(mesh).empty());
}

TEST(HexMesh, TetrahedraOnlyCodeRefusesHexahedraByName) {
  const TetMesh mesh = readMesh(kData / "cubes.veg");
  try {
    (void)elementQuality(mesh, 0);
    ADD_FAILURE() << "expected a ValidationError";
  } catch (const ValidationError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("elementQuality"), std::string::npos) << message;
    EXPECT_NE(message.find("4 hexahedra"), std::string::npos) << message;
    EXPECT_NE(message.find("--hex-to-tets"), std::string::npos) << message;
  }
  // The tetrahedral accessors refuse too, instead of reading past the connectivity.
  EXPECT_THROW((void)mesh.elements(), ValidationError);
  EXPECT_THROW((void)mesh.elementRestPositions(0), ValidationError);
  const TetMesh tets = hexahedraToTetrahedra(mesh);
  EXPECT_THROW((void)tets.hexahedra(), ValidationError);
  EXPECT_NO_THROW(tets.requireTetrahedra("anything"));
}

TEST(HexMesh, VegAndVtuWritersKeepHexahedra) {
  const test::ScratchDir dir;
  const TetMesh mesh = readMesh(kData / "cubes.veg");
  writeVeg(dir.path() / "out.veg", mesh);
  const TetMesh again = readVeg(dir.path() / "out.veg");
  ASSERT_TRUE(again.isHexahedral());
  EXPECT_EQ(again.hexahedra(), mesh.hexahedra());
  EXPECT_EQ(again.restPositions(), mesh.restPositions());
  EXPECT_EQ(again.materials(), mesh.materials());
  EXPECT_EQ(again.elementMaterials(), mesh.elementMaterials());
  EXPECT_EQ(again.elementSets(), mesh.elementSets());

  writeVtu(dir.path() / "out.vtu", mesh, {}, {}, {}, VtuEncoding::ascii);
  std::ifstream in(dir.path() / "out.vtu");
  std::stringstream text;
  text << in.rdbuf();
  const std::string vtu = text.str();
  EXPECT_NE(vtu.find("NumberOfCells=\"4\""), std::string::npos);
  // Offsets 8, 16, 24, 32 and four cells of VTK_HEXAHEDRON (12).
  EXPECT_NE(vtu.find("8 16 24 32\n"), std::string::npos) << vtu;
  EXPECT_NE(vtu.find("12 12 12 12\n"), std::string::npos) << vtu;
  // The connectivity is the mesh's vertex order (first element: 0 1 4 3 9 10 13 12).
  EXPECT_NE(vtu.find("0 1 4 3 9 10 13 12"), std::string::npos) << vtu;
}

/// A one-cube CUBIC .veg of side 1 with vertices as given (8 lines "x y z") and the element
/// line as given; the header is on line 13, the element on line 14.
std::string oneCube(const std::string& vertices, const std::string& element, const std::string& header = "1 8 0") {
  return "*VERTICES\n8 3 0 0\n" + vertices + "*ELEMENTS\nCUBIC\n" + header + "\n" + element +
         "\n*MATERIAL m\nENU, 1000, 1e6, 0.45\n*REGION\nallElements, m\n";
}
const std::string kCubeVertices = "1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0 0 1\n6 1 0 1\n7 1 1 1\n8 0 1 1\n";

TEST(HexMesh, VegCubicErrorsNameFileLineAndElement) {
  const test::ScratchDir dir;
  // The good cube reads.
  EXPECT_EQ(readVeg(dir.write("good.veg", oneCube(kCubeVertices, "1 1 2 3 4 5 6 7 8"))).numElements(), 1);
  // Vega's order swapped at vertices 2 and 3: not the cube Vega assumes.
  test::expectParseError([&] { readVeg(dir.write("order.veg", oneCube(kCubeVertices, "1 1 2 4 3 5 6 7 8"))); },
                         "order.veg", 14, {"element 1", "not an axis-aligned cube", "vertex 2 (file vertex 4)"});
  // A sheared cube.
  test::expectParseError(
      [&] {
        readVeg(dir.write("shear.veg", oneCube("1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0.3 0 1\n6 1.3 0 1\n7 1.3 1 "
                                               "1\n8 0.3 1 1\n",
                                               "1 1 2 3 4 5 6 7 8")));
      },
      "shear.veg", 14, {"element 1", "not an axis-aligned cube of side 1", "vertex 4 (file vertex 5)"});
  // Two vertices at one position (a collapsed edge).
  test::expectParseError(
      [&] {
        readVeg(dir.write(
            "collapsed.veg",
            oneCube("1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0 0 1\n6 1 0 1\n7 1 1 1\n8 1 1 1\n", "1 1 2 3 4 5 6 7 8")));
      },
      "collapsed.veg", 14, {"element 1 is collapsed", "vertex 6 (file vertex 7)", "vertex 7 (file vertex 8)"});
  test::expectParseError([&] { readVeg(dir.write("twice.veg", oneCube(kCubeVertices, "1 1 2 3 4 5 6 7 7"))); },
                         "twice.veg", 14, {"element 1 uses vertex 7 twice"});
  test::expectParseError([&] { readVeg(dir.write("header.veg", oneCube(kCubeVertices, "1 1 2 3 4", "1 4 0"))); },
                         "header.veg", 13, {"CUBIC elements have 8 vertices"});
  test::expectParseError([&] { readVeg(dir.write("short.veg", oneCube(kCubeVertices, "1 1 2 3 4 5 6 7"))); },
                         "short.veg", 14, {"element line needs 'index v1 ... v8'"});
}

TEST(HexMesh, VegCubesMustShareElementOnesSide) {
  const test::ScratchDir dir;
  // Two cubes along x, the second twice as large (Vega would give it the first one's side).
  const std::string text = "*VERTICES\n16 3 0 0\n" + kCubeVertices +
                           "9 1 0 0\n10 3 0 0\n11 3 2 0\n12 1 2 0\n13 1 0 2\n14 3 0 2\n15 3 2 2\n16 1 2 2\n"
                           "*ELEMENTS\nCUBIC\n2 8 0\n1 1 2 3 4 5 6 7 8\n2 9 10 11 12 13 14 15 16\n"
                           "*MATERIAL m\nENU, 1000, 1e6, 0.45\n*REGION\nallElements, m\n";
  test::expectParseError([&] { readVeg(dir.write("sizes.veg", text)); }, "sizes.veg", 23,
                         {"element 2", "not an axis-aligned cube of side 1", "file vertex 10"});
}

/// A Gmsh 2.2 file with the cube's 8 nodes and the given element lines.
std::string gmshCube(const std::string& elements, int count) {
  return "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 7 \"block\"\n$EndPhysicalNames\n$Nodes\n8\n" +
         kCubeVertices + "$EndNodes\n$Elements\n" + std::to_string(count) + "\n" + elements + "$EndElements\n";
}

TEST(HexMesh, GmshHexahedraWithPhysicalGroups) {
  const test::ScratchDir dir;
  MeshReadReport report;
  const TetMesh mesh =
      readGmsh(dir.write("cube.msh", gmshCube("1 3 2 0 1 1 2 3 4\n2 5 2 7 1 1 2 3 4 5 6 7 8\n", 2)), {}, &report);
  ASSERT_TRUE(mesh.isHexahedral());
  EXPECT_EQ(mesh.numElements(), 1);
  EXPECT_EQ(mesh.elementSet("block"), std::vector<int>{0});
  EXPECT_EQ(report.ignoredElements, 1);  // the quadrangle (type 3)
  EXPECT_NEAR(totalVolume(mesh), 1.0, 1e-14);

  // Top and bottom faces swapped: negative Jacobian at every corner, reoriented.
  const TetMesh turned = readGmsh(dir.write("turned.msh", gmshCube("1 5 2 7 1 5 6 7 8 1 2 3 4\n", 1)), {}, &report);
  EXPECT_EQ(report.reorientedElements, 1);
  EXPECT_NEAR(totalVolume(turned), 1.0, 1e-14);
  MeshReadOptions strict;
  strict.reorientInvertedElements = false;
  test::expectParseError([&] { readGmsh(dir.path() / "turned.msh", strict); }, "turned.msh", 21,
                         {"element 1 is inverted"});
}

TEST(HexMesh, GmshBadHexahedraAreNamed) {
  const test::ScratchDir dir;
  // Vertices 2 and 3 swapped: the bottom face is a bow tie, inverted at some corners only.
  test::expectParseError([&] { readGmsh(dir.write("twisted.msh", gmshCube("4 5 2 7 1 1 2 4 3 5 6 7 8\n", 1))); },
                         "twisted.msh", 21, {"element 4 has a non-positive Jacobian at its vertex", "order"});
  test::expectParseError(
      [&] { readGmsh(dir.write("mixed.msh", gmshCube("1 5 2 7 1 1 2 3 4 5 6 7 8\n2 4 2 7 1 1 2 4 5\n", 2))); },
      "mixed.msh", 22,
      {"element 2 is a 4-node tetrahedron", "mixed tetrahedral and hexahedral meshes are not supported"});
  test::expectParseError([&] { readGmsh(dir.write("fields.msh", gmshCube("1 5 2 7 1 1 2 3 4 5 6 7\n", 1))); },
                         "fields.msh", 21, {"element 1 (8-node hexahedron) needs 13 fields"});
}

TEST(HexMesh, SixTetsPerCubeConformAndKeepVolumeMaterialsAndSets) {
  const TetMesh hexes = readMesh(kData / "cubes.veg");
  const TetMesh tets = hexahedraToTetrahedra(hexes);
  ASSERT_FALSE(tets.isHexahedral());
  EXPECT_EQ(tets.numElements(), 24);
  for (int e = 0; e < tets.numElements(); ++e) {
    EXPECT_GT(signedElementVolume(tets, e), 0.0) << "tet " << e;
    EXPECT_EQ(tets.elementMaterialIndex(e), hexes.elementMaterialIndex(e / 6));
  }
  EXPECT_NEAR(totalVolume(tets), 0.5, 1e-14);
  EXPECT_NEAR(totalMass(tets), totalMass(hexes), 1e-12);
  // Conforming: a face the two splits triangulated differently would show up as boundary.
  EXPECT_EQ(boundaryTriangles(tets).size(), 32U);
  EXPECT_NEAR(enclosedVolume(tets), 0.5, 1e-14);
  EXPECT_EQ(tets.elementSet("right").size(), 12U);
  EXPECT_EQ(tets.setVertices("right"), hexes.setVertices("right"));
}

TEST(HexMesh, ConversionRefusesFacesSplitAlongDifferentDiagonals) {
  // Two unit cubes along x; the second's corner (2, 1, 0) pulled down so that its smallest
  // x + y + z is there: its split cuts the shared face x = 1 along the other diagonal.
  Eigen::Matrix3Xd x(3, 12);
  x << 0, 1, 1, 0, 0, 1, 1, 0, 2, 2, 2, 2,  //
      0, 0, 1, 1, 0, 0, 1, 1, 0, 1, 0, 1,   //
      0, 0, 0, 0, 1, 1, 1, 1, 0, -2.5, 1, 1;
  HexElements h(8, 2);
  h.col(0) << 0, 1, 2, 3, 4, 5, 6, 7;
  h.col(1) << 1, 8, 9, 2, 5, 10, 11, 6;
  const TetMesh mesh(x, h, {Material{"m", 1000, 1e6, 0.3}}, {0, 0});
  try {
    (void)hexahedraToTetrahedra(mesh);
    ADD_FAILURE() << "expected a ValidationError";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("hexahedra 0 and 1 share a face"), std::string::npos) << e.what();
  }
}

TEST(HexMesh, CornerJacobiansAndQualityOfDistortedAndInvertedElements) {
  // A box 2 x 1 x 0.5: scaled Jacobian 1 at every corner, det of the corner edges = 1.
  Eigen::Matrix<double, 3, 8> box;
  for (int a = 0; a < 8; ++a) {
    const auto& c = hexahedron::kCorners[static_cast<std::size_t>(a)];
    box.col(a) = Eigen::Vector3d((c[0] + 1) * 1.0, (c[1] + 1) * 0.5, (c[2] + 1) * 0.25);
  }
  EXPECT_NEAR(hexahedron::signedVolume(box), 1.0, 1e-15);
  for (int a = 0; a < 8; ++a) {
    EXPECT_NEAR(hexahedron::cornerScaledJacobians(box)[a], 1.0, 1e-15);
    EXPECT_NEAR(hexahedron::cornerJacobians(box)[a], 1.0, 1e-15);
  }
  // Pushing vertex 6 through the element inverts it at that corner only.
  Eigen::Matrix<double, 3, 8> dented = box;
  dented.col(6) = Eigen::Vector3d(0.2, 0.2, 0.1);
  Eigen::Matrix3Xd positions(3, 16);
  positions << box, dented;
  HexElements h(8, 2);
  h.col(0) << 0, 1, 2, 3, 4, 5, 6, 7;
  h.col(1) << 8, 9, 10, 11, 12, 13, 14, 15;
  const TetMesh mesh(positions, h, {Material{"m", 1000, 1e6, 0.3}}, {0, 0});
  const HexahedronQuality q = hexahedronQuality(mesh, 1);
  EXPECT_LT(q.minScaledJacobian, 0.0);
  EXPECT_EQ(q.worstCorner, 6);
  const HexahedronQualitySummary s = summarizeHexahedronQuality(mesh);
  EXPECT_EQ(s.invertedElements, std::vector<int>{1});
  EXPECT_NEAR(hexahedronQuality(mesh, 0).minScaledJacobian, 1.0, 1e-15);
  EXPECT_NEAR(hexahedronQuality(mesh, 0).edgeRatio, 4.0, 1e-15);
}

}  // namespace
}  // namespace asyncfem
