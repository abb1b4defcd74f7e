// SPDX-License-Identifier: BSD-3-Clause
// Vega .veg reader (TET and CUBIC elements); see docs/file-formats.md for what is accepted.
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "detail/rawMesh.hpp"
#include "detail/textInput.hpp"

namespace asyncfem {

namespace {

using detail::LineCursor;
using detail::Location;

/// Sets written by writeVeg only to give each material a *REGION; they are used to
/// assign materials but not kept as element sets of the mesh.
constexpr std::string_view kMaterialSetPrefix = "__material_";

struct PendingSet {
  std::string name;
  bool vertexSet = false;
  std::vector<std::pair<long long, Location>> ids;  ///< 1-based ids as written, with their line
};

struct RegionLine {
  std::string setName;
  std::string materialName;
  Location location;
};

bool isKeywordLine(std::string_view line) { return !line.empty() && line.front() == '*'; }

/// The single name after a keyword such as "*MATERIAL steel".
std::string nameAfterKeyword(const LineCursor& cursor, std::string_view keyword,
                             const std::vector<std::string_view>& tokens) {
  if (tokens.size() < 2) cursor.fail(std::string(keyword) + " needs a name on the same line");
  if (tokens.size() > 2) cursor.fail(std::string(keyword) + " takes one name without spaces or commas");
  return std::string(tokens[1]);
}

class VegParser {
 public:
  explicit VegParser(const detail::FlatText& flat) : cursor_(flat, true) {}

  TetMesh parse(const MeshReadOptions& options, MeshReadReport& report) {
    while (cursor_.next()) {
      const std::string_view line = cursor_.line();
      if (!isKeywordLine(line)) {
        cursor_.fail("expected a keyword (*VERTICES, *ELEMENTS, *MATERIAL, *SET, *REGION), got '" + std::string(line) +
                     "'");
      }
      const std::vector<std::string_view> tokens = detail::splitTokens(line, false);
      const std::string_view keyword = tokens.front();
      if (detail::equalsIgnoreCase(keyword, "*VERTICES")) {
        readVertices();
      } else if (detail::equalsIgnoreCase(keyword, "*ELEMENTS")) {
        readElements();
      } else if (detail::equalsIgnoreCase(keyword, "*MATERIAL")) {
        readMaterial(nameAfterKeyword(cursor_, "*MATERIAL", tokens));
      } else if (detail::equalsIgnoreCase(keyword, "*SET")) {
        readSet(nameAfterKeyword(cursor_, "*SET", tokens), false);
      } else if (detail::equalsIgnoreCase(keyword, "*VERTEXSET")) {
        readSet(nameAfterKeyword(cursor_, "*VERTEXSET", tokens), true);
      } else if (detail::equalsIgnoreCase(keyword, "*REGION")) {
        if (tokens.size() > 1) cursor_.fail("*REGION takes no arguments; put 'set, material' on the next lines");
        readRegion();
      } else {
        cursor_.fail("unknown keyword '" + std::string(keyword) +
                     "' (supported: *VERTICES, *ELEMENTS, *MATERIAL, *SET, *VERTEXSET, *REGION, *INCLUDE)");
      }
    }
    if (!haveVertices_) cursor_.failAtEnd("no *VERTICES section");
    if (!haveElements_) cursor_.failAtEnd("no *ELEMENTS section");
    resolveSetsAndRegions();
    return detail::finishMesh(std::move(raw_), cursor_, options, report, detail::MissingMaterialPolicy::Error);
  }

 private:
  /// Reads the count line after *VERTICES / *ELEMENTS (more numbers may follow it).
  std::vector<std::string_view> headerLine(const std::string& keyword, const std::string& expected) {
    if (!cursor_.next() || isKeywordLine(cursor_.line())) {
      cursor_.fail(keyword + " needs a header line '" + expected + "'");
    }
    auto tokens = detail::splitTokens(cursor_.line(), true);
    if (tokens.empty()) cursor_.fail(keyword + " needs a header line '" + expected + "'");
    return tokens;
  }

