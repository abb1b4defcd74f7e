// SPDX-License-Identifier: BSD-3-Clause
// The error conventions every utility shares (docs/utilities.md): "PROGRAM: message" on
// stderr, status 2 for usage errors found before any work, 1 for other errors; outputs
// that are inputs refused. Runs the built executables.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "utilityTest.hpp"

namespace {

namespace fs = std::filesystem;

using asyncfem::test::readText;
using asyncfem::test::RunResult;

class UtilityErrorsTest : public asyncfem::test::UtilityTest {
 protected:
  /// Runs PROGRAM (in ASYNCFEM_BIN_DIR) with the arguments, in the scratch folder.
  RunResult run(const std::string& program, const std::string& arguments) const {
    return runCommand("cd '" + folder_.string() + "' && '" + std::string(ASYNCFEM_BIN_DIR) + "/" + program + "' " +
                      arguments);
  }

  /// A small scene on a generated box (its own folder's scene.json).
  fs::path writeScene() const {
    const fs::path path = folder_ / "scene.json";
    std::ofstream(path) << R"({
      "mesh": {"generator": "box", "size": [3, 1, 1], "cells": [3, 1, 1]},
      "fixed": {"sets": ["xmin"]},
      "integrator": {"name": "backward-euler", "timestep": 0.01},
      "frames": {"rate": 20, "count": 2}
    })";
    return path;
  }
};

TEST_F(UtilityErrorsTest, UsageErrorsArePrefixedAndExitWithTwo) {
  for (const std::string program :
       {"meshInfo", "proposeRegions", "tetMesher", "offlineSimulator", "integratorBenchmark", "stabilityStressTest"}) {
    const RunResult r = run(program, "--no-such-option x");
    EXPECT_EQ(r.exitCode, 2) << program << ": " << r.err;
    EXPECT_EQ(r.err.rfind(program + ": ", 0), 0U) << r.err;
    EXPECT_NE(r.err.find("(see --help)"), std::string::npos) << r.err;
    EXPECT_EQ(run(program, "--help").exitCode, 0) << program;
  }
  // Range errors read as a bound, not as CLI11's "not in range 2.2e-308 to 1.797...e+308".
  const RunResult negative = run("proposeRegions", "scene.json --dt -1");
  EXPECT_EQ(negative.exitCode, 2);
  EXPECT_EQ(negative.err, "proposeRegions: --dt: must be > 0 (got -1) (see --help)\n");
  const RunResult cells = run("meshInfo", "--generate beam --cells 0");
  EXPECT_EQ(cells.exitCode, 2);
  EXPECT_EQ(cells.err, "meshInfo: --cells: must be in [1, 1000] (got 0) (see --help)\n");
}

TEST_F(UtilityErrorsTest, MeshInfoChecksTheOutputExtensionFirst) {
  const RunResult r = run("meshInfo", "--generate beam --write x.stl");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err,
            "meshInfo: --write: cannot write 'x.stl': unknown extension '.stl' (supported: .veg, .vtu) (see "
            "--help)\n");
  EXPECT_TRUE(r.out.empty()) << r.out;  // nothing generated or printed
}

TEST_F(UtilityErrorsTest, MeshInfoReadsATetGenBaseName) {
  std::ofstream(folder_ / "cube.node") << "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
  std::ofstream(folder_ / "cube.ele") << "1 4 0\n1 1 2 3 4\n";
  const RunResult r = run("meshInfo", "cube");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("format: tetgen"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("elements: 1"), std::string::npos) << r.out;
}

TEST_F(UtilityErrorsTest, ProposeRegionsRefusesToWriteOverItsInput) {
  const fs::path scene = writeScene();
  const std::string text = readText(scene);
  fs::create_symlink(scene, folder_ / "link.json");
  for (const std::string target : {"scene.json", "./scene.json", "link.json"}) {
    const RunResult r = run("proposeRegions", "scene.json --write " + target);
    EXPECT_EQ(r.exitCode, 1) << target;
    EXPECT_EQ(r.err, "proposeRegions: --write " + target +
                         " is the scene scene.json: writing it would destroy the "
                         "input; write the regions to another file\n");
  }
  EXPECT_EQ(readText(scene), text);
}

// Every configuration is checked before the (expensive) reference is computed.
TEST_F(UtilityErrorsTest, IntegratorBenchmarkRejectsABadConfigurationFirst) {
  writeScene();
  const RunResult r = run("integratorBenchmark", "scene.json --quick --out out --config runge-kutta:spf=2");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("integratorBenchmark: configuration \"runge-kutta"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("unknown integrator \"runge-kutta\""), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("Reference:"), std::string::npos) << r.out;
}

