// SPDX-License-Identifier: BSD-3-Clause
// Hexahedra against the tetrahedra of the same cubes (6 per cube, meshInfo --hex-to-tets),
// printed as Markdown tables; every ratio compares two measurements of the same run.
//
//   benchmarkHexahedra [--levels 4] [--kernel-cells 8] [--repeats 5] [--threads 1]
//
// 1. A cantilever of length 1 and square section 0.1 x 0.1 (E 1e7, nu 0.3, rho 1000),
//    clamped at x = 0, under its own weight (load M g, consistent mass: the exact load
//    functional of gravity on either element space), on 10 k x k x k cubes for
//    k = 1, 2, 4, ...: the tip deflection (mean of the x = 1 face) against Euler-Bernoulli,
//    q L^4 / (8 E I), and Timoshenko's shear correction q L^2 / (2 kappa G A) (kappa = 5/6).
//    Errors are against the Richardson extrapolation of the two finest hexahedral levels
//    (the displacement converges as h^2), not against beam theory, whose clamp and section
//    kinematics differ from the 3D solid's by about 1%.
// 2. The same static solves as run time against error at equal DOFs (the hexahedra and
//    their tetrahedra share the vertices): assembly + CHOLMOD factorization + solve.
// 3. StVK's energy of one cube by 2 x 2 x 2 Gauss (hexStvk) against 3 x 3 x 3, which is exact
//    for the degree-4 polynomial a trilinear field gives (and so equal to what Vega's
//    closed-form cube coefficients compute), under a random strain of growing size.
// 4. forcesAndTangent() per element, per cube and per vertex of StVK and corotational FEM
//    on a 4 c x c x c box of cubes at a random 1% strain, hexahedra against the tetrahedra
//    of the same cubes.
#include <omp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/hexElements/hexCorotationalForceModel.hpp>
#include <asyncfem/hexElements/hexStvk.hpp>
#include <asyncfem/hexElements/hexStvkForceModel.hpp>
#include <asyncfem/hyperelasticFEM/stvkFEM.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/hexToTets.hpp>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "../../hexElements/hexBar.hpp"
#include "../benchmarkMachine.hpp"

namespace {

using namespace asyncfem;

constexpr double kLength = 1.0, kSide = 0.1, kGravity = 9.81;
const Material kSteelish{"bar", 1000.0, 1e7, 0.3};

struct Matrices {
  Eigen::SparseMatrix<double> stiffness, mass;
};

/// Tip deflection and the seconds of assembly + factorization + solve.
struct StaticSolve {
  double tip = 0.0;
  double seconds = 0.0;
  int dofs = 0;
};

StaticSolve solveStatic(const TetMesh& mesh, const std::function<Matrices()>& assemble) {
  Stopwatch watch;
  watch.start();
  const Matrices matrices = assemble();
  std::vector<int> fixed, tip;
  for (int v = 0; v < mesh.numVertices(); ++v) {
    if (mesh.restPosition(v).x() == 0.0) fixed.push_back(v);
    if (mesh.restPosition(v).x() == kLength) tip.push_back(v);
  }
  const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), fixed);
  Eigen::VectorXd gravity = Eigen::VectorXd::Zero(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) gravity[(3 * v) + 1] = -kGravity;
  auto solver = makeSparseSolver(SolverKind::cholmod);
  const SubmatrixExtractor free(matrices.stiffness, dofs.freeToFull(), dofs.freeToFull());
  solver->compute(free.extract(matrices.stiffness));
  const Eigen::VectorXd u = dofs.expand(solver->solve(dofs.restrict(matrices.mass * gravity)));
  StaticSolve result;
  result.seconds = watch.stop();
  for (const int v : tip) result.tip -= u[(3 * v) + 1] / static_cast<double>(tip.size());
  result.dofs = dofs.numFree();
  return result;
}

TetMesh cantilever(int k) {
  return test::hexBox(Eigen::Vector3i(10 * k, k, k), Eigen::Vector3d(kLength, kSide, kSide), kSteelish);
}

struct Level {
  int k = 0, cubes = 0, dofs = 0;
  StaticSolve hex, tet;
};

