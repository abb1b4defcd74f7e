// SPDX-License-Identifier: BSD-3-Clause
#include "detail/subMeshModel.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/hexElements/hexCorotationalForceModel.hpp>
#include <asyncfem/hexElements/hexHyperelasticForceModel.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <regex>
#include <string>

namespace asyncfem::detail {

namespace {

/// The hyperelastic material of a backend model kind (the others have none).
HyperelasticMaterialKind hyperelasticMaterial(PetscForceModelKind kind) {
  switch (kind) {
    case PetscForceModelKind::stvk:
      return HyperelasticMaterialKind::stvk;
    case PetscForceModelKind::neoHookean:
      return HyperelasticMaterialKind::neoHookean;
    case PetscForceModelKind::mooneyRivlin:
      return HyperelasticMaterialKind::mooneyRivlin;
    default:
      break;
  }
  throw Error("PETSc backend: the " + toString(kind) + " model is not hyperelastic");
}

}  // namespace

TetMesh subMesh(const TetMesh& mesh, const std::vector<int>& elements, std::vector<int>& meshVertex) {
  meshVertex.clear();
  const int corners = mesh.verticesPerElement();
  for (int e : elements) {
    for (int a = 0; a < corners; ++a) meshVertex.push_back(mesh.elementVertex(e, a));
  }
  std::sort(meshVertex.begin(), meshVertex.end());
  meshVertex.erase(std::unique(meshVertex.begin(), meshVertex.end()), meshVertex.end());
  std::vector<int> subVertex(static_cast<std::size_t>(mesh.numVertices()), -1);
  Eigen::Matrix3Xd positions(3, static_cast<Eigen::Index>(meshVertex.size()));
  for (std::size_t i = 0; i < meshVertex.size(); ++i) {
    subVertex[static_cast<std::size_t>(meshVertex[i])] = static_cast<int>(i);
    positions.col(static_cast<Eigen::Index>(i)) = mesh.restPositions().col(meshVertex[i]);
  }
  Eigen::MatrixXi connectivity(corners, static_cast<Eigen::Index>(elements.size()));
  std::vector<int> materials;
  materials.reserve(elements.size());
  for (std::size_t k = 0; k < elements.size(); ++k) {
    for (int a = 0; a < corners; ++a) {
      connectivity(a, static_cast<Eigen::Index>(k)) =
          subVertex[static_cast<std::size_t>(mesh.elementVertex(elements[k], a))];
    }
    materials.push_back(mesh.elementMaterialIndex(elements[k]));
  }
  if (mesh.isHexahedral())
    return TetMesh(std::move(positions), HexElements(connectivity), mesh.materials(), std::move(materials));
  return TetMesh(std::move(positions), Eigen::Matrix4Xi(connectivity), mesh.materials(), std::move(materials));
}

// As Problem builds them: on hexahedra the hexahedral kernels (corotational FEM's exact
// tangent the derivative of R K v, makeHexHyperelasticForceModel for the materials).
std::unique_ptr<ForceModel> makeSubMeshModel(const TetMesh& mesh, PetscForceModelKind kind, TangentKind tangent,
                                             const HyperelasticOptions& hyperelastic) {
  if (kind == PetscForceModelKind::linear) throw Error("PETSc backend: the linear model has no local force model");
  if (kind == PetscForceModelKind::corotational) {
    if (mesh.isHexahedral()) return std::make_unique<HexCorotationalForceModel>(mesh, tangent == TangentKind::simple);
    return std::make_unique<CorotationalLinearFEM>(mesh, tangent);
  }
  const HyperelasticMaterialKind material = hyperelasticMaterial(kind);
  return mesh.isHexahedral() ? makeHexHyperelasticForceModel(mesh, material, hyperelastic)
                             : makeHyperelasticForceModel(mesh, material, hyperelastic);
}

void inMeshNumbering(const std::vector<int>& meshElement, const std::function<void()>& work) {
  const auto translate = [&](const std::string& message) {
    static const std::regex elementNumber("element (\\d+)");
    std::string result;
    auto last = message.cbegin();
    for (std::sregex_iterator it(message.begin(), message.end(), elementNumber), end; it != end; ++it) {
      const std::size_t sub = std::stoul((*it)[1].str());
      result.append(last, message.cbegin() + it->position());
      result += "element " + (sub < meshElement.size() ? std::to_string(meshElement[sub]) : (*it)[1].str());
      last = message.cbegin() + it->position() + it->length();
    }
    result.append(last, message.cend());
    return result;
  };
  try {
    work();
  } catch (const NumericalError& error) {
    throw NumericalError(translate(error.what()));
  } catch (const ValidationError& error) {
    throw ValidationError(translate(error.what()));
  } catch (const Error& error) {
    throw Error(translate(error.what()));
  }
}

}  // namespace asyncfem::detail
