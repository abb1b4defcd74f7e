// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/elementSets.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <memory>

namespace asyncfem {

Eigen::Matrix3Xd elementCentroids(const TetMesh& mesh) {
  Eigen::Matrix3Xd centroids(3, mesh.numElements());
  const int n = mesh.verticesPerElement();
  for (int e = 0; e < mesh.numElements(); ++e) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int a = 0; a < n; ++a) sum += mesh.restPosition(mesh.elementVertex(e, a));
    centroids.col(e) = sum / n;
  }
  return centroids;
}

void setElementAndVertexSet(TetMesh& mesh, const std::string& name, std::vector<int> elements) {
  std::vector<int> vertices;
  const int n = mesh.verticesPerElement();
  vertices.reserve(static_cast<std::size_t>(n) * elements.size());
  for (int e : elements)
    for (int a = 0; a < n; ++a) vertices.push_back(mesh.elementVertex(e, a));
  mesh.setElementSet(name, std::move(elements));
  mesh.setVertexSet(name, std::move(vertices));
}

int addBoxSet(TetMesh& mesh, const std::string& name, const Eigen::AlignedBox3d& box) {
  const Eigen::Matrix3Xd centroids = elementCentroids(mesh);
  std::vector<int> members;
  for (int e = 0; e < mesh.numElements(); ++e)
    if (box.contains(centroids.col(e))) members.push_back(e);
  const int count = static_cast<int>(members.size());
  setElementAndVertexSet(mesh, name, std::move(members));
  return count;
}

std::vector<int> addImplicitPartSets(TetMesh& mesh, const std::vector<ImplicitPart>& parts) {
  std::vector<std::string> names;
  std::map<std::string, int> nameIndex;
  std::vector<int> partToName;
  for (const ImplicitPart& part : parts) {
    const auto [it, inserted] = nameIndex.try_emplace(part.name, static_cast<int>(names.size()));
    if (inserted) names.push_back(part.name);
    partToName.push_back(it->second);
  }
  std::vector<std::vector<int>> members(names.size());
  const Eigen::Matrix3Xd centroids = elementCentroids(mesh);
  for (int e = 0; e < mesh.numElements(); ++e) {
    int best = -1;
    double bestValue = std::numeric_limits<double>::infinity();
    for (std::size_t p = 0; p < parts.size(); ++p) {
      const double value = parts[p].function(centroids.col(e));
      if (value < bestValue) {
        bestValue = value;
        best = static_cast<int>(p);
      }
    }
    if (best >= 0) members[static_cast<std::size_t>(partToName[static_cast<std::size_t>(best)])].push_back(e);
  }
  std::vector<int> counts;
  for (std::size_t n = 0; n < names.size(); ++n) {
    counts.push_back(static_cast<int>(members[n].size()));
    setElementAndVertexSet(mesh, names[n], std::move(members[n]));
  }
  return counts;
}

std::vector<int> addNearestPartSets(TetMesh& mesh, const SignedDistance& distance) {
  const TriangleSurface& surface = distance.surface();
  std::vector<std::vector<int>> members(surface.partNames.size());
  const Eigen::Matrix3Xd centroids = elementCentroids(mesh);
  for (int e = 0; e < mesh.numElements(); ++e) {
    int triangle = -1;
    distance.distance(centroids.col(e), &triangle);
    const int part = surface.triangleParts.empty() ? 0 : surface.triangleParts[static_cast<std::size_t>(triangle)];
    members[static_cast<std::size_t>(part)].push_back(e);
  }
  std::vector<int> counts;
  for (std::size_t p = 0; p < members.size(); ++p) {
    counts.push_back(static_cast<int>(members[p].size()));
    if (!members[p].empty()) setElementAndVertexSet(mesh, surface.partNames[p], std::move(members[p]));
  }
  return counts;
}

