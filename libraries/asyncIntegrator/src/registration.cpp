// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/asyncIntegrator/schroeder2011.hpp>
#include <asyncfem/asyncIntegrator/uncoupledMultirate.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/settings/jsonReader.hpp>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

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

// One region object; with window set (a scheduled region) also its "start" and "end".
AsyncRegion parseRegion(const std::string& sourceName, const TetMesh& mesh, const nlohmann::json& value,
                        const std::string& path, ScheduledRegion* window = nullptr) {
  JsonObjectReader reader(value, path, sourceName);
  AsyncRegion region;
  region.name = reader.string("name", "");
  region.ratio = reader.integer("ratio", 1, 1, 100000);
  if (window) {
    window->start = reader.number("start", 0.0);
    window->end = reader.number("end", window->end);
    if (!(window->end > window->start)) reader.fail("end", "must be after \"start\"");
  }
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

// The names of each choice of the options object, in both directions (read and written
// from one table, so the two cannot drift apart).
template <typename Enum>
using ChoiceTable = std::vector<std::pair<std::string, Enum>>;

const ChoiceTable<AsyncCoupling> kCouplings{{"stable", AsyncCoupling::stable}, {"paper", AsyncCoupling::paper}};
const ChoiceTable<SchurMode> kSchurModes{
    {"low-rank", SchurMode::lowRank}, {"lu", SchurMode::lu}, {"symmetric", SchurMode::symmetric}};
const ChoiceTable<AsyncSolveMethod> kSolveMethods{{"structured", AsyncSolveMethod::structured},
                                                  {"naive", AsyncSolveMethod::naive},
                                                  {"hierarchy", AsyncSolveMethod::hierarchy}};
const ChoiceTable<RecoveryMode> kRecoveryModes{{"automatic", RecoveryMode::automatic},
                                               {"substitution", RecoveryMode::substitution},
                                               {"dense-z", RecoveryMode::denseZ}};

// The value of key (one of the table's names; the first one when absent).
template <typename Enum>
Enum readChoice(JsonObjectReader& reader, const std::string& key, const ChoiceTable<Enum>& table) {
  std::vector<std::string> names;
  for (const auto& entry : table) names.push_back(entry.first);
  const std::string name = reader.choice(key, names.front(), names);
  for (const auto& [entryName, value] : table) {
    if (entryName == name) return value;
  }
  return table.front().second;  // unreachable: choice() accepts only the names
}

template <typename Enum>
const std::string& choiceName(const ChoiceTable<Enum>& table, Enum value) {
  for (const auto& [name, entryValue] : table) {
    if (entryValue == value) return name;
  }
  throw Error("asyncSettingsJson: invalid enumerator " + std::to_string(static_cast<int>(value)));
}

// One key of the solver options: how it is read into AsyncOptions and written back (only
// where it differs from the default). kSolverKeys below is the codec: every key is read,
// written and listed from that one table, so the three cannot drift apart.
struct SolverKey {
  const char* key;
  std::function<void(JsonObjectReader&, AsyncOptions&)> read;
  std::function<void(const AsyncOptions& options, const AsyncOptions& defaults, nlohmann::json& out)> write;
};

// Where a key's value lives in AsyncOptions: one of its members, or a member of one of its
// groups (AsyncOptions::keptFactors, contact).
template <typename T>
struct Place {
  std::function<T&(AsyncOptions&)> at;
  std::function<const T&(const AsyncOptions&)> of;
};

template <typename T>
Place<T> place(T AsyncOptions::*member) {
  return {[member](AsyncOptions& o) -> T& { return o.*member; },
          [member](const AsyncOptions& o) -> const T& { return o.*member; }};
}

template <typename T, typename Group>
Place<T> place(Group AsyncOptions::*group, T Group::*member) {
  return {[group, member](AsyncOptions& o) -> T& { return (o.*group).*member; },
          [group, member](const AsyncOptions& o) -> const T& { return (o.*group).*member; }};
}

template <typename T>
SolverKey valueKey(const char* key, Place<T> where, std::function<T(JsonObjectReader&, const char*, T)> read) {
  return {
      key,
      [key, where, read](JsonObjectReader& reader, AsyncOptions& o) { where.at(o) = read(reader, key, where.of(o)); },
      [key, where](const AsyncOptions& o, const AsyncOptions& defaults, nlohmann::json& out) {
        if (where.of(o) != where.of(defaults)) out[key] = where.of(o);
      }};
}

SolverKey booleanKey(const char* key, Place<bool> where) {
  return valueKey<bool>(key, std::move(where),
                        [](JsonObjectReader& reader, const char* k, bool value) { return reader.boolean(k, value); });
}

SolverKey integerKey(const char* key, Place<int> where, int lowest, int highest) {
  return valueKey<int>(key, std::move(where), [lowest, highest](JsonObjectReader& reader, const char* k, int value) {
    return reader.integer(k, value, lowest, highest);
  });
}

template <typename Enum>
SolverKey choiceKey(const char* key, Place<Enum> where, const ChoiceTable<Enum>& table) {
  return {
      key,
      [key, where, &table](JsonObjectReader& reader, AsyncOptions& o) { where.at(o) = readChoice(reader, key, table); },
      [key, where, &table](const AsyncOptions& o, const AsyncOptions& defaults, nlohmann::json& out) {
        if (where.of(o) != where.of(defaults)) out[key] = choiceName(table, where.of(o));
      }};
}

const ChoiceTable<SolverKind> kRegionSolvers{{"cholmod", SolverKind::cholmod},
                                             {"umfpack", SolverKind::umfpack},
                                             {"eigen-ldlt", SolverKind::eigenLDLT},
                                             {"eigen-lu", SolverKind::eigenLU},
                                             {"dense", SolverKind::dense}};
const ChoiceTable<ZSolve> kZSolves{
    {"automatic", ZSolve::automatic}, {"substitution", ZSolve::substitution}, {"modes", ZSolve::modes}};
const ChoiceTable<NestedSolve> kNestedSolves{
    {"automatic", NestedSolve::automatic}, {"structured", NestedSolve::structured}, {"lu", NestedSolve::lu}};

const std::vector<SolverKey>& solverKeys() {
  static const std::vector<SolverKey> keys{
      // What the step solves and how.
      choiceKey("coupling", place(&AsyncOptions::coupling), kCouplings),
      choiceKey("schur", place(&AsyncOptions::schur), kSchurModes),
      choiceKey("method", place(&AsyncOptions::method), kSolveMethods),
      choiceKey("recovery", place(&AsyncOptions::recovery), kRecoveryModes),
      choiceKey("zSolve", place(&AsyncOptions::zSolve), kZSolves),
      choiceKey("regionSolver", place(&AsyncOptions::regionSolver), kRegionSolvers),
      integerKey("denseRegionDofs", place(&AsyncOptions::denseRegionDofs), 0, 4096),
      choiceKey("nestedSolve", place(&AsyncOptions::nestedSolve), kNestedSolves),
      integerKey("threads", place(&AsyncOptions::threads), 0, 1024),
      // Nonlinear forces and set-ups: the kept factors.
      booleanKey("laggedSchur", place(&AsyncOptions::keptFactors, &AsyncOptions::KeptFactors::laggedSchur)),
      booleanKey("laggedSchurRotation",
                 place(&AsyncOptions::keptFactors, &AsyncOptions::KeptFactors::laggedSchurRotation)),
      booleanKey("quickSetUp", place(&AsyncOptions::keptFactors, &AsyncOptions::KeptFactors::quickSetUp)),
      // Contact.
      booleanKey("substepStatePrediction",
                 place(&AsyncOptions::contact, &AsyncOptions::Contact::substepStatePrediction)),
      integerKey("contactIterations", place(&AsyncOptions::contact, &AsyncOptions::Contact::iterations), 1, 1000),
      valueKey<double>("contactTolerance", place(&AsyncOptions::contact, &AsyncOptions::Contact::tolerance),
                       [](JsonObjectReader& reader, const char* k, double value) {
                         const double tolerance = reader.number(k, value);
                         if (!(tolerance > 0.0 && tolerance < 1.0)) reader.fail(k, "must be in (0, 1)");
                         return tolerance;
                       }),
      booleanKey("certifyContactFree", place(&AsyncOptions::contact, &AsyncOptions::Contact::certifyContactFree)),
  };
  return keys;
}

AsyncOptions parseSolverOptions(JsonObjectReader& reader, bool hasContact) {
  AsyncOptions solver;
  if (reader.find("substepContact")) {
    reader.fail("substepContact",
                "renamed \"substepStatePrediction\" (f_ext at each substep's predicted state; it is not contact)");
  }
  for (const SolverKey& key : solverKeys()) key.read(reader, solver);
  if (solver.contact.substepStatePrediction && !hasContact) {
    reader.fail("substepStatePrediction", "only meaningful with a \"contact\" section");
  }
  return solver;
}

// "adaptive": {"contact": {...}, "schedule": [...], "minDwell", "shrink", "cache"}.
RunTimeRegionOptions parseAdaptive(const IntegratorContext& context, const nlohmann::json& value,
                                   const std::string& path) {
  const std::string& sourceName = context.sourceName;
  JsonObjectReader reader(value, path, sourceName);
  RunTimeRegionOptions out;
  if (const nlohmann::json* contact = reader.find("contact")) {
    if (!context.hasContact) reader.fail("contact", "needs obstacles: add a \"contact\" section to the scene");
    JsonObjectReader c(*contact, reader.keyPath("contact"), sourceName);
    out.contact = true;
    out.contactRatio = c.integer("ratio", out.contactRatio, 2, 100000);
    out.contactMargin = c.number("margin", out.contactMargin);
    if (!(out.contactMargin >= 0.0)) c.fail("margin", "must be >= 0 (a length)");
    out.contactLookahead = c.number("lookahead", out.contactLookahead);
    if (!(out.contactLookahead >= 0.0)) c.fail("lookahead", "must be >= 0 (large steps)");
    out.contactRings = c.integer("rings", out.contactRings, 0, 100);
    out.contactSlack = c.integer("slack", out.contactSlack, 0, 100);
    c.finish();
  }
  if (const nlohmann::json* indicator = reader.find("indicator")) {
    JsonObjectReader c(*indicator, reader.keyPath("indicator"), sourceName);
    out.indicator = true;
    out.indicatorTolerance = c.number("tolerance", out.indicatorTolerance);
    if (!(out.indicatorTolerance > 0.0)) c.fail("tolerance", "must be > 0 (a fraction of the RMS vertex speed)");
    out.indicatorRatio = c.integer("ratio", out.indicatorRatio, 2, 100000);
    out.indicatorRings = c.integer("rings", out.indicatorRings, 0, 100);
    c.finish();
  }
  if (const nlohmann::json* schedule = reader.find("schedule")) {
    if (!schedule->is_array()) reader.fail("schedule", "expected an array of regions with \"start\" and \"end\"");
    for (std::size_t i = 0; i < schedule->size(); ++i) {
      ScheduledRegion window;
      AsyncRegion region =
          parseRegion(sourceName, *context.mesh, (*schedule)[i], reader.elementPath("schedule", i), &window);
      window.name = region.name;
      window.ratio = region.ratio;
      window.vertices = std::move(region.vertices);
      out.schedule.push_back(std::move(window));
    }
  }
  if (const nlohmann::json* loads = reader.find("loads")) {  // the loads policy: loadsPolicy.hpp
    JsonObjectReader c(*loads, reader.keyPath("loads"), sourceName);
    out.loads = true;
    out.loadsRatio = c.integer("ratio", out.loadsRatio, 2, 100000);
    out.loadsRings = c.integer("rings", out.loadsRings, 0, 100);
    out.loadsNeighbourhood = c.integer("neighbourhood", out.loadsNeighbourhood, 0, 100);
    out.loadsRelease = c.number("release", out.loadsRelease);
    if (!(out.loadsRelease >= 0.0 && out.loadsRelease < 1.0))
      c.fail("release", "must be in [0, 1) (of the peak energy)");
    if (const nlohmann::json* parts = c.find("parts")) {
      if (!parts->is_array()) c.fail("parts", "expected an array of regions");
      for (std::size_t i = 0; i < parts->size(); ++i) {
        AsyncRegion part = parseRegion(sourceName, *context.mesh, (*parts)[i], c.elementPath("parts", i));
        if (!(*parts)[i].contains("ratio")) part.ratio = out.loadsRatio;
        if (part.ratio < 2) JsonObjectReader::failAt(sourceName, c.elementPath("parts", i) + ".ratio", "must be >= 2");
        out.loadsParts.push_back(std::move(part));
      }
    }
    c.finish();
  }
  if (!out.contact && !out.indicator && out.schedule.empty() && !out.loads) {
    JsonObjectReader::failAt(sourceName, path,
                             "give at least one policy: \"contact\", \"indicator\", \"schedule\" or \"loads\"");
  }
  out.minDwell = reader.integer("minDwell", out.minDwell, 0, 1000000);
  out.shrinkFactor = reader.number("shrink", out.shrinkFactor);
  if (!(out.shrinkFactor >= 1.0)) reader.fail("shrink", "must be >= 1");
  out.cacheSize = reader.integer("cache", out.cacheSize, 0, 64);
  out.nest = reader.boolean("nest", out.nest);
  reader.finish();
  return out;
}

// "regions" (default "auto") and "auto" into out: the explicit regions, or the automatic
// settings (the proposal runs after the keys are checked).
void parseRegions(JsonObjectReader& reader, const IntegratorContext& context, const nlohmann::json& options,
                  AsyncSettings& out) {
  static const nlohmann::json automaticRegions = "auto";
  const std::string& sourceName = context.sourceName;
  const nlohmann::json* given = reader.find("regions");
  const nlohmann::json& regions = given ? *given : automaticRegions;  // default: proposed regions
  const std::string regionsPath = reader.keyPath("regions");
  if (regions.is_string()) {
    if (regions.get<std::string>() != "auto") {
      JsonObjectReader::failAt(sourceName, regionsPath, "expected \"auto\" or an array of regions");
    }
    out.automaticRegions = true;
    out.automatic = parseRegionProposalOptions(context, options);
    (void)reader.find("auto");  // read by parseRegionProposalOptions
  } else if (regions.is_object()) {
    if (reader.find("auto")) reader.fail("auto", "only with \"regions\": \"auto\"");
    JsonObjectReader object(regions, regionsPath, sourceName);
    out.adaptiveSource = object.required("adaptive");
    out.adaptive = parseAdaptive(context, out.adaptiveSource, object.keyPath("adaptive"));
    object.finish();
  } else if (regions.is_array()) {
    if (reader.find("auto")) reader.fail("auto", "only with \"regions\": \"auto\"");
    for (std::size_t i = 0; i < regions.size(); ++i) {
      out.regions.push_back(parseRegion(sourceName, *context.mesh, regions[i], reader.elementPath("regions", i)));
    }
  } else {
    JsonObjectReader::failAt(
        sourceName, regionsPath,
        "expected \"auto\", an array of regions or {\"adaptive\": ...}, got " + JsonObjectReader::describe(regions));
  }
}

// The other multirate integrators read the regions as "async" does; its solver keys have
// no meaning there: reject them by name rather than silently ignoring a setting the user
// expects to matter. options must be an object.
void rejectAsyncOnlyKeys(const IntegratorContext& context, const nlohmann::json& options, const std::string& name) {
  const std::string& path = context.optionsPath;
  if (!options.is_object()) {
    JsonObjectReader::failAt(context.sourceName, path,
                             "expected an object, got " + JsonObjectReader::describe(options));
  }
  for (const char* key : {"coupling", "schur", "method", "recovery", "zSolve", "substepStatePrediction"}) {
    if (options.contains(key)) {
      JsonObjectReader::failAt(context.sourceName, path + "." + key, "used by \"async\" only, not by \"" + name + "\"");
    }
  }
}

}  // namespace

