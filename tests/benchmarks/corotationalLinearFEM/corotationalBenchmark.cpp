// SPDX-License-Identifier: BSD-3-Clause
// Corotational backward Euler step: this toolkit against a Vega-style reference.
//
// The reference is written here the way Vega FEM's CorotationalLinearFEM and its
// implicit backward Euler integrator proceed, single-threaded: per element the
// deformation gradient, the polar decomposition by the scaled Newton iteration
// X <- (g X + X^{-T} / g) / 2 to a 1e-6 tolerance (a reflection flipped through the SVD),
// dense 12x12 products R K and R K R^T, f = R K (R^T x - X), scattered into the sparse
// matrix through precomputed positions; then M + h^2 K on the free DOFs, a full
// numeric factorization (the same CHOLMOD as the toolkit, so the comparison isolates
// everything but the factorization library) and one solve per step.
//
// Usage: corotationalBenchmark [STEPS] [--warmup N] [--mesh NAME|box:N] [--rayleigh-mass A] [--rayleigh-stiffness B]
//                              [--toolkit-only exact|reuse] [--write-meshes DIR]
//                              [--model MODEL] [--newton-iterations N] [--newton-tolerance EPS]
// (default 30 timed steps per configuration). --write-meshes writes each timed problem
// for an external program (see writeProblem) and exits; --toolkit-only times one toolkit
// configuration alone (for whole-process timing against another program). --model picks
// the force model of those two modes (corotational with the simple or the exact tangent,
// StVK, neo-Hookean, Mooney-Rivlin, the hyperelastic ones with the settings of the Vega
// agreement scenes, tests/data/vega/README.md); the comparison with the built-in reference
// is corotational only. --newton-iterations N > 1 runs Newton as Vega does (relative
// residual EPS, full steps, Rayleigh K at each iterate).
#include <omp.h>

#include <CLI/CLI.hpp>
#include <Eigen/Dense>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "../benchmarkMachine.hpp"

namespace {

using asyncfem::bench::cpuModel;
using asyncfem::bench::loadAverage;

using namespace asyncfem;
using SparseMatrix = Eigen::SparseMatrix<double>;

constexpr double kTimestep = 0.01;
constexpr int kWarmupSteps = 5;
const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);
// The hyperelastic settings of the Vega agreement scenes (tests/data/vega/README.md):
// Vega's inversion threshold (clamped stretches) and compression resistance, and the
// Mooney-Rivlin constants of their body material (Pa; density as the other models).
constexpr double kInversionThreshold = 0.2;
constexpr double kCompressionResistance = 500.0;
const MooneyRivlinParameters kMooneyRivlin{3e4, 1.4e5, 2e6};
const std::vector<std::string> kModels{"corotational", "corotational-exact", "stvk", "neo-hookean", "mooney-rivlin"};

// The problem besides the mesh: force model and Newton settings (--model, --newton-*).
struct ProblemSettings {
  std::string model = "corotational";
  int maxIterations = 1;      // 1: one linearized step, as Vega with maxIterations 1
  double tolerance = 1e-6;    // Vega's epsilon: relative residual of the free DOFs
  double rayleighMass = 0.0;  // D = alpha M + beta K(u at the step start)
  double rayleighStiffness = 0.0;
  double factorCost = 0.0;  // the kept factor's price in PCG iterations (<= 0: the flop model)
  int refactorIterations = IntegratorOptions{}.pcgRefactorIterations;
  bool singlePrecision = IntegratorOptions{}.pcgSinglePrecision;
};

struct Scene {
  std::string name;
  TetMesh mesh;
  std::shared_ptr<const MatrixAssembler> assembler;
  SparseMatrix mass;
  FreeDofs freeDofs;
  Eigen::VectorXd gravityForce;  // M g, full
  double rayleighMass = 0.0;     // D = alpha M + beta K(u at the step start)
  double rayleighStiffness = 0.0;
  std::string model = "corotational";
  int maxIterations = 1;
  double tolerance = 1e-6;
  double factorCost = 0.0;
  int refactorIterations = IntegratorOptions{}.pcgRefactorIterations;
  bool singlePrecision = IntegratorOptions{}.pcgSinglePrecision;
};

