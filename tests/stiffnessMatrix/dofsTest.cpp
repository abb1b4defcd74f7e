// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <random>
#include <string>
#include <vector>

#include "testMeshes.hpp"

namespace asyncfem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

template <class F>
std::string errorMessage(F&& f) {
  try {
    f();
  } catch (const ValidationError& error) {
    return error.what();
  }
  return "(no ValidationError)";
}

TEST(FreeDofs, RestrictExpandRoundTrip) {
  const FreeDofs dofs(10, {7, 2, 2, 9});
  EXPECT_EQ(dofs.numDofs(), 10);
  EXPECT_EQ(dofs.numFree(), 7);
  EXPECT_EQ(dofs.numFixed(), 3);
  EXPECT_EQ(dofs.freeToFull(), (std::vector<int>{0, 1, 3, 4, 5, 6, 8}));
  EXPECT_EQ(dofs.fullToFree()[2], -1);
  EXPECT_EQ(dofs.fullToFree()[8], 6);
  EXPECT_TRUE(dofs.isFixed(9));
  EXPECT_FALSE(dofs.isFixed(0));

  const Eigen::VectorXd free = Eigen::VectorXd::LinSpaced(7, 1.0, 7.0);
  const Eigen::VectorXd full = dofs.expand(free);
  ASSERT_EQ(full.size(), 10);
  EXPECT_EQ(full[2], 0.0);
  EXPECT_EQ(full[7], 0.0);
  EXPECT_EQ(full[9], 0.0);
  EXPECT_EQ(dofs.restrict(full), free);  // exact: entries are copied
  const Eigen::VectorXd any = Eigen::VectorXd::LinSpaced(10, -1.0, 1.0);
  const Eigen::VectorXd projected = dofs.expand(dofs.restrict(any));
  for (int i = 0; i < 10; ++i) EXPECT_EQ(projected[i], dofs.isFixed(i) ? 0.0 : any[i]);

  const FreeDofs vertices = FreeDofs::fromFixedVertices(4, {3, 1});
  EXPECT_EQ(vertices.freeToFull(), (std::vector<int>{0, 1, 2, 6, 7, 8}));
}

TEST(FreeDofs, ErrorsNameTheOffendingIndex) {
  const std::string dofMessage = errorMessage([] { FreeDofs(12, {0, 12}); });
  EXPECT_NE(dofMessage.find("fixed DOF 12"), std::string::npos) << dofMessage;
  EXPECT_NE(dofMessage.find("[0, 12)"), std::string::npos) << dofMessage;
  const std::string negative = errorMessage([] { FreeDofs(12, {-1}); });
  EXPECT_NE(negative.find("fixed DOF -1"), std::string::npos) << negative;
  const std::string vertexMessage = errorMessage([] { FreeDofs::fromFixedVertices(5, {5}); });
  EXPECT_NE(vertexMessage.find("fixed vertex 5"), std::string::npos) << vertexMessage;
  const FreeDofs dofs(6, {1});
  EXPECT_THROW(dofs.restrict(Eigen::VectorXd::Zero(5)), Error);
  EXPECT_THROW(dofs.expand(Eigen::VectorXd::Zero(6)), Error);
}

// A random rows x cols sparse matrix with about density * rows * cols entries.
SparseMatrix randomSparse(int rows, int cols, double density, std::mt19937& random) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::bernoulli_distribution keep(density);
  std::vector<Eigen::Triplet<double>> triplets;
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i)
      if (keep(random)) triplets.emplace_back(i, j, uniform(random));
  SparseMatrix matrix(rows, cols);
  matrix.setFromTriplets(triplets.begin(), triplets.end());
  return matrix;
}

std::vector<int> randomAscending(int size, double fraction, std::mt19937& random) {
  std::bernoulli_distribution keep(fraction);
  std::vector<int> indices;
  for (int i = 0; i < size; ++i)
    if (keep(random)) indices.push_back(i);
  return indices;
}

Eigen::MatrixXd denseBlock(const Eigen::MatrixXd& dense, const std::vector<int>& rows, const std::vector<int>& cols) {
  Eigen::MatrixXd block(rows.size(), cols.size());
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < cols.size(); ++j) block(i, j) = dense(rows[i], cols[j]);
  return block;
}

