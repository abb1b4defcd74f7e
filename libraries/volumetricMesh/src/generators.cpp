// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <string>

namespace asyncfem {

namespace {

double signedVolume(const Eigen::Matrix3Xd& x, const Eigen::Vector4i& t) {
  const Eigen::Vector3d a = x.col(t[1]) - x.col(t[0]);
  const Eigen::Vector3d b = x.col(t[2]) - x.col(t[0]);
  const Eigen::Vector3d c = x.col(t[3]) - x.col(t[0]);
  return a.dot(b.cross(c)) / 6.0;
}

bool inside(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

/// Writes the six tetrahedra of the lattice cell whose low corner is `low` into columns
/// e .. e + 5 of elements (advancing e), positively oriented. Freudenthal (Kuhn) split: one
/// tet per permutation of the axes, walking from the cell's low corner to its high corner.
/// All cells use the same main diagonal, so the triangulations of shared faces match.
/// vertexId(i, j, k): the mesh vertex at lattice point (i, j, k); x: rest positions.
template <class VertexId>
void appendCellTets(const std::array<int, 3>& low, const VertexId& vertexId, const Eigen::Matrix3Xd& x,
                    Eigen::Matrix4Xi& elements, int& e) {
  static constexpr std::array<std::array<int, 3>, 6> permutations{
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (const auto& p : permutations) {
    std::array<int, 3> c = low;
    Eigen::Vector4i t;
    t[0] = vertexId(c[0], c[1], c[2]);
    for (int s = 0; s < 3; ++s) {
      ++c[static_cast<std::size_t>(p[static_cast<std::size_t>(s)])];
      t[s + 1] = vertexId(c[0], c[1], c[2]);
    }
    if (signedVolume(x, t) < 0.0) std::swap(t[2], t[3]);
    elements.col(e++) = t;
  }
}

/// Sets name to the elements, and the vertex set of the same name to their vertices.
void setElementAndVertexSet(TetMesh& mesh, const std::string& name, std::vector<int> elements) {
  std::vector<int> vertices;
  for (int el : elements)
    for (int a = 0; a < 4; ++a) vertices.push_back(mesh.elements()(a, el));
  mesh.setElementSet(name, std::move(elements));
  mesh.setVertexSet(name, std::move(vertices));
}

/// The box's elements by region: elementMaterials (region r's material is r + 1, later
/// regions win) and the elements of each region, by centroid.
std::vector<std::vector<int>> assignBoxRegions(const BoxMeshSpec& spec, const Eigen::Matrix3Xd& x,
                                               const Eigen::Matrix4Xi& elements, std::vector<int>& elementMaterials) {
  elementMaterials.assign(static_cast<std::size_t>(elements.cols()), 0);
  std::vector<std::vector<int>> regionElements(spec.regions.size());
  for (int el = 0; el < elements.cols(); ++el) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) centroid += 0.25 * x.col(elements(a, el));
    for (std::size_t r = 0; r < spec.regions.size(); ++r) {
      if (inside(centroid, spec.regions[r].min, spec.regions[r].max)) {
        // Later regions win the material; every containing region lists the element.
        elementMaterials[static_cast<std::size_t>(el)] = static_cast<int>(r) + 1;
        regionElements[r].push_back(el);
      }
    }
  }
  return regionElements;
}

/// The vertex sets xmin, xmax, ..., zmax of a box of cells[0] x cells[1] x cells[2] cells.
template <class VertexId>
void addBoxFaceSets(TetMesh& mesh, const Eigen::Vector3i& cells, const VertexId& vertexId) {
  const std::array<const char*, 6> faceNames{"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<int> low, high;
    for (int k = 0; k <= cells.z(); ++k)
      for (int j = 0; j <= cells.y(); ++j)
        for (int i = 0; i <= cells.x(); ++i) {
          const std::array<int, 3> c{i, j, k};
          const int last = cells[axis];
          if (c[static_cast<std::size_t>(axis)] == 0) low.push_back(vertexId(i, j, k));
          if (c[static_cast<std::size_t>(axis)] == last) high.push_back(vertexId(i, j, k));
        }
    mesh.setVertexSet(faceNames[static_cast<std::size_t>(2 * axis)], std::move(low));
    mesh.setVertexSet(faceNames[static_cast<std::size_t>(2 * axis + 1)], std::move(high));
  }
}

}  // namespace

TetMesh makeBoxMesh(const BoxMeshSpec& spec) {
  const Eigen::Vector3i n = spec.cells;
  if ((n.array() < 1).any()) throw ValidationError("box mesh: every cell count must be >= 1");
  if (!(spec.size.array() > 0.0).all() || !spec.size.allFinite() || !spec.origin.allFinite()) {
    throw ValidationError("box mesh: size must be positive and finite");
  }
  const long long cellCount = static_cast<long long>(n.x()) * n.y() * n.z();
  if (cellCount * 6 > 200'000'000LL) throw ValidationError("box mesh: more than 2e8 elements requested");

  const int nx = n.x() + 1, ny = n.y() + 1, nz = n.z() + 1;
  auto vertexId = [&](int i, int j, int k) { return i + nx * (j + ny * k); };
  Eigen::Matrix3Xd x(3, nx * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        x.col(vertexId(i, j, k)) = spec.origin + spec.size.cwiseProduct(Eigen::Vector3d(
                                                     double(i) / n.x(), double(j) / n.y(), double(k) / n.z()));

  Eigen::Matrix4Xi elements(4, cellCount * 6);
  int e = 0;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) appendCellTets({i, j, k}, vertexId, x, elements, e);

  std::vector<Material> materials{spec.material};
  std::vector<int> elementMaterials;
  std::vector<std::vector<int>> regionElements = assignBoxRegions(spec, x, elements, elementMaterials);
  for (const BoxRegion& r : spec.regions) materials.push_back(r.material);

  TetMesh mesh(std::move(x), std::move(elements), std::move(materials), std::move(elementMaterials));
  for (std::size_t r = 0; r < spec.regions.size(); ++r) {
    setElementAndVertexSet(mesh, spec.regions[r].name, std::move(regionElements[r]));
  }
  addBoxFaceSets(mesh, n, vertexId);
  return mesh;
}

TetMesh makeBeamMesh(const BeamSpec& spec) {
  if (spec.cellsAlongLength < 1) throw ValidationError("beam: cellsAlongLength must be >= 1");
  if (!(spec.tipFraction >= 0.0 && spec.tipFraction < 1.0))
    throw ValidationError("beam: tipFraction must be in [0, 1)");
  if (!(spec.length > 0 && spec.height > 0 && spec.depth > 0))
    throw ValidationError("beam: dimensions must be positive");
  const double cell = spec.length / spec.cellsAlongLength;
  BoxMeshSpec box;
  box.size = Eigen::Vector3d(spec.length, spec.height, spec.depth);
  box.cells = Eigen::Vector3i(spec.cellsAlongLength, std::max(1, static_cast<int>(std::lround(spec.height / cell))),
                              std::max(1, static_cast<int>(std::lround(spec.depth / cell))));
  box.material = spec.body;
  const double tipStart = spec.length * (1.0 - spec.tipFraction);
  if (spec.tipFraction > 0.0) {
    box.regions.push_back({"tip", Eigen::Vector3d(tipStart, -1.0, -1.0),
                           Eigen::Vector3d(spec.length + 1.0, spec.height + 1.0, spec.depth + 1.0), spec.tip});
  }
  TetMesh mesh = makeBoxMesh(box);
  mesh.setVertexSet("root", mesh.vertexSet("xmin"));
  std::vector<int> bodyElements;
  const std::vector<int> tipElements = spec.tipFraction > 0.0 ? mesh.elementSet("tip") : std::vector<int>{};
  for (int e = 0, t = 0; e < mesh.numElements(); ++e) {
    if (t < static_cast<int>(tipElements.size()) && tipElements[static_cast<std::size_t>(t)] == e) {
      ++t;
      continue;
    }
    bodyElements.push_back(e);
  }
  mesh.setElementSet("body", std::move(bodyElements));
  return mesh;
}

namespace {

/// The lattice a cell mesh's blocks span: cells lo .. hi - 1 on each axis, and the
/// lattice points lo .. hi.
struct CellLattice {
  Eigen::Vector3i lo;
  Eigen::Vector3i hi;
  Eigen::Vector3i cells;   ///< hi - lo
  Eigen::Vector3i points;  ///< cells + 1

