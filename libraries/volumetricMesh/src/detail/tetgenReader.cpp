// SPDX-License-Identifier: BSD-3-Clause
// TetGen .node/.ele reader; see docs/file-formats.md.
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "detail/rawMesh.hpp"
#include "detail/textInput.hpp"

namespace asyncfem {

namespace {

using detail::LineCursor;

/// Attributes per vertex beyond this are surely a corrupt header.
constexpr long long kMaxAttributes = 1000;

std::vector<std::string_view> headerTokens(LineCursor& cursor, const std::string& expected) {
  if (!cursor.next()) cursor.failAtEnd("missing header line '" + expected + "'");
  return detail::splitTokens(cursor.line(), false);
}

long long headerField(const LineCursor& cursor, const std::vector<std::string_view>& tokens, std::size_t i,
                      long long fallback, const std::string& what) {
  return i < tokens.size() ? detail::integerAt(cursor, tokens[i], what) : fallback;
}

/// The .node header: vertex count, attributes per vertex, boundary marker flag.
struct NodeHeader {
  long long count = 0;
  long long attributes = 0;
  long long markers = 0;
  detail::Location at;
};

NodeHeader readNodeHeader(LineCursor& cursor) {
  const auto header = headerTokens(cursor, "<count> 3 <attributes> <boundaryMarker>");
  NodeHeader node;
  node.at = cursor.location();
  if (header.size() > 4)
    cursor.fail(".node header needs '<count> 3 <attributes> <boundaryMarker>', got " + std::to_string(header.size()) +
                " fields");
  node.count = headerField(cursor, header, 0, 0, ".node vertex count");
  const long long dimension = headerField(cursor, header, 1, 3, ".node dimension");
  node.attributes = headerField(cursor, header, 2, 0, ".node attribute count");
  node.markers = headerField(cursor, header, 3, 0, ".node boundary marker flag");
  if (dimension != 3) cursor.fail(".node dimension must be 3, got " + std::to_string(dimension));
  if (node.attributes < 0 || node.attributes > kMaxAttributes)
    cursor.fail(".node attribute count " + std::to_string(node.attributes) + " is out of range");
  if (node.markers != 0 && node.markers != 1)
    cursor.fail(".node boundary marker flag must be 0 or 1, got " + std::to_string(node.markers));
  cursor.checkCountFits(node.count, 7, "vertices");
  return node;
}

/// Reads one vertex line (already split into the right number of tokens) into raw; the
/// first line sets the numbering base.
void readVertexLine(const LineCursor& cursor, const std::vector<std::string_view>& tokens, bool first,
                    const NodeHeader& header, long long& base, std::vector<char>& seen, detail::RawMesh& raw) {
  const long long count = header.count;
  const long long id = detail::integerAt(cursor, tokens[0], "vertex index");
  if (first) {
    if (id != 0 && id != 1)
      cursor.fail("the first vertex index must be 0 or 1 (it sets the numbering base), got " + std::to_string(id));
    base = id;
  }
  if (id < base || id >= base + count) {
    cursor.fail("vertex index " + std::to_string(id) + " is outside [" + std::to_string(base) + ", " +
                std::to_string(base + count - 1) + "]");
  }
  const auto v = static_cast<std::size_t>(id - base);
  if (seen[v]) cursor.fail("duplicate vertex index " + std::to_string(id));
  seen[v] = 1;
  raw.vertexFileIds[v] = id;
  for (std::size_t c = 0; c < 3; ++c) {
    raw.positions[3 * v + c] =
        detail::finiteDoubleAt(cursor, tokens[c + 1], "vertex " + std::to_string(id) + " coordinate");
  }
  for (std::size_t a = 4; a < 4 + static_cast<std::size_t>(header.attributes); ++a) {
    detail::doubleAt(cursor, tokens[a], "vertex " + std::to_string(id) + " attribute");
  }
  if (header.markers) detail::integerAt(cursor, tokens.back(), "vertex " + std::to_string(id) + " boundary marker");
}

/// Reads the .node file into raw; returns the numbering base (0 or 1).
long long readNodes(LineCursor& cursor, detail::RawMesh& raw) {
  const NodeHeader header = readNodeHeader(cursor);
  const long long count = header.count;
  const auto n = static_cast<std::size_t>(count);
  const std::size_t fields = 4 + static_cast<std::size_t>(header.attributes + header.markers);
  raw.positions.assign(3 * n, 0.0);
  raw.vertexFileIds.resize(n);
  std::vector<char> seen(n, 0);
  long long base = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!cursor.next()) {
      cursor.failAt(header.at, ".node header says " + std::to_string(count) + " vertices, but the file has only " +
                                   std::to_string(i));
    }
    const auto tokens = detail::splitTokens(cursor.line(), false);
    if (tokens.size() != fields) {
      cursor.fail("vertex line needs " + std::to_string(fields) + " fields (index x y z, " +
                  std::to_string(header.attributes) + " attributes, " + std::to_string(header.markers) +
                  " marker), got " + std::to_string(tokens.size()));
    }
    readVertexLine(cursor, tokens, i == 0, header, base, seen, raw);
  }
  if (cursor.next()) {
    cursor.fail(".node header says " + std::to_string(count) + " vertices, but there are more vertex lines");
  }
  return base;
}