TEST(SubmatrixExtractor, MatchesDenseReferenceOnRandomIndexSets) {
  std::mt19937 random(2024);
  for (int trial = 0; trial < 20; ++trial) {
    SparseMatrix full = randomSparse(37, 29, 0.2, random);
    const std::vector<int> rows = randomAscending(37, trial % 2 == 0 ? 0.5 : 0.9, random);
    const std::vector<int> cols = randomAscending(29, trial % 3 == 0 ? 0.3 : 0.7, random);
    const SubmatrixExtractor extractor(full, rows, cols);
    SparseMatrix sub = extractor.extract(full);
    ASSERT_TRUE(sub.isCompressed());
    // Values are copied, never computed: exact.
    EXPECT_EQ(Eigen::MatrixXd(sub), denseBlock(Eigen::MatrixXd(full), rows, cols)) << "trial " << trial;
    for (int c = 0; c < sub.cols(); ++c)
      for (int p = sub.outerIndexPtr()[c] + 1; p < sub.outerIndexPtr()[c + 1]; ++p)
        ASSERT_LT(sub.innerIndexPtr()[p - 1], sub.innerIndexPtr()[p]);

    // New values, same pattern: update() copies them.
    std::uniform_real_distribution<double> uniform(-5.0, 5.0);
    for (int k = 0; k < full.nonZeros(); ++k) full.valuePtr()[k] = uniform(random);
    extractor.update(full, sub);
    EXPECT_EQ(Eigen::MatrixXd(sub), denseBlock(Eigen::MatrixXd(full), rows, cols)) << "trial " << trial;
  }
}

TEST(SubmatrixExtractor, ExtractsFreeSystemOfAssembledStiffness) {
  const TetMesh mesh = test::mixedMaterialBox(3);
  const MatrixAssembler assembler(mesh);
  SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
  const SubmatrixExtractor extractor(k, dofs.freeToFull(), dofs.freeToFull());
  SparseMatrix free = extractor.extract(k);
  EXPECT_EQ(free.rows(), dofs.numFree());
  EXPECT_EQ(Eigen::MatrixXd(free), denseBlock(Eigen::MatrixXd(k), dofs.freeToFull(), dofs.freeToFull()));
  // A rectangular coupling block (free rows, fixed columns).
  std::vector<int> fixed;
  for (int i = 0; i < dofs.numDofs(); ++i)
    if (dofs.isFixed(i)) fixed.push_back(i);
  const SubmatrixExtractor coupling(k, dofs.freeToFull(), fixed);
  EXPECT_EQ(Eigen::MatrixXd(coupling.extract(k)), denseBlock(Eigen::MatrixXd(k), dofs.freeToFull(), fixed));
  // Re-assembled values flow through update().
  SparseMatrix twice = k;
  twice *= 2.0;
  extractor.update(twice, free);
  EXPECT_EQ(Eigen::MatrixXd(free), 2.0 * denseBlock(Eigen::MatrixXd(k), dofs.freeToFull(), dofs.freeToFull()));
}

// Stiffness and consistent mass of the mixed-material box (one assembler, one pattern),
// with the free DOFs of its xmin face held.
struct BoxMatrices {
  TetMesh mesh = test::mixedMaterialBox(3);
  MatrixAssembler assembler{mesh};
  SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  SparseMatrix m = massMatrix(mesh, assembler, MassType::consistent);
  FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
};

// updateCombination: a A + b B on the block in one pass equals the sum of the two
// extractions (each entry a A_ij + b B_ij, the same two products and one sum: exact), for M
// and K of one mesh (one assembler, one pattern); a matrix of another pattern is refused.
TEST(SubmatrixExtractor, CombinesTwoMatricesOfOnePattern) {
  const BoxMatrices box;
  const SparseMatrix& k = box.k;
  const SparseMatrix& m = box.m;
  const FreeDofs& dofs = box.dofs;
  const SubmatrixExtractor extractor(m, dofs.freeToFull(), dofs.freeToFull());
  SparseMatrix combined = extractor.extract(m);
  const double a = 1.0, b = 0.01 * 0.01;
  extractor.updateCombination(a, m, b, k, combined);
  const Eigen::MatrixXd expected = a * denseBlock(Eigen::MatrixXd(m), dofs.freeToFull(), dofs.freeToFull()) +
                                   b * denseBlock(Eigen::MatrixXd(k), dofs.freeToFull(), dofs.freeToFull());
  EXPECT_EQ(Eigen::MatrixXd(combined), expected);
  EXPECT_GT(expected.norm(), 0.0);
  // extractCombination: the same matrix, pattern included, from nothing; and it can be updated.
  SparseMatrix fresh = extractor.extractCombination(a, m, b, k);
  EXPECT_EQ(fresh.nonZeros(), combined.nonZeros());
  EXPECT_EQ(Eigen::MatrixXd(fresh), expected);
  extractor.updateCombination(2.0 * a, m, b, k, fresh);
  EXPECT_EQ(Eigen::MatrixXd(fresh), 2.0 * a * denseBlock(Eigen::MatrixXd(m), dofs.freeToFull(), dofs.freeToFull()) +
                                        b * denseBlock(Eigen::MatrixXd(k), dofs.freeToFull(), dofs.freeToFull()));
  std::mt19937 random(3);
  const SparseMatrix other = randomSparse(m.rows(), m.cols(), 0.01, random);
  EXPECT_THROW(extractor.updateCombination(a, m, b, other, combined), Error);
  EXPECT_THROW((void)extractor.extractCombination(a, m, b, other), Error);
}

