// SPDX-License-Identifier: BSD-3-Clause
// Every validation error of the region partition names what is wrong.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <string>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

std::string partitionError(const test::TestSystem& ts, std::vector<AsyncRegion> regions) {
  try {
    RegionPartition partition(ts.mesh, ts.system.freeDofs, std::move(regions));
  } catch (const ValidationError& e) {
    return e.what();
  }
  return "";
}

TEST(RegionPartition, RejectsRatioBelowOne) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  const std::string message = partitionError(ts, {{"tip", test::verticesBeyond(ts.mesh, 0.875), 0}});
  EXPECT_NE(message.find("'tip'"), std::string::npos) << message;
  EXPECT_NE(message.find("ratio"), std::string::npos) << message;
}

TEST(RegionPartition, RejectsOverlapNamingTheVertex) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.875);
  const std::string message = partitionError(ts, {{"a", tip, 2}, {"b", {tip.back()}, 2}});
  EXPECT_NE(message.find("overlap"), std::string::npos) << message;
  EXPECT_NE(message.find("vertex " + std::to_string(tip.back())), std::string::npos) << message;
}

// Regions that touch are a partition (the hierarchy solve runs them); a solve that couples
// each region only to L refuses them, naming an element and both regions. Regions one
// element layer apart do not touch.
TEST(RegionPartition, TouchingRegionsAreNamedWhereTheyMustBeSeparated) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  const RegionPartition touching(
      ts.mesh, ts.system.freeDofs,
      {{"a", test::verticesOnPlanes(ts.mesh, {0.5}), 2}, {"b", test::verticesOnPlanes(ts.mesh, {0.625}), 2}});
  EXPECT_TRUE(touching.touching());
  EXPECT_EQ(touching.levels(), (std::vector<int>{1, 2}));
  try {
    touching.requireSeparated("two-level solve");
    FAIL() << "touching regions passed requireSeparated";
  } catch (const ValidationError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("two-level solve: element ", 0), 0u) << message;
    EXPECT_NE(message.find("'a' and 'b'"), std::string::npos) << message;
  }
  const RegionPartition apart(
      ts.mesh, ts.system.freeDofs,
      {{"a", test::verticesOnPlanes(ts.mesh, {0.25}), 2}, {"b", test::verticesOnPlanes(ts.mesh, {0.625}), 4}});
  EXPECT_FALSE(apart.touching());
  EXPECT_NO_THROW(apart.requireSeparated("two-level solve"));
  EXPECT_EQ(apart.units(), 4);
  EXPECT_EQ(apart.levels(), (std::vector<int>{1, 2, 4}));
}

TEST(RegionPartition, RejectsRegionWithoutFreeDofs) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  const std::string message = partitionError(ts, {{"root", ts.mesh.vertexSet("xmin"), 2}});
  EXPECT_NE(message.find("'root'"), std::string::npos) << message;
  EXPECT_NE(message.find("no free"), std::string::npos) << message;
}

TEST(RegionPartition, RejectsOutOfRangeVertex) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  const std::string message = partitionError(ts, {{"x", {ts.mesh.numVertices()}, 2}});
  EXPECT_NE(message.find("vertex " + std::to_string(ts.mesh.numVertices())), std::string::npos) << message;
}

TEST(RegionPartition, InterfaceIsTheLayerOfLNextToS) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  RegionPartition partition(ts.mesh, ts.system.freeDofs, {{"tip", test::verticesBeyond(ts.mesh, 0.875), 3}});
  // Interface L vertices: the plane x = 0.75 (one cell before the S planes 0.875 and 1).
  const std::vector<int> plane = test::verticesOnPlanes(ts.mesh, {0.75});
  EXPECT_EQ(partition.interfaceDofs(0).size(), 3 * plane.size());
  for (int dof : partition.interfaceDofs(0)) {
    EXPECT_NEAR(ts.mesh.restPosition(dof / 3).x(), 0.75, 1e-12);
  }
  EXPECT_EQ(partition.regionDofs(0).size(), 3 * test::verticesBeyond(ts.mesh, 0.875).size());
  EXPECT_FALSE(partition.interfaceElements().empty());
}

TEST(RegionPartition, SelectorResolvesSetsBoxesAndIds) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  RegionSelector selector;
  selector.vertexSets = {"xmax"};
  selector.boxMin = {Eigen::Vector3d(0.49, -1, -1)};
  selector.boxMax = {Eigen::Vector3d(0.51, 1, 1)};
  selector.vertices = {0};
  const std::vector<int> got = regionVertices(ts.mesh, selector);
  const std::size_t expected = ts.mesh.vertexSet("xmax").size() + test::verticesOnPlanes(ts.mesh, {0.5}).size() + 1;
  EXPECT_EQ(got.size(), expected);
  selector.vertexSets = {"nope"};
  EXPECT_THROW(regionVertices(ts.mesh, selector), ValidationError);
}

}  // namespace
}  // namespace asyncfem
