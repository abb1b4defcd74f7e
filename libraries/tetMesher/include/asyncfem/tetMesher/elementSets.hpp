// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Geometry>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// Rest-position centroid (vertex mean) of every element, tetrahedron or hexahedron, 3 x
/// numElements. The functions below serve both kinds of mesh.
Eigen::Matrix3Xd elementCentroids(const TetMesh& mesh);

/// Sets the element set `name` to the given elements and the vertex set `name` to their
/// vertices (replacing sets of that name).
void setElementAndVertexSet(TetMesh& mesh, const std::string& name, std::vector<int> elements);

/// Element (and vertex) set `name`: the elements whose centroid lies in box (bounds
/// included). Returns the number of elements; an empty box makes an empty set.
int addBoxSet(TetMesh& mesh, const std::string& name, const Eigen::AlignedBox3d& box);

/// One element (and vertex) set per part name: each element goes to the part whose
/// function is smallest (most inside) at the element centroid. Parts sharing a name share
/// a set. Returns the number of elements per distinct name, in first-appearance order.
std::vector<int> addImplicitPartSets(TetMesh& mesh, const std::vector<ImplicitPart>& parts);

/// One element (and vertex) set per part of distance.surface(): each element goes to the
/// part of the triangle nearest its centroid. Parts that receive no element get no set.
/// Returns the number of elements per part (indexed like surface().partNames).
std::vector<int> addNearestPartSets(TetMesh& mesh, const SignedDistance& distance);

/// Which triangle labels of a surface addSurfaceLabelSets groups elements by.
enum class SurfaceLabel {
  Part,      ///< triangleParts / partNames (assimp meshes)
  Material,  ///< triangleMaterials / materialNames (the file's materials)
  Group,     ///< triangleGroups / groupNames (OBJ g/o, glTF/FBX nodes)
};

/// One element (and vertex) set per label of distance.surface(), named after the label:
/// an element goes to the innermost label whose triangles enclose its centroid (generalized
/// winding number of that label's triangles above 1/2; among several, the one enclosing the
/// least volume, so that a part nested in another, such as a core inside a shell, keeps its
/// own elements); elements enclosed by no label (open labels) go to the label of the nearest
/// triangle. Labels that receive no element get no set. Returns the element count per label
/// (indexed like the names). ValidationError if the surface has no such labels.
std::vector<int> addSurfaceLabelSets(TetMesh& mesh, const SignedDistance& distance, SurfaceLabel kind);

/// Gives every element of element set `set` the material (added to the mesh, or replacing
/// the material of the same name). ValidationError if the set does not exist.
void assignSetMaterial(TetMesh& mesh, const std::string& set, const Material& material);

}  // namespace asyncfem
