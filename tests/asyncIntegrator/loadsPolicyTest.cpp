// SPDX-License-Identifier: BSD-3-Clause
// The loads policy of run-time regions (loadsPolicy.hpp): a part that a load reaches within
// the next large step is fast from that step, against a run whose partition is set by hand
// at the same steps; its release once its motion relative to its neighbourhood has decayed;
// the probe and the energy it releases on.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/asyncIntegrator/loadsPolicy.hpp>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/asyncIntegrator/runTimeRegions.hpp>
#include <asyncfem/core/error.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

constexpr double kLargeStep = 5e-3;

void expectSameState(const Integrator& a, const Integrator& b, int step) {
  EXPECT_EQ(a.time(), b.time()) << "step " << step;
  EXPECT_EQ((a.displacement() - b.displacement()).cwiseAbs().maxCoeff(), 0.0) << "step " << step;
  EXPECT_EQ((a.velocity() - b.velocity()).cwiseAbs().maxCoeff(), 0.0) << "step " << step;
}

// The stiff-end bar (clamped at x = 0), linear, with Rayleigh damping alpha (1/s) and the
// given load windows, as a scene builds it (Problem: the external force and when it changes).
test::TestBody pulledBar(double alpha, std::vector<VertexLoad> windows) {
  const Problem bar = test::stiffEndBarProblem();
  return test::TestBody(Problem(bar.sharedMesh(), bar.fixedVertices(),
                                test::testSettings(ForceModelType::linear, alpha, 0.0), std::move(windows)));
}

// A pull on the x = 1 face from 2.5 hL to 5.5 hL (a window that starts and ends inside a
// large step), a part "tip" (x >= 0.75) at ratio 4. The probe sees the pull start in the step
// [2 hL, 3 hL], so the tip is fast from step 2 on; it stays fast while the pull ends (step
// 5, a load change too) and is released once its motion relative to its neighbourhood has
// stayed at or below 1% of its peak for minDwell steps. The run equals one whose partition
// is set by hand at those two steps, bit for bit, at every step.
TEST(LoadsPolicy, APartIsFastFromTheStepItsLoadStartsAndEqualsTheRunSetByHand) {
  const Problem bar = test::stiffEndBarProblem();
  const std::vector<int> face = bar.mesh().vertexSet("xmax");
  const test::TestBody body =
      pulledBar(60.0, {VertexLoad{face, Eigen::Vector3d(0.0, -0.5, 0.2), 2.5 * kLargeStep, 5.5 * kLargeStep}});
  const std::vector<int> tip = test::verticesBeyond(body.mesh, 0.75);
  RunTimeRegionOptions options;
  options.loads = true;
  options.loadsParts = {{"tip", tip, 4}};
  options.minDwell = 4;
  AsyncBackwardEuler adaptive(body.mesh, body.system, kLargeStep, {});
  adaptive.setRunTimeRegions(options);
  EXPECT_EQ(adaptive.partition().numRegions(), 0);  // nothing reaches the tip in the first step
  const int steps = 60;
  for (int k = 0; k < steps; ++k) adaptive.step();
  const std::vector<RepartitionRecord>& records = adaptive.repartitions();
  ASSERT_EQ(records.size(), 2U) << (records.empty() ? "" : records[0].reason);
  EXPECT_EQ(records[0].step, 2);
  EXPECT_EQ(records[0].regions, 1);
  EXPECT_EQ(records[0].fastVertices, static_cast<int>(tip.size()));
  EXPECT_NE(records[0].reason.find("loads: part 'tip' fast from t = 0.0100 s, m = 4 (a load reaches " +
                                   std::to_string(face.size()) + " of its " + std::to_string(tip.size()) +
                                   " vertices in (0.0100, 0.0150] s)"),
            std::string::npos)
      << records[0].reason;
  const long long released = records[1].step;
  EXPECT_GT(released, 5 + options.minDwell);  // not before the pull has ended and minDwell passed
  EXPECT_EQ(records[1].regions, 0);
  EXPECT_NE(records[1].reason.find("loads: part 'tip' released at t = "), std::string::npos) << records[1].reason;
  EXPECT_NE(records[1].reason.find("has stayed at or below 0.01 of its peak"), std::string::npos) << records[1].reason;
  EXPECT_TRUE(records[1].reused);  // the empty partition of the constructor, from the cache

  AsyncBackwardEuler byHand(body.mesh, body.system, kLargeStep, {});
  AsyncBackwardEuler replay(body.mesh, body.system, kLargeStep, {});
  replay.setRunTimeRegions(options);
  for (int k = 0; k < steps; ++k) {
    if (k == 2) byHand.setUp(RegionPartition(body.mesh, body.system.freeDofs, {{"tip", tip, 4}}));
    if (k == released) byHand.setUp(RegionPartition(body.mesh, body.system.freeDofs, {}));
    byHand.step();
    replay.step();
    expectSameState(replay, byHand, k);
    EXPECT_EQ(replay.partition().numRegions(), (k >= 2 && k < released) ? 1 : 0) << "step " << k;
  }
  // The summary lists both switches with their explanations.
  bool listedFast = false, listedRelease = false;
  for (const std::string& line : adaptive.report().lines) {
    listedFast = listedFast || line.find("loads: part 'tip' fast from") != std::string::npos;
    listedRelease = listedRelease || line.find("loads: part 'tip' released at") != std::string::npos;
  }
  EXPECT_TRUE(listedFast);
  EXPECT_TRUE(listedRelease);
}

