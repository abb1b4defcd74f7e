// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <asyncfem/stiffnessMatrix/symmetrizeElementMatrix.hpp>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <utility>

#include "elementBatches.hpp"

namespace asyncfem {

namespace {

using Index = std::size_t;
Index toIndex(int i) { return static_cast<Index>(i); }

/// [p]x, the matrix with [p]x q = p x q.
Eigen::Matrix3d crossMatrix(const Eigen::Vector3d& p) {
  Eigen::Matrix3d m;
  m << 0.0, -p[2], p[1], p[2], 0.0, -p[0], -p[1], p[0], 0.0;
  return m;
}

/// R K_e R^T, block (a, b) = R K_ab R^T.
void simpleElementTangent(const ElementMatrix& stiffness, const Eigen::Matrix3d& rotation, ElementMatrix& out) {
  const Eigen::Matrix3d rotationTransposed = rotation.transpose();
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a < 4; ++a) {
      const Eigen::Matrix3d rotatedRight = stiffness.block<3, 3>(3 * a, 3 * b) * rotationTransposed;
      out.block<3, 3>(3 * a, 3 * b).noalias() = rotation * rotatedRight;
    }
  }
}

/// W (3x12): column 3a + c is the axial vector w of R^T dR for a unit change of
/// coordinate c of vertex a. There dF = e_c g_a^T, so R^T dF - dF^T R = r_c g_a^T -
/// g_a r_c^T with axial vector g_a x r_c, and w = (tr S I - S)^{-1} (g_a x r_c).
inline Eigen::Matrix<double, 3, 12> rotationDifferentials(const Eigen::Matrix3d& rotation,
                                                          const Eigen::Matrix3d& differentialOperator,
                                                          const Eigen::Matrix<double, 3, 4>& gradients) {
  Eigen::Matrix<double, 3, 12> w;
  for (int a = 0; a < 4; ++a) {
    const Eigen::Vector3d g = gradients.col(a);
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d rowOfRotation = rotation.row(c).transpose();
      w.col((3 * a) + c).noalias() = differentialOperator * g.cross(rowOfRotation);
    }
  }
  return w;
}

/// Z + K Y (12x3): the change of R^T f_e per unit axial vector w of R^T dR, at corotated
/// positions y and K v (v = y - X). d(R^T x_b) from dR = R [w]x is -[w]x y_b = [y_b]x w,
/// and dR (K v)_b = -R [(K v)_b]x w.
inline Eigen::Matrix<double, 12, 3> rotationResponse(const ElementMatrix& stiffness,
                                                     const ElementPositions& corotatedPositions,
                                                     const ElementVector& kv) {
  Eigen::Matrix<double, 12, 3> response = Eigen::Matrix<double, 12, 3>::Zero();
  for (int b = 0; b < 4; ++b) {
    response.noalias() += stiffness.middleCols<3>(3 * b) * crossMatrix(corotatedPositions.col(b));
  }
  for (int b = 0; b < 4; ++b) response.middleRows<3>(3 * b) -= crossMatrix(kv.segment<3>(3 * b));
  return response;
}

/// d f_e / d x = R (K_e R^T + (Z + K_e Y) W), symmetrised; see the class comment for Z,
/// Y and W. differentialOperator is (tr S I - S)^{-1}.
void exactElementTangent(const ElementMatrix& stiffness, const Eigen::Matrix3d& rotation,
                         const Eigen::Matrix3d& differentialOperator, const Eigen::Matrix<double, 3, 4>& gradients,
                         const ElementPositions& current, const ElementPositions& rest, ElementMatrix& out) {
  const ElementPositions corotatedPositions = rotation.transpose() * current;  // y = R^T x
  const ElementPositions v = corotatedPositions - rest;
  const ElementVector kv = stiffness * Eigen::Map<const ElementVector>(v.data());
  const Eigen::Matrix<double, 3, 12> w = rotationDifferentials(rotation, differentialOperator, gradients);
  const Eigen::Matrix<double, 12, 3> response = rotationResponse(stiffness, corotatedPositions, kv);

  ElementMatrix inner;  // K R^T + (Z + K Y) W, before the final rotation
  const Eigen::Matrix3d rotationTransposed = rotation.transpose();
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a < 4; ++a) {
      inner.block<3, 3>(3 * a, 3 * b).noalias() = stiffness.block<3, 3>(3 * a, 3 * b) * rotationTransposed;
    }
  }
  inner.noalias() += response * w;
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a < 4; ++a) {
      out.block<3, 3>(3 * a, 3 * b).noalias() = rotation * inner.block<3, 3>(3 * a, 3 * b);
    }
  }
  symmetrizeElementMatrix(out);
}