  std::size_t cellIndex(int i, int j, int k) const {
    return static_cast<std::size_t>((i - lo.x()) + cells.x() * ((j - lo.y()) + cells.y() * (k - lo.z())));
  }
  std::size_t pointIndex(int i, int j, int k) const {
    return static_cast<std::size_t>((i - lo.x()) + points.x() * ((j - lo.y()) + points.y() * (k - lo.z())));
  }
  long long numCells() const { return static_cast<long long>(cells.x()) * cells.y() * cells.z(); }
};

/// Checks the spec's cell size and blocks; the lattice they span.
CellLattice checkedLattice(const CellMeshSpec& spec) {
  if (!(spec.cellSize > 0.0) || !std::isfinite(spec.cellSize) || !spec.origin.allFinite()) {
    throw ValidationError("cell mesh: cellSize must be positive and finite, origin finite");
  }
  if (spec.blocks.empty()) throw ValidationError("cell mesh: no blocks");
  CellLattice lattice{spec.blocks.front().begin, spec.blocks.front().end, {}, {}};
  for (const CellBlock& b : spec.blocks) {
    if (b.name.empty()) throw ValidationError("cell mesh: a block has no name");
    if ((b.end.array() <= b.begin.array()).any()) {
      throw ValidationError("cell mesh: block '" + b.name + "' is empty (end must exceed begin on every axis)");
    }
    lattice.lo = lattice.lo.cwiseMin(b.begin);
    lattice.hi = lattice.hi.cwiseMax(b.end);
  }
  lattice.cells = lattice.hi - lattice.lo;
  lattice.points = lattice.cells + Eigen::Vector3i::Ones();
  if (lattice.numCells() > 50'000'000LL) {
    throw ValidationError("cell mesh: the blocks span more than 5e7 lattice cells");
  }
  return lattice;
}

/// Materials by name, in order of first use, into materials; the material of each block.
std::vector<int> blockMaterials(const CellMeshSpec& spec, std::vector<Material>& materials) {
  std::vector<int> blockMaterial;
  for (const CellBlock& b : spec.blocks) {
    auto same =
        std::find_if(materials.begin(), materials.end(), [&](const Material& m) { return m.name == b.material.name; });
    if (same != materials.end() && !(*same == b.material)) {
      throw ValidationError("cell mesh: material '" + b.material.name + "' is given two different values");
    }
    if (same == materials.end()) {
      materials.push_back(b.material);
      same = materials.end() - 1;
    }
    blockMaterial.push_back(static_cast<int>(same - materials.begin()));
  }
  return blockMaterial;
}

/// The block owning each lattice cell (the last block claiming it; -1: empty).
std::vector<int> cellOwners(const CellMeshSpec& spec, const CellLattice& lattice) {
  std::vector<int> owner(static_cast<std::size_t>(lattice.numCells()), -1);
  for (std::size_t b = 0; b < spec.blocks.size(); ++b)
    for (int k = spec.blocks[b].begin.z(); k < spec.blocks[b].end.z(); ++k)
      for (int j = spec.blocks[b].begin.y(); j < spec.blocks[b].end.y(); ++j)
        for (int i = spec.blocks[b].begin.x(); i < spec.blocks[b].end.x(); ++i)
          owner[lattice.cellIndex(i, j, k)] = static_cast<int>(b);
  return owner;
}

/// Numbers the lattice points used by some occupied cell in lattice order: vertexOfPoint
/// (by CellLattice::pointIndex, -1 unused); returns the point of each vertex.
std::vector<Eigen::Vector3i> numberCellVertices(const CellLattice& lattice, const std::vector<int>& owner,
                                                std::vector<int>& vertexOfPoint) {
  const Eigen::Vector3i& lo = lattice.lo;
  const Eigen::Vector3i& hi = lattice.hi;
  vertexOfPoint.assign(static_cast<std::size_t>(lattice.points.prod()), -1);
  for (int k = lo.z(); k < hi.z(); ++k)
    for (int j = lo.y(); j < hi.y(); ++j)
      for (int i = lo.x(); i < hi.x(); ++i) {
        if (owner[lattice.cellIndex(i, j, k)] < 0) continue;
        for (int c = 0; c < 8; ++c)
          vertexOfPoint[lattice.pointIndex(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))] = 0;
      }
  std::vector<Eigen::Vector3i> pointOfVertex;
  for (int k = lo.z(); k <= hi.z(); ++k)
    for (int j = lo.y(); j <= hi.y(); ++j)
      for (int i = lo.x(); i <= hi.x(); ++i) {
        int& v = vertexOfPoint[lattice.pointIndex(i, j, k)];
        if (v < 0) continue;
        v = static_cast<int>(pointOfVertex.size());
        pointOfVertex.emplace_back(i, j, k);
      }
  return pointOfVertex;
}

/// The vertex set of each vertex ring: the vertices within ring.rings lattice steps (in
/// the max norm) of the sets it is around.
void addVertexRings(TetMesh& mesh, const std::vector<CellVertexRing>& rings,
                    const std::vector<Eigen::Vector3i>& pointOfVertex) {
  for (const CellVertexRing& ring : rings) {
    if (ring.name.empty() || ring.rings < 0)
      throw ValidationError("cell mesh: a vertex ring needs a name and rings >= 0");
    std::vector<Eigen::Vector3i> core;
    for (const std::string& name : ring.around) {
      if (mesh.vertexSets().count(name) == 0) {
        throw ValidationError("cell mesh: vertex ring '" + ring.name + "' around unknown set '" + name + "'");
      }
      for (int v : mesh.vertexSet(name)) core.push_back(pointOfVertex[static_cast<std::size_t>(v)]);
    }
    std::vector<int> members;
    for (int v = 0; v < mesh.numVertices(); ++v) {
      const Eigen::Vector3i& p = pointOfVertex[static_cast<std::size_t>(v)];
      if (std::any_of(core.begin(), core.end(),
                      [&](const Eigen::Vector3i& c) { return (c - p).cwiseAbs().maxCoeff() <= ring.rings; })) {
        members.push_back(v);
      }
    }
    mesh.setVertexSet(ring.name, std::move(members));
  }
}

}  // namespace

