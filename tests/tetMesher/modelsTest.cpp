// SPDX-License-Identifier: BSD-3-Clause
// The shipped example models: each .veg loads, is a valid mesh with the documented sets,
// counts and quality (models/README.md, docs/tet-mesher.md), equals what the generator
// produces now, and its scene runs.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/exampleModels.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace asyncfem {
namespace {

struct Documented {
  ExampleModel model;
  int vertices;
  int elements;
  double minDihedral;  // degrees, as printed (2 decimals) in models/README.md
  double maxDihedral;
  std::vector<std::string> sets;
};

const std::vector<Documented>& documented() {
  static const std::vector<Documented> table{
      {ExampleModel::Dinosaur, 1946, 7418, 16.59, 143.14, {"head", "tail", "body", "feet"}},
      {ExampleModel::Flower, 1484, 4879, 19.66, 141.97, {"petals", "upperLeaves", "stem", "base"}},
      {ExampleModel::Dragon,
       1996,
       7493,
       17.30,
       148.17,
       {"jaw", "s1", "s2", "s3", "s4", "s5", "s6", "head", "neck", "body", "tail", "feet"}},
      {ExampleModel::Drop, 1097, 4507, 19.40, 138.33, {"stiffPart", "soft"}},
      {ExampleModel::Ball, 1506, 6798, 22.94, 125.82, {"ball"}},
  };
  return table;
}

std::filesystem::path modelFile(ExampleModel model, const std::string& extension) {
  const std::string name = exampleModelName(model);
  return std::filesystem::path(ASYNCFEM_MODELS_DIR) / name / (name + extension);
}

/// True if some element has vertices in both vertex sets (the async integrator forbids it).
bool elementTouchesBoth(const TetMesh& mesh, const std::vector<int>& a, const std::vector<int>& b) {
  const std::set<int> inA(a.begin(), a.end()), inB(b.begin(), b.end());
  for (int e = 0; e < mesh.numElements(); ++e) {
    bool touchesA = false, touchesB = false;
    for (int k = 0; k < 4; ++k) {
      touchesA = touchesA || inA.count(mesh.elements()(k, e)) > 0;
      touchesB = touchesB || inB.count(mesh.elements()(k, e)) > 0;
    }
    if (touchesA && touchesB) return true;
  }
  return false;
}

TEST(ExampleModels, ShippedMeshesLoadWithDocumentedSetsAndQuality) {
  for (const Documented& d : documented()) {
    SCOPED_TRACE(exampleModelName(d.model));
    const auto path = modelFile(d.model, ".veg");
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    EXPECT_LT(std::filesystem::file_size(path), 2u * 1024u * 1024u);
    const TetMesh mesh = readVeg(path);
    EXPECT_EQ(mesh.numVertices(), d.vertices);
    EXPECT_EQ(mesh.numElements(), d.elements);
    const MeshCheckReport check = checkTetMesh(mesh);
    EXPECT_TRUE(check.ok()) << check.firstProblem;
    EXPECT_EQ(check.components, 1);
    for (const std::string& set : d.sets) {
      EXPECT_FALSE(mesh.elementSet(set).empty()) << set;
      EXPECT_FALSE(mesh.vertexSet(set).empty()) << set;
    }
    const MeshQuality quality = meshQuality(mesh);
    EXPECT_NEAR(quality.minDihedralDegrees, d.minDihedral, 0.006);
    EXPECT_NEAR(quality.maxDihedralDegrees, d.maxDihedral, 0.006);
  }
}

/// The generator's mesh equals the shipped file: elements, sets, materials, positions.
void expectGeneratorReproduces(const TetMesh& generated, const TetMesh& shipped) {
  ASSERT_EQ(generated.numVertices(), shipped.numVertices());
  ASSERT_EQ(generated.elements(), shipped.elements());
  // writeVeg round-trips doubles exactly; allow for other compilers' last bits.
  EXPECT_LE((generated.restPositions() - shipped.restPositions()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(generated.elementSets(), shipped.elementSets());
  EXPECT_EQ(generated.vertexSets(), shipped.vertexSets());
  EXPECT_EQ(generated.materials(), shipped.materials());
  EXPECT_EQ(generated.elementMaterials(), shipped.elementMaterials());
}

TEST(ExampleModels, GeneratorReproducesTheShippedMeshes) {
  // `tetMesher --model NAME -o models/NAME/NAME.veg` (models/README.md) wrote the shipped files.
  for (const Documented& d : documented()) {
    SCOPED_TRACE(exampleModelName(d.model));
    expectGeneratorReproduces(makeExampleModel(d.model), readVeg(modelFile(d.model, ".veg")));
  }
}

// The lattice-cell models (models/README.md, "Appendage models"), from volumetricMesh's
// generators: `meshInfo --generate antenna|snail [--block-cells 20 4 20]` wrote the shipped
// files.
TEST(ExampleModels, CellGeneratorsReproduceTheShippedMeshes) {
  const std::filesystem::path models(ASYNCFEM_MODELS_DIR);
  {
    SCOPED_TRACE("antenna");
    expectGeneratorReproduces(makeAntennaMesh(), readVeg(models / "antenna" / "antenna.veg"));
  }
  {
    SCOPED_TRACE("antenna-wide");
    AntennaSpec wide;
    wide.blockCells = Eigen::Vector3i(20, 4, 20);
    expectGeneratorReproduces(makeAntennaMesh(wide), readVeg(models / "antenna" / "antenna-wide.veg"));
  }
  {
    SCOPED_TRACE("antenna-nested");
    AntennaSpec whip;
    whip.whipCells = 4;
    expectGeneratorReproduces(makeAntennaMesh(whip), readVeg(models / "antenna" / "antenna-nested.veg"));
  }
  {
    SCOPED_TRACE("snail");
    expectGeneratorReproduces(makeSnailMesh(), readVeg(models / "snail" / "snail.veg"));
  }
}

TEST(ExampleModels, FastRegionsAreStifferLighterAndSeparated) {
  auto waveSpeed = [](const TetMesh& mesh, const std::string& set) {
    const Material& m = mesh.elementMaterial(mesh.elementSet(set).front());
    return std::sqrt(m.youngsModulus / m.density);
  };
  const TetMesh dinosaur = readVeg(modelFile(ExampleModel::Dinosaur, ".veg"));
  EXPECT_GT(waveSpeed(dinosaur, "head"), 14.0 * waveSpeed(dinosaur, "body"));
  EXPECT_GT(waveSpeed(dinosaur, "tail"), 7.0 * waveSpeed(dinosaur, "body"));
  EXPECT_FALSE(elementTouchesBoth(dinosaur, dinosaur.vertexSet("head"), dinosaur.vertexSet("tail")));

  const TetMesh flower = readVeg(modelFile(ExampleModel::Flower, ".veg"));
  EXPECT_GT(waveSpeed(flower, "petals"), 11.0 * waveSpeed(flower, "stem"));
  EXPECT_GT(waveSpeed(flower, "upperLeaves"), 9.0 * waveSpeed(flower, "stem"));
  EXPECT_FALSE(elementTouchesBoth(flower, flower.vertexSet("petals"), flower.vertexSet("upperLeaves")));

  const TetMesh dragon = readVeg(modelFile(ExampleModel::Dragon, ".veg"));
  EXPECT_GT(waveSpeed(dragon, "jaw"), 11.0 * waveSpeed(dragon, "body"));
  std::vector<int> previous = dragon.elementSet("jaw");
  for (int k = 1; k <= 6; ++k) {
    std::string name = "s";
    name += std::to_string(k);
    const std::vector<int> current = dragon.elementSet(name);
    EXPECT_GT(current.size(), previous.size()) << "s" << k;
    EXPECT_TRUE(std::includes(current.begin(), current.end(), previous.begin(), previous.end())) << "s" << k;
    previous = current;
  }

  const TetMesh drop = readVeg(modelFile(ExampleModel::Drop, ".veg"));
  EXPECT_GT(waveSpeed(drop, "stiffPart"), 9.0 * waveSpeed(drop, "soft"));
}

TEST(ExampleModels, NamesRoundTripAndUnknownNamesAreErrors) {
  for (const std::string& name : exampleModelNames()) EXPECT_EQ(exampleModelName(exampleModelFromName(name)), name);
  try {
    exampleModelFromName("unicorn");
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("known: dinosaur, flower, dragon, drop"), std::string::npos) << e.what();
  }
}

TEST(ExampleModels, ScenesRunWithTheAsyncIntegrator) {
  const std::string simulator = std::string(ASYNCFEM_BIN_DIR) + "/offlineSimulator";
  if (!std::filesystem::exists(simulator)) GTEST_SKIP() << "offlineSimulator not built";
  for (const Documented& d : documented()) {
    SCOPED_TRACE(exampleModelName(d.model));
    const auto output = std::filesystem::temp_directory_path() /
                        ("asyncfem-model-" + exampleModelName(d.model) + "-" + std::to_string(::getpid()) + ".afsim");
    const std::string command =
        simulator + " " + modelFile(d.model, ".json").string() + " --frames 3 --quiet --output " + output.string();
    const int status = std::system(command.c_str());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
    EXPECT_TRUE(std::filesystem::exists(output));
    std::filesystem::remove(output);
    std::filesystem::remove(output.string() + ".checkpoint");  // the simulator's checkpoint beside it
  }
}

}  // namespace
}  // namespace asyncfem