// A pull that lasts (a window from t = 0 that never closes) makes its part fast from the
// first step; without given parts the part is the loaded face grown by one ring, at the
// loads ratio. (Backward Euler's own damping at hL and hS lets the relative motion decay
// even without Rayleigh damping, so the part may later be released: that is a release.)
TEST(LoadsPolicy, ALoadFromTheStartMakesTheLoadedVerticesAPartFromTheFirstStep) {
  const Problem bar = test::stiffEndBarProblem();
  const std::vector<int> face = bar.mesh().vertexSet("xmax");
  const test::TestBody body = pulledBar(0.0, {VertexLoad{face, Eigen::Vector3d(0.0, -0.5, 0.0), 0.0}});
  RunTimeRegionOptions options;
  options.loads = true;
  options.loadsRatio = 4;
  options.loadsRings = 1;
  AsyncBackwardEuler async(body.mesh, body.system, kLargeStep, {});
  async.setRunTimeRegions(options);
  ASSERT_EQ(async.partition().numRegions(), 1);  // from the first step
  EXPECT_EQ(async.partition().region(0).vertices, test::verticesBeyond(body.mesh, 0.875));
  EXPECT_EQ(async.partition().ratio(0), 4);
  for (int k = 0; k < 40; ++k) async.step();
  const std::vector<RepartitionRecord>& records = async.repartitions();
  ASSERT_GE(records.size(), 1U);
  EXPECT_EQ(records[0].step, 0);
  EXPECT_NE(records[0].reason.find("loads: part 'loaded1' fast from t = 0.0000 s"), std::string::npos)
      << records[0].reason;
  for (std::size_t k = 1; k < records.size(); ++k) {
    EXPECT_EQ(records[k].regions, k % 2 == 0 ? 1 : 0) << records[k].reason;
    EXPECT_NE(records[k].reason.find(k % 2 == 0 ? "fast from" : "released at"), std::string::npos) << records[k].reason;
  }
}

// The probe: an impulse (the scene's form: the force I / hL over (t + hL/2, t + 3 hL/2]) at
// t = 0.012 reaches its vertices in the one large step whose end lies in that window, and
// only those vertices; gravity (constant) reaches nothing.
TEST(LoadsPolicy, TheProbeSeesAnImpulseInTheStepThatDeliversIt) {
  const Problem bar = test::stiffEndBarProblem();
  const std::vector<int> hit{bar.mesh().vertexSet("xmax")[0], bar.mesh().vertexSet("xmax")[1]};
  const double time = 0.012;
  VertexLoad impulse{hit, Eigen::Vector3d(0.0, 0.0, 1.0 / kLargeStep), time + 0.5 * kLargeStep, time + 1.5 * kLargeStep,
                     true};
  ProblemSettings settings = test::testSettings(ForceModelType::linear);
  settings.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  const test::TestBody body(Problem(bar.sharedMesh(), bar.fixedVertices(), settings, {impulse}));
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(body.mesh.numDofs());
  for (int k = 0; k < 6; ++k) {
    const double t0 = k * kLargeStep;
    const std::vector<int> reached = verticesReachedByLoads(body.system.externalForce, body.system.externalForceChanges,
                                                            t0, t0, kLargeStep, 4, zero, zero);
    // The window (0.0145, 0.0195] holds 0.015 (end of step 2) and, for ratio 4, the substep
    // times of step 2 from 0.01625 on and of step 3 up to 0.01875: steps 2 and 3 see it
    // start and end, the others nothing.
    if (k == 2 || k == 3) {
      EXPECT_EQ(reached, hit) << "step " << k;
    } else {
      EXPECT_TRUE(reached.empty()) << "step " << k;
    }
  }
}

