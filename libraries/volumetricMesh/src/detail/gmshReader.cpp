// SPDX-License-Identifier: BSD-3-Clause
// Gmsh .msh reader, ASCII versions 2.2 and 4.1; see docs/file-formats.md.
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <map>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "detail/rawMesh.hpp"
#include "detail/textInput.hpp"

namespace asyncfem {

namespace {

using detail::LineCursor;

constexpr long long kTetrahedron = 4;      // 4-node tetrahedron
constexpr long long kHexahedron = 5;       // 8-node hexahedron (VTK's vertex order)
constexpr long long kQuadraticTet = 11;    // 10-node tetrahedron
constexpr long long kQuadraticHex = 12;    // 27-node hexahedron
constexpr long long kSerendipityHex = 17;  // 20-node hexahedron
// Every element of a volume entity joins each of the entity's physical groups, so the
// set memberships are (elements) x (groups per entity): a bound on the latter keeps
// them linear in the file size.
constexpr std::size_t kMaxPhysicalTagsPerEntity = 64;

/// The dimension of a Gmsh element type: 0 for the point, 1 for lines, 2 for triangles
/// and quadrangles (of any order), 3 for the rest (volumes).
int elementTypeDimension(long long type) {
  switch (type) {
    case 15:
      return 0;
    case 1:
    case 8:
    case 26:
    case 27:
    case 28:
      return 1;
    case 2:
    case 3:
    case 9:
    case 10:
    case 16:
    case 20:
    case 21:
    case 22:
    case 23:
    case 24:
    case 25:
      return 2;
    default:
      return 3;
  }
}

/// A physical group of Gmsh: its dimension and tag (tags are per dimension).
using PhysicalGroup = std::pair<long long, long long>;

/// The name of a physical group without a $PhysicalNames entry.
std::string unnamedGroup(const PhysicalGroup& group) {
  static const char* const kinds[] = {"physical_point_", "physical_curve_", "physical_surface_", "physical_"};
  return kinds[group.first] + std::to_string(group.second);
}

std::string typeName(long long type) { return type == kHexahedron ? "8-node hexahedron" : "4-node tetrahedron"; }

class GmshParser {
 public:
  explicit GmshParser(const detail::FlatText& flat) : cursor_(flat, false) {}

  TetMesh parse(const MeshReadOptions& options, MeshReadReport& report) {
    if (!cursor_.next()) cursor_.failAtEnd("empty file: not a Gmsh mesh");
    if (cursor_.line() != "$MeshFormat") {
      cursor_.fail("not a Gmsh ASCII file: expected $MeshFormat, got '" + std::string(cursor_.line().substr(0, 40)) +
                   "'");
    }
    readMeshFormat();
    report.format = version41_ ? "gmsh 4.1" : "gmsh 2.2";
    readSections();
    reportIgnoredElements(report);
    for (const auto& [tag, members] : physicalElements_) {
      auto& set = raw_.elementSets[groupName({3, tag})];
      set.insert(set.end(), members.begin(), members.end());
    }
    for (const auto& [group, members] : physicalVertices_) {
      auto& set = raw_.vertexSets[groupName(group)];
      set.insert(set.end(), members.begin(), members.end());
    }
    return detail::finishMesh(std::move(raw_), cursor_, options, report, detail::MissingMaterialPolicy::FormatDefault);
  }

 private:
  /// The sections after $MeshFormat, up to the end of the file.
  void readSections() {
    bool haveNodes = false;
    bool haveElements = false;
    while (cursor_.next()) {
      const std::string_view line = cursor_.line();
      if (line.front() != '$')
        cursor_.fail("expected a section such as $Nodes, got '" + std::string(line.substr(0, 40)) + "'");
      const std::string section(line.substr(1));
      if (section == "PhysicalNames") {
        readPhysicalNames();
      } else if (section == "Entities" && version41_) {
        readEntities();
      } else if (section == "Nodes") {
        if (haveNodes) cursor_.fail("second $Nodes section");
        haveNodes = true;
        version41_ ? readNodes41() : readNodes22();
      } else if (section == "Elements") {
        if (haveElements) cursor_.fail("second $Elements section");
        if (!haveNodes) cursor_.fail("$Elements before $Nodes");
        haveElements = true;
        version41_ ? readElements41() : readElements22();
      } else if (section.rfind("End", 0) == 0) {
        cursor_.fail("'" + std::string(line) + "' without its opening section");
      } else {
        skipSection(section);
      }
    }
    if (!haveNodes) cursor_.failAtEnd("no $Nodes section");
    if (!haveElements) cursor_.failAtEnd("no $Elements section");
  }

