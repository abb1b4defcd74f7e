// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <atomic>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "testMeshes.hpp"

namespace asyncfem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

bool bitIdentical(const SparseMatrix& a, const SparseMatrix& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && a.nonZeros() == b.nonZeros() &&
         std::memcmp(a.valuePtr(), b.valuePtr(), sizeof(double) * static_cast<std::size_t>(a.nonZeros())) == 0 &&
         std::memcmp(a.innerIndexPtr(), b.innerIndexPtr(), sizeof(int) * static_cast<std::size_t>(a.nonZeros())) == 0 &&
         std::memcmp(a.outerIndexPtr(), b.outerIndexPtr(), sizeof(int) * static_cast<std::size_t>(a.cols() + 1)) == 0;
}

// Restores the OpenMP thread count a test changed.
class ThreadCountGuard {
 public:
  ThreadCountGuard() : saved_(omp_get_max_threads()) {}
  ~ThreadCountGuard() { omp_set_num_threads(saved_); }
  ThreadCountGuard(const ThreadCountGuard&) = delete;
  ThreadCountGuard& operator=(const ThreadCountGuard&) = delete;

 private:
  int saved_;
};

// Reference assembly: every element's 144 entries as triplets, summed by Eigen.
SparseMatrix tripletStiffness(const TetMesh& mesh) {
  std::vector<Eigen::Triplet<double>> triplets;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Material& m = mesh.elementMaterial(e);
    const ElementMatrix k = linearElementStiffness(mesh.elementRestPositions(e), m.youngsModulus, m.poissonRatio);
    const Eigen::Vector4i v = mesh.element(e);
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) triplets.emplace_back((3 * v[i / 3]) + (i % 3), (3 * v[j / 3]) + (j % 3), k(i, j));
  }
  SparseMatrix reference(mesh.numDofs(), mesh.numDofs());
  reference.setFromTriplets(triplets.begin(), triplets.end());
  return reference;
}

void expectRigidModesInNullSpace(const TetMesh& mesh) {
  const MatrixAssembler assembler(mesh);
  const SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  const Eigen::MatrixXd modes = test::rigidBodyModes(mesh);
  for (int mode = 0; mode < 6; ++mode) {
    const Eigen::VectorXd r = modes.col(mode);
    // K r cancels sums of entries of size ||K||; double rounding leaves ~1e-15 of
    // ||K|| ||r|| even with stiffness contrasts of 1e4, so 1e-10 is generous but still
    // far below what a wrong entry (O(1) relative) would give.
    EXPECT_LE((k * r).norm(), 1e-10 * k.norm() * r.norm()) << "mode " << mode;
  }
}

TEST(Assembler, RigidBodyModesAreInNullSpaceOfMixedMaterialBox) {
  expectRigidModesInNullSpace(test::mixedMaterialBox(4));
}

TEST(Assembler, RigidBodyModesAreInNullSpaceOfPerturbedMesh) {
  const TetMesh mesh = test::perturbedBox(5, 42);
  for (int e = 0; e < mesh.numElements(); ++e) {
    double volume = 0.0;
    shapeFunctionGradients(mesh.elementRestPositions(e), &volume);
    ASSERT_GT(volume, 0.0) << "perturbation inverted element " << e;
  }
  expectRigidModesInNullSpace(mesh);
}

TEST(Assembler, StiffnessIsSymmetricAndPositiveSemiDefinite) {
  const TetMesh mesh = test::mixedMaterialBox(2);  // 27 vertices, 81 DOFs
  const MatrixAssembler assembler(mesh);
  const SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  // Entries (i, j) and (j, i) receive the same element contributions in the same order,
  // and the element matrices are exactly symmetric, so K is exactly symmetric.
  const SparseMatrix transpose = k.transpose();
  EXPECT_EQ((k - transpose).norm(), 0.0);

  const Eigen::MatrixXd dense = Eigen::MatrixXd(k);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(dense);
  const Eigen::VectorXd values = eigen.eigenvalues();
  const double largest = values.maxCoeff();
  // The eigensolver is backward stable: eigenvalues are accurate to ~n eps ||K||, far
  // below 1e-10 of the largest one.
  EXPECT_GE(values.minCoeff(), -1e-10 * largest);
  // Exactly six zero modes (rigid motions) for the unconstrained body: the seventh
  // eigenvalue is a genuine deformation mode, many orders above the rounding level.
  EXPECT_LE(std::abs(values[5]), 1e-10 * largest);
  EXPECT_GT(values[6], 1e-8 * largest);
}

