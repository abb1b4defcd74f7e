// SPDX-License-Identifier: BSD-3-Clause
// Vega .interp render-mesh weights: the shipped box embedded in the bar, what the weights
// must reproduce, and one test per refusal naming the file and line.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/render/vegaInterpolation.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;

const fs::path vegaData = fs::path(ASYNCFEM_TEST_DATA_DIR) / "vega";

class VegaInterpolationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() /
              ("asyncfem-vegaInterp-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path path = folder_ / name;
    std::ofstream(path) << text;
    return path;
  }
  // The message reading text as an .interp for a 3-vertex render mesh in a 10-vertex tet
  // mesh throws.
  std::string errorOf(const std::string& text) const {
    const fs::path path = write("bad.interp", text);
    try {
      readVegaInterpolation(path, 3, 10);
    } catch (const ParseError& error) {
      return error.what();
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return "";
  }

  fs::path folder_;
};

TEST_F(VegaInterpolationTest, ShippedWeightsReproduceTheRestPositions) {
  const TetMesh mesh = readVeg(vegaData / "bar.veg");
  const SurfaceEmbedding embedding =
      embedWithVegaInterpolation(mesh, vegaData / "bar-box.obj", vegaData / "bar-box.interp");
  ASSERT_EQ(embedding.numSurfaceVertices(), 20);
  EXPECT_EQ(embedding.triangles().size(), 36u);
  // sum_a w_a X(v_a) is the render vertex: the file's weights and coordinates carry nine
  // significant digits, so each term is off by about 1e-9 (coordinates <= 1 m): 1e-8.
  for (int k = 0; k < 20; ++k) {
    Eigen::Vector3d interpolated = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) {
      interpolated += embedding.weights()(a, k) * mesh.restPosition(embedding.tetVertices()(a, k));
    }
    EXPECT_LT((interpolated - embedding.restSurface().vertices.col(k)).norm(), 1e-8) << "vertex " << k;
  }
  // A translation u = t of every tet vertex moves every render vertex by t (weights sum to
  // 1 to about 1e-9, so 1e-8 relative to |t|).
  const Eigen::Vector3d t(0.3, -0.2, 0.1);
  const Eigen::VectorXd u = t.replicate(mesh.numVertices(), 1);
  const Eigen::Matrix3Xd moved = embedding.positions(u);
  for (int k = 0; k < 20; ++k) {
    EXPECT_LT((moved.col(k) - embedding.restSurface().vertices.col(k) - t).norm(), 1e-8 * t.norm()) << k;
  }
}

TEST_F(VegaInterpolationTest, ObjVerticesKeepTheirFileOrderAndDuplicates) {
  // Two vertices at one position stay two (an .interp line each); faces in every OBJ form.
  const fs::path obj = write("quad.obj",
                             "# comment\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 0\nvt 0 0\nvn 0 0 1\n"
                             "g part\nf 1/1/1 2/1/1 3//1 4\nf -1 -4 -3\n");
  const SurfaceMesh surface = readObjInFileOrder(obj);
  ASSERT_EQ(surface.vertices.cols(), 5);
  EXPECT_EQ(surface.vertices.col(4), Eigen::Vector3d::Zero());
  ASSERT_EQ(surface.triangles.size(), 3u);  // the quad as a fan of two, then the triangle
  EXPECT_EQ(surface.triangles[1], (std::array<int, 3>{0, 2, 3}));
  EXPECT_EQ(surface.triangles[2], (std::array<int, 3>{4, 1, 2}));
  const fs::path bad = write("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  try {
    readObjInFileOrder(bad);
    FAIL() << "no error";
  } catch (const ParseError& error) {
    EXPECT_EQ(error.line(), 3u);
    EXPECT_NE(std::string(error.what()).find("face names vertex 3 but 2 vertices precede it"), std::string::npos)
        << error.what();
  }
}

TEST_F(VegaInterpolationTest, VertexCountMustMatchTheRenderMesh) {
  const std::string line0 = "0 0 0.25 1 0.25 2 0.25 3 0.25\n";
  const std::string line1 = "1 0 0.25 1 0.25 2 0.25 3 0.25\n";
  const std::string line2 = "2 0 0.25 1 0.25 2 0.25 3 0.25\n";
  const std::string fewer = errorOf(line0 + line1);
  EXPECT_NE(fewer.find("bad.interp: weights for 2 vertices, but the render mesh has 3"), std::string::npos) << fewer;
  const std::string more = errorOf(line0 + line1 + line2 + "3 0 0.25 1 0.25 2 0.25 3 0.25\n");
  EXPECT_NE(more.find("bad.interp:4: more lines than the render mesh's 3 vertices"), std::string::npos) << more;
  // And through the embedding: the shipped weights do not fit another OBJ.
  const fs::path obj = write("small.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const TetMesh mesh = readVeg(vegaData / "bar.veg");
  EXPECT_THROW(embedWithVegaInterpolation(mesh, obj, vegaData / "bar-box.interp"), ParseError);
}

TEST_F(VegaInterpolationTest, EachBadLineIsNamed) {
  const std::string good = "0 0 0.25 1 0.25 2 0.25 3 0.25\n";
  const std::pair<std::string, std::string> cases[] = {
      {good + "# note\n1 0 0.25 1 0.25 2 0.25 10 0.25\n", "bad.interp:3: tet vertex 10 out of range [0, 10)"},
      {good + "1 0 0.25 -1 0.25 2 0.25 3 0.25\n", "bad.interp:2: tet vertex -1 out of range"},
      {good + "1 0 0.25 1 nan 2 0.25 3 0.25\n", "bad.interp:2: weight 1 is not finite"},
      {good + "1 0 0.5 1 0.25 2 0.25 3 0.25\n", "bad.interp:2: weights sum to 1.25"},
      {good + "2 0 0.25 1 0.25 2 0.25 3 0.25\n", "bad.interp:2: render vertex 2 where vertex 1 comes next"},
      {good + "1 0 0.25 1 0.25 2 0.5\n", "bad.interp:2: expected a vertex index and 4 (tet vertex, weight) pairs"},
      {good + "1 0 0.25 1 x 2 0.25 3 0.25\n", "bad.interp:2: \"x\" is not a number"},
      {"0 0 0.125 1 0.125 2 0.125 3 0.125 4 0.125 5 0.125 6 0.125 7 0.125\n",
       "bad.interp:1: 8 (vertex, weight) pairs: weights in a cube mesh"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string message = errorOf(text);
    EXPECT_NE(message.find(expected), std::string::npos) << message;
  }
}

}  // namespace