TetMesh makeCellMesh(const CellMeshSpec& spec) {
  const CellLattice lattice = checkedLattice(spec);
  std::vector<Material> materials;
  const std::vector<int> blockMaterial = blockMaterials(spec, materials);
  const std::vector<int> owner = cellOwners(spec, lattice);
  std::vector<int> vertexOfPoint;
  const std::vector<Eigen::Vector3i> pointOfVertex = numberCellVertices(lattice, owner, vertexOfPoint);
  Eigen::Matrix3Xd x(3, static_cast<Eigen::Index>(pointOfVertex.size()));
  for (std::size_t v = 0; v < pointOfVertex.size(); ++v) {
    x.col(static_cast<Eigen::Index>(v)) = spec.origin + spec.cellSize * pointOfVertex[v].cast<double>();
  }
  auto vertexId = [&](int i, int j, int k) { return vertexOfPoint[lattice.pointIndex(i, j, k)]; };

  const auto occupied = static_cast<int>(std::count_if(owner.begin(), owner.end(), [](int b) { return b >= 0; }));
  Eigen::Matrix4Xi elements(4, 6 * occupied);
  std::vector<int> elementMaterials;
  std::map<std::string, std::vector<int>> setElements;
  int e = 0;
  for (int k = lattice.lo.z(); k < lattice.hi.z(); ++k)
    for (int j = lattice.lo.y(); j < lattice.hi.y(); ++j)
      for (int i = lattice.lo.x(); i < lattice.hi.x(); ++i) {
        const int b = owner[lattice.cellIndex(i, j, k)];
        if (b < 0) continue;
        std::vector<int>& set = setElements[spec.blocks[static_cast<std::size_t>(b)].name];
        for (int t = 0; t < 6; ++t) {
          set.push_back(e + t);
          elementMaterials.push_back(blockMaterial[static_cast<std::size_t>(b)]);
        }
        appendCellTets({i, j, k}, vertexId, x, elements, e);
      }

  TetMesh mesh(std::move(x), std::move(elements), std::move(materials), std::move(elementMaterials));
  for (auto& [name, members] : setElements) setElementAndVertexSet(mesh, name, std::move(members));
  std::vector<int> bottom;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (pointOfVertex[static_cast<std::size_t>(v)].y() == lattice.lo.y()) bottom.push_back(v);
  mesh.setVertexSet("bottom", std::move(bottom));
  addVertexRings(mesh, spec.vertexRings, pointOfVertex);
  return mesh;
}

