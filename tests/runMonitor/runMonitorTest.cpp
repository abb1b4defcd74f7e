// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>

namespace asyncfem {
namespace {

std::shared_ptr<const TetMesh> beam() {
  BeamSpec spec;
  spec.cellsAlongLength = 6;
  return std::make_shared<const TetMesh>(makeBeamMesh(spec));
}

/// An integrator whose step does what a test tells it to the state.
class ScriptedIntegrator : public Integrator {
 public:
  using Script = std::function<void(long long step, Eigen::VectorXd& u, Eigen::VectorXd& v)>;
  ScriptedIntegrator(DynamicSystem system, double h, Script script)
      : Integrator(std::move(system), h), script_(std::move(script)) {}
  std::string name() const override { return "scripted"; }
  void step() override {
    script_(++steps_, displacement_, velocity_);
    advanceTime();
  }

 private:
  Script script_;
  long long steps_ = 0;
};

TEST(RunMonitor, NonFiniteStateIsReportedWithItsLocation) {
  const auto mesh = beam();
  const Problem problem(mesh, mesh->vertexSets().at("root"), ProblemSettings{});
  const int vertex = mesh->vertexSets().at("tip").front();
  ScriptedIntegrator integrator(problem.dynamicSystem(), 0.01, [&](long long step, Eigen::VectorXd& u, auto&) {
    if (step == 5) u[3 * vertex + 2] = std::nan("");
  });
  RunMonitor monitor(problem);
  monitor.advanceFrame(integrator, 0, 3);  // steps 1-3: fine
  try {
    monitor.advanceFrame(integrator, 1, 3);  // step 5 fails
    FAIL() << "no error";
  } catch (const NumericalError& error) {
    EXPECT_EQ(error.location().frame, 1);
    EXPECT_EQ(error.location().step, 5);
    EXPECT_EQ(error.location().vertex, vertex);
    EXPECT_EQ(error.location().dof, 3 * vertex + 2);
    EXPECT_NEAR(error.location().time, 0.05, 1e-15);
    EXPECT_NE(std::string(error.what()).find("not finite"), std::string::npos);
  }
}

TEST(RunMonitor, BlowUpBeyondTheLimitIsAnError) {
  const auto mesh = beam();
  const Problem problem(mesh, {}, ProblemSettings{});
  RunMonitor monitor(problem);
  const double limit = monitor.blowUpDisplacement();
  EXPECT_NEAR(limit, 1000.0 * monitor.boundingBoxDiagonal(), 1e-12 * limit);
  double amplitude = 0.5 * limit;
  ScriptedIntegrator integrator(problem.dynamicSystem(), 0.01,
                                [&](long long, Eigen::VectorXd& u, auto&) { u[7] = amplitude; });
  monitor.advanceFrame(integrator, 0, 1);  // below the limit: fine
  amplitude = 1.01 * limit;
  try {
    monitor.advanceFrame(integrator, 1, 1);
    FAIL() << "no error";
  } catch (const NumericalError& error) {
    EXPECT_EQ(error.location().vertex, 2);
    EXPECT_NE(std::string(error.what()).find("blow-up"), std::string::npos);
  }
}

/// A beam pulled up at its tip until t = 0.1, whose scripted step then sets one tip
/// velocity that grows 1.5 x per step: kinetic energy grows 2.25 x per step.
struct GrowingEnergyRun {
  static VertexLoad tipPull(const TetMesh& mesh) {
    VertexLoad pull;
    pull.vertices = mesh.vertexSets().at("tip");
    pull.perVertex = Eigen::Vector3d(0, 1, 0);
    pull.end = 0.1;
    return pull;
  }
  std::shared_ptr<const TetMesh> mesh = beam();
  VertexLoad pull = tipPull(*mesh);
  Problem problem{mesh, mesh->vertexSets().at("root"), ProblemSettings{}, {pull}};
  double speed = 1.0;
  ScriptedIntegrator integrator{problem.dynamicSystem(), 0.01, [this](long long, Eigen::VectorXd&, Eigen::VectorXd& v) {
                                  v = Eigen::VectorXd::Zero(v.size());
                                  v[3 * pull.vertices.front()] = speed;
                                  speed *= 1.5;
                                }};
};

TEST(RunMonitor, EnergyGrowthAfterTheLoadsIsAnErrorAndNotBefore) {
  GrowingEnergyRun run;
  RunMonitor monitor(run.problem);
  EXPECT_NEAR(monitor.energyCheckFrom(), 0.1, 1e-15);
  // While the load acts (t < 0.1) energy may grow: no check.
  for (int frame = 0; frame < 10; ++frame) monitor.advanceFrame(run.integrator, frame, 1);
  EXPECT_EQ(monitor.energyEvaluations(), 0);
  monitor.advanceFrame(run.integrator, 10, 1);  // the first free frame: the reference
  EXPECT_EQ(monitor.energyEvaluations(), 1);
  monitor.advanceFrame(run.integrator, 11, 1);                                // 2.25 x: below 10 x
  monitor.advanceFrame(run.integrator, 12, 1);                                // 5.1 x
  EXPECT_THROW(monitor.advanceFrame(run.integrator, 13, 1), NumericalError);  // 11.4 x
}

/// A free beam over a ground plane through its lowest vertices (k = 1e4 per vertex), its
/// scripted step setting the state.
struct ContactRun {
  explicit ContactRun(Eigen::Vector3d gravity = Eigen::Vector3d::Zero()) {
    ContactPlane ground;
    ground.offset = mesh->restPositions().row(1).minCoeff();
    PenaltyContactParameters parameters;
    parameters.stiffness = 1e4;
    contact = std::make_shared<PenaltyContact>(mesh->restPositions(), std::vector<ContactPlane>{ground},
                                               std::vector<ContactSphere>{}, parameters);
    ProblemSettings settings;
    settings.gravity = gravity;
    problem = std::make_unique<Problem>(mesh, std::vector<int>{}, settings, std::vector<VertexLoad>{}, contact);
  }
  std::shared_ptr<const TetMesh> mesh = beam();
  std::shared_ptr<const PenaltyContact> contact;
  std::unique_ptr<Problem> problem;
};

// With contact the energy check runs too (from the last window, here t = 0), the penalty
// potential in the energy: a beam held at one depth in the ground keeps it, one sinking
// deeper (the potential 4x per frame, nothing else changing) is stopped at the frame that
// passes 10x, and the message names the contact's term.
TEST(RunMonitor, ContactScenesAreCheckedWithTheirPenaltyEnergy) {
  ContactRun run;
  double depth = 1e-3;
  ScriptedIntegrator integrator(run.problem->dynamicSystem(), 0.01, [&](long long, Eigen::VectorXd& u, auto& v) {
    v.setZero();
    for (Eigen::Index dof = 1; dof < u.size(); dof += 3) u[dof] = -depth;  // the whole beam, rigidly
  });
  RunMonitor monitor(*run.problem);
  EXPECT_EQ(monitor.energyCheckFrom(), 0.0);
  for (int frame = 0; frame < 5; ++frame) monitor.advanceFrame(integrator, frame, 1);
  EXPECT_EQ(monitor.energyEvaluations(), 5);
  depth *= 2;
  monitor.advanceFrame(integrator, 5, 1);  // 4 x
  depth *= 2;
  try {
    monitor.advanceFrame(integrator, 6, 1);  // 16 x
    FAIL() << "no error";
  } catch (const NumericalError& error) {
    EXPECT_EQ(error.location().frame, 6);
    EXPECT_NE(std::string(error.what()).find("kinetic + elastic + contact penalty"), std::string::npos) << error.what();
  }
  for (const std::string& line : monitor.skipped()) EXPECT_EQ(line.find("energy"), std::string::npos) << line;
}

// A body at rest under gravity starts the free phase at zero energy: the constant load's
// work over the body's size sets the scale, so that a small gain (the kinetic energy of
// 1 mm/s) does not stop the run, where 9 x zero would; a gain of 10 x that scale does.
TEST(RunMonitor, ContactScenesAtRestTakeTheLoadWorkAsTheEnergyScale) {
  ContactRun run(Eigen::Vector3d(0, -9.81, 0));
  double speed = 0.0;
  ScriptedIntegrator integrator(run.problem->dynamicSystem(), 0.01, [&](long long, Eigen::VectorXd& u, auto& v) {
    u.setZero();                                                          // resting on the ground, no penetration
    for (Eigen::Index dof = 0; dof < v.size(); dof += 3) v[dof] = speed;  // sliding along x
  });
  RunMonitor monitor(*run.problem);
  monitor.advanceFrame(integrator, 0, 1);  // the reference: zero
  speed = 1e-3;
  EXPECT_NO_THROW(monitor.advanceFrame(integrator, 1, 1));
  // m g diagonal = m v^2 / 2 at v = sqrt(2 g diagonal): 10 x that energy.
  speed = std::sqrt(10.0 * 2.0 * 9.81 * monitor.boundingBoxDiagonal());
  EXPECT_THROW(monitor.advanceFrame(integrator, 2, 1), NumericalError);
}

TEST(RunMonitor, EnergyReferenceCarriedThroughStateStopsAResumedRunAtTheSameFrame) {
  // A resumed run continues with a new monitor: with the state of the one before (what the
  // checkpoint holds), its energy check stops at the frame the uninterrupted run stops at;
  // a monitor that takes its reference afresh after the resume would let the run go on.
  GrowingEnergyRun run;
  RunMonitor before(run.problem);
  EXPECT_EQ(before.state().size(), 0);  // no reference before the free phase
  for (int frame = 0; frame <= 11; ++frame) before.advanceFrame(run.integrator, frame, 1);  // reference at frame 10
  const Eigen::VectorXd state = before.state();
  ASSERT_EQ(state.size(), 3);
  EXPECT_NEAR(state[2], 0.11, 1e-12);  // the time of the reference

  RunMonitor resumed(run.problem);
  resumed.setState(state);
  EXPECT_TRUE(resumed.state() == state);
  const double speedAtResume = run.speed;
  resumed.advanceFrame(run.integrator, 12, 1);                                // 5.1 x the reference
  EXPECT_THROW(resumed.advanceFrame(run.integrator, 13, 1), NumericalError);  // 11.4 x: as without the stop

  run.speed = speedAtResume;  // the same frames with a monitor that lost the reference
  RunMonitor forgetful(run.problem);
  forgetful.advanceFrame(run.integrator, 12, 1);
  EXPECT_NO_THROW(forgetful.advanceFrame(run.integrator, 13, 1));
  EXPECT_THROW(resumed.setState(Eigen::VectorXd::Zero(2)), Error);
}

/// A scripted integrator that reports one fast region holding the "tip" vertices, as
/// multirate integrators do through the MultirateIntegrator interface.
class ScriptedMultirate : public ScriptedIntegrator, public MultirateIntegrator {
 public:
  ScriptedMultirate(DynamicSystem system, double h, Script script, std::vector<int> tip)
      : ScriptedIntegrator(std::move(system), h, std::move(script)), tip_(std::move(tip)) {}
  std::vector<RegionSummary> regionSummaries() const override { return {{"tip", static_cast<int>(tip_.size()), 0, 4}}; }
  int regionOfVertex(int vertex) const override {
    return std::binary_search(tip_.begin(), tip_.end(), vertex) ? 0 : -1;
  }
  const MultirateIntegrator* multirate() const override { return this; }

