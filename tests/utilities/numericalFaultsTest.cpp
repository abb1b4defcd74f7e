// SPDX-License-Identifier: BSD-3-Clause
// Numerical faults under offlineSimulator (docs/robustness.md, "Faults, counted"): an
// element that inverts under a hyperelastic model without inversion handling, a Newton
// iteration that diverges, a CHOLMOD factorization that fails on an indefinite system.
// Each must stop the run with exit status 1 and a message naming the frame, the step's
// time and the element or vertex, and leave in the .afsim file exactly the frames before
// the fault, all finite. (A NaN from a force model written in Python:
// tests/python/test_numericalFaults.py.)
#include <gtest/gtest.h>

#include <asyncfem/simulationIO/simulationFile.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "utilityTest.hpp"

namespace {

namespace fs = std::filesystem;

void expectMatch(const std::string& message, const std::string& pattern) {
  EXPECT_TRUE(std::regex_search(message, std::regex(pattern))) << "expected /" << pattern << "/ in: " << message;
}

const std::string simulatorPath = std::string(ASYNCFEM_BIN_DIR) + "/offlineSimulator";

class NumericalFaultsTest : public asyncfem::test::UtilityTest {
 protected:
  /// A 3 x 1 x 1 bar of 6 x 2 x 2 cells fixed at x = 0, at rest until t = 0.1 (the first
  /// frames, at 20 frames per second), then pushed along -x at x = 3 with `push` (far beyond
  /// what the bar can carry, so the fault comes a few steps later).
  static nlohmann::json compressedBar(double push) {
    nlohmann::json scene = nlohmann::json::parse(R"({
      "mesh": {"generator": "box", "size": [3, 1, 1], "cells": [6, 2, 2],
               "material": {"density": 1000, "youngsModulus": 1e6, "poissonRatio": 0.4}},
      "fixed": {"sets": ["xmin"]},
      "frames": {"rate": 20, "count": 20},
      "output": {"file": "fault.afsim"}
    })");
    scene["forces"] = {{{"type", "pull"}, {"set", "xmax"}, {"force", {-push, 0, 0}}, {"window", {0.1, 10}}}};
    return scene;
  }

  struct Fault {
    std::string message;
    long long frame = -1;
    double t = 0.0;  ///< the simulated time the message names (not a wall-clock figure)
  };

  /// Runs the scene, expects exit status 1 and the "frame N (step S, t = T)" prefix, and
  /// checks that the output holds exactly frames 0 .. N-1, complete and finite.
  Fault runToFault(const nlohmann::json& scene) const {
    const fs::path path = folder_ / "scene.json";
    std::ofstream(path) << scene.dump(2);
    const asyncfem::test::RunResult r = runCommand("'" + simulatorPath + "' '" + path.string() + "' --quiet");
    Fault fault;
    fault.message = r.err;
    EXPECT_EQ(r.exitCode, 1) << r.err;
    std::smatch where;
    if (!std::regex_search(r.err, where, std::regex(R"(frame (\d+) \(step (\d+), t = ([-+.0-9e]+)\))"))) {
      ADD_FAILURE() << "the message names no frame, step and time: " << r.err;
      return fault;
    }
    fault.frame = std::stoll(where[1].str());
    fault.t = std::stod(where[3].str());
    // Frame N covers the times (N / 20, (N + 1) / 20]; a fault before the load (backward
    // Euler feels it in the step to t = 0.1) would mean the scene, not the fault, is broken.
    EXPECT_GE(fault.t, 0.1 - 1e-12);
    EXPECT_GE(fault.frame, 1) << "at least one frame before the fault";
    EXPECT_GT(fault.t, static_cast<double>(fault.frame) / 20.0 - 1e-12);
    EXPECT_LE(fault.t, static_cast<double>(fault.frame + 1) / 20.0 + 1e-12);
    EXPECT_NE(r.err.find("the " + std::to_string(fault.frame) + " frames before it are kept in"), std::string::npos)
        << r.err;
    asyncfem::SimulationReader reader(folder_ / "fault.afsim");
    EXPECT_FALSE(reader.hasTruncatedFrame());
    EXPECT_EQ(reader.numFrames(), fault.frame) << "the file must hold exactly the frames before the fault";
    for (std::int64_t k = 0; k < reader.numFrames(); ++k) {
      EXPECT_TRUE(reader.readFrame(k).displacement.allFinite()) << "frame " << k;
    }
    return fault;
  }
};

TEST_F(NumericalFaultsTest, InvertedElementUnderAModelWithoutInversionHandlingNamesTheElement) {
  // Neo-Hookean as implemented sees only J^2 = det C: an inverted element would carry on
  // as its mirror image, with finite forces. Symplectic Euler: no factorization fails first.
  nlohmann::json scene = compressedBar(2e6);
  scene["forceModel"] = {{"type", "neo-hookean"}};
  scene["integrator"] = {{"name", "symplectic-euler"}, {"stepsPerFrame", 100}};
  const Fault fault = runToFault(scene);
  expectMatch(fault.message, R"(: element \d+ \(first vertex: vertex \d+ of the mesh)");
  EXPECT_NE(fault.message.find(") inverted (J = det F = -"), std::string::npos) << fault.message;
  EXPECT_NE(fault.message.find("neo-hookean model, which has no inversion handling"), std::string::npos)
      << fault.message;
  EXPECT_NE(fault.message.find("forceModel.inversionThreshold"), std::string::npos) << fault.message;
}

