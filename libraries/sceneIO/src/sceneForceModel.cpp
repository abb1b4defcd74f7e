// SPDX-License-Identifier: BSD-3-Clause
// The scene's "forceModel" section: the model type and the hyperelastic options
// (docs/scene-format.md, "forceModel").
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/settings/jsonReader.hpp>
#include <cmath>
#include <string>

#include "detail/sceneSections.hpp"

namespace asyncfem::detail {

namespace {

using nlohmann::json;

// forceModel's hyperelastic keys; rejects each one the chosen model does not read.
void parseHyperelasticOptions(JsonObjectReader& reader, const Scene& scene, HyperelasticOptions& h) {
  const bool hyperelastic =
      scene.forceModel != Scene::ForceModelKind::linear && scene.forceModel != Scene::ForceModelKind::corotational;
  for (const char* key : {"inversionThreshold", "inversionHandling", "compressionResistance", "enforceSPD",
                          "stvkFormulation", "mooneyRivlin"}) {
    if (reader.has(key) && !hyperelastic) {
      reader.fail(key, "only the hyperelastic force models (stvk, neo-hookean, mooney-rivlin) read it");
    }
  }
  if (reader.has("inversionThreshold")) {
    h.inversionThreshold = reader.number("inversionThreshold", 0.0);
    if (!(h.inversionThreshold > 0.0 && h.inversionThreshold < 1.0)) {
      reader.fail("inversionThreshold", "expected a principal stretch in (0, 1)");
    }
  }
  h.inversionHandling = reader.choice("inversionHandling", "extrapolate", {"extrapolate", "vega-clamp"}) == "vega-clamp"
                            ? InversionHandling::vegaClamp
                            : InversionHandling::extrapolate;
  if (reader.has("compressionResistance")) {
    h.enableCompressionResistance = true;
    h.compressionResistance = reader.number("compressionResistance", h.compressionResistance);
    if (!(h.compressionResistance >= 0.0)) reader.fail("compressionResistance", "expected a number >= 0");
  }
  h.enforceSPD = reader.boolean("enforceSPD", h.enforceSPD);
  h.stvkFormulation =
      reader.choice("stvkFormulation", "green-strain", {"green-strain", "principal-stretches"}) == "green-strain"
          ? StVKFormulation::greenStrain
          : StVKFormulation::principalStretches;
  if (scene.forceModel == Scene::ForceModelKind::stvk && h.stvkFormulation == StVKFormulation::greenStrain) {
    for (const char* key : {"inversionThreshold", "compressionResistance", "enforceSPD"}) {
      if (reader.has(key)) {
        reader.fail(key,
                    "the Green-strain StVK has no inversion handling: set \"stvkFormulation\": "
                    "\"principal-stretches\" to use it");
      }
    }
  }
}

void parseMooneyRivlin(JsonObjectReader& reader, const Scene& scene, HyperelasticOptions& h) {
  const json* mooney = reader.find("mooneyRivlin");
  if (mooney == nullptr) return;
  if (scene.forceModel != Scene::ForceModelKind::mooneyRivlin) {
    reader.fail("mooneyRivlin", "only with \"type\": \"mooney-rivlin\"");
  }
  JsonObjectReader m(*mooney, reader.keyPath("mooneyRivlin"), scene.sourceName);
  MooneyRivlinParameters parameters;
  parameters.mu01 = m.number("mu01", parameters.mu01);
  parameters.mu10 = m.number("mu10", parameters.mu10);
  parameters.v1 = m.number("v1", parameters.v1);
  m.finish();
  h.mooneyRivlin = parameters;
}

}  // namespace

void parseForceModel(JsonObjectReader& top, Scene& scene) {
  const json* forceModel = top.find("forceModel");
  if (forceModel == nullptr) return;
  JsonObjectReader reader(*forceModel, "forceModel", scene.sourceName);
  const std::string type =
      reader.choice("type", "linear", {"linear", "corotational", "stvk", "neo-hookean", "mooney-rivlin"});
  scene.forceModel = type == "linear"         ? Scene::ForceModelKind::linear
                     : type == "corotational" ? Scene::ForceModelKind::corotational
                     : type == "stvk"         ? Scene::ForceModelKind::stvk
                     : type == "neo-hookean"  ? Scene::ForceModelKind::neoHookean
                                              : Scene::ForceModelKind::mooneyRivlin;
  if (reader.has("tangent")) {
    if (scene.forceModel != Scene::ForceModelKind::corotational) {
      reader.fail("tangent", "only the corotational force model has a tangent choice");
    }
    scene.tangent = reader.choice("tangent", "simple", {"simple", "exact"}) == "exact" ? Scene::Tangent::exact
                                                                                       : Scene::Tangent::simple;
  }
  parseHyperelasticOptions(reader, scene, scene.hyperelastic);
  parseMooneyRivlin(reader, scene, scene.hyperelastic);
  reader.finish();
}

}  // namespace asyncfem::detail
