// SPDX-License-Identifier: BSD-3-Clause
// AsyncSettings to JSON and back: asyncSettingsJson() is read by parseAsyncSettings() to
// the same solver options and regions, proposed regions included.
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/registration.hpp>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

void expectSameSolverOptions(const AsyncOptions& a, const AsyncOptions& b) {
  EXPECT_EQ(a.coupling, b.coupling);
  EXPECT_EQ(a.schur, b.schur);
  EXPECT_EQ(a.method, b.method);
  EXPECT_EQ(a.recovery, b.recovery);
  EXPECT_EQ(a.regionSolver, b.regionSolver);
  EXPECT_EQ(a.contact.substepStatePrediction, b.contact.substepStatePrediction);
  EXPECT_EQ(a.keptFactors.laggedSchur, b.keptFactors.laggedSchur);
  EXPECT_EQ(a.keptFactors.laggedSchurRotation, b.keptFactors.laggedSchurRotation);
  EXPECT_EQ(a.threads, b.threads);
  EXPECT_EQ(a.contact.iterations, b.contact.iterations);
  EXPECT_EQ(a.contact.tolerance, b.contact.tolerance);
  EXPECT_EQ(a.contact.certifyContactFree, b.contact.certifyContactFree);
}

void expectSameRegions(const std::vector<AsyncRegion>& a, const std::vector<AsyncRegion>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].name, b[i].name);
    EXPECT_EQ(a[i].ratio, b[i].ratio);
    EXPECT_EQ(a[i].vertices, b[i].vertices);
  }
}

// Every non-default value of every solver key, with regions given by a selector and by
// ids, comes back unchanged (the regions as resolved vertex lists).
TEST(AsyncSettingsCodec, ExplicitSettingsRoundTrip) {
  const IntegratorContext context = test::barContext();
  std::vector<int> midBarVertices;  // the cross-section at x = 0.5, away from the stiff end
  for (int v = 0; v < context.mesh->numVertices(); ++v) {
    if (std::abs(context.mesh->restPosition(v).x() - 0.5) < 1e-9) midBarVertices.push_back(v);
  }
  ASSERT_FALSE(midBarVertices.empty());
  const std::vector<nlohmann::json> solverKeys{
      {{"coupling", "paper"}, {"schur", "lu"}, {"method", "naive"}, {"recovery", "substitution"}},
      {{"schur", "symmetric"}, {"recovery", "dense-z"}, {"regionSolver", "eigen-ldlt"}, {"laggedSchur", false}},
      {{"regionSolver", "umfpack"}, {"threads", 3}, {"laggedSchurRotation", false}},
      {{"contactIterations", 12}, {"contactTolerance", 1e-6}, {"certifyContactFree", false}},
      nlohmann::json::object()};
  for (nlohmann::json options : solverKeys) {
    options["regions"] = {{{"name", "stiff"}, {"ratio", 6}, {"elementSets", {"stiff"}}},
                          {{"name", ""}, {"ratio", 2}, {"vertices", midBarVertices}}};
    const AsyncSettings parsed = parseAsyncSettings(context, options);
    const nlohmann::json written = asyncSettingsJson(parsed);
    const AsyncSettings again = parseAsyncSettings(context, written);
    SCOPED_TRACE(written.dump());
    expectSameSolverOptions(parsed.solver, again.solver);
    expectSameRegions(parsed.regions, again.regions);
    EXPECT_FALSE(again.automaticRegions);
  }
}

// Default solver options write no key but "regions", so the object also suits
// "multirate-uncoupled", which rejects the async-only keys.
TEST(AsyncSettingsCodec, DefaultsWriteRegionsAlone) {
  AsyncSettings settings;
  settings.regions = {{"tip", {4, 2, 9}, 8}};
  const nlohmann::json written = asyncSettingsJson(settings);
  EXPECT_EQ(written.size(), 1u) << written.dump();
  EXPECT_EQ(written.at("regions"), nlohmann::json::parse(R"([{"name": "tip", "ratio": 8, "vertices": [4, 2, 9]}])"));
}

// Proposed regions are written as the regions the proposal kept: reading them back runs
// no proposal and gives the same partition.
TEST(AsyncSettingsCodec, AutomaticRegionsAreWrittenResolved) {
  const IntegratorContext context = test::barContext();
  const nlohmann::json options = {{"regions", "auto"}, {"auto", {{"modalCheck", false}, {"costCheck", false}}}};
  const AsyncSettings parsed = parseAsyncSettings(context, options);
  ASSERT_TRUE(parsed.automaticRegions);
  ASSERT_FALSE(parsed.regions.empty()) << "the stiff light end should want a fast region at hL = 0.01";
  const AsyncSettings again = parseAsyncSettings(context, asyncSettingsJson(parsed));
  EXPECT_FALSE(again.automaticRegions);
  EXPECT_FALSE(again.proposal.has_value());
  expectSameRegions(parsed.regions, again.regions);
}

TEST(AsyncSettingsCodec, LargestRatio) {
  EXPECT_EQ(largestRatio({}), 1);
  EXPECT_EQ(largestRatio({{"a", {0}, 2}, {"b", {1}, 7}, {"c", {2}, 3}}), 7);
}

}  // namespace
}  // namespace asyncfem
