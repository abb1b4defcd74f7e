// SPDX-License-Identifier: BSD-3-Clause
// The bodies the integrator, asynchronous-integrator and hyperelastic tests step, built
// through Problem as a scene builds them (mesh, fixed vertices, ProblemSettings), and the
// random initial states those tests start from. Units are SI: lengths in m, densities in
// kg/m^3, moduli in Pa, times in s. Matrices are 3n x 3n for a mesh of n vertices.
#pragma once

#include <Eigen/Core>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <random>
#include <string>
#include <utility>

namespace asyncfem::test {

/// Physics settings of a test body: forceModel (with the simple tangent when corotational),
/// Rayleigh damping D = alpha M + beta K (alpha in 1/s, beta in s), mass; no gravity.
inline ProblemSettings testSettings(ForceModelType forceModel, double alpha = 0.0, double beta = 0.0,
                                    MassType mass = MassType::consistent) {
  ProblemSettings settings;
  settings.forceModel = forceModel;
  settings.rayleighAlpha = alpha;
  settings.rayleighBeta = beta;
  settings.mass = mass;
  return settings;
}

/// A 1 x 0.2 x 0.2 bar along x of cells.x() x cells.y() x cells.z() cubes (6 tets each),
/// rubber: density 1000, E = 1e6, nu = 0.45. The default 4 x 1 x 1 has 24 tets and 20
/// vertices. Vertex sets "xmin", "xmax", ... of the box generator.
inline std::shared_ptr<const TetMesh> rubberBarMesh(const Eigen::Vector3i& cells = Eigen::Vector3i(4, 1, 1)) {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(1.0, 0.2, 0.2);
  spec.cells = cells;
  spec.material = Material{"rubber", 1000.0, 1e6, 0.45};
  return std::make_shared<const TetMesh>(makeBoxMesh(spec));
}

/// rubberBarMesh(cells) clamped at its x = 0 face ("xmin"): a cantilever (48 free DOFs at
/// the default 4 x 1 x 1, small enough for dense eigen-solves). No load.
inline Problem rubberBarProblem(const ProblemSettings& settings = {},
                                const Eigen::Vector3i& cells = Eigen::Vector3i(4, 1, 1)) {
  std::shared_ptr<const TetMesh> mesh = rubberBarMesh(cells);
  std::vector<int> clamped = mesh->vertexSet("xmin");
  return Problem(std::move(mesh), std::move(clamped), settings);
}

/// The bar [0, 1] x [0, 0.25] x [0, 0.25] of 8 x 2 x 2 cubes (192 tets, 135 vertices; other
/// cells on request):
/// soft (density 1000, E = 1e5, nu = 0.4) with a stiff, light end x > 0.75 (density 200,
/// E = 5e6, nu = 0.3; element and vertex set "stiff"), whose wave speed sqrt(E / density)
/// is 16 times the rest's: the fast region of the multirate tests. Clamped at x = 0
/// ("xmin"). No load.
inline Problem stiffEndBarProblem(const ProblemSettings& settings = {},
                                  const Eigen::Vector3i& cells = Eigen::Vector3i(8, 2, 2)) {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(1.0, 0.25, 0.25);
  spec.cells = cells;
  spec.material = Material{"soft", 1000.0, 1e5, 0.4};
  spec.regions.push_back(
      {"stiff", Eigen::Vector3d(0.75, -1, -1), Eigen::Vector3d(2, 2, 2), Material{"stiff", 200.0, 5e6, 0.3}});
  auto mesh = std::make_shared<const TetMesh>(makeBoxMesh(spec));
  std::vector<int> clamped = mesh->vertexSet("xmin");
  return Problem(std::move(mesh), std::move(clamped), settings);
}

/// The default scene's beam (models/beam/beam.veg: a 1 x 0.2 x 0.2 rubber beam with a
/// stiff, light "tip"), clamped at its vertex set "root". No load.
inline Problem defaultBeamProblem(const ProblemSettings& settings = {}) {
  auto mesh = std::make_shared<const TetMesh>(readMesh(std::string(ASYNCFEM_MODELS_DIR) + "/beam/beam.veg"));
  std::vector<int> clamped = mesh->vertexSet("root");
  return Problem(std::move(mesh), std::move(clamped), settings);
}

/// problem's mesh, fixed vertices and loads under other settings (another force model,
/// mass type or damping for the same body).
inline Problem withSettings(const Problem& problem, const ProblemSettings& settings) {
  return Problem(problem.sharedMesh(), problem.fixedVertices(), settings, problem.windows(), problem.contact());
}

/// A problem and the DynamicSystem it returned, which a test may change (set a load, swap
/// the force model, free the DOFs). Copies share the problem; mesh stays valid as long as
/// any copy lives, whatever happens to system.mesh.
struct TestBody {
  explicit TestBody(Problem problemToOwn)
      : problem(std::make_shared<const Problem>(std::move(problemToOwn))),
        mesh(problem->mesh()),
        system(problem->dynamicSystem()) {}

  std::shared_ptr<const Problem> problem;
  const TetMesh& mesh;  ///< problem->mesh(): n vertices
  DynamicSystem system;
};

/// Which draws a random state takes on fixed DOFs (the tests' seeds were chosen with one
/// or the other; both give zero there).
enum class FixedDofDraws {
  skipped,         ///< only free DOFs draw
  drawnThenZeroed  ///< every DOF draws, fixed ones are zeroed afterwards
};

/// A state of a body: full vectors of size 3n (m, m/s).
struct RandomState {
  Eigen::VectorXd displacement, velocity;
};

/// A random state on every free DOF: displacement uniform in 1e-3 [-1, 1], velocity
/// uniform in 1e-2 [-1, 1], drawn DOF by DOF (u then v) from std::mt19937(seed); zero on
/// fixed DOFs.

inline RandomState randomState(const FreeDofs& dofs, unsigned seed, FixedDofDraws draws) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  RandomState state{Eigen::VectorXd::Zero(dofs.numDofs()), Eigen::VectorXd::Zero(dofs.numDofs())};
  for (int k = 0; k < dofs.numDofs(); ++k) {
    const bool fixed = dofs.isFixed(k);
    if (fixed && draws == FixedDofDraws::skipped) continue;
    const double u = 1e-3 * uniform(random);
    const double v = 1e-2 * uniform(random);
    if (fixed) continue;
    state.displacement[k] = u;
    state.velocity[k] = v;
  }
  return state;
}

}  // namespace asyncfem::test