/// Throws Error unless the assembler was built for the mesh (same DOFs and elements).
void checkAssemblerMatchesMesh(const MatrixAssembler* assembler, const TetMesh& mesh) {
  if (assembler == nullptr) throw Error("CorotationalLinearFEM: the assembler is null");
  if (assembler->numDofs() != mesh.numDofs() || assembler->numElements() != mesh.numElements()) {
    throw Error("CorotationalLinearFEM: the assembler was built for a mesh with " +
                std::to_string(assembler->numDofs() / 3) + " vertices and " + std::to_string(assembler->numElements()) +
                " elements, not " + std::to_string(mesh.numVertices()) + " and " + std::to_string(mesh.numElements()));
  }
}

/// Scatter offsets into the assembler's pattern: blockSlots[16 e + 4 b + a] is the
/// valuePtr() index of block (a, b) of element e, columnLengths[4 e + b] the distance
/// between two scalar columns of vertex b's block column.
void elementScatterOffsets(const MatrixAssembler& assembler, int numElements, std::vector<int>& blockSlots,
                           std::vector<int>& columnLengths) {
  blockSlots.resize(toIndex(numElements) * 16);
  columnLengths.resize(toIndex(numElements) * 4);
  for (int e = 0; e < numElements; ++e) {
    for (int b = 0; b < 4; ++b) {
      for (int a = 0; a < 4; ++a)
        blockSlots[(toIndex(e) * 16) + toIndex((4 * b) + a)] = assembler.slot(e, 3 * a, 3 * b);
      columnLengths[(toIndex(e) * 4) + toIndex(b)] = assembler.slot(e, 0, (3 * b) + 1) - assembler.slot(e, 0, 3 * b);
    }
  }
}

/// Vertex -> element incidences of the per-vertex assembly pass: the (element, local
/// vertex) pairs 4 e + a of vertex v are incidences[offsets[v] .. offsets[v+1]),
/// ascending.
void vertexIncidences(const Eigen::Matrix4Xi& elements, int numVertices, std::vector<int>& offsets,
                      std::vector<int>& incidences) {
  const auto entries = static_cast<Index>(elements.size());
  offsets.assign(toIndex(numVertices) + 1, 0);
  for (Index k = 0; k < entries; ++k) ++offsets[toIndex(elements.data()[k]) + 1];
  for (Index v = 0; v < toIndex(numVertices); ++v) offsets[v + 1] += offsets[v];
  incidences.resize(entries);
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (int k = 0; k < static_cast<int>(entries); ++k) incidences[toIndex(fill[toIndex(elements.data()[k])]++)] = k;
}

/// F = I + sum_a u_a g_a^T of element e: the same as sum_a x_a g_a^T (sum_a X_a g_a^T =
/// I), without the cancellation of positions far from the origin.
inline Eigen::Matrix3d elementDeformationGradient(const Eigen::VectorXd& displacement, const Eigen::Matrix4Xi& elements,
                                                  int e, const Eigen::Matrix<double, 3, 4>& g) {
  ElementPositions elementDisplacement;
  for (int a = 0; a < 4; ++a) {
    elementDisplacement.col(a) = displacement.segment<3>(3 * static_cast<Eigen::Index>(elements(a, e)));
  }
  Eigen::Matrix3d f = elementDisplacement * g.transpose();
  f.diagonal().array() += 1.0;
  return f;
}

/// V sigma = lambda V tr(eps) I + 2 mu V eps for the corotated strain eps = sym(R^T F) - I,
/// with lameVolume = (lambda V, mu V); sets energy to the element's strain energy.
inline Eigen::Matrix3d corotatedStressVolume(const Eigen::Matrix3d& rotation, const Eigen::Matrix3d& f,
                                             const Eigen::Vector2d& lameVolume, double& energy) {
  const Eigen::Matrix3d corotated = rotation.transpose() * f;
  Eigen::Matrix3d strain = 0.5 * (corotated + corotated.transpose());
  strain.diagonal().array() -= 1.0;
  const double lambdaVolume = lameVolume[0];
  const double muVolume = lameVolume[1];
  const double trace = strain.trace();
  Eigen::Matrix3d stressVolume = (2.0 * muVolume) * strain;
  stressVolume.diagonal().array() += lambdaVolume * trace;
  energy = (muVolume * strain.squaredNorm()) + (0.5 * lambdaVolume * trace * trace);
  return stressVolume;
}

}  // namespace

CorotationalLinearFEM::CorotationalLinearFEM(const TetMesh& mesh, TangentKind tangentKind)
    : CorotationalLinearFEM(mesh, std::make_shared<const MatrixAssembler>(mesh), tangentKind) {}

