// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>

namespace asyncfem {
namespace {

struct Fixture {
  std::shared_ptr<const TetMesh> mesh;
  std::unique_ptr<Problem> problem;
  IntegratorRegistry registry;
  Fixture() {
    BeamSpec spec;
    spec.cellsAlongLength = 6;
    mesh = std::make_shared<const TetMesh>(makeBeamMesh(spec));
    problem = std::make_unique<Problem>(mesh, mesh->vertexSets().at("root"), ProblemSettings{});
    registerSingleRateIntegrators(registry);
    registerMultirateIntegrators(registry);
  }
  IntegratorContext context(double timestep = 0.01) const {
    IntegratorContext c;
    c.mesh = mesh;
    c.system = problem->dynamicSystem();
    c.timestep = timestep;
    c.sourceName = "test.json";
    return c;
  }
  std::string failure(const std::string& name, const nlohmann::json& options, double timestep = 0.01) const {
    try {
      registry.create(name, context(timestep), options);
    } catch (const Error& error) {
      return error.what();
    }
    return "no error";
  }
};

TEST(IntegratorRegistry, EachLibraryRegistersItsIntegrators) {
  const Fixture f;
  for (const char* name :
       {"backward-euler", "trapezoidal", "central-differences", "symplectic-euler", "async", "multirate-uncoupled"}) {
    EXPECT_NE(f.registry.find(name), nullptr) << name;
  }
  const auto integrator = f.registry.create("async", f.context(),
                                            {{"regions", {{{"name", "tip"}, {"ratio", 4}, {"vertexSets", {"tip"}}}}}});
  ASSERT_EQ(regionSummaries(*integrator).size(), 1u);
  EXPECT_EQ(regionSummaries(*integrator)[0].name, "tip");
  EXPECT_EQ(regionSummaries(*integrator)[0].ratio, 4);
  EXPECT_GT(regionSummaries(*integrator)[0].interfaceDofs, 0);
  const int tipVertex = f.mesh->vertexSets().at("tip").back();
  EXPECT_EQ(regionOfVertex(*integrator, tipVertex), 0);
  EXPECT_EQ(regionOfVertex(*integrator, f.mesh->vertexSets().at("root").front()), -1);
}

TEST(IntegratorRegistry, ErrorsNameTheKey) {
  const Fixture f;
  EXPECT_EQ(f.failure("nope", nlohmann::json::object()).rfind("test.json: integrator.name: unknown integrator", 0), 0u);
  EXPECT_EQ(f.failure("backward-euler", {{"solvr", "cholmod"}}).rfind("test.json: integrator.options.solvr", 0), 0u)
      << f.failure("backward-euler", {{"solvr", "cholmod"}});
  EXPECT_EQ(f.failure("async", {{"auto", {{"grow", 2}}}}).rfind("test.json: integrator.options.auto.grow", 0), 0u)
      << f.failure("async", {{"auto", {{"grow", 2}}}});
  // An explicit method above its stable step: the error is at the timestep's key, by type.
  const std::string message = f.failure("central-differences", nlohmann::json::object(), 0.05);
  EXPECT_EQ(message.rfind("test.json: integrator.timestep: timestep 0.05 exceeds", 0), 0u) << message;
}

TEST(IntegratorRegistry, SwitchingDropsForeignOptionsOnly) {
  const Fixture f;
  nlohmann::json options = {{"regions", "auto"}, {"coupling", "paper"}, {"solver", "umfpack"}};
  EXPECT_EQ(f.registry.dropForeignOptions("backward-euler", options),
            (std::vector<std::string>{"coupling", "regions"}));
  EXPECT_EQ(options, (nlohmann::json{{"solver", "umfpack"}}));
}

}  // namespace
}  // namespace asyncfem