TEST(Assembler, PatchTestLinearFieldGivesNoInteriorForce) {
  // One material: a linear displacement has constant stress, so the forces of the
  // elements around an interior vertex cancel (with mixed materials they would not).
  const TetMesh mesh = test::perturbedBox(5, 3);
  const MatrixAssembler assembler(mesh);
  const SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  Eigen::Matrix3d a;
  a << 0.01, -0.02, 0.005, 0.03, 0.002, -0.01, 0.004, 0.007, -0.015;
  const Eigen::Vector3d b(0.1, -0.2, 0.3);
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) u.segment<3>(3 * v) = a * mesh.restPosition(v) + b;
  const Eigen::VectorXd f = k * u;
  double interiorForce = 0.0, boundaryForce = 0.0;
  const Eigen::Vector3d size(2.0, 1.5, 1.0);
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d p = mesh.restPosition(v);
    const bool boundary = (p.array() < 1e-9).any() || (p.array() > size.array() - 1e-9).any();
    (boundary ? boundaryForce : interiorForce) += f.segment<3>(3 * v).squaredNorm();
  }
  // Cancellation of O(||K|| ||u||) terms; 1e-10 leaves room for the rounding of the
  // about 40 contributions per entry.
  EXPECT_LE(std::sqrt(interiorForce), 1e-10 * k.norm() * u.norm());
  // The boundary carries the traction of the constant stress: clearly non-zero.
  EXPECT_GT(std::sqrt(boundaryForce), 1e-6 * k.norm() * u.norm());
}

TEST(Assembler, MassMatricesSumToTotalMass) {
  const TetMesh mesh = test::mixedMaterialBox(4);
  // Regions follow cell boundaries: half the unit box is the stiff slab (x < 0.5), the
  // corner [0.75, 1]^3 is soft, the rest default.
  const double expected = 7800.0 * 0.5 + 300.0 * 0.25 * 0.25 * 0.25 + 1000.0 * (0.5 - 0.25 * 0.25 * 0.25);
  const MatrixAssembler assembler(mesh);
  for (MassType type : {MassType::consistent, MassType::lumped}) {
    const SparseMatrix m = massMatrix(mesh, assembler, type);
    EXPECT_EQ(m.nonZeros(), assembler.nonZeros());  // lumped keeps the pattern
    for (int c = 0; c < 3; ++c) {
      Eigen::VectorXd ones = Eigen::VectorXd::Zero(mesh.numDofs());
      for (int v = 0; v < mesh.numVertices(); ++v) ones[(3 * v) + c] = 1.0;
      // Sums of ~2000 positive terms: relative rounding below 1e-13.
      EXPECT_NEAR(ones.dot(m * ones), expected, 1e-13 * expected) << "coordinate " << c;
    }
    if (type == MassType::lumped) {
      double offDiagonal = 0.0;
      for (int col = 0; col < m.outerSize(); ++col)
        for (SparseMatrix::InnerIterator it(m, col); it; ++it)
          if (it.row() != it.col()) offDiagonal += std::abs(it.value());
      EXPECT_EQ(offDiagonal, 0.0);
    }
  }
}

