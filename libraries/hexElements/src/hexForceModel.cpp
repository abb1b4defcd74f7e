// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexForceModel.hpp>
#include <climits>
#include <exception>
#include <numeric>
#include <string>
#include <utility>

namespace asyncfem {

namespace {

// Below this many hexahedra an evaluation takes about a millisecond on one core, and the
// barriers between colours cost more than the threads gain on a loaded machine. The result
// does not depend on it: the colouring fixes the order in which every entry is summed.
constexpr Eigen::Index kMinElementsForThreads = 2048;

// Greedy colouring of the elements, each the smallest colour no earlier element sharing a
// vertex has: elements of one colour share no vertex, so their scatters never collide.
// Returns the elements grouped by colour (ascending within a colour) and the offsets.
std::pair<std::vector<int>, std::vector<int>> colorElements(const Eigen::Matrix<int, 8, Eigen::Dynamic>& hexahedra,
                                                            int numVertices) {
  std::vector<std::vector<int>> vertexElements(static_cast<std::size_t>(numVertices));
  for (Eigen::Index e = 0; e < hexahedra.cols(); ++e)
    for (int a = 0; a < 8; ++a)
      vertexElements[static_cast<std::size_t>(hexahedra(a, e))].push_back(static_cast<int>(e));
  std::vector<int> color(static_cast<std::size_t>(hexahedra.cols()), -1);
  std::vector<Eigen::Index> takenBy;  // takenBy[c] == e: a neighbour of e has colour c
  for (Eigen::Index e = 0; e < hexahedra.cols(); ++e) {
    for (int a = 0; a < 8; ++a)
      for (const int other : vertexElements[static_cast<std::size_t>(hexahedra(a, e))])
        if (other < e) takenBy[static_cast<std::size_t>(color[static_cast<std::size_t>(other)])] = e;
    int c = 0;
    while (c < static_cast<int>(takenBy.size()) && takenBy[static_cast<std::size_t>(c)] == e) ++c;
    if (c == static_cast<int>(takenBy.size())) takenBy.push_back(-1);
    color[static_cast<std::size_t>(e)] = c;
  }
  std::vector<int> offsets(takenBy.size() + 1, 0);
  for (const int c : color) ++offsets[static_cast<std::size_t>(c) + 1];
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<int> ordered(color.size());
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (std::size_t e = 0; e < color.size(); ++e)
    ordered[static_cast<std::size_t>(fill[color[e]]++)] = static_cast<int>(e);
  return {std::move(ordered), std::move(offsets)};
}

}  // namespace

HexForceModel::HexForceModel(const TetMesh& mesh, std::string name)
    : name_(std::move(name)),
      numDofs_(mesh.numDofs()),
      restPositions_(mesh.restPositions()),
      hexahedra_(mesh.hexahedra()) {
  const int numElements = mesh.numElements();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(numElements) * 64 * 9);
  for (int e = 0; e < numElements; ++e) {
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) entries.emplace_back((3 * hexahedra_(a, e)) + i, (3 * hexahedra_(b, e)) + j, 0.0);
  }
  pattern_.resize(numDofs_, numDofs_);
  pattern_.setFromTriplets(entries.begin(), entries.end());
  pattern_.makeCompressed();
  const int* outer = pattern_.outerIndexPtr();
  const int* inner = pattern_.innerIndexPtr();
  columnLength_.resize(static_cast<std::size_t>(mesh.numVertices()));
  for (int v = 0; v < mesh.numVertices(); ++v)
    columnLength_[static_cast<std::size_t>(v)] = outer[(3 * v) + 1] - outer[3 * v];
  blockSlots_.resize(static_cast<std::size_t>(numElements));
  for (int e = 0; e < numElements; ++e) {
    for (int b = 0; b < 8; ++b) {
      const int column = 3 * hexahedra_(b, e);
      for (int a = 0; a < 8; ++a) {
        const int* found = std::lower_bound(inner + outer[column], inner + outer[column + 1], 3 * hexahedra_(a, e));
        blockSlots_[static_cast<std::size_t>(e)](a, b) = static_cast<int>(found - inner);
      }
    }
  }
  std::tie(coloredElements_, colorOffsets_) = colorElements(hexahedra_, mesh.numVertices());
}