namespace {

/// The vertices of `set` with the largest y (the top of an upright appendage).
std::vector<int> topVertices(const TetMesh& mesh, const std::vector<int>& set) {
  double top = -std::numeric_limits<double>::infinity();
  for (int v : set) top = std::max(top, mesh.restPositions()(1, v));
  std::vector<int> result;
  for (int v : set)
    if (mesh.restPositions()(1, v) == top) result.push_back(v);
  return result;
}

}  // namespace

TetMesh makeAntennaMesh(const AntennaSpec& spec) {
  if ((spec.blockCells.array() < 1).any() || spec.rodCells < 1) {
    throw ValidationError("antenna: blockCells and rodCells must be >= 1");
  }
  if (spec.whipCells < 0 || spec.whipCells >= spec.rodCells) {
    throw ValidationError("antenna: whipCells must be in [0, rodCells)");
  }
  CellMeshSpec cells;
  cells.cellSize = spec.cellSize;
  const Eigen::Vector3i foot(spec.blockCells.x() / 2, spec.blockCells.y(), spec.blockCells.z() / 2);
  const Eigen::Vector3i whipFoot = foot + Eigen::Vector3i(0, spec.rodCells - spec.whipCells, 0);
  cells.blocks = {{"block", Eigen::Vector3i::Zero(), spec.blockCells, spec.block},
                  {"rod", foot, whipFoot + Eigen::Vector3i(1, 0, 1), spec.rod}};
  cells.vertexRings = {{"rodAndRing", {"rod"}, 1}};
  if (spec.whipCells > 0) {
    cells.blocks.push_back({"whip", whipFoot, foot + Eigen::Vector3i(1, spec.rodCells, 1), spec.whip});
    cells.vertexRings.front().around.push_back("whip");
  }
  TetMesh mesh = makeCellMesh(cells);
  if (spec.whipCells == 0) {
    mesh.setVertexSet("rodTip", topVertices(mesh, mesh.vertexSet("rod")));
    return mesh;
  }
  std::vector<int> whip = mesh.vertexSet("whip"), region = mesh.vertexSet("rodAndRing"), below;
  mesh.setVertexSet("rodTip", topVertices(mesh, whip));
  std::sort(whip.begin(), whip.end());
  std::sort(region.begin(), region.end());
  std::set_difference(region.begin(), region.end(), whip.begin(), whip.end(), std::back_inserter(below));
  mesh.setVertexSet("rodAndRingBelowWhip", std::move(below));
  return mesh;
}

