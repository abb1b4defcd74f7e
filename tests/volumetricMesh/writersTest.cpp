// SPDX-License-Identifier: BSD-3-Clause
// writeVeg round trip (bit-exact) and writeVtu content.
#include "testFiles.hpp"

#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <sstream>

namespace asyncfem {
namespace {

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void expectSameMesh(const TetMesh& a, const TetMesh& b) {
  ASSERT_EQ(a.numVertices(), b.numVertices());
  // Bitwise: the writer prints enough digits to reproduce each double exactly.
  EXPECT_EQ(std::memcmp(a.restPositions().data(), b.restPositions().data(),
                        sizeof(double) * static_cast<std::size_t>(a.restPositions().size())),
            0);
  EXPECT_EQ(a.elements(), b.elements());
  EXPECT_EQ(a.materials(), b.materials());
  EXPECT_EQ(a.elementMaterials(), b.elementMaterials());
  EXPECT_EQ(a.elementSets(), b.elementSets());
  EXPECT_EQ(a.vertexSets(), b.vertexSets());
}

TEST(MeshWriters, VegRoundTripIsExact) {
  test::ScratchDir dir;
  BoxMeshSpec spec;
  // Coordinates such as 0.1 + k/3 have no short decimal form.
  spec.origin = Eigen::Vector3d(0.1, -1.0 / 3.0, 1e-7);
  spec.size = Eigen::Vector3d(std::sqrt(2.0), 1.0 / 7.0, 3.3);
  spec.cells = Eigen::Vector3i(3, 2, 2);
  spec.material = Material{"base", 1234.5678901234567, 3.3e7, 0.4999};
  // Overlapping regions: material sets then differ from every element set, so the
  // writer must add its own region sets without them reappearing after reading.
  spec.regions.push_back({"left", Eigen::Vector3d(-9, -9, -9), Eigen::Vector3d(0.8, 9, 9), Material{"soft", 900, 1e5, 0.3}});
  spec.regions.push_back({"front", Eigen::Vector3d(-9, -9, -9), Eigen::Vector3d(9, 9, 1.0), Material{"hard", 7800, 2e11, 0.29}});
  const TetMesh mesh = makeBoxMesh(spec);
  const auto path = dir.path() / "box.veg";
  writeVeg(path, mesh);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "box.veg.tmp"));
  MeshReadReport report;
  const TetMesh back = readVeg(path, {}, &report);
  EXPECT_TRUE(report.warnings.empty());
  expectSameMesh(mesh, back);
}

TEST(MeshWriters, VegRoundTripOfBeamAndUnusedMaterial) {
  test::ScratchDir dir;
  TetMesh beam = makeBeamMesh(BeamSpec{});
  beam.addMaterial(Material{"spare", 1, 2, 0.1});
  const auto path = dir.path() / "beam.veg";
  writeVeg(path, beam);
  expectSameMesh(beam, readVeg(path));
}

TEST(MeshWriters, VegRejectsNamesItCannotWrite) {
  test::ScratchDir dir;
  TetMesh mesh = makeBoxMesh(BoxMeshSpec{});
  mesh.setElementSet("two words", {0});
  EXPECT_THROW(writeVeg(dir.path() / "x.veg", mesh), ValidationError);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "x.veg"));
}

TEST(MeshWriters, UnwritablePathIsAnError) {
  test::ScratchDir dir;
  EXPECT_THROW(writeVeg(dir.path() / "no" / "such" / "dir.veg", makeBoxMesh(BoxMeshSpec{})), Error);
}

TEST(MeshWriters, VtuHasPointsCellsMaterialsAndArrays) {
  test::ScratchDir dir;
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i(1, 1, 1);
  const TetMesh mesh = makeBoxMesh(spec);
  Eigen::VectorXd u = Eigen::VectorXd::Constant(mesh.numDofs(), 0.5);
  VtuArray speed{"speed", 1, std::vector<double>(static_cast<std::size_t>(mesh.numVertices()), 2.0)};
  VtuArray stress{"stress", 3, std::vector<double>(3 * static_cast<std::size_t>(mesh.numElements()), 1.0)};
  const auto path = dir.path() / "box.vtu";
  writeVtu(path, mesh, u, {speed}, {stress});
  const std::string text = slurp(path);
  EXPECT_NE(text.find("<VTKFile type=\"UnstructuredGrid\""), std::string::npos);
  EXPECT_NE(text.find("NumberOfPoints=\"8\" NumberOfCells=\"6\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"material\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"displacement\" NumberOfComponents=\"3\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"speed\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"stress\" NumberOfComponents=\"3\""), std::string::npos);
  EXPECT_NE(text.find(" 10 10 10 10 10 10\n"), std::string::npos);  // VTK_TETRA
  EXPECT_NE(text.find("1.5 1.5 1.5"), std::string::npos);          // displaced far corner

  VtuArray wrong{"wrong", 1, {1.0}};
  EXPECT_THROW(writeVtu(path, mesh, {}, {wrong}), ValidationError);
  EXPECT_THROW(writeVtu(path, mesh, Eigen::VectorXd::Zero(2)), ValidationError);
}

}  // namespace
}  // namespace asyncfem
