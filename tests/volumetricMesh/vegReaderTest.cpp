// SPDX-License-Identifier: BSD-3-Clause
// Reading valid .veg files: includes, comments, odd whitespace, line ends, the shipped beam.
#include <gtest/gtest.h>

#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <string>

#include "testFiles.hpp"

namespace asyncfem {
namespace {

const std::filesystem::path kData = std::filesystem::path(ASYNCFEM_TEST_DATA_DIR) / "volumetricMesh";

std::string twoTetVeg() {
  return std::string(test::kTwoTetVertices) + std::string(test::kTwoTetElements) + std::string(test::kSteelRegion);
}

TEST(VegReader, ReadsMinimalFile) {
  test::ScratchDir dir;
  MeshReadReport report;
  const TetMesh mesh = readVeg(dir.write("two.veg", twoTetVeg()), {}, &report);
  EXPECT_EQ(report.format, "veg");
  EXPECT_TRUE(report.warnings.empty());
  EXPECT_EQ(mesh.numVertices(), 5);
  EXPECT_EQ(mesh.numElements(), 2);
  ASSERT_EQ(mesh.materials().size(), 1u);
  EXPECT_EQ(mesh.materials()[0], (Material{"steel", 7800, 2e11, 0.3}));
  EXPECT_EQ(mesh.element(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_EQ(mesh.restPosition(4), Eigen::Vector3d(1, 1, 1));
  EXPECT_DOUBLE_EQ(totalVolume(mesh), 1.0 / 6.0 + 1.0 / 3.0);
}

TEST(VegReader, IncludeInsideSetBody) {
  MeshReadReport report;
  const TetMesh mesh = readMesh(kData / "includeSet.veg", {}, &report);
  ASSERT_EQ(mesh.numElements(), 2);
  EXPECT_EQ(mesh.elementSet("second"), std::vector<int>{1});
  EXPECT_EQ(mesh.elementMaterial(0).name, "soft");
  EXPECT_EQ(mesh.elementMaterial(1).name, "hard");
  EXPECT_EQ(mesh.elementMaterial(0).youngsModulus, 25e5);  // written 25E5
  EXPECT_EQ(mesh.elementMaterial(1).youngsModulus, 1000000000.0);
}

TEST(VegReader, CommentsOddWhitespaceAndSeveralRegions) {
  const TetMesh mesh = readVeg(kData / "oddWhitespace.veg");
  EXPECT_EQ(mesh.numVertices(), 5);
  EXPECT_EQ(mesh.restPosition(1), Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(mesh.restPosition(4), Eigen::Vector3d(1, 1, 1));
  EXPECT_EQ(mesh.elementSet("both"), (std::vector<int>{0, 1}));
  // The second *REGION block wins for element 1 (0-based 0).
  EXPECT_EQ(mesh.elementMaterial(0).name, "plastic");
  EXPECT_EQ(mesh.elementMaterial(1).name, "rubber");
}

TEST(VegReader, CrlfAndLoneCrLineEnds) {
  test::ScratchDir dir;
  std::string crlf, cr;
  for (char c : twoTetVeg()) {
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    cr += c == '\n' ? '\r' : c;
  }
  const TetMesh a = readVeg(dir.write("crlf.veg", crlf));
  const TetMesh b = readVeg(dir.write("cr.veg", cr));
  EXPECT_EQ(a.numElements(), 2);
  EXPECT_EQ(b.numElements(), 2);
  EXPECT_EQ(a.restPositions(), b.restPositions());
  // Line numbers stay right with CRLF: break element 2 (line 12) and look.
  std::string bad = crlf;
  bad.replace(bad.find("2 2 3 4 5"), 9, "2 2 3 4 9");
  test::expectParseError([&] { readVeg(dir.write("badcrlf.veg", bad)); }, "badcrlf.veg", 12, {"element 2", "vertex 9"});
}

TEST(VegReader, DefaultMaterialCoversElementsWithoutRegion) {
  test::ScratchDir dir;
  const std::string text = std::string(test::kTwoTetVertices) + std::string(test::kTwoTetElements) +
                           "*MATERIAL steel\nENU, 7800, 2e11, 0.3\n*SET one\n1\n*REGION\none, steel\n";
  MeshReadOptions options;
  options.defaultMaterial = Material{"filler", 10, 1e3, 0.2};
  const TetMesh mesh = readVeg(dir.write("partial.veg", text), options);
  EXPECT_EQ(mesh.elementMaterial(0).name, "steel");
  EXPECT_EQ(mesh.elementMaterial(1).name, "filler");
}

TEST(VegReader, ReorientsInvertedElementsAndCountsThem) {
  test::ScratchDir dir;
  std::string text = twoTetVeg();
  text.replace(text.find("1 1 2 3 4"), 9, "1 1 3 2 4");
  MeshReadReport report;
  const TetMesh mesh = readVeg(dir.write("inverted.veg", text), {}, &report);
  EXPECT_EQ(report.reorientedElements, 1);
  ASSERT_FALSE(report.warnings.empty());
  EXPECT_NE(report.warnings[0].find("reoriented 1"), std::string::npos);
  EXPECT_GT(signedElementVolume(mesh, 0), 0.0);
}

TEST(VegReader, UnusedVerticesAreReportedNotFatal) {
  test::ScratchDir dir;
  std::string text = twoTetVeg();
  text.replace(text.find("5 3 0 0"), 7, "6 3 0 0");
  text.replace(text.find("5 1 1 1\n"), 8, "5 1 1 1\n6 7 7 7\n");
  MeshReadReport report;
  const TetMesh mesh = readVeg(dir.write("unused.veg", text), {}, &report);
  EXPECT_EQ(mesh.numVertices(), 6);
  EXPECT_EQ(report.unusedVertices, 1);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("vertex 6"), std::string::npos) << report.warnings[0];
}

TEST(VegReader, ShippedBeamMatchesItsGenerator) {
  MeshReadReport report;
  const TetMesh beam = readMesh(std::filesystem::path(ASYNCFEM_MODELS_DIR) / "beam" / "beam.veg", {}, &report);
  EXPECT_TRUE(report.warnings.empty());
  BeamSpec spec;
  spec.cellsAlongLength = 30;
  const TetMesh expected = makeBeamMesh(spec);
  EXPECT_EQ(beam.numVertices(), 31 * 7 * 7);
  EXPECT_EQ(beam.numElements(), 30 * 6 * 6 * 6);
  // Written with round-trip precision, so everything matches bit for bit.
  EXPECT_EQ(beam.restPositions(), expected.restPositions());
  EXPECT_EQ(beam.elements(), expected.elements());
  EXPECT_EQ(beam.materials(), expected.materials());
  EXPECT_EQ(beam.elementMaterials(), expected.elementMaterials());
  EXPECT_EQ(beam.elementSets(), expected.elementSets());
  EXPECT_EQ(beam.vertexSets(), expected.vertexSets());
  EXPECT_EQ(beam.vertexSet("root").size(), 49u);
  EXPECT_EQ(beam.materials()[static_cast<std::size_t>(beam.findMaterial("tip"))].youngsModulus, 5e7);
}

TEST(VegReader, ReadBouAcceptsCommasWhitespaceAndComments) {
  test::ScratchDir dir;
  EXPECT_EQ(readBou(dir.write("fixed.bou", "# fixed\n3, 1,\n  2 \t5,\n\n1,\n"), 5), (std::vector<int>{0, 1, 2, 4}));
  EXPECT_TRUE(readBou(dir.write("empty.bou", ""), 5).empty());
  test::expectParseError([&] { readBou(dir.write("bad.bou", "1,\n2, 6\n"), 5); }, "bad.bou", 2, {"vertex 6", "[1, 5]"});
  test::expectParseError([&] { readBou(dir.write("nan.bou", "1, x2\n"), 5); }, "nan.bou", 1, {"'x2'"});
}

}  // namespace
}  // namespace asyncfem
