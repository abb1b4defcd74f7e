// SPDX-License-Identifier: BSD-3-Clause
// End-to-end runs of the tetMesher utility on OBJ files written here (needs assimp).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "surfaces.hpp"

namespace asyncfem {
namespace {

const std::string kTetMesher = std::string(ASYNCFEM_BIN_DIR) + "/tetMesher";

struct RunResult {
  int status;
  std::string output;  // stdout and stderr together
};

RunResult run(const std::string& arguments) {
  const auto log = std::filesystem::temp_directory_path() / ("asyncfem-tetMesher-run-" + std::to_string(::getpid()));
  const std::string command = kTetMesher + " " + arguments + " > " + log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  RunResult result{WIFEXITED(status) ? WEXITSTATUS(status) : -1,
                   std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>())};
  std::filesystem::remove(log);
  return result;
}

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("asyncfem-tetMesher-cli-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir / name;
}

TEST(TetMesherUtility, MeshesAnObjWithPartAndBoxSets) {
  const auto obj = scratch("two.obj");
  std::ofstream(obj) << test::toObj(test::concatenate(test::uvSphere(Eigen::Vector3d(-1.1, 0, 0), 1.0, 24, 12), "left",
                                                      test::uvSphere(Eigen::Vector3d(1.1, 0, 0), 1.0, 24, 12),
                                                      "right"));
  const auto veg = scratch("two.veg");
  const RunResult result =
      run(obj.string() + " --cells 20 --part-sets --set upper:-3,0,-2,3,2,2 --material left:500,1e7,0.4 -o " +
          veg.string());
  ASSERT_EQ(result.status, 0) << result.output;
  EXPECT_NE(result.output.find("quality: dihedral angles min"), std::string::npos) << result.output;
  const TetMesh mesh = readVeg(veg);
  EXPECT_FALSE(mesh.elementSet("left").empty());
  EXPECT_FALSE(mesh.elementSet("right").empty());
  EXPECT_FALSE(mesh.elementSet("upper").empty());
  EXPECT_GE(mesh.findMaterial("left"), 0);
}

TEST(TetMesherUtility, OpenSurfaceIsAnErrorUnlessRepaired) {
  TriangleSurface cube = test::splitCube(Eigen::Vector3d::Zero(), 1.0);
  cube.triangles.conservativeResize(3, cube.numTriangles() - 1);
  cube.triangleParts.pop_back();
  const auto obj = scratch("open.obj");
  std::ofstream(obj) << test::toObj(cube);
  const auto veg = scratch("open.veg");
  std::filesystem::remove(veg);
  const RunResult refused = run(obj.string() + " --cells 10 -o " + veg.string());
  EXPECT_EQ(refused.status, 1) << refused.output;
  EXPECT_NE(refused.output.find("tetMesher: "), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("3 open boundary edges"), std::string::npos) << refused.output;
  EXPECT_FALSE(std::filesystem::exists(veg));

  const RunResult repaired = run(obj.string() + " --cells 10 --repair -o " + veg.string());
  ASSERT_EQ(repaired.status, 0) << repaired.output;
  EXPECT_NE(repaired.output.find("generalized winding number"), std::string::npos) << repaired.output;
  EXPECT_GT(readVeg(veg).numElements(), 100);
}

TEST(TetMesherUtility, ReportsFidelityAndRefusesInputItCannotMeshFaithfully) {
  // A closed sphere: volume and Hausdorff distance are reported, the latter below a spacing
  // (boundary vertices lie on the surface; the 24 x 12 polyhedron's facets are within
  // ~0.03 of the mesh boundary's, and the spacing is 0.15).
  const auto sphereObj = scratch("sphere.obj");
  std::ofstream(sphereObj) << test::toObj(test::uvSphere(Eigen::Vector3d::Zero(), 1.0, 24, 12));
  const RunResult sphere = run(sphereObj.string() + " --spacing 0.15 -o " + scratch("sphere.veg").string());
  ASSERT_EQ(sphere.status, 0) << sphere.output;
  EXPECT_NE(sphere.output.find("volume: mesh"), std::string::npos) << sphere.output;
  // The figure is a sampled one and says so (a lower bound of the exact distance).
  EXPECT_NE(sphere.output.find("a lower bound of the exact distance"), std::string::npos) << sphere.output;
  const std::size_t at = sphere.output.find("(", sphere.output.find("fidelity: sampled Hausdorff distance"));
  ASSERT_NE(at, std::string::npos) << sphere.output;
  EXPECT_LT(std::stod(sphere.output.substr(at + 1)), 1.0) << sphere.output;  // in spacings

  // Half a sphere is open far beyond repair: the winding number would invent the whole cap.
  TriangleSurface half = test::uvSphere(Eigen::Vector3d::Zero(), 1.0, 24, 12);
  Eigen::Matrix3Xi upper(3, 0);
  for (int t = 0; t < half.numTriangles(); ++t) {
    if (half.vertices.col(half.triangles(0, t)).z() + half.vertices.col(half.triangles(1, t)).z() +
            half.vertices.col(half.triangles(2, t)).z() >
        0.0) {
      upper.conservativeResize(3, upper.cols() + 1);
      upper.col(upper.cols() - 1) = half.triangles.col(t);
    }
  }
  half.triangles = upper;
  half.triangleParts.assign(static_cast<std::size_t>(upper.cols()), 0);
  const auto halfObj = scratch("half.obj");
  std::ofstream(halfObj) << test::toObj(half);
  const RunResult open = run(halfObj.string() + " --repair --spacing 0.15 -o " + scratch("half.veg").string());
  EXPECT_EQ(open.status, 1) << open.output;
  EXPECT_NE(open.output.find("open beyond repair"), std::string::npos) << open.output;
  EXPECT_NE(open.output.find("near ("), std::string::npos) << open.output;
  EXPECT_NE(open.output.find("input triangle, #"), std::string::npos) << open.output;

  // Two closed spheres overlapping: each is a manifold, together they intersect; the
  // pseudonormal sign is wrong inside the overlap, so this is an error naming the place,
  // and --repair meshes the union.
  const auto overlapObj = scratch("overlap.obj");
  std::ofstream(overlapObj) << test::toObj(
      test::concatenate(test::uvSphere(Eigen::Vector3d(-0.4, 0, 0), 1.0, 24, 12), "a",
                        test::uvSphere(Eigen::Vector3d(0.4, 0, 0), 1.0, 24, 12), "b"));
  const RunResult overlap = run(overlapObj.string() + " --spacing 0.15 -o " + scratch("overlap.veg").string());
  EXPECT_EQ(overlap.status, 1) << overlap.output;
  EXPECT_NE(overlap.output.find("intersects or overlaps itself"), std::string::npos) << overlap.output;
  EXPECT_NE(overlap.output.find("nearest triangle #"), std::string::npos) << overlap.output;
  const RunResult united = run(overlapObj.string() + " --repair --spacing 0.15 -o " + scratch("overlap.veg").string());
  EXPECT_EQ(united.status, 0) << united.output;
}

TEST(TetMesherUtility, AShellAroundACoreBecomesATwoMaterialMeshInOneCommand) {
  // Two nested closed spheres in OBJ groups "shell" (radius 1) and "core" (radius 0.5): the
  // winding number meshes the union, the core's elements are those its own triangles enclose.
  const auto obj = scratch("shell.obj");
  std::ofstream(obj) << test::toObj(test::concatenate(test::uvSphere(Eigen::Vector3d::Zero(), 1.0, 32, 16), "shell",
                                                      test::uvSphere(Eigen::Vector3d::Zero(), 0.5, 24, 12), "core"));
  const auto veg = scratch("shell.veg");
  const double spacing = 0.1;
  const RunResult result = run(obj.string() + " --repair --spacing 0.1 --group-sets --material core:3000,1e8,0.3 " +
                               "--material shell:1000,1e5,0.45 -o " + veg.string());
  ASSERT_EQ(result.status, 0) << result.output;
  const TetMesh mesh = readVeg(veg);
  ASSERT_FALSE(mesh.elementSet("core").empty());
  ASSERT_FALSE(mesh.elementSet("shell").empty());
  EXPECT_EQ(mesh.elementSet("core").size() + mesh.elementSet("shell").size(),
            static_cast<std::size_t>(mesh.numElements()));
  // Every element is in the material of its side of the inner sphere, up to one element
  // size (a centroid lies within about a spacing of the sphere it is assigned by).
  for (int e = 0; e < mesh.numElements(); ++e) {
    const double r = mesh.elementRestPositions(e).rowwise().mean().norm();
    const std::string& material = mesh.elementMaterial(e).name;
    if (r < 0.5 - spacing) {
      EXPECT_EQ(material, "core") << "element " << e << " at radius " << r;
    }
    if (r > 0.5 + spacing) {
      EXPECT_EQ(material, "shell") << "element " << e << " at radius " << r;
    }
  }
  // Material ids of the file work the same way (toObj writes no materials: one default).
  const RunResult materials = run(obj.string() + " --repair --spacing 0.2 --material-sets -o " + veg.string());
  EXPECT_EQ(materials.status, 0) << materials.output;
  EXPECT_NE(materials.output.find("set "), std::string::npos) << materials.output;
}

TEST(TetMesherUtility, GradedSurfaceMeshKeepsTheSurfaceWithFewerElements) {
  const auto obj = scratch("ball.obj");
  std::ofstream(obj) << test::toObj(test::uvSphere(Eigen::Vector3d::Zero(), 1.0, 32, 16));
  const auto uniformVeg = scratch("uniform.veg"), gradedVeg = scratch("graded.veg");
  const RunResult uniform = run(obj.string() + " --cells 30 -o " + uniformVeg.string());
  const RunResult graded = run(obj.string() + " --cells 30 --grade 3 -o " + gradedVeg.string());
  ASSERT_EQ(uniform.status, 0) << uniform.output;
  ASSERT_EQ(graded.status, 0) << graded.output;
  EXPECT_EQ(uniform.output.find("grading:"), std::string::npos) << uniform.output;
  EXPECT_NE(graded.output.find("grading: 3 levels"), std::string::npos) << graded.output;
  // The same "volume:" line (same boundary), fewer elements.
  auto line = [](const std::string& text, const std::string& key) {
    const auto at = text.find(key);
    return at == std::string::npos ? std::string() : text.substr(at, text.find('\n', at) - at);
  };
  EXPECT_FALSE(line(graded.output, "volume:").empty());
  EXPECT_EQ(line(graded.output, "volume:"), line(uniform.output, "volume:"));
  EXPECT_LT(readVeg(gradedVeg).numElements(), readVeg(uniformVeg).numElements());
}

TEST(TetMesherUtility, CubesFromASurfaceOrAModelWithTheVolumeError) {
  // The 48 x 24 UV sphere at spacing 0.1: 4224 cubes (the count voxelize gives for this grid,
  // Voxelize.SphereVolumeErrorShrinksUnderRefinement), written as CUBIC elements and read back.
  const auto obj = scratch("cubeSphere.obj");
  std::ofstream(obj) << test::toObj(test::uvSphere(Eigen::Vector3d::Zero(), 1.0, 48, 24));
  const auto veg = scratch("cubeSphere.veg");
  const RunResult sphere = run(obj.string() + " --cubes --spacing 0.1 -o " + veg.string());
  ASSERT_EQ(sphere.status, 0) << sphere.output;
  EXPECT_NE(sphere.output.find("4224 cubes, 5233 vertices"), std::string::npos) << sphere.output;
  EXPECT_NE(sphere.output.find("volume: cubes 4.224, surface 4.15897, error +1.56%"), std::string::npos)
      << sphere.output;
  const TetMesh mesh = readVeg(veg);
  EXPECT_TRUE(mesh.isHexahedral());
  EXPECT_EQ(mesh.numElements(), 4224);

  const RunResult model = run("--model drop --cubes -o " + scratch("cubeDrop.vtu").string());
  ASSERT_EQ(model.status, 0) << model.output;
  EXPECT_NE(model.output.find("set stiffPart: "), std::string::npos) << model.output;
}

TEST(TetMesherUtility, CubesRefuseOpenOrMisorientedSurfacesAndBadSpacings) {
  const auto expectError = [](const std::string& arguments, const std::string& message) {
    const RunResult result = run(arguments);
    EXPECT_EQ(result.status, 1) << arguments << ": " << result.output;
    EXPECT_NE(result.output.find(message), std::string::npos) << arguments << ": " << result.output;
  };
  TriangleSurface open = test::splitCube(Eigen::Vector3d::Zero(), 1.0);
  open.triangles.conservativeResize(3, open.numTriangles() - 1);
  open.triangleParts.pop_back();
  const auto openObj = scratch("cubesOpen.obj");
  std::ofstream(openObj) << test::toObj(open);
  const std::string veg = " -o " + scratch("cubes.veg").string();
  expectError(openObj.string() + " --cubes --spacing 0.1" + veg, "3 open boundary edges");
  // One triangle reversed: its three edges are traversed the same way as by their neighbours.
  TriangleSurface flipped = test::splitCube(Eigen::Vector3d::Zero(), 1.0);
  flipped.triangles.col(0).tail<2>().reverseInPlace();
  const auto flippedObj = scratch("cubesFlipped.obj");
  std::ofstream(flippedObj) << test::toObj(flipped);
  expectError(flippedObj.string() + " --cubes --spacing 0.1" + veg,
              "0 open boundary edges, 0 non-manifold edges, 3 inconsistently oriented edges");
  const auto cubeObj = scratch("cubesClosed.obj");
  std::ofstream(cubeObj) << test::toObj(test::splitCube(Eigen::Vector3d::Zero(), 1.0));
  // One cell of edge 10 from the corner (0, 0, 0): its centre (5, 5, 5) is outside.
  expectError(cubeObj.string() + " --cubes --spacing 10" + veg, "no cube centre at spacing 10 lies inside");
  expectError(cubeObj.string() + " --cubes --spacing 0.1 --max-cubes 500" + veg,
              "1000 cubes, more than the cap of 500; a spacing of about 0.125992 or larger fits");
  expectError(cubeObj.string() + " --cubes --spacing 0.1 --grade 2" + veg, "--grade applies to tetrahedra");
  const RunResult fine = run(cubeObj.string() + " --cubes --spacing 0.1" + veg);
  EXPECT_EQ(fine.status, 0) << fine.output;
  EXPECT_NE(fine.output.find("1000 cubes, 1331 vertices"), std::string::npos) << fine.output;
  EXPECT_NE(fine.output.find("error +0.00%"), std::string::npos) << fine.output;
}

TEST(TetMesherUtility, BadOptionsAreErrors) {
  EXPECT_EQ(run("--model nosuch -o " + scratch("x.veg").string()).status, 1);
  EXPECT_NE(run("--model nosuch -o " + scratch("x.veg").string()).output.find("known: dinosaur"), std::string::npos);
  EXPECT_EQ(run("--model drop --set bad:1,2 -o " + scratch("x.veg").string()).status, 1);
  // Usage errors (status 2) are found before any meshing, with readable messages.
  const auto badExtension = run("--model drop -o " + scratch("x.stl").string());
  EXPECT_EQ(badExtension.status, 2);
  EXPECT_NE(badExtension.output.find("tetMesher: --output: cannot write '" + scratch("x.stl").string() +
                                     "': unknown extension '.stl' (supported: .veg, .vtu)"),
            std::string::npos)
      << badExtension.output;
  EXPECT_EQ(badExtension.output.find("lattice:"), std::string::npos) << badExtension.output;  // no mesh made
  const auto negative = run("--spacing -1 --model drop -o " + scratch("x.veg").string());
  EXPECT_EQ(negative.status, 2);
  EXPECT_NE(negative.output.find("tetMesher: --spacing: must be > 0 (got -1) (see --help)"), std::string::npos)
      << negative.output;
  const auto grade = run("--model drop --grade 7 -o " + scratch("x.veg").string());
  EXPECT_EQ(grade.status, 2);
  EXPECT_NE(grade.output.find("--grade"), std::string::npos) << grade.output;
  const auto unknown = run("--no-such-option");
  EXPECT_EQ(unknown.status, 2);
  EXPECT_EQ(unknown.output.rfind("tetMesher: ", 0), 0U) << unknown.output;
}

}  // namespace
}  // namespace asyncfem