// The energy the release is measured on: zero for a rigid motion of the neighbourhood (a
// translation plus a spin, at a displaced state), positive for a part that moves on its own.
TEST(LoadsPolicy, RelativeMotionEnergyIgnoresRigidMotion) {
  const Problem bar = test::stiffEndBarProblem();
  const TetMesh& mesh = bar.mesh();
  const Eigen::VectorXd mass = lumpedVertexMasses(mesh);
  EXPECT_NEAR(mass.sum(), 0.25 * 0.25 * (0.75 * 1000.0 + 0.25 * 200.0), 1e-12);
  std::vector<int> all(static_cast<std::size_t>(mesh.numVertices()));
  for (int v = 0; v < mesh.numVertices(); ++v) all[static_cast<std::size_t>(v)] = v;
  const std::vector<int> tip = test::verticesBeyond(mesh, 0.75);
  Eigen::VectorXd u(mesh.numDofs()), v(mesh.numDofs());
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d spin(0.3, -2.0, 1.5), drift(0.1, 0.2, -0.3);
  for (int i = 0; i < mesh.numVertices(); ++i) {
    const Eigen::Vector3d x = rotation * mesh.restPosition(i) + Eigen::Vector3d(0.5, 0, 0);
    u.segment<3>(3 * i) = x - mesh.restPosition(i);
    v.segment<3>(3 * i) = drift + spin.cross(x);
  }
  const double kinetic = 0.5 * [&] {
    double sum = 0.0;
    for (int i = 0; i < mesh.numVertices(); ++i) sum += mass[i] * v.segment<3>(3 * i).squaredNorm();
    return sum;
  }();
  EXPECT_LT(relativeMotionEnergy(mesh, mass, tip, all, u, v), 1e-24 * kinetic + 1e-30);
  // The tip alone swings: it moves relative to the whole body's best rigid fit.
  for (int i : tip) v.segment<3>(3 * i) += Eigen::Vector3d(0.0, 1.0, 0.0);
  EXPECT_GT(relativeMotionEnergy(mesh, mass, tip, all, u, v), 1e-3 * kinetic);
  EXPECT_EQ(relativeMotionEnergy(mesh, mass, {}, all, u, v), 0.0);
}

TEST(LoadsPolicy, SceneKeysAndErrors) {
  const IntegratorContext context = test::barContext();
  const nlohmann::json options = nlohmann::json::parse(R"({"regions": {"adaptive": {"loads": {
      "ratio": 6, "rings": 2, "release": 0.02, "neighbourhood": 1,
      "parts": [{"name": "tip", "boxes": [{"min": [0.74, -1, -1], "max": [2, 2, 2]}]},
                {"name": "end", "ratio": 3, "vertexSets": ["xmax"]}]}, "minDwell": 3}}})");
  const AsyncSettings parsed = parseAsyncSettings(context, options);
  ASSERT_TRUE(parsed.adaptive);
  const RunTimeRegionOptions& adaptive = *parsed.adaptive;
  EXPECT_TRUE(adaptive.loads);
  EXPECT_EQ(adaptive.loadsRatio, 6);
  EXPECT_EQ(adaptive.loadsRings, 2);
  EXPECT_EQ(adaptive.loadsRelease, 0.02);
  EXPECT_EQ(adaptive.loadsNeighbourhood, 1);
  EXPECT_EQ(adaptive.minDwell, 3);
  ASSERT_EQ(adaptive.loadsParts.size(), 2U);
  EXPECT_EQ(adaptive.loadsParts[0].name, "tip");
  EXPECT_EQ(adaptive.loadsParts[0].ratio, 6);  // the policy's ratio where the part gives none
  EXPECT_EQ(adaptive.loadsParts[0].vertices, test::verticesBeyond(*context.mesh, 0.75));
  EXPECT_EQ(adaptive.loadsParts[1].ratio, 3);
  EXPECT_EQ(asyncSettingsJson(parsed)["regions"], options["regions"]);
  const auto error = [&](const char* text) {
    try {
      (void)parseAsyncSettings(context, nlohmann::json::parse(text));
    } catch (const ValidationError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error(R"({"regions": {"adaptive": {"loads": {"release": 1.5}}}})").find("adaptive.loads.release"),
            std::string::npos);
  EXPECT_NE(error(R"({"regions": {"adaptive": {"loads": {"ratio": 1}}}})").find("adaptive.loads.ratio"),
            std::string::npos);
  EXPECT_NE(error(R"({"regions": {"adaptive": {"loads": {"parts": [{"ratio": 1, "vertices": [1]}]}}}})")
                .find("loads.parts[0].ratio"),
            std::string::npos);
  EXPECT_NE(error(R"({"regions": {"adaptive": {"loads": {"lookahead": 1}}}})").find("loads.lookahead"),
            std::string::npos);
  // The policy needs loads to probe.
  test::TestSystem free = test::makeTestSystem(0.0, 0.0);
  free.system.externalForce = nullptr;
  AsyncBackwardEuler async(free.mesh, free.system, kLargeStep, {});
  RunTimeRegionOptions loads;
  loads.loads = true;
  EXPECT_THROW(async.setRunTimeRegions(loads), ValidationError);
}

}  // namespace
}  // namespace asyncfem
