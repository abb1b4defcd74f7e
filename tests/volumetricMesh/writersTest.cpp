// SPDX-License-Identifier: BSD-3-Clause
// writeVeg round trip (bit-exact), writeVtu content in both encodings, writePvd.
#include <gtest/gtest.h>

#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <sstream>

#include "testFiles.hpp"

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
  spec.regions.push_back(
      {"left", Eigen::Vector3d(-9, -9, -9), Eigen::Vector3d(0.8, 9, 9), Material{"soft", 900, 1e5, 0.3}});
  spec.regions.push_back(
      {"front", Eigen::Vector3d(-9, -9, -9), Eigen::Vector3d(9, 9, 1.0), Material{"hard", 7800, 2e11, 0.29}});
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

/// What a minimal .vtu reader sees: the attributes of the VTKFile and AppendedData tags,
/// and every DataArray's values as doubles (the Points array is named "Points").
struct VtuContents {
  std::map<std::string, std::string> file;
  std::map<std::string, std::string> appended;
  std::map<std::string, std::map<std::string, std::string>> attributes;
  std::map<std::string, std::vector<double>> arrays;
};

std::map<std::string, std::string> tagAttributes(const std::string& tag) {
  std::map<std::string, std::string> attributes;
  const std::regex attribute("([A-Za-z_]+)=\"([^\"]*)\"");
  for (auto it = std::sregex_iterator(tag.begin(), tag.end(), attribute); it != std::sregex_iterator(); ++it) {
    attributes[(*it)[1]] = (*it)[2];
  }
  return attributes;
}

template <typename T>
std::vector<double> decode(const std::string& text, std::size_t at, std::size_t bytes) {
  std::vector<double> values(bytes / sizeof(T));
  for (std::size_t i = 0; i < values.size(); ++i) {
    T value;
    std::memcpy(&value, text.data() + at + i * sizeof(T), sizeof(T));
    values[i] = static_cast<double>(value);
  }
  return values;
}

/// Reads the XML tags up to the appended block, then each appended array as a UInt64
/// byte count followed by raw little-endian values (VTK's header_type="UInt64" layout).
VtuContents readVtuFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  VtuContents vtu;
  const std::size_t fileTag = text.find("<VTKFile");
  vtu.file = tagAttributes(text.substr(fileTag, text.find('>', fileTag) - fileTag));
  const std::size_t appendedTag = text.find("<AppendedData");
  const std::size_t xmlEnd = appendedTag == std::string::npos ? text.size() : appendedTag;
  std::size_t appendedBase = 0;
  if (appendedTag != std::string::npos) {
    const std::size_t tagEnd = text.find('>', appendedTag);
    vtu.appended = tagAttributes(text.substr(appendedTag, tagEnd - appendedTag));
    appendedBase = text.find('_', tagEnd) + 1;
  }
  for (std::size_t at = text.find("<DataArray"); at < xmlEnd; at = text.find("<DataArray", at + 1)) {
    const std::size_t tagEnd = text.find('>', at);
    std::map<std::string, std::string> attributes = tagAttributes(text.substr(at, tagEnd - at));
    const std::string name = attributes.count("Name") ? attributes["Name"] : "Points";
    const std::string& type = attributes["type"];
    std::vector<double>& values = vtu.arrays[name];
    if (attributes["format"] == "appended") {
      const std::size_t start = appendedBase + std::stoull(attributes["offset"]);
      std::uint64_t bytes = 0;
      std::memcpy(&bytes, text.data() + start, sizeof(bytes));
      const std::size_t data = start + sizeof(bytes);
      if (type == "Float64") values = decode<double>(text, data, bytes);
      if (type == "Int32") values = decode<std::int32_t>(text, data, bytes);
      if (type == "UInt8") values = decode<std::uint8_t>(text, data, bytes);
    } else {
      std::istringstream numbers(text.substr(tagEnd + 1, text.find("</DataArray>", tagEnd) - tagEnd - 1));
      for (double value = 0; numbers >> value;) values.push_back(value);
    }
    vtu.attributes[name] = std::move(attributes);
  }
  return vtu;
}

std::vector<double> asVector(const double* data, Eigen::Index size) { return {data, data + size}; }