  /// Counts the elements that are neither 4-node tetrahedra nor 8-node hexahedra into
  /// report, with a warning by type; a file of second-order volume elements only is an error.
  void reportIgnoredElements(MeshReadReport& report) const {
    report.ignoredElements = ignoredTotal_;
    if (ignoredTotal_ > 0) {
      std::string types;
      for (const auto& [type, count] : ignoredByType_) {
        types += (types.empty() ? "" : ", ") + std::to_string(count) + " of type " + std::to_string(type);
      }
      report.warnings.push_back("ignored " + std::to_string(ignoredTotal_) + " element(s) that are not " +
                                (raw_.kind == ElementKind::hexahedron ? "8-node hexahedra" : "4-node tetrahedra") +
                                " (" + types + ")");
    }
    if (raw_.numElements() == 0 && ignoredByType_.count(kQuadraticTet)) {
      cursor_.failAtEnd("only 10-node tetrahedra (type 11) found: export a first-order mesh (Mesh.ElementOrder = 1)");
    }
    if (raw_.numElements() == 0 && (ignoredByType_.count(kQuadraticHex) || ignoredByType_.count(kSerendipityHex))) {
      cursor_.failAtEnd(
          "only second-order hexahedra (type 12 or 17) found: export a first-order mesh (Mesh.ElementOrder = 1)");
    }
  }

  /// The set name of a physical group: its $PhysicalNames name, or unnamedGroup().
  std::string groupName(const PhysicalGroup& group) const {
    auto it = physicalNames_.find(group);
    return it != physicalNames_.end() ? it->second : unnamedGroup(group);
  }

  std::vector<std::string_view> nextRecord(const std::string& what) {
    if (!cursor_.next()) cursor_.failAtEnd("file ends inside " + what);
    if (cursor_.line().front() == '$')
      cursor_.fail("section ends early: expected " + what + ", got '" + std::string(cursor_.line()) + "'");
    return detail::splitTokens(cursor_.line(), false);
  }

  void expectEnd(const std::string& section, const std::string& overflowMessage) {
    if (!cursor_.next()) cursor_.failAtEnd("missing $End" + section);
    if (cursor_.line() != "$End" + section) {
      if (cursor_.line().front() != '$') cursor_.fail(overflowMessage);
      cursor_.fail("expected $End" + section + ", got '" + std::string(cursor_.line()) + "'");
    }
  }

  void skipSection(const std::string& section) {
    const auto start = cursor_.location();
    const std::string end = "$End" + section;
    while (cursor_.next()) {
      if (cursor_.line() == end) return;
    }
    cursor_.failAt(start, "section $" + section + " has no " + end);
  }

  void readMeshFormat() {
    const auto tokens = nextRecord("the $MeshFormat line 'version fileType dataSize'");
    if (tokens.size() != 3)
      cursor_.fail("$MeshFormat needs 'version fileType dataSize', got " + std::to_string(tokens.size()) + " fields");
    if (tokens[1] == "1") {
      cursor_.fail(
          "binary .msh files are not supported: save the mesh as ASCII (Gmsh: Mesh.Binary = 0, "
          "or File > Export without 'Save in binary format')");
    }
    if (tokens[1] != "0") cursor_.fail("$MeshFormat file type must be 0 (ASCII), got '" + std::string(tokens[1]) + "'");
    if (tokens[0] == "4.1") {
      version41_ = true;
    } else if (tokens[0] != "2.2") {
      cursor_.fail(
          "unsupported Gmsh format version '" + std::string(tokens[0]) +
          "': this reader reads ASCII versions 2.2 and 4.1 (export as 'Version 4 ASCII' or 'Version 2 ASCII')");
    }
    expectEnd("MeshFormat", "$MeshFormat has more than one line");
  }

