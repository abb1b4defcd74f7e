// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/vertexSelection.hpp>
#include <filesystem>
#include <fstream>

namespace asyncfem {
namespace {

TetMesh beam() {
  BeamSpec spec;
  spec.cellsAlongLength = 4;
  return makeBeamMesh(spec);
}

TEST(VertexSelection, UnionOfSetsBoxesIdsSortedUnique) {
  const TetMesh mesh = beam();
  VertexSelection selection;
  selection.sets = {"root"};
  selection.vertices = {mesh.vertexSets().at("root").front(), 5};
  selection.boxes.push_back({Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(0.0, 10, 10)});  // the x = 0 face again
  const std::vector<int> selected = selectVertices(mesh, selection);
  std::vector<int> expected = mesh.vertexSets().at("root");
  expected.push_back(5);
  std::sort(expected.begin(), expected.end());
  expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
  EXPECT_EQ(selected, expected);
}

TEST(VertexSelection, ElementSetsSelectTheirVertices) {
  const TetMesh mesh = beam();
  VertexSelection selection;
  selection.sets = {"tip"};
  ASSERT_TRUE(mesh.elementSets().count("tip"));
  EXPECT_EQ(selectVertices(mesh, selection), mesh.setVertices("tip"));
}

TEST(VertexSelection, ErrorsNameThePartAndIndex) {
  const TetMesh mesh = beam();
  const auto failure = [&](const VertexSelection& selection) {
    try {
      selectVertices(mesh, selection);
    } catch (const SelectionError& error) {
      return error.keySuffix() + ": " + error.what();
    }
    return std::string("no error");
  };
  VertexSelection unknown;
  unknown.sets = {"root", "nope"};
  EXPECT_EQ(failure(unknown).rfind("sets[1]: unknown set \"nope\"", 0), 0u) << failure(unknown);
  // The message lists the sets and says where sets come from in each format.
  EXPECT_NE(failure(unknown).find("(vertex sets: root, tip, xmax"), std::string::npos) << failure(unknown);
  EXPECT_NE(failure(unknown).find("vertex sets come from Gmsh physical surfaces, curves and points, TetGen .face "
                                  "markers (marker_<k>)"),
            std::string::npos)
      << failure(unknown);
  VertexSelection emptyBox;
  emptyBox.boxes.push_back({Eigen::Vector3d(50, 50, 50), Eigen::Vector3d(60, 60, 60)});
  EXPECT_EQ(failure(emptyBox), "boxes[0]: selects no vertex");
  VertexSelection inverted;
  inverted.boxes.push_back({Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(0, 0, 0)});
  EXPECT_EQ(failure(inverted), "boxes[0]: expected min <= max");
  VertexSelection outOfRange;
  outOfRange.vertices = {0, mesh.numVertices()};
  EXPECT_EQ(failure(outOfRange).rfind("vertices[1]: vertex " + std::to_string(mesh.numVertices()), 0), 0u);
  VertexSelection missingBou;
  missingBou.bouFile = "/nonexistent/fixed.bou";
  EXPECT_EQ(failure(missingBou).rfind("bou: ", 0), 0u);
}

TEST(VertexSelection, BouFileIsOneBased) {
  const TetMesh mesh = beam();
  const auto path = std::filesystem::temp_directory_path() / "asyncfem-selection-test.bou";
  {
    std::ofstream out(path);
    out << "1, 3,\n";
  }
  VertexSelection selection;
  selection.bouFile = path;
  EXPECT_EQ(selectVertices(mesh, selection), (std::vector<int>{0, 2}));
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace asyncfem
