// SPDX-License-Identifier: BSD-3-Clause
// .veg MOONEYRIVLIN materials: reading, the derived small-strain E and nu, writing back,
// and one test per documented error (file, line and material named).
#include <gtest/gtest.h>

#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <string>

#include "testFiles.hpp"

namespace asyncfem {
namespace {

// Line 13 is *MATERIAL, line 14 the material line (see vegErrorsTest.cpp).
std::string vegWithMaterialLine(const std::string& materialLine) {
  return std::string(test::kTwoTetVertices) + std::string(test::kTwoTetElements) + "*MATERIAL rubber\n" + materialLine +
         "\n*REGION\nallElements, rubber\n";
}

TEST(VegMooneyRivlin, ReadsParametersAndDerivesSmallStrainModuli) {
  test::ScratchDir dir;
  const auto path = dir.write("rubber.veg", vegWithMaterialLine("MOONEYRIVLIN, 1100, 2e4, 8e4, 5e5"));
  const TetMesh mesh = readVeg(path);
  ASSERT_EQ(mesh.materials().size(), 1U);
  const Material& m = mesh.elementMaterial(1);
  EXPECT_EQ(m.name, "rubber");
  EXPECT_EQ(m.density, 1100.0);
  ASSERT_TRUE(m.mooneyRivlin.has_value());
  EXPECT_EQ(m.mooneyRivlin->mu01, 2e4);
  EXPECT_EQ(m.mooneyRivlin->mu10, 8e4);
  EXPECT_EQ(m.mooneyRivlin->v1, 5e5);
  // G = 2 (mu01 + mu10) = 2e5, K = 2 v1 = 1e6: E = 9 K G / (3 K + G), nu = (3K - 2G) / (2 (3K + G)),
  // computed here independently (relative 1e-14: a few roundings).
  const double shear = 2e5;
  const double bulk = 1e6;
  EXPECT_NEAR(m.youngsModulus, 9.0 * bulk * shear / (3.0 * bulk + shear), 1e-14 * m.youngsModulus);
  EXPECT_NEAR(m.poissonRatio, (3.0 * bulk - 2.0 * shear) / (2.0 * (3.0 * bulk + shear)), 1e-14);
}

TEST(VegMooneyRivlin, EnuMaterialsHaveNoMooneyRivlinBlock) {
  test::ScratchDir dir;
  const auto path = dir.write("steel.veg", vegWithMaterialLine("ENU, 7800, 2e11, 0.3"));
  const TetMesh mesh = readVeg(path);
  EXPECT_FALSE(mesh.materials().front().mooneyRivlin.has_value());
  EXPECT_EQ(mesh.materials().front().youngsModulus, 2e11);
}

TEST(VegMooneyRivlin, WriterRoundTripsMixedMaterials) {
  test::ScratchDir dir;
  const auto path = dir.write("rubber.veg", vegWithMaterialLine("MOONEYRIVLIN, 1100, 0.1, 3.3e4, 7.77e5"));
  TetMesh mesh = readVeg(path);
  mesh.setElementSet("second", {1});
  const int steel = mesh.addMaterial(Material{"steel", 7800.0, 2e11, 0.3});
  mesh.assignMaterial("second", steel);
  const auto written = dir.path() / "written.veg";
  writeVeg(written, mesh);
  const TetMesh again = readVeg(written);
  ASSERT_EQ(again.materials().size(), 2U);
  EXPECT_EQ(again.materials(), mesh.materials());
  EXPECT_EQ(again.elementMaterials(), mesh.elementMaterials());
}

TEST(VegMooneyRivlin, WrongNumberOfFields) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", vegWithMaterialLine("MOONEYRIVLIN, 1100, 2e4, 8e4"));
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 14,
                         {"material 'rubber'", "MOONEYRIVLIN needs exactly 4 numbers", "got 3"});
}

TEST(VegMooneyRivlin, NonNumericParameter) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", vegWithMaterialLine("MOONEYRIVLIN, 1100, soft, 8e4, 5e5"));
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 14, {"material 'rubber' mu01", "soft"});
}

TEST(VegMooneyRivlin, NonPositiveShearModulus) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", vegWithMaterialLine("MOONEYRIVLIN, 1100, -9e4, 8e4, 5e5"));
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 14, {"material 'rubber'", "mu01 + mu10 > 0"});
}

TEST(VegMooneyRivlin, NonPositiveBulkParameter) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", vegWithMaterialLine("MOONEYRIVLIN, 1100, 2e4, 8e4, 0"));
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 14, {"material 'rubber'", "v1 > 0"});
}

TEST(VegMooneyRivlin, NonPositiveDensity) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", vegWithMaterialLine("MOONEYRIVLIN, -1, 2e4, 8e4, 5e5"));
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 14, {"material 'rubber'", "density must be > 0"});
}

TEST(VegMooneyRivlin, UnknownMaterialKeywordNamesBothSupportedForms) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", vegWithMaterialLine("ORTHOTROPIC, 1100, 1, 2, 3"));
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 14, {"'ORTHOTROPIC'", "ENU", "MOONEYRIVLIN"});
}

}  // namespace
}  // namespace asyncfem