  void readPhysicalNames() {
    const auto header = nextRecord("the physical name count");
    if (header.size() != 1) cursor_.fail("$PhysicalNames needs a count line");
    const long long count = detail::integerAt(cursor_, header[0], "physical name count");
    cursor_.checkCountFits(count, 7, "physical names");
    for (long long i = 0; i < count; ++i) {
      const auto tokens = nextRecord("'dim tag \"name\"'");
      if (tokens.size() < 3) cursor_.fail("physical name line needs 'dim tag \"name\"'");
      const long long dim = detail::integerAt(cursor_, tokens[0], "physical name dimension");
      const long long tag = detail::integerAt(cursor_, tokens[1], "physical tag");
      // The name is the rest of the line, in quotes, and may contain spaces.
      std::string_view rest = cursor_.line().substr(static_cast<std::size_t>(tokens[2].data() - cursor_.line().data()));
      rest = detail::trim(rest);
      if (!rest.empty() && rest.front() == '"') {
        if (rest.size() < 2 || rest.back() != '"') {
          cursor_.fail("physical group " + std::to_string(tag) + ": its name has no closing quote");
        }
        rest = rest.substr(1, rest.size() - 2);
      }
      if (rest.empty()) cursor_.fail("physical group " + std::to_string(tag) + " has an empty name");
      if (dim < 0 || dim > 3) cursor_.fail("physical name dimension must be 0..3, got " + std::to_string(dim));
      physicalNames_[{dim, tag}] = std::string(rest);
    }
    expectEnd("PhysicalNames", "$PhysicalNames has more lines than its count " + std::to_string(count));
  }

  void readEntities() {
    const auto header = nextRecord("'numPoints numCurves numSurfaces numVolumes'");
    if (header.size() != 4) cursor_.fail("$Entities header needs 4 counts, got " + std::to_string(header.size()));
    long long lower = 0;
    long long counts[4];
    for (std::size_t i = 0; i < 4; ++i) {
      counts[i] = detail::integerAt(cursor_, header[i], "$Entities count");
      cursor_.checkCountFits(counts[i], 7, "entities");
      lower += counts[i];
    }
    cursor_.checkCountFits(lower, 7, "entities");
    for (long long dim = 0; dim < 4; ++dim) {
      for (long long i = 0; i < counts[dim]; ++i) readEntity(dim);
    }
    expectEnd("Entities", "$Entities has more lines than its counts");
  }

  /// One entity line of $Entities: a point is 'tag x y z numPhysicalTags tags...', a curve,
  /// surface or volume 'tag minX minY minZ maxX maxY maxZ numPhysicalTags tags... (bounding
  /// entities)'. Keeps the entity's physical tags.
  void readEntity(long long dim) {
    static const char* const kinds[] = {"point", "curve", "surface", "volume"};
    const std::string kind = std::string(kinds[dim]) + " entity";
    const std::size_t coordinates = dim == 0 ? 3 : 6;
    const auto tokens = nextRecord("a " + kind + " line");
    if (tokens.size() < coordinates + 2) {
      cursor_.fail(kind + " line needs 'tag " + (dim == 0 ? "x y z" : "minX minY minZ maxX maxY maxZ") +
                   " numPhysicalTags ...'");
    }
    const long long tag = detail::integerAt(cursor_, tokens[0], kind + " tag");
    for (std::size_t c = 1; c <= coordinates; ++c) detail::doubleAt(cursor_, tokens[c], kind + " coordinates");
    const std::size_t first = coordinates + 2;
    const long long numPhysicals = detail::integerAt(cursor_, tokens[first - 1], kind + " physical tag count");
    if (numPhysicals < 0 || static_cast<std::size_t>(numPhysicals) > tokens.size() - first) {
      cursor_.fail(kind + " " + std::to_string(tag) + " claims " + std::to_string(numPhysicals) +
                   " physical tags but the line has fewer");
    }
    auto& physicals = entityPhysicals_[{dim, tag}];
    for (std::size_t p = 0; p < static_cast<std::size_t>(numPhysicals); ++p) {
      physicals.push_back(detail::integerAt(cursor_, tokens[first + p], "physical tag"));
    }
    // A tag listed twice (or an entity listed twice) adds nothing.
    std::sort(physicals.begin(), physicals.end());
    physicals.erase(std::unique(physicals.begin(), physicals.end()), physicals.end());
    if (physicals.size() > kMaxPhysicalTagsPerEntity) {
      cursor_.fail(kind + " " + std::to_string(tag) + " is in " + std::to_string(physicals.size()) +
                   " physical groups; at most " + std::to_string(kMaxPhysicalTagsPerEntity) + " are supported");
    }
  }

