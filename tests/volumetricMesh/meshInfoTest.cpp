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
  EXPECT_NE(r.output.find("min dihedral angle"), std::string::npos);
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
  EXPECT_NEAR(j["quality"]["minDihedralAngleDegrees"]["min"].get<double>(), 45.0, 1e-9);
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

}  // namespace
}  // namespace asyncfem
