// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

struct Simulation;

/// The mesh of a scene of several bodies (scene.objects): each object's mesh (read or
/// generated as a scene's mesh is), placed, one after the other as disconnected parts.
/// In it each object's name is a vertex set and an element set, its own sets are
/// "<name>/<set>", its materials "<name>/<material>", and its fixed vertices the vertex set
/// "<name>/fixed". Throws ValidationError naming the scene key for a mesh or fixed
/// selection that fails, and naming the two objects and a triangle pair when two objects
/// start interpenetrating (the collision library's exact triangle-triangle test; touching
/// counts). warnings: as for buildSceneMesh, prefixed "<scene>: objects[i]".
TetMesh buildObjectsMesh(const Scene& scene, std::vector<std::string>* warnings = nullptr);

/// Each mesh vertex's object (the index in scene.objects), from the objects' vertex sets
/// of mesh; empty for a scene of one body.
std::vector<int> objectOfVertex(const Scene& scene, const TetMesh& mesh);

/// The penalty contact a scene describes on mesh (null without a contact section): planes
/// and spheres, and with obstacles or contact.surfaces a SurfaceContact between the bodies'
/// boundary surfaces and the obstacles (read with assimp, welded, placed). Throws
/// ValidationError naming contact.obstacles[i].file for a file that cannot be read, an
/// obstacle that must be closed but is not (open, non-manifold or inconsistently oriented
/// edges), or a build without assimp.
std::shared_ptr<const PenaltyContact> buildSceneContact(const Scene& scene, const TetMesh& mesh);

/// Gives the simulation's integrator the objects' initial velocities (fixed and unused
/// vertices stay at rest); nothing when every object starts at rest.
void applyInitialVelocities(const Scene& scene, Simulation& simulation);

/// Lines for a run summary on the surface contact: candidate pairs, active pairs and
/// detection time per step (empty without surface contact).
std::vector<std::string> surfaceContactSummary(const Simulation& simulation);

}  // namespace asyncfem