  /// Adds the nodes of an element of dimension dim < 3 to the vertex sets of its physical
  /// groups (Gmsh physical surfaces, curves and points name boundary vertices).
  void addGroupNodes(long long dim, const std::vector<long long>& physicals, const std::string_view* nodeTokens,
                     std::size_t numNodes, long long elementTag) {
    for (std::size_t a = 0; a < numNodes; ++a) {
      const long long nodeTag = detail::integerAt(cursor_, nodeTokens[a], "element node");
      auto it = nodeIndex_.find(nodeTag);
      if (it == nodeIndex_.end()) {
        cursor_.fail("element " + std::to_string(elementTag) + " references node " + std::to_string(nodeTag) +
                     ", which $Nodes does not define");
      }
      for (long long p : physicals) physicalVertices_[{dim, p}].push_back(it->second);
    }
  }

  void addNode(long long tag, const std::string_view* coordinates) {
    if (tag < 1) cursor_.fail("node tag " + std::to_string(tag) + " must be a positive integer");
    const int index = static_cast<int>(raw_.vertexFileIds.size());
    if (!nodeIndex_.emplace(tag, index).second) cursor_.fail("duplicate node tag " + std::to_string(tag));
    raw_.vertexFileIds.push_back(tag);
    for (int c = 0; c < 3; ++c) {
      raw_.positions.push_back(
          detail::finiteDoubleAt(cursor_, coordinates[c], "node " + std::to_string(tag) + " coordinate"));
    }
  }

  void readNodes22() {
    const auto header = nextRecord("the node count");
    const auto headerAt = cursor_.location();
    if (header.size() != 1) cursor_.fail("$Nodes needs a count line");
    const long long count = detail::integerAt(cursor_, header[0], "node count");
    cursor_.checkCountFits(count, 7, "nodes");
    reserveNodes(count);
    for (long long i = 0; i < count; ++i) {
      if (!cursor_.next() || cursor_.line().front() == '$') {
        cursor_.failAt(
            headerAt, "$Nodes says " + std::to_string(count) + " nodes, but the section has only " + std::to_string(i));
      }
      const auto tokens = detail::splitTokens(cursor_.line(), false);
      if (tokens.size() != 4)
        cursor_.fail("node line needs 'tag x y z', got " + std::to_string(tokens.size()) + " fields");
      addNode(detail::integerAt(cursor_, tokens[0], "node tag"), &tokens[1]);
    }
    expectEnd("Nodes", "$Nodes says " + std::to_string(count) + " nodes, but there are more node lines");
  }

  void reserveNodes(long long count) {
    raw_.vertexFileIds.reserve(static_cast<std::size_t>(count));
    raw_.positions.reserve(3 * static_cast<std::size_t>(count));
  }