TEST(Assembler, PatternIsSortedCompressedFullStorage) {
  const TetMesh mesh = test::perturbedBox(3, 1);
  const MatrixAssembler assembler(mesh);
  const SparseMatrix k = assembler.createMatrix();
  ASSERT_TRUE(k.isCompressed());
  EXPECT_EQ(k.nonZeros(), assembler.nonZeros());
  for (int col = 0; col < k.cols(); ++col) {
    bool hasDiagonal = false;
    for (int p = k.outerIndexPtr()[col]; p < k.outerIndexPtr()[col + 1]; ++p) {
      if (p > k.outerIndexPtr()[col]) {
        ASSERT_LT(k.innerIndexPtr()[p - 1], k.innerIndexPtr()[p]);
      }
      hasDiagonal = hasDiagonal || k.innerIndexPtr()[p] == col;
    }
    EXPECT_TRUE(hasDiagonal) << col;
  }
  // Same pattern as the triplet reference (which stores every coupled pair).
  const SparseMatrix reference = tripletStiffness(mesh);
  ASSERT_EQ(reference.nonZeros(), k.nonZeros());
  EXPECT_EQ(std::memcmp(reference.innerIndexPtr(), k.innerIndexPtr(), sizeof(int) * k.nonZeros()), 0);
  EXPECT_EQ(std::memcmp(reference.outerIndexPtr(), k.outerIndexPtr(), sizeof(int) * (k.cols() + 1)), 0);
}

TEST(Assembler, SlotMapAgreesWithTripletAssembly) {
  const TetMesh mesh = test::mixedMaterialBox(4);
  const MatrixAssembler assembler(mesh);
  const SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  const SparseMatrix reference = tripletStiffness(mesh);
  // Same contributions summed in another order: differences of a few ulp of the largest
  // entries, 1e-12 of the norm leaves a wide margin.
  EXPECT_LE((k - reference).norm(), 1e-12 * reference.norm());
  // Every slot points at the entry of the right row and column.
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i v = mesh.element(e);
    for (int i = 0; i < 12; ++i) {
      for (int j = 0; j < 12; ++j) {
        const int slot = assembler.slot(e, i, j);
        const int row = (3 * v[i / 3]) + (i % 3), col = (3 * v[j / 3]) + (j % 3);
        ASSERT_EQ(k.innerIndexPtr()[slot], row) << "element " << e << " (" << i << ", " << j << ")";
        ASSERT_GE(slot, k.outerIndexPtr()[col]);
        ASSERT_LT(slot, k.outerIndexPtr()[col + 1]);
      }
    }
  }
}

TEST(Assembler, AssemblyIsBitIdenticalAcrossThreadCountsAndRepeats) {
  const ThreadCountGuard guard;
  // 24576 elements: above the size from which the assembler uses threads.
  const TetMesh mesh = test::perturbedBox(16, 11);
  const MatrixAssembler assembler(mesh);
  ASSERT_GT(assembler.numColors(), 1);
  omp_set_num_threads(1);
  const SparseMatrix serial = linearStiffnessMatrix(mesh, assembler);
  const Eigen::VectorXd serialVector = assembler.assembleVector(
      [&](int e, ElementVector& out) { out = ElementVector::LinSpaced(0.1, 1.2) * std::sin(e); });
  for (int threads : {2, 3, 4}) {
    omp_set_num_threads(threads);
    const SparseMatrix parallel = linearStiffnessMatrix(mesh, assembler);
    EXPECT_TRUE(bitIdentical(serial, parallel)) << threads << " threads";
    const Eigen::VectorXd parallelVector = assembler.assembleVector(
        [&](int e, ElementVector& out) { out = ElementVector::LinSpaced(0.1, 1.2) * std::sin(e); });
    EXPECT_EQ(std::memcmp(serialVector.data(), parallelVector.data(), sizeof(double) * serialVector.size()), 0);
  }
  // Re-assembly into the same matrix overwrites (does not accumulate) the values.
  omp_set_num_threads(2);
  SparseMatrix k = assembler.createMatrix();
  const auto elementStiffness = [&](int e, ElementMatrix& out) {
    const Material& m = mesh.elementMaterial(e);
    out = linearElementStiffness(mesh.elementRestPositions(e), m.youngsModulus, m.poissonRatio);
  };
  assembler.assemble(elementStiffness, k);
  const SparseMatrix first = k;
  for (int repeat = 0; repeat < 3; ++repeat) {
    assembler.assemble(elementStiffness, k);
    EXPECT_TRUE(bitIdentical(first, k)) << "repeat " << repeat;
  }
  // The std::function path computes the same element matrices as linearStiffnessMatrix.
  EXPECT_TRUE(bitIdentical(first, serial));
}

