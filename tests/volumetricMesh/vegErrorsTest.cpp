// SPDX-License-Identifier: BSD-3-Clause
// Malformed .veg input: one test per documented error, each checking that the message
// names the file, the line and the offending element, vertex, set or material.
#include <gtest/gtest.h>

#include <asyncfem/volumetricMesh/readers.hpp>
#include <string>

#include "testFiles.hpp"

namespace asyncfem {
namespace {

// Line numbers of the base file (see testFiles.hpp):
//  1 *VERTICES   2 header   3..7 vertices 1..5   8 *ELEMENTS   9 TET   10 header
// 11 element 1  12 element 2  13 *MATERIAL steel  14 ENU line  15 *REGION  16 allElements, steel
std::string baseVeg() {
  return std::string(test::kTwoTetVertices) + std::string(test::kTwoTetElements) + std::string(test::kSteelRegion);
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  // Built by concatenation: GCC 12 warns (-Wrestrict) on std::string::replace at -O3.
  return text.substr(0, at) + to + text.substr(at + from.size());
}

/// Writes the base file with one replacement and expects a ParseError at line.
void expectVegError(const std::string& from, const std::string& to, std::size_t line,
                    std::initializer_list<std::string> fragments, const MeshReadOptions& options = {}) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", replaced(baseVeg(), from, to));
  test::expectParseError([&] { readVeg(path, options); }, "bad.veg", line, fragments);
}

TEST(VegErrors, UnreadableFileIsAnErrorNamingThePath) {
  test::ScratchDir dir;
  const auto missing = dir.path() / "missing.veg";
  try {
    readVeg(missing);
    FAIL() << "expected asyncfem::Error";
  } catch (const ParseError&) {
    FAIL() << "a missing file is not a parse error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(readVeg(dir.path()), Error);  // a directory
}

// The message of readMesh(path) (empty when it reads).
std::string readMeshError(const std::string& path) {
  try {
    (void)readMesh(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(VegErrors, UnknownExtension) {
  EXPECT_EQ(readMeshError("mesh.xyz"),
            "cannot read mesh 'mesh.xyz': unknown extension '.xyz' (expected a .veg, .node, .ele or .msh file, or "
            "the base name of a TetGen .node/.ele pair)");
  // A surface format points to tetMesher, with the command for this file.
  for (const std::string surface : {"mesh.stl", "mesh.off", "mesh.OBJ"}) {
    const std::string message = readMeshError(surface);
    EXPECT_NE(message.find("is a surface format, and a simulation needs a tetrahedral mesh: make one with "
                           "tetMesher (tetMesher " +
                           surface + " --output mesh.veg; docs/tet-mesher.md)"),
              std::string::npos)
        << message;
  }
  // No extension: a TetGen base name, and the message says which files it looked for.
  EXPECT_EQ(readMeshError("cube"),
            "cannot read mesh 'cube': there is no TetGen pair 'cube.node' + 'cube.ele' (a name without an extension "
            "is taken as a TetGen base name); give a .veg, .node, .ele or .msh file, or the base name of a TetGen "
            ".node/.ele pair");
}

TEST(VegErrors, ElementVertexOutOfRange) {
  expectVegError("2 2 3 4 5", "2 2 3 4 9", 12, {"element 2", "vertex 9", "[1, 5]"});
}

TEST(VegErrors, ElementVertexZeroIsOutOfRange) {
  expectVegError("1 1 2 3 4", "1 0 2 3 4", 11, {"element 1", "vertex 0"});
}

TEST(VegErrors, ElementLineMissingAnIndex) { expectVegError("2 2 3 4 5", "2 2 3 4", 12, {"got 4 fields"}); }

TEST(VegErrors, ElementUsesVertexTwice) {
  expectVegError("1 1 2 3 4", "1 1 2 1 4", 11, {"element 1", "vertex 1 twice"});
}

TEST(VegErrors, LinesOfOnlySeparators) {
  expectVegError("5 3 0 0", ",", 2, {"*VERTICES needs a header line"});
  expectVegError("TET", ", ,", 9, {"unsupported element type"});
  expectVegError("ENU, 7800, 2e11, 0.3", ",,", 14, {"steel", "ENU, density, E, nu"});
}

TEST(VegErrors, FewerVerticesThanHeader) { expectVegError("5 3 0 0", "7 3 0 0", 2, {"7 vertices", "only 5"}); }

TEST(VegErrors, MoreVertexLinesThanHeader) {
  expectVegError("5 3 0 0", "4 3 0 0", 7, {"4 vertices", "more vertex lines"});
}

TEST(VegErrors, VertexIndexOutOfRange) { expectVegError("4 0 0 1", "9 0 0 1", 6, {"vertex index 9", "[1, 5]"}); }

TEST(VegErrors, MoreElementLinesThanHeader) {
  expectVegError("2 4 0", "1 4 0", 12, {"1 elements", "more element lines"});
}

TEST(VegErrors, FewerElementsThanHeader) { expectVegError("2 4 0", "3 4 0", 10, {"3 elements", "only 2"}); }

TEST(VegErrors, NonNumericCoordinate) { expectVegError("3 0 1 0", "3 0 1.5abc 0", 5, {"vertex 3", "'1.5abc'"}); }

TEST(VegErrors, NonNumericElementIndex) { expectVegError("2 2 3 4 5", "2 2 3x 4 5", 12, {"element 2", "'3x'"}); }

TEST(VegErrors, NanCoordinate) { expectVegError("3 0 1 0", "3 0 nan 0", 5, {"vertex 3", "not finite"}); }

TEST(VegErrors, InfiniteCoordinate) { expectVegError("4 0 0 1", "4 0 0 -inf", 6, {"vertex 4", "not finite"}); }

TEST(VegErrors, DuplicateVertexIndex) { expectVegError("3 0 1 0", "2 0 1 0", 5, {"duplicate vertex index 2"}); }

TEST(VegErrors, DegenerateElement) {
  // Vertex 4 moved into the plane of vertices 1, 2, 3: element 1 is flat.
  expectVegError("4 0 0 1", "4 1 1 0", 11, {"element 1", "degenerate"});
}

TEST(VegErrors, InvertedElementWithoutReorientation) {
  MeshReadOptions options;
  options.reorientInvertedElements = false;
  expectVegError("1 1 2 3 4", "1 1 3 2 4", 11, {"element 1", "inverted"}, options);
}

TEST(VegErrors, UnknownMaterialInRegion) {
  expectVegError("allElements, steel", "allElements, steal", 16, {"unknown material 'steal'", "steel"});
}

TEST(VegErrors, UnknownSetInRegion) {
  expectVegError("allElements, steel", "shell, steel", 16, {"unknown set 'shell'"});
}

TEST(VegErrors, ElementWithoutRegion) {
  test::ScratchDir dir;
  const std::string text = std::string(test::kTwoTetVertices) + std::string(test::kTwoTetElements) +
                           "*MATERIAL steel\nENU, 7800, 2e11, 0.3\n*SET one\n1\n*REGION\none, steel\n";
  const auto path = dir.write("bad.veg", text);
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 12, {"element 2", "no *REGION"});
}

// CUBIC files are read (hexMeshTest.cpp); a TET header under CUBIC is an error at the header.
TEST(VegErrors, CubicElementsNeedEightVertices) {
  expectVegError("TET", "CUBIC", 10, {"CUBIC elements have 8 vertices, but the header says 4"});
}

TEST(VegErrors, UnknownMaterialKeyword) {
  // MOONEYRIVLIN is read since Mooney-Rivlin materials exist (mooneyRivlinTest.cpp).
  expectVegError("ENU, 7800, 2e11, 0.3", "ORTHOTROPIC_N1, 1, 2, 3", 14, {"ORTHOTROPIC_N1", "steel"});
}

TEST(VegErrors, MaterialOutOfRange) {
  expectVegError("ENU, 7800, 2e11, 0.3", "ENU, 7800, 2e11, 0.5", 14, {"steel", "Poisson"});
  expectVegError("ENU, 7800, 2e11, 0.3", "ENU, -1, 2e11, 0.3", 14, {"steel", "density"});
}

TEST(VegErrors, MaterialDefinedTwice) {
  expectVegError("*REGION", "*MATERIAL steel\nENU, 1, 1, 0.1\n*REGION", 15, {"'steel' is defined twice"});
}

TEST(VegErrors, UnknownKeyword) { expectVegError("*REGION", "*FIXEDVERTICES\n*REGION", 15, {"*FIXEDVERTICES"}); }

TEST(VegErrors, AbsurdVertexCountFailsFast) {
  expectVegError("5 3 0 0", "1000000000000 3 0 0", 2, {"1000000000000"});
  expectVegError("5 3 0 0", "2000000000 3 0 0", 2, {"header says 2000000000 vertices", "can hold at most"});
  expectVegError("5 3 0 0", "-5 3 0 0", 2, {"negative"});
}

TEST(VegErrors, AbsurdElementCountFailsFast) {
  expectVegError("2 4 0", "900000000 4 0", 10, {"header says 900000000 elements"});
}

TEST(VegErrors, SetListsElementOutOfRange) {
  expectVegError("*REGION", "*SET s\n1,\n3\n*REGION", 17, {"set 's'", "element 3"});
}

TEST(VegErrors, SetWithNonNumericMember) {
  expectVegError("*REGION", "*SET s\n1, two\n*REGION", 16, {"set 's'", "'two'"});
}

TEST(VegErrors, ElementsBeforeVertices) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", std::string(test::kTwoTetElements) + std::string(test::kTwoTetVertices));
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 1, {"*ELEMENTS before *VERTICES"});
}

TEST(VegErrors, EmptyFile) {
  test::ScratchDir dir;
  const auto path = dir.write("empty.veg", "# nothing\n");
  test::expectParseError([&] { readVeg(path); }, "empty.veg", 0, {"no *VERTICES"});
}

TEST(VegErrors, MissingIncludeNamesTheIncludingLine) {
  test::ScratchDir dir;
  const auto path = dir.write("bad.veg", replaced(baseVeg(), "*REGION", "*SET s\n*INCLUDE nothere.txt\n*REGION"));
  test::expectParseError([&] { readVeg(path); }, "bad.veg", 16, {"nothere.txt"});
}

TEST(VegErrors, IncludeCycle) {
  test::ScratchDir dir;
  dir.write("loop.inc", "*INCLUDE bad.veg\n");
  const auto path = dir.write("bad.veg", replaced(baseVeg(), "*REGION", "*SET s\n*INCLUDE loop.inc\n*REGION"));
  test::expectParseError([&] { readVeg(path); }, "loop.inc", 1, {"cycle"});
}

TEST(VegErrors, IncludeNestedTooDeep) {
  test::ScratchDir dir;
  for (int i = 1; i < 40; ++i) {
    std::string name = "f", next = "*INCLUDE f";
    name += std::to_string(i) + ".inc";
    next += std::to_string(i + 1) + ".inc\n";
    dir.write(name, next);
  }
  dir.write("f40.inc", "1\n");
  const auto path = dir.write("bad.veg", replaced(baseVeg(), "*REGION", "*SET s\n*INCLUDE f1.inc\n*REGION"));
  // bad.veg is the first file on the include stack, f32.inc the 33rd.
  test::expectParseError([&] { readVeg(path); }, "f32.inc", 1, {"deeper than 32"});
}

}  // namespace
}  // namespace asyncfem