  void readNodes41() {
    const auto header = nextRecord("'numEntityBlocks numNodes minNodeTag maxNodeTag'");
    const auto headerAt = cursor_.location();
    if (header.size() != 4) cursor_.fail("$Nodes header needs 'numEntityBlocks numNodes minNodeTag maxNodeTag'");
    const long long blocks = detail::integerAt(cursor_, header[0], "node block count");
    const long long count = detail::integerAt(cursor_, header[1], "node count");
    cursor_.checkCountFits(blocks, 7, "node blocks");
    cursor_.checkCountFits(count, 7, "nodes");
    reserveNodes(count);
    long long read = 0;
    for (long long b = 0; b < blocks; ++b) {
      read += readNodeBlock(headerAt, count, read);
    }
    if (read != count) {
      cursor_.failAt(headerAt,
                     "$Nodes says " + std::to_string(count) + " nodes, but its blocks hold " + std::to_string(read));
    }
    expectEnd("Nodes", "$Nodes has more lines than its blocks describe");
  }

  /// Reads one node block of a 4.1 $Nodes section (the tags, then the coordinates) after
  /// `read` of the section's `count` nodes; returns the nodes in the block.
  long long readNodeBlock(detail::Location headerAt, long long count, long long read) {
    const auto block = nextRecord("a node block header 'entityDim entityTag parametric numNodesInBlock'");
    if (block.size() != 4) cursor_.fail("node block header needs 'entityDim entityTag parametric numNodesInBlock'");
    const long long dim = detail::integerAt(cursor_, block[0], "node block entity dimension");
    const long long parametric = detail::integerAt(cursor_, block[2], "node block parametric flag");
    const long long inBlock = detail::integerAt(cursor_, block[3], "node block size");
    if (dim < 0 || dim > 3) cursor_.fail("node block entity dimension must be 0..3, got " + std::to_string(dim));
    if (parametric != 0 && parametric != 1) cursor_.fail("node block parametric flag must be 0 or 1");
    cursor_.checkCountFits(inBlock, 7, "nodes in the block");
    if (read + inBlock > count)
      cursor_.failAt(headerAt, "$Nodes says " + std::to_string(count) + " nodes, but its blocks hold more");
    std::vector<long long> tags(static_cast<std::size_t>(inBlock));
    for (auto& tag : tags) {
      const auto tokens = nextRecord("a node tag");
      if (tokens.size() != 1)
        cursor_.fail("node block: expected one node tag per line, got " + std::to_string(tokens.size()) + " fields");
      tag = detail::integerAt(cursor_, tokens[0], "node tag");
    }
    const std::size_t fields = 3 + static_cast<std::size_t>(parametric ? dim : 0);
    for (long long tag : tags) {
      const auto tokens = nextRecord("node coordinates");
      if (tokens.size() != fields) {
        cursor_.fail("node " + std::to_string(tag) + ": expected " + std::to_string(fields) + " coordinates, got " +
                     std::to_string(tokens.size()));
      }
      addNode(tag, tokens.data());
    }
    return inBlock;
  }

  /// Appends one tetrahedron (type 4) or hexahedron (type 5) given its Gmsh element tag
  /// and node tags. A mesh holds one element kind, so the first volume element fixes it
  /// and an element of the other kind is an error.
  void addVolumeElement(long long type, long long tag, const std::string_view* nodeTokens) {
    const ElementKind kind = type == kHexahedron ? ElementKind::hexahedron : ElementKind::tetrahedron;
    if (raw_.numElements() == 0) {
      raw_.kind = kind;
    } else if (kind != raw_.kind) {
      cursor_.fail("element " + std::to_string(tag) + " is " +
                   (kind == ElementKind::hexahedron ? "an 8-node hexahedron" : "a 4-node tetrahedron") +
                   ", but the file's first volume element was " +
                   (raw_.kind == ElementKind::hexahedron ? "a hexahedron" : "a tetrahedron") +
                   ": mixed tetrahedral and hexahedral meshes are not supported (a mesh holds one element kind; mesh "
                   "the volume with one kind, e.g. Gmsh's Mesh.SubdivisionAlgorithm = 2 makes all hexahedra)");
    }
    if (kind == ElementKind::hexahedron) {
      raw_.hexahedra.push_back(elementNodes<8>(tag, nodeTokens));
    } else {
      raw_.elements.push_back(elementNodes<4>(tag, nodeTokens));
    }
    if (!elementTags_.insert(tag).second) cursor_.fail("duplicate element tag " + std::to_string(tag));
    raw_.elementLocations.push_back(cursor_.location());
    raw_.elementFileIds.push_back(tag);
    raw_.elementMaterials.push_back(-1);
  }

