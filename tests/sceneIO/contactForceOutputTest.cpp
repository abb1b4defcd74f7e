// SPDX-License-Identifier: BSD-3-Clause
// output.contactForces: every vertex's contact force at each frame's state, stored in the
// .afsim records. Checked against the momentum the forces change, against the weight of a
// body at rest on the ground, and through a written and read file.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <string>

#include "sceneTestUtilities.hpp"

namespace asyncfem {
namespace {

using nlohmann::json;

// A 0.2 m rubber cube (2^3 cells, 8 kg) released 5 mm above the ground, no Rayleigh
// damping, so that the only forces on the whole body are gravity and contact.
json cubeOnTheGround(bool implicitContact) {
  json scene = json::parse(R"({
    "objects": [{"name": "cube", "translation": [-0.1, 0.005, -0.1],
                 "mesh": {"generator": "box", "size": [0.2, 0.2, 0.2], "cells": [2, 2, 2],
                          "material": {"name": "rubber", "density": 1000, "youngsModulus": 1e5,
                                       "poissonRatio": 0.3}}}],
    "gravity": [0, -9.81, 0],
    "contact": {"ground": {"height": 0}, "stiffness": 2e3, "damping": 20},
    "output": {"contactForces": true},
    "integrator": {"name": "backward-euler", "timestep": 0.004166666666666667},
    "frames": {"rate": 30, "count": 15}
  })");
  scene["contact"]["implicit"] = implicitContact;
  return scene;
}

constexpr double kMass = 8.0;  // 0.2^3 m^3 at 1000 kg/m^3
constexpr double kGravity = 9.81;

// sum_i (M v)_i per axis: the whole body's momentum.
Eigen::Vector3d momentum(const Simulation& simulation) {
  const Eigen::VectorXd mv = simulation.problem->massMatrix() * simulation.integrator->velocity();
  return mv.reshaped(3, mv.size() / 3).rowwise().sum();
}

Eigen::Vector3d total(const Eigen::VectorXd& forces) { return forces.reshaped(3, forces.size() / 3).rowwise().sum(); }

// Backward Euler with explicit contact: M (v+ - v) = h (f_elastic(u+) + M g + f_c(u, v)).
// The elastic forces sum to zero (a rigid translation is in the stiffness's null space), so
// the momentum changes by h (m g + sum_i f_c,i) with f_c the stored force of the state the
// step started from: that force, and no other, is what contactForces() must give.
TEST(ContactForceOutput, TheForcesAreWhatChangesTheMomentum) {
  Simulation simulation = buildSimulation(parseScene(cubeOnTheGround(false), "", "s.json"));
  const double h = simulation.integrator->timestep();
  const Eigen::Vector3d weight(0.0, -kMass * kGravity, 0.0);
  double largestContact = 0.0, largestMismatch = 0.0;
  for (int step = 0; step < 60; ++step) {
    const Eigen::Vector3d before = momentum(simulation);
    const Eigen::Vector3d contact = total(contactForces(simulation));
    simulation.integrator->step();
    largestContact = std::max(largestContact, contact.norm());
    largestMismatch = std::max(largestMismatch, ((momentum(simulation) - before) / h - weight - contact).norm());
  }
  EXPECT_GT(largestContact, kMass * kGravity);  // it landed, and the ground pushed back harder than gravity pulls
  // The solve's round-off, scaled by the forces (largest about 3 m g here): 1e-9 of m g.
  EXPECT_LE(largestMismatch, 1e-9 * kMass * kGravity);
}

// At rest on the ground the contact forces carry the weight: after 0.8 s their sum is m g
// upwards and nothing sideways (measured 0.9995 m g; tolerance 1%, above what the decaying
// motion leaves). Implicit contact: with explicit contact the bottom vertices keep a
// contact force that alternates from step to step (a period-two-step oscillation, its
// damping term clamping the force on alternate steps), and frames eight steps apart sample
// one phase of it: their sum sat at 1.17 m g (at nine steps per frame it alternates
// 1.009, 0.992 m g from frame to frame), which these stored forces showed.
TEST(ContactForceOutput, AtRestTheGroundCarriesTheWeight) {
  Simulation simulation = buildSimulation(parseScene(cubeOnTheGround(true), "", "s.json"));
  for (int step = 0; step < 192; ++step) simulation.integrator->step();
  const Eigen::VectorXd forces = contactForces(simulation);
  const Eigen::Vector3d sum = total(forces);
  EXPECT_NEAR(sum.y(), kMass * kGravity, 0.01 * kMass * kGravity);
  EXPECT_NEAR(sum.x(), 0.0, 0.01 * kMass * kGravity);
  EXPECT_NEAR(sum.z(), 0.0, 0.01 * kMass * kGravity);
  // Only the bottom layer (9 vertices at y = 0.005 at rest) touches; every other force is zero.
  const Eigen::Matrix3Xd& rest = simulation.mesh->restPositions();
  int touching = 0;
  for (int v = 0; v < simulation.mesh->numVertices(); ++v) {
    const bool bottom = rest(1, v) < 0.005 + 1e-9;
    const double force = forces.segment<3>(3 * v).norm();
    if (!bottom) EXPECT_EQ(force, 0.0) << "vertex " << v;
    touching += force > 0.0 ? 1 : 0;
  }
  EXPECT_EQ(touching, 9);
}

// Explicit contact damping c, or friction's viscosity eta in its viscous regime, beyond
// c h / m = 2 on the median boundary vertex (lumped mass 1/4 kg here) flips the vertices'
// velocity every step: the scene is warned, naming the key, the ratio and the limit. At
// c h / m = 1/3 (damping 20) or with implicit contact there is no such warning.
TEST(ContactForceOutput, ExplicitDampingAndFrictionBeyondTheLimitAreWarned) {
  json scene = cubeOnTheGround(false);
  scene["contact"]["damping"] = 300;  // c h / m = 300 x (1/240) / (1/4) = 5
  const Simulation warned = buildSimulation(parseScene(scene, "", "s.json"));
  ASSERT_EQ(warned.warnings.size(), 1u);
  const std::string& warning = warned.warnings.front();
  EXPECT_NE(warning.find("s.json: contact.damping: 300 on a boundary vertex of median lumped mass 0.25"),
            std::string::npos)
      << warning;
  EXPECT_NE(warning.find("c h / m = 5"), std::string::npos) << warning;
  EXPECT_NE(warning.find("below 120"), std::string::npos) << warning;
  EXPECT_TRUE(buildSimulation(parseScene(cubeOnTheGround(false), "", "s.json")).warnings.empty());
  scene["contact"]["implicit"] = true;
  EXPECT_TRUE(buildSimulation(parseScene(scene, "", "s.json")).warnings.empty());
  json friction = cubeOnTheGround(false);
  friction["contact"]["friction"] = 0.5;  // the default viscosity 1e3: eta h / m = 16.7
  const Simulation rubbing = buildSimulation(parseScene(friction, "", "s.json"));
  ASSERT_EQ(rubbing.warnings.size(), 1u);
  EXPECT_NE(rubbing.warnings.front().find("s.json: contact.frictionViscosity: 1000"), std::string::npos)
      << rubbing.warnings.front();
  friction["contact"]["frictionViscosity"] = 100;  // 1.67
  EXPECT_TRUE(buildSimulation(parseScene(friction, "", "s.json")).warnings.empty());
}

// The forces go into the records bit for bit, frame by frame; the header says so.
TEST(ContactForceOutput, TheRecordsCarryTheForcesOfEachFrame) {
  test::ScratchFolder folder;
  const Scene scene = parseScene(cubeOnTheGround(false), "", "s.json");
  Simulation simulation = buildSimulation(scene);
  SimulationFileHeader header;
  header.numVertices = simulation.mesh->numVertices();
  header.frameInterval = simulation.timing.frameInterval;
  describeContactForceOutput(scene, simulation, header);
  ASSERT_TRUE(header.hasContactForces);
  const std::filesystem::path path = folder.path() / "run.afsim";
  std::vector<Eigen::VectorXd> expected;
  {
    SimulationWriter writer(path, header);
    for (int frame = 0; frame < 6; ++frame) {
      advanceFrame(simulation, frame);
      appendSimulationFrame(writer, simulation);
      expected.push_back(contactForces(simulation));
    }
  }
  SimulationReader reader(path);
  ASSERT_EQ(reader.numFrames(), 6);
  double largest = 0.0;
  for (int frame = 0; frame < 6; ++frame) {
    EXPECT_EQ(reader.readFrame(frame).contactForce, expected[static_cast<std::size_t>(frame)]) << frame;
    largest = std::max(largest, expected[static_cast<std::size_t>(frame)].norm());
  }
  EXPECT_GT(largest, 0.0);  // the cube touched within the six frames
}

// Asking for contact forces in a scene without contact is an error naming the key.
TEST(ContactForceOutput, ASceneWithoutContactIsRefusedByKey) {
  json scene = test::smallScene();
  scene["output"] = {{"contactForces", true}};
  const Scene parsed = parseScene(scene, "", "s.json");
  const Simulation simulation = buildSimulation(parsed);
  SimulationFileHeader header;
  try {
    describeContactForceOutput(parsed, simulation, header);
    ADD_FAILURE() << "no error";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("s.json: output.contactForces: the scene has no contact"),
              std::string::npos)
        << error.what();
  }
  json typo = test::smallScene();
  typo["output"] = {{"contactForces", "yes"}};
  EXPECT_THROW((void)parseScene(typo, "", "s.json"), ValidationError);
}

}  // namespace
}  // namespace asyncfem
