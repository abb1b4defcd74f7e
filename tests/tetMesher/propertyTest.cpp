// SPDX-License-Identifier: BSD-3-Clause
// Properties of isosurface stuffing over many inputs chosen to be hard: random noise fields
// (thin sheets, tiny islands, many cut points per cell), random unions of primitives, and
// open surfaces meshed through the generalized winding number. Every mesh must have its
// dihedral angles inside the paper's bound, no inverted element, a closed, outward boundary
// and every vertex used; smooth solids must also keep their volume.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "surfaces.hpp"

namespace asyncfem {
namespace {

using Eigen::Vector3d;

// Labelle & Shewchuk (2007) prove every dihedral angle lies in [10.78, 164.74] degrees for
// the alphas used; the printed bound is rounded, so allow 0.01 degree of rounding.
constexpr double kBoundMin = 10.78 - 0.01;
constexpr double kBoundMax = 164.74 + 0.01;

struct Extremes {
  double minAngle = 180.0;
  double maxAngle = 0.0;
  int meshes = 0;
  void add(const MeshQuality& q) {
    minAngle = std::min(minAngle, q.minDihedralDegrees);
    maxAngle = std::max(maxAngle, q.maxDihedralDegrees);
    ++meshes;
  }
  void print(const char* what) const {
    std::printf("%s: %d meshes, dihedral angles %.2f to %.2f degrees\n", what, meshes, minAngle, maxAngle);
  }
};

/// Meshes f and checks the properties every output must have. Returns the mesh.
TetMesh expectValid(const ImplicitFunction& f, const Eigen::AlignedBox3d& box, double spacing, const std::string& name,
                    Extremes& extremes) {
  SCOPED_TRACE(name);
  MesherOptions options;
  options.minDihedralDegrees = 0.0;  // measure here instead of throwing inside
  StuffingReport report;
  const TetMesh mesh = stuffIsosurface(f, box, spacing, options, &report);
  const MeshQuality quality = meshQuality(mesh);
  extremes.add(quality);
  EXPECT_GE(quality.minDihedralDegrees, kBoundMin);
  EXPECT_LE(quality.maxDihedralDegrees, kBoundMax);
  EXPECT_EQ(report.minDihedralDegrees, quality.minDihedralDegrees);
  const MeshCheckReport check = checkTetMesh(mesh);
  EXPECT_TRUE(check.ok()) << check.firstProblem;  // closed, outward, none inverted, all used
  EXPECT_EQ(check.invertedElements, 0);
  EXPECT_EQ(check.openBoundaryEdges, 0);
  EXPECT_EQ(check.misorientedBoundaryEdges, 0);
  EXPECT_GT(check.boundaryVolume, 0.0);
  return mesh;
}

/// A random field: values uniform in [-1, 1] on a grid of the given period, interpolated
/// trilinearly, shifted by `bias` (more inside or outside) and cut to a ball of radius 1 so
/// that the solid is bounded.
ImplicitFunction noiseField(std::uint32_t seed, double period, double bias) {
  const int n = static_cast<int>(std::ceil(2.4 / period)) + 2;
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  auto values = std::make_shared<std::vector<double>>(static_cast<std::size_t>(n * n * n));
  for (double& v : *values) v = uniform(random);
  return [values, n, period, bias](const Vector3d& x) {
    const Vector3d g = (x + Vector3d::Constant(1.2)) / period;
    const Eigen::Vector3i i0 = g.array().floor().cast<int>().cwiseMax(0).cwiseMin(n - 2);
    const Vector3d t = (g - i0.cast<double>()).cwiseMax(0.0).cwiseMin(1.0);
    double value = 0.0;
    for (int c = 0; c < 8; ++c) {
      const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
      const double w = (dx ? t.x() : 1.0 - t.x()) * (dy ? t.y() : 1.0 - t.y()) * (dz ? t.z() : 1.0 - t.z());
      value += w * (*values)[static_cast<std::size_t>((i0.x() + dx) + n * ((i0.y() + dy) + n * (i0.z() + dz)))];
    }
    return std::max(value + bias, x.norm() - 1.0);
  };
}

TEST(StuffingProperties, NoiseFieldsKeepTheAngleBound) {
  // The worst case for the stencils: sign changes everywhere, at every scale down to the
  // lattice spacing, so that every sign pattern and every warp combination occurs.
  Extremes extremes;
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.0), Vector3d::Constant(1.0));
  std::uint32_t seed = 1;
  for (double period : {0.09, 0.17, 0.3})
    for (double bias : {-0.3, 0.0, 0.3})
      for (double spacing : {0.071, 0.1}) {
        expectValid(noiseField(seed, period, bias), box, spacing,
                    "noise seed " + std::to_string(seed) + " period " + std::to_string(period) + " spacing " +
                        std::to_string(spacing),
                    extremes);
        ++seed;
      }
  extremes.print("noise fields");
}