/// The .ele header: element count, nodes per tetrahedron (4 or 10), region attribute flag.
struct EleHeader {
  long long count = 0;
  long long nodesPerTet = 4;
  long long region = 0;
  detail::Location at;
};

EleHeader readEleHeader(LineCursor& cursor) {
  const auto header = headerTokens(cursor, "<count> <4|10> <regionAttribute 0|1>");
  EleHeader ele;
  ele.at = cursor.location();
  if (header.size() > 3)
    cursor.fail(".ele header needs '<count> <4|10> <0|1>', got " + std::to_string(header.size()) + " fields");
  ele.count = headerField(cursor, header, 0, 0, ".ele element count");
  ele.nodesPerTet = headerField(cursor, header, 1, 4, ".ele nodes per tetrahedron");
  ele.region = headerField(cursor, header, 2, 0, ".ele region attribute flag");
  if (ele.nodesPerTet != 4 && ele.nodesPerTet != 10) {
    cursor.fail(".ele nodes per tetrahedron must be 4 or 10, got " + std::to_string(ele.nodesPerTet));
  }
  if (ele.region != 0 && ele.region != 1)
    cursor.fail(".ele region attribute flag must be 0 or 1, got " + std::to_string(ele.region));
  cursor.checkCountFits(ele.count, 9, "elements");
  return ele;
}

/// Which vertices some element uses as a corner, and which as an edge node (10-node tets).
struct VertexRoles {
  std::vector<char> corner;
  std::vector<char> edge;
};

/// Reads the vertices of element e (file index id) from tokens[1 ..] into raw.elements[e],
/// marking their roles.
void readElementVertices(const LineCursor& cursor, const std::vector<std::string_view>& tokens, std::size_t e,
                         long long id, const EleHeader& header, long long base, detail::RawMesh& raw,
                         VertexRoles& roles) {
  const auto numVertices = static_cast<long long>(raw.vertexFileIds.size());
  const std::string name = "element " + std::to_string(id);
  for (std::size_t a = 0; a < static_cast<std::size_t>(header.nodesPerTet); ++a) {
    const long long v = detail::integerAt(cursor, tokens[a + 1], name + " vertex");
    if (v < base || v >= base + numVertices) {
      cursor.fail(name + " references vertex " + std::to_string(v) + ", outside [" + std::to_string(base) + ", " +
                  std::to_string(base + numVertices - 1) + "]");
    }
    const int local = static_cast<int>(v - base);
    if (a < 4) {
      for (std::size_t b = 0; b < a; ++b) {
        if (raw.elements[e][b] == local) cursor.fail(name + " uses vertex " + std::to_string(v) + " twice");
      }
      raw.elements[e][a] = local;
      roles.corner[static_cast<std::size_t>(local)] = 1;
    } else {
      roles.edge[static_cast<std::size_t>(local)] = 1;
    }
  }
  if (header.region) {
    const double value = detail::finiteDoubleAt(cursor, tokens.back(), name + " region attribute");
    raw.elementSets["region_" + detail::formatDouble(value)].push_back(static_cast<int>(e));
  }
}

