// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/collision/triangleIntersection.hpp>
#include <asyncfem/contact/surfaceContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/sceneObjects.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/volumetricMesh/vertexSelection.hpp>
#include <cstdio>
#include <map>

namespace asyncfem {

namespace {

std::string objectKey(std::size_t i) { return "objects[" + std::to_string(i) + "]"; }

std::string describeObject(const Scene& scene, std::size_t i) {
  return objectKey(i) + " '" + scene.objects[i].name + "'";
}

// The object's mesh as a scene of its own would build it (reader warnings and errors
// prefixed with the object's key), placed.
TetMesh placedObjectMesh(const Scene& scene, std::size_t i, std::vector<std::string>* warnings,
                         std::vector<int>& fixed) {
  const Scene::Object& object = scene.objects[i];
  Scene part;
  part.sourceName = scene.sourceName + ": " + objectKey(i);
  part.baseDirectory = scene.baseDirectory;
  part.mesh = object.mesh;
  TetMesh mesh = buildSceneMesh(part, warnings);
  fixed.clear();
  if (!object.fixed.sets.empty() || !object.fixed.boxes.empty() || object.fixed.bouFile) {
    VertexSelection selection;
    selection.sets = object.fixed.sets;
    selection.boxes = object.fixed.boxes;
    selection.bouFile = object.fixed.bouFile;
    try {
      fixed = selectVertices(mesh, selection);
    } catch (const SelectionError& error) {
      throwSceneError(scene, objectKey(i) + ".fixed." + error.keySuffix(), error.what());
    }
  }
  Eigen::Matrix3Xd placed = mesh.restPositions();
  for (Eigen::Index v = 0; v < placed.cols(); ++v) placed.col(v) = object.placement.apply(placed.col(v));
  TetMesh result = mesh.isHexahedral() ? TetMesh(placed, mesh.hexahedra(), mesh.materials(), mesh.elementMaterials())
                                       : TetMesh(placed, mesh.elements(), mesh.materials(), mesh.elementMaterials());
  for (const auto& [name, members] : mesh.elementSets()) result.setElementSet(name, members);
  for (const auto& [name, members] : mesh.vertexSets()) result.setVertexSet(name, members);
  return result;
}

// Refuses objects whose boundary surfaces intersect, naming the first pair found.
void requireApart(const Scene& scene, const TetMesh& mesh, const std::vector<int>& firstVertex) {
  const CollisionSurface whole = boundarySurface(mesh);
  const std::size_t count = scene.objects.size();
  std::vector<std::vector<int>> trianglesOf(count);
  const auto objectOf = [&](int v) {
    return static_cast<std::size_t>(std::upper_bound(firstVertex.begin(), firstVertex.end(), v) - firstVertex.begin() -
                                    1);
  };
  for (int t = 0; t < whole.numTriangles(); ++t) trianglesOf[objectOf(whole.triangles(0, t))].push_back(t);
  std::vector<CollisionSurface> surfaces;
  for (const std::vector<int>& list : trianglesOf) {
    Eigen::Matrix3Xi triangles(3, static_cast<Eigen::Index>(list.size()));
    for (std::size_t k = 0; k < list.size(); ++k)
      triangles.col(static_cast<Eigen::Index>(k)) = whole.triangles.col(list[k]);
    surfaces.push_back(triangleSurface(triangles, mesh.numVertices()));
  }
  const Eigen::Matrix3Xd& x = mesh.restPositions();
  for (std::size_t a = 0; a < count; ++a) {
    for (std::size_t b = a + 1; b < count; ++b) {
      const std::vector<std::pair<int, int>> crossing = intersectingTrianglePairs(surfaces[a], x, surfaces[b], x);
      if (crossing.empty()) continue;
      const auto describe = [&](std::size_t object, int triangle) {
        const auto corners = surfaces[object].triangles.col(triangle);
        const int offset = firstVertex[object];
        return "triangle " + std::to_string(triangle) + " of '" + scene.objects[object].name + "' (its vertices " +
               std::to_string(corners[0] - offset) + ", " + std::to_string(corners[1] - offset) + ", " +
               std::to_string(corners[2] - offset) + ")";
      };
      throwSceneError(scene, "objects",
                      describeObject(scene, a) + " and " + describeObject(scene, b) +
                          " start interpenetrating: " + describe(a, crossing.front().first) + " and " +
                          describe(b, crossing.front().second) + " intersect (" + std::to_string(crossing.size()) +
                          " triangle pairs; touching counts): place them apart");
    }
  }
}

}  // namespace

TetMesh buildObjectsMesh(const Scene& scene, std::vector<std::string>* warnings) {
  std::vector<TetMesh> parts;
  std::vector<std::vector<int>> fixed(scene.objects.size());
  std::vector<int> firstVertex;
  int vertices = 0;
  int elements = 0;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    parts.push_back(placedObjectMesh(scene, i, warnings, fixed[i]));
    firstVertex.push_back(vertices);
    vertices += parts.back().numVertices();
    elements += parts.back().numElements();
  }
  // One mesh holds one element kind: every object tetrahedra, or every object hexahedra.
  for (std::size_t i = 1; i < parts.size(); ++i) {
    if (parts[i].elementKind() != parts.front().elementKind()) {
      throwSceneError(scene, objectKey(i) + ".mesh",
                      describeObject(scene, i) + " has " + elementKindPlural(parts[i].elementKind()) + " and " +
                          describeObject(scene, 0) + " " + elementKindPlural(parts.front().elementKind()) +
                          ": the objects of a scene share one element kind (meshInfo MESH --hex-to-tets --write "
                          "OUT.veg converts hexahedra)");
    }
  }
  const int corners = parts.empty() ? 4 : parts.front().verticesPerElement();
  Eigen::Matrix3Xd positions(3, vertices);
  Eigen::MatrixXi connectivity(corners, elements);
  std::vector<Material> materials;
  std::vector<int> elementMaterials;
  int firstElement = 0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const TetMesh& part = parts[i];
    const std::string& name = scene.objects[i].name;
    positions.middleCols(firstVertex[i], part.numVertices()) = part.restPositions();
    connectivity.middleCols(firstElement, part.numElements()) = part.connectivity().array() + firstVertex[i];
    const int firstMaterial = static_cast<int>(materials.size());
    for (Material material : part.materials()) {
      material.name = name + "/" + material.name;
      materials.push_back(material);
    }
    for (const int m : part.elementMaterials()) elementMaterials.push_back(firstMaterial + m);
    firstElement += part.numElements();
  }
  TetMesh mesh = corners == 8 ? TetMesh(positions, HexElements(connectivity), materials, elementMaterials)
                              : TetMesh(positions, Eigen::Matrix4Xi(connectivity), materials, elementMaterials);
  firstElement = 0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const TetMesh& part = parts[i];
    const std::string& name = scene.objects[i].name;
    const auto shifted = [](std::vector<int> ids, int offset) {
      for (int& id : ids) id += offset;
      return ids;
    };
    std::vector<int> all(static_cast<std::size_t>(part.numVertices()));
    for (int v = 0; v < part.numVertices(); ++v) all[static_cast<std::size_t>(v)] = firstVertex[i] + v;
    mesh.setVertexSet(name, all);
    std::vector<int> allElements(static_cast<std::size_t>(part.numElements()));
    for (int e = 0; e < part.numElements(); ++e) allElements[static_cast<std::size_t>(e)] = firstElement + e;
    mesh.setElementSet(name, allElements);
    for (const auto& [set, members] : part.elementSets())
      mesh.setElementSet(name + "/" + set, shifted(members, firstElement));
    for (const auto& [set, members] : part.vertexSets())
      mesh.setVertexSet(name + "/" + set, shifted(members, firstVertex[i]));
    if (!fixed[i].empty()) mesh.setVertexSet(name + "/fixed", shifted(fixed[i], firstVertex[i]));
    firstElement += part.numElements();
  }
  requireApart(scene, mesh, firstVertex);
  return mesh;
}