TEST(StuffingProperties, RandomUnionsKeepTheBoundAndTheirBoundaryOnTheSurface) {
  Extremes extremes;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto point = [&]() -> Vector3d {
    return Vector3d(unit(random), unit(random), unit(random)) * 1.2 - Vector3d::Constant(0.6);
  };
  for (int shape = 0; shape < 24; ++shape) {
    std::vector<ImplicitFunction> parts;
    const int count = 1 + shape % 4;
    for (int i = 0; i < count; ++i) {
      const double r = 0.08 + 0.3 * unit(random);
      switch ((shape + i) % 4) {
        case 0:
          parts.push_back(implicitSphere(point(), r));
          break;
        case 1:
          parts.push_back(implicitCapsule(point(), point(), 0.6 * r));
          break;
        case 2:
          parts.push_back(implicitTorus(point(), point().normalized(), 0.3 + 0.2 * unit(random), 0.4 * r));
          break;
        default:
          parts.push_back(implicitBox(point(), Vector3d(r, 0.7 * r, 1.2 * r), 0.3 * r));
          break;
      }
    }
    const ImplicitFunction f = implicitSmoothUnion(parts, 0.05 * (shape % 3));
    const double spacing = 0.04 + 0.05 * unit(random);
    const Eigen::AlignedBox3d box(Vector3d::Constant(-1.8), Vector3d::Constant(1.8));
    const TetMesh mesh = expectValid(f, box, spacing, "union " + std::to_string(shape), extremes);
    // Boundary vertices are cut points or warped vertices: roots of f to ~1e-12 h.
    for (const auto& t : boundaryTriangles(mesh))
      for (int v : t) ASSERT_NEAR(f(mesh.restPosition(v)), 0.0, 1e-9 * spacing) << "shape " << shape;
  }
  extremes.print("random unions");
}

TEST(StuffingProperties, OpenSurfacesThroughTheWindingNumber) {
  // A sphere with random triangles removed (holes of one to a few triangles): the winding
  // number still says inside from outside, the distance is to the remaining triangles, so
  // the function is not a smooth distance near the holes.
  Extremes extremes;
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double exact = 4.0 / 3.0 * std::numbers::pi;
  for (int trial = 0; trial < 6; ++trial) {
    TriangleSurface sphere = test::uvSphere(Vector3d::Zero(), 1.0, 24 + 4 * trial, 12 + 2 * trial);
    std::vector<int> keep;
    for (int t = 0; t < sphere.numTriangles(); ++t)
      if (unit(random) > 0.04) keep.push_back(t);
    Eigen::Matrix3Xi kept(3, static_cast<Eigen::Index>(keep.size()));
    for (std::size_t i = 0; i < keep.size(); ++i)
      kept.col(static_cast<Eigen::Index>(i)) = sphere.triangles.col(keep[i]);
    sphere.triangles = kept;
    sphere.triangleParts.assign(keep.size(), 0);
    const SignedDistance distance(sphere, SignMode::WindingNumber);
    const double spacing = 0.07 + 0.03 * unit(random);
    const TetMesh mesh =
        expectValid(distance.function(), Eigen::AlignedBox3d(Vector3d::Constant(-1.1), Vector3d::Constant(1.1)),
                    spacing, "open sphere " + std::to_string(trial), extremes);
    // The polyhedral sphere's volume is below the round one's by its chord error (~3% for
    // 24 slices); the mesh must be within 5% of the round sphere.
    EXPECT_NEAR(totalVolume(mesh), exact, 0.05 * exact) << "trial " << trial;
  }
  extremes.print("open surfaces");
}

