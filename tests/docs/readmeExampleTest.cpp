// SPDX-License-Identifier: BSD-3-Clause
// README's "Compose the libraries" program, compiled from the README text itself (see
// CMakeLists.txt), runs and does what the README says: the pulled tip goes down, and once
// released the beam swings back up past its rest shape.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

int readmeExampleMain();  // README's main(), renamed when compiled for this test

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;

/// Mean y displacement of the vertices.
double meanY(const Eigen::VectorXd& u, const std::vector<int>& vertices) {
  double sum = 0.0;
  for (const int v : vertices) sum += u[(3 * v) + 1];
  return sum / static_cast<double>(vertices.size());
}

TEST(ReadmeExample, PullsTheTipDownAndLetsTheBeamSwing) {
  // The program reads models/beam/beam.veg and writes beam.afsim in its working folder:
  // run it in a fresh folder laid out like the repository.
  const fs::path folder = fs::temp_directory_path() / ("asyncfem-readme-example-" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  fs::create_directory_symlink(ASYNCFEM_MODELS_DIR, folder / "models");
  const fs::path previous = fs::current_path();
  fs::current_path(folder);
  const int status = readmeExampleMain();
  fs::current_path(previous);
  ASSERT_EQ(status, 0);

  SimulationReader reader(folder / "beam.afsim");
  ASSERT_EQ(reader.numFrames(), 60);
  const TetMesh mesh = readMesh(fs::path(ASYNCFEM_MODELS_DIR) / "beam" / "beam.veg");
  ASSERT_EQ(reader.numVertices(), mesh.numVertices());
  const std::vector<int>& tip = mesh.vertexSet("tip");

  // The static deflection under the same 40 N: K_ff u_f = f_f.
  const MatrixAssembler assembler(mesh);
  const Eigen::SparseMatrix<double> stiffness = linearStiffnessMatrix(mesh, assembler);
  const FreeDofs freeDofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("root"));
  const Eigen::SparseMatrix<double> freeStiffness =
      SubmatrixExtractor(stiffness, freeDofs.freeToFull(), freeDofs.freeToFull()).extract(stiffness);
  Eigen::VectorXd load = Eigen::VectorXd::Zero(mesh.numDofs());
  for (const int v : tip) load[(3 * v) + 1] = -40.0 / static_cast<double>(tip.size());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor(freeStiffness);
  ASSERT_EQ(factor.info(), Eigen::Success);
  const double staticDeflection = meanY(freeDofs.expand(factor.solve(freeDofs.restrict(load))), tip);
  ASSERT_LT(staticDeflection, 0.0);

  double lowestWhilePulled = 0.0;
  double highestAfterRelease = -1e300;
  for (std::int64_t k = 0; k < reader.numFrames(); ++k) {
    const SimulationFrame frame = reader.readFrame(k);
    // Frames every 4 steps of 1/120 s; step times are k h, so equal up to round-off.
    EXPECT_NEAR(frame.time, static_cast<double>(k + 1) / 30.0, 1e-12);
    ASSERT_TRUE(frame.displacement.allFinite()) << "frame " << k;
    const double y = meanY(frame.displacement, tip);
    if (frame.time <= 0.3) {
      lowestWhilePulled = std::min(lowestWhilePulled, y);
    } else {
      highestAfterRelease = std::max(highestAfterRelease, y);
    }
  }
  // A load switched on at rest drives the lowest mode to about twice its static deflection
  // after half a period (the pull lasts about that long); backward Euler's damping at
  // omega h ~ 0.09 removes a few percent. Half the static deflection is a safe lower bound.
  EXPECT_LT(lowestWhilePulled, 0.5 * staticDeflection);
  // Released below its rest shape with no physical damping, the tip must swing above it;
  // after 1.7 s backward Euler keeps about half the amplitude, so a fifth of the static
  // deflection above rest is a safe bound.
  EXPECT_GT(highestAfterRelease, -0.2 * staticDeflection);
  fs::remove_all(folder);
}

}  // namespace