// A beam clamped at x = 0 that sags under gravity (rubber-like, so rotations are large).
Scene makeScene(const std::string& name, const Eigen::Vector3d& size, const Eigen::Vector3i& cells,
                const ProblemSettings& settings) {
  BoxMeshSpec spec;
  spec.size = size;
  spec.cells = cells;
  spec.material = Material{"rubber", 1000.0, 5e5, 0.45};
  if (settings.model == "mooney-rivlin") spec.material.mooneyRivlin = kMooneyRivlin;
  Scene scene{name,
              makeBoxMesh(spec),
              nullptr,
              {},
              {},
              {},
              settings.rayleighMass,
              settings.rayleighStiffness,
              settings.model,
              settings.maxIterations,
              settings.tolerance,
              settings.factorCost,
              settings.refactorIterations,
              settings.singlePrecision};
  scene.assembler = std::make_shared<const MatrixAssembler>(scene.mesh);
  scene.mass = massMatrix(scene.mesh, *scene.assembler, MassType::consistent);
  std::vector<int> clamped;
  for (int v = 0; v < scene.mesh.numVertices(); ++v) {
    if (scene.mesh.restPosition(v).x() <= 1e-12) clamped.push_back(v);
  }
  scene.freeDofs = FreeDofs::fromFixedVertices(scene.mesh.numVertices(), clamped);
  Eigen::VectorXd g(scene.mesh.numDofs());
  for (int v = 0; v < scene.mesh.numVertices(); ++v) g.segment<3>(3 * v) = kGravity;
  scene.gravityForce = scene.mass * g;
  return scene;
}

// ---------------------------------------------------------------- Vega-style reference

// Polar rotation by the scaled Newton iteration on X (Higham), stopping when the
// relative change of X in the 1-norm falls below 1e-6; a reflection (inverted element)
// is replaced by the SVD rotation with the sign fix.
Eigen::Matrix3d iterativePolarRotation(const Eigen::Matrix3d& f) {
  Eigen::Matrix3d x = f;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const Eigen::Matrix3d inverseTransposed = x.inverse().transpose();
    const double scale = std::sqrt(inverseTransposed.cwiseAbs().colwise().sum().maxCoeff() *
                                   inverseTransposed.cwiseAbs().rowwise().sum().maxCoeff() /
                                   (x.cwiseAbs().colwise().sum().maxCoeff() * x.cwiseAbs().rowwise().sum().maxCoeff()));
    const Eigen::Matrix3d next = 0.5 * ((std::sqrt(scale) * x) + (inverseTransposed / std::sqrt(scale)));
    const double change = (next - x).cwiseAbs().colwise().sum().maxCoeff();
    x = next;
    if (change <= 1e-6 * x.cwiseAbs().colwise().sum().maxCoeff()) break;
  }
  if (!(x.determinant() > 0.0) || !x.allFinite()) return polarDecomposition(f).rotation;
  return x;
}