std::vector<int> objectOfVertex(const Scene& scene, const TetMesh& mesh) {
  if (scene.objects.empty()) return {};
  std::vector<int> object(static_cast<std::size_t>(mesh.numVertices()), -1);
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    for (const int v : mesh.vertexSet(scene.objects[i].name)) object[static_cast<std::size_t>(v)] = static_cast<int>(i);
  }
  return object;
}

namespace {

// An obstacle's surface: read, welded, checked closed and turned outward where it must be
// closed, placed.
MeshObstacle readObstacle(const Scene& scene, std::size_t i) {
  const Scene::Contact::Obstacle& given = scene.contact.obstacles[i];
  const std::string key = "contact.obstacles[" + std::to_string(i) + "].file";
  if (!surfaceReaderAvailable()) {
    throwSceneError(scene, key,
                    "mesh obstacles are read with assimp, and this build has none (configure with "
                    "-DASYNCFEM_WITH_ASSIMP=ON)");
  }
  TriangleSurface surface;
  try {
    surface = readSurface(given.file);
  } catch (const Error& error) {
    throwSceneError(scene, key, error.what());
  }
  weldVertices(surface, 1e-7 * surface.bounds().diagonal().norm());
  if (given.closed) {
    try {
      requireClosedSurface(surface, given.file.string());
    } catch (const Error& error) {
      throwSceneError(scene, key,
                      std::string(error.what()) + "; or set \"closed\": false for a surface both of whose sides repel");
    }
    if (surfaceTopology(surface).signedVolume < 0.0) flipOrientation(surface);
  }
  MeshObstacle obstacle;
  obstacle.name = given.name;
  obstacle.closed = given.closed;
  obstacle.triangles = surface.triangles;
  obstacle.vertices.resize(3, surface.numVertices());
  for (int v = 0; v < surface.numVertices(); ++v)
    obstacle.vertices.col(v) = given.placement.apply(surface.vertices.col(v));
  if (!given.path.empty()) obstacle.path.emplace(given.path);
  return obstacle;
}

double meanEdgeLength(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions) {
  if (surface.numEdges() == 0) return 0.0;
  double sum = 0.0;
  for (int e = 0; e < surface.numEdges(); ++e) {
    sum += (positions.col(surface.edges(0, e)) - positions.col(surface.edges(1, e))).norm();
  }
  return sum / surface.numEdges();
}

}  // namespace

