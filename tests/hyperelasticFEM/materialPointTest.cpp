// SPDX-License-Identifier: BSD-3-Clause
// IsotropicMaterialPoint (the per-F material law) against IsotropicHyperelasticFEM on one
// tetrahedron: f_a = |V| P g_a and K = |V| G^T (dP/dF) G for every material and every
// inversion option, on moderate, inverted and nearly flat deformations.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/hyperelasticFEM/isotropicMaterialPoint.hpp>
#include <asyncfem/hyperelasticFEM/tetElementGeometry.hpp>
#include <random>
#include <string>
#include <vector>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

using Matrix9d = Eigen::Matrix<double, 9, 9>;

struct OptionCase {
  std::string label;
  HyperelasticOptions options;
};

std::vector<OptionCase> optionCases() {
  std::vector<OptionCase> cases;
  cases.push_back({"defaults (invariant path)", {}});
  HyperelasticOptions stretches;
  stretches.invariantPath = false;
  cases.push_back({"principal stretches only", stretches});
  HyperelasticOptions extrapolate;
  extrapolate.inversionThreshold = 0.2;
  cases.push_back({"threshold 0.2, extrapolate", extrapolate});
  HyperelasticOptions clamp = extrapolate;
  clamp.inversionHandling = InversionHandling::vegaClamp;
  cases.push_back({"threshold 0.2, vega clamp", clamp});
  HyperelasticOptions spd = extrapolate;
  spd.enforceSPD = true;
  spd.enableCompressionResistance = true;
  cases.push_back({"threshold 0.2, enforceSPD, compression resistance", spd});
  return cases;
}

double relativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const double scale = std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff());
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

TEST(IsotropicMaterialPoint, IntegratedOverATetrahedronItIsTheTetrahedralModel) {
  const TetMesh mesh = test::unitTet();
  const TetElementGeometry geometry(mesh, "test");
  const Eigen::Matrix<double, 3, 4>& g = geometry.shapeGradients[0];
  const double volume = geometry.volumes[0];
  std::mt19937 random(7);
  const Eigen::Matrix3d left = test::randomRotation(random);
  const Eigen::Matrix3d right = test::randomRotation(random);
  const std::vector<Eigen::Vector3d> stretchSets = {{1.3, 0.9, 0.8}, {1.05, 0.9, -0.3}, {1.2, 0.1, -0.5}};
  for (const HyperelasticMaterialKind kind :
       {HyperelasticMaterialKind::stvk, HyperelasticMaterialKind::neoHookean, HyperelasticMaterialKind::mooneyRivlin}) {
    for (const OptionCase& option : optionCases()) {
      HyperelasticOptions options = option.options;
      if (kind == HyperelasticMaterialKind::stvk) options.stvkFormulation = StVKFormulation::principalStretches;
      IsotropicHyperelasticFEM model(mesh, kind, options);
      const IsotropicMaterialPoint point(kind, mesh.elementMaterial(0), options);
      for (const Eigen::Vector3d& s : stretchSets) {
        SCOPED_TRACE(toString(kind) + ", " + option.label + ", stretches " + std::to_string(s[2]));
        const Eigen::Matrix3d f = left * s.asDiagonal() * right.transpose();
        double energy = 0.0;
        ElementVector force;
        ElementMatrix tangent;
        model.elementTerms(test::homogeneousDisplacement(mesh, f), 0, &energy, &force, &tangent);
        double density = 0.0;
        Eigen::Matrix3d stress;
        Matrix9d derivative;
        point.evaluate(f, &density, &stress, &derivative);
        const Eigen::Matrix<double, 3, 4> nodal = volume * stress * g;
        ElementMatrix integrated;
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b)
            for (int c = 0; c < 3; ++c)
              for (int d = 0; d < 3; ++d) {
                integrated((3 * a) + c, (3 * b) + d) =
                    volume * g.col(a).dot(derivative.block<3, 3>(3 * c, 3 * d) * g.col(b));
              }
        // The same arithmetic in another order (world frame against the tetrahedron's
        // rotated frame): equal to a few hundred roundings of the largest entry.
        EXPECT_NEAR(volume * density, energy, 1e-13 * std::abs(energy) + 1e-300);
        EXPECT_LE(relativeDifference(Eigen::Map<const ElementVector>(nodal.data()), force), 1e-12);
        EXPECT_LE(relativeDifference(integrated, tangent), 1e-12);
      }
    }
  }
}

TEST(IsotropicMaterialPoint, RefusesMooneyRivlinWithoutParametersAndBadOptions) {
  const Material plain{"plain", 1000.0, 1e6, 0.3};
  try {
    IsotropicMaterialPoint point(HyperelasticMaterialKind::mooneyRivlin, plain);
    ADD_FAILURE() << "accepted a Mooney-Rivlin material without parameters";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("'plain'"), std::string::npos) << error.what();
  }
  HyperelasticOptions options;
  options.inversionThreshold = 1.5;
  EXPECT_THROW(IsotropicMaterialPoint(HyperelasticMaterialKind::neoHookean, plain, options), ValidationError);
  options = {};
  options.mooneyRivlin = MooneyRivlinParameters{1e4, 5e4, 1e6};
  EXPECT_NO_THROW(IsotropicMaterialPoint(HyperelasticMaterialKind::mooneyRivlin, plain, options));
}

}  // namespace
}  // namespace asyncfem