class VegaStyleReference {
 public:
  explicit VegaStyleReference(const Scene& scene) : scene_(scene) {
    const TetMesh& mesh = scene.mesh;
    const int numElements = mesh.numElements();
    restGradients_.resize(static_cast<std::size_t>(numElements));
    stiffness_.resize(static_cast<std::size_t>(numElements));
    positions_.resize(static_cast<std::size_t>(numElements) * 144);
    for (int e = 0; e < numElements; ++e) {
      double volume = 0.0;
      const ElementPositions rest = mesh.elementRestPositions(e);
      restGradients_[static_cast<std::size_t>(e)] = shapeFunctionGradients(rest, &volume);
      const Material& m = mesh.elementMaterial(e);
      stiffness_[static_cast<std::size_t>(e)] = linearElementStiffness(rest, m.youngsModulus, m.poissonRatio);
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j)
          positions_[(static_cast<std::size_t>(e) * 144) + static_cast<std::size_t>((12 * j) + i)] =
              scene.assembler->slot(e, i, j);
    }
    fullStiffness_ = scene.assembler->createMatrix();
    const std::vector<int>& free = scene.freeDofs.freeToFull();
    extractor_ = SubmatrixExtractor(fullStiffness_, free, free);
    freeMass_ = extractor_.extract(scene.mass);
    freeStiffness_ = extractor_.extract(fullStiffness_);
    solver_ = makeSparseSolver(SolverKind::cholmod);
  }

  // f_int(u) and K(u) into fullForces_ / fullStiffness_, one element after the other.
  void forcesAndStiffness(const Eigen::VectorXd& u) {
    const TetMesh& mesh = scene_.mesh;
    fullForces_.setZero(mesh.numDofs());
    double* values = fullStiffness_.valuePtr();
    std::fill(values, values + fullStiffness_.nonZeros(), 0.0);
    for (int e = 0; e < mesh.numElements(); ++e) {
      const auto i = static_cast<std::size_t>(e);
      ElementPositions x = mesh.elementRestPositions(e);
      for (int a = 0; a < 4; ++a) x.col(a) += u.segment<3>(3 * mesh.elements()(a, e));
      const Eigen::Matrix3d rotation = iterativePolarRotation(x * restGradients_[i].transpose());
      Eigen::Matrix<double, 12, 12> blockRotation = Eigen::Matrix<double, 12, 12>::Zero();
      for (int a = 0; a < 4; ++a) blockRotation.block<3, 3>(3 * a, 3 * a) = rotation;
      const Eigen::Matrix<double, 12, 12> rk = blockRotation * stiffness_[i];
      const Eigen::Matrix<double, 12, 12> rkrt = rk * blockRotation.transpose();
      Eigen::Matrix<double, 12, 1> z;
      for (int a = 0; a < 4; ++a) {
        z.segment<3>(3 * a) = rotation.transpose() * x.col(a) - mesh.elementRestPositions(e).col(a);
      }
      const Eigen::Matrix<double, 12, 1> f = rk * z;
      for (int a = 0; a < 4; ++a) fullForces_.segment<3>(3 * mesh.elements()(a, e)) += f.segment<3>(3 * a);
      const int* slots = positions_.data() + (i * 144);
      for (int k = 0; k < 144; ++k) values[slots[k]] += rkrt.data()[k];
    }
  }

  // One linearized backward Euler step, timing its phases:
  // (M + h D + h^2 K) dv = h (f_ext - f_int - D v - h K v), D = alpha M + beta K.
  void step(Eigen::VectorXd& u, Eigen::VectorXd& v) {
    Stopwatch watch;
    watch.start();
    forcesAndStiffness(u);
    elementSeconds += watch.stop();
    watch.start();
    extractor_.update(fullStiffness_, freeStiffness_);
    const double h = kTimestep;
    const double alpha = scene_.rayleighMass;
    const double beta = scene_.rayleighStiffness;
    systemMatrix_ = ((1.0 + (h * alpha)) * freeMass_) + (((h * beta) + (h * h)) * freeStiffness_);
    if (!analysed_) {
      solver_->analyzePattern(systemMatrix_);
      analysed_ = true;
    }
    solver_->factorize(systemMatrix_);
    factorSeconds += watch.stop();
    watch.start();
    const FreeDofs& dofs = scene_.freeDofs;
    const Eigen::VectorXd freeV = dofs.restrict(v);
    const Eigen::VectorXd rhs = h * (dofs.restrict(scene_.gravityForce) - dofs.restrict(fullForces_) -
                                     (alpha * (freeMass_ * freeV)) - ((beta + h) * (freeStiffness_ * freeV)));
    const Eigen::VectorXd dv = solver_->solve(rhs);
    const Eigen::VectorXd newV = freeV + dv;
    v = dofs.expand(newV);
    u += h * v;
    solveSeconds += watch.stop();
  }

  double elementSeconds = 0.0, factorSeconds = 0.0, solveSeconds = 0.0;

 private:
  const Scene& scene_;
  std::vector<Eigen::Matrix<double, 3, 4>> restGradients_;
  std::vector<ElementMatrix> stiffness_;
  std::vector<int> positions_;
  SparseMatrix fullStiffness_, freeMass_, freeStiffness_, systemMatrix_;
  Eigen::VectorXd fullForces_;
  SubmatrixExtractor extractor_;
  std::unique_ptr<SparseSolver> solver_;
  bool analysed_ = false;
};

// ---------------------------------------------------------------- the toolkit

struct Timing {
  double elementMs = 0, factorMs = 0, solveMs = 0, stepMs = 0;
  double elementMicrosPerElement = 0;
  long long factorizations = 0, pcgIterations = 0, newtonIterations = 0;
  double factorCostInIterations = 0.0;
  Eigen::VectorXd finalDisplacement;
};

// The scene's force model: corotational (Vega's warp 1 = simple tangent, warp 2 = exact),
// or hyperelastic; neo-Hookean and Mooney-Rivlin with Vega's clamped inversion threshold
// and compression resistance, StVK in the Green-strain form of Vega's StVKForceModel.
std::shared_ptr<ForceModel> makeModel(const Scene& scene, RotationStart start) {
  if (scene.model == "corotational" || scene.model == "corotational-exact") {
    auto model = std::make_shared<CorotationalLinearFEM>(
        scene.mesh, scene.assembler, scene.model == "corotational" ? TangentKind::simple : TangentKind::exact);
    model->setRotationStart(start);
    return model;
  }
  HyperelasticOptions options;
  HyperelasticMaterialKind kind = HyperelasticMaterialKind::stvk;
  if (scene.model != "stvk") {
    kind = scene.model == "neo-hookean" ? HyperelasticMaterialKind::neoHookean : HyperelasticMaterialKind::mooneyRivlin;
    options.inversionThreshold = kInversionThreshold;
    options.inversionHandling = InversionHandling::vegaClamp;
    options.enableCompressionResistance = true;
    options.compressionResistance = kCompressionResistance;
  }
  return makeHyperelasticForceModel(scene.mesh, kind, options, scene.assembler);
}

