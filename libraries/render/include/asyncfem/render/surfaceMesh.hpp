// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <vector>

namespace asyncfem {

/// A triangle surface: vertex positions (3 x m, length units of the tet mesh) and
/// triangles of 0-based vertex ids, counter-clockwise seen from outside where the
/// source says so (the renderer lights both sides, so orientation is not required).
struct SurfaceMesh {
  Eigen::Matrix3Xd vertices;
  std::vector<std::array<int, 3>> triangles;
};

/// Reads a surface mesh in any format assimp reads (OBJ, PLY, STL, glTF, OFF, ...). All
/// meshes of the file are merged with their node transforms applied; polygons are
/// triangulated, points and lines dropped, and vertices at exactly the same position are
/// merged (formats that split vertices at normal or texture seams would otherwise show
/// the seams in the shading). Throws asyncfem::Error naming the file when assimp cannot
/// read it or it holds no triangle.
SurfaceMesh loadSurfaceMesh(const std::filesystem::path& path);

/// Writes an ASCII Wavefront OBJ (v and f lines only), e.g. for tests and for exporting
/// a deformed surface. Throws asyncfem::Error naming the file on failure.
void writeObj(const std::filesystem::path& path, const SurfaceMesh& surface);

/// A sphere of the given centre and radius (> 0) as a subdivided icosahedron: refinements
/// (0 to 6) times each triangle is split in four and the new vertices are pushed onto the
/// sphere, so it has 20 * 4^refinements triangles (4: 5,120), counter-clockwise seen from
/// outside. Used to draw a scene's contact spheres. Throws asyncfem::Error for a
/// non-positive or non-finite radius or refinements out of range.
SurfaceMesh sphereSurface(const Eigen::Vector3d& center, double radius, int refinements = 4);

}  // namespace asyncfem
