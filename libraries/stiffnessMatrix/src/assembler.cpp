// SPDX-License-Identifier: BSD-3-Clause
#include <omp.h>

#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <climits>
#include <cmath>
#include <cstring>
#include <exception>
#include <numeric>
#include <string>

#include "detail/linearStiffness.hpp"
#include "detail/sizeIndex.hpp"

namespace asyncfem {

namespace {

using detail::Index;
using detail::toIndex;

// Below this many elements an assembly takes about 2 ms on one core; the handful of
// barriers (one per colour) of a threaded run then gains little and, on a loaded machine
// where a thread may be descheduled at a barrier, can cost several times the work. The
// result does not depend on this choice: the summation order is fixed by the colouring.
constexpr int kMinElementsForThreads = 16384;

// Prefix sum of counts in place: counts[i] becomes the start of segment i; returns the
// total. counts has one trailing entry that receives the total.
long long exclusiveScan(std::vector<int>& counts) {
  long long running = 0;
  for (int& c : counts) {
    const long long count = c;
    if (running > INT_MAX) throw Error("MatrixAssembler: index overflow while building the pattern");
    c = static_cast<int>(running);
    running += count;
  }
  return running;
}

// Compressed rows: the items of row r are items[offsets[r] .. offsets[r+1]).
struct CompressedRows {
  std::vector<int> offsets;
  std::vector<int> items;
};

// Distinct vertices of every chunk of chunkSize consecutive elements, in first-seen
// order.
CompressedRows chunkVertexSets(const Eigen::Matrix4Xi& elements, int numVertices, int chunkSize) {
  const int numElements = static_cast<int>(elements.cols());
  const int numChunks = (numElements + chunkSize - 1) / chunkSize;
  CompressedRows chunkVertices{std::vector<int>(toIndex(numChunks) + 1, 0), std::vector<int>(toIndex(numElements) * 4)};
  std::vector<int> stamp(toIndex(numVertices), -1);
  int written = 0;
  for (int chunk = 0; chunk < numChunks; ++chunk) {
    chunkVertices.offsets[toIndex(chunk)] = written;
    const Index first = toIndex(chunk * chunkSize) * 4;
    const Index last = toIndex(std::min(numElements, (chunk + 1) * chunkSize)) * 4;
    for (Index k = first; k < last; ++k) {
      const int v = elements.data()[k];
      if (stamp[toIndex(v)] == chunk) continue;
      stamp[toIndex(v)] = chunk;
      chunkVertices.items[toIndex(written++)] = v;
    }
  }
  chunkVertices.offsets[toIndex(numChunks)] = written;
  chunkVertices.items.resize(toIndex(written));
  return chunkVertices;
}

// Transpose of chunkVertices: the chunks touching every vertex, ascending.
CompressedRows vertexChunkSets(const CompressedRows& chunkVertices, int numVertices) {
  const int numChunks = static_cast<int>(chunkVertices.offsets.size()) - 1;
  CompressedRows vertexChunks{std::vector<int>(toIndex(numVertices) + 1, 0),
                              std::vector<int>(chunkVertices.items.size())};
  for (int v : chunkVertices.items) ++vertexChunks.offsets[toIndex(v)];
  exclusiveScan(vertexChunks.offsets);
  std::vector<int> fill(vertexChunks.offsets.begin(), vertexChunks.offsets.end() - 1);
  for (int chunk = 0; chunk < numChunks; ++chunk) {
    for (int p = chunkVertices.offsets[toIndex(chunk)]; p < chunkVertices.offsets[toIndex(chunk) + 1]; ++p) {
      const int v = chunkVertices.items[toIndex(p)];
      vertexChunks.items[toIndex(fill[toIndex(v)]++)] = chunk;
    }
  }
  return vertexChunks;
}

// Chunk colouring: chunks of chunkSize consecutive elements; greedy, smallest colour not
// used by an earlier chunk sharing a vertex. Returns the colour of every chunk.
std::vector<int> colorChunks(const Eigen::Matrix4Xi& elements, int numVertices, int chunkSize, int* numColors) {
  const CompressedRows chunkVertices = chunkVertexSets(elements, numVertices, chunkSize);
  const CompressedRows vertexChunks = vertexChunkSets(chunkVertices, numVertices);
  const int numChunks = static_cast<int>(chunkVertices.offsets.size()) - 1;
  std::vector<int> colors(toIndex(numChunks), -1);
  std::vector<int> forbiddenBy;  // forbiddenBy[c] == chunk: colour c is taken by a neighbour of chunk
  int colorCount = 0;
  for (int chunk = 0; chunk < numChunks; ++chunk) {
    for (int p = chunkVertices.offsets[toIndex(chunk)]; p < chunkVertices.offsets[toIndex(chunk) + 1]; ++p) {
      const int v = chunkVertices.items[toIndex(p)];
      for (int q = vertexChunks.offsets[toIndex(v)]; q < vertexChunks.offsets[toIndex(v) + 1]; ++q) {
        const int other = vertexChunks.items[toIndex(q)];
        if (other >= chunk) break;  // ascending: the rest are not coloured yet
        forbiddenBy[toIndex(colors[toIndex(other)])] = chunk;
      }
    }
    int color = 0;
    while (color < colorCount && forbiddenBy[toIndex(color)] == chunk) ++color;
    if (color == colorCount) {
      ++colorCount;
      forbiddenBy.push_back(-1);
    }
    colors[toIndex(chunk)] = color;
  }
  *numColors = colorCount;
  return colors;
}

// Incident (element, local vertex) pairs of every vertex, encoded 4 e + b, ascending in
// e: counting sort, two passes.
CompressedRows vertexIncidences(const Eigen::Matrix4Xi& elements, int numVertices) {
  const int numElements = static_cast<int>(elements.cols());
  CompressedRows incidences{std::vector<int>(toIndex(numVertices) + 1, 0), std::vector<int>(toIndex(numElements) * 4)};
  for (Index k = 0; k < toIndex(numElements) * 4; ++k) ++incidences.offsets[toIndex(elements.data()[k])];
  exclusiveScan(incidences.offsets);
  std::vector<int> fill(incidences.offsets.begin(), incidences.offsets.end() - 1);
  for (int k = 0; k < numElements * 4; ++k) incidences.items[toIndex(fill[toIndex(elements.data()[k])]++)] = k;
  return incidences;
}

// Row vertices of column vertex v: v itself (so that every diagonal block is in the
// pattern, even for a vertex no element uses) and the vertices of its elements, appended
// to rows (cleared first) unsorted; stamp[u] == v marks u as seen.
inline void collectRows(int v, const CompressedRows& incidences, const int* elementVertices, std::vector<int>& stamp,
                        std::vector<int>& rows) {
  rows.clear();
  stamp[toIndex(v)] = v;
  rows.push_back(v);
  for (int p = incidences.offsets[toIndex(v)]; p < incidences.offsets[toIndex(v) + 1]; ++p) {
    const Index e = toIndex(incidences.items[toIndex(p)] / 4);
    for (Index a = 0; a < 4; ++a) {
      const int u = elementVertices[(4 * e) + a];
      if (stamp[toIndex(u)] != v) {
        stamp[toIndex(u)] = v;
        rows.push_back(u);
      }
    }
  }
}

// Pattern pass 1: blockOuter[v] = the number of row vertices of column vertex v, then
// the exclusive prefix sum; returns the number of vertex blocks. Per-thread stamp
// arrays replace sets and searches.
long long countBlockRows(const CompressedRows& incidences, const int* elementVertices, int numVertices,
                         std::vector<int>& blockOuter) {
  const Index vertexCount = toIndex(numVertices);
  blockOuter.assign(vertexCount + 1, 0);
#pragma omp parallel
  {
    std::vector<int> stamp(vertexCount, -1);
    std::vector<int> rows;
#pragma omp for schedule(static)
    for (int v = 0; v < numVertices; ++v) {
      collectRows(v, incidences, elementVertices, stamp, rows);
      blockOuter[toIndex(v)] = static_cast<int>(rows.size());
    }
  }
  const long long blockCount = exclusiveScan(blockOuter);
  if (9 * blockCount > INT_MAX) {
    throw Error("MatrixAssembler: the pattern has " + std::to_string(9 * blockCount) +
                " entries, more than int indices can address");
  }
  return blockCount;
}

// Pattern pass 2: writes the sorted row vertices of every column vertex into blockRows
// and, through a vertex -> position map, the block slots (valuePtr() offsets) of every
// incident element into blockSlots (numElements * 16, at e * 16 + b * 4 + a).
void writeBlockRowsAndSlots(const CompressedRows& incidences, const int* elementVertices, int numVertices,
                            const std::vector<int>& blockOuter, std::vector<int>& blockRows,
                            std::vector<int>& blockSlots) {
  const Index vertexCount = toIndex(numVertices);
#pragma omp parallel
  {
    std::vector<int> stamp(vertexCount, -1);
    std::vector<int> position(vertexCount, 0);
    std::vector<int> rows;
#pragma omp for schedule(static)
    for (int v = 0; v < numVertices; ++v) {
      collectRows(v, incidences, elementVertices, stamp, rows);
      std::sort(rows.begin(), rows.end());
      const int begin = blockOuter[toIndex(v)];
      for (std::size_t p = 0; p < rows.size(); ++p) {
        blockRows[toIndex(begin) + p] = rows[p];
        position[toIndex(rows[p])] = static_cast<int>(p);
      }
      // Scalar column 3 v starts at 9 * blockOuter[v]; block row p starts 3 p below.
      for (int p = incidences.offsets[toIndex(v)]; p < incidences.offsets[toIndex(v) + 1]; ++p) {
        const Index e = toIndex(incidences.items[toIndex(p)] / 4);
        const Index b = toIndex(incidences.items[toIndex(p)] % 4);
        for (Index a = 0; a < 4; ++a) {
          const int u = elementVertices[(4 * e) + a];
          blockSlots[(e * 16) + (b * 4) + a] = (9 * begin) + (3 * position[toIndex(u)]);
        }
      }
    }
  }
}

// Chunk colouring of the scheduling: chunks of consecutive elements (good locality
// within a chunk), shrunk until every colour has enough of them to keep threads busy.
// Returns the colour of every chunk and sets chunkSize and numColors. The result depends
// on the mesh only, never on the thread count.
std::vector<int> chooseChunkColoring(const Eigen::Matrix4Xi& elements, int numVertices, int* chunkSize,
                                     int* numColors) {
  const int numElements = static_cast<int>(elements.cols());
  *chunkSize = std::max(1, std::min(256, numElements / 64));
  while (true) {
    std::vector<int> colors = colorChunks(elements, numVertices, *chunkSize, numColors);
    const int numChunks = static_cast<int>(colors.size());
    if (*chunkSize == 1 || numChunks >= 16 * *numColors) return colors;
    *chunkSize = std::max(1, *chunkSize / 4);
  }
}

// Counting sort of the chunks by colour: colour c holds
// coloredChunks[colorOffsets[c] .. colorOffsets[c+1]), ascending.
void groupChunksByColor(const std::vector<int>& colors, int numColors, std::vector<int>& colorOffsets,
                        std::vector<int>& coloredChunks) {
  colorOffsets.assign(toIndex(numColors) + 1, 0);
  for (int c : colors) ++colorOffsets[toIndex(c)];
  exclusiveScan(colorOffsets);
  coloredChunks.resize(colors.size());
  std::vector<int> fill(colorOffsets.begin(), colorOffsets.end() - 1);
  for (int chunk = 0; chunk < static_cast<int>(colors.size()); ++chunk) {
    coloredChunks[toIndex(fill[toIndex(colors[toIndex(chunk)])]++)] = chunk;
  }
}

// The exception of the lowest failing element of a parallel loop: exceptions may not
// leave a parallel region, and keeping the lowest element's one makes the error reported
// independent of the thread count and the schedule.
class FirstElementError {
 public:
  // Keeps the exception in flight if element e is below every earlier failing element.
  void record(int e) {
#pragma omp critical(asyncfem_assembler_error)
    {
      if (e < element_) {
        element_ = e;
        error_ = std::current_exception();
      }
    }
  }
  // Rethrows the kept exception, if any.
  void rethrowIfAny() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::exception_ptr error_;
  int element_ = INT_MAX;
};

// Element schedule of an assembler: chunks of chunkSize consecutive elements grouped by
// colour (see MatrixAssembler's members of the same names).
struct ColoredChunkSchedule {
  const std::vector<int>& colorOffsets;
  const std::vector<int>& coloredChunks;
  int chunkSize;
  int numElements;
};

// Inside a parallel region: computes compute(e, local) and then scatter(e, local) for
// every element, colours in order and the chunks of one colour shared among the threads.
// Chunks of one colour share no vertex, so no two threads write the same value and every
// entry receives its contributions in the same order whatever the thread count. An
// element whose compute throws is recorded in errors and not scattered; all elements are
// still visited.
template <class Local, class Compute, class Scatter>
inline void forEachElementByColor(const ColoredChunkSchedule& schedule, const Compute& compute, const Scatter& scatter,
                                  FirstElementError& errors) {
  const int numColors = static_cast<int>(schedule.colorOffsets.size()) - 1;
  for (int color = 0; color < numColors; ++color) {
#pragma omp for schedule(dynamic, 1)
    for (int k = schedule.colorOffsets[toIndex(color)]; k < schedule.colorOffsets[toIndex(color) + 1]; ++k) {
      const int chunk = schedule.coloredChunks[toIndex(k)];
      const int first = chunk * schedule.chunkSize;
      const int last = std::min(schedule.numElements, first + schedule.chunkSize);
      Local local;
      for (int e = first; e < last; ++e) {
        try {
          compute(e, local);
        } catch (...) {
          errors.record(e);
          continue;
        }
        scatter(e, local);
      }
    }
  }
}

/// The mesh's tetrahedra; a hexahedral mesh is refused by name (hexElements assembles those).
const Eigen::Matrix4Xi& tetrahedraToAssemble(const TetMesh& mesh) {
  mesh.requireTetrahedra("MatrixAssembler (the tetrahedral stiffness, mass and force-model assembly)");
  return mesh.elements();
}

}  // namespace

MatrixAssembler::MatrixAssembler(const TetMesh& mesh)
    : numDofs_(mesh.numDofs()), numElements_(mesh.numElements()), elements_(tetrahedraToAssemble(mesh)) {
  const int numVertices = mesh.numVertices();
  {
    const CompressedRows incidences = vertexIncidences(elements_, numVertices);
    const long long blockCount = countBlockRows(incidences, elements_.data(), numVertices, blockOuter_);
    blockRows_.resize(static_cast<Index>(blockCount));
    blockSlots_.resize(toIndex(numElements_) * 16);
    writeBlockRowsAndSlots(incidences, elements_.data(), numVertices, blockOuter_, blockRows_, blockSlots_);
  }
  int numColors = 0;
  const std::vector<int> colors = chooseChunkColoring(elements_, numVertices, &chunkSize_, &numColors);
  groupChunksByColor(colors, numColors, colorOffsets_, coloredChunks_);
}

Eigen::Index MatrixAssembler::nonZeros() const {
  return blockOuter_.empty() ? 0 : 9 * static_cast<Eigen::Index>(blockOuter_.back());
}

Eigen::SparseMatrix<double> MatrixAssembler::createMatrix() const {
  Eigen::SparseMatrix<double> matrix(numDofs_, numDofs_);
  const Eigen::Index nnz = nonZeros();
  matrix.resizeNonZeros(nnz);
  int* outer = matrix.outerIndexPtr();
  int* inner = matrix.innerIndexPtr();
  double* values = matrix.valuePtr();
  const int numVertices = numDofs_ / 3;
#pragma omp parallel for schedule(static)
  for (int v = 0; v < numVertices; ++v) {
    const int begin = blockOuter_[toIndex(v)];
    const int count = blockOuter_[toIndex(v) + 1] - begin;
    for (int cj = 0; cj < 3; ++cj) {
      const int start = (9 * begin) + (cj * 3 * count);
      outer[(3 * v) + cj] = start;
      for (int p = 0; p < count; ++p) {
        const int row = 3 * blockRows_[toIndex(begin + p)];
        for (int ci = 0; ci < 3; ++ci) {
          inner[start + (3 * p) + ci] = row + ci;
          values[start + (3 * p) + ci] = 0.0;
        }
      }
    }
  }
  outer[numDofs_] = static_cast<int>(nnz);
  return matrix;
}

void MatrixAssembler::checkPattern(const Eigen::SparseMatrix<double>& matrix, const char* caller) const {
  // Sizes and column starts are cheap to compare and catch every matrix not made by
  // createMatrix() of an assembler of the same mesh connectivity.
  const bool same = matrix.rows() == numDofs_ && matrix.cols() == numDofs_ && matrix.isCompressed() &&
                    matrix.nonZeros() == nonZeros() && [&] {
                      const int* outer = matrix.outerIndexPtr();
                      for (int v = 0; v < numDofs_ / 3; ++v) {
                        if (outer[3 * v] != 9 * blockOuter_[toIndex(v)]) return false;
                      }
                      return true;
                    }();
  if (!same) {
    throw Error(std::string("MatrixAssembler::") + caller + ": the " + std::to_string(matrix.rows()) + " x " +
                std::to_string(matrix.cols()) + " matrix with " + std::to_string(matrix.nonZeros()) +
                " stored entries does not have the assembler's pattern (" + std::to_string(numDofs_) + " x " +
                std::to_string(numDofs_) + ", " + std::to_string(nonZeros()) +
                " entries); create it with createMatrix()");
  }
}

// Adds the element's 4x4 vertex blocks at their slots; a column of a block is
// columnLength values before the next.
void MatrixAssembler::scatterElement(int e, const ElementMatrix& local, double* values) const {
  const int* slots = blockSlots_.data() + (toIndex(e) * 16);
  for (int b = 0; b < 4; ++b) {
    const Index columnVertex = toIndex(elements_(b, e));
    const int columnLength = 3 * (blockOuter_[columnVertex + 1] - blockOuter_[columnVertex]);
    for (int a = 0; a < 4; ++a) {
      double* block = values + slots[(b * 4) + a];
      for (int cj = 0; cj < 3; ++cj) {
        double* column = block + (cj * columnLength);
        for (int ci = 0; ci < 3; ++ci) column[ci] += local((3 * a) + ci, (3 * b) + cj);
      }
    }
  }
}

template <class ElementFunction>
void MatrixAssembler::assembleWith(const ElementFunction& elementMatrix, Eigen::SparseMatrix<double>& matrix) const {
  checkPattern(matrix, "assemble");
  double* values = matrix.valuePtr();
  const Eigen::Index nnz = matrix.nonZeros();
  const ColoredChunkSchedule schedule{colorOffsets_, coloredChunks_, chunkSize_, numElements_};
  const auto scatter = [&](int e, const ElementMatrix& local) { scatterElement(e, local, values); };
  FirstElementError errors;
#pragma omp parallel if (numElements_ >= kMinElementsForThreads)
  {
#pragma omp for schedule(static)
    for (Eigen::Index k = 0; k < nnz; ++k) values[k] = 0.0;
    forEachElementByColor<ElementMatrix>(schedule, elementMatrix, scatter, errors);
  }
  errors.rethrowIfAny();
}

void MatrixAssembler::assemble(const ElementMatrixFunction& elementMatrix, Eigen::SparseMatrix<double>& matrix) const {
  assembleWith(elementMatrix, matrix);
}

void MatrixAssembler::assembleBatches(const ElementBatchFunction& elementBatch,
                                      Eigen::SparseMatrix<double>& matrix) const {
  checkPattern(matrix, "assembleBatches");
  double* values = matrix.valuePtr();
  const Eigen::Index nnz = matrix.nonZeros();
  const ColoredChunkSchedule schedule{colorOffsets_, coloredChunks_, chunkSize_, numElements_};
  FirstElementError errors;
#pragma omp parallel if (numElements_ >= kMinElementsForThreads)
  {
#pragma omp for schedule(static)
    for (Eigen::Index k = 0; k < nnz; ++k) values[k] = 0.0;
    const int numColors = static_cast<int>(schedule.colorOffsets.size()) - 1;
    for (int color = 0; color < numColors; ++color) {
#pragma omp for schedule(dynamic, 1)
      for (int k = schedule.colorOffsets[toIndex(color)]; k < schedule.colorOffsets[toIndex(color) + 1]; ++k) {
        const int chunk = schedule.coloredChunks[toIndex(k)];
        const int chunkEnd = std::min(schedule.numElements, (chunk + 1) * schedule.chunkSize);
        std::array<ElementMatrix, kElementBatch> local;
        // Elements in the order assemble() visits them, so every entry sums alike.
        for (int first = chunk * schedule.chunkSize; first < chunkEnd; first += kElementBatch) {
          const int count = std::min(kElementBatch, chunkEnd - first);
          try {
            elementBatch(first, count, local.data());
          } catch (...) {
            errors.record(first);
            continue;
          }
          for (int i = 0; i < count; ++i) scatterElement(first + i, local[toIndex(i)], values);
        }
      }
    }
  }
  errors.rethrowIfAny();
}

void MatrixAssembler::assemble(const std::vector<ElementMatrix>& elementMatrices,
                               Eigen::SparseMatrix<double>& matrix) const {
  if (elementMatrices.size() != toIndex(numElements_)) {
    throw Error("MatrixAssembler::assemble: got " + std::to_string(elementMatrices.size()) +
                " element matrices for a mesh of " + std::to_string(numElements_) + " elements");
  }
  assembleWith([&](int e, ElementMatrix& out) { out = elementMatrices[toIndex(e)]; }, matrix);
}

Eigen::VectorXd MatrixAssembler::assembleVector(const ElementVectorFunction& elementVector) const {
  Eigen::VectorXd result = Eigen::VectorXd::Zero(numDofs_);
  double* values = result.data();
  const ColoredChunkSchedule schedule{colorOffsets_, coloredChunks_, chunkSize_, numElements_};
  const auto scatter = [&](int e, const ElementVector& local) {
    for (int a = 0; a < 4; ++a) {
      double* vertexValues = values + (3 * toIndex(elements_(a, e)));
      for (int c = 0; c < 3; ++c) vertexValues[c] += local((3 * a) + c);
    }
  };
  FirstElementError errors;
#pragma omp parallel if (numElements_ >= kMinElementsForThreads)
  forEachElementByColor<ElementVector>(schedule, elementVector, scatter, errors);
  errors.rethrowIfAny();
  return result;
}

namespace {

// Throws ValidationError when element e is degenerate (checkElementVolume).
void checkVolume(int e, double signedVolume, const ElementPositions& x) {
  checkElementVolume(e, signedVolume, longestEdge(x));
}

}  // namespace

Eigen::SparseMatrix<double> linearStiffnessMatrix(const TetMesh& mesh, const MatrixAssembler& assembler) {
  Eigen::SparseMatrix<double> stiffness = assembler.createMatrix();
  assembleLinearStiffness(mesh, assembler, stiffness);
  return stiffness;
}

void assembleLinearStiffness(const TetMesh& mesh, const MatrixAssembler& assembler,
                             Eigen::SparseMatrix<double>& stiffness) {
  if (mesh.numElements() != assembler.numElements() || mesh.numDofs() != assembler.numDofs()) {
    throw Error("assembleLinearStiffness: the assembler was built for another mesh");
  }
  // Lame parameters once per material instead of once per element.
  std::vector<Eigen::Vector2d> lame;
  for (const Material& m : mesh.materials()) lame.push_back(lameParameters(m.youngsModulus, m.poissonRatio));
  assembler.assembleWith(
      [&](int e, ElementMatrix& out) {
        const ElementPositions x = mesh.elementRestPositions(e);
        double signedVolume = 0.0;
        const Eigen::Matrix<double, 3, 4> g = shapeFunctionGradients(x, &signedVolume);
        checkVolume(e, signedVolume, x);
        const Eigen::Vector2d& parameters = lame[toIndex(mesh.elementMaterialIndex(e))];
        const double volume = std::abs(signedVolume);
        detail::linearStiffnessFromGradients(g, parameters[0] * volume, parameters[1] * volume, out);
      },
      stiffness);
}

Eigen::SparseMatrix<double> massMatrix(const TetMesh& mesh, const MatrixAssembler& assembler, MassType type) {
  if (mesh.numElements() != assembler.numElements() || mesh.numDofs() != assembler.numDofs()) {
    throw Error("massMatrix: the assembler was built for another mesh");
  }
  Eigen::SparseMatrix<double> mass = assembler.createMatrix();
  assembler.assembleWith(
      [&](int e, ElementMatrix& out) {
        const ElementPositions x = mesh.elementRestPositions(e);
        double signedVolume = 0.0;
        shapeFunctionGradients(x, &signedVolume);
        checkVolume(e, signedVolume, x);
        const double density = mesh.elementMaterial(e).density;
        out = type == MassType::consistent ? consistentElementMass(signedVolume, density)
                                           : lumpedElementMass(signedVolume, density);
      },
      mass);
  return mass;
}

Eigen::SparseMatrix<double> rayleighDamping(const Eigen::SparseMatrix<double>& mass,
                                            const Eigen::SparseMatrix<double>& stiffness, double alpha, double beta) {
  Eigen::SparseMatrix<double> damping;
  combine({alpha, beta}, {&mass, &stiffness}, damping);
  return damping;
}

namespace {

bool samePattern(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  if (&a == &b) return true;
  if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros()) return false;
  if (!a.isCompressed() || !b.isCompressed()) return false;
  const Index outerBytes = (toIndex(static_cast<int>(a.cols())) + 1) * sizeof(int);
  const Index innerBytes = static_cast<Index>(a.nonZeros()) * sizeof(int);
  return std::memcmp(a.outerIndexPtr(), b.outerIndexPtr(), outerBytes) == 0 &&
         (a.innerIndexPtr() == b.innerIndexPtr() || std::memcmp(a.innerIndexPtr(), b.innerIndexPtr(), innerBytes) == 0);
}

}  // namespace