// Exact solves or the kept factor, with the scene's Newton settings (Vega's loop: full
// steps, D with K at each iterate, the relative residual of the free DOFs).
IntegratorOptions integratorOptions(const Scene& scene, bool reuse, double pcgTolerance = 1e-8) {
  IntegratorOptions options;
  options.reuseFactor = reuse;
  options.pcgTolerance = pcgTolerance;
  options.pcgFactorCost = scene.factorCost;
  options.pcgRefactorIterations = scene.refactorIterations;
  options.pcgSinglePrecision = scene.singlePrecision;
  options.maxIterations = scene.maxIterations;
  if (scene.maxIterations > 1) {
    options.tolerance = scene.tolerance;
    options.lineSearch = false;
    options.rayleighStiffnessAtIterate = true;
  }
  return options;
}

DynamicSystem toolkitSystem(const Scene& scene, RotationStart start = RotationStart::fromDeformation) {
  DynamicSystem system;
  system.forceModel = makeModel(scene, start);
  system.mass = scene.mass;
  system.freeDofs = scene.freeDofs;
  system.rayleighMass = scene.rayleighMass;
  system.rayleighStiffness = scene.rayleighStiffness;
  const Eigen::VectorXd gravity = scene.gravityForce;
  system.externalForce = [gravity](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& forces) {
    forces = gravity;
  };
  return system;
}

Timing runToolkit(const Scene& scene, int warmup, int steps, bool reuse, double pcgTolerance = 1e-8,
                  RotationStart start = RotationStart::fromDeformation) {
  BackwardEuler integrator(toolkitSystem(scene, start), kTimestep, integratorOptions(scene, reuse, pcgTolerance));
  for (int k = 0; k < warmup; ++k) integrator.step();
  const IntegratorStats before = integrator.stats();
  const long long pcgBefore = reuse ? integrator.factorReuseStats()->pcgIterations : 0;
  long long newtonIterations = 0;
  Stopwatch watch;
  watch.start();
  for (int k = 0; k < steps; ++k) {
    integrator.step();
    newtonIterations += integrator.lastIterations();
  }
  const double total = watch.stop();
  const IntegratorStats& after = integrator.stats();
  Timing t;
  t.stepMs = 1e3 * total / steps;
  t.elementMs =
      1e3 * ((after.forceSeconds - before.forceSeconds) + (after.assemblySeconds - before.assemblySeconds)) / steps;
  t.factorMs = 1e3 * (after.factorizationSeconds - before.factorizationSeconds) / steps;
  t.solveMs = 1e3 * (after.solveSeconds - before.solveSeconds) / steps;
  t.factorizations = after.factorizations - before.factorizations;
  t.newtonIterations = newtonIterations;
  t.pcgIterations = reuse ? integrator.factorReuseStats()->pcgIterations - pcgBefore : 0;
  t.factorCostInIterations = reuse ? integrator.factorReuseStats()->factorCostInIterations : 0.0;
  t.finalDisplacement = integrator.displacement();
  return t;
}

Timing runReference(const Scene& scene, int warmup, int steps) {
  VegaStyleReference reference(scene);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(scene.mesh.numDofs());
  Eigen::VectorXd v = u;
  for (int k = 0; k < warmup; ++k) reference.step(u, v);
  reference.elementSeconds = reference.factorSeconds = reference.solveSeconds = 0.0;
  Stopwatch watch;
  watch.start();
  for (int k = 0; k < steps; ++k) reference.step(u, v);
  const double total = watch.stop();
  Timing t;
  t.stepMs = 1e3 * total / steps;
  t.elementMs = 1e3 * reference.elementSeconds / steps;
  t.factorMs = 1e3 * reference.factorSeconds / steps;
  t.solveMs = 1e3 * reference.solveSeconds / steps;
  t.factorizations = steps;
  t.finalDisplacement = u;
  return t;
}