std::vector<Level> measureCantilever(int levels) {
  std::vector<Level> rows;
  for (int level = 0, k = 1; level < levels; ++level, k *= 2) {
    const TetMesh hexes = cantilever(k);
    const TetMesh tets = hexahedraToTetrahedra(hexes);
    Level row;
    row.k = k;
    row.cubes = hexes.numElements();
    row.hex = solveStatic(hexes, [&] {
      return Matrices{hexLinearStiffnessMatrix(hexes), hexMassMatrix(hexes, MassType::consistent)};
    });
    row.tet = solveStatic(tets, [&] {
      const MatrixAssembler assembler(tets);
      return Matrices{linearStiffnessMatrix(tets, assembler), massMatrix(tets, assembler, MassType::consistent)};
    });
    row.dofs = row.hex.dofs;
    rows.push_back(row);
    std::fprintf(stderr, "  cantilever k = %d done (%d cubes)\n", k, row.cubes);
  }
  return rows;
}

void printCantilever(const std::vector<Level>& rows) {
  const double area = kSide * kSide, inertia = std::pow(kSide, 4) / 12.0;
  const double q = kSteelish.density * kGravity * area;
  const double bending = q * std::pow(kLength, 4) / (8.0 * kSteelish.youngsModulus * inertia);
  const double shearModulus = kSteelish.youngsModulus / (2.0 * (1.0 + kSteelish.poissonRatio));
  const double timoshenko = bending + (q * kLength * kLength / (2.0 * (5.0 / 6.0) * shearModulus * area));
  const double fine = rows.back().hex.tip, coarser = rows[rows.size() - 2].hex.tip;
  const double reference = fine + ((fine - coarser) / 3.0);  // Richardson, error ~ h^2
  std::printf("\n## Cantilever under its own weight: tip deflection\n\n");
  std::printf(
      "Euler-Bernoulli %.6e, Timoshenko %.6e, reference (Richardson of the two finest hexahedral levels) "
      "%.6e = %.4f x Euler-Bernoulli\n\n",
      bending, timoshenko, reference, reference / bending);
  std::printf(
      "| cubes | free DOFs | hex tip / E-B | tets tip / E-B | hex error | tets error | hex s | tets s | "
      "tets s / hex s |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const Level& row : rows) {
    std::printf("| %d x %d x %d | %d | %.4f | %.4f | %.2e | %.2e | %.4f | %.4f | %.2f |\n", 10 * row.k, row.k, row.k,
                row.dofs, row.hex.tip / bending, row.tet.tip / bending, std::abs(row.hex.tip - reference) / reference,
                std::abs(row.tet.tip - reference) / reference, row.hex.seconds, row.tet.seconds,
                row.tet.seconds / row.hex.seconds);
  }
}

/// StVK's energy of one hexahedron by 3 x 3 x 3 Gauss-Legendre, exact for its integrand.
double exactStvkEnergy(const HexElementPositions& rest, const HexElementPositions& deformed, double lambda, double mu) {
  const double points[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)}, weights[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  double energy = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        double volume = 0.0;
        const Eigen::Matrix<double, 3, 8> gradients =
            hexShapeGradients(rest, Eigen::Vector3d(points[i], points[j], points[k]), &volume);
        const Eigen::Matrix3d f = deformed * gradients.transpose();
        const Eigen::Matrix3d green = 0.5 * (f.transpose() * f - Eigen::Matrix3d::Identity());
        energy += weights[i] * weights[j] * weights[k] * volume *
                  ((0.5 * lambda * green.trace() * green.trace()) + (mu * green.squaredNorm()));
      }
  return energy;
}

void printQuadrature() {
  const TetMesh cube = test::hexBox(Eigen::Vector3i::Ones(), Eigen::Vector3d::Ones(), kSteelish);
  HexElementPositions rest;
  for (int a = 0; a < 8; ++a) rest.col(a) = cube.restPosition(cube.hexahedron(0)[a]);
  const Eigen::Vector2d lame = lameParameters(kSteelish.youngsModulus, kSteelish.poissonRatio);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  HexElementPositions direction;
  for (int a = 0; a < 8; ++a) direction.col(a) = Eigen::Vector3d(unit(random), unit(random), unit(random));
  std::printf("\n## StVK energy of one cube: 2 x 2 x 2 Gauss against exact (3 x 3 x 3) integration\n\n");
  std::printf(
      "| vertex displacement / side | energy 2x2x2 | energy exact | relative difference |\n|---|---|---|---|\n");
  for (const double size : {0.001, 0.01, 0.1, 0.3}) {
    const HexElementPositions deformed = rest + (size * direction);
    const double gauss = hexStvk(rest, deformed, kSteelish.youngsModulus, kSteelish.poissonRatio, false).energy;
    const double exact = exactStvkEnergy(rest, deformed, lame[0], lame[1]);
    std::printf("| %g | %.6e | %.6e | %.2e |\n", size, gauss, exact, (gauss - exact) / exact);
  }
}

