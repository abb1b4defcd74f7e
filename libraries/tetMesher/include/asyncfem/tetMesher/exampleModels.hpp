// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Geometry>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/voxelize.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// The procedurally generated models shipped in models/ (docs/tet-mesher.md and
/// models/README.md describe their sets and materials). Lengths in metres, y up, the ground
/// at y = 0.
enum class ExampleModel {
  Dinosaur,  ///< body, four legs with "feet", a long neck with a head ("head"), a tail ("tail")
  Flower,    ///< "base", "stem", two "upperLeaves", five "petals" around a centre
  Dragon,    ///< dragon-like body, stiff "jaw", nested head regions "s1" ... "s6"
  Drop,      ///< soft rounded block ("soft") with a stiff knob ("stiffPart"), above the ground
  Ball,      ///< rubber ball ("ball", radius 0.2) centred 0.45 above the ground
};

/// "dinosaur", "flower", "dragon", "drop", "ball", in enum order.
const std::vector<std::string>& exampleModelNames();
std::string exampleModelName(ExampleModel model);
/// Inverse of exampleModelName; ValidationError listing the names for an unknown one.
ExampleModel exampleModelFromName(const std::string& name);

/// A model's implicit description: named parts (their smooth union with width blend is the
/// solid; each element's set is the part most inside at its centroid) and a box that
/// contains the solid.
struct ImplicitModel {
  std::vector<ImplicitPart> parts;
  double blend = 0.0;
  Eigen::AlignedBox3d bounds;
  double spacing = 0.0;  ///< lattice spacing of the shipped .veg
};
ImplicitModel exampleModelShape(ExampleModel model);

/// Meshes the model with stuffIsosurface (spacing <= 0: the shipped spacing), then adds the
/// element and vertex sets of its parts and its extra sets, and assigns its materials.
/// The result is checked (validateTetMesh) and must be one connected piece (ValidationError
/// otherwise, e.g. when a spacing too coarse cuts a thin part off). gradingLevels as in
/// MesherOptions (0: the uniform lattice of the shipped meshes).
TetMesh makeExampleModel(ExampleModel model, double spacing = 0.0, StuffingReport* report = nullptr,
                         int gradingLevels = 0);

/// The model as cubes (voxelize of its implicit solid at the given spacing, <= 0: the shipped
/// spacing), with the same part sets, extra sets and materials as makeExampleModel. Unlike
/// makeExampleModel it does not require one connected piece (cubes touching along an edge only
/// are a valid mesh).
TetMesh makeExampleModelCubes(ExampleModel model, double spacing = 0.0, VoxelReport* report = nullptr);

}  // namespace asyncfem