TEST(Assembler, BatchedAssemblyEqualsElementByElementBitForBit) {
  // assembleBatches visits the elements in assemble()'s order, so the same element
  // matrices give the same bits for any thread count; each batch is up to four consecutive
  // elements of one chunk.
  const ThreadCountGuard guard;
  const TetMesh mesh = test::perturbedBox(16, 13);  // 24576 elements: threaded assembly
  const MatrixAssembler assembler(mesh);
  const auto elementStiffness = [&](int e, ElementMatrix& out) {
    const Material& m = mesh.elementMaterial(e);
    out = linearElementStiffness(mesh.elementRestPositions(e), m.youngsModulus, m.poissonRatio);
  };
  omp_set_num_threads(1);
  SparseMatrix reference = assembler.createMatrix();
  assembler.assemble(elementStiffness, reference);
  std::vector<int> visits(static_cast<std::size_t>(mesh.numElements()), 0);
  std::atomic<bool> batchesValid{true};
  int longest = 0;
  for (int threads : {1, 2, 3}) {
    omp_set_num_threads(threads);
    std::fill(visits.begin(), visits.end(), 0);
    SparseMatrix batched = assembler.createMatrix();
    assembler.assembleBatches(
        [&](int first, int count, ElementMatrix* out) {
          const int chunk = assembler.elementsPerChunk();
          // count in [1, 4], all in the chunk of first.
          if (count < 1 || count > MatrixAssembler::kElementBatch || first / chunk != (first + count - 1) / chunk) {
            batchesValid = false;
          }
#pragma omp critical(assembler_test_longest)
          longest = std::max(longest, count);
          for (int i = 0; i < count; ++i) {
            ++visits[static_cast<std::size_t>(first + i)];
            elementStiffness(first + i, out[i]);
          }
        },
        batched);
    EXPECT_TRUE(bitIdentical(reference, batched)) << threads << " threads";
    EXPECT_TRUE(std::all_of(visits.begin(), visits.end(), [](int v) { return v == 1; })) << threads << " threads";
  }
  EXPECT_TRUE(batchesValid);
  EXPECT_EQ(longest, MatrixAssembler::kElementBatch);
  // A batch that throws: the lowest failing batch's exception arrives, after every batch ran.
  omp_set_num_threads(2);
  SparseMatrix k = assembler.createMatrix();
  std::fill(visits.begin(), visits.end(), 0);
  try {
    assembler.assembleBatches(
        [&](int first, int count, ElementMatrix* out) {
          for (int i = 0; i < count; ++i) {
            ++visits[static_cast<std::size_t>(first + i)];
            out[i].setZero();
          }
          if (first <= 1000 && 1000 < first + count) throw Error("batch of element 1000");
          if (first <= 20000 && 20000 < first + count) throw Error("batch of element 20000");
        },
        k);
    ADD_FAILURE() << "no exception";
  } catch (const Error& error) {
    EXPECT_STREQ(error.what(), "batch of element 1000");
  }
  EXPECT_TRUE(std::all_of(visits.begin(), visits.end(), [](int v) { return v == 1; }));
}