TetMesh makeSnailMesh(const SnailSpec& spec) {
  if (spec.tentacleCells < 1) throw ValidationError("snail: tentacleCells must be >= 1");
  // Cells (0.05 m each by default): a sole 16 x 1 x 6; a stepped shell on its back half;
  // a neck and a head on its front; the tentacles stand on the head, three cells apart so
  // that each keeps its own ring of head vertices around its foot.
  using V = Eigen::Vector3i;
  CellMeshSpec cells;
  cells.cellSize = spec.cellSize;
  const int top = 4;  // the head's top layer
  cells.blocks = {{"sole", V(0, 0, 0), V(16, 1, 6), spec.body},
                  {"shell", V(1, 1, 0), V(9, 5, 6), spec.shell},
                  {"shell", V(2, 5, 1), V(8, 7, 5), spec.shell},
                  {"head", V(9, 1, 1), V(16, 3, 5), spec.body},
                  {"head", V(13, 3, 1), V(16, top, 5), spec.body},
                  {"tentacles", V(14, top, 1), V(15, top + spec.tentacleCells, 2), spec.tentacles},
                  {"tentacles", V(14, top, 4), V(15, top + spec.tentacleCells, 5), spec.tentacles}};
  cells.vertexRings = {{"tentaclesAndRing", {"tentacles"}, 1}};
  TetMesh mesh = makeCellMesh(cells);
  mesh.setVertexSet("tentacleTips", topVertices(mesh, mesh.vertexSet("tentacles")));
  return mesh;
}

}  // namespace asyncfem