void combine(const std::vector<double>& coefficients, const std::vector<const Eigen::SparseMatrix<double>*>& matrices,
             Eigen::SparseMatrix<double>& out) {
  if (coefficients.size() != matrices.size() || matrices.empty()) {
    throw Error("combine: need as many coefficients as matrices, at least one (got " +
                std::to_string(coefficients.size()) + " coefficients, " + std::to_string(matrices.size()) +
                " matrices)");
  }
  for (std::size_t i = 0; i < matrices.size(); ++i) {
    if (matrices[i] == nullptr) throw Error("combine: matrix " + std::to_string(i) + " is null");
    if (!matrices[i]->isCompressed()) throw Error("combine: matrix " + std::to_string(i) + " is not compressed");
    if (!samePattern(*matrices[0], *matrices[i])) {
      throw Error("combine: matrix " + std::to_string(i) + " (" + std::to_string(matrices[i]->rows()) + " x " +
                  std::to_string(matrices[i]->cols()) + ", " + std::to_string(matrices[i]->nonZeros()) +
                  " entries) does not have the pattern of matrix 0 (" + std::to_string(matrices[0]->rows()) + " x " +
                  std::to_string(matrices[0]->cols()) + ", " + std::to_string(matrices[0]->nonZeros()) + " entries)");
    }
  }
  const Eigen::SparseMatrix<double>& reference = *matrices[0];
  // out may alias one of the inputs: keep its values until all reads of an entry are done
  // (each entry is read and written by the same iteration, so in-place is safe).
  bool aliased = false;
  for (const auto* m : matrices) aliased = aliased || m == &out;
  if (!aliased && !samePattern(reference, out)) {
    out = reference;  // copies the pattern (values are overwritten below)
  }
  const Eigen::Index nnz = reference.nonZeros();
  const std::size_t count = matrices.size();
  std::vector<const double*> sources(count);
  for (std::size_t i = 0; i < count; ++i) sources[i] = matrices[i]->valuePtr();
  double* target = out.valuePtr();
#pragma omp parallel for schedule(static)
  for (Eigen::Index k = 0; k < nnz; ++k) {
    double sum = coefficients[0] * sources[0][k];
    for (std::size_t i = 1; i < count; ++i) sum += coefficients[i] * sources[i][k];
    target[k] = sum;
  }
}

}  // namespace asyncfem