void HexForceModel::checkDisplacement(const Eigen::VectorXd& displacement, const char* what) const {
  if (displacement.size() != numDofs_) {
    throw Error(name_ + "::" + what + ": displacement has " + std::to_string(displacement.size()) +
                " entries, expected " + std::to_string(numDofs_));
  }
}

void HexForceModel::scatter(Eigen::Index e, const HexElementEnergy& result, Eigen::VectorXd* forces,
                            Eigen::SparseMatrix<double>* stiffness) const {
  if (forces != nullptr) {
    for (int a = 0; a < 8; ++a)
      forces->segment<3>(3 * static_cast<Eigen::Index>(hexahedra_(a, e))) += result.force.segment<3>(3 * a);
  }
  if (stiffness == nullptr) return;
  double* values = stiffness->valuePtr();
  const Eigen::Matrix<int, 8, 8>& slots = blockSlots_[static_cast<std::size_t>(e)];
  for (int b = 0; b < 8; ++b) {
    const int length = columnLength_[static_cast<std::size_t>(hexahedra_(b, e))];
    for (int a = 0; a < 8; ++a)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) values[slots(a, b) + (j * length) + i] += result.tangent((3 * a) + i, (3 * b) + j);
  }
}

double HexForceModel::evaluate(const Eigen::VectorXd& displacement, Eigen::VectorXd* forces,
                               Eigen::SparseMatrix<double>* stiffness) const {
  if (forces != nullptr) forces->setZero(numDofs_);
  if (stiffness != nullptr) {
    if (stiffness->nonZeros() != pattern_.nonZeros() || !stiffness->isCompressed()) *stiffness = pattern_;
    std::fill(stiffness->valuePtr(), stiffness->valuePtr() + stiffness->nonZeros(), 0.0);
  }
  const Eigen::Index numElements = hexahedra_.cols();
  std::vector<double> energies(static_cast<std::size_t>(numElements), 0.0);
  std::exception_ptr failure;
  Eigen::Index failed = numElements;  // the first failing element, so the error names the same one on any threads
  // Colours in order, the elements of one colour (sharing no vertex) spread over the threads.
  for (std::size_t c = 0; c + 1 < colorOffsets_.size(); ++c) {
#pragma omp parallel for schedule(dynamic, 16) if (numElements >= kMinElementsForThreads)
    for (int k = colorOffsets_[c]; k < colorOffsets_[c + 1]; ++k) {
      const Eigen::Index e = coloredElements_[static_cast<std::size_t>(k)];
      HexElementPositions rest;
      HexElementPositions deformed;
      for (int a = 0; a < 8; ++a) {
        const int v = hexahedra_(a, e);
        rest.col(a) = restPositions_.col(v);
        deformed.col(a) = rest.col(a) + displacement.segment<3>(3 * static_cast<Eigen::Index>(v));
      }
      try {
        const HexElementEnergy result = element(e, rest, deformed, stiffness != nullptr);
        energies[static_cast<std::size_t>(e)] = result.energy;
        scatter(e, result, forces, stiffness);
      } catch (...) {
#pragma omp critical(hexForceModelFailure)
        if (e < failed) {
          failed = e;
          failure = std::current_exception();
        }
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
  return std::accumulate(energies.begin(), energies.end(), 0.0);  // element order: the same sum on any threads
}

void HexForceModel::internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) {
  checkDisplacement(displacement, "internalForces");
  evaluate(displacement, &forces, nullptr);
}

void HexForceModel::tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "tangentStiffness");
  evaluate(displacement, nullptr, &stiffness);
}

void HexForceModel::forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                                     Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "forcesAndTangent");
  evaluate(displacement, &forces, &stiffness);
}

double HexForceModel::elasticEnergy(const Eigen::VectorXd& displacement) {
  checkDisplacement(displacement, "elasticEnergy");
  return evaluate(displacement, nullptr, nullptr);
}

}  // namespace asyncfem