RegionProposalOptions parseRegionProposalOptions(const IntegratorContext& context, const nlohmann::json& options) {
  RegionProposalOptions automatic;
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
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> out{"regions", "auto"};
    for (const SolverKey& key : solverKeys()) out.emplace_back(key.key);
    return out;
  }();
  return keys;
}

AsyncSettings parseAsyncSettings(const IntegratorContext& context, const nlohmann::json& options) {
  const std::string& sourceName = context.sourceName;
  if (!context.mesh) throw ValidationError(sourceName + ": " + context.optionsPath + ": async needs the mesh");
  const TetMesh& mesh = *context.mesh;
  JsonObjectReader reader(options, context.optionsPath, sourceName);
  AsyncSettings out;
  out.solver = parseSolverOptions(reader, context.hasContact);
  const std::string regionsPath = reader.keyPath("regions");
  parseRegions(reader, context, options, out);
  reader.finish();
  const FreeDofs& freeDofs = context.system.freeDofs;
  if (out.automaticRegions) {
    if (out.automatic.modalCheck) {
      // K and M are assembled only when the modal check runs (not after the pre-check).
      out.proposal = proposeRegions(mesh, freeDofs, out.automatic, context.massType);
    } else {
      out.proposal = proposeRegions(mesh, freeDofs, out.automatic);
    }
    out.regions = out.proposal->asyncRegions();
  }
  // The partition, built once here so that its errors name the key; its shape chooses the
  // step solver when the integrator is made (chooseStepSolver, which checks the options).
  try {
    out.partition.emplace(mesh, freeDofs, out.regions);
  } catch (const ValidationError& e) {
    JsonObjectReader::failAt(sourceName, regionsPath, e.what());
  }
  return out;
}

