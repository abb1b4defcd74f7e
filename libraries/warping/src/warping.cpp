// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/enumNames.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/warping/modalWarping.hpp>
#include <asyncfem/warping/rotationStrainWarping.hpp>
#include <asyncfem/warping/warping.hpp>
#include <string>

namespace asyncfem {

namespace {

/// WarpingKind::none: the linear displacement as it is.
class IdentityWarping final : public Warping {
 public:
  explicit IdentityWarping(int numVertices) : numVertices_(numVertices) {}
  WarpingKind kind() const override { return WarpingKind::none; }
  int numVertices() const override { return numVertices_; }
  Eigen::VectorXd warp(const Eigen::Ref<const Eigen::VectorXd>& displacement) override {
    if (displacement.size() != 3 * static_cast<Eigen::Index>(numVertices_)) {
      throw Error("warping: displacement has " + std::to_string(displacement.size()) + " entries, expected 3 x " +
                  std::to_string(numVertices_));
    }
    return displacement;
  }

 private:
  int numVertices_;
};

}  // namespace

namespace {
constexpr EnumName<WarpingKind> kWarpingNames[] = {
    {WarpingKind::none, "none"}, {WarpingKind::rotationStrain, "rotation-strain"}, {WarpingKind::modal, "modal"}};
}  // namespace

std::string toString(WarpingKind kind) { return std::string(findEnumName(kWarpingNames, kind).value_or("unknown")); }

WarpingKind parseWarpingKind(const std::string& name) {
  if (const std::optional<WarpingKind> kind = findEnumValue(kWarpingNames, name)) return *kind;
  throw Error("unknown warping \"" + name + "\" (expected " + joinEnumNames(kWarpingNames, ", ", " or ") + ")");
}

std::unique_ptr<Warping> makeWarping(WarpingKind kind, const TetMesh& mesh, const std::vector<int>& fixedVertices) {
  switch (kind) {
    case WarpingKind::rotationStrain:
      return std::make_unique<RotationStrainWarping>(mesh, fixedVertices);
    case WarpingKind::modal:
      return std::make_unique<ModalWarping>(mesh);
    case WarpingKind::none:
      break;
  }
  return std::make_unique<IdentityWarping>(mesh.numVertices());
}

Eigen::Matrix3Xd deformedPositions(const TetMesh& mesh, const Eigen::Ref<const Eigen::VectorXd>& displacement) {
  if (displacement.size() != static_cast<Eigen::Index>(mesh.numDofs())) {
    throw Error("deformedPositions: displacement has " + std::to_string(displacement.size()) +
                " entries, expected 3 x " + std::to_string(mesh.numVertices()));
  }
  return mesh.restPositions() + Eigen::Map<const Eigen::Matrix3Xd>(displacement.data(), 3, mesh.numVertices());
}

}  // namespace asyncfem