/// Best-of-repeats seconds of forcesAndTangent() at a displacement flipped between calls.
double kernelSeconds(ForceModel& model, const Eigen::VectorXd& displacement, int repeats) {
  Eigen::VectorXd forces, u = displacement;
  Eigen::SparseMatrix<double> tangent = model.createStiffnessMatrix();
  double best = 1e300;
  for (int run = 0; run < repeats + 1; ++run) {
    u[0] = -u[0];
    Stopwatch watch;
    watch.start();
    model.forcesAndTangent(u, forces, tangent);
    if (run > 0) best = std::min(best, watch.stop());  // the first call warms caches and pools
  }
  return best;
}

void printKernels(int cells, int repeats) {
  const TetMesh hexes =
      test::hexBox(Eigen::Vector3i(4 * cells, cells, cells), Eigen::Vector3d(1.0, 0.25, 0.25), kSteelish);
  const TetMesh tets = hexahedraToTetrahedra(hexes);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> offset(-0.01 * 0.25 / cells, 0.01 * 0.25 / cells);
  Eigen::VectorXd u(hexes.numDofs());
  for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = offset(random);
  struct Pair {
    const char* name;
    std::unique_ptr<ForceModel> hex, tet;
  };
  Pair pairs[] = {{"StVK", std::make_unique<HexStvkForceModel>(hexes), std::make_unique<StVKFEM>(tets)},
                  {"corotational (simple tangent)", std::make_unique<HexCorotationalForceModel>(hexes),
                   std::make_unique<CorotationalLinearFEM>(tets)}};
  std::printf("\n## forcesAndTangent(): %d cubes (%d tetrahedra), %d vertices, %d thread(s)\n\n", hexes.numElements(),
              tets.numElements(), hexes.numVertices(), omp_get_max_threads());
  std::printf(
      "| model | hex us / cube | tets us / tet | tets us / cube (6 tets) | hex us / vertex | "
      "tets us / vertex | hex / tets per cube |\n|---|---|---|---|---|---|---|\n");
  for (Pair& pair : pairs) {
    const double hex = kernelSeconds(*pair.hex, u, repeats), tet = kernelSeconds(*pair.tet, u, repeats);
    const double cubes = hexes.numElements(), vertices = hexes.numVertices();
    std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f |\n", pair.name, 1e6 * hex / cubes,
                1e6 * tet / tets.numElements(), 1e6 * tet / cubes, 1e6 * hex / vertices, 1e6 * tet / vertices,
                hex / tet);
  }
}

}  // namespace

int main(int argc, char** argv) {
  preferPassiveThreadWaiting(argv);
  CLI::App app{
      "Hexahedra against the tetrahedra of the same cubes: cantilever convergence, run time against "
      "error at equal DOFs, element-kernel throughput (Markdown tables)."};
  int levels = 4, kernelCells = 8, repeats = 5, threads = 1;
  app.add_option("--levels", levels, "cantilever levels k = 1, 2, 4, ... (10 k x k x k cubes)")
      ->check(CLI::Range(2, 6));
  app.add_option("--kernel-cells", kernelCells, "kernel box of 4 c x c x c cubes")->check(CLI::Range(1, 64));
  app.add_option("--repeats", repeats, "kernel calls timed (best of)")->check(CLI::Range(1, 1000));
  app.add_option("--threads", threads, "OpenMP threads")->check(CLI::Range(1, 256));
  CLI11_PARSE(app, argc, argv);
  omp_set_num_threads(threads);
  std::printf("benchmarkHexahedra on %s, load %s, %d thread(s)\n", bench::cpuModel().c_str(),
              bench::loadAverage().c_str(), threads);
  printCantilever(measureCantilever(levels));
  printQuadrature();
  printKernels(kernelCells, repeats);
  return 0;
}
