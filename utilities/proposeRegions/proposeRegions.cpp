// SPDX-License-Identifier: BSD-3-Clause
// proposeRegions: proposes fast regions and ratios for the asynchronous integrator from the
// materials and element sizes of a mesh, checks them against the lowest modes, and with
// --modes K prints the modal table of the given or proposed regions (see
// docs/asynchronous-integrator.md, "Which modes can async keep?").
#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/vertexSelection.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "commandLine.hpp"

namespace {

using namespace asyncfem;

struct CommandLine {
  std::string input, writePath;
  double largeTimestep = 0.0;
  RegionProposalOptions options;
  std::vector<std::string> fixedSets;
  std::vector<std::vector<double>> fixedBoxes;  // min x y z, max x y z each
  std::string fixedBou;
  bool json = false;
  int modeCount = 0;
  double frameRate = 0.0;
  bool noModalCheck = false;
  std::string massName = "consistent";
  int adaptiveSteps = 120;
  // Which of the proposed-region options were given (they replace a scene's own).
  bool givenTarget = false, givenRelative = false, givenGrow = false, givenMaxRatio = false;
  bool anyGiven() const { return givenTarget || givenRelative || givenGrow || givenMaxRatio; }
};

// What the input gives: the mesh and constraints, and from a scene its regions or its
// proposed-region settings.
struct Input {
  std::shared_ptr<const TetMesh> mesh;
  FreeDofs freeDofs;
  MassType massType = MassType::consistent;
  std::vector<AsyncRegion> givenRegions;  // a scene's explicit regions
  bool corotational = false;
  std::optional<RegionProposalOptions> sceneAuto;  // an async scene with "regions": "auto"
  std::optional<Scene> runTimeScene;               // an async scene with "regions": {"adaptive": ...}
};

void addOptions(CLI::App& app, CommandLine& cl) {
  app.add_option("input", cl.input, "scene .json or mesh (.veg, .node/.ele, .msh)")->required();
  app.add_option("--dt", cl.largeTimestep, "large timestep hL (default: the scene's integrator.timestep)")
      ->check(cli::positive());
  app.add_option("--target", cl.options.targetOmegaH,
                 "absolute target for omega * h in every region (default: relative mode)")
      ->check(cli::positive());
  app.add_option("--relative", cl.options.relativeThreshold,
                 "relative mode: elements above this multiple of the median element frequency become fast")
      ->check(cli::inRange(1.0001, 1e9))
      ->capture_default_str();
  app.add_option("--grow", cl.options.growLayers, "vertex rings added around each region")
      ->check(cli::inRange(0, 100))
      ->capture_default_str();
  app.add_option("--max-ratio", cl.options.maxRatio, "largest ratio m proposed")
      ->check(cli::inRange(1, 100000))
      ->capture_default_str();
  app.add_option("--fixed-set", cl.fixedSets, "vertex set to treat as fixed (mesh input only)");
  app.add_option("--fixed-box", cl.fixedBoxes,
                 "box MINX MINY MINZ MAXX MAXY MAXZ whose vertices are fixed (mesh input only; repeatable)")
      ->expected(6)
      ->allow_extra_args(false);
  app.add_option("--fixed-bou", cl.fixedBou, "Vega .bou file of fixed vertices, 1-based (mesh input only)");
  app.add_option("--write", cl.writePath, "write the regions as JSON, ready for integrator.options.regions");
  app.add_flag("--json", cl.json, "print the proposal as JSON instead of a table");
  app.add_option("--modes", cl.modeCount,
                 "print the K lowest modes with omega*hL, omega*hS and S share for the scene's regions "
                 "(or the proposal), and whether async can keep any of them")
      ->check(cli::inRange(1, 100000));
  app.add_option("--frame-rate", cl.frameRate,
                 "frames per second for the visibility test (default: the scene's, or 30)")
      ->check(cli::positive());
  app.add_flag("--no-modal-check", cl.noModalCheck,
               "keep the proposal even when no visible mode lives in it (the check is on by default, as for "
               "\"regions\": \"auto\" in scenes)");
  app.add_option("--adaptive-steps", cl.adaptiveSteps,
                 "a scene with run-time regions: large steps to run to see which partitions its policies choose")
      ->check(CLI::Range(1, 100000));
  app.add_option("--mass", cl.massName, "mass matrix for a mesh input (scenes use their own)")
      ->check(CLI::IsMember({"consistent", "lumped"}))
      ->capture_default_str();
}

// A scene: its mesh and constraints (the problem, nothing assembled), timestep, frame rate
// and mass, and its regions as the simulator reads them.
Input readScene(CommandLine& cl) {
  if (!cl.fixedSets.empty() || !cl.fixedBoxes.empty() || !cl.fixedBou.empty()) {
    throw ValidationError(
        "--fixed-set, --fixed-box and --fixed-bou apply to mesh inputs only: a scene fixes its vertices with its "
        "\"fixed\" key (docs/scene-format.md)");
  }
  Scene scene = loadScene(cl.input);
  if (!cl.writePath.empty()) {
    std::vector<cli::NamedPath> inputs{{"the scene", cl.input}};
    if (scene.mesh.source == Scene::MeshSource::file) inputs.push_back({"the mesh", scene.mesh.file});
    cli::refuseOutputOverInputs({"--write", cl.writePath}, inputs, "write the regions to another file");
  }
  // The scene's timing, at the large step asked for (no need to divide its frames).
  FrameTiming timing = requireFrameTiming(scene);
  if (cl.largeTimestep > 0.0) timing.timestep = cl.largeTimestep;
  cl.largeTimestep = timing.timestep;
  if (cl.frameRate <= 0.0) cl.frameRate = timing.frameRate;
  Input in;
  in.massType = scene.mass;
  in.corotational = scene.forceModel != Scene::ForceModelKind::linear;
  const Scene::IntegratorSettings& integrator = scene.integrator;
  const std::shared_ptr<const Problem> problem = buildProblem(scene);
  in.mesh = problem->sharedMesh();
  in.freeDofs = problem->freeDofs();
  const nlohmann::json* regions = integrator.options.is_object() && integrator.options.contains("regions")
                                      ? &integrator.options["regions"]
                                      : nullptr;
  if (integrator.name == "async" && regions && regions->is_object() && regions->contains("adaptive")) {
    in.runTimeScene = scene;
  } else if (integrator.name == "async" && regions && regions->is_array()) {
    in.givenRegions = parseAsyncOptions(scene, *in.mesh, in.freeDofs, integrator.options).regions;
  } else if (integrator.name == "async") {
    // What the simulator would run: the scene's own auto settings (command-line
    // options given explicitly replace them).
    in.sceneAuto = parseRegionProposalOptions(integratorContext(scene, timing), integrator.options);
  }
  return in;
}

// The vertices --fixed-set, --fixed-box and --fixed-bou name, with errors naming the option.
std::vector<int> fixedVertices(const CommandLine& cl, const TetMesh& mesh) {
  VertexSelection selection;
  selection.sets = cl.fixedSets;
  for (const std::vector<double>& b : cl.fixedBoxes) {
    selection.boxes.push_back({Eigen::Vector3d(b[0], b[1], b[2]), Eigen::Vector3d(b[3], b[4], b[5])});
  }
  if (!cl.fixedBou.empty()) selection.bouFile = cl.fixedBou;
  if (selection.empty()) return {};
  try {
    return selectVertices(mesh, selection);
  } catch (const SelectionError& error) {
    const std::string option = error.part() == "sets"    ? "--fixed-set"
                               : error.part() == "boxes" ? "--fixed-box"
                                                         : "--fixed-bou";
    const std::string which = error.index() >= 0 ? " #" + std::to_string(error.index() + 1) : "";
    throw ValidationError(option + which + ": " + error.what());
  }
}

// A mesh file, with the --fixed-set, --fixed-box and --fixed-bou vertices fixed and --mass.
Input readMesh(const CommandLine& cl) {
  if (!cl.writePath.empty()) {
    cli::refuseOutputOverInputs({"--write", cl.writePath}, {{"the mesh", cl.input}},
                                "write the regions to another file");
  }
  if (cl.largeTimestep <= 0.0) throw Error("give the large timestep with --dt for a mesh input");
  MeshReadReport report;
  auto loaded = std::make_shared<TetMesh>(readMesh(cl.input, {}, &report));
  for (const std::string& w : report.warnings) std::cerr << "proposeRegions: warning: " << w << "\n";
  Input in;
  in.massType = cl.massName == "lumped" ? MassType::lumped : MassType::consistent;
  in.freeDofs = FreeDofs::fromFixedVertices(loaded->numVertices(), fixedVertices(cl, *loaded));
  in.mesh = loaded;
  return in;
}

// The proposal's settings: a scene's "auto" settings with the options given here
// replacing theirs, else the command line's.
RegionProposalOptions proposalOptions(const CommandLine& cl, const Input& in) {
  RegionProposalOptions options = cl.options;
  if (in.sceneAuto) {
    options = *in.sceneAuto;
    if (cl.givenTarget) options.targetOmegaH = cl.options.targetOmegaH;
    if (cl.givenRelative) options.relativeThreshold = cl.options.relativeThreshold;
    if (cl.givenGrow) options.growLayers = cl.options.growLayers;
    if (cl.givenMaxRatio) options.maxRatio = cl.options.maxRatio;
    if (cl.noModalCheck) options.modalCheck = false;
  } else {
    options.modalCheck = !cl.noModalCheck;
  }
  options.largeTimestep = cl.largeTimestep;
  options.frameRate = cl.frameRate;
  return options;
}

std::vector<AsyncRegion> withdrawnRegions(const RegionProposal& proposal) {
  std::vector<AsyncRegion> regions;
  for (const ProposedRegion& r : proposal.withdrawnRegions) regions.push_back(r.region);
  return regions;
}

/// The per-mode rows of a report (--modes with --json).
nlohmann::json modesJson(const RegionModeReport& report) {
  nlohmann::json modes = nlohmann::json::array();
  for (const ModeInRegions& mode : report.modes) {
    modes.push_back({{"omega", mode.omega},
                     {"hertz", mode.hertz},
                     {"omegaLargeStep", mode.omegaLargeStep},
                     {"omegaSubstep", mode.omegaSubstep},
                     {"regionShare", mode.regionShare},
                     {"fastShare", mode.fastShare},
                     {"visible", mode.visible},
                     {"livesInFastRegions", mode.livesInFastRegions},
                     {"keepable", mode.keepable}});
  }
  return {
      {"regions", report.regionNames}, {"ratios", report.ratios}, {"modes", modes}, {"verdict", report.verdictText()}};
}

void printJson(const RegionProposal& proposal, double largeTimestep, const std::optional<RegionModeReport>& modes) {
  nlohmann::json out{{"largeTimestep", largeTimestep},
                     {"target", proposal.targetOmegaH},
                     {"largeRegionOmegaH", proposal.largeRegionMaxFrequency * largeTimestep},
                     {"regions", asyncRegionsJson(proposal.asyncRegions())},
                     {"withdrawnRegions", asyncRegionsJson(withdrawnRegions(proposal))},
                     {"modalVerdict", proposal.modalReport ? proposal.modalReport->verdictText() : ""}};
  if (modes) out["modes"] = modesJson(*modes);
  std::cout << out.dump(2) << "\n";
}

void printTable(const RegionProposal& proposal, const TetMesh& mesh, const RegionProposalOptions& options) {
  const double largeTimestep = options.largeTimestep;
  std::printf("mesh: %d vertices, %d %s; hL = %g; target omega*h = %.3g%s\n", mesh.numVertices(), mesh.numElements(),
              mesh.isHexahedral() ? "hexahedra" : "tets", largeTimestep, proposal.targetOmegaH,
              options.targetOmegaH > 0 ? "" : " (relative mode)");
  std::printf("L: max omega*hL = %.3g over the elements left in L\n", proposal.largeRegionMaxFrequency * largeTimestep);
  if (proposal.regions.empty() && proposal.withdrawnRegions.empty() && proposal.precheckWithdrawnRegions.empty()) {
    std::printf("no fast region needed: every element meets the target at hL\n");
  }
  std::printf("%-8s %8s %10s %10s %12s %14s %12s\n", "region", "ratio", "vertices", "tets", "interface", "max omega",
              "omega*hS");
  for (const std::vector<ProposedRegion>* list :
       {&proposal.regions, &proposal.withdrawnRegions, &proposal.precheckWithdrawnRegions}) {
    for (const ProposedRegion& r : *list) {
      std::printf("%-8s %8d %10zu %10d %12d %14.3g %12.3g%s\n", r.region.name.c_str(), r.region.ratio,
                  r.region.vertices.size(), r.numElements, r.numInterfaceDofs, r.maxFrequency,
                  r.maxFrequency * largeTimestep / r.region.ratio,
                  list == &proposal.withdrawnRegions           ? "  (withdrawn by the modal check)"
                  : list == &proposal.precheckWithdrawnRegions ? "  (withdrawn by the pre-check)"
                                                               : "");
    }
  }
  std::printf("decided in %.3g ms by the %s (element frequencies %.3g ms%s)\n", 1e3 * proposal.decisionSeconds,
              toString(proposal.decidedBy), 1e3 * proposal.frequencySeconds,
              proposal.modalReport ? ", modal check included" : "");
  if (!proposal.precheckWithdrawnRegions.empty()) std::printf("%s\n", regionProposalSummary(proposal).c_str());
  // The cost check ran first; when the modal check then withdrew the regions, say so on the
  // same line, so that "kept" is never read as the final answer.
  if (proposal.cost.evaluated) {
    std::printf("cost check: %s%s\n", proposal.cost.decision.c_str(),
                proposal.withdrawnRegions.empty() ? "" : " (then withdrawn by the modal check below)");
  }
  if (proposal.modalReport) {
    std::printf("modal check (%zu lowest modes, %.3g s: %d factorization, %d solves): %s\n",
                proposal.modalReport->modes.size(), proposal.modalSeconds, proposal.modalFactorizations,
                proposal.modalSolves, proposal.modalReport->verdictText().c_str());
    for (const ProposedRegion& r : proposal.regions) {
      std::printf("ratio of %s: %s\n", r.region.name.c_str(), ratioReason(proposal, r).c_str());
    }
    if (!proposal.withdrawnRegions.empty()) {
      std::printf(
          "no fast region proposed: the asynchronous integrator runs single-rate at hL "
          "(--no-modal-check keeps the regions)\n");
    }
  }
}

// The modal report of the scene's given regions, else of the proposal (withdrawn or not),
// printed as a table unless --json (the caller then puts it in the JSON document).
RegionModeReport printModes(const CommandLine& cl, const Input& in, const RegionProposal& proposal,
                            const VibrationMatrices& matrices) {
  const bool given = !in.givenRegions.empty();
  const std::vector<AsyncRegion> regions =
      given ? in.givenRegions : (proposal.regions.empty() ? withdrawnRegions(proposal) : proposal.asyncRegions());
  ModalOptions modal;
  modal.count = std::min(cl.modeCount, in.freeDofs.numFree() - 1);
  const ModalResult modes = lowestModes(matrices.stiffness, matrices.mass, in.freeDofs, modal);
  RegionModeReport report =
      analyseRegionModes(modes, matrices.mass, modalRegions(regions), cl.largeTimestep, cl.frameRate);
  if (cl.json) return report;  // printed in the JSON document, nothing on the console
  std::ostream& out = std::cout;
  out << "\nmodes of " << (given ? "the scene's regions" : "the proposed regions") << ": " << modal.count
      << " lowest of K phi = omega^2 M phi (" << in.freeDofs.numFree() << " free DOFs, linear K, "
      << (in.massType == MassType::lumped ? "lumped" : "consistent") << " M"
      << (in.corotational ? "; nonlinear scene: K is its rest tangent" : "") << ")\n";
  char line[160];
  std::snprintf(line, sizeof line, "eigensolve: %.3g s (factorization %.3g s, %d solves, %d restarts, shift %.3g)\n",
                modes.solveSeconds, modes.factorSeconds, modes.operatorApplications, modes.iterations, modes.shift);
  out << line;
  printRegionModeReport(out, report);
  return report;
}

// The proposed regions to writePath, through a temporary file so a failed write leaves
// no partial file behind.
void writeRegions(const std::string& writePath, const RegionProposal& proposal) {
  const std::filesystem::path target(writePath);
  const std::filesystem::path temporary = target.string() + ".tmp";
  {
    std::ofstream out(temporary);
    out << asyncRegionsJson(proposal.asyncRegions()).dump(1) << "\n";
    if (!out) throw Error("cannot write " + temporary.string());
  }
  std::filesystem::rename(temporary, target);
}

// A scene whose regions are chosen at run time: run its first steps and explain each
// partition its policies chose, priced by the cost model against single-rate at hL.
void explainRunTimeRegions(const CommandLine& cl, const Input& in) {
  const Scene& scene = *in.runTimeScene;
  std::printf("settings: the scene chooses its regions at run time (integrator.options.regions.adaptive: %s)\n",
              scene.integrator.options["regions"]["adaptive"].dump().c_str());
  Simulation simulation = buildSimulation(scene);
  auto* async = dynamic_cast<AsyncBackwardEuler*>(simulation.integrator.get());
  if (async == nullptr) throw Error("the scene's integrator is not the asynchronous one");
  struct Span {
    long long from = 0, to = 0;
    std::vector<AsyncRegion> regions;
  };
  std::vector<Span> spans;
  for (int k = 0; k < cl.adaptiveSteps; ++k) {
    async->step();
    std::vector<AsyncRegion> regions;
    for (int i = 0; i < async->partition().numRegions(); ++i) regions.push_back(async->partition().region(i));
    if (spans.empty() || spans.back().regions.size() != regions.size() ||
        !std::equal(regions.begin(), regions.end(), spans.back().regions.begin(),
                    [](const AsyncRegion& a, const AsyncRegion& b) {
                      return a.ratio == b.ratio && a.vertices == b.vertices;
                    })) {
      spans.push_back({k, k, regions});
    }
    spans.back().to = k + 1;
  }
  std::printf("ran %d large steps of hL = %g s: %zu partitions (%zu re-partitions, %zu from the set-up cache)\n",
              cl.adaptiveSteps, async->timestep(), spans.size(), async->repartitions().size(),
              static_cast<std::size_t>(std::count_if(async->repartitions().begin(), async->repartitions().end(),
                                                     [](const RepartitionRecord& r) { return r.reused; })));
  std::printf("%-14s %-10s %-9s %-8s %-28s\n", "steps", "vertices", "ratio", "|I|", "async / single-rate hL (model)");
  double weighted = 0.0;
  for (const Span& span : spans) {
    int fast = 0, ratio = 1;
    for (const AsyncRegion& r : span.regions) {
      fast += static_cast<int>(r.vertices.size());
      ratio = std::max(ratio, r.ratio);
    }
    double relative = 1.0;
    int interface = 0;
    if (!span.regions.empty()) {
      const RegionProposalCost cost = estimateAsyncCost(*in.mesh, in.freeDofs, span.regions, in.corotational);
      relative = cost.asyncFlops / (cost.singleRateFlops / cost.singleRateSubsteps);
      interface = cost.interfaceDofs;
    }
    weighted += relative * static_cast<double>(span.to - span.from);
    const std::string steps = std::to_string(span.from) + "-" + std::to_string(span.to);
    std::printf("%-14s %-10d %-9d %-8d %.2f\n", steps.c_str(), fast, ratio, interface, relative);
  }
  std::printf(
      "expected cost per large step (cost model, steady steps weighted by how long each partition ran): %.2fx "
      "single-rate at hL; set-up %.3f s for %zu fresh partitions (run it: offlineSimulator prints each)\n",
      weighted / cl.adaptiveSteps, async->runStats().setupSeconds,
      async->repartitions().size() -
          static_cast<std::size_t>(std::count_if(async->repartitions().begin(), async->repartitions().end(),
                                                 [](const RepartitionRecord& r) { return r.reused; })));
}

int run(CommandLine& cl) {
  const Input in = std::filesystem::path(cl.input).extension() == ".json" ? readScene(cl) : readMesh(cl);
  if (in.runTimeScene && !cl.json) {
    explainRunTimeRegions(cl, in);
    std::printf("\nfor comparison, fixed regions from element frequencies (what \"regions\": \"auto\" would run):\n");
  }
  if (cl.frameRate <= 0.0) cl.frameRate = 30.0;
  const RegionProposalOptions options = proposalOptions(cl, in);
  if (in.sceneAuto && !cl.json) {
    std::printf("settings: the scene's \"regions\": \"auto\" (integrator.options.auto%s), as the simulator runs it\n",
                cl.anyGiven() ? ", with the options given here" : "");
  }
  const VibrationMatrices matrices = vibrationMatrices(*in.mesh, in.massType);
  const RegionProposal proposal = proposeRegions(*in.mesh, in.freeDofs, options, matrices.stiffness, matrices.mass);
  if (!cl.json) printTable(proposal, *in.mesh, options);
  std::optional<RegionModeReport> modes;
  if (cl.modeCount > 0) modes = printModes(cl, in, proposal, matrices);
  if (cl.json) printJson(proposal, cl.largeTimestep, modes);
  if (!cl.writePath.empty()) {
    writeRegions(cl.writePath, proposal);
    if (!cl.json) std::printf("regions written to %s\n", cl.writePath.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  CLI::App app{
      "Proposes fast regions and ratios for the asynchronous integrator.\n"
      "Input: a scene (.json: its mesh, fixed vertices and integrator.timestep) or a mesh file."};
  CommandLine cl;
  addOptions(app, cl);
  if (const std::optional<int> status = cli::parse(app, argc, argv, "proposeRegions")) return *status;
  cl.givenTarget = app.count("--target") > 0;
  cl.givenRelative = app.count("--relative") > 0;
  cl.givenGrow = app.count("--grow") > 0;
  cl.givenMaxRatio = app.count("--max-ratio") > 0;
  return cli::run("proposeRegions", [&] { return run(cl); });
}