namespace {

/// AsyncBackwardEuler for the settings, on the partition they built; an option that
/// chooseStepSolver() refuses is named by its scene key.
std::unique_ptr<AsyncBackwardEuler> makeAsync(IntegratorContext& context, AsyncSettings& parsed) {
  if (!context.system.mesh)
    context.system = PartitionedIntegrator::withMesh("async", *context.mesh, std::move(context.system));
  try {
    return std::make_unique<AsyncBackwardEuler>(std::move(context.system), context.timestep,
                                                std::move(*parsed.partition), parsed.solver);
  } catch (const AsyncOptionError& e) {
    const std::vector<std::string>& keys = asyncOptionKeys();
    const bool sceneKey = std::find(keys.begin(), keys.end(), e.key()) != keys.end();
    JsonObjectReader::failAt(context.sourceName, context.optionsPath + (sceneKey ? "." + e.key() : ""),
                             sceneKey ? e.reason() : e.what());
  }
}

}  // namespace

nlohmann::json asyncRegionJson(const AsyncRegion& region) {
  return {{"name", region.name}, {"ratio", region.ratio}, {"vertices", region.vertices}};
}

nlohmann::json asyncRegionsJson(const std::vector<AsyncRegion>& regions) {
  nlohmann::json out = nlohmann::json::array();
  for (const AsyncRegion& region : regions) out.push_back(asyncRegionJson(region));
  return out;
}

