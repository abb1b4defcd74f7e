// SPDX-License-Identifier: BSD-3-Clause
// A Vega FEM simulator config run as it is: offlineSimulator runs the .config, and
// frameRenderer draws the run with the config's secondary render mesh placed by its .interp
// weights. Bad inputs stop either program with a message naming the file and line.
#include <gtest/gtest.h>

#include <asyncfem/simulationIO/simulationFile.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "utilityTest.hpp"

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;
using asyncfem::test::RunResult;

const std::string simulatorPath = std::string(ASYNCFEM_BIN_DIR) + "/offlineSimulator";
const std::string rendererPath = std::string(ASYNCFEM_BIN_DIR) + "/frameRenderer";
const fs::path vegaData = fs::path(ASYNCFEM_TEST_DATA_DIR) / "vega";

class VegaConfigRun : public asyncfem::test::UtilityTest {
 protected:
  void SetUp() override {
    UtilityTest::SetUp();
    for (const char* name : {"cantilever.config", "bar.veg", "bar-root.bou", "bar-box.obj", "bar-box.interp"}) {
      fs::copy_file(vegaData / name, folder_ / name);
    }
  }
  RunResult runIn(const std::string& program, const std::string& arguments) const {
    return runCommand("cd '" + folder_.string() + "' && '" + program + "' " + arguments);
  }
};

TEST_F(VegaConfigRun, SimulatesAndRendersTheEmbeddedMesh) {
  const RunResult simulated = runIn(simulatorPath, "cantilever.config --output run.afsim --frames 3 --quiet");
  ASSERT_EQ(simulated.exitCode, 0) << simulated.err;
  SimulationReader reader(folder_ / "run.afsim");
  ASSERT_EQ(reader.numFrames(), 3);
  ASSERT_EQ(reader.numVertices(), 81);
  // One Vega frame is *timestep (0.01 s); 1e-12 covers the rounding of 1 / (1 / 0.01).
  EXPECT_NEAR(reader.header().frameInterval, 0.01, 1e-12);
  const SimulationFrame last = reader.readFrame(2);
  EXPECT_NEAR(last.time, 0.03, 1e-12);
  // The .bou's root vertices (1-based 1, 10, ..., 73) stay exactly at rest; gravity (*addGravity
  // true) pulls the free tip down.
  for (int vertex = 0; vertex < 81; vertex += 9) {
    EXPECT_EQ(last.displacement.segment<3>(3 * vertex).norm(), 0.0) << vertex;
  }
  EXPECT_LT(last.displacement(3 * 8 + 1), 0.0);

  const RunResult rendered = runIn(rendererPath, "run.afsim --output frames --width 64 --height 48");
  ASSERT_EQ(rendered.exitCode, 0) << rendered.err;
  EXPECT_NE(rendered.out.find("bar-box.obj, 20 vertices, 36 triangles"), std::string::npos) << rendered.out;
  for (const char* frame : {"frame_00000.png", "frame_00001.png", "frame_00002.png"}) {
    EXPECT_TRUE(fs::exists(folder_ / "frames" / frame)) << frame;
  }
  // The same weights given on the command line.
  const RunResult explicitWeights = runIn(
      rendererPath, "run.afsim --mesh bar.veg --render-mesh bar-box.obj --interp bar-box.interp --output f2 --quiet");
  EXPECT_EQ(explicitWeights.exitCode, 0) << explicitWeights.err;
  EXPECT_TRUE(fs::exists(folder_ / "f2" / "frame_00002.png"));
}

TEST_F(VegaConfigRun, BadWeightsStopTheRenderer) {
  const RunResult simulated = runIn(simulatorPath, "cantilever.config --output run.afsim --frames 1 --quiet");
  ASSERT_EQ(simulated.exitCode, 0) << simulated.err;
  // A vertex index out of range on line 2.
  std::ofstream(folder_ / "bar-box.interp") << "0 0 0.25 1 0.25 2 0.25 3 0.25\n1 0 0.25 1 0.25 2 0.25 81 0.25\n";
  const RunResult outOfRange = runIn(rendererPath, "run.afsim --output frames --quiet");
  EXPECT_EQ(outOfRange.exitCode, 1);
  EXPECT_NE(outOfRange.err.find("bar-box.interp:2: tet vertex 81 out of range [0, 81)"), std::string::npos)
      << outOfRange.err;
  // Weights for fewer vertices than the OBJ has.
  std::ofstream(folder_ / "bar-box.interp") << "0 0 0.25 1 0.25 2 0.25 3 0.25\n";
  const RunResult fewer = runIn(rendererPath, "run.afsim --output frames --quiet");
  EXPECT_EQ(fewer.exitCode, 1);
  EXPECT_NE(fewer.err.find("bar-box.interp: weights for 1 vertices, but the render mesh has 20"), std::string::npos)
      << fewer.err;
}

TEST_F(VegaConfigRun, BadConfigsStopTheSimulator) {
  std::ofstream(folder_ / "unknown.config") << "# a misspelt key\n*timeStep\n0.01\n";
  const RunResult unknown = runIn(simulatorPath, "unknown.config --output run.afsim");
  EXPECT_EQ(unknown.exitCode, 1);
  EXPECT_NE(unknown.err.find("unknown.config:2: *timeStep: unknown option"), std::string::npos) << unknown.err;
  std::ofstream(folder_ / "model.config") << "*volumetricMeshFilename\nbar.veg\n*timestep\n0.01\n*dampingMassCoef\n0\n"
                                             "*dampingStiffnessCoef\n0\n*deformableObjectMethod\nFEM\n";
  const RunResult model = runIn(simulatorPath, "model.config --output run.afsim");
  EXPECT_EQ(model.exitCode, 1);
  EXPECT_NE(model.err.find("model.config:9: *deformableObjectMethod: unknown deformable model \"FEM\""),
            std::string::npos)
      << model.err;
  EXPECT_FALSE(fs::exists(folder_ / "run.afsim"));
}

}  // namespace