  /// The N vertex indices of element tag from its node tags, checked to exist and differ.
  template <std::size_t N>
  std::array<int, N> elementNodes(long long tag, const std::string_view* nodeTokens) {
    const std::string name = "element " + std::to_string(tag);
    std::array<int, N> t{};
    for (std::size_t a = 0; a < N; ++a) {
      const long long nodeTag = detail::integerAt(cursor_, nodeTokens[a], name + " node");
      auto it = nodeIndex_.find(nodeTag);
      if (it == nodeIndex_.end())
        cursor_.fail(name + " references node " + std::to_string(nodeTag) + ", which $Nodes does not define");
      for (std::size_t b = 0; b < a; ++b) {
        if (t[b] == it->second) cursor_.fail(name + " uses node " + std::to_string(nodeTag) + " twice");
      }
      t[a] = it->second;
    }
    return t;
  }

  void ignore(long long type) {
    ++ignoredTotal_;
    ++ignoredByType_[type];
  }

  void readElements22() {
    const auto header = nextRecord("the element count");
    const auto headerAt = cursor_.location();
    if (header.size() != 1) cursor_.fail("$Elements needs a count line");
    const long long count = detail::integerAt(cursor_, header[0], "element count");
    cursor_.checkCountFits(count, 7, "elements");
    for (long long i = 0; i < count; ++i) {
      if (!cursor_.next() || cursor_.line().front() == '$') {
        cursor_.failAt(headerAt, "$Elements says " + std::to_string(count) + " elements, but the section has only " +
                                     std::to_string(i));
      }
      const auto tokens = detail::splitTokens(cursor_.line(), false);
      if (tokens.size() < 3) cursor_.fail("element line needs 'tag type numTags tags... nodes...'");
      const long long tag = detail::integerAt(cursor_, tokens[0], "element tag");
      const long long type = detail::integerAt(cursor_, tokens[1], "element " + std::to_string(tag) + " type");
      const long long numTags = detail::integerAt(cursor_, tokens[2], "element " + std::to_string(tag) + " tag count");
      if (numTags < 0 || static_cast<std::size_t>(numTags) > tokens.size() - 3) {
        cursor_.fail("element " + std::to_string(tag) + " claims " + std::to_string(numTags) +
                     " tags but the line has fewer fields");
      }
      if (type != kTetrahedron && type != kHexahedron) {
        ignore(type);
        const long long dim = elementTypeDimension(type);
        if (numTags >= 1 && dim < 3) {
          const long long physical =
              detail::integerAt(cursor_, tokens[3], "element " + std::to_string(tag) + " physical tag");
          const std::size_t nodesAt = 3 + static_cast<std::size_t>(numTags);
          if (physical != 0) addGroupNodes(dim, {physical}, &tokens[nodesAt], tokens.size() - nodesAt, tag);
        }
        continue;
      }
      const std::size_t expected = 3 + static_cast<std::size_t>(numTags) + (type == kHexahedron ? 8 : 4);
      if (tokens.size() != expected) {
        cursor_.fail("element " + std::to_string(tag) + " (" + typeName(type) + ") needs " + std::to_string(expected) +
                     " fields, got " + std::to_string(tokens.size()));
      }
      addVolumeElement(type, tag, &tokens[3 + static_cast<std::size_t>(numTags)]);
      if (numTags >= 1) {
        const long long physical =
            detail::integerAt(cursor_, tokens[3], "element " + std::to_string(tag) + " physical tag");
        if (physical != 0) physicalElements_[physical].push_back(static_cast<int>(raw_.numElements()) - 1);
      }
    }
    expectEnd("Elements", "$Elements says " + std::to_string(count) + " elements, but there are more element lines");
  }