// Element kernel alone (forces + simple tangent, rotations included), microseconds per
// element, at a sagged state, with the given thread count.
double kernelMicros(const Scene& scene, const Eigen::VectorXd& u, int threads, int repeats,
                    RotationStart start = RotationStart::fromDeformation) {
  omp_set_num_threads(threads);
  CorotationalLinearFEM model(scene.mesh, scene.assembler);
  model.setRotationStart(start);
  SparseMatrix k = model.createStiffnessMatrix();
  Eigen::VectorXd f;
  Eigen::VectorXd perturbed = u;
  model.forcesAndTangent(perturbed, f, k);
  Stopwatch watch;
  watch.start();
  for (int r = 0; r < repeats; ++r) {
    perturbed[0] += 1e-12;  // a new displacement each time: no cache hit
    model.forcesAndTangent(perturbed, f, k);
  }
  return 1e6 * watch.stop() / (repeats * static_cast<double>(scene.mesh.numElements()));
}

double referenceKernelMicros(const Scene& scene, const Eigen::VectorXd& u, int repeats) {
  VegaStyleReference reference(scene);
  Stopwatch watch;
  watch.start();
  for (int r = 0; r < repeats; ++r) reference.forcesAndStiffness(u);
  return 1e6 * watch.stop() / (repeats * static_cast<double>(scene.mesh.numElements()));
}

double scaledDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).lpNorm<Eigen::Infinity>() / std::max(a.lpNorm<Eigen::Infinity>(), 1e-300);
}

// The .params lines that say which force model and Newton loop run (Vega's names: warp 1
// or 2, the inversion threshold and compression resistance, maxIterations, epsilon).
void writeModelParams(std::ostream& params, const Scene& scene) {
  params << "model " << (scene.model == "corotational-exact" ? std::string("corotational") : scene.model) << '\n';
  if (scene.model == "corotational" || scene.model == "corotational-exact") {
    params << "warp " << (scene.model == "corotational" ? 1 : 2) << '\n';
  } else if (scene.model != "stvk") {
    params << "inversionThreshold " << kInversionThreshold << "\ncompressionResistance " << kCompressionResistance
           << '\n';
  }
  if (scene.model == "mooney-rivlin") {
    params << "# Mooney-Rivlin mu01 " << kMooneyRivlin.mu01 << " mu10 " << kMooneyRivlin.mu10 << " v1 "
           << kMooneyRivlin.v1 << " Pa (in the .veg; youngsModulus and poissonRatio are unused)\n";
  }
  params << "maxIterations " << scene.maxIterations << "\nepsilon " << scene.tolerance << '\n';
}

// Writes the problem a run of this benchmark times, for an external program to run the
// identical one: DIR/NAME.veg (the mesh and its material, writeVeg), DIR/NAME.fixed (the
// fixed DOFs, 0-based global ids x 3 + coordinate, ascending, one a line), DIR/NAME.params
// (force model, material, time step, Rayleigh damping, gravity, Newton settings, step
// counts: `key value...` lines; see writeModelParams) and
// unless states is false, DIR/NAME.u and DIR/NAME.reuse.u (the toolkit's displacement after warmup + steps steps
// from rest, exact solves and the default kept factor, PCG 1e-10; 17 significant digits, one
// DOF a line).
void writeProblem(const Scene& scene, const std::filesystem::path& dir, int warmup, int steps, bool states) {
  std::filesystem::create_directories(dir);
  writeVeg(dir / (scene.name + ".veg"), scene.mesh);
  const auto open = [&](const std::string& extension) {
    const std::filesystem::path path = dir / (scene.name + extension);
    std::ofstream out(path);
    if (!out) throw asyncfem::Error("cannot write " + path.string());
    out.precision(17);
    return out;
  };
  {
    std::ofstream fixed = open(".fixed");
    for (int dof = 0; dof < scene.mesh.numDofs(); ++dof) {
      if (scene.freeDofs.isFixed(dof)) fixed << dof << '\n';
    }
  }
  {
    const Material& m = scene.mesh.elementMaterial(0);
    std::ofstream params = open(".params");
    params << "# " << scene.model << ", consistent mass, external force M g, from rest (u = v = 0),\n"
           << "# backward Euler with at most maxIterations Newton iterations per step\n";
    writeModelParams(params, scene);
    params << "youngsModulus " << m.youngsModulus << "\npoissonRatio " << m.poissonRatio << "\ndensity " << m.density
           << "\ntimestep " << kTimestep << "\ndampingMass " << scene.rayleighMass << "\ndampingStiffness "
           << scene.rayleighStiffness << "\ngravity " << kGravity.x() << ' ' << kGravity.y() << ' ' << kGravity.z()
           << "\nwarmupSteps " << warmup << "\ntimedSteps " << steps << "\nfixedDofs " << scene.freeDofs.numFixed()
           << '\n';
  }
  if (!states) {
    std::printf("%s: wrote %s/%s.{veg,fixed,params} (%d vertices, %d tets, %d fixed DOFs)\n", scene.name.c_str(),
                dir.string().c_str(), scene.name.c_str(), scene.mesh.numVertices(), scene.mesh.numElements(),
                scene.freeDofs.numFixed());
    return;
  }
  Eigen::VectorXd exact;
  for (const bool reuse : {false, true}) {
    BackwardEuler integrator(toolkitSystem(scene), kTimestep,
                             integratorOptions(scene, reuse, IntegratorOptions{}.pcgTolerance));
    for (int k = 0; k < warmup + steps; ++k) integrator.step();
    const Eigen::VectorXd& u = integrator.displacement();
    if (!u.allFinite())
      throw asyncfem::Error(scene.name + ": displacement not finite after " + std::to_string(warmup + steps) +
                            " steps");
    std::ofstream displacement = open(reuse ? ".reuse.u" : ".u");
    for (Eigen::Index i = 0; i < u.size(); ++i) displacement << u[i] << '\n';
    if (!reuse) exact = u;
  }
  std::printf(
      "%s: wrote %s/%s.{veg,fixed,params,u,reuse.u} (%d vertices, %d tets, %d fixed DOFs; u after %d steps, max |u| "
      "%.6f)\n",
      scene.name.c_str(), dir.string().c_str(), scene.name.c_str(), scene.mesh.numVertices(), scene.mesh.numElements(),
      scene.freeDofs.numFixed(), warmup + steps, exact.lpNorm<Eigen::Infinity>());
}