// rebuild(): a re-partition's cut in the storage of the previous one. The rebuilt extractor
// gives exactly what a fresh one for the new lists gives (same entries, same copies:
// exact), and extractCombinationInto() fills a matrix that held a larger cut without
// moving its entries (no allocation); a bad list leaves the old map usable.
TEST(SubmatrixExtractor, RebuildsForNewIndexListsInItsOwnStorage) {
  const BoxMatrices box;
  const SparseMatrix& k = box.k;
  const SparseMatrix& m = box.m;
  const FreeDofs& wide = box.dofs;
  std::vector<int> narrow;  // every other free DOF: fewer entries than the first cut
  for (std::size_t i = 0; i < wide.freeToFull().size(); i += 2) narrow.push_back(wide.freeToFull()[i]);
  SubmatrixExtractor extractor(m, wide.freeToFull(), wide.freeToFull());
  const double a = 1.0, b = 0.01 * 0.01;
  SparseMatrix sub = extractor.extractCombination(a, m, b, k);
  const double* storage = sub.valuePtr();
  extractor.rebuild(m, narrow, narrow);
  extractor.extractCombinationInto(a, m, b, k, sub);
  EXPECT_EQ(sub.valuePtr(), storage);
  const SubmatrixExtractor fresh(m, narrow, narrow);
  const SparseMatrix expected = fresh.extractCombination(a, m, b, k);
  ASSERT_EQ(sub.rows(), static_cast<Eigen::Index>(narrow.size()));
  EXPECT_EQ(sub.nonZeros(), expected.nonZeros());
  EXPECT_EQ(Eigen::MatrixXd(sub), Eigen::MatrixXd(expected));
  EXPECT_EQ(Eigen::MatrixXd(extractor.extract(k)), denseBlock(Eigen::MatrixXd(k), narrow, narrow));
  // Back to the wide cut (more entries than it holds now: it grows).
  extractor.rebuild(m, wide.freeToFull(), wide.freeToFull());
  extractor.extractCombinationInto(a, m, b, k, sub);
  EXPECT_EQ(Eigen::MatrixXd(sub), a * denseBlock(Eigen::MatrixXd(m), wide.freeToFull(), wide.freeToFull()) +
                                      b * denseBlock(Eigen::MatrixXd(k), wide.freeToFull(), wide.freeToFull()));
  EXPECT_THROW(extractor.rebuild(m, {2, 1}, {0}), ValidationError);
  EXPECT_EQ(Eigen::MatrixXd(extractor.extract(m)),
            denseBlock(Eigen::MatrixXd(m), wide.freeToFull(), wide.freeToFull()));
}

TEST(SubmatrixExtractor, RejectsBadIndexListsAndForeignMatrices) {
  std::mt19937 random(1);
  const SparseMatrix full = randomSparse(10, 8, 0.3, random);
  const std::string descending = errorMessage([&] { SubmatrixExtractor(full, {1, 3, 2}, {0}); });
  EXPECT_NE(descending.find("ascending"), std::string::npos) << descending;
  const std::string outOfRange = errorMessage([&] { SubmatrixExtractor(full, {0}, {0, 8}); });
  EXPECT_NE(outOfRange.find("column index 8"), std::string::npos) << outOfRange;
  const SubmatrixExtractor extractor(full, {0, 1, 2}, {3, 4});
  SparseMatrix sub = extractor.extract(full);
  const SparseMatrix other = randomSparse(10, 8, 0.6, random);
  EXPECT_THROW(extractor.update(other, sub), Error);
  SparseMatrix wrongSub(2, 2);
  EXPECT_THROW(extractor.update(full, wrongSub), Error);
}

}  // namespace
}  // namespace asyncfem
