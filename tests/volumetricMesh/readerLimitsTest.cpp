// SPDX-License-Identifier: BSD-3-Clause
// Regression tests for inputs found by fuzzing the mesh readers (tests/fuzz,
// docs/robustness.md): each must fail fast with an error naming the problem, or read.
#include <gtest/gtest.h>

#include <asyncfem/volumetricMesh/readers.hpp>
#include <string>

#include "testFiles.hpp"

namespace asyncfem {
namespace {

// A Gmsh 4.1 mesh of one tetrahedron in volume entity 1, which lists physicalTags; then
// `elements` copies of the tetrahedron line (tags 1..elements).
std::string msh41WithPhysicals(const std::string& physicalTags, int numPhysicals, int elements) {
  std::string text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n1 0 0 0 1 1 1 " +
                     std::to_string(numPhysicals) + " " + physicalTags + " 0\n$EndEntities\n";
  text += "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n";
  text += "$Elements\n1 " + std::to_string(elements) + " 1 " + std::to_string(elements) + "\n3 1 4 " +
          std::to_string(elements) + "\n";
  for (int e = 1; e <= elements; ++e) text += std::to_string(e) + " 1 2 3 4\n";
  return text + "$EndElements\n";
}

TEST(ReaderLimits, GmshEntityInThousandsOfPhysicalGroupsFailsFast) {
  // Found while writing the fuzz harnesses and confirmed with fuzz_gmsh (an out-of-memory
  // report): every element joins every physical group of its entity, so 20000
  // groups x 20000 elements in a 380 kB file asked for 4e8 set memberships (> 2 GB).
  std::string tags;
  for (int t = 1; t <= 20000; ++t) tags += std::to_string(t) + " ";
  test::ScratchDir dir;
  const auto path = dir.write("many.msh", msh41WithPhysicals(tags, 20000, 20000));
  try {
    readGmsh(path);
    FAIL() << "accepted";
  } catch (const ParseError& error) {
    EXPECT_EQ(error.line(), 6U);
    EXPECT_NE(std::string(error.what()).find("volume entity 1 is in 20000 physical groups; at most 64 are supported"),
              std::string::npos)
        << error.what();
  }
}

TEST(ReaderLimits, GmshRepeatedPhysicalTagsCountOnce) {
  // 70 tags listed, 2 distinct: within the limit, and each element is in each set once.
  std::string tags;
  for (int t = 0; t < 70; ++t) tags += (t % 2 == 0 ? "5 " : "9 ");
  test::ScratchDir dir;
  const TetMesh mesh = readGmsh(dir.write("repeated.msh", msh41WithPhysicals(tags, 70, 1)));
  EXPECT_EQ(mesh.elementSet("physical_5"), std::vector<int>{0});
  EXPECT_EQ(mesh.elementSet("physical_9"), std::vector<int>{0});
}

}  // namespace
}  // namespace asyncfem
