// SPDX-License-Identifier: BSD-3-Clause
// libraries/modalAnalysis (lowest modes, per-mode shares of the fast regions and the
// verdict) and the scene-level region proposal, the document proposeRegions --json prints.

#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <bindings.hpp>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

namespace asyncfem::python {

namespace {

/// A list of regions as the "regions" array of proposeRegions --json (name, ratio, vertices).
py::object regionsObject(const std::vector<AsyncRegion>& regions) {
  return py::module_::import("json").attr("loads")(asyncRegionsJson(regions).dump());
}

/// The "modes" object of proposeRegions --json --modes K, as a dict with the same keys.
py::dict reportDict(const RegionModeReport& report) {
  py::list rows;
  for (const ModeInRegions& mode : report.modes) {
    py::dict row;
    row["omega"] = mode.omega;
    row["hertz"] = mode.hertz;
    row["omegaLargeStep"] = mode.omegaLargeStep;
    row["omegaSubstep"] = mode.omegaSubstep;
    row["regionShare"] = mode.regionShare;
    row["fastShare"] = mode.fastShare;
    row["visible"] = mode.visible;
    row["livesInFastRegions"] = mode.livesInFastRegions;
    row["keepable"] = mode.keepable;
    rows.append(row);
  }
  py::dict result;
  result["regions"] = report.regionNames;
  result["ratios"] = report.ratios;
  result["modes"] = rows;
  result["verdict"] = report.verdictText();
  return result;
}

std::vector<AsyncRegion> regionsOf(const std::vector<ProposedRegion>& proposed) {
  std::vector<AsyncRegion> regions;
  for (const ProposedRegion& r : proposed) regions.push_back(r.region);
  return regions;
}

/// The proposal part of proposeRegions --json (all but "modes"), as a dict.
py::dict proposalDict(const RegionProposal& proposal) {
  py::dict result;
  result["largeTimestep"] = proposal.largeTimestep;
  result["target"] = proposal.targetOmegaH;
  result["largeRegionOmegaH"] = proposal.largeRegionMaxFrequency * proposal.largeTimestep;
  result["regions"] = regionsObject(proposal.asyncRegions());
  result["withdrawnRegions"] = regionsObject(regionsOf(proposal.withdrawnRegions));
  result["modalVerdict"] = proposal.modalReport ? proposal.modalReport->verdictText() : std::string();
  return result;
}

/// What the scene-level proposal found: the proposal and, when modes were asked for, the
/// report of the scene's regions (or the proposal's).
struct SceneProposal {
  RegionProposal proposal;
  std::optional<RegionModeReport> modes;
};

/// proposeRegions SCENE --json [--modes K] [--dt H] [--frame-rate F]: the scene's own
/// "auto" settings when its async regions are proposed, else the default ones with the
/// modal check; the modal report is of the scene's explicit regions, else of the proposal.
SceneProposal proposeSceneRegions(const std::filesystem::path& path, int modeCount, double largeTimestep,
                                  double frameRate) {
  const Scene scene = loadScene(path);
  // The scene's timing, at the large step asked for (no need to divide its frames).
  FrameTiming timing = requireFrameTiming(scene);
  if (largeTimestep > 0.0) timing.timestep = largeTimestep;
  const double hL = timing.timestep;
  const double rate = frameRate > 0.0 ? frameRate : timing.frameRate;
  const std::shared_ptr<const Problem> problem = buildProblem(scene);
  const TetMesh& mesh = *problem->sharedMesh();
  const nlohmann::json& options = scene.integrator.options;
  const bool isAsync = scene.integrator.name == "async";
  const bool explicitRegions =
      isAsync && options.is_object() && options.contains("regions") && options["regions"].is_array();
  RegionProposalOptions automatic;
  automatic.modalCheck = true;
  if (isAsync && !explicitRegions) {
    automatic = parseRegionProposalOptions(integratorContext(scene, timing), options);
  }
  automatic.largeTimestep = hL;
  automatic.frameRate = rate;
  const VibrationMatrices matrices = vibrationMatrices(mesh, scene.mass);
  SceneProposal result{proposeRegions(mesh, problem->freeDofs(), automatic, matrices.stiffness, matrices.mass), {}};
  const RegionProposal& proposal = result.proposal;
  if (modeCount <= 0) return result;
  const std::vector<AsyncRegion> regions =
      explicitRegions ? parseAsyncOptions(scene, mesh, problem->freeDofs(), options).regions
                      : (proposal.regions.empty() ? regionsOf(proposal.withdrawnRegions) : proposal.asyncRegions());
  ModalOptions modal;
  modal.count = std::min(modeCount, problem->freeDofs().numFree() - 1);
  const ModalResult modes = lowestModes(matrices.stiffness, matrices.mass, problem->freeDofs(), modal);
  result.modes = analyseRegionModes(modes, matrices.mass, modalRegions(regions), hL, rate);
  return result;
}

void bindModalResult(py::module_& module) {
  py::class_<ModalResult>(module, "ModalResult",
                          "The lowest modes of K phi = omega^2 M phi on the free DOFs (lowest_modes)")
      .def_readonly("eigenvalues", &ModalResult::eigenvalues, "lambda_j = omega_j^2 (1/s^2), ascending")
      .def_readonly("frequencies", &ModalResult::frequencies, "omega_j (rad/s), ascending; rigid modes about 0")
      .def_property_readonly(
          "hertz", [](const ModalResult& r) { return Eigen::VectorXd(r.frequencies / (2.0 * M_PI)); },
          "omega_j / (2 pi) (Hz)")
      .def_readonly("modes", &ModalResult::modes,
                    "(3n, K) mode shapes, column j for frequency j: fixed DOFs zero, M-orthonormal")
      .def_readonly("shift", &ModalResult::shift, "the shift sigma of the shift-invert solve (1/s^2)")
      .def_readonly("iterations", &ModalResult::iterations, "implicit restarts of the Lanczos iteration")
      .def_readonly("operator_applications", &ModalResult::operatorApplications, "solves with K - sigma M")
      .def_readonly("factor_seconds", &ModalResult::factorSeconds, "time of the factorization of K - sigma M")
      .def_readonly("solve_seconds", &ModalResult::solveSeconds, "time of the whole eigensolve");

  module.def(
      "vibration_matrices",
      [](const TetMesh& mesh, MassType mass) {
        VibrationMatrices matrices;
        {
          py::gil_scoped_release release;
          matrices = vibrationMatrices(mesh, mass);
        }
        return py::make_tuple(matrices.stiffness, matrices.mass);
      },
      py::arg("mesh"), py::arg("mass") = MassType::consistent,
      "(K, M): linear K (the rest tangent of corotational FEM) and M of the requested type, full 3n x 3n "
      "csc_matrix, the matrices whose modes lowest_modes finds");
  module.def(
      "lowest_modes",
      [](const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
         const FreeDofs& freeDofs, int count, std::optional<double> shift, SolverKind solver, double tolerance,
         int maxIterations) {
        ModalOptions options;
        options.count = count;
        options.shift = shift.value_or(std::numeric_limits<double>::quiet_NaN());
        options.solver = solver;
        options.tolerance = tolerance;
        options.maxIterations = maxIterations;
        py::gil_scoped_release release;
        return lowestModes(stiffness, mass, freeDofs, options);
      },
      py::arg("stiffness"), py::arg("mass"), py::arg("free_dofs"), py::arg("count") = 10, py::arg("shift") = py::none(),
      py::arg("solver") = SolverKind::cholmod, py::arg("tolerance") = 1e-10, py::arg("max_iterations") = 1000,
      "The count lowest modes of K phi = omega^2 M phi restricted to the free DOFs (sparse shift-invert "
      "Lanczos, no dense matrix): a ModalResult with frequencies (rad/s) and the (3n, count) mode shapes. "
      "stiffness, mass: full 3n x 3n (vibration_matrices). shift: sigma (1/s^2), default a small negative "
      "one below every eigenvalue. ValidationError for count outside (0, free DOFs), NumericalError when "
      "the factorization fails or the iteration does not converge.");
}

void bindRegionModes(py::module_& module) {
  py::enum_<ModalVerdict>(module, "ModalVerdict", "What a RegionModeReport concludes")
      .value("async_keeps_modes", ModalVerdict::asyncKeepsModes)
      .value("no_visible_mode_in_fast", ModalVerdict::noVisibleModeInFast)
      .value("resolved_at_large_step", ModalVerdict::resolvedAtLargeStep)
      .value("unresolved_at_substep", ModalVerdict::unresolvedAtSubstep);
  py::class_<ModeInRegions>(module, "ModeInRegions", "One mode of a RegionModeReport")
      .def_readonly("omega", &ModeInRegions::omega, "rad/s")
      .def_readonly("hertz", &ModeInRegions::hertz, "omega / (2 pi)")
      .def_readonly("omega_large_step", &ModeInRegions::omegaLargeStep, "omega hL")
      .def_readonly("omega_substep", &ModeInRegions::omegaSubstep, "omega hS_i per region")
      .def_readonly("region_share", &ModeInRegions::regionShare,
                    "share of modal mass phi_Si^T M^SiSi phi_Si per region, in [0, 1]")
      .def_readonly("fast_share", &ModeInRegions::fastShare, "share of modal mass in all fast regions together")
      .def_readonly("visible", &ModeInRegions::visible, "omega below the frame Nyquist frequency pi * frame rate")
      .def_readonly("lives_in_fast_regions", &ModeInRegions::livesInFastRegions, "visible and fast share >= 0.95")
      .def_readonly("keepable", &ModeInRegions::keepable,
                    "lives in the fast regions, omega hL >= 0.5 and omega hS <= 0.1: async keeps it");
  py::class_<RegionModeReport>(module, "RegionModeReport",
                               "Per-mode S shares, omega h and the verdict for a set of fast regions (region_modes)")
      .def_readonly("large_timestep", &RegionModeReport::largeTimestep, "hL (s)")
      .def_readonly("frame_rate", &RegionModeReport::frameRate, "frames per second")
      .def_readonly("nyquist_omega", &RegionModeReport::nyquistOmega, "pi * frame rate (rad/s)")
      .def_readonly("region_names", &RegionModeReport::regionNames, "names of the regions, in order")
      .def_readonly("ratios", &RegionModeReport::ratios, "their ratios m")
      .def_readonly("modes", &RegionModeReport::modes, "list of ModeInRegions, ascending frequency")
      .def_readonly("visible_modes_truncated", &RegionModeReport::visibleModesTruncated,
                    "the highest mode computed is still visible: visible modes above it were not examined")
      .def_readonly("verdict", &RegionModeReport::verdict, "ModalVerdict")
      .def_readonly("kept_modes", &RegionModeReport::keptModes, "indices into modes of the keepable ones")
      .def("verdict_text", &RegionModeReport::verdictText, "the verdict as one line, as proposeRegions prints it")
      .def(
          "table",
          [](const RegionModeReport& report) {
            std::ostringstream out;
            printRegionModeReport(out, report);
            return out.str();
          },
          "the table proposeRegions --modes prints (mode, Hz, rad/s, omega hL, per region omega hS and share, "
          "S share, flags) and the verdict line")
      .def("as_dict", &reportDict, "the report as proposeRegions --json --modes K puts it under \"modes\"");
  module.def(
      "region_modes",
      [](const ModalResult& result, const Eigen::SparseMatrix<double>& mass, const std::vector<AsyncRegion>& regions,
         double largeTimestep, double frameRate) {
        return analyseRegionModes(result, mass, modalRegions(regions), largeTimestep, frameRate);
      },
      py::arg("modes"), py::arg("mass"), py::arg("regions"), py::arg("large_timestep"), py::arg("frame_rate") = 30.0,
      "The per-mode report of lowest_modes' result for these fast regions (AsyncRegion list): each mode's "
      "omega hL, omega hS and share of modal mass per region, and whether async can keep it "
      "(docs/asynchronous-integrator.md, \"Which modes can async keep?\"). mass: the full M the modes are "
      "M-orthonormal in.");
}

}  // namespace

void bindModal(py::module_& module) {
  bindModalResult(module);
  bindRegionModes(module);
  // A method of RegionProposal (bound with the asynchronous integrator).
  py::object proposalClass = module.attr("RegionProposal");
  proposalClass.attr("as_dict") =
      py::cpp_function(&proposalDict, py::name("as_dict"), py::is_method(proposalClass),
                       "The proposal as the document proposeRegions --json prints (largeTimestep, target, "
                       "largeRegionOmegaH, regions, withdrawnRegions, modalVerdict)");
  module.def(
      "propose_scene_regions",
      [](const std::filesystem::path& path, int modes, std::optional<double> largeTimestep,
         std::optional<double> frameRate) {
        std::optional<SceneProposal> sceneProposal;
        {
          py::gil_scoped_release release;
          sceneProposal = proposeSceneRegions(path, modes, largeTimestep.value_or(0.0), frameRate.value_or(0.0));
        }
        py::dict document = proposalDict(sceneProposal->proposal);
        if (sceneProposal->modes) document["modes"] = reportDict(*sceneProposal->modes);
        return document;
      },
      py::arg("path"), py::arg("modes") = 0, py::arg("large_timestep") = py::none(), py::arg("frame_rate") = py::none(),
      "What `proposeRegions SCENE --json [--modes K] [--dt H] [--frame-rate F]` prints, as a dict: the proposed "
      "and withdrawn fast regions with their ratios, the target, the modal verdict and, with modes > 0, the "
      "per-mode report (frequency, omega h, shares, flags, verdict) of the scene's own regions (or the "
      "proposal's). The scene's \"regions\": \"auto\" settings are used when it has them.");
}

}  // namespace asyncfem::python
