// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/stepGrowthCheck.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// The stability stress test (utilities/stabilityStressTest, docs/benchmarks.md): free
/// vibration of a two-material bar under each integrator over a grid of stiffness ratios,
/// timestep ratios, damping and mesh quality, or a user's multirate scene under several
/// ratios; each run ends in a StressOutcome that stabilityVerdict() classifies.

/// Rayleigh damping D = alpha M + beta K of a grid row, by name (none, light, heavy).
struct StressDamping {
  std::string name;
  double alpha = 0.0;  ///< 1/s
  double beta = 0.0;   ///< s
};

/// One run of the grid.
struct StressCase {
  std::string integrator;       ///< registry name: async, multirate-uncoupled or backward-euler
  std::string variant;          ///< "" or "symmetric" (async with the symmetric Schur complement)
  double stiffnessRatio = 1.0;  ///< Young's modulus of the stiff quarter / that of the rest
  int ratio = 1;                ///< timestep ratio m of the stiff quarter (multirate only)
  StressDamping damping;
  bool perturbed = false;  ///< on perturbedBoxMesh() of the bar instead of the regular one
};

/// What a run did.
struct StressOutcome {
  /// max over the measured frames of E / E_ref, E = kinetic + elastic - constant loads . u
  double energyGrowth = 0.0;
  bool energyMeasured = false;   ///< false when no frame ended after the loads (or contact acts)
  int failedFrame = -1;          ///< the frame advanceFrame() refused (non-finite, blow-up), -1: none
  std::string failure;           ///< its message
  double maxDisplacement = 0.0;  ///< max over frames and DOFs of |u|, length units
  double seconds = 0.0;          ///< wall time of the frames
  /// Scene runs: estimateSceneStepGrowth() of the run's scene, before the run.
  std::optional<StepGrowthEstimate> stepGrowth;
};

/// E / E_ref above 1 + energyGrowthTolerance counts as growth: far above the round-off of
/// the energy sums of a few thousand DOFs (about 1e-13 relative), far below the growth of
/// an unstable step, which compounds by a factor > 1 every step.
inline constexpr double energyGrowthTolerance = 1e-9;

enum class StabilityVerdict {
  stable,        ///< every frame stored, no measured energy growth
  energyGrowth,  ///< every frame stored, but E / E_ref > 1 + energyGrowthTolerance
  blowUp,        ///< a frame was refused (failedFrame >= 0)
};

/// The verdict on one run: blowUp when a frame failed, else energyGrowth when the energy
/// was measured and grew beyond energyGrowthTolerance, else stable.
StabilityVerdict stabilityVerdict(const StressOutcome& outcome);
/// "stable", "energy growth" or "blow-up".
std::string toString(StabilityVerdict verdict);

/// The bar of the grid: 1 x 0.25 x 0.25 (length units) with cells (x, y, z) cells, density
/// 1000 and Young's modulus 1e5 (Poisson 0.4); its last quarter along x (element and
/// vertex set "stiff") has density 500 and Young's modulus 1e5 stiffnessRatio. Vertex set
/// "xmin" is the fixed end.
BoxMeshSpec stressBarSpec(const Eigen::Vector3i& cells, double stiffnessRatio);

/// A box mesh with its vertices moved by a uniform random shift in
/// [-maxShiftCells, maxShiftCells] cell widths per axis, except along the axes where a
/// vertex lies on the box's faces (so the box keeps its shape): slivers and badly shaped
/// elements, never an inverted one or one of quality below 1e-3 (another draw is taken
/// then, up to 20). Quality: 6 sqrt(2) |V| / l_max^3 (1 for a regular tet, 0 for a flat
/// one). The same seed gives the same mesh. Throws asyncfem::Error when 20 draws all
/// invert or flatten an element (maxShiftCells too large for the cells).
struct PerturbedMesh {
  TetMesh mesh;               ///< the box mesh's elements, materials and sets, moved vertices
  double worstQuality = 1.0;  ///< the lowest element quality, in (1e-3, 1]
};
PerturbedMesh perturbedBoxMesh(const BoxMeshSpec& spec, unsigned seed, double maxShiftCells = 0.4);

