// SPDX-License-Identifier: BSD-3-Clause
// HexForceModel's coloured, threaded element loop: the same forces, tangent and energy on
// one thread and on several (bit for bit: the colouring fixes every entry's summation
// order), and equal to a plain element-by-element sum of hexStvk (to round-off: that sum
// adds the contributions in another order), so no element is lost or counted twice.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <asyncfem/hexElements/hexStvk.hpp>
#include <asyncfem/hexElements/hexStvkForceModel.hpp>
#include <cmath>
#include <vector>

#include "hexBar.hpp"

namespace asyncfem {
namespace {

/// The model's sums at one displacement.
struct Evaluation {
  double energy = 0.0;
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> tangent;
};

Evaluation evaluate(HexStvkForceModel& model, const Eigen::VectorXd& u, int threads) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
  Evaluation out;
  out.tangent = model.createStiffnessMatrix();
  model.forcesAndTangent(u, out.forces, out.tangent);
  out.energy = model.elasticEnergy(u);
  omp_set_num_threads(before);
  return out;
}

TEST(HexForceModelThreads, OneThreadAndSeveralAgreeBitForBitAndWithTheElementSum) {
  // 16 x 16 x 8 = 2048 cubes: the smallest mesh the loop runs on threads.
  const TetMesh mesh =
      test::hexBox(Eigen::Vector3i(16, 16, 8), Eigen::Vector3d(1.0, 1.0, 0.5), Material{"m", 1000.0, 1e6, 0.3});
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = mesh.restPosition(v);
    u.segment<3>(3 * v) = 0.05 * Eigen::Vector3d(std::sin(3.0 * x.y()), x.x() * x.z(), std::cos(2.0 * x.x())) +
                          0.001 * Eigen::Vector3d(std::sin(3.0 * v), std::cos(5.0 * v), std::sin(7.0 * v));
  }
  HexStvkForceModel model(mesh);
  const Evaluation serial = evaluate(model, u, 1);
  const Evaluation threaded = evaluate(model, u, 4);
  EXPECT_EQ(serial.energy, threaded.energy);
  EXPECT_EQ((serial.forces - threaded.forces).cwiseAbs().maxCoeff(), 0.0);
  ASSERT_EQ(serial.tangent.nonZeros(), threaded.tangent.nonZeros());  // the fixed pattern, value for value
  EXPECT_EQ((serial.tangent.coeffs() - threaded.tangent.coeffs()).cwiseAbs().maxCoeff(), 0.0);

  Eigen::VectorXd forces = Eigen::VectorXd::Zero(mesh.numDofs());
  std::vector<Eigen::Triplet<double>> entries;
  double energy = 0.0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    HexElementPositions rest, deformed;
    for (int a = 0; a < 8; ++a) {
      const int v = mesh.hexahedron(e)[a];
      rest.col(a) = mesh.restPosition(v);
      deformed.col(a) = rest.col(a) + u.segment<3>(3 * v);
    }
    const HexElementEnergy element = hexStvk(rest, deformed, 1e6, 0.3, true);
    energy += element.energy;
    for (int a = 0; a < 8; ++a) {
      const int va = mesh.hexahedron(e)[a];
      forces.segment<3>(3 * va) += element.force.segment<3>(3 * a);
      for (int b = 0; b < 8; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            entries.emplace_back((3 * va) + i, (3 * mesh.hexahedron(e)[b]) + j,
                                 element.tangent((3 * a) + i, (3 * b) + j));
    }
  }
  Eigen::SparseMatrix<double> tangent(mesh.numDofs(), mesh.numDofs());
  tangent.setFromTriplets(entries.begin(), entries.end());
  // Another summation order of at most 8 terms per entry: 1e-12 of the largest entry is far
  // above its round-off (~1e-15) and far below one element's contribution.
  EXPECT_NEAR(threaded.energy, energy, 1e-12 * energy);
  EXPECT_LE((threaded.forces - forces).cwiseAbs().maxCoeff(), 1e-12 * forces.cwiseAbs().maxCoeff());
  const Eigen::SparseMatrix<double> difference = threaded.tangent - tangent;
  EXPECT_LE(difference.coeffs().cwiseAbs().maxCoeff(), 1e-12 * tangent.coeffs().cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace asyncfem
