// SPDX-License-Identifier: BSD-3-Clause
// HyperelasticOptions::batchedKernel (four elements per SIMD batch on the invariant path)
// against one element at a time.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/hyperelasticFEM/stvkFEM.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

using test::ModelCase;

struct Evaluation {
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> tangent;
  long long batchedElements = 0;
  long long expectedBatched = 0;
};

// Whether element e at u takes the invariant path, decided independently of the library:
// det F > 0 and, with inversion handling, every singular value of F above the threshold.
bool onInvariantPath(const IsotropicHyperelasticFEM& model, int e, const Eigen::VectorXd& u) {
  const Eigen::Matrix3d f = model.geometry().deformationGradient(e, u);
  if (!(f.determinant() > 0.0)) return false;
  if (!model.options().inversionHandlingEnabled()) return true;
  // The smallest singular value of F is the square root of C's smallest eigenvalue.
  const double threshold = model.options().inversionThreshold;
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(f.transpose() * f).eigenvalues().minCoeff() >
         threshold * threshold;
}

// The elements the batched run should batch: the assembler's chunks of consecutive
// elements cut into batches of four from each chunk's start; a full batch of one material
// whose elements all take the invariant path.
long long expectedBatchedElements(const TetMesh& mesh, const IsotropicHyperelasticFEM& model,
                                  const Eigen::VectorXd& u) {
  const int chunk = model.assembler().elementsPerChunk();
  long long expected = 0;
  for (int start = 0; start < mesh.numElements(); start += chunk) {
    const int end = std::min(mesh.numElements(), start + chunk);
    for (int first = start; first + 4 <= end; first += 4) {
      bool batch = true;
      for (int e = first; e < first + 4; ++e) {
        batch =
            batch && mesh.elementMaterialIndex(e) == mesh.elementMaterialIndex(first) && onInvariantPath(model, e, u);
      }
      expected += batch ? 4 : 0;
    }
  }
  return expected;
}

Evaluation evaluate(const TetMesh& mesh, const ModelCase& c, bool batched, const Eigen::VectorXd& u) {
  HyperelasticOptions options = c.options;
  options.batchedKernel = batched;
  IsotropicHyperelasticFEM model(mesh, c.kind, options);
  Evaluation result;
  result.tangent = model.createStiffnessMatrix();
  model.forcesAndTangent(u, result.forces, result.tangent);
  result.batchedElements = model.batchedElements();
  result.expectedBatched = batched ? expectedBatchedElements(mesh, model, u) : 0;
  return result;
}

// The principal-stretch cases (every material, with and without the inversion threshold
// and compression resistance); Green-strain StVK is another model.
std::vector<ModelCase> invariantCases() {
  std::vector<ModelCase> cases;
  for (const ModelCase& c : test::allModelCases()) {
    if (c.kind == HyperelasticMaterialKind::stvk && c.options.stvkFormulation == StVKFormulation::greenStrain) continue;
    cases.push_back(c);
  }
  return cases;
}

// Both run the same formulas (K1, K2) per element; the batch evaluates them in another
// order (cofactor expansion, the symmetric half of dP/dF, the 12x12 product), a few ulps
// of each per-element quantity, and the assembly sums the same element terms in the same
// order. 1e-12 of the largest entry leaves a margin of about 1000 over that rounding (the
// differences measured are printed), while a wrong term (stress / E ~ 1e-2) fails.
constexpr double kRoundingTolerance = 1e-12;

// Runs both, checks they agree and returns how many elements the batched run batched.
long long expectKernelsAgree(const TetMesh& mesh, const ModelCase& c, const Eigen::VectorXd& u,
                             const std::string& label) {
  const Evaluation batched = evaluate(mesh, c, true, u);
  const Evaluation single = evaluate(mesh, c, false, u);
  const double forceDifference = test::relativeEntryDifference(batched.forces, single.forces);
  const double tangentDifference = test::relativeEntryDifference(batched.tangent, single.tangent);
  const std::string what = c.label + ", " + label;
  std::printf(
      "[ measured ] %s: %lld of %d elements batched (chunks of %d); forces %.2e, tangent %.2e of the largest "
      "entry\n",
      what.c_str(), batched.batchedElements, mesh.numElements(), MatrixAssembler(mesh).elementsPerChunk(),
      forceDifference, tangentDifference);
  EXPECT_LE(forceDifference, kRoundingTolerance) << what;
  EXPECT_LE(tangentDifference, kRoundingTolerance) << what;
  EXPECT_EQ(single.batchedElements, 0) << what;
  EXPECT_EQ(batched.batchedElements, batched.expectedBatched) << what;
  return batched.batchedElements;
}

TEST(HyperelasticBatchedKernel, EqualsOneElementAtATimeOnRandomDeformations) {
  // 6000 elements: the assembler's chunks are long enough to hold batches of four (below
  // a few thousand elements they are one to three elements long and nothing is batched).
  const TetMesh mesh = test::smallBox(10);
  std::mt19937 random(41);
  for (const ModelCase& c : invariantCases()) {
    for (const double amplitude : {0.01, 0.03}) {  // cells of 0.1: strains of about 10% and 30%
      const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), amplitude, random);
      const long long batched = expectKernelsAgree(mesh, c, u, "amplitude " + std::to_string(amplitude));
      // No stretch comes near 0.2 at these strains: every full batch is batched.
      EXPECT_GE(batched, mesh.numElements() / 2) << c.label;
    }
  }
}