// The full comparison on one corotational scene: the built-in reference, the toolkit's
// configurations, the element kernels alone and the agreement of the final states.
void compareWithReference(const Scene& scene, int warmup, int steps, int threads) {
  std::printf("\n%s: %d vertices, %d tets, %d free DOFs\n", scene.name.c_str(), scene.mesh.numVertices(),
              scene.mesh.numElements(), scene.freeDofs.numFree());
  omp_set_num_threads(threads);
  const Timing reference = runReference(scene, warmup, steps);
  const Timing exact = runToolkit(scene, warmup, steps, false);
  const Timing reuse = runToolkit(scene, warmup, steps, true);
  const Timing byDefault = runToolkit(scene, warmup, steps, true, IntegratorOptions{}.pcgTolerance);
  // reuseFactor already makes results depend on the history (which factor is kept), so
  // warm-started rotations lose nothing more there.
  const Timing warm = runToolkit(scene, warmup, steps, true, 1e-8, RotationStart::previousEvaluation);
  const int repeats = 10;
  const double kernel1 = kernelMicros(scene, exact.finalDisplacement, 1, repeats);
  const double kernelN = kernelMicros(scene, exact.finalDisplacement, threads, repeats);
  const double kernelWarm = kernelMicros(scene, exact.finalDisplacement, 1, repeats, RotationStart::previousEvaluation);
  const double kernelReference = referenceKernelMicros(scene, exact.finalDisplacement, 3);
  omp_set_num_threads(threads);
  std::printf(
      "  element kernel (forces + tangent, us/element): reference %.3f, toolkit 1 thread %.3f (%.1fx), "
      "%d threads %.3f (%.1fx)\n",
      kernelReference, kernel1, kernelReference / kernel1, threads, kernelN, kernelReference / kernelN);
  std::printf("  element kernel with warm-started rotations, 1 thread: %.3f us/element (%.1fx)\n", kernelWarm,
              kernelReference / kernelWarm);
  std::printf("  %-28s %10s %10s %10s %10s %8s %8s %9s\n", "per step (ms)", "elements", "factor", "solve", "step",
              "factors", "PCG its", "vs ref");
  const auto row = [&](const char* label, const Timing& t) {
    std::printf("  %-28s %10.2f %10.2f %10.2f %10.2f %8lld %8lld %8.2fx\n", label, t.elementMs, t.factorMs, t.solveMs,
                t.stepMs, t.factorizations, t.pcgIterations, reference.stepMs / t.stepMs);
  };
  row("Vega-style reference (1 thr)", reference);
  row("toolkit, exact solves", exact);
  row("toolkit, reuseFactor 1e-8", reuse);
  row("toolkit, default (kept, 1e-10)", byDefault);
  row("toolkit, reuse 1e-8 + warm R", warm);
  std::printf(
      "  final displacement, max |difference| / max |u|: toolkit exact vs reference %.2e, reuseFactor 1e-8 vs "
      "exact %.2e, default (1e-10) vs exact %.2e (tip sag %.3f m)\n",
      scaledDifference(exact.finalDisplacement, reference.finalDisplacement),
      scaledDifference(reuse.finalDisplacement, exact.finalDisplacement),
      scaledDifference(byDefault.finalDisplacement, exact.finalDisplacement),
      exact.finalDisplacement.lpNorm<Eigen::Infinity>());
  std::printf("  reuseFactor: one factorization counted as %.1f PCG iterations (flop ratio / 6)\n",
              reuse.factorCostInIterations);
}

