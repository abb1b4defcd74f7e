// SPDX-License-Identifier: BSD-3-Clause
// advanceFrame's numerical-failure messages: they name the frame, the step, the time and
// where the failure is (the vertex, its region for the asynchronous integrator or "the
// mesh", and a vertex set holding it).
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <string>

#include "sceneTestUtilities.hpp"

namespace {

using asyncfem::test::smallScene;

// Runs every frame; returns the NumericalError's message, or "" if none was thrown.
std::string failureOf(const nlohmann::json& json) {
  asyncfem::Simulation simulation = asyncfem::buildSimulation(asyncfem::parseScene(json, "", "scene.json"));
  try {
    for (int frame = 0; frame < simulation.timing.frameCount; ++frame) asyncfem::advanceFrame(simulation, frame);
  } catch (const asyncfem::NumericalError& error) {
    return error.what();
  }
  return "";
}

TEST(AdvanceFrameErrors, BlowUpInAFastRegionNamesTheRegion) {
  // A load far beyond anything physical on the free end, which is the fast region S_1:
  // the (linear, implicit, stable) run exceeds the blow-up limit in its first step.
  auto json = smallScene();
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [0, -1e15, 0]}])");
  json["integrator"] = nlohmann::json::parse(R"({"name": "async", "timestep": 0.01,
      "options": {"regions": [{"name": "end", "ratio": 2, "vertexSets": ["xmax"]}]}})");
  const std::string message = failureOf(json);
  EXPECT_EQ(message.rfind("frame 0 (step 1, t = 0.01): blow-up: max |u| = ", 0), 0U) << message;
  EXPECT_NE(message.find(" in fast region S_1 'end' (vertex set 'xmax')"), std::string::npos) << message;
  EXPECT_NE(message.find("the simulation is unstable"), std::string::npos) << message;
}

TEST(AdvanceFrameErrors, BlowUpInTheLargeStepRegionSaysL) {
  auto json = smallScene();
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [0, -1e15, 0]}])");
  json["integrator"] = nlohmann::json::parse(R"({"name": "async", "timestep": 0.01,
      "options": {"regions": [{"name": "root", "ratio": 2, "boxes": [{"min": [0.9, 0, 0], "max": [1.1, 1, 1]}]}]}})");
  const std::string message = failureOf(json);
  EXPECT_NE(message.find(" in the large-step region L (vertex set 'xmax')"), std::string::npos) << message;
}

TEST(AdvanceFrameErrors, BlowUpUnderTheUncoupledMultirateSchemeNamesTheRegion) {
  auto json = smallScene();
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [0, -1e15, 0]}])");
  json["integrator"] = nlohmann::json::parse(R"({"name": "multirate-uncoupled", "timestep": 0.01,
      "options": {"regions": [{"name": "end", "ratio": 2, "vertexSets": ["xmax"]}]}})");
  const std::string message = failureOf(json);
  EXPECT_NE(message.find(" in fast region S_1 'end' (vertex set 'xmax')"), std::string::npos) << message;
}

TEST(AdvanceFrameErrors, SchroederSubstepAboveItsLimitFailsBeforeAnyFrame) {
  // schroeder2011's outer layer is explicit in its elastic forces: a substep above its
  // limit is refused when the simulation is built (no frame is computed or written), with
  // the region and the largest stable substep in the message.
  auto json = smallScene();
  json["mesh"]["material"]["youngsModulus"] = 1e9;
  json["integrator"] = nlohmann::json::parse(R"({"name": "schroeder2011", "timestep": 0.01,
      "options": {"regions": [{"name": "end", "ratio": 2, "vertexSets": ["xmax"]}]}})");
  try {
    asyncfem::buildSimulation(asyncfem::parseScene(json, "", "scene.json"));
    FAIL() << "no error";
  } catch (const asyncfem::TimestepError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind("scene.json: integrator.timestep: schroeder2011: fast region S_1 'end'", 0), 0U) << message;
    EXPECT_NE(message.find("the largest stable substep"), std::string::npos) << message;
  }
  // Forced past the check, the run fails within its first frames (the energy check),
  // naming the region.
  json["integrator"]["options"]["force"] = true;
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [0, -1, 0]}])");
  const std::string message = failureOf(json);
  EXPECT_EQ(message.rfind("frame ", 0), 0U) << message;
  EXPECT_NE(message.find("in fast region S_1 'end'"), std::string::npos) << message;
  EXPECT_NE(message.find("the simulation is unstable"), std::string::npos) << message;
}

TEST(AdvanceFrameErrors, UnstableExplicitRunNamesTheFrameAndTheMesh) {
  // Central differences forced far above its stable timestep: the state grows by orders
  // of magnitude per step until the blow-up check stops it.
  auto json = smallScene();
  json["mesh"]["material"]["youngsModulus"] = 1e9;
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [0, -1, 0]}])");
  json["integrator"] = nlohmann::json::parse(R"({"name": "central-differences", "timestep": 0.01,
                                                 "options": {"force": true}})");
  json["frames"] = {{"rate", 10}, {"count", 50}};
  const std::string message = failureOf(json);
  ASSERT_EQ(message.rfind("frame ", 0), 0U) << message;
  EXPECT_NE(message.find(" at vertex "), std::string::npos) << message;
  EXPECT_NE(message.find(" of the mesh"), std::string::npos) << message;
  EXPECT_NE(message.find("unstable"), std::string::npos) << message;
}

// The uncoupled multirate comparator at m = 200 on a uniform bar (stiffness ratio 1) is
// unstable (docs/benchmarks.md, stabilityStressTest): after the pull ends, its energy
// grows without any load. The energy check stops it long before the displacement limit.
nlohmann::json unstableMultirateBar(const std::string& integrator) {
  return nlohmann::json::parse(R"({
    "mesh": {"generator": "box", "size": [1, 0.25, 0.25], "cells": [8, 2, 2],
             "material": {"name": "soft", "density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.4}},
    "fixed": {"sets": ["xmin"]},
    "forces": [{"type": "pull", "set": "xmax", "force": [0, -1, 0], "window": [0, 0.2]}],
    "integrator": {"name": ")" +
                               integrator + R"(", "timestep": 0.008333333333333333,
                   "options": {"regions": [{"name": "end", "ratio": 200,
                                            "boxes": [{"min": [0.74, -1, -1], "max": [2, 2, 2]}]}]}},
    "frames": {"rate": 30, "count": 150}
  })");
}

TEST(AdvanceFrameErrors, EnergyGrowthAfterTheLoadsIsABlowUp) {
  const std::string message = failureOf(unstableMultirateBar("multirate-uncoupled"));
  EXPECT_EQ(message.rfind("frame ", 0), 0U) << message;
  EXPECT_NE(message.find("energy blow-up: with no load changing since t = 0.2"), std::string::npos) << message;
  EXPECT_NE(message.find("in fast region S_1 'end'"), std::string::npos) << message;
  // Well before max |u| reaches 1000 x the bounding-box diagonal: |u| is still below 1 m.
  const std::size_t at = message.find("largest |u| = ");
  ASSERT_NE(at, std::string::npos) << message;
  EXPECT_LT(std::stod(message.substr(at + 14)), 1.0) << message;
}

TEST(AdvanceFrameErrors, StableIntegratorsPassTheEnergyCheck) {
  // The same scene under the asynchronous integrator: it dissipates, never trips the check.
  EXPECT_EQ(failureOf(unstableMultirateBar("async")), "");
}

}  // namespace