TEST(StuffingProperties, EverySpacingFromTheCoarsestWorks) {
  // An open, non-smooth input (a sphere with holes, through the winding number) at every
  // spacing from its diameter down to 1/16 of it: each run either meshes validly or, when too coarse
  // for any lattice vertex to be inside, says so; once one spacing works, every finer one
  // works too.
  TriangleSurface sphere = test::uvSphere(Vector3d(0.01, -0.02, 0.03), 1.0, 20, 10);
  std::vector<int> keep;
  for (int t = 0; t < sphere.numTriangles(); ++t)
    if (t % 17 != 3) keep.push_back(t);
  selectTriangles(sphere, keep);
  const SignedDistance distance(sphere, SignMode::WindingNumber);
  const Eigen::AlignedBox3d box(Vector3d::Constant(-1.1), Vector3d::Constant(1.1));
  Extremes extremes;
  bool worked = false;
  for (int cells = 1; cells <= 16; ++cells) {
    const double spacing = 2.0 / cells;
    try {
      expectValid(distance.function(), box, spacing, "cells " + std::to_string(cells), extremes);
      worked = true;
    } catch (const ValidationError& e) {
      EXPECT_FALSE(worked) << "cells " << cells << " failed after a coarser spacing worked: " << e.what();
      EXPECT_NE(std::string(e.what()).find("no lattice vertex lies inside"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(worked);
  extremes.print("spacing sweep");
}

TEST(StuffingProperties, RealSurfacesFromAssimpTestModels) {
  // Debian's assimp-testmodels, when installed (not a build dependency): closed and open
  // real surfaces, each at several spacings; closed ones must also keep their volume.
  const std::filesystem::path models("/usr/share/assimp/models");
  if (!surfaceReaderAvailable() || !std::filesystem::is_directory(models))
    GTEST_SKIP() << "assimp-testmodels not installed (apt-get install assimp-testmodels)";
  Extremes extremes;
  for (const char* relative : {"Collada/duck.dae", "3DS/fels.3ds", "FBX/huesitos.fbx", "OBJ/WusonOBJ.obj",
                               "OBJ/spider.obj", "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf"}) {
    const std::filesystem::path path = models / relative;
    if (!std::filesystem::exists(path)) {
      ADD_FAILURE() << path.string() << " is missing from assimp-testmodels";
      continue;
    }
    TriangleSurface surface = readSurface(path);
    const Eigen::AlignedBox3d bounds = surface.bounds();
    weldVertices(surface, 1e-7 * bounds.diagonal().norm());
    const SurfaceTopology topology = surfaceTopology(surface);
    if (topology.signedVolume < 0.0) flipOrientation(surface);
    const bool closed = topology.closed();
    const SignedDistance distance(surface, closed ? SignMode::Pseudonormal : SignMode::WindingNumber);
    for (int cells : {9, 16}) {
      const double spacing = bounds.sizes().maxCoeff() / cells;
      const Eigen::AlignedBox3d box(bounds.min().array() - spacing, bounds.max().array() + spacing);
      const TetMesh mesh = expectValid(distance.function(), box, spacing,
                                       std::string(relative) + " cells " + std::to_string(cells), extremes);
      // A closed surface at 16 cells: within 5% of its volume (the inscribed boundary loses
      // about h^2 times the curvature over the area; 2% is met at 30 cells, see the benchmark).
      if (closed && cells == 16) {
        const double enclosed = std::abs(topology.signedVolume);
        EXPECT_NEAR(totalVolume(mesh), enclosed, 0.05 * enclosed) << relative;
      }
    }
  }
  extremes.print("assimp test models");
}

}  // namespace
}  // namespace asyncfem