// The exact and the factor-reusing path side by side over 100 steps of a scene.
void compareOver100Steps(const Scene& scene) {
  BackwardEuler exact(toolkitSystem(scene), kTimestep, integratorOptions(scene, false));
  BackwardEuler reuse(toolkitSystem(scene), kTimestep,
                      integratorOptions(scene, true, IntegratorOptions{}.pcgTolerance));
  double largest = 0.0;
  for (int k = 0; k < 100; ++k) {
    exact.step();
    reuse.step();
    largest = std::max(largest, scaledDifference(reuse.displacement(), exact.displacement()));
  }
  std::printf(
      "\n%s, 100 steps from rest: max over steps of max |u_reuse - u_exact| / max |u_exact| = %.2e; "
      "reuseFactor: %lld factorizations, %lld PCG iterations; exact: %lld factorizations\n",
      scene.name.c_str(), largest, reuse.factorReuseStats()->refactorizations, reuse.factorReuseStats()->pcgIterations,
      exact.stats().factorizations);
}

// One toolkit configuration alone, one line per scene (for timing against another program).
void timeToolkitOnly(const std::vector<Scene>& scenes, int warmup, int steps, const std::string& configuration) {
  for (const Scene& scene : scenes) {
    const Timing t = runToolkit(scene, warmup, steps, configuration == "reuse", IntegratorOptions{}.pcgTolerance);
    std::printf(
        "%s, %s, toolkit %s, per step (ms): elements %.2f, factor %.2f, solve %.2f, step %.2f; %lld factorizations, "
        "%lld PCG iterations, %lld Newton iterations; factorization priced at %.1f PCG iterations; max |u| %.9f\n",
        scene.name.c_str(), scene.model.c_str(), configuration.c_str(), t.elementMs, t.factorMs, t.solveMs, t.stepMs,
        t.factorizations, t.pcgIterations, t.newtonIterations, t.factorCostInIterations,
        t.finalDisplacement.lpNorm<Eigen::Infinity>());
  }
}

struct CommandLine {
  int steps = 30;
  int warmup = kWarmupSteps;
  std::string meshName = "all";
  std::string writeDir;
  bool writeStates = true;
  std::string toolkitOnly;
  ProblemSettings settings;
};

