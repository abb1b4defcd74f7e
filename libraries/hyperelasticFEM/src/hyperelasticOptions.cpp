// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/enumNames.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <cctype>
#include <cmath>
#include <sstream>

namespace asyncfem {

namespace {

// Names of the materials, in the order error messages list them.
constexpr EnumName<HyperelasticMaterialKind> kMaterialNames[] = {
    {HyperelasticMaterialKind::stvk, "stvk"},
    {HyperelasticMaterialKind::neoHookean, "neo-hookean"},
    {HyperelasticMaterialKind::mooneyRivlin, "mooney-rivlin"}};
// Other spellings parseHyperelasticMaterialKind accepts.
constexpr EnumName<HyperelasticMaterialKind> kMaterialAliases[] = {
    {HyperelasticMaterialKind::neoHookean, "neohookean"}, {HyperelasticMaterialKind::mooneyRivlin, "mooneyrivlin"}};

}  // namespace

HyperelasticMaterialKind parseHyperelasticMaterialKind(std::string_view name) {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (const std::optional<HyperelasticMaterialKind> kind = findEnumValue(kMaterialNames, lower)) return *kind;
  if (const std::optional<HyperelasticMaterialKind> kind = findEnumValue(kMaterialAliases, lower)) return *kind;
  throw ValidationError("unknown hyperelastic material '" + std::string(name) + "' (expected " +
                        joinEnumNames(kMaterialNames, ", ", " or ") + ")");
}

std::string toString(HyperelasticMaterialKind kind) {
  return std::string(findEnumName(kMaterialNames, kind).value_or("unknown"));
}

LameParameters vegaLameParameters(double youngsModulus, double poissonRatio) {
  // Vega's ENuMaterial: getLambda() = nu E / ((1 + nu)(1 - 2 nu)), getMu() = E / (2 (1 + nu)).
  return {(poissonRatio * youngsModulus) / ((1.0 + poissonRatio) * (1.0 - (2.0 * poissonRatio))),
          youngsModulus / (2.0 * (1.0 + poissonRatio))};
}

SmallStrainModuli mooneyRivlinSmallStrainModuli(const MooneyRivlinParameters& parameters) {
  const double shear = 2.0 * (parameters.mu10 + parameters.mu01);
  const double bulk = 2.0 * parameters.v1;
  if (!std::isfinite(parameters.mu01) || !std::isfinite(parameters.mu10) || !std::isfinite(parameters.v1) ||
      !(shear > 0.0) || !(bulk > 0.0)) {
    std::ostringstream message;
    message << "Mooney-Rivlin parameters mu01 = " << parameters.mu01 << ", mu10 = " << parameters.mu10
            << ", v1 = " << parameters.v1
            << " are not a stable material: need finite values with mu10 + mu01 > 0 and v1 > 0";
    throw ValidationError(message.str());
  }
  return {parameters.equivalentYoungsModulus(), parameters.equivalentPoissonRatio()};
}

}  // namespace asyncfem
