// SPDX-License-Identifier: BSD-3-Clause
// afsimTool end to end: writes a small .afsim (and mesh) with the libraries, runs the
// built executable on it and checks what it prints and writes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "utilityTest.hpp"

namespace {

namespace fs = std::filesystem;

using asyncfem::test::readText;
using asyncfem::test::RunResult;

const std::string toolPath = std::string(ASYNCFEM_BIN_DIR) + "/afsimTool";

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts{""};
  for (const char c : text) {
    if (c == separator) {
      parts.emplace_back();
    } else {
      parts.back() += c;
    }
  }
  return parts;
}

class AfsimToolTest : public asyncfem::test::UtilityTest {
 protected:
  static constexpr int frames = 5;

  /// A 2 x 1 x 1 box (12 vertices) as box.veg and run.afsim with 5 frames of a known
  /// displacement (u of vertex v, axis a at frame k = sin(k + 3v + a) / 7), frame rate 20.
  void SetUp() override {
    UtilityTest::SetUp();
    asyncfem::BoxMeshSpec spec;
    spec.size = Eigen::Vector3d(2, 1, 1);
    spec.cells = Eigen::Vector3i(2, 1, 1);
    mesh_ = asyncfem::makeBoxMesh(spec);
    asyncfem::writeVeg(folder_ / "box.veg", mesh_);
    asyncfem::SimulationFileHeader header;
    header.numVertices = mesh_.numVertices();
    header.frameInterval = 0.05;
    header.timestep = 0.01;
    asyncfem::SimulationWriter writer(folder_ / "run.afsim", header);
    for (int k = 0; k < frames; ++k) writer.appendFrame(0.05 * (k + 1), displacement(k));
  }
  Eigen::VectorXd displacement(int frame) const {
    Eigen::VectorXd u(mesh_.numDofs());
    for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = std::sin(static_cast<double>(frame + i)) / 7.0;
    return u;
  }

  /// Runs afsimTool in the test's folder (relative paths are the folder's files).
  RunResult run(const std::string& arguments) const {
    return runCommand("cd '" + folder_.string() + "' && '" + toolPath + "' " + arguments);
  }

  asyncfem::TetMesh mesh_;
};

TEST_F(AfsimToolTest, InfoPrintsHeaderTimesChecksumsAndTheCheckpoint) {
  const RunResult r = run("info run.afsim");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* line : {"vertices    12\n", "frames      5 complete\n",
                           "frame rate  20 per time unit (interval 0.05)\n", "timestep    0.01\n", "velocities  no\n",
                           "times       0.05 to 0.25\n", "checksums   ok (5 frames)\n", "checkpoint  none"}) {
    EXPECT_NE(r.out.find(line), std::string::npos) << line << "\n" << r.out;
  }

  asyncfem::SimulationCheckpoint checkpoint;
  checkpoint.frames = frames;
  checkpoint.time = 0.25;
  checkpoint.fingerprint = 0x12abcdefU;
  checkpoint.integrator = "backward-euler";
  checkpoint.displacement = displacement(frames - 1);
  checkpoint.velocity = Eigen::VectorXd::Zero(mesh_.numDofs());
  asyncfem::writeCheckpoint(asyncfem::checkpointPathFor(folder_ / "run.afsim"), checkpoint);
  const RunResult withCheckpoint = run("info run.afsim");
  ASSERT_EQ(withCheckpoint.exitCode, 0) << withCheckpoint.err;
  EXPECT_NE(withCheckpoint.out.find("run fingerprint 0x12abcdef"), std::string::npos) << withCheckpoint.out;
  EXPECT_NE(withCheckpoint.out.find("after frame 5, t = 0.25, integrator backward-euler"), std::string::npos)
      << withCheckpoint.out;

  EXPECT_NE(withCheckpoint.out.find("scene       not recorded in the .afsim file\n"), std::string::npos)
      << withCheckpoint.out;

  // A version-2 file names its scene once and never says it is not recorded.
  asyncfem::SimulationFileHeader recorded;
  recorded.numVertices = mesh_.numVertices();
  recorded.frameInterval = 0.05;
  recorded.timestep = 0.01;
  recorded.scenePath = "/scenes/box.json";
  recorded.sceneFingerprint = 0xabcU;
  {
    asyncfem::SimulationWriter writer(folder_ / "recorded.afsim", recorded);
    writer.appendFrame(0.05, displacement(0));
  }
  const RunResult v2 = run("info recorded.afsim");
  ASSERT_EQ(v2.exitCode, 0) << v2.err;
  EXPECT_NE(v2.out.find("scene       /scenes/box.json (mesh and fixed vertices fingerprint 00000abc)\n"),
            std::string::npos)
      << v2.out;
  EXPECT_EQ(v2.out.find("not recorded"), std::string::npos) << v2.out;
  EXPECT_NE(v2.out.find("checkpoint  none"), std::string::npos) << v2.out;

  // One flipped byte in frame 2's displacement: info names it and exits 1.
  const std::int64_t record = 24 + 24 * static_cast<std::int64_t>(mesh_.numVertices());
  {
    std::fstream file(folder_ / "run.afsim", std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(64 + 2 * record + 20);
    file.put('\x7f');
  }
  const RunResult bad = run("info run.afsim");
  EXPECT_EQ(bad.exitCode, 1);
  EXPECT_NE(bad.out.find("checksums   BAD: "), std::string::npos) << bad.out;
  EXPECT_NE(bad.err.find("frame 2: checksum mismatch"), std::string::npos) << bad.err;
}