TEST(HyperelasticBatchedKernel, BatchesWithAnElementBelowTheThresholdGoOneAtATime) {
  // Squeeze one corner of the box so that some elements fall below the inversion threshold
  // (or invert): their batches must take the principal-stretch path element by element, the
  // rest stay batched, and the result still equals the unbatched one.
  const TetMesh mesh = test::smallBox(10);
  std::mt19937 random(43);
  Eigen::VectorXd u = test::deformedDisplacement(mesh, Eigen::Matrix3d::Identity(), 0.005, random);
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = mesh.restPosition(v);
    if (x.x() > 0.6 && x.y() > 0.5) u[(3 * v) + 0] -= 0.9 * (x.x() - 0.6);  // crush the corner along x
  }
  for (const ModelCase& c : invariantCases()) {
    if (!c.options.inversionHandlingEnabled()) continue;  // without handling a crushed element has log J of J <= 0
    const long long batched = expectKernelsAgree(mesh, c, u, "crushed corner");
    EXPECT_GT(batched, 0) << c.label;
    const IsotropicHyperelasticFEM model(mesh, c.kind, c.options);
    int below = 0;
    for (int e = 0; e < mesh.numElements(); ++e) below += onInvariantPath(model, e, u) ? 0 : 1;
    EXPECT_GT(below, 0) << c.label << ": the crushed corner must put elements below the threshold";
  }
}

/// box's elements alternating every seven between its material and a ten times stiffer
/// copy ("stiff", Poisson ratio 0.3): some batches of four hold both, most one.
TetMesh alternatingMaterials(const TetMesh& box) {
  std::vector<Material> materials = box.materials();
  Material stiff = materials.front();
  stiff.name = "stiff";
  stiff.youngsModulus *= 10.0;
  stiff.poissonRatio = 0.3;
  stiff.mooneyRivlin->mu01 *= 10.0;
  stiff.mooneyRivlin->mu10 *= 10.0;
  stiff.mooneyRivlin->v1 *= 10.0;
  materials.push_back(stiff);
  std::vector<int> elementMaterials(static_cast<std::size_t>(box.numElements()));
  for (int e = 0; e < box.numElements(); ++e) elementMaterials[static_cast<std::size_t>(e)] = (e / 7) % 2;
  return TetMesh(box.restPositions(), box.elements(), materials, elementMaterials);
}

TEST(HyperelasticBatchedKernel, BatchesMixingMaterialsGoOneAtATime) {
  const TetMesh mesh = alternatingMaterials(test::smallBox(10));
  std::mt19937 random(47);
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), 0.02, random);
  for (const ModelCase& c : invariantCases()) {
    const long long batched = expectKernelsAgree(mesh, c, u, "two materials");
    EXPECT_GT(batched, 0) << c.label;
    // Without the material check every full batch would be batched; the mixed ones are not.
    const int chunk = MatrixAssembler(mesh).elementsPerChunk();
    long long fullBatches = 0;
    for (int start = 0; start < mesh.numElements(); start += chunk)
      fullBatches += (std::min(mesh.numElements(), start + chunk) - start) / 4;
    EXPECT_LT(batched, 4 * fullBatches) << c.label;
  }
}

// StVK in the Green-strain form (StVKFEM) batches every full batch of four of a chunk,
// whatever the materials (its Lame parameters are per element): on random deformations of
// about 10% and 30% strain, and with two materials alternating every seven elements, the
// batched forces and tangent equal one element at a time to kRoundingTolerance (the same
// formulas, products summed in another order), and the count of batched elements equals
// the full batches of the assembler's chunks.
TEST(StVKBatchedKernel, EqualsOneElementAtATime) {
  const TetMesh box = test::smallBox(10);
  const TetMesh mixed = alternatingMaterials(box);
  std::mt19937 random(53);
  for (const TetMesh* mesh : {&box, &mixed}) {
    const int chunk = MatrixAssembler(*mesh).elementsPerChunk();
    long long fullBatches = 0;
    for (int start = 0; start < mesh->numElements(); start += chunk)
      fullBatches += (std::min(mesh->numElements(), start + chunk) - start) / 4;
    ASSERT_GT(fullBatches, 0);
    for (const double amplitude : {0.01, 0.03}) {
      const Eigen::VectorXd u = test::deformedDisplacement(*mesh, test::randomRotation(random), amplitude, random);
      StVKFEM batched(*mesh, nullptr, true), single(*mesh, nullptr, false);
      Eigen::VectorXd forcesBatched, forcesSingle;
      Eigen::SparseMatrix<double> tangentBatched = batched.createStiffnessMatrix();
      Eigen::SparseMatrix<double> tangentSingle = single.createStiffnessMatrix();
      batched.forcesAndTangent(u, forcesBatched, tangentBatched);
      single.forcesAndTangent(u, forcesSingle, tangentSingle);
      const double forceDifference = test::relativeEntryDifference(forcesBatched, forcesSingle);
      const double tangentDifference = test::relativeEntryDifference(tangentBatched, tangentSingle);
      std::printf(
          "[ measured ] StVK Green strain, %s, amplitude %.2f: forces %.2e, tangent %.2e of the largest entry\n",
          mesh == &box ? "one material" : "two materials", amplitude, forceDifference, tangentDifference);
      EXPECT_LE(forceDifference, kRoundingTolerance);
      EXPECT_LE(tangentDifference, kRoundingTolerance);
      EXPECT_EQ(batched.batchedElements(), 4 * fullBatches);
      EXPECT_EQ(single.batchedElements(), 0);
    }
  }
}

}  // namespace
}  // namespace asyncfem