CorotationalLinearFEM::CorotationalLinearFEM(const TetMesh& mesh, std::shared_ptr<const MatrixAssembler> assembler,
                                             TangentKind tangentKind)
    : assembler_(std::move(assembler)),
      tangentKind_(tangentKind),
      numDofs_(mesh.numDofs()),
      elements_(mesh.elements()) {
  checkAssemblerMatchesMesh(assembler_.get(), mesh);
  const int numElements = mesh.numElements();
  const Index count = toIndex(numElements);
  restPositions_.resize(count);
  shapeGradients_.resize(count);
  elementStiffness_.resize(count);
  rotations_.assign(count, Eigen::Matrix3d::Identity());
  elementEnergies_.assign(count, 0.0);
  lameVolume_.resize(count);
  rotatedGradients_.resize(count);
  elementForces_.resize(count);
  std::vector<double> signedVolumes(count);
  std::vector<double> longestEdges(count);
#pragma omp parallel for schedule(static)
  for (int e = 0; e < numElements; ++e) {
    const Index i = toIndex(e);
    const ElementPositions x = mesh.elementRestPositions(e);
    restPositions_[i] = x;
    shapeGradients_[i] = shapeFunctionGradients(x, &signedVolumes[i]);
    longestEdges[i] = longestEdge(x);
    const Material& material = mesh.elementMaterial(e);
    elementStiffness_[i] = linearElementStiffness(x, material.youngsModulus, material.poissonRatio);
    lameVolume_[i] = lameParameters(material.youngsModulus, material.poissonRatio) * std::abs(signedVolumes[i]);
  }
  // Checked after the loop, in element order, so the error names the lowest element
  // whatever the thread count.
  for (int e = 0; e < numElements; ++e)
    checkElementVolume(e, signedVolumes[toIndex(e)], longestEdges[toIndex(e)], "CorotationalLinearFEM");
  elementScatterOffsets(*assembler_, numElements, blockSlots_, columnLengths_);
  vertexIncidences(elements_, mesh.numVertices(), incidenceOffsets_, incidences_);
  batches_ = std::make_shared<const detail::ElementBatches>(
      detail::makeElementBatches(elements_, shapeGradients_, lameVolume_));
  const Eigen::SparseMatrix<double> pattern = assembler_->createMatrix();
  patternOuter_.assign(pattern.outerIndexPtr(), pattern.outerIndexPtr() + pattern.outerSize() + 1);
}

Eigen::SparseMatrix<double> CorotationalLinearFEM::createStiffnessMatrix() const { return assembler_->createMatrix(); }

void CorotationalLinearFEM::checkDisplacement(const Eigen::VectorXd& displacement, const char* caller) const {
  if (displacement.size() != numDofs_) {
    throw Error(std::string("CorotationalLinearFEM::") + caller + ": displacement has size " +
                std::to_string(displacement.size()) + ", expected " + std::to_string(numDofs_));
  }
}

ElementPositions CorotationalLinearFEM::currentPositions(int e, const Eigen::VectorXd& displacement) const {
  ElementPositions x = restPositions_[toIndex(e)];
  for (int a = 0; a < 4; ++a) x.col(a) += displacement.segment<3>(3 * static_cast<Eigen::Index>(elements_(a, e)));
  return x;
}

bool CorotationalLinearFEM::cacheHolds(const Eigen::VectorXd& displacement) const {
  return cacheValid_ && cachedDisplacement_.size() == displacement.size() &&
         std::memcmp(cachedDisplacement_.data(), displacement.data(),
                     sizeof(double) * static_cast<std::size_t>(displacement.size())) == 0;
}

void CorotationalLinearFEM::evaluateElement(int e, const Eigen::VectorXd& displacement, bool warmStart,
                                            bool needDifferentialOperator, long long& newtonSteps,
                                            long long& fallbacks) {
  const Index i = toIndex(e);
  const Eigen::Matrix<double, 3, 4>& g = shapeGradients_[i];
  const Eigen::Matrix3d deformationGradient = elementDeformationGradient(displacement, elements_, e, g);
  const PolarRotation polar =
      polarRotation(deformationGradient, warmStart ? &rotations_[i] : nullptr, needDifferentialOperator);
  newtonSteps += polar.newtonSteps;
  fallbacks += polar.usedDecomposition ? 1 : 0;
  const Eigen::Matrix3d& rotation = polar.rotation;
  rotations_[i] = rotation;
  if (needDifferentialOperator) differentialOperators_[i] = polar.differentialOperator;
  const Eigen::Matrix3d stressVolume =
      corotatedStressVolume(rotation, deformationGradient, lameVolume_[i], elementEnergies_[i]);
  const Eigen::Matrix3d rotatedStress = rotation * stressVolume;
  elementForces_[i].noalias() = rotatedStress * g;
  rotatedGradients_[i].noalias() = rotation * g;
}