/// The bar scene of a grid case on the mesh in meshFile: "xmin" fixed, the case's damping
/// and integrator, large step 1/120 s, 30 frames per second; multirate integrators get one
/// fast region, the stiff quarter (stiffVertices: the vertices of its elements), at the
/// case's ratio.
Scene stressScene(const StressCase& run, const std::filesystem::path& meshFile, const std::vector<int>& stiffVertices);

/// Runs `frames` frames of a built simulation (advanceFrame). The energy is measured after
/// the frames that end at or after freeFrom (no load changes from then on, so it may only
/// stay or decrease) against referenceEnergy when > 0, else the first of those energies.
StressOutcome runStressFrames(Simulation& simulation, int frames, double freeFrom, double referenceEnergy = -1.0);

/// Which parts of the grid to run; an empty list takes the whole default (or full) list.
struct StressGridSelection {
  bool full = false;  ///< stiffness ratios 1 to 1e6 by decades, m in {1, 2, 8, 32, 100, 200}
  std::vector<double> stiffnessRatios;
  std::vector<int> ratios;
  std::vector<std::string> dampings;     ///< none, light, heavy
  std::vector<std::string> integrators;  ///< async, async-symmetric, multirate-uncoupled, backward-euler
  std::vector<std::string> meshes;       ///< regular, perturbed
};

/// The lists a grid covers.
struct StressGrid {
  std::vector<double> stiffnessRatios;
  std::vector<int> ratios;
  std::vector<StressDamping> dampings;
  std::vector<std::pair<std::string, std::string>> integrators;  ///< registry name, variant
  std::vector<bool> meshes;                                      ///< perturbed?
};
StressGrid stressGrid(const StressGridSelection& selection);

/// One case of the grid with the mesh file it runs on.
struct StressJob {
  StressCase stressCase;
  std::filesystem::path meshFile;
  double quality = 1.0;            ///< worst element quality of the mesh (1: regular)
  std::vector<int> stiffVertices;  ///< the fast region of multirate cases
};

/// The cases of grid, in the order of the table: stiffness ratio, mesh, damping,
/// integrator, m (backward Euler once, m does not apply). Writes each bar mesh once, as
/// folder/bar-J[-perturbed].veg, J the number of jobs before it (perturbedBoxMesh(seed)
/// for the perturbed ones).
std::vector<StressJob> stressJobs(const StressGrid& grid, const Eigen::Vector3i& cells, unsigned seed,
                                  const std::filesystem::path& folder);

/// One grid run: the case's scene for `frames` frames from a bent bar at rest (u_y =
/// 0.02 x^2 / L, zero velocity) with no load; energy growth E / E_0 from t = 0.
StressOutcome runStressJob(const StressJob& job, int frames);

/// Runs work(i) for i in [0, count) on `workers` threads (runs are independent) and calls
/// report(i, outcome) in index order, one call at a time, as soon as runs 0..i are done. A
/// run that throws is reported as failed at frame 0 ("setup failed: <message>").
void runStressJobsInOrder(std::size_t count, int workers, const std::function<StressOutcome(std::size_t)>& work,
                          const std::function<void(std::size_t, const StressOutcome&)>& report);

/// A scene run: one integrator (async, async-symmetric, multirate-uncoupled,
/// backward-euler) with every region at ratio m.
struct SceneStressJob {
  std::string integrator;
  int ratio = 1;
};

/// The runs of a scene: each integrator at each ratio (backward Euler once).
std::vector<SceneStressJob> sceneStressJobs(const std::vector<std::string>& integrators,
                                            const std::vector<int>& ratios);

/// The scene's explicit regions as the simulator reads them (mesh and constraints only,
/// nothing assembled). Throws asyncfem::Error naming the scene unless it is an async or
/// multirate-uncoupled scene with explicit regions.
std::vector<AsyncRegion> sceneStressRegions(const Scene& scene);

/// The scene of a run: every region's ratio set to the run's m, or backward Euler, for
/// `frames` frames.
Scene sceneForStressJob(const Scene& base, std::vector<AsyncRegion> regions, const SceneStressJob& job, int frames);

}  // namespace asyncfem