  /// The vertex count of the *VERTICES header line, checked.
  long long readVerticesHeader() {
    const auto header = headerLine("*VERTICES", "<count> 3 0 0");
    if (header.size() > 4)
      cursor_.fail("*VERTICES header has " + std::to_string(header.size()) + " fields; expected '<count> 3 0 0'");
    const long long count = detail::integerAt(cursor_, header[0], "*VERTICES count");
    if (header.size() >= 2 && detail::integerAt(cursor_, header[1], "*VERTICES dimension") != 3) {
      cursor_.fail("*VERTICES dimension must be 3, got " + std::string(header[1]));
    }
    for (std::size_t i = 2; i < header.size(); ++i) detail::integerAt(cursor_, header[i], "*VERTICES header");
    cursor_.checkCountFits(count, 7, "vertices");
    return count;
  }

  void readVertices() {
    if (haveVertices_) cursor_.fail("second *VERTICES section");
    haveVertices_ = true;
    const long long count = readVerticesHeader();
    const Location headerAt = cursor_.location();
    const auto n = static_cast<std::size_t>(count);
    raw_.positions.assign(3 * n, 0.0);
    raw_.vertexFileIds.resize(n);
    std::vector<char> seen(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (!cursor_.next() || isKeywordLine(cursor_.line())) {
        cursor_.failAt(headerAt, "*VERTICES header says " + std::to_string(count) +
                                     " vertices, but the section has only " + std::to_string(i));
      }
      const auto tokens = detail::splitTokens(cursor_.line(), true);
      if (tokens.size() != 4) {
        cursor_.fail("vertex line needs 'index x y z', got " + std::to_string(tokens.size()) + " fields");
      }
      const long long id = detail::integerAt(cursor_, tokens[0], "vertex index");
      if (id < 1 || id > count) {
        cursor_.fail("vertex index " + std::to_string(id) + " is outside [1, " + std::to_string(count) + "]");
      }
      const auto v = static_cast<std::size_t>(id - 1);
      if (seen[v]) cursor_.fail("duplicate vertex index " + std::to_string(id));
      seen[v] = 1;
      raw_.vertexFileIds[v] = id;
      for (std::size_t c = 0; c < 3; ++c) {
        raw_.positions[3 * v + c] =
            detail::finiteDoubleAt(cursor_, tokens[c + 1], "vertex " + std::to_string(id) + " coordinate");
      }
    }
    expectSectionEnd("*VERTICES", count, "vertices", "vertex");
  }

  void readElements() {
    if (haveElements_) cursor_.fail("second *ELEMENTS section");
    if (!haveVertices_) cursor_.fail("*ELEMENTS before *VERTICES: vertices must come first");
    haveElements_ = true;
    readElementType();
    const long long count = readElementsHeader();
    const Location headerAt = cursor_.location();
    const auto n = static_cast<std::size_t>(count);
    const std::size_t corners = raw_.kind == ElementKind::hexahedron ? 8 : 4;
    if (corners == 8) {
      raw_.hexahedra.resize(n);
    } else {
      raw_.elements.resize(n);
    }
    raw_.elementLocations.resize(n);
    raw_.elementFileIds.resize(n);
    raw_.elementMaterials.assign(n, -1);
    std::vector<char> seen(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (!cursor_.next() || isKeywordLine(cursor_.line())) {
        cursor_.failAt(headerAt, "*ELEMENTS header says " + std::to_string(count) +
                                     " elements, but the section has only " + std::to_string(i));
      }
      const auto tokens = detail::splitTokens(cursor_.line(), true);
      if (tokens.size() != corners + 1) {
        cursor_.fail(std::string("element line needs 'index ") + (corners == 8 ? "v1 ... v8" : "v1 v2 v3 v4") +
                     "', got " + std::to_string(tokens.size()) + " fields");
      }
      const long long id = detail::integerAt(cursor_, tokens[0], "element index");
      if (id < 1 || id > count) {
        cursor_.fail("element index " + std::to_string(id) + " is outside [1, " + std::to_string(count) + "]");
      }
      const auto e = static_cast<std::size_t>(id - 1);
      if (seen[e]) cursor_.fail("duplicate element index " + std::to_string(id));
      seen[e] = 1;
      if (corners == 8) {
        readElementVertices(tokens, id, raw_.hexahedra[e]);
      } else {
        readElementVertices(tokens, id, raw_.elements[e]);
      }
      raw_.elementLocations[e] = cursor_.location();
      raw_.elementFileIds[e] = id;
    }
    expectSectionEnd("*ELEMENTS", count, "elements", "element");
  }