TEST(Assembler, ShuffledNumberingStaysCorrectAndDeterministic) {
  // Random vertex and element numbering defeats the locality the chunk colouring relies
  // on; the assembler must shrink its chunks and still be exact and deterministic.
  const ThreadCountGuard guard;
  const TetMesh box = test::mixedMaterialBox(16);  // 24576 elements: threaded assembly
  std::mt19937 random(17);
  std::vector<int> vertexOrder(static_cast<std::size_t>(box.numVertices()));
  std::vector<int> elementOrder(static_cast<std::size_t>(box.numElements()));
  for (std::size_t i = 0; i < vertexOrder.size(); ++i) vertexOrder[i] = static_cast<int>(i);
  for (std::size_t i = 0; i < elementOrder.size(); ++i) elementOrder[i] = static_cast<int>(i);
  std::shuffle(vertexOrder.begin(), vertexOrder.end(), random);
  std::shuffle(elementOrder.begin(), elementOrder.end(), random);
  Eigen::Matrix3Xd x(3, box.numVertices());
  for (int v = 0; v < box.numVertices(); ++v) x.col(vertexOrder[static_cast<std::size_t>(v)]) = box.restPosition(v);
  Eigen::Matrix4Xi elements(4, box.numElements());
  std::vector<int> materials(static_cast<std::size_t>(box.numElements()));
  for (int e = 0; e < box.numElements(); ++e) {
    const int target = elementOrder[static_cast<std::size_t>(e)];
    for (int a = 0; a < 4; ++a) elements(a, target) = vertexOrder[static_cast<std::size_t>(box.elements()(a, e))];
    materials[static_cast<std::size_t>(target)] = box.elementMaterialIndex(e);
  }
  const TetMesh mesh(x, elements, box.materials(), materials);
  const MatrixAssembler assembler(mesh);
  omp_set_num_threads(1);
  const SparseMatrix serial = linearStiffnessMatrix(mesh, assembler);
  omp_set_num_threads(3);
  EXPECT_TRUE(bitIdentical(serial, linearStiffnessMatrix(mesh, assembler)));
  const SparseMatrix reference = tripletStiffness(mesh);
  // Same tolerance and reason as SlotMapAgreesWithTripletAssembly.
  EXPECT_LE((serial - reference).norm(), 1e-12 * reference.norm());
  EXPECT_GT(assembler.numColors(), 1);
}

TEST(Assembler, PrecomputedElementMatricesAndVectorsMatch) {
  const TetMesh mesh = test::perturbedBox(3, 5);
  const MatrixAssembler assembler(mesh);
  std::vector<ElementMatrix> elementMatrices(static_cast<std::size_t>(mesh.numElements()));
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Material& m = mesh.elementMaterial(e);
    elementMatrices[static_cast<std::size_t>(e)] =
        linearElementStiffness(mesh.elementRestPositions(e), m.youngsModulus, m.poissonRatio);
  }
  SparseMatrix k = assembler.createMatrix();
  assembler.assemble(elementMatrices, k);
  EXPECT_TRUE(bitIdentical(k, linearStiffnessMatrix(mesh, assembler)));

  // sum_e K_e u_e equals K u.
  std::mt19937 random(9);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd u(mesh.numDofs());
  for (int i = 0; i < u.size(); ++i) u[i] = uniform(random);
  const Eigen::VectorXd f = assembler.assembleVector([&](int e, ElementVector& out) {
    const Eigen::Vector4i v = mesh.element(e);
    ElementVector ue;
    for (int a = 0; a < 4; ++a) ue.segment<3>(3 * a) = u.segment<3>(3 * v[a]);
    out = elementMatrices[static_cast<std::size_t>(e)] * ue;
  });
  // Same products summed in another order: 1e-13 of the norm.
  EXPECT_LE((f - k * u).norm(), 1e-13 * f.norm());

  elementMatrices.pop_back();
  EXPECT_THROW(assembler.assemble(elementMatrices, k), Error);
}