/// Reads a TetGen .face file (header '<count> <boundaryMarker 0|1>', then
/// 'index a b c [3 edge nodes of -o2] [marker] [2 adjacent tets of -nn]'): the vertices of
/// the faces with marker k != 0 form the vertex set "marker_<k>".
void readFaces(LineCursor& cursor, long long base, detail::RawMesh& raw) {
  const auto header = headerTokens(cursor, "<count> <boundaryMarker 0|1>");
  const detail::Location headerAt = cursor.location();
  if (header.empty() || header.size() > 2)
    cursor.fail(".face header needs '<count> <boundaryMarker 0|1>', got " + std::to_string(header.size()) + " fields");
  const long long count = headerField(cursor, header, 0, 0, ".face count");
  const long long markers = headerField(cursor, header, 1, 0, ".face boundary marker flag");
  if (markers != 0 && markers != 1)
    cursor.fail(".face boundary marker flag must be 0 or 1, got " + std::to_string(markers));
  cursor.checkCountFits(count, 7, "faces");
  const auto numVertices = static_cast<long long>(raw.vertexFileIds.size());
  for (long long i = 0; i < count; ++i) {
    if (!cursor.next()) {
      cursor.failAt(headerAt, ".face header says " + std::to_string(count) + " faces, but the file has only " +
                                  std::to_string(i));
    }
    const auto tokens = detail::splitTokens(cursor.line(), false);
    // Beyond 'index a b c' and the marker: 0, 2 (-nn), 3 (-o2) or 5 (both) fields.
    const long long extra = static_cast<long long>(tokens.size()) - 4 - markers;
    if (extra != 0 && extra != 2 && extra != 3 && extra != 5) {
      cursor.fail("face line needs 'index a b c" + std::string(markers ? " marker" : "") +
                  "' (with 3 edge nodes of -o2 before the marker and 2 adjacent tetrahedra of -nn after it), got " +
                  std::to_string(tokens.size()) + " fields");
    }
    const std::string name = "face " + std::string(tokens[0]);
    std::array<int, 3> vertices{};
    for (std::size_t a = 0; a < 3; ++a) {
      const long long v = detail::integerAt(cursor, tokens[a + 1], name + " vertex");
      if (v < base || v >= base + numVertices) {
        cursor.fail(name + " references vertex " + std::to_string(v) + ", outside [" + std::to_string(base) + ", " +
                    std::to_string(base + numVertices - 1) + "]");
      }
      vertices[a] = static_cast<int>(v - base);
    }
    if (!markers) continue;
    const std::size_t markerAt = 4 + ((extra == 3 || extra == 5) ? 3 : 0);
    const long long marker = detail::integerAt(cursor, tokens[markerAt], name + " boundary marker");
    if (marker == 0) continue;
    auto& set = raw.vertexSets["marker_" + std::to_string(marker)];
    set.insert(set.end(), vertices.begin(), vertices.end());
  }
  if (cursor.next()) cursor.fail(".face header says " + std::to_string(count) + " faces, but there are more lines");
}

/// Linear elements use only the corners of 10-node tetrahedra; vertices that only ever
/// were edge nodes would carry no mass or stiffness, so they are dropped and the rest
/// renumbered (with a warning in report).
void dropEdgeOnlyVertices(detail::RawMesh& raw, const VertexRoles& roles, MeshReadReport& report) {
  std::vector<int> newIndex(raw.vertexFileIds.size(), -1);
  int kept = 0;
  int dropped = 0;
  for (std::size_t v = 0; v < newIndex.size(); ++v) {
    if (roles.edge[v] && !roles.corner[v]) {
      ++dropped;
      continue;
    }
    newIndex[v] = kept;
    raw.vertexFileIds[static_cast<std::size_t>(kept)] = raw.vertexFileIds[v];
    for (std::size_t c = 0; c < 3; ++c)
      raw.positions[3 * static_cast<std::size_t>(kept) + c] = raw.positions[3 * v + c];
    ++kept;
  }
  raw.vertexFileIds.resize(static_cast<std::size_t>(kept));
  raw.positions.resize(3 * static_cast<std::size_t>(kept));
  for (auto& t : raw.elements)
    for (int& v : t) v = newIndex[static_cast<std::size_t>(v)];
  for (auto& [name, members] : raw.vertexSets) {
    std::vector<int> kept;
    for (const int v : members) {
      if (newIndex[static_cast<std::size_t>(v)] >= 0) kept.push_back(newIndex[static_cast<std::size_t>(v)]);
    }
    members = std::move(kept);
  }
  report.warnings.push_back(
      "10-node (quadratic) tetrahedra: using the 4 corner vertices of each element and "
      "dropping the " +
      std::to_string(dropped) + " edge-only nodes (vertices are renumbered)");
}

