// SPDX-License-Identifier: BSD-3-Clause
// meshInfo end to end: runs the built executable and checks its output and exit status.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <asyncfem/volumetricMesh/readers.hpp>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "testFiles.hpp"

namespace asyncfem {
namespace {

struct RunResult {
  int exitCode = -1;
  std::string output;  ///< stdout and stderr together
};

RunResult runMeshInfo(const std::string& arguments, bool withStderr = true) {
  std::string command = ASYNCFEM_BIN_DIR;
  command += "/meshInfo ";
  command += arguments;
  command += withStderr ? " 2>&1" : " 2>/dev/null";
  RunResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) result.output.append(buffer, n);
  const int status = ::pclose(pipe);
  result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

/// The argument in double quotes (built by appending: GCC 12 gives a false -Wrestrict
/// warning for "literal" + std::string).
std::string quoted(const std::string& argument) {
  std::string q(1, '"');
  q += argument;
  q += '"';
  return q;
}

const std::string kBeam = std::string(ASYNCFEM_MODELS_DIR) + "/beam/beam.veg";

TEST(MeshInfo, PrintsSummaryOfShippedBeam) {
  const RunResult r = runMeshInfo(quoted(kBeam));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("vertices: 1519"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("elements: 6480"), std::string::npos);
  EXPECT_NE(r.output.find("format: veg"), std::string::npos);
  EXPECT_NE(r.output.find("tip: density 200"), std::string::npos);
  EXPECT_NE(r.output.find("root: 49"), std::string::npos);
  // The beam's cube tets have dihedral angles of 45, 60 and 90 degrees only (printed with round-off).
  EXPECT_NE(r.output.find("dihedral angles (degrees): min 44.9999"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("elements with a dihedral angle below 10.0 degrees: 0\n"), std::string::npos) << r.output;
}

TEST(MeshInfo, JsonOutput) {
  const RunResult r = runMeshInfo("--json " + quoted(kBeam), false);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["vertices"], 1519);
  EXPECT_EQ(j["elements"], 6480);
  EXPECT_EQ(j["materials"].size(), 2u);
  EXPECT_EQ(j["elementSets"]["tip"], 1296);
  EXPECT_NEAR(j["volume"].get<double>(), 0.04, 1e-12);
  // body 1000 * 0.032 + tip 200 * 0.008
  EXPECT_NEAR(j["mass"].get<double>(), 33.6, 1e-9);
  // Angles of the cube's tets: 45, 60 and 90 degrees (1e-9: round-off of acos/atan2).
  const nlohmann::json& quality = j["quality"];
  EXPECT_NEAR(quality["dihedralAngleDegrees"]["min"].get<double>(), 45.0, 1e-9);
  EXPECT_NEAR(quality["dihedralAngleDegrees"]["max"].get<double>(), 90.0, 1e-9);
  EXPECT_NEAR(quality["meanElementMinDihedralAngleDegrees"].get<double>(), 45.0, 1e-9);
  EXPECT_EQ(quality["elementsBelowAngle"]["count"], 0);
  // --angle-threshold 50: every element has its 45 degree angle below it.
  const RunResult strict = runMeshInfo("--json --angle-threshold 50 " + quoted(kBeam), false);
  ASSERT_EQ(strict.exitCode, 0) << strict.output;
  const nlohmann::json s = nlohmann::json::parse(strict.output)["quality"]["elementsBelowAngle"];
  EXPECT_EQ(s["thresholdDegrees"], 50.0);
  EXPECT_EQ(s["count"], 6480);
}

// A Gmsh group name with a space cannot go into .veg: the error says how to rename it, and
// --rename-set does; --default-material replaces the format's default material.
TEST(MeshInfo, RenameSetAndDefaultMaterial) {
  test::ScratchDir dir;
  const auto msh = dir.write("g.msh",
                             "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 3 \"fixed face\"\n"
                             "$EndPhysicalNames\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                             "$Elements\n2\n1 2 2 3 1 1 2 3\n2 4 2 0 1 1 2 3 4\n$EndElements\n");
  const auto out = dir.path() / "g.veg";
  const RunResult refused = runMeshInfo(quoted(msh.string()) + " --write " + quoted(out.string()));
  EXPECT_EQ(refused.exitCode, 1);
  EXPECT_NE(
      refused.output.find("vertex set name 'fixed face' cannot be written to .veg (it must be one token "
                          "without spaces, commas or '#'); rename it with meshInfo --rename-set 'fixed face=NEW'"),
      std::string::npos)
      << refused.output;
  const RunResult renamed = runMeshInfo(quoted(msh.string()) + " --write " + quoted(out.string()) +
                                        " --rename-set 'fixed face=fixedFace' --default-material 1100,2e5,0.3");
  ASSERT_EQ(renamed.exitCode, 0) << renamed.output;
  EXPECT_EQ(renamed.output.find("the file has no materials"), std::string::npos) << renamed.output;
  const TetMesh written = readVeg(out);
  EXPECT_EQ(written.vertexSet("fixedFace"), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(written.materials().at(0), (Material{"default", 1100, 2e5, 0.3}));
  const RunResult unknown = runMeshInfo(quoted(msh.string()) + " --rename-set nope=x");
  EXPECT_EQ(unknown.exitCode, 1);
  EXPECT_NE(unknown.output.find("unknown set 'nope' (vertex sets: fixed face;"), std::string::npos) << unknown.output;
  const RunResult malformed = runMeshInfo(quoted(msh.string()) + " --rename-set nope");
  EXPECT_EQ(malformed.exitCode, 2);
  EXPECT_NE(malformed.output.find("--rename-set 'nope': expected OLD=NEW"), std::string::npos) << malformed.output;
}

TEST(MeshInfo, GenerateAndWrite) {
  test::ScratchDir dir;
  const auto out = dir.path() / "box.veg";
  const RunResult r = runMeshInfo("--generate box --cells 2 --write " + quoted(out.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("elements: 48"), std::string::npos) << r.output;
  EXPECT_EQ(readVeg(out).numElements(), 48);
  const RunResult vtu = runMeshInfo("--generate beam --cells 5 --write " + quoted((dir.path() / "b.vtu").string()));
  EXPECT_EQ(vtu.exitCode, 0) << vtu.output;
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "b.vtu"));
}

TEST(MeshInfo, GeneratesTheCellModels) {
  test::ScratchDir dir;
  // --cells sets the rod's (tentacles') length in cells: 4 rod cells add 4 layers of 4 vertices;
  // the fast region is the rod's 20 vertices plus 28 block vertices around its foot.
  const auto antenna = dir.path() / "antenna.veg";
  const RunResult r = runMeshInfo("--generate antenna --cells 4 --write " + quoted(antenna.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("rodAndRing: 48"), std::string::npos) << r.output;
  EXPECT_EQ(readVeg(antenna).numVertices(), 11 * 5 * 11 + 4 * 4);
  const RunResult snail = runMeshInfo("--generate snail");
  ASSERT_EQ(snail.exitCode, 0) << snail.output;
  EXPECT_NE(snail.output.find("tentaclesAndRing: 88"), std::string::npos) << snail.output;
}

TEST(MeshInfo, BadFileExitsWithMessage) {
  test::ScratchDir dir;
  const auto bad = dir.write("bad.veg", "*VERTICES\n1 3 0 0\n1 0 0 zero\n");
  const RunResult r = runMeshInfo(quoted(bad.string()));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.output.find("meshInfo: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bad.veg:3: "), std::string::npos) << r.output;
  const RunResult missing = runMeshInfo(quoted((dir.path() / "none.veg").string()));
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.output.find("none.veg"), std::string::npos) << missing.output;
}

TEST(MeshInfo, WarningsGoToStderr) {
  test::ScratchDir dir;
  dir.write("m.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  dir.write("m.ele", "1 4 0\n1 1 2 3 4\n");
  const RunResult quiet = runMeshInfo(quoted((dir.path() / "m.node").string()), false);
  EXPECT_EQ(quiet.exitCode, 0);
  EXPECT_EQ(quiet.output.find("warning"), std::string::npos);
  const RunResult loud = runMeshInfo(quoted((dir.path() / "m.node").string()), true);
  EXPECT_NE(loud.output.find("meshInfo: warning: "), std::string::npos) << loud.output;
}

const std::string kCubes = std::string(ASYNCFEM_TEST_DATA_DIR) + "/volumetricMesh/cubes.veg";

TEST(MeshInfo, HexahedralMeshQualityInJson) {
  const RunResult r = runMeshInfo(quoted(kCubes) + " --json", false);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["elementKind"], "hexahedra");
  EXPECT_EQ(j["elements"], 4);
  EXPECT_EQ(j["boundaryTriangles"], 32);
  // Exact cubes: every corner's scaled Jacobian is 1 up to a rounding of its terms.
  EXPECT_NEAR(j["quality"]["scaledJacobian"]["min"].get<double>(), 1.0, 1e-15);
  EXPECT_TRUE(j["quality"]["invertedElements"].empty());
}

TEST(MeshInfo, HexToTetsConvertsAndWrites) {
  const test::ScratchDir dir;
  const std::string out = (dir.path() / "tets.veg").string();
  const RunResult r = runMeshInfo(quoted(kCubes) + " --hex-to-tets --write " + quoted(out));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("split 4 hexahedra into 24 tetrahedra"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("elements: 24\n"), std::string::npos) << r.output;
  const TetMesh tets = readMesh(out);
  EXPECT_FALSE(tets.isHexahedral());
  EXPECT_EQ(tets.numElements(), 24);
  EXPECT_EQ(tets.elementSet("right").size(), 12U);
  // On a tetrahedral mesh the option is an error.
  const RunResult again = runMeshInfo(quoted(out) + " --hex-to-tets");
  EXPECT_EQ(again.exitCode, 1);
  EXPECT_NE(again.output.find("holds tetrahedra already"), std::string::npos) << again.output;
}

}  // namespace
}  // namespace asyncfem