  void readElements41() {
    const auto header = nextRecord("'numEntityBlocks numElements minElementTag maxElementTag'");
    const auto headerAt = cursor_.location();
    if (header.size() != 4)
      cursor_.fail("$Elements header needs 'numEntityBlocks numElements minElementTag maxElementTag'");
    const long long blocks = detail::integerAt(cursor_, header[0], "element block count");
    const long long count = detail::integerAt(cursor_, header[1], "element count");
    cursor_.checkCountFits(blocks, 7, "element blocks");
    cursor_.checkCountFits(count, 3, "elements");
    long long read = 0;
    for (long long b = 0; b < blocks; ++b) {
      read += readElementBlock(headerAt, count, read);
    }
    if (read != count) {
      cursor_.failAt(headerAt, "$Elements says " + std::to_string(count) + " elements, but its blocks hold " +
                                   std::to_string(read));
    }
    expectEnd("Elements", "$Elements has more lines than its blocks describe");
  }

  /// Reads one element block of a 4.1 $Elements section after `read` of the section's
  /// `count` elements; returns the elements in the block.
  long long readElementBlock(detail::Location headerAt, long long count, long long read) {
    const auto block = nextRecord("an element block header 'entityDim entityTag elementType numElementsInBlock'");
    if (block.size() != 4)
      cursor_.fail("element block header needs 'entityDim entityTag elementType numElementsInBlock'");
    const long long dim = detail::integerAt(cursor_, block[0], "element block entity dimension");
    const long long entity = detail::integerAt(cursor_, block[1], "element block entity tag");
    const long long type = detail::integerAt(cursor_, block[2], "element block type");
    const long long inBlock = detail::integerAt(cursor_, block[3], "element block size");
    cursor_.checkCountFits(inBlock, 3, "elements in the block");
    if (read + inBlock > count)
      cursor_.failAt(headerAt, "$Elements says " + std::to_string(count) + " elements, but its blocks hold more");
    const std::vector<long long>* physicals = nullptr;
    if (auto it = entityPhysicals_.find({dim, entity}); it != entityPhysicals_.end()) physicals = &it->second;
    for (long long i = 0; i < inBlock; ++i) {
      const auto tokens = nextRecord("an element line");
      if (type != kTetrahedron && type != kHexahedron) {
        ignore(type);
        if (physicals && dim >= 0 && dim < 3 && tokens.size() > 1) {
          const long long tag = detail::integerAt(cursor_, tokens[0], "element tag");
          addGroupNodes(dim, *physicals, &tokens[1], tokens.size() - 1, tag);
        }
        continue;
      }
      const std::size_t expected = type == kHexahedron ? 9 : 5;
      if (tokens.size() != expected) {
        cursor_.fail(typeName(type) + " line needs 'tag n1 ... n" + std::to_string(expected - 1) + "', got " +
                     std::to_string(tokens.size()) + " fields");
      }
      addVolumeElement(type, detail::integerAt(cursor_, tokens[0], "element tag"), &tokens[1]);
      if (physicals && dim == 3) {
        for (long long p : *physicals) physicalElements_[p].push_back(static_cast<int>(raw_.numElements()) - 1);
      }
    }
    return inBlock;
  }

  LineCursor cursor_;
  detail::RawMesh raw_;
  bool version41_ = false;
  std::unordered_map<long long, int> nodeIndex_;
  std::unordered_set<long long> elementTags_;
  std::map<PhysicalGroup, std::string> physicalNames_;
  std::map<PhysicalGroup, std::vector<long long>> entityPhysicals_;  ///< (dim, entity tag) -> physical tags
  std::map<long long, std::vector<int>> physicalElements_;           ///< volume group tag -> elements
  std::map<PhysicalGroup, std::vector<int>> physicalVertices_;       ///< lower-dimensional group -> nodes
  std::map<long long, long long> ignoredByType_;
  int ignoredTotal_ = 0;
};

}  // namespace

TetMesh readGmsh(const std::filesystem::path& path, const MeshReadOptions& options, MeshReadReport* report) {
  MeshReadReport local;
  MeshReadReport& out = report ? *report : local;
  out = MeshReadReport{};
  out.format = "gmsh";
  const detail::FlatText flat = detail::loadFlatText(path, false);
  GmshParser parser(flat);
  return parser.parse(options, out);
}

}  // namespace asyncfem