nlohmann::json asyncSettingsJson(const AsyncSettings& settings) {
  const AsyncOptions defaults;
  nlohmann::json out = nlohmann::json::object();
  for (const SolverKey& key : solverKeys()) key.write(settings.solver, defaults, out);
  out["regions"] =
      settings.adaptive ? nlohmann::json{{"adaptive", settings.adaptiveSource}} : asyncRegionsJson(settings.regions);
  return out;
}

int largestRatio(const std::vector<AsyncRegion>& regions) {
  int largest = 1;
  for (const AsyncRegion& region : regions) largest = std::max(largest, region.ratio);
  return largest;
}

void registerMultirateIntegrators(IntegratorRegistry& registry, AsyncSettingsHook asyncHook) {
  registry.add(
      "async",
      [asyncHook](IntegratorContext context, const nlohmann::json& options) -> std::unique_ptr<Integrator> {
        AsyncSettings parsed = parseAsyncSettings(context, options);
        if (asyncHook) asyncHook(parsed, context);
        std::unique_ptr<AsyncBackwardEuler> integrator = makeAsync(context, parsed);
        if (parsed.adaptive) integrator->setRunTimeRegions(*parsed.adaptive);
        if (parsed.automaticRegions && parsed.proposal)
          integrator->setRegionNote(regionProposalSummary(*parsed.proposal));
        return integrator;
      },
      asyncOptionKeys());
  registry.add(
      "multirate-uncoupled",
      [](IntegratorContext context, const nlohmann::json& options) -> std::unique_ptr<Integrator> {
        const std::string& path = context.optionsPath;
        rejectAsyncOnlyKeys(context, options, "multirate-uncoupled");
        UncoupledMultirateOptions solverOptions;
        nlohmann::json regionOptions = options;  // what parseAsyncSettings reads
        if (const auto it = options.find("compoundSolver"); it != options.end()) {
          const std::string name = JsonObjectReader::toString(*it, path + ".compoundSolver", context.sourceName);
          if (name != "umfpack" && name != "eigen-lu") {
            JsonObjectReader::failAt(
                context.sourceName, path + ".compoundSolver",
                "unknown value \"" + name + "\" (expected one of umfpack, eigen-lu: the system is unsymmetric)");
          }
          solverOptions.compoundSolver = parseSolverKind(name);
          regionOptions.erase("compoundSolver");
        }
        const AsyncSettings parsed = parseAsyncSettings(context, regionOptions);
        if (parsed.adaptive || parsed.partition->touching()) {
          JsonObjectReader::failAt(context.sourceName, path + ".regions",
                                   std::string(parsed.adaptive ? "run-time (adaptive)" : "touching or nested") +
                                       " regions are available with \"async\" only");
        }
        solverOptions.regionSolver = parsed.solver.regionSolver;
        return std::make_unique<UncoupledMultirate>(*context.mesh, std::move(context.system), context.timestep,
                                                    parsed.regions, solverOptions);
      },
      {"compoundSolver", "regionSolver", "regions", "auto"});
  registry.add("schroeder2011",
               [](IntegratorContext context, const nlohmann::json& options) -> std::unique_ptr<Integrator> {
                 const std::string& path = context.optionsPath;
                 rejectAsyncOnlyKeys(context, options, "schroeder2011");
                 // Its own keys are read here; the rest (regions, auto, regionSolver) as "async" reads them.
                 Schroeder2011Options solverOptions;
                 nlohmann::json regionOptions = options;
                 nlohmann::json own = nlohmann::json::object();
                 for (const char* key : {"compoundSolver", "rigidity", "force"}) {
                   if (const auto it = options.find(key); it != options.end()) {
                     own[key] = *it;
                     regionOptions.erase(key);
                   }
                 }
                 JsonObjectReader reader(own, path, context.sourceName);
                 const std::string compound = reader.choice("compoundSolver", "umfpack", {"umfpack", "eigen-lu"});
                 solverOptions.compoundSolver = parseSolverKind(compound);
                 solverOptions.rigidity = reader.number("rigidity", solverOptions.rigidity);
                 if (!(solverOptions.rigidity >= 0.0 && solverOptions.rigidity <= 1.0)) {
                   reader.fail("rigidity", "expected a number in [0, 1]");
                 }
                 solverOptions.force = reader.boolean("force", solverOptions.force);
                 reader.finish();
                 const AsyncSettings parsed = parseAsyncSettings(context, regionOptions);
                 if (parsed.partition->touching()) {
                   JsonObjectReader::failAt(context.sourceName, path + ".regions",
                                            "touching or nested regions are available with \"async\" only");
                 }
                 solverOptions.regionSolver = parsed.solver.regionSolver;
                 return std::make_unique<Schroeder2011>(*context.mesh, std::move(context.system), context.timestep,
                                                        parsed.regions, solverOptions);
               },
               {"compoundSolver", "regionSolver", "rigidity", "force", "regions", "auto"});
}

}  // namespace asyncfem