TEST(Assembler, CombineAndRayleighDampingAreValueWiseSums) {
  const TetMesh mesh = test::mixedMaterialBox(4);
  const MatrixAssembler assembler(mesh);
  const SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  const SparseMatrix m = massMatrix(mesh, assembler, MassType::consistent);
  const double h = 1e-3;
  SparseMatrix system;
  combine({1.0, h * h}, {&m, &k}, system);
  const SparseMatrix reference = m + (h * h) * k;
  // Each entry is the same two-term sum: exact up to one rounding.
  EXPECT_LE((system - reference).norm(), 1e-15 * reference.norm());
  EXPECT_EQ(system.nonZeros(), assembler.nonZeros());
  const SparseMatrix damping = rayleighDamping(m, k, 0.1, 0.01);
  EXPECT_LE((damping - (0.1 * m + 0.01 * k)).norm(), 1e-15 * damping.norm());
  // In place: out aliases an input.
  SparseMatrix inPlace = m;
  combine({2.0, 1.0}, {&inPlace, &k}, inPlace);
  EXPECT_LE((inPlace - (2.0 * m + k)).norm(), 1e-15 * inPlace.norm());
}

TEST(Assembler, CombineRejectsMismatchedPatterns) {
  const TetMesh mesh = test::mixedMaterialBox(2);
  const MatrixAssembler assembler(mesh);
  const SparseMatrix k = linearStiffnessMatrix(mesh, assembler);
  // Same size and entry count, different rows: swap the rows of one column's entries.
  SparseMatrix shuffled = k;
  shuffled.innerIndexPtr()[0] = shuffled.innerIndexPtr()[1];
  SparseMatrix out;
  EXPECT_THROW(combine({1.0, 1.0}, {&k, &shuffled}, out), Error);
  // Other mesh, other size.
  const TetMesh other = test::mixedMaterialBox(3);
  const MatrixAssembler otherAssembler(other);
  const SparseMatrix otherK = linearStiffnessMatrix(other, otherAssembler);
  try {
    combine({1.0, 1.0}, {&k, &otherK}, out);
    FAIL() << "combine accepted matrices of different sizes";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("matrix 1"), std::string::npos) << error.what();
  }
  // Pruned matrix: fewer entries.
  SparseMatrix pruned = k;
  pruned.prune(1e300, 1.0);
  EXPECT_THROW(combine({1.0, 1.0}, {&k, &pruned}, out), Error);
  EXPECT_THROW(combine({1.0}, {&k, &k}, out), Error);
}

TEST(Assembler, RejectsForeignMatricesAndDegenerateElements) {
  const TetMesh mesh = test::mixedMaterialBox(2);
  const MatrixAssembler assembler(mesh);
  SparseMatrix wrong(mesh.numDofs(), mesh.numDofs());
  EXPECT_THROW(assembler.assemble([](int, ElementMatrix& out) { out.setZero(); }, wrong), Error);
  // A throwing element function: the exception of the lowest failing element arrives.
  SparseMatrix k = assembler.createMatrix();
  try {
    assembler.assemble(
        [](int e, ElementMatrix& out) {
          if (e % 7 == 3) throw ValidationError("element " + std::to_string(e));
          out.setZero();
        },
        k);
    FAIL() << "no exception";
  } catch (const ValidationError& error) {
    EXPECT_EQ(std::string(error.what()), "element 3");
  }
  // A flat element: its fourth vertex moved into the plane of the other three.
  Eigen::Matrix3Xd x = mesh.restPositions();
  const Eigen::Vector4i t = mesh.element(5);
  x.col(t[3]) = (x.col(t[0]) + x.col(t[1]) + x.col(t[2])) / 3.0;
  const TetMesh flat(x, mesh.elements(), mesh.materials(), mesh.elementMaterials());
  try {
    linearStiffnessMatrix(flat, assembler);
    FAIL() << "degenerate element accepted";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("element "), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("degenerate"), std::string::npos) << error.what();
  }
  const TetMesh other = test::mixedMaterialBox(3);
  EXPECT_THROW(linearStiffnessMatrix(other, assembler), Error);
}

}  // namespace
}  // namespace asyncfem