 private:
  std::vector<int> tip_;
};

TEST(RunMonitor, ErrorsNameTheRegionOfTheVertex) {
  const auto mesh = beam();
  const Problem problem(mesh, mesh->vertexSets().at("root"), ProblemSettings{});
  const std::vector<int>& tip = mesh->vertexSets().at("tip");
  const int vertex = tip.back();
  ScriptedMultirate integrator(
      problem.dynamicSystem(), 0.01,
      [&](long long step, Eigen::VectorXd& u, auto&) {
        if (step == 3) u[3 * vertex] = std::numeric_limits<double>::infinity();
      },
      tip);
  RunMonitor monitor(problem);
  try {
    for (int frame = 0; frame < 5; ++frame) monitor.advanceFrame(integrator, frame, 1);
    FAIL() << "no error";
  } catch (const NumericalError& error) {
    EXPECT_EQ(error.location().region, 0) << error.what();
    EXPECT_EQ(error.location().regionName, "tip");
    EXPECT_EQ(error.location().frame, 2);
    EXPECT_NE(std::string(error.what()).find("fast region S_1 'tip'"), std::string::npos) << error.what();
  }
}

// The integrator's own NumericalError (a non-finite load here) keeps its DOF and vertex and
// gains the frame and step.
TEST(RunMonitor, ErrorsOfTheIntegratorGainFrameAndStep) {
  const auto mesh = beam();
  const Problem problem(mesh, mesh->vertexSets().at("root"), ProblemSettings{});
  DynamicSystem system = problem.dynamicSystem();
  const int vertex = mesh->vertexSets().at("tip").back();
  system.externalForce = [vertex](double t, const auto&, const auto&, Eigen::VectorXd& f) {
    if (t > 0.025) f[3 * vertex] = std::nan("");
  };
  auto integrator = makeIntegrator("backward-euler", std::move(system), 0.01);
  RunMonitor monitor(problem);
  try {
    for (int frame = 0; frame < 10; ++frame) monitor.advanceFrame(*integrator, frame, 1);
    FAIL() << "no error";
  } catch (const NumericalError& error) {
    EXPECT_EQ(error.location().frame, 2) << error.what();
    EXPECT_EQ(error.location().step, 3);
    EXPECT_EQ(error.location().region, -1);
    EXPECT_NE(std::string(error.what()).find("frame 2 (step 3"), std::string::npos) << error.what();
  }
}

TEST(CheckpointSchedule, TimeFramesOrBoth) {
  const CheckpointSchedule byTime;  // the default: every 30 s
  EXPECT_FALSE(byTime.due(1, 29.9));
  EXPECT_TRUE(byTime.due(1, 30.0));
  EXPECT_EQ(byTime.describe(), "every 30 s of wall time");
  const CheckpointSchedule byFrames{5, 0.0};
  EXPECT_FALSE(byFrames.due(4, 1000.0));
  EXPECT_TRUE(byFrames.due(10, 0.0));
  const CheckpointSchedule both{2, 10.0};
  EXPECT_TRUE(both.due(2, 0.0));
  EXPECT_TRUE(both.due(3, 11.0));
  EXPECT_FALSE(both.due(3, 1.0));
}

TEST(RunFingerprint, ChangesWithEveryPartOfTheRunIdentity) {
  const auto mesh = beam();
  const Problem problem(mesh, mesh->vertexSets().at("root"), ProblemSettings{});
  const std::uint32_t base = runFingerprint("{}", "async", 0.01, 1.0 / 30, problem);
  EXPECT_EQ(base, runFingerprint("{}", "async", 0.01, 1.0 / 30, problem));
  EXPECT_NE(base, runFingerprint("{\"a\":1}", "async", 0.01, 1.0 / 30, problem));
  EXPECT_NE(base, runFingerprint("{}", "backward-euler", 0.01, 1.0 / 30, problem));
  EXPECT_NE(base, runFingerprint("{}", "async", 0.02, 1.0 / 30, problem));
  const Problem otherBoundary(mesh, mesh->vertexSets().at("tip"), ProblemSettings{});
  EXPECT_NE(base, runFingerprint("{}", "async", 0.01, 1.0 / 30, otherBoundary));
}

}  // namespace
}  // namespace asyncfem