// proposeRegions proposes what the simulator would run: an async scene's "auto" settings
// (here maxRatio 2) apply, and a typo inside "auto" is an unknown key there too.
TEST_F(UtilityErrorsTest, ProposeRegionsHonoursTheScenesAutoSettings) {
  std::ofstream(folder_ / "scene.json") << R"({
    "mesh": {"generator": "box", "size": [1, 0.25, 0.25], "cells": [8, 2, 2],
             "material": {"density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.4},
             "regions": [{"name": "tip", "min": [0.75, -1, -1], "max": [2, 2, 2],
                          "material": {"density": 200, "youngsModulus": 5e6, "poissonRatio": 0.3}}]},
    "fixed": {"sets": ["xmin"]},
    "integrator": {"name": "async", "timestep": 0.1,
                   "options": {"regions": "auto", "auto": {"maxRatio": 2, "modalCheck": false}}},
    "frames": {"rate": 10, "count": 1}
  })";
  const RunResult r = run("proposeRegions", "scene.json --json");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const nlohmann::json proposal = nlohmann::json::parse(r.out);
  ASSERT_FALSE(proposal.at("regions").empty()) << r.out;
  for (const auto& region : proposal.at("regions")) EXPECT_LE(region.at("ratio").get<int>(), 2) << r.out;
  // An explicit option replaces the scene's.
  const RunResult wider = run("proposeRegions", "scene.json --json --max-ratio 64");
  ASSERT_EQ(wider.exitCode, 0) << wider.err;
  EXPECT_GT(nlohmann::json::parse(wider.out).at("regions").at(0).at("ratio").get<int>(), 2) << wider.out;
  // With --modes the modal report is part of the one JSON document (nothing else on stdout).
  const RunResult withModes = run("proposeRegions", "scene.json --json --modes 3");
  ASSERT_EQ(withModes.exitCode, 0) << withModes.err;
  const nlohmann::json document = nlohmann::json::parse(withModes.out);
  ASSERT_EQ(document.at("modes").at("modes").size(), 3U) << withModes.out;
  EXPECT_GT(document.at("modes").at("modes").at(0).at("omega").get<double>(), 0.0);
  EXPECT_FALSE(document.at("modes").at("verdict").get<std::string>().empty());

  std::ofstream(folder_ / "typo.json") << R"({
    "mesh": {"generator": "box", "size": [1, 0.25, 0.25], "cells": [8, 2, 2]},
    "fixed": {"sets": ["xmin"]},
    "integrator": {"name": "async", "timestep": 0.1, "options": {"auto": {"maxRatoi": 2}}},
    "frames": {"rate": 10, "count": 1}
  })";
  const RunResult typo = run("proposeRegions", "typo.json");
  EXPECT_EQ(typo.exitCode, 1);
  EXPECT_NE(typo.err.find("typo.json: integrator.options.auto.maxRatoi"), std::string::npos) << typo.err;
  const RunResult simulator = run("offlineSimulator", "typo.json -o out.afsim");
  EXPECT_EQ(simulator.exitCode, 1);
  EXPECT_NE(simulator.err.find("typo.json: integrator.options.auto.maxRatoi"), std::string::npos) << simulator.err;
}

// A bare mesh is fixed by a box or a Vega .bou file as well as by a named set: the three
// ways give the same proposal when they select the same vertices (the beam's root face,
// x = 0), and a box selecting nothing or a missing .bou file is named by its option.
// A scene with run-time regions: proposeRegions runs its first steps and lists every
// partition its policies chose, with the cost model's price against single-rate at hL.
// The ball falls for about 50 large steps before its contact patch needs a region.
TEST_F(UtilityErrorsTest, ProposeRegionsExplainsRunTimeRegions) {
  const RunResult result =
      run("proposeRegions", std::string("'") + ASYNCFEM_MODELS_DIR + "/ball/ball.json' --adaptive-steps 70");
  ASSERT_EQ(result.exitCode, 0) << result.err;
  EXPECT_NE(result.out.find("the scene chooses its regions at run time"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("\"contact\""), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("ran 70 large steps"), std::string::npos) << result.out;
  // The first partition is the empty one (priced 1.00), a later one has the contact ratio.
  EXPECT_NE(result.out.find("\n0-"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find(" 8 "), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("expected cost per large step"), std::string::npos) << result.out;
}

TEST_F(UtilityErrorsTest, ProposeRegionsFixesABareMeshByBoxOrBouFile) {
  const std::string beam = std::string("'") + ASYNCFEM_MODELS_DIR + "/beam/beam.veg' --dt 0.0083333 --json";
  const RunResult bySet = run("proposeRegions", beam + " --fixed-set xmin");
  ASSERT_EQ(bySet.exitCode, 0) << bySet.err;
  const RunResult byBox = run("proposeRegions", beam + " --fixed-box -1 -1 -1 1e-9 1 1");
  ASSERT_EQ(byBox.exitCode, 0) << byBox.err;
  // The .bou file of the same vertices: Vega's 1-based ids, one a line.
  std::ofstream bou(folder_ / "root.bou");
  std::ifstream veg(std::string(ASYNCFEM_MODELS_DIR) + "/beam/beam.veg");
  std::string line;
  bool vertices = false;
  while (std::getline(veg, line)) {
    if (line.rfind("*VERTICES", 0) == 0) {
      vertices = true;
      std::getline(veg, line);  // the count line
      continue;
    }
    if (line.rfind("*", 0) == 0) vertices = false;
    int id = 0;
    double x = 1.0;
    if (vertices && std::sscanf(line.c_str(), "%d %lf", &id, &x) == 2 && x == 0.0) bou << id << "\n";
  }
  bou.close();
  const RunResult byBou = run("proposeRegions", beam + " --fixed-bou root.bou");
  ASSERT_EQ(byBou.exitCode, 0) << byBou.err;
  EXPECT_EQ(byBox.out, bySet.out);
  EXPECT_EQ(byBou.out, bySet.out);
  // A scene fixes its vertices with its own "fixed" key: the options are refused there.
  writeScene();
  const RunResult scene = run("proposeRegions", "scene.json --fixed-box 0 0 0 1 1 1");
  EXPECT_EQ(scene.exitCode, 1);
  EXPECT_NE(scene.err.find("mesh inputs only"), std::string::npos) << scene.err;

  const RunResult empty = run("proposeRegions", beam + " --fixed-box 5 5 5 6 6 6");
  EXPECT_EQ(empty.exitCode, 1);
  EXPECT_NE(empty.err.find("--fixed-box #1: "), std::string::npos) << empty.err;
  const RunResult missing = run("proposeRegions", beam + " --fixed-bou missing.bou");
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.err.find("--fixed-bou: "), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("missing.bou"), std::string::npos) << missing.err;
}

}  // namespace
