// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/sceneIO/jsonReader.hpp>
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

AsyncRegion parseRegion(const Scene& scene, const TetMesh& mesh, const nlohmann::json& value, const std::string& path) {
  JsonObjectReader reader(value, path, scene.sourceName);
  AsyncRegion region;
  region.name = reader.string("name", "");
  region.ratio = reader.integer("ratio", 1, 1, 100000);
  RegionSelector selector;
  selector.vertexSets = stringList(reader, "vertexSets");
  selector.elementSets = stringList(reader, "elementSets");
  if (const nlohmann::json* boxes = reader.find("boxes")) {
    if (!boxes->is_array()) reader.fail("boxes", "expected an array of {\"min\": [x, y, z], \"max\": [x, y, z]}");
    for (std::size_t i = 0; i < boxes->size(); ++i) {
      JsonObjectReader box((*boxes)[i], reader.elementPath("boxes", i), scene.sourceName);
      const Eigen::Vector3d lo = JsonObjectReader::toVector3(box.required("min"), box.keyPath("min"), scene.sourceName);
      const Eigen::Vector3d hi = JsonObjectReader::toVector3(box.required("max"), box.keyPath("max"), scene.sourceName);
      if (!((lo.array() <= hi.array()).all()))
        JsonObjectReader::failAt(scene.sourceName, box.path(), "expected min <= max");
      box.finish();
      selector.boxMin.push_back(lo);
      selector.boxMax.push_back(hi);
    }
  }
  if (const nlohmann::json* vertices = reader.find("vertices")) {
    if (!vertices->is_array()) reader.fail("vertices", "expected an array of 0-based vertex ids");
    for (std::size_t i = 0; i < vertices->size(); ++i) {
      selector.vertices.push_back(JsonObjectReader::toInteger((*vertices)[i], reader.elementPath("vertices", i),
                                                              scene.sourceName, 0, mesh.numVertices() - 1));
    }
  }
  reader.finish();
  try {
    region.vertices = regionVertices(mesh, selector);
  } catch (const ValidationError& e) {
    JsonObjectReader::failAt(scene.sourceName, path, e.what());
  }
  if (region.vertices.empty()) {
    JsonObjectReader::failAt(scene.sourceName, path,
                             "selects no vertex (give vertexSets, elementSets, boxes or vertices)");
  }
  return region;
}

}  // namespace

AsyncSceneOptions parseAsyncOptions(const Scene& scene, const TetMesh& mesh, const FreeDofs& freeDofs,
                                    const nlohmann::json& options) {
  JsonObjectReader reader(options, "integrator.options", scene.sourceName);
  AsyncSceneOptions out;
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
  if (out.solver.substepStatePrediction && !scene.contact.enabled()) {
    reader.fail("substepContact", "only meaningful with a \"contact\" section");
  }

  static const nlohmann::json automaticRegions = "auto";
  const nlohmann::json* given = reader.find("regions");
  const nlohmann::json& regions = given ? *given : automaticRegions;  // default: automatic regions
  const std::string regionsPath = reader.keyPath("regions");
  if (regions.is_string()) {
    if (regions.get<std::string>() != "auto") {
      JsonObjectReader::failAt(scene.sourceName, regionsPath, "expected \"auto\" or an array of regions");
    }
    out.automaticRegions = true;
    out.automatic.largeTimestep = scene.integrator.timestep;
    out.automatic.modalCheck = true;
    out.automatic.frameRate = scene.frames.rate;
    if (const nlohmann::json* automatic = reader.find("auto")) {
      JsonObjectReader autoReader(*automatic, reader.keyPath("auto"), scene.sourceName);
      if (autoReader.has("target")) {  // absent: the relative mode
        out.automatic.targetOmegaH = autoReader.number("target", out.automatic.targetOmegaH);
        if (!(out.automatic.targetOmegaH > 0.0)) autoReader.fail("target", "must be > 0");
      }
      out.automatic.growLayers = autoReader.integer("growLayers", out.automatic.growLayers, 0, 100);
      out.automatic.maxRatio = autoReader.integer("maxRatio", out.automatic.maxRatio, 1, 100000);
      out.automatic.modalCheck = autoReader.boolean("modalCheck", out.automatic.modalCheck);
      autoReader.finish();
    }
  } else if (regions.is_array()) {
    if (reader.find("auto")) reader.fail("auto", "only with \"regions\": \"auto\"");
    for (std::size_t i = 0; i < regions.size(); ++i) {
      out.regions.push_back(parseRegion(scene, mesh, regions[i], reader.elementPath("regions", i)));
    }
  } else {
    JsonObjectReader::failAt(scene.sourceName, regionsPath,
                             "expected \"auto\" or an array of regions, got " + JsonObjectReader::describe(regions));
  }
  reader.finish();
  if (out.automaticRegions) {
    // The modal check needs the scene's K (linear, = the corotational rest tangent) and M.
    const VibrationMatrices matrices = vibrationMatrices(mesh, scene.mass);
    out.regions = suggestRegions(mesh, freeDofs, out.automatic, matrices.stiffness, matrices.mass).asyncRegions();
  }
  // Validate the partition here so its errors name the scene key.
  try {
    RegionPartition check(mesh, freeDofs, out.regions);
  } catch (const ValidationError& e) {
    JsonObjectReader::failAt(scene.sourceName, regionsPath, e.what());
  }
  return out;
}

IntegratorFactory asyncIntegratorFactory() {
  return [](const Scene& scene, const TetMesh& mesh, DynamicSystem system,
            const nlohmann::json& options) -> std::unique_ptr<Integrator> {
    const AsyncSceneOptions parsed = parseAsyncOptions(scene, mesh, system.freeDofs, options);
    return std::make_unique<AsyncBackwardEuler>(mesh, std::move(system), scene.integrator.timestep, parsed.regions,
                                                parsed.solver);
  };
}

}  // namespace asyncfem