namespace {

/// One kind of triangle label of a surface: each triangle's label and the labels' names.
struct SurfaceLabels {
  const std::vector<int>& labels;
  const std::vector<std::string>& names;
};

SurfaceLabels surfaceLabels(const TriangleSurface& surface, SurfaceLabel kind) {
  const auto require = [&](const std::vector<int>& labels, const std::vector<std::string>& names, const char* what) {
    if (labels.size() != static_cast<std::size_t>(surface.numTriangles()) || names.empty()) {
      throw ValidationError(std::string("the surface has no ") + what + " to make element sets from");
    }
    return SurfaceLabels{labels, names};
  };
  switch (kind) {
    case SurfaceLabel::Part:
      return require(surface.triangleParts, surface.partNames, "parts");
    case SurfaceLabel::Material:
      return require(surface.triangleMaterials, surface.materialNames, "materials");
    case SurfaceLabel::Group:
      return require(surface.triangleGroups, surface.groupNames, "named groups");
  }
  throw ValidationError("unknown surface label");
}

/// One label's triangles as a surface of their own, for its winding number.
struct LabelSurface {
  std::unique_ptr<SignedDistance> distance;  ///< null for a label without triangles
  Eigen::AlignedBox3d box;
  double volume = 0.0;
};

std::vector<LabelSurface> labelSurfaces(const TriangleSurface& surface, const SurfaceLabels& labels) {
  std::vector<LabelSurface> byLabel(labels.names.size());
  for (std::size_t l = 0; l < labels.names.size(); ++l) {
    std::vector<int> keep;
    for (int t = 0; t < surface.numTriangles(); ++t)
      if (labels.labels[static_cast<std::size_t>(t)] == static_cast<int>(l)) keep.push_back(t);
    if (keep.empty()) continue;
    TriangleSurface own = surface;
    selectTriangles(own, keep);
    byLabel[l].box = own.bounds();
    byLabel[l].volume = std::abs(surfaceTopology(own).signedVolume);
    byLabel[l].distance = std::make_unique<SignedDistance>(std::move(own), SignMode::WindingNumber);
  }
  return byLabel;
}

/// The innermost (smallest) label surface whose winding number at x exceeds 1/2, or -1.
int innermostLabel(const std::vector<LabelSurface>& byLabel, const Eigen::Vector3d& x) {
  int best = -1;
  for (std::size_t l = 0; l < byLabel.size(); ++l) {
    const LabelSurface& label = byLabel[l];
    if (!label.distance || !label.box.contains(x)) continue;
    if (std::abs(label.distance->windingNumber(x)) <= 0.5) continue;
    if (best < 0 || label.volume < byLabel[static_cast<std::size_t>(best)].volume) best = static_cast<int>(l);
  }
  return best;
}

}  // namespace

std::vector<int> addSurfaceLabelSets(TetMesh& mesh, const SignedDistance& distance, SurfaceLabel kind) {
  const TriangleSurface& surface = distance.surface();
  const SurfaceLabels labels = surfaceLabels(surface, kind);
  const std::vector<LabelSurface> byLabel = labelSurfaces(surface, labels);
  std::vector<std::vector<int>> members(labels.names.size());
  const Eigen::Matrix3Xd centroids = elementCentroids(mesh);
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector3d x = centroids.col(e);
    int best = innermostLabel(byLabel, x);
    if (best < 0) {
      int triangle = -1;
      distance.distance(x, &triangle);
      best = labels.labels[static_cast<std::size_t>(triangle)];
    }
    members[static_cast<std::size_t>(best)].push_back(e);
  }
  std::vector<int> counts;
  for (std::size_t l = 0; l < members.size(); ++l) {
    counts.push_back(static_cast<int>(members[l].size()));
    if (!members[l].empty()) setElementAndVertexSet(mesh, labels.names[l], std::move(members[l]));
  }
  return counts;
}

void assignSetMaterial(TetMesh& mesh, const std::string& set, const Material& material) {
  mesh.elementSet(set);  // throws, naming the known sets, if absent
  const int index = mesh.addMaterial(material);
  mesh.assignMaterial(set, index);
}

}  // namespace asyncfem