void CorotationalLinearFEM::evaluateBatches(const Eigen::VectorXd& displacement, bool needDifferentialOperator,
                                            long long& newtonSteps, long long& fallbacks) {
  detail::BatchOutputs outputs;
  outputs.rotations = rotations_.data();
  outputs.differentialOperators = needDifferentialOperator ? differentialOperators_.data() : nullptr;
  outputs.energies = elementEnergies_.data();
  outputs.rotatedGradients = rotatedGradients_.data();
  outputs.forces = elementForces_.data();
  const int numBatches = batches_->numBatches;
  long long steps = 0;
  long long decompositions = 0;
#pragma omp parallel for schedule(static) reduction(+ : steps, decompositions)
  for (int batch = 0; batch < numBatches; ++batch) {
    detail::BatchCounters counters;
    detail::evaluateBatch(*batches_, batch, displacement, outputs, counters);
    steps += counters.newtonSteps;
    decompositions += counters.fallbacks;
  }
  newtonSteps += steps;
  fallbacks += decompositions;
}

void CorotationalLinearFEM::evaluateElements(const Eigen::VectorXd& displacement, bool needDifferentialOperator) {
  if ((cacheHolds(displacement)) && (!needDifferentialOperator || cacheHasDifferentialOperators_)) {
    ++rotationStats_.reusedEvaluations;
    return;
  }
  const int numElements = this->numElements();
  if (needDifferentialOperator) differentialOperators_.resize(toIndex(numElements));
  // The rotations of the previous evaluation, if there is one, are the warm start.
  const bool warmStart = rotationStart_ == RotationStart::previousEvaluation && cacheValid_;
  long long newtonSteps = 0;
  long long fallbacks = 0;
  // Elements before firstScalar went through the batched kernel.
  int firstScalar = 0;
  if (elementKernel_ == ElementKernel::batched && rotationStart_ == RotationStart::fromDeformation) {
    evaluateBatches(displacement, needDifferentialOperator, newtonSteps, fallbacks);
    firstScalar = batches_->numBatches * detail::kElementLanes;
  }
#pragma omp parallel for schedule(static) reduction(+ : newtonSteps, fallbacks)
  for (int e = firstScalar; e < numElements; ++e)
    evaluateElement(e, displacement, warmStart, needDifferentialOperator, newtonSteps, fallbacks);
  rotationStats_.extractions += numElements;
  rotationStats_.newtonSteps += newtonSteps;
  rotationStats_.decompositionFallbacks += fallbacks;
  // Summed serially in element order: the total does not depend on the thread count.
  double energy = 0.0;
  for (const double elementEnergy : elementEnergies_) energy += elementEnergy;
  cachedEnergy_ = energy;
  cachedDisplacement_ = displacement;
  cacheValid_ = true;
  cacheHasDifferentialOperators_ = needDifferentialOperator;
}

void CorotationalLinearFEM::assembleForces(Eigen::VectorXd& forces) const {
  const int numVertices = numDofs_ / 3;
  forces.resize(numDofs_);
#pragma omp parallel for schedule(static)
  for (int v = 0; v < numVertices; ++v) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int p = incidenceOffsets_[toIndex(v)]; p < incidenceOffsets_[toIndex(v) + 1]; ++p) {
      const int incidence = incidences_[toIndex(p)];
      sum += elementForces_[toIndex(incidence / 4)].col(incidence % 4);
    }
    forces.segment<3>(3 * static_cast<Eigen::Index>(v)) = sum;
  }
}