  /// The line after *ELEMENTS must name the element type: TET or CUBIC (Vega's cubes).
  void readElementType() {
    if (!cursor_.next() || isKeywordLine(cursor_.line()))
      cursor_.fail("*ELEMENTS needs the element type (TET or CUBIC) on the next line");
    const std::string_view type = cursor_.line();
    long long ignored = 0;
    if (detail::equalsIgnoreCase(type, "CUBIC")) {
      raw_.kind = ElementKind::hexahedron;
      raw_.vegaCubes = true;
      return;
    }
    if (!detail::equalsIgnoreCase(type, "TET")) {
      const auto typeTokens = detail::splitTokens(type, true);
      if (!typeTokens.empty() && detail::parseInteger(typeTokens.front(), ignored)) {
        cursor_.fail("*ELEMENTS needs the element type (TET or CUBIC) on its own line before the count");
      }
      cursor_.fail("unsupported element type '" + std::string(type) + "': TET and CUBIC are supported");
    }
  }

  /// The element count of the *ELEMENTS header line, checked.
  long long readElementsHeader() {
    const bool cubes = raw_.kind == ElementKind::hexahedron;
    const std::string expected = cubes ? "<count> 8 0" : "<count> 4 0";
    const auto header = headerLine("*ELEMENTS", expected);
    if (header.size() > 3) {
      cursor_.fail("*ELEMENTS header has " + std::to_string(header.size()) + " fields; expected '" + expected + "'");
    }
    const long long count = detail::integerAt(cursor_, header[0], "*ELEMENTS count");
    if (header.size() >= 2 &&
        detail::integerAt(cursor_, header[1], "*ELEMENTS vertices per element") != (cubes ? 8 : 4)) {
      cursor_.fail(std::string(cubes ? "CUBIC elements have 8" : "TET elements have 4") +
                   " vertices, but the header says " + std::string(header[1]));
    }
    if (header.size() >= 3) detail::integerAt(cursor_, header[2], "*ELEMENTS header");
    // A line holds at least the index and the vertices, each with a separator.
    cursor_.checkCountFits(count, cubes ? 17 : 9, "elements");
    return count;
  }

  /// Reads the vertices of element id (its file index) from tokens[1 .. N] into element.
  template <class Tokens, std::size_t N>
  void readElementVertices(const Tokens& tokens, long long id, std::array<int, N>& element) {
    const auto numVertices = static_cast<long long>(raw_.vertexFileIds.size());
    const std::string name = "element " + std::to_string(id);
    for (std::size_t a = 0; a < N; ++a) {
      const long long v = detail::integerAt(cursor_, tokens[a + 1], name + " vertex");
      if (v < 1 || v > numVertices) {
        cursor_.fail(name + " references vertex " + std::to_string(v) + ", outside [1, " + std::to_string(numVertices) +
                     "]");
      }
      for (std::size_t b = 0; b < a; ++b) {
        if (element[b] == static_cast<int>(v - 1)) cursor_.fail(name + " uses vertex " + std::to_string(v) + " twice");
      }
      element[a] = static_cast<int>(v - 1);
    }
  }

  /// After count records, the next line must be a keyword (or the end of the input).
  void expectSectionEnd(const std::string& keyword, long long count, const std::string& plural,
                        const std::string& singular) {
    if (cursor_.next()) {
      if (!isKeywordLine(cursor_.line())) {
        cursor_.fail(keyword + " header says " + std::to_string(count) + " " + plural + ", but there are more " +
                     singular + " lines");
      }
      cursor_.pushBack();
    }
  }

