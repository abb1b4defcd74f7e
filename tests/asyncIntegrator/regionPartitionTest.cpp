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

TEST(RegionPartition, RejectsElementTouchingTwoFastRegions) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  const std::string message = partitionError(
      ts, {{"a", test::verticesOnPlanes(ts.mesh, {0.5}), 2}, {"b", test::verticesOnPlanes(ts.mesh, {0.625}), 2}});
  EXPECT_NE(message.find("element "), std::string::npos) << message;
  EXPECT_NE(message.find("'a' and 'b'"), std::string::npos) << message;
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