void readTets(LineCursor& cursor, detail::RawMesh& raw, long long base, MeshReadReport& report) {
  const EleHeader header = readEleHeader(cursor);
  const long long count = header.count;
  const auto n = static_cast<std::size_t>(count);
  const std::size_t fields = 1 + static_cast<std::size_t>(header.nodesPerTet + header.region);
  raw.elements.resize(n);
  raw.elementLocations.resize(n);
  raw.elementFileIds.resize(n);
  raw.elementMaterials.assign(n, -1);
  std::vector<char> seen(n, 0);
  VertexRoles roles{std::vector<char>(raw.vertexFileIds.size(), 0), std::vector<char>(raw.vertexFileIds.size(), 0)};
  for (std::size_t i = 0; i < n; ++i) {
    if (!cursor.next()) {
      cursor.failAt(header.at, ".ele header says " + std::to_string(count) + " elements, but the file has only " +
                                   std::to_string(i));
    }
    const auto tokens = detail::splitTokens(cursor.line(), false);
    if (tokens.size() != fields) {
      cursor.fail("element line needs " + std::to_string(fields) + " fields (index, " +
                  std::to_string(header.nodesPerTet) + " vertices" + (header.region ? ", region" : "") + "), got " +
                  std::to_string(tokens.size()));
    }
    const long long id = detail::integerAt(cursor, tokens[0], "element index");
    if (id < base || id >= base + count) {
      cursor.fail("element index " + std::to_string(id) + " is outside [" + std::to_string(base) + ", " +
                  std::to_string(base + count - 1) + "]");
    }
    const auto e = static_cast<std::size_t>(id - base);
    if (seen[e]) cursor.fail("duplicate element index " + std::to_string(id));
    seen[e] = 1;
    readElementVertices(cursor, tokens, e, id, header, base, raw, roles);
    raw.elementLocations[e] = cursor.location();
    raw.elementFileIds[e] = id;
  }
  if (cursor.next())
    cursor.fail(".ele header says " + std::to_string(count) + " elements, but there are more element lines");
  if (header.nodesPerTet == 10) dropEdgeOnlyVertices(raw, roles, report);
}

}  // namespace

TetMesh readTetGen(const std::filesystem::path& path, const MeshReadOptions& options, MeshReadReport* report) {
  MeshReadReport local;
  MeshReadReport& out = report ? *report : local;
  out = MeshReadReport{};
  out.format = "tetgen";
  std::filesystem::path base = path;
  const std::string extension = path.extension().string();
  if (detail::equalsIgnoreCase(extension, ".node") || detail::equalsIgnoreCase(extension, ".ele")) {
    base.replace_extension();
  }
  const std::filesystem::path nodePath = base.string() + ".node";
  const std::filesystem::path elePath = base.string() + ".ele";

  detail::RawMesh raw;
  const detail::FlatText nodeText = detail::loadFlatText(nodePath, false);
  LineCursor nodeCursor(nodeText, true);
  const long long numberingBase = readNodes(nodeCursor, raw);
  // The .face file is optional: TetGen writes it with -f, its markers name boundary parts.
  const std::filesystem::path facePath = base.string() + ".face";
  std::error_code ignored;
  if (std::filesystem::is_regular_file(facePath, ignored)) {
    const detail::FlatText faceText = detail::loadFlatText(facePath, false);
    LineCursor faceCursor(faceText, true);
    readFaces(faceCursor, numberingBase, raw);
  }
  const detail::FlatText eleText = detail::loadFlatText(elePath, false);
  LineCursor eleCursor(eleText, true);
  readTets(eleCursor, raw, numberingBase, out);
  return detail::finishMesh(std::move(raw), eleCursor, options, out, detail::MissingMaterialPolicy::FormatDefault);
}

}  // namespace asyncfem