// A bar 1 x 0.25 x 0.25 of 4 cubes in Vega's CUBIC format (vertex id = i + 5 (j + 2 k) + 1).
std::string cubicBarVeg() {
  std::ostringstream veg;
  veg << "*VERTICES\n20 3 0 0\n";
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 5; ++i)
        veg << (i + (5 * (j + (2 * k))) + 1) << ' ' << 0.25 * i << ' ' << 0.25 * j << ' ' << 0.25 * k << '\n';
  veg << "*ELEMENTS\nCUBIC\n4 8 0\n";
  const auto id = [](int i, int j, int k) { return i + (5 * (j + (2 * k))) + 1; };
  for (int i = 0; i < 4; ++i) {
    veg << (i + 1) << ' ' << id(i, 0, 0) << ' ' << id(i + 1, 0, 0) << ' ' << id(i + 1, 1, 0) << ' ' << id(i, 1, 0)
        << ' ' << id(i, 0, 1) << ' ' << id(i + 1, 0, 1) << ' ' << id(i + 1, 1, 1) << ' ' << id(i, 1, 1) << '\n';
  }
  veg << "*MATERIAL bar\nENU, 1000, 1e6, 0.4\n*REGION\nallElements, bar\n";
  return veg.str();
}

TEST_F(NumericalFaultsTest, InvertedHexahedronUnderStvkNamesTheElementAndTheInvertibleFormulation) {
  // StVK in its Green-strain form has no inversion handling (the message names the
  // formulation that has); on hexahedra the check compares the eight corner Jacobians. The
  // x = 1 face (0-based vertices 4, 9, 14, 19) is pushed along -x far beyond what the bar
  // carries once t >= 0.1.
  std::ofstream(folder_ / "bar.veg") << cubicBarVeg();
  nlohmann::json scene = nlohmann::json::parse(R"({
    "mesh": {"file": "bar.veg"},
    "fixed": {"boxes": [{"min": [-0.01, -0.01, -0.01], "max": [0.01, 0.26, 0.26]}]},
    "forceModel": {"type": "stvk"},
    "integrator": {"name": "symplectic-euler", "stepsPerFrame": 100},
    "frames": {"rate": 20, "count": 20},
    "output": {"file": "fault.afsim"}
  })");
  scene["forces"] = {{{"type", "pull"}, {"vertices", {4, 9, 14, 19}}, {"force", {-2e5, 0, 0}}, {"window", {0.1, 10}}}};
  const Fault fault = runToFault(scene);
  expectMatch(fault.message, R"(: element \d+ \(first vertex: vertex \d+ of the mesh)");
  EXPECT_NE(fault.message.find(") inverted (J = det F = -"), std::string::npos) << fault.message;
  EXPECT_NE(fault.message.find("stvk model, which has no inversion handling"), std::string::npos) << fault.message;
  EXPECT_NE(fault.message.find("\"principal-stretches\" and forceModel.inversionThreshold"), std::string::npos)
      << fault.message;
}

TEST_F(NumericalFaultsTest, DivergingNewtonIterationNamesTheVertex) {
  // Corotational, 50 full Newton steps without line search at h = 0.05 under a push 100
  // times what the bar carries: the iterates run away instead of converging.
  nlohmann::json scene = compressedBar(2e6);
  scene["forceModel"] = {{"type", "corotational"}};
  scene["integrator"] = {{"name", "backward-euler"},
                         {"timestep", 0.05},
                         {"options", {{"solver", "umfpack"}, {"maxIterations", 50}, {"lineSearch", false}}}};
  const Fault fault = runToFault(scene);
  expectMatch(fault.message,
              R"(backward-euler: Newton's iteration diverged in the step to time [.0-9]+: after 50 iterations )"
              R"(its residual is [.0-9]+ times the step's initial one, largest at DOF \d+ \(vertex \d+\))");
  expectMatch(fault.message, R"(\[vertex \d+ of the mesh)");
  EXPECT_NE(fault.message.find("the state was left at the start of the step"), std::string::npos) << fault.message;
}

TEST_F(NumericalFaultsTest, CholmodFailureOnAnIndefiniteSystemNamesTheVertex) {
  // Neo-Hookean with inversion handling (so the inversion check does not stop it first)
  // and without enforceSPD: under strong compression the tangent, and with it
  // M + h^2 K, becomes indefinite and CHOLMOD meets a non-positive pivot.
  nlohmann::json scene = compressedBar(2e6);
  scene["forceModel"] = {{"type", "neo-hookean"}, {"inversionThreshold", 0.1}};
  scene["integrator"] = {{"name", "backward-euler"}, {"timestep", 0.01}};
  const Fault fault = runToFault(scene);
  expectMatch(fault.message,
              R"(cholmod: matrix is not positive definite: non-positive pivot at column \d+ \(elimination step )"
              R"(\d+ of \d+\), which is DOF \d+ \(vertex \d+, coordinate [xyz]\) of the mesh \[vertex \d+ )");
}

}  // namespace
