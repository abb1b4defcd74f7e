// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/asyncIntegrator/uncoupledMultirate.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/settings/jsonReader.hpp>
#include <string>

namespace asyncfem {

namespace {

std::vector<std::string> stringList(JsonObjectReader& reader, const std::string& key) {
  std::vector<std::string> out;
  const nlohmann::json* value = reader.find(key);
  if (!value) return out;
  if (!value->is_array()) reader.fail(key, "expected an array of names, got " + JsonObjectReader::describe(*value));
  for (std::size_t i = 0; i < value->size(); ++i) {
    out.push_back(JsonObjectReader::toString((*value)[i], reader.elementPath(key, i), reader.sourceName()));
  }
  return out;
}

AsyncRegion parseRegion(const std::string& sourceName, const TetMesh& mesh, const nlohmann::json& value,
                        const std::string& path) {
  JsonObjectReader reader(value, path, sourceName);
  AsyncRegion region;
  region.name = reader.string("name", "");
  region.ratio = reader.integer("ratio", 1, 1, 100000);
  RegionSelector selector;
  selector.vertexSets = stringList(reader, "vertexSets");
  selector.elementSets = stringList(reader, "elementSets");
  if (const nlohmann::json* boxes = reader.find("boxes")) {
    if (!boxes->is_array()) reader.fail("boxes", "expected an array of {\"min\": [x, y, z], \"max\": [x, y, z]}");
    for (std::size_t i = 0; i < boxes->size(); ++i) {
      JsonObjectReader box((*boxes)[i], reader.elementPath("boxes", i), sourceName);
      const Eigen::Vector3d lo = JsonObjectReader::toVector3(box.required("min"), box.keyPath("min"), sourceName);
      const Eigen::Vector3d hi = JsonObjectReader::toVector3(box.required("max"), box.keyPath("max"), sourceName);
      if (!((lo.array() <= hi.array()).all())) JsonObjectReader::failAt(sourceName, box.path(), "expected min <= max");
      box.finish();
      selector.boxMin.push_back(lo);
      selector.boxMax.push_back(hi);
    }
  }
  if (const nlohmann::json* vertices = reader.find("vertices")) {
    if (!vertices->is_array()) reader.fail("vertices", "expected an array of 0-based vertex ids");
    for (std::size_t i = 0; i < vertices->size(); ++i) {
      selector.vertices.push_back(JsonObjectReader::toInteger((*vertices)[i], reader.elementPath("vertices", i),
                                                              sourceName, 0, mesh.numVertices() - 1));
    }
  }
  reader.finish();
  try {
    region.vertices = regionVertices(mesh, selector);
  } catch (const SelectionError& e) {
    JsonObjectReader::failAt(sourceName, path + "." + e.keySuffix(), e.what());
  } catch (const ValidationError& e) {
    JsonObjectReader::failAt(sourceName, path, e.what());
  }
  if (region.vertices.empty()) {
    JsonObjectReader::failAt(sourceName, path, "selects no vertex (give vertexSets, elementSets, boxes or vertices)");
  }
  return region;
}

}  // namespace

AutoRegionOptions parseAutoRegionOptions(const IntegratorContext& context, const nlohmann::json& options) {
  AutoRegionOptions automatic;
  automatic.largeTimestep = context.timestep;
  // Nonlinear forces refactor every step on both sides: the cost check counts that.
  automatic.nonlinear = context.system.forceModel && !context.system.forceModel->isLinear();
  automatic.modalCheck = true;
  if (context.frameRate > 0.0) automatic.frameRate = context.frameRate;
  if (!options.is_object() || !options.contains("auto")) return automatic;
  const std::string path = context.optionsPath + ".auto";
  JsonObjectReader reader(options.at("auto"), path, context.sourceName);
  if (reader.has("target")) {  // absent: the relative mode
    automatic.targetOmegaH = reader.number("target", automatic.targetOmegaH);
    if (!(automatic.targetOmegaH > 0.0)) reader.fail("target", "must be > 0");
  }
  automatic.growLayers = reader.integer("growLayers", automatic.growLayers, 0, 100);
  automatic.maxRatio = reader.integer("maxRatio", automatic.maxRatio, 1, 100000);
  automatic.modalCheck = reader.boolean("modalCheck", automatic.modalCheck);
  automatic.maxRegions = reader.integer("maxRegions", automatic.maxRegions, 1, 1000);
  automatic.costCheck = reader.boolean("costCheck", automatic.costCheck);
  automatic.costMargin = reader.number("costMargin", automatic.costMargin);
  if (!(automatic.costMargin > 0.0)) reader.fail("costMargin", "must be > 0");
  reader.finish();
  return automatic;
}

const std::vector<std::string>& asyncOptionKeys() {
  static const std::vector<std::string> keys{"coupling",       "schur",       "method",  "recovery", "regionSolver",
                                             "substepContact", "laggedSchur", "threads", "regions",  "auto"};
  return keys;
}

AsyncSettings parseAsyncSettings(const IntegratorContext& context, const nlohmann::json& options) {
  const std::string& sourceName = context.sourceName;
  if (!context.mesh) throw ValidationError(sourceName + ": " + context.optionsPath + ": async needs the mesh");
  const TetMesh& mesh = *context.mesh;
  JsonObjectReader reader(options, context.optionsPath, sourceName);
  AsyncSettings out;
  const std::string coupling = reader.choice("coupling", "stable", {"stable", "paper"});
  out.solver.coupling = coupling == "paper" ? AsyncCoupling::paper : AsyncCoupling::stable;
  const std::string schur = reader.choice("schur", "low-rank", {"low-rank", "lu", "symmetric"});
  out.solver.schur = schur == "lu" ? SchurMode::lu : schur == "symmetric" ? SchurMode::symmetric : SchurMode::lowRank;
  const std::string method = reader.choice("method", "structured", {"structured", "naive"});
  out.solver.method = method == "naive" ? AsyncSolveMethod::naive : AsyncSolveMethod::structured;
  const std::string recovery = reader.choice("recovery", "automatic", {"automatic", "substitution", "dense-z"});
  out.solver.recovery = recovery == "substitution" ? RecoveryMode::substitution
                        : recovery == "dense-z"    ? RecoveryMode::denseZ
                                                   : RecoveryMode::automatic;
  const std::string regionSolver =
      reader.choice("regionSolver", "cholmod", {"cholmod", "umfpack", "eigen-ldlt", "eigen-lu"});
  out.solver.regionSolver = parseSolverKind(regionSolver);
  out.solver.substepStatePrediction = reader.boolean("substepContact", false);
  out.solver.laggedSchur = reader.boolean("laggedSchur", out.solver.laggedSchur);
  out.solver.threads = reader.integer("threads", out.solver.threads, 0, 1024);
  if (out.solver.substepStatePrediction && !context.hasContact) {
    reader.fail("substepContact", "only meaningful with a \"contact\" section");
  }

  static const nlohmann::json automaticRegions = "auto";
  const nlohmann::json* given = reader.find("regions");
  const nlohmann::json& regions = given ? *given : automaticRegions;  // default: automatic regions
  const std::string regionsPath = reader.keyPath("regions");
  if (regions.is_string()) {
    if (regions.get<std::string>() != "auto") {
      JsonObjectReader::failAt(sourceName, regionsPath, "expected \"auto\" or an array of regions");
    }
    out.automaticRegions = true;
    out.automatic = parseAutoRegionOptions(context, options);
    (void)reader.find("auto");  // read by parseAutoRegionOptions
  } else if (regions.is_array()) {
    if (reader.find("auto")) reader.fail("auto", "only with \"regions\": \"auto\"");
    for (std::size_t i = 0; i < regions.size(); ++i) {
      out.regions.push_back(parseRegion(sourceName, mesh, regions[i], reader.elementPath("regions", i)));
    }
  } else {
    JsonObjectReader::failAt(sourceName, regionsPath,
                             "expected \"auto\" or an array of regions, got " + JsonObjectReader::describe(regions));
  }
  reader.finish();
  const FreeDofs& freeDofs = context.system.freeDofs;
  if (out.automaticRegions) {
    if (out.automatic.modalCheck) {
      // The modal check needs the linear K (= the corotational rest tangent) and M.
      const VibrationMatrices matrices = vibrationMatrices(mesh, context.massType);
      out.proposal = suggestRegions(mesh, freeDofs, out.automatic, matrices.stiffness, matrices.mass);
    } else {
      out.proposal = suggestRegions(mesh, freeDofs, out.automatic);
    }
    out.regions = out.proposal->asyncRegions();
  }
  // Validate the partition here so its errors name the key.
  try {
    RegionPartition check(mesh, freeDofs, out.regions);
  } catch (const ValidationError& e) {
    JsonObjectReader::failAt(sourceName, regionsPath, e.what());
  }
  return out;
}

void registerMultirateIntegrators(IntegratorRegistry& registry) {
  registry.add(
      "async",
      [](IntegratorContext context, const nlohmann::json& options) -> std::unique_ptr<Integrator> {
        const AsyncSettings parsed = parseAsyncSettings(context, options);
        return std::make_unique<AsyncBackwardEuler>(*context.mesh, std::move(context.system), context.timestep,
                                                    parsed.regions, parsed.solver);
      },
      asyncOptionKeys());
  registry.add("multirate-uncoupled",
               [](IntegratorContext context, const nlohmann::json& options) -> std::unique_ptr<Integrator> {
                 const std::string& path = context.optionsPath;
                 if (!options.is_object()) {
                   JsonObjectReader::failAt(context.sourceName, path,
                                            "expected an object, got " + JsonObjectReader::describe(options));
                 }
                 // Keys of the async integrator that have no meaning here: reject them by name
                 // rather than silently ignoring a setting the user expects to matter.
                 for (const char* key : {"coupling", "schur", "method", "recovery", "substepContact"}) {
                   if (options.contains(key)) {
                     JsonObjectReader::failAt(context.sourceName, path + "." + key,
                                              "used by \"async\" only, not by \"multirate-uncoupled\"");
                   }
                 }
                 UncoupledMultirateOptions solverOptions;
                 nlohmann::json regionOptions = options;  // what parseAsyncSettings reads
                 if (const auto it = options.find("compoundSolver"); it != options.end()) {
                   const std::string name =
                       JsonObjectReader::toString(*it, path + ".compoundSolver", context.sourceName);
                   if (name != "umfpack" && name != "eigen-lu") {
                     JsonObjectReader::failAt(context.sourceName, path + ".compoundSolver",
                                              "unknown value \"" + name +
                                                  "\" (expected one of umfpack, eigen-lu: the system is unsymmetric)");
                   }
                   solverOptions.compoundSolver = parseSolverKind(name);
                   regionOptions.erase("compoundSolver");
                 }
                 const AsyncSettings parsed = parseAsyncSettings(context, regionOptions);
                 solverOptions.regionSolver = parsed.solver.regionSolver;
                 return std::make_unique<UncoupledMultirate>(*context.mesh, std::move(context.system), context.timestep,
                                                             parsed.regions, solverOptions);
               },
               {"compoundSolver", "regionSolver", "regions", "auto"});
}

}  // namespace asyncfem
