// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace asyncfem {

/// Parameters of Vega FEM's compressible Mooney-Rivlin material (all in stress units,
/// e.g. Pa), strain energy density per rest volume
///     W = mu01 (I2bar - 3) + mu10 (I1bar - 3) + v1 (J - 1)^2,
/// with I1bar = I1 / J^(2/3), I2bar = I2 / J^(4/3) the isochoric invariants of
/// C = F^T F and J = det F. Small strains: shear modulus G = 2 (mu10 + mu01), bulk
/// modulus K = 2 v1.
struct MooneyRivlinParameters {
  double mu01 = 0.0;
  double mu10 = 0.0;
  double v1 = 0.0;

  /// The small-strain Young's modulus E = 9 K G / (3 K + G) and Poisson ratio
  /// nu = (3 K - 2 G) / (2 (3 K + G)) of G and K above; meaningful for G > 0, K > 0.
  double equivalentYoungsModulus() const {
    const double shear = 2.0 * (mu10 + mu01);
    const double bulk = 2.0 * v1;
    return 9.0 * bulk * shear / ((3.0 * bulk) + shear);
  }
  double equivalentPoissonRatio() const {
    const double shear = 2.0 * (mu10 + mu01);
    const double bulk = 2.0 * v1;
    return ((3.0 * bulk) - (2.0 * shear)) / (2.0 * ((3.0 * bulk) + shear));
  }

  bool operator==(const MooneyRivlinParameters&) const = default;
};

/// Isotropic linear-elastic material. SI units are conventional but not required;
/// the toolkit only needs them consistent.
struct Material {
  Material() = default;
  /// Positional form, Material{name, density, E, nu} (and optionally the Mooney-Rivlin
  /// block); a constructor rather than aggregate initialisation so that the optional
  /// block can be left out without compiler warnings.
  Material(std::string materialName, double materialDensity, double materialYoungsModulus, double materialPoissonRatio,
           std::optional<MooneyRivlinParameters> mooneyRivlinParameters = std::nullopt)
      : name(std::move(materialName)),
        density(materialDensity),
        youngsModulus(materialYoungsModulus),
        poissonRatio(materialPoissonRatio),
        mooneyRivlin(mooneyRivlinParameters) {}

  std::string name;
  double density = 1000.0;     ///< rho, mass per volume (kg/m^3)
  double youngsModulus = 1e6;  ///< E (Pa)
  double poissonRatio = 0.45;  ///< nu, in (-1, 0.5)
  /// Set for materials given as Mooney-Rivlin (.veg MOONEYRIVLIN lines); then E and nu
  /// hold the small-strain equivalent (from G and K above) so that linear and
  /// corotational models still apply, and the hyperelastic Mooney-Rivlin model reads
  /// these parameters.
  std::optional<MooneyRivlinParameters> mooneyRivlin;

  bool operator==(const Material&) const = default;
};

/// The element kind of a volumetric mesh; a mesh holds elements of one kind.
enum class ElementKind {
  tetrahedron,  ///< linear 4-node tetrahedron
  hexahedron,   ///< trilinear 8-node hexahedron, vertices in VTK / Vega / Gmsh order (hexahedron.hpp)
};
/// 4 for tetrahedra, 8 for hexahedra.
constexpr int verticesPerElement(ElementKind kind) { return kind == ElementKind::hexahedron ? 8 : 4; }
/// "tetrahedra" or "hexahedra", for messages.
const char* elementKindPlural(ElementKind kind);

/// Connectivity of a hexahedral mesh: 8 x numElements, 0-based vertex ids per column.
using HexElements = Eigen::Matrix<int, 8, Eigen::Dynamic>;
using Vector8i = Eigen::Matrix<int, 8, 1>;

/// The volumetric mesh of the toolkit: linear (4-node) tetrahedra or trilinear (8-node)
/// hexahedra (elementKind(); one kind per mesh), with a material per element and named
/// vertex and element sets. Indices are 0-based everywhere in the API; readers and
/// writers convert. The name is historical (the toolkit began with tetrahedra only);
/// `VolumetricMesh` is an alias.
///
/// Code that handles one kind only asks elementKind() or calls requireTetrahedra(what),
/// which throws a ValidationError naming `what`. The tetrahedral accessors (elements(),
/// element(e), elementRestPositions(e), setElement) throw the same error on a hexahedral
/// mesh, so a tetrahedra-only path that forgot to check fails with a message instead of
/// reading out of bounds; connectivity() and elementVertex() serve both kinds.
///
/// Invariants (checked by the constructor and the mutators, which throw
/// asyncfem::ValidationError naming the offending element, vertex, set or material):
/// - every element index is in [0, numVertices), the indices of an element differ;
/// - every element has a material index in [0, materials().size());
/// - every material has E > 0, rho > 0, -1 < nu < 0.5, all finite;
/// - all rest positions are finite;
/// - set members are in range; set names are non-empty.
/// Element orientation (positive signed volume) is the readers' business (see
/// readers.hpp), not an invariant of this class, so algorithms that need it check.
class TetMesh {
 public:
  TetMesh() = default;
  /// restPositions: 3 x numVertices; elements: 4 x numElements (0-based vertex ids);
  /// elementMaterials: numElements entries, each an index into materials.
  TetMesh(Eigen::Matrix3Xd restPositions, Eigen::Matrix4Xi elements, std::vector<Material> materials,
          std::vector<int> elementMaterials);
  /// A hexahedral mesh. hexahedra: 8 x numElements (0-based vertex ids in VTK order,
  /// hexahedron.hpp); the rest as for tetrahedra. Orientation and shape (a positive
  /// Jacobian at every corner) are the readers' business, as for tetrahedra.
  TetMesh(Eigen::Matrix3Xd restPositions, HexElements hexahedra, std::vector<Material> materials,
          std::vector<int> elementMaterials);