void addOptions(CLI::App& app, CommandLine& c) {
  app.add_option("steps", c.steps, "Timed steps per configuration (after the warm-up steps)")
      ->check(CLI::PositiveNumber);
  app.add_option("--warmup", c.warmup, "Untimed steps before the timed ones (default 5)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--mesh", c.meshName,
                 "Which mesh: all, bridge-sized, dragon-sized, or box:N (the 4 x 1 x 1 box of scripts/scale-study.py, "
                 "4N x N x N cubes of 6 tets: 24 N^3 tets)")
      ->check([](const std::string& name) -> std::string {
        if (name == "all" || name == "bridge-sized" || name == "dragon-sized") return {};
        if (name.rfind("box:", 0) == 0 && name.size() > 4 &&
            name.find_first_not_of("0123456789", 4) == std::string::npos && std::stoi(name.substr(4)) >= 1) {
          return {};
        }
        return "expected all, bridge-sized, dragon-sized or box:N with N >= 1, got " + name;
      });
  app.add_option("--rayleigh-mass", c.settings.rayleighMass, "Rayleigh damping alpha (D = alpha M + beta K)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--rayleigh-stiffness", c.settings.rayleighStiffness, "Rayleigh damping beta")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--write-meshes", c.writeDir,
                 "Write each problem (.veg, fixed DOFs, parameters, final displacement) to this folder and exit");
  app.add_flag("!--no-states", c.writeStates,
               "With --write-meshes: skip the toolkit's final states (.u, .reuse.u), which cost two runs");
  app.add_option("--toolkit-only", c.toolkitOnly,
                 "Time only this toolkit configuration (exact solves, or reuse: the default kept factor, PCG to 1e-10)")
      ->check(CLI::IsMember({"exact", "reuse"}));
  app.add_option("--model", c.settings.model,
                 "Force model (with --toolkit-only or --write-meshes; corotational = Vega's warp 1, "
                 "corotational-exact = warp 2)")
      ->check(CLI::IsMember(kModels));
  app.add_option("--newton-iterations", c.settings.maxIterations,
                 "Newton iterations per step at most (Vega's maxIterations)")
      ->check(CLI::PositiveNumber);
  app.add_option("--newton-tolerance", c.settings.tolerance, "Newton's relative residual (Vega's epsilon)")
      ->check(CLI::PositiveNumber);
  app.add_option("--factor-cost", c.settings.factorCost,
                 "The kept factor's refactorization priced in PCG iterations (IntegratorOptions::pcgFactorCost; "
                 "0: the flop model)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--refactor-iterations", c.settings.refactorIterations,
                 "Refactor after a PCG solve of more iterations (IntegratorOptions::pcgRefactorIterations)")
      ->check(CLI::PositiveNumber);
  app.add_flag("!--double-preconditioner", c.settings.singlePrecision,
               "Precondition PCG with the double factor (IntegratorOptions::pcgSinglePrecision = false)");
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  CLI::App app{"Nonlinear backward Euler steps of this toolkit against a Vega-style reference."};
  CommandLine c;
  addOptions(app, c);
  CLI11_PARSE(app, argc, argv);
  const bool reference = c.toolkitOnly.empty() && c.writeDir.empty();
  if (reference && (c.settings.model != "corotational" || c.settings.maxIterations != 1)) {
    std::fprintf(stderr,
                 "corotationalBenchmark: --model %s --newton-iterations %d needs --toolkit-only or --write-meshes (the "
                 "built-in reference is corotational with one iteration)\n",
                 c.settings.model.c_str(), c.settings.maxIterations);
    return 1;
  }
  const int warmup = c.warmup;
  const int threads = omp_get_max_threads();
  std::printf(
      "%s backward Euler step, h = %g, %d warm-up + %d timed steps, Newton at most %d iterations (tolerance %g); "
      "Rayleigh alpha %g beta %g; %d OpenMP threads; %s; load %s\n",
      c.settings.model.c_str(), kTimestep, warmup, c.steps, c.settings.maxIterations, c.settings.tolerance,
      c.settings.rayleighMass, c.settings.rayleighStiffness, threads, cpuModel().c_str(), loadAverage().c_str());
  std::vector<Scene> scenes;
  if (c.meshName.rfind("box:", 0) == 0) {
    // The scale study's box (scripts/scale-study.py): same material, clamp and gravity as the
    // bridge-sized mesh, so a Vega run of the written problem times the same step at scale.
    const int n = std::stoi(c.meshName.substr(4));
    scenes.push_back(makeScene("box-" + std::to_string(n), Eigen::Vector3d(4.0, 1.0, 1.0), Eigen::Vector3i(4 * n, n, n),
                               c.settings));
  } else if (c.meshName != "dragon-sized") {
    scenes.push_back(makeScene("bridge-sized", Eigen::Vector3d(4.8, 0.6, 0.7), Eigen::Vector3i(48, 6, 7), c.settings));
  }
  if (c.meshName == "all" || c.meshName == "dragon-sized") {
    scenes.push_back(
        makeScene("dragon-sized", Eigen::Vector3d(3.2, 1.6, 1.4), Eigen::Vector3i(32, 16, 14), c.settings));
  }
  if (!c.writeDir.empty()) {
    try {
      for (const Scene& scene : scenes) writeProblem(scene, c.writeDir, warmup, c.steps, c.writeStates);
    } catch (const std::exception& error) {
      std::fprintf(stderr, "corotationalBenchmark --write-meshes %s: %s\n", c.writeDir.c_str(), error.what());
      return 1;
    }
    return 0;
  }
  if (!c.toolkitOnly.empty()) {
    timeToolkitOnly(scenes, warmup, c.steps, c.toolkitOnly);
    return 0;
  }
  for (const Scene& scene : scenes) compareWithReference(scene, warmup, c.steps, threads);
  if (scenes.front().name == "bridge-sized") compareOver100Steps(scenes.front());
  return 0;
}