  void readMaterial(const std::string& name) {
    if (!materialNames_.insert(name).second) cursor_.fail("material '" + name + "' is defined twice");
    const std::string expected = "a line 'ENU, density, E, nu' or 'MOONEYRIVLIN, density, mu01, mu10, v1'";
    if (!cursor_.next() || isKeywordLine(cursor_.line())) cursor_.fail("*MATERIAL " + name + " needs " + expected);
    const auto tokens = detail::splitTokens(cursor_.line(), true);
    if (tokens.empty()) cursor_.fail("*MATERIAL " + name + " needs " + expected);
    const bool mooneyRivlin = detail::equalsIgnoreCase(tokens.front(), "MOONEYRIVLIN");
    if (!mooneyRivlin && !detail::equalsIgnoreCase(tokens.front(), "ENU")) {
      cursor_.fail("material '" + name + "': unsupported material keyword '" + std::string(tokens.front()) +
                   "' (supported: 'ENU, density, E, nu' and 'MOONEYRIVLIN, density, mu01, mu10, v1')");
    }
    if (mooneyRivlin) {
      readMooneyRivlinMaterial(name, tokens);
      return;
    }
    if (tokens.size() != 4) {
      cursor_.fail("material '" + name + "': ENU needs exactly 3 numbers (density, E, nu), got " +
                   std::to_string(tokens.size() - 1));
    }
    Material m;
    m.name = name;
    m.density = detail::finiteDoubleAt(cursor_, tokens[1], "material '" + name + "' density");
    m.youngsModulus = detail::finiteDoubleAt(cursor_, tokens[2], "material '" + name + "' Young's modulus");
    m.poissonRatio = detail::finiteDoubleAt(cursor_, tokens[3], "material '" + name + "' Poisson's ratio");
    detail::checkMaterialAt(cursor_, m);
    raw_.materials.push_back(std::move(m));
  }

  // Vega's compressible Mooney-Rivlin material; E and nu are set to its small-strain
  // equivalents so that linear and corotational models still apply.
  template <class Tokens>
  void readMooneyRivlinMaterial(const std::string& name, const Tokens& tokens) {
    if (tokens.size() != 5) {
      cursor_.fail("material '" + name + "': MOONEYRIVLIN needs exactly 4 numbers (density, mu01, mu10, v1), got " +
                   std::to_string(tokens.size() - 1));
    }
    Material m;
    m.name = name;
    m.density = detail::finiteDoubleAt(cursor_, tokens[1], "material '" + name + "' density");
    MooneyRivlinParameters parameters;
    parameters.mu01 = detail::finiteDoubleAt(cursor_, tokens[2], "material '" + name + "' mu01");
    parameters.mu10 = detail::finiteDoubleAt(cursor_, tokens[3], "material '" + name + "' mu10");
    parameters.v1 = detail::finiteDoubleAt(cursor_, tokens[4], "material '" + name + "' v1");
    if (!(parameters.mu01 + parameters.mu10 > 0.0)) {
      cursor_.fail("material '" + name +
                   "': MOONEYRIVLIN needs mu01 + mu10 > 0 (the shear modulus is 2 (mu01 + mu10)), got " +
                   detail::formatDouble(parameters.mu01 + parameters.mu10));
    }
    if (!(parameters.v1 > 0.0)) {
      cursor_.fail("material '" + name + "': MOONEYRIVLIN needs v1 > 0 (the bulk modulus is 2 v1), got " +
                   detail::formatDouble(parameters.v1));
    }
    m.youngsModulus = parameters.equivalentYoungsModulus();
    m.poissonRatio = parameters.equivalentPoissonRatio();
    m.mooneyRivlin = parameters;
    detail::checkMaterialAt(cursor_, m);
    raw_.materials.push_back(std::move(m));
  }

  void readSet(const std::string& name, bool vertexSet) {
    auto& names = vertexSet ? vertexSetNames_ : elementSetNames_;
    if (!names.insert(name).second) cursor_.fail("set '" + name + "' is defined twice");
    PendingSet set;
    set.name = name;
    set.vertexSet = vertexSet;
    while (cursor_.next()) {
      if (isKeywordLine(cursor_.line())) {
        cursor_.pushBack();
        break;
      }
      for (const std::string_view token : detail::splitTokens(cursor_.line(), true)) {
        long long id = 0;
        if (!detail::parseInteger(token, id)) {
          cursor_.fail("set '" + name + "': expected a " + (vertexSet ? "vertex" : "element") + " index, got '" +
                       std::string(token) + "'");
        }
        set.ids.emplace_back(id, cursor_.location());
      }
      // A set's members cannot outnumber the bytes of the input, so this stays bounded.
    }
    sets_.push_back(std::move(set));
  }

