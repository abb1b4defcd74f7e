// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/elementSets.hpp>
#include <asyncfem/tetMesher/exampleModels.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <cmath>
#include <numbers>

namespace asyncfem {

namespace {

using Eigen::Vector3d;

/// Four legs (capsules from the body down) and four feet (flattened ellipsoids on the
/// ground) at x = +-legX, z = +-legZ.
void addLegs(std::vector<ImplicitPart>& parts, double legX, double legZ, double hipY, double legRadius,
             const Vector3d& footRadii) {
  for (int sx = -1; sx <= 1; sx += 2)
    for (int sz = -1; sz <= 1; sz += 2) {
      const Vector3d hip(sx * legX, hipY, sz * legZ);
      const Vector3d ankle(sx * (legX + 0.02), footRadii.y() + 0.06, sz * (legZ + 0.02));
      parts.push_back({"body", implicitCapsule(hip, ankle, legRadius)});
      parts.push_back(
          {"feet", implicitEllipsoid(Vector3d(sx * (legX + 0.03), footRadii.y(), sz * (legZ + 0.02)), footRadii)});
    }
}

ImplicitModel dinosaur() {
  ImplicitModel model;
  std::vector<ImplicitPart>& p = model.parts;
  p.push_back({"body", implicitEllipsoid(Vector3d(0.0, 0.62, 0.0), Vector3d(0.45, 0.27, 0.25))});
  addLegs(p, 0.26, 0.14, 0.55, 0.085, Vector3d(0.12, 0.07, 0.1));
  // Head set = neck + head.
  p.push_back({"head", implicitTaperedCapsule(Vector3d(0.34, 0.72, 0.0), Vector3d(0.7, 1.15, 0.0), 0.13, 0.085)});
  p.push_back({"head", implicitOrientedEllipsoid(Vector3d(0.8, 1.19, 0.0), Vector3d(1.0, -0.25, 0.0), Vector3d::UnitY(),
                                                 Vector3d(0.17, 0.095, 0.095))});
  p.push_back({"tail", implicitTaperedCapsule(Vector3d(-0.38, 0.62, 0.0), Vector3d(-0.85, 0.5, 0.0), 0.14, 0.085)});
  p.push_back({"tail", implicitTaperedCapsule(Vector3d(-0.85, 0.5, 0.0), Vector3d(-1.2, 0.48, 0.0), 0.085, 0.06)});
  model.blend = 0.05;
  model.bounds = Eigen::AlignedBox3d(Vector3d(-1.35, -0.05, -0.4), Vector3d(1.05, 1.4, 0.4));
  model.spacing = 0.075;
  return model;
}

ImplicitModel flower() {
  ImplicitModel model;
  std::vector<ImplicitPart>& p = model.parts;
  p.push_back({"base", implicitEllipsoid(Vector3d(0.0, 0.06, 0.0), Vector3d(0.17, 0.08, 0.17))});
  p.push_back({"stem", implicitCapsule(Vector3d(0.0, 0.08, 0.0), Vector3d(0.0, 0.92, 0.0), 0.045)});
  for (int side = -1; side <= 1; side += 2) {
    p.push_back({"upperLeaves", implicitOrientedEllipsoid(Vector3d(side * 0.16, 0.52, 0.0), Vector3d(side, 0.6, 0.0),
                                                          Vector3d::UnitY(), Vector3d(0.17, 0.04, 0.085))});
  }
  const Vector3d centre(0.0, 0.97, 0.0);
  p.push_back({"petals", implicitSphere(centre, 0.075)});
  for (int i = 0; i < 5; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / 5.0 + 0.3;
    const Vector3d direction(std::cos(angle), 0.3, std::sin(angle));
    p.push_back({"petals", implicitOrientedEllipsoid(centre + 0.14 * Vector3d(std::cos(angle), 0.2, std::sin(angle)),
                                                     direction, Vector3d::UnitY(), Vector3d(0.14, 0.04, 0.075))});
  }
  model.blend = 0.03;
  model.bounds = Eigen::AlignedBox3d(Vector3d(-0.45, -0.05, -0.45), Vector3d(0.45, 1.2, 0.45));
  model.spacing = 0.045;
  return model;
}

const Vector3d kDragonHeadCentre(0.93, 1.05, 0.0);

ImplicitModel dragon() {
  ImplicitModel model;
  std::vector<ImplicitPart>& p = model.parts;
  p.push_back({"body", implicitEllipsoid(Vector3d(0.0, 0.58, 0.0), Vector3d(0.52, 0.25, 0.24))});
  addLegs(p, 0.3, 0.15, 0.5, 0.08, Vector3d(0.12, 0.065, 0.09));
  p.push_back({"neck", implicitTaperedCapsule(Vector3d(0.42, 0.66, 0.0), Vector3d(0.78, 1.02, 0.0), 0.13, 0.085)});
  p.push_back({"head", implicitOrientedEllipsoid(Vector3d(0.9, 1.08, 0.0), Vector3d(1.0, -0.2, 0.0), Vector3d::UnitY(),
                                                 Vector3d(0.18, 0.1, 0.1))});
  p.push_back({"jaw", implicitOrientedEllipsoid(Vector3d(1.0, 0.97, 0.0), Vector3d(1.0, -0.5, 0.0), Vector3d::UnitY(),
                                                Vector3d(0.16, 0.05, 0.075))});
  p.push_back({"tail", implicitTaperedCapsule(Vector3d(-0.45, 0.58, 0.0), Vector3d(-1.0, 0.42, 0.0), 0.14, 0.08)});
  p.push_back({"tail", implicitTaperedCapsule(Vector3d(-1.0, 0.42, 0.0), Vector3d(-1.35, 0.5, 0.0), 0.08, 0.06)});
  p.push_back({"tail", implicitEllipsoid(Vector3d(-1.42, 0.52, 0.0), Vector3d(0.1, 0.06, 0.1))});
  model.blend = 0.04;
  model.bounds = Eigen::AlignedBox3d(Vector3d(-1.6, -0.05, -0.4), Vector3d(1.25, 1.3, 0.4));
  model.spacing = 0.075;
  return model;
}

ImplicitModel drop() {
  ImplicitModel model;
  std::vector<ImplicitPart>& p = model.parts;
  p.push_back({"soft", implicitBox(Vector3d(0.0, 0.35, 0.0), Vector3d(0.28, 0.15, 0.22), 0.08)});
  p.push_back({"stiffPart", implicitCapsule(Vector3d(-0.15, 0.52, 0.0), Vector3d(0.15, 0.52, 0.0), 0.07)});
  model.blend = 0.02;
  model.bounds = Eigen::AlignedBox3d(Vector3d(-0.35, 0.15, -0.3), Vector3d(0.35, 0.65, 0.3));
  model.spacing = 0.06;
  return model;
}

ImplicitModel ball() {
  ImplicitModel model;
  model.parts.push_back({"ball", implicitSphere(Vector3d(0.0, 0.45, 0.0), 0.2)});
  model.bounds = Eigen::AlignedBox3d(Vector3d(-0.25, 0.2, -0.25), Vector3d(0.25, 0.7, 0.25));
  model.spacing = 0.04;
  return model;
}

/// Radii of the nested dragon regions s1 ... s6 around the head centre.
constexpr std::array<double, 6> kDragonRegionRadii{0.15, 0.22, 0.3, 0.4, 0.52, 0.66};

}  // namespace

const std::vector<std::string>& exampleModelNames() {
  static const std::vector<std::string> names{"dinosaur", "flower", "dragon", "drop", "ball"};
  return names;
}

std::string exampleModelName(ExampleModel model) { return exampleModelNames()[static_cast<std::size_t>(model)]; }

ExampleModel exampleModelFromName(const std::string& name) {
  const std::vector<std::string>& names = exampleModelNames();
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<ExampleModel>(i);
  std::string known;
  for (const std::string& n : names) {
    if (!known.empty()) known += ", ";
    known += n;
  }
  throw ValidationError("unknown example model \"" + name + "\" (known: " + known + ")");
}

ImplicitModel exampleModelShape(ExampleModel model) {
  switch (model) {
    case ExampleModel::Dinosaur:
      return dinosaur();
    case ExampleModel::Flower:
      return flower();
    case ExampleModel::Dragon:
      return dragon();
    case ExampleModel::Drop:
      return drop();
    case ExampleModel::Ball:
      return ball();
  }
  throw ValidationError("unknown example model");
}

namespace {

/// The soft default material of each model; the fast parts get stiffer, lighter ones.
Material defaultMaterial(ExampleModel model) {
  switch (model) {
    case ExampleModel::Dinosaur:
      return Material{"body", 1000.0, 1e5, 0.45};
    case ExampleModel::Flower:
      return Material{"stem", 1000.0, 2e5, 0.45};
    case ExampleModel::Dragon:
      return Material{"body", 1000.0, 1.5e5, 0.45};
    case ExampleModel::Drop:
      return Material{"soft", 1000.0, 1e5, 0.45};
    case ExampleModel::Ball:
      return Material{"rubber", 1000.0, 2e5, 0.45};
  }
  throw ValidationError("unknown example model");
}

/// The dragon's nested regions s1 ... s6: the jaw plus the elements whose centroid lies
/// within kDragonRegionRadii of the head centre.
void addDragonRegionSets(TetMesh& mesh) {
  const Eigen::Matrix3Xd centroids = elementCentroids(mesh);
  const std::vector<int> jaw = mesh.elementSet("jaw");
  for (std::size_t k = 0; k < kDragonRegionRadii.size(); ++k) {
    std::vector<int> members = jaw;
    for (int e = 0; e < mesh.numElements(); ++e)
      if ((centroids.col(e) - kDragonHeadCentre).norm() <= kDragonRegionRadii[k]) members.push_back(e);
    std::sort(members.begin(), members.end());
    members.erase(std::unique(members.begin(), members.end()), members.end());
    std::string setName = "s";
    setName += std::to_string(k + 1);
    setElementAndVertexSet(mesh, setName, std::move(members));
  }
}

/// The stiff, light materials of the fast parts (and the dragon's region sets).
void assignFastParts(TetMesh& mesh, ExampleModel model) {
  switch (model) {
    case ExampleModel::Dinosaur:
      // Wave speed sqrt(E / rho): 10 m/s in the body, 158 in head and neck (ratio ~15),
      // 82 in the tail (ratio ~8).
      assignSetMaterial(mesh, "head", Material{"head", 200.0, 5e6, 0.45});
      assignSetMaterial(mesh, "tail", Material{"tail", 300.0, 2e6, 0.45});
      break;
    case ExampleModel::Flower:
      // 14 m/s in stem and base, 175 in the petals (~12x), 141 in the upper leaves (~10x).
      assignSetMaterial(mesh, "petals", Material{"petals", 130.0, 4e6, 0.45});
      assignSetMaterial(mesh, "upperLeaves", Material{"upperLeaves", 150.0, 3e6, 0.45});
      break;
    case ExampleModel::Dragon:
      // 12 m/s in the body, 155 in the jaw (~12x).
      assignSetMaterial(mesh, "jaw", Material{"jaw", 250.0, 6e6, 0.45});
      addDragonRegionSets(mesh);
      break;
    case ExampleModel::Drop:
      // 10 m/s in the soft block, 100 in the stiff handle (10x).
      assignSetMaterial(mesh, "stiffPart", Material{"stiffPart", 300.0, 3e6, 0.45});
      break;
    case ExampleModel::Ball:
      break;  // one material: fast regions come from contact at run time
  }
}

}  // namespace

TetMesh makeExampleModel(ExampleModel model, double spacing, StuffingReport* report, int gradingLevels) {
  const ImplicitModel shape = exampleModelShape(model);
  const std::string name = exampleModelName(model);
  MesherOptions options;
  options.gradingLevels = gradingLevels;
  options.material = defaultMaterial(model);
  TetMesh mesh = stuffIsosurface(implicitUnionOfParts(shape.parts, shape.blend), shape.bounds,
                                 spacing > 0.0 ? spacing : shape.spacing, options, report);
  const MeshCheckReport check = checkTetMesh(mesh);
  if (check.components != 1) {
    throw ValidationError("example model " + name + ": the mesh has " + std::to_string(check.components) +
                          " separate pieces at spacing " + std::to_string(spacing > 0.0 ? spacing : shape.spacing) +
                          "; use a smaller spacing");
  }
  addImplicitPartSets(mesh, shape.parts);
  assignFastParts(mesh, model);
  return mesh;
}

TetMesh makeExampleModelCubes(ExampleModel model, double spacing, VoxelReport* report) {
  const ImplicitModel shape = exampleModelShape(model);
  VoxelOptions options;
  options.material = defaultMaterial(model);
  TetMesh mesh = voxelize(implicitUnionOfParts(shape.parts, shape.blend), shape.bounds,
                          spacing > 0.0 ? spacing : shape.spacing, options, report);
  addImplicitPartSets(mesh, shape.parts);
  assignFastParts(mesh, model);
  return mesh;
}

}  // namespace asyncfem