void CorotationalLinearFEM::assembleSimpleTangent(Eigen::SparseMatrix<double>& stiffness) const {
  const int numVertices = numDofs_ / 3;
  const int* outer = stiffness.outerIndexPtr();
  double* values = stiffness.valuePtr();
#pragma omp parallel for schedule(static)
  for (int v = 0; v < numVertices; ++v) {
    // The three columns of vertex v are contiguous and written by this iteration only.
    std::fill(values + outer[3 * v], values + outer[(3 * v) + 3], 0.0);
    for (int p = incidenceOffsets_[toIndex(v)]; p < incidenceOffsets_[toIndex(v) + 1]; ++p) {
      const int incidence = incidences_[toIndex(p)];
      const Index e = toIndex(incidence / 4);
      const int b = incidence % 4;
      const Eigen::Matrix<double, 3, 4>& h = rotatedGradients_[e];
      const double lambdaVolume = lameVolume_[e][0];
      const double muVolume = lameVolume_[e][1];
      const Eigen::Vector3d hb = h.col(b);
      const int columnLength = columnLengths_[(e * 4) + toIndex(b)];
      const int* slots = blockSlots_.data() + (e * 16) + toIndex(4 * b);
      // Block (a, b) = lambda V h_a h_b^T + mu V h_b h_a^T + mu V (h_a . h_b) I; its
      // column j is lambda V h_b[j] h_a + mu V h_a[j] h_b + mu V (h_a . h_b) e_j.
      const Eigen::Vector3d lambdaHb = lambdaVolume * hb;
      const Eigen::Vector4d dots = muVolume * (h.transpose() * hb);
      for (int a = 0; a < 4; ++a) {
        const Eigen::Vector3d ha = h.col(a);
        const Eigen::Vector3d muHa = muVolume * ha;
        double* block = values + slots[a];
        for (int j = 0; j < 3; ++j) {
          Eigen::Map<Eigen::Vector3d> column(block + (j * columnLength));
          column += (lambdaHb[j] * ha) + (muHa[j] * hb);
          column[j] += dots[a];
        }
      }
    }
  }
}

void CorotationalLinearFEM::assembleTangent(const Eigen::VectorXd& displacement,
                                            Eigen::SparseMatrix<double>& stiffness) const {
  if (stiffness.rows() != numDofs_ || stiffness.cols() != numDofs_ || !stiffness.isCompressed() ||
      stiffness.nonZeros() != assembler_->nonZeros()) {
    stiffness = assembler_->createMatrix();
  }
  if (tangentKind_ == TangentKind::simple) {
    if (!std::equal(patternOuter_.begin(), patternOuter_.end(), stiffness.outerIndexPtr())) {
      throw Error("CorotationalLinearFEM::tangentStiffness: the " + std::to_string(stiffness.rows()) + " x " +
                  std::to_string(stiffness.cols()) +
                  " matrix does not have the assembler's pattern; create it with createStiffnessMatrix()");
    }
    assembleSimpleTangent(stiffness);
  } else {
    assembler_->assemble(
        [&](int e, ElementMatrix& out) {
          const Index i = toIndex(e);
          exactElementTangent(elementStiffness_[i], rotations_[i], differentialOperators_[i], shapeGradients_[i],
                              currentPositions(e, displacement), restPositions_[i], out);
        },
        stiffness);
  }
}

void CorotationalLinearFEM::internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) {
  checkDisplacement(displacement, "internalForces");
  evaluateElements(displacement, false);
  assembleForces(forces);
}

void CorotationalLinearFEM::tangentStiffness(const Eigen::VectorXd& displacement,
                                             Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "tangentStiffness");
  evaluateElements(displacement, tangentKind_ == TangentKind::exact);
  assembleTangent(displacement, stiffness);
}

void CorotationalLinearFEM::forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                                             Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "forcesAndTangent");
  evaluateElements(displacement, tangentKind_ == TangentKind::exact);
  assembleForces(forces);
  assembleTangent(displacement, stiffness);
}

bool CorotationalLinearFEM::elementTangent(const Eigen::VectorXd& displacement, int element,
                                           ElementMatrix& tangent) const {
  checkDisplacement(displacement, "elementTangent");
  if (element < 0 || element >= numElements()) {
    throw Error("CorotationalLinearFEM::elementTangent: element " + std::to_string(element) + " is out of range [0, " +
                std::to_string(numElements()) + ")");
  }
  const Index i = toIndex(element);
  const ElementPositions x = currentPositions(element, displacement);
  const PolarDecomposition polar = polarDecomposition(x * shapeGradients_[i].transpose());
  if (tangentKind_ == TangentKind::simple) {
    simpleElementTangent(elementStiffness_[i], polar.rotation, tangent);
  } else {
    exactElementTangent(elementStiffness_[i], polar.rotation, rotationDifferentialOperator(polar), shapeGradients_[i],
                        x, restPositions_[i], tangent);
  }
  return true;
}

double CorotationalLinearFEM::elasticEnergy(const Eigen::VectorXd& displacement) {
  checkDisplacement(displacement, "elasticEnergy");
  evaluateElements(displacement, false);
  return cachedEnergy_;
}

double CorotationalLinearFEM::energyOfLastEvaluation() const {
  if (!cacheValid_) throw Error("CorotationalLinearFEM::energyOfLastEvaluation: no evaluation has been made yet");
  return cachedEnergy_;
}

}  // namespace asyncfem