  ElementKind elementKind() const { return kind_; }
  bool isHexahedral() const { return kind_ == ElementKind::hexahedron; }
  /// 4 or 8.
  int verticesPerElement() const { return asyncfem::verticesPerElement(kind_); }
  /// Throws ValidationError "<what> supports tetrahedral meshes only; this mesh has N
  /// hexahedra (...)" on a hexahedral mesh, with the command that converts it.
  void requireTetrahedra(std::string_view what) const {
    if (kind_ != ElementKind::tetrahedron) throwTetrahedraOnly(what);
  }

  int numVertices() const { return static_cast<int>(restPositions_.cols()); }
  int numElements() const {
    return static_cast<int>(kind_ == ElementKind::tetrahedron ? elements_.cols() : hexahedra_.cols());
  }
  /// Number of degrees of freedom, 3 * numVertices.
  int numDofs() const { return 3 * numVertices(); }

  const Eigen::Matrix3Xd& restPositions() const { return restPositions_; }
  Eigen::Vector3d restPosition(int vertex) const { return restPositions_.col(vertex); }
  /// Tetrahedra, 4 x numElements (throws on a hexahedral mesh, see requireTetrahedra).
  const Eigen::Matrix4Xi& elements() const {
    requireTetrahedra(
        "TetMesh::elements() (the tetrahedral connectivity; hexahedra() and connectivity() serve both kinds)");
    return elements_;
  }
  Eigen::Vector4i element(int e) const { return elements().col(e); }
  /// 3 x 4 matrix of the rest positions of element e's vertices (columns in element order).
  Eigen::Matrix<double, 3, 4> elementRestPositions(int e) const;

  /// Hexahedra, 8 x numElements (throws ValidationError on a tetrahedral mesh).
  const HexElements& hexahedra() const;
  Vector8i hexahedron(int e) const { return hexahedra().col(e); }
  /// 3 x 8 matrix of the rest positions of hexahedron e's vertices.
  Eigen::Matrix<double, 3, 8> hexahedronRestPositions(int e) const;

  /// Either kind: verticesPerElement() x numElements view of the connectivity.
  Eigen::Map<const Eigen::MatrixXi> connectivity() const {
    return {kind_ == ElementKind::tetrahedron ? elements_.data() : hexahedra_.data(), verticesPerElement(),
            numElements()};
  }
  /// Either kind: vertex a (0 <= a < verticesPerElement()) of element e.
  int elementVertex(int e, int a) const {
    return kind_ == ElementKind::tetrahedron ? elements_(a, e) : hexahedra_(a, e);
  }

  const std::vector<Material>& materials() const { return materials_; }
  const std::vector<int>& elementMaterials() const { return elementMaterials_; }
  int elementMaterialIndex(int e) const { return elementMaterials_[static_cast<std::size_t>(e)]; }
  const Material& elementMaterial(int e) const { return materials_[static_cast<std::size_t>(elementMaterialIndex(e))]; }
  /// Index of the material called name, or -1.
  int findMaterial(const std::string& name) const;
  /// Adds a material (or replaces the one with the same name) and returns its index.
  int addMaterial(const Material& material);
  /// Assigns material index to every element of the element set called setName.
  void assignMaterial(const std::string& setName, int materialIndex);

  /// Named element sets (sorted, unique, 0-based element ids).
  const std::map<std::string, std::vector<int>>& elementSets() const { return elementSets_; }
  /// Named vertex sets (sorted, unique, 0-based vertex ids).
  const std::map<std::string, std::vector<int>>& vertexSets() const { return vertexSets_; }
  /// The element set called name; "allElements" always exists implicitly.
  /// Throws ValidationError naming the set (and listing the known ones) if absent.
  std::vector<int> elementSet(const std::string& name) const;
  /// The vertex set called name; throws ValidationError naming it if absent.
  const std::vector<int>& vertexSet(const std::string& name) const;
  /// The vertices a set of either kind names: the vertex set called name if there is one,
  /// else every vertex of the element set called name (Vega meshes carry element sets
  /// only), sorted and unique. Throws ValidationError naming it and listing the sets of
  /// both kinds if neither exists. Every place that takes "a set" (loads, fixed
  /// vertices, regions, tints) resolves it through here.
  std::vector<int> setVertices(const std::string& name) const;
  /// Adds or replaces a set; members are sorted and de-duplicated, range-checked.
  void setElementSet(const std::string& name, std::vector<int> elements);
  void setVertexSet(const std::string& name, std::vector<int> vertices);
  /// Renames the element set and/or the vertex set called from to to (e.g. a Gmsh group
  /// name with a space, which .veg cannot hold). Throws ValidationError when no set is
  /// called from (listing the sets), when to is empty or names a set of the same kind.
  void renameSet(const std::string& from, const std::string& to);

  /// Replaces the vertex order of element e (used by readers to fix orientation).
  void setElement(int e, const Eigen::Vector4i& vertices);

 private:
  void validate() const;
  [[noreturn]] void throwTetrahedraOnly(std::string_view what) const;

  ElementKind kind_ = ElementKind::tetrahedron;
  Eigen::Matrix3Xd restPositions_;
  Eigen::Matrix4Xi elements_;  ///< tetrahedral meshes only (empty otherwise)
  HexElements hexahedra_;      ///< hexahedral meshes only (empty otherwise)
  std::vector<Material> materials_;
  std::vector<int> elementMaterials_;
  std::map<std::string, std::vector<int>> elementSets_;
  std::map<std::string, std::vector<int>> vertexSets_;
};

/// The volumetric mesh under its general name (tetrahedra or hexahedra).
using VolumetricMesh = TetMesh;

}  // namespace asyncfem
