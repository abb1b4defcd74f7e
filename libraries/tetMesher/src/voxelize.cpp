// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/tetMesher/voxelize.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace asyncfem {
namespace {

/// Six significant digits, as in the tool's report.
std::string number(double value) {
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

std::string describeBox(const Eigen::AlignedBox3d& box) {
  return "(" + number(box.min().x()) + ", " + number(box.min().y()) + ", " + number(box.min().z()) + ") - (" +
         number(box.max().x()) + ", " + number(box.max().y()) + ", " + number(box.max().z()) + ")";
}

/// Cells along each axis: ceil(size / spacing), at least one; a size within a relative
/// 1e-9 of a multiple of the spacing takes that multiple (no sliver of cells outside).
Eigen::Vector3i gridCells(const Eigen::AlignedBox3d& bounds, double spacing, long long maxCells) {
  Eigen::Vector3i cells;
  for (int axis = 0; axis < 3; ++axis) {
    const double ratio = bounds.sizes()[axis] / spacing;
    const double count = std::max(1.0, std::ceil(ratio * (1.0 - 1e-9)));
    if (!(count <= static_cast<double>(maxCells))) {
      throw ValidationError("voxelize: spacing " + number(spacing) + " gives " + number(count) +
                            " cells along one axis of the box " + describeBox(bounds) + "; the cap is " +
                            std::to_string(maxCells) + " grid cells");
    }
    cells[axis] = static_cast<int>(count);
  }
  return cells;
}

/// Whether the centre of every grid cell is inside (f < 0), cell index x fastest.
std::vector<char> insideCells(const ImplicitFunction& f, const Eigen::Vector3d& origin, double spacing,
                              const Eigen::Vector3i& cells, bool parallel) {
  const long long count = static_cast<long long>(cells.x()) * cells.y() * cells.z();
  std::vector<char> inside(static_cast<std::size_t>(count), 0);
  bool nonFinite = false;
#pragma omp parallel for schedule(dynamic, 1024) if (parallel) reduction(|| : nonFinite)
  for (long long c = 0; c < count; ++c) {
    const long long i = c % cells.x();
    const long long j = (c / cells.x()) % cells.y();
    const long long k = c / (static_cast<long long>(cells.x()) * cells.y());
    const Eigen::Vector3d centre =
        origin + spacing * Eigen::Vector3d(static_cast<double>(i) + 0.5, static_cast<double>(j) + 0.5,
                                           static_cast<double>(k) + 0.5);
    const double value = f(centre);
    if (!std::isfinite(value)) nonFinite = true;
    inside[static_cast<std::size_t>(c)] = value < 0.0 ? 1 : 0;
  }
  if (nonFinite) throw ValidationError("voxelize: the inside test returned a non-finite value");
  return inside;
}

/// Numbers the grid vertices the inside cells use, in grid order, and builds the cubes.
TetMesh buildCubes(const std::vector<char>& inside, const Eigen::Vector3d& origin, double spacing,
                   const Eigen::Vector3i& cells, int numCubes, const Material& material) {
  const long long vx = cells.x() + 1;
  const long long vy = cells.y() + 1;
  const long long numGridVertices = vx * vy * (cells.z() + 1);
  auto cornerOf = [&](long long c, int a) {
    const auto& corner = hexahedron::kCorners[static_cast<std::size_t>(a)];
    const long long i = c % cells.x() + (corner[0] > 0 ? 1 : 0);
    const long long j = (c / cells.x()) % cells.y() + (corner[1] > 0 ? 1 : 0);
    const long long k = c / (static_cast<long long>(cells.x()) * cells.y()) + (corner[2] > 0 ? 1 : 0);
    return i + vx * (j + vy * k);
  };
  std::vector<int> vertexId(static_cast<std::size_t>(numGridVertices), -1);
  for (long long c = 0; c < static_cast<long long>(inside.size()); ++c)
    if (inside[static_cast<std::size_t>(c)] != 0)
      for (int a = 0; a < 8; ++a) vertexId[static_cast<std::size_t>(cornerOf(c, a))] = 0;
  int numVertices = 0;
  std::vector<long long> gridVertex;
  for (long long v = 0; v < numGridVertices; ++v) {
    if (vertexId[static_cast<std::size_t>(v)] < 0) continue;
    vertexId[static_cast<std::size_t>(v)] = numVertices++;
    gridVertex.push_back(v);
  }
  Eigen::Matrix3Xd positions(3, numVertices);
  for (int v = 0; v < numVertices; ++v) {
    const long long g = gridVertex[static_cast<std::size_t>(v)];
    positions.col(v) =
        origin + spacing * Eigen::Vector3d(static_cast<double>(g % vx), static_cast<double>((g / vx) % vy),
                                           static_cast<double>(g / (vx * vy)));
  }
  HexElements cubes(8, numCubes);
  int e = 0;
  for (long long c = 0; c < static_cast<long long>(inside.size()); ++c) {
    if (inside[static_cast<std::size_t>(c)] == 0) continue;
    for (int a = 0; a < 8; ++a) cubes(a, e) = vertexId[static_cast<std::size_t>(cornerOf(c, a))];
    ++e;
  }
  return {std::move(positions), std::move(cubes), {material}, std::vector<int>(static_cast<std::size_t>(numCubes), 0)};
}

}  // namespace

TetMesh voxelize(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                 const VoxelOptions& options, VoxelReport* report) {
  Stopwatch watch;
  watch.start();
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    throw ValidationError("voxelize: the spacing must be positive and finite (got " + number(spacing) + ")");
  }
  if (bounds.isEmpty() || !bounds.min().allFinite() || !bounds.max().allFinite()) {
    throw ValidationError("voxelize: the bounding box " + describeBox(bounds) + " is empty or not finite");
  }
  const long long maxCells = 8 * options.maxCubes;
  const Eigen::Vector3i cells = gridCells(bounds, spacing, maxCells);
  const double cellProduct = static_cast<double>(cells.x()) * cells.y() * cells.z();  // no overflow
  if (cellProduct > static_cast<double>(maxCells)) {
    throw ValidationError("voxelize: spacing " + number(spacing) + " gives a grid of " + number(cellProduct) +
                          " cells over " + describeBox(bounds) + ", more than " + std::to_string(maxCells) +
                          " (8 x the cap of " + std::to_string(options.maxCubes) + " cubes); use a larger spacing");
  }
  const long long cellCount = static_cast<long long>(cellProduct);
  const std::vector<char> inside = insideCells(f, bounds.min(), spacing, cells, options.parallel);
  const long long numCubes = std::count(inside.begin(), inside.end(), 1);
  if (numCubes == 0) {
    throw ValidationError("voxelize: no cube centre at spacing " + number(spacing) + " lies inside the surface (box " +
                          describeBox(bounds) + "); use a smaller spacing");
  }
  if (numCubes > options.maxCubes) {
    const double fitting = spacing * std::cbrt(static_cast<double>(numCubes) / static_cast<double>(options.maxCubes));
    throw ValidationError("voxelize: spacing " + number(spacing) + " gives " + std::to_string(numCubes) +
                          " cubes, more than the cap of " + std::to_string(options.maxCubes) + "; a spacing of about " +
                          number(fitting) + " or larger fits");
  }
  TetMesh mesh = buildCubes(inside, bounds.min(), spacing, cells, static_cast<int>(numCubes), options.material);
  if (report != nullptr) {
    report->gridCells = cells;
    report->gridCellCount = cellCount;
    report->cubes = mesh.numElements();
    report->vertices = mesh.numVertices();
    report->cubeVolume = static_cast<double>(numCubes) * spacing * spacing * spacing;
    report->seconds = watch.stop();
  }
  return mesh;
}

double relativeVolumeError(double cubeVolume, double enclosedVolume) {
  if (!(enclosedVolume > 0.0)) {
    throw ValidationError("relativeVolumeError: the enclosed volume must be positive (got " + number(enclosedVolume) +
                          ")");
  }
  return (cubeVolume - enclosedVolume) / enclosedVolume;
}

}  // namespace asyncfem