TEST(MeshWriters, VtuBinaryAndAsciiHoldTheSameExactValues) {
  test::ScratchDir dir;
  const TetMesh mesh = makeBeamMesh(BeamSpec{});
  // Values without short decimal forms, so that the ASCII writer must print them exactly.
  Eigen::VectorXd u(mesh.numDofs());
  for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = std::sin(0.37 * static_cast<double>(i)) / 3.0;
  VtuArray speed{"speed", 1, std::vector<double>(static_cast<std::size_t>(mesh.numVertices()), 1.0 / 7.0)};
  VtuArray stress{"stress", 3, std::vector<double>(3 * static_cast<std::size_t>(mesh.numElements()), -2.5e-9)};
  writeVtu(dir.path() / "binary.vtu", mesh, u, {speed}, {stress});
  writeVtu(dir.path() / "ascii.vtu", mesh, u, {speed}, {stress}, VtuEncoding::ascii);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "binary.vtu.tmp"));

  const VtuContents binary = readVtuFile(dir.path() / "binary.vtu");
  const VtuContents ascii = readVtuFile(dir.path() / "ascii.vtu");
  EXPECT_EQ(binary.file.at("type"), "UnstructuredGrid");
  EXPECT_EQ(binary.file.at("header_type"), "UInt64");
  EXPECT_EQ(binary.file.at("byte_order"), "LittleEndian");
  EXPECT_EQ(binary.appended.at("encoding"), "raw");
  EXPECT_EQ(binary.attributes.at("displacement").at("format"), "appended");
  EXPECT_EQ(ascii.attributes.at("displacement").at("format"), "ascii");
  EXPECT_TRUE(ascii.appended.empty());

  // Same arrays, same values, bit for bit.
  ASSERT_EQ(binary.arrays.size(), 8U);  // displacement speed material stress Points connectivity offsets types
  EXPECT_EQ(binary.arrays, ascii.arrays);
  // Points are the rest positions; the deformation is only in "displacement", so that
  // Warp By Vector applies it once.
  EXPECT_EQ(binary.arrays.at("Points"), asVector(mesh.restPositions().data(), mesh.restPositions().size()));
  EXPECT_EQ(binary.arrays.at("displacement"), asVector(u.data(), u.size()));
  EXPECT_EQ(binary.arrays.at("speed"), speed.values);
  EXPECT_EQ(binary.arrays.at("stress"), stress.values);
  EXPECT_EQ(binary.attributes.at("displacement").at("NumberOfComponents"), "3");
  const std::vector<double>& connectivity = binary.arrays.at("connectivity");
  ASSERT_EQ(connectivity.size(), 4 * static_cast<std::size_t>(mesh.numElements()));
  for (int e = 0; e < mesh.numElements(); ++e) {
    for (int corner = 0; corner < 4; ++corner) {
      EXPECT_EQ(connectivity[static_cast<std::size_t>(4 * e + corner)], mesh.element(e)[corner]);
    }
  }
  EXPECT_EQ(binary.arrays.at("offsets").back(), 4.0 * mesh.numElements());
  EXPECT_EQ(binary.arrays.at("types"), std::vector<double>(static_cast<std::size_t>(mesh.numElements()), 10.0));
  EXPECT_EQ(binary.arrays.at("material"),
            std::vector<double>(mesh.elementMaterials().begin(), mesh.elementMaterials().end()));

  // The binary file is the raw values (8 bytes per double, 4 per index, 1 per type), one
  // 8-byte count per array and about 1.5 KB of XML; ASCII needs up to 24 characters for
  // a double such as sin(k)/3.
  const auto n = static_cast<std::uintmax_t>(mesh.numVertices());
  const auto m = static_cast<std::uintmax_t>(mesh.numElements());
  const std::uintmax_t rawBytes = 8 * (3 * n + n + 3 * n) + 8 * 3 * m + 4 * m + 4 * 4 * m + 4 * m + m + 8 * 8;
  const auto binaryBytes = std::filesystem::file_size(dir.path() / "binary.vtu");
  const auto asciiBytes = std::filesystem::file_size(dir.path() / "ascii.vtu");
  EXPECT_GT(binaryBytes, rawBytes);
  EXPECT_LT(binaryBytes, rawBytes + 2048);
  EXPECT_LT(binaryBytes, asciiBytes);
}

TEST(MeshWriters, VtuWithoutDisplacementAndBadArrays) {
  test::ScratchDir dir;
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i(1, 1, 1);
  const TetMesh mesh = makeBoxMesh(spec);
  const auto path = dir.path() / "box.vtu";
  writeVtu(path, mesh, {}, {}, {}, VtuEncoding::ascii);
  const std::string text = slurp(path);
  EXPECT_NE(text.find("NumberOfPoints=\"8\" NumberOfCells=\"6\""), std::string::npos);
  EXPECT_NE(text.find(" 10 10 10 10 10 10\n"), std::string::npos);  // VTK_TETRA
  EXPECT_EQ(text.find("displacement"), std::string::npos);
  EXPECT_EQ(readVtuFile(path).arrays.size(), 5U);  // material Points connectivity offsets types

  VtuArray wrong{"wrong", 1, {1.0}};
  EXPECT_THROW(writeVtu(path, mesh, {}, {wrong}), ValidationError);
  EXPECT_THROW(writeVtu(path, mesh, Eigen::VectorXd::Zero(2)), ValidationError);
  VtuArray twoComponents{"pair", 2, std::vector<double>(16, 0.0)};
  EXPECT_THROW(writeVtu(path, mesh, {}, {twoComponents}), ValidationError);
}

TEST(MeshWriters, PvdListsFramesWithTheirTimes) {
  test::ScratchDir dir;
  const auto path = dir.path() / "frames.pvd";
  writePvd(path, {{0.05, "frame_00000.vtu"}, {0.1, "frame_00001.vtu"}});
  writePvd(path, {{0.05, "frame_00000.vtu"}, {0.1, "frame_00001.vtu"}, {1.0 / 3.0, "a&b.vtu"}});
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "frames.pvd.tmp"));
  const std::string text = slurp(path);
  EXPECT_NE(text.find("<VTKFile type=\"Collection\""), std::string::npos);
  EXPECT_NE(text.find("<DataSet timestep=\"0.05\" group=\"\" part=\"0\" file=\"frame_00000.vtu\"/>"),
            std::string::npos);
  EXPECT_NE(text.find("timestep=\"0.1\""), std::string::npos);
  EXPECT_NE(text.find("timestep=\"0.3333333333333333\""), std::string::npos);
  EXPECT_NE(text.find("file=\"a&amp;b.vtu\""), std::string::npos);
  EXPECT_NE(text.find("</Collection>\n</VTKFile>\n"), std::string::npos);
  EXPECT_THROW(writePvd(dir.path() / "missing" / "x.pvd", {}), Error);
}

}  // namespace
}  // namespace asyncfem