  void readRegion() {
    while (cursor_.next()) {
      if (isKeywordLine(cursor_.line())) {
        cursor_.pushBack();
        break;
      }
      const auto tokens = detail::splitTokens(cursor_.line(), true);
      if (tokens.size() != 2) {
        cursor_.fail("*REGION line needs 'set, material', got " + std::to_string(tokens.size()) + " fields");
      }
      regions_.push_back({std::string(tokens[0]), std::string(tokens[1]), cursor_.location()});
    }
  }

  void resolveSetsAndRegions() {
    const std::map<std::string, std::vector<int>> regionSets = resolveSets();
    for (const RegionLine& region : regions_) {
      std::vector<int> all;
      const std::vector<int>& members = regionMembers(region, regionSets, all);
      const int material = regionMaterial(region);
      // Later *REGION lines win where sets overlap.
      for (int e : members) raw_.elementMaterials[static_cast<std::size_t>(e)] = material;
    }
  }

  /// Checks the ids of every set and stores the sets in raw_ (0-based); returns the
  /// element sets a *REGION line may name (material sets included).
  std::map<std::string, std::vector<int>> resolveSets() {
    const auto numElements = static_cast<long long>(raw_.numElements());
    const auto numVertices = static_cast<long long>(raw_.vertexFileIds.size());
    std::map<std::string, std::vector<int>> regionSets;
    for (PendingSet& set : sets_) {
      const long long limit = set.vertexSet ? numVertices : numElements;
      std::vector<int> members;
      members.reserve(set.ids.size());
      for (const auto& [id, where] : set.ids) {
        if (id < 1 || id > limit) {
          cursor_.failAt(where, "set '" + set.name + "' lists " + (set.vertexSet ? "vertex " : "element ") +
                                    std::to_string(id) + ", outside [1, " + std::to_string(limit) + "]");
        }
        members.push_back(static_cast<int>(id - 1));
      }
      if (set.vertexSet) {
        raw_.vertexSets[set.name] = std::move(members);
      } else {
        regionSets[set.name] = members;
        if (set.name.rfind(kMaterialSetPrefix, 0) != 0) raw_.elementSets[set.name] = std::move(members);
      }
    }
    return regionSets;
  }

  /// The elements of the set a *REGION line names (allElements: every element, built in all).
  const std::vector<int>& regionMembers(const RegionLine& region,
                                        const std::map<std::string, std::vector<int>>& regionSets,
                                        std::vector<int>& all) const {
    if (auto it = regionSets.find(region.setName); it != regionSets.end()) {
      return it->second;
    }
    if (region.setName != "allElements") {
      std::string known = "allElements";
      for (const auto& [n, s] : raw_.elementSets) known += ", " + n;
      cursor_.failAt(region.location, "*REGION refers to unknown set '" + region.setName + "' (known: " + known + ")");
    }
    all.resize(raw_.numElements());
    for (std::size_t e = 0; e < all.size(); ++e) all[e] = static_cast<int>(e);
    return all;
  }

  /// The index of the material a *REGION line names (the last of that name).
  int regionMaterial(const RegionLine& region) const {
    int material = -1;
    for (std::size_t m = 0; m < raw_.materials.size(); ++m) {
      if (raw_.materials[m].name == region.materialName) material = static_cast<int>(m);
    }
    if (material < 0) {
      std::string known;
      for (const Material& m : raw_.materials) known += (known.empty() ? "" : ", ") + m.name;
      cursor_.failAt(region.location, "*REGION refers to unknown material '" + region.materialName +
                                          "' (known: " + (known.empty() ? "none" : known) + ")");
    }
    return material;
  }

  LineCursor cursor_;
  detail::RawMesh raw_;
  bool haveVertices_ = false;
  bool haveElements_ = false;
  std::set<std::string> materialNames_;
  std::set<std::string> elementSetNames_;
  std::set<std::string> vertexSetNames_;
  std::vector<PendingSet> sets_;
  std::vector<RegionLine> regions_;
};

}  // namespace

TetMesh readVeg(const std::filesystem::path& path, const MeshReadOptions& options, MeshReadReport* report) {
  MeshReadReport local;
  MeshReadReport& out = report ? *report : local;
  out = MeshReadReport{};
  out.format = "veg";
  const detail::FlatText flat = detail::loadFlatText(path, true);
  VegParser parser(flat);
  return parser.parse(options, out);
}

}  // namespace asyncfem