// Records with region ratios: info counts the fast vertices (ratio above 1) of the first
// and the last frame; files without them say so.
TEST_F(AfsimToolTest, InfoCountsTheFastVerticesOfTheFirstAndLastFrame) {
  asyncfem::SimulationFileHeader header;
  header.numVertices = mesh_.numVertices();
  header.frameInterval = 0.05;
  header.hasRegionRatios = true;
  {
    asyncfem::SimulationWriter writer(folder_ / "regions.afsim", header);
    for (int k = 0; k < 3; ++k) {
      std::vector<int> ratios(static_cast<std::size_t>(mesh_.numVertices()), 1);
      for (int v = 0; v < 2 + (3 * k); ++v) ratios[static_cast<std::size_t>(v)] = 4 + k;  // 2, 5, 8 fast
      writer.appendFrame(0.05 * (k + 1), displacement(k), ratios);
    }
  }
  const RunResult r = run("info regions.afsim");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("regions     yes, each vertex's step ratio per frame: 2 fast vertices in the first frame, 8 "
                       "in the last (frame 2)\n"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("checksums   ok (3 frames)"), std::string::npos) << r.out;
  EXPECT_NE(run("info run.afsim").out.find("regions     no (the records carry no region ratios)\n"), std::string::npos);
}

TEST_F(AfsimToolTest, CsvHasTimeDisplacementAndPositionsOfTheChosenVertices) {
  const RunResult r = run("csv run.afsim --vertices 3,11 --frames 1:4:2 --mesh box.veg -o out/traj.csv");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::vector<std::string> lines = split(readText(folder_ / "out/traj.csv"), '\n');
  ASSERT_EQ(lines.size(), 4U);  // header, frames 1 and 3, empty after the last newline
  EXPECT_EQ(lines[0], "frame,time,u3_x,u3_y,u3_z,p3_x,p3_y,p3_z,u11_x,u11_y,u11_z,p11_x,p11_y,p11_z");
  for (int row = 0; row < 2; ++row) {
    const int frame = 1 + 2 * row;
    const std::vector<std::string> cells = split(lines[static_cast<std::size_t>(row + 1)], ',');
    ASSERT_EQ(cells.size(), 14U);
    EXPECT_EQ(std::stoi(cells[0]), frame);
    EXPECT_EQ(std::stod(cells[1]), 0.05 * (frame + 1));
    const Eigen::VectorXd u = displacement(frame);
    for (std::size_t i = 0; i < 2; ++i) {
      const int vertex = i == 0 ? 3 : 11;
      for (int axis = 0; axis < 3; ++axis) {
        // Printed in the shortest form that reads back exactly.
        EXPECT_EQ(std::stod(cells[2 + 6 * i + static_cast<std::size_t>(axis)]), u[3 * vertex + axis]);
        EXPECT_EQ(std::stod(cells[5 + 6 * i + static_cast<std::size_t>(axis)]),
                  mesh_.restPosition(vertex)[axis] + u[3 * vertex + axis]);
      }
    }
  }
  // --scene gives the same mesh through the scene's generator.
  std::ofstream(folder_ / "scene.json") << R"({"mesh": {"generator": "box", "size": [2, 1, 1], "cells": [2, 1, 1]},
    "integrator": {"name": "backward-euler", "timestep": 0.01}})";
  const RunResult scene = run("csv run.afsim --vertices 3,11 --frames 1:4:2 --scene scene.json -o out/scene.csv");
  ASSERT_EQ(scene.exitCode, 0) << scene.err;
  EXPECT_EQ(readText(folder_ / "out/scene.csv"), readText(folder_ / "out/traj.csv"));

  // Without -o to stdout; without a mesh no positions; all frames by default.
  const RunResult plain = run("csv run.afsim --vertices 0");
  ASSERT_EQ(plain.exitCode, 0) << plain.err;
  EXPECT_EQ(split(plain.out, '\n').size(), static_cast<std::size_t>(frames + 2));
  EXPECT_EQ(split(plain.out, '\n')[0], "frame,time,u0_x,u0_y,u0_z");
}