std::shared_ptr<const PenaltyContact> buildSceneContact(const Scene& scene, const TetMesh& mesh) {
  const Scene::Contact& contact = scene.contact;
  if (!contact.enabled()) return nullptr;
  std::shared_ptr<const SurfaceContact> surfaces;
  if (contact.surfaces) {
    std::vector<MeshObstacle> obstacles;
    for (std::size_t i = 0; i < contact.obstacles.size(); ++i) obstacles.push_back(readObstacle(scene, i));
    SurfaceContactOptions options;
    options.thickness =
        contact.surfaces->thickness.value_or(0.2 * meanEdgeLength(boundarySurface(mesh), mesh.restPositions()));
    options.betweenBodies = contact.surfaces->betweenBodies;
    options.self = contact.surfaces->self;
    options.edges = contact.surfaces->edges;
    options.broadPhase = contact.surfaces->broadPhase;
    const PenaltyContactParameters& p = contact.parameters;
    surfaces = std::make_shared<SurfaceContact>(mesh, objectOfVertex(scene, mesh), std::move(obstacles), options,
                                                p.stiffness, p.damping, p.friction, p.frictionViscosity);
  }
  return std::make_shared<PenaltyContact>(mesh.restPositions(), contact.planes, contact.spheres, contact.parameters,
                                          std::move(surfaces));
}

void applyInitialVelocities(const Scene& scene, Simulation& simulation) {
  const bool moving = std::any_of(scene.objects.begin(), scene.objects.end(),
                                  [](const Scene::Object& object) { return !object.velocity.isZero(0.0); });
  if (!moving) return;
  const TetMesh& mesh = simulation.problem->mesh();
  Eigen::VectorXd velocity = Eigen::VectorXd::Zero(mesh.numDofs());
  for (const Scene::Object& object : scene.objects) {
    for (const int v : mesh.vertexSet(object.name))
      velocity.segment<3>(3 * static_cast<Eigen::Index>(v)) = object.velocity;
  }
  for (const int v : simulation.problem->heldVertices())
    velocity.segment<3>(3 * static_cast<Eigen::Index>(v)).setZero();
  simulation.integrator->setState(Eigen::VectorXd::Zero(mesh.numDofs()), velocity, 0.0);
}

std::vector<std::string> surfaceContactSummary(const Simulation& simulation) {
  if (!simulation.contact || !simulation.contact->surfaces()) return {};
  const SurfaceContact& surfaces = *simulation.contact->surfaces();
  const SurfaceContactStats stats = surfaces.stats();
  const double steps = std::max<double>(1.0, static_cast<double>(simulation.integrator->stats().steps));
  char line[400];
  std::snprintf(
      line, sizeof(line),
      "surfaces: %d body and %d obstacle triangles, thickness %.4g; %.1f candidate pairs per broad-phase run "
      "(%lld runs in %lld force evaluations), %.1f active pairs per evaluation (most %lld), detection %.3f ms per "
      "step",
      surfaces.bodySurface().numTriangles(), surfaces.obstacleSurface().numTriangles(), surfaces.options().thickness,
      stats.detections > 0 ? static_cast<double>(stats.candidates) / static_cast<double>(stats.detections) : 0.0,
      stats.detections, stats.evaluations,
      stats.evaluations > 0 ? static_cast<double>(stats.activePairs) / static_cast<double>(stats.evaluations) : 0.0,
      stats.largestActive, 1000.0 * stats.detectionSeconds / steps);
  return {line};
}

}  // namespace asyncfem