TEST_F(AfsimToolTest, VtuWritesTheChosenFramesAndACollection) {
  const RunResult r = run("vtu run.afsim --mesh box.veg --frames 0,3 -o frames");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(folder_ / "frames/frame_00000.vtu"));
  EXPECT_TRUE(fs::exists(folder_ / "frames/frame_00003.vtu"));
  EXPECT_FALSE(fs::exists(folder_ / "frames/frame_00001.vtu"));
  const std::string pvd = readText(folder_ / "frames/frames.pvd");
  EXPECT_NE(pvd.find("timestep=\"0.05\" group=\"\" part=\"0\" file=\"frame_00000.vtu\""), std::string::npos) << pvd;
  EXPECT_NE(pvd.find("timestep=\"0.2\" group=\"\" part=\"0\" file=\"frame_00003.vtu\""), std::string::npos) << pvd;
  EXPECT_NE(readText(folder_ / "frames/frame_00003.vtu").find("<AppendedData encoding=\"raw\">"), std::string::npos);

  const RunResult ascii = run("vtu run.afsim --mesh box.veg --frames 4 --encoding ascii -o text");
  ASSERT_EQ(ascii.exitCode, 0) << ascii.err;
  const std::string text = readText(folder_ / "text/frame_00004.vtu");
  EXPECT_NE(text.find("Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\""), std::string::npos);
}

// intersections on two unit boxes 0.5 apart above the ground (16 vertices): at rest
// nothing intersects; with the second box moved 1 along -x the two overlap; with both
// moved 0.1 down they sink 0.1 below the ground without intersecting each other.
TEST_F(AfsimToolTest, IntersectionsCountTrianglePairsAndTheContactDepthPerFrame) {
  std::ofstream(folder_ / "boxes.json") << R"({
    "objects": [
      {"name": "a", "mesh": {"generator": "box", "size": [1, 1, 1], "cells": [1, 1, 1]}},
      {"name": "b", "mesh": {"generator": "box", "size": [1, 1, 1], "cells": [1, 1, 1]}, "translation": [1.5, 0, 0]}
    ],
    "contact": {"ground": {"height": 0}},
    "integrator": {"name": "backward-euler", "timestep": 0.05},
    "frames": {"rate": 20, "count": 3}
  })";
  asyncfem::SimulationFileHeader header;
  header.numVertices = 16;
  header.frameInterval = 0.05;
  {
    asyncfem::SimulationWriter writer(folder_ / "boxes.afsim", header);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(48);
    writer.appendFrame(0.05, u);
    for (int v = 8; v < 16; ++v) u[3 * v] = -1.0;
    writer.appendFrame(0.1, u);
    u.setZero();
    for (int v = 0; v < 16; ++v) u[(3 * v) + 1] = -0.1;
    writer.appendFrame(0.15, u);
  }
  const RunResult r = run("intersections boxes.afsim --scene boxes.json");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::vector<std::string> lines = split(r.out, '\n');
  ASSERT_GE(lines.size(), 4U) << r.out;
  EXPECT_EQ(lines[0], "frame,time,bodyPairs,obstaclePairs,contactDepth");
  EXPECT_EQ(lines[1], "0,0.05,0,0,0");
  const std::vector<std::string> overlapping = split(lines[2], ',');
  ASSERT_EQ(overlapping.size(), 5U);
  EXPECT_GT(std::stoi(overlapping[2]), 0) << lines[2];
  EXPECT_EQ(lines[3], "2,0.15,0,0,0.1");
  EXPECT_NE(r.err.find("intersections: 1 of 3 frames have intersecting triangles"), std::string::npos) << r.err;
  // A file that records no scene needs one.
  const RunResult noScene = run("intersections boxes.afsim");
  EXPECT_EQ(noScene.exitCode, 1);
  EXPECT_NE(noScene.err.find("boxes.afsim records no scene: give it with --scene SCENE.json"), std::string::npos)
      << noScene.err;
}

TEST_F(AfsimToolTest, ErrorsNameWhatIsWrong) {
  const std::vector<std::pair<std::string, std::string>> cases{
      {"csv run.afsim --vertices 3,12", "vertex 12 is out of range: run.afsim has 12 vertices (ids 0 to 11)"},
      {"csv run.afsim --vertices 3,x", "--vertices 3,x: \"x\" is not a vertex id"},
      {"csv run.afsim --vertices 3 --frames 2:9",
       "frames 2:9: stop 9 is beyond the 5 frames of run.afsim (frames 0 to 4)"},
      {"vtu run.afsim --mesh box.veg --frames 7", "frames 7: start 7 is beyond the 5 frames of run.afsim"},
      {"info missing.afsim", "cannot open 'missing.afsim': no such file"},
      {"info box.veg", "box.veg: not an AsyncFEM simulation file (bad magic)"},
      {"vtu run.afsim", "vtu needs the mesh: give --mesh FILE or --scene SCENE.json"},
      {"vtu run.afsim --mesh small.veg", "run.afsim has 12 vertices but the mesh (small.veg) has 8"},
  };
  asyncfem::BoxMeshSpec small;
  small.cells = Eigen::Vector3i(1, 1, 1);
  asyncfem::writeVeg(folder_ / "small.veg", asyncfem::makeBoxMesh(small));
  for (const auto& [arguments, message] : cases) {
    const RunResult r = run(arguments);
    EXPECT_EQ(r.exitCode, 1) << arguments;
    EXPECT_NE(r.err.find("afsimTool: "), std::string::npos) << arguments << "\n" << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << arguments << "\n" << r.err;
  }
}

}  // namespace
