// SPDX-License-Identifier: BSD-3-Clause
#include "detail/keptFactor.hpp"

#include <asyncfem/core/error.hpp>
#include <cmath>
#include <string>
#include <vector>

namespace asyncfem::detail {

namespace {

// Layout (doubles; counts and flags are whole numbers, exact in a double):
//
//   [0]  layout version (1)
//   [1]  rule.hasFactor          [2] rule.refactorPending
//   [3]  rule.firstStaleIterations  [4] rule.cycleCost  [5] rule.cycleSolves
//   [6]  matrix kind (0 none, 1 step, 2 newton)  [7] timestep  [8] dampingAtIterate
//   [9]  length of previousSolution (0 or the free DOFs)
//   [10] length of stepStart (0 or 3n)  [11] length of iterate (0 or 3n)
//   [12] contact entries c
//   then previousSolution, stepStart, iterate, and per contact entry: its vertex, the
//   stiffness block and the damping block (9 values each, column-major).
constexpr double layoutVersion = 1.0;
constexpr Eigen::Index headerSize = 13;
constexpr Eigen::Index contactEntrySize = 19;

void append(std::vector<double>& out, const Eigen::VectorXd& values) {
  out.insert(out.end(), values.data(), values.data() + values.size());
}

void append(std::vector<double>& out, const Eigen::Matrix3d& block) {
  out.insert(out.end(), block.data(), block.data() + 9);
}

// Reads the state's fields in order, checking each against what it may be.
class Reader {
 public:
  Reader(const Eigen::VectorXd& values, std::string who) : values_(values), who_(std::move(who)) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw Error(who_ + ": setInternalState: not a kept-factor state of this integrator (" + what + ")");
  }
  double number() {
    if (next_ >= values_.size()) fail("too short");
    const double value = values_[next_++];
    if (!std::isfinite(value)) fail("non-finite value");
    return value;
  }
  long long whole(double limit, const char* what) {
    const double value = number();
    if (value != std::floor(value) || value < 0.0 || value > limit) fail(what);
    return static_cast<long long>(value);
  }
  bool flag(const char* what) { return whole(1.0, what) == 1; }
  Eigen::VectorXd vector(Eigen::Index size) {
    if (size > values_.size() - next_) fail("too short");
    Eigen::VectorXd out = values_.segment(next_, size);
    next_ += size;
    if (!out.allFinite()) fail("non-finite value");
    return out;
  }
  Eigen::Matrix3d block() {
    const Eigen::VectorXd entries = vector(9);
    return Eigen::Map<const Eigen::Matrix3d>(entries.data());
  }
  bool atEnd() const { return next_ == values_.size(); }

 private:
  const Eigen::VectorXd& values_;
  std::string who_;
  Eigen::Index next_ = 0;
};

}  // namespace

Eigen::VectorXd encodeKeptFactorState(const KeptFactorState& state) {
  const KeptMatrix& matrix = state.matrix;
  std::vector<double> out{layoutVersion,
                          state.rule.hasFactor ? 1.0 : 0.0,
                          state.rule.refactorPending ? 1.0 : 0.0,
                          static_cast<double>(state.rule.firstStaleIterations),
                          state.rule.cycleCost,
                          static_cast<double>(state.rule.cycleSolves),
                          static_cast<double>(static_cast<int>(matrix.kind)),
                          matrix.timestep,
                          matrix.dampingAtIterate ? 1.0 : 0.0,
                          static_cast<double>(state.previousSolution.size()),
                          static_cast<double>(matrix.stepStart.size()),
                          static_cast<double>(matrix.iterate.size()),
                          static_cast<double>(matrix.contact.vertices.size())};
  append(out, state.previousSolution);
  append(out, matrix.stepStart);
  append(out, matrix.iterate);
  for (std::size_t k = 0; k < matrix.contact.vertices.size(); ++k) {
    out.push_back(static_cast<double>(matrix.contact.vertices[k]));
    append(out, matrix.contact.stiffness[k]);
    append(out, matrix.contact.damping[k]);
  }
  return Eigen::Map<const Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
}

KeptFactorState decodeKeptFactorState(const Eigen::VectorXd& encoded, const KeptFactorShape& shape,
                                      const std::string& who) {
  Reader in(encoded, who);
  if (encoded.size() < headerSize) in.fail("too short");
  if (in.number() != layoutVersion) in.fail("unknown layout version");
  KeptFactorState state;
  constexpr double countLimit = 9.0e15;  // below 2^53: whole numbers stay exact
  state.rule.hasFactor = in.flag("hasFactor");
  state.rule.refactorPending = in.flag("refactorPending");
  state.rule.firstStaleIterations = static_cast<int>(in.whole(1e9, "firstStaleIterations"));
  state.rule.cycleCost = in.number();
  state.rule.cycleSolves = in.whole(countLimit, "cycleSolves");
  KeptMatrix& matrix = state.matrix;
  matrix.kind = static_cast<KeptMatrix::Kind>(in.whole(2.0, "matrix kind"));
  matrix.timestep = in.number();
  matrix.dampingAtIterate = in.flag("dampingAtIterate");
  const auto solutionSize = static_cast<Eigen::Index>(in.whole(countLimit, "solution length"));
  const auto stepStartSize = static_cast<Eigen::Index>(in.whole(countLimit, "stepStart length"));
  const auto iterateSize = static_cast<Eigen::Index>(in.whole(countLimit, "iterate length"));
  const auto contactEntries = static_cast<Eigen::Index>(in.whole(countLimit, "contact entries"));
  const bool needsMatrix = state.rule.hasFactor && !state.rule.refactorPending;
  const bool newton = matrix.kind == KeptMatrix::Kind::newton;
  const bool stepStartWanted =
      !shape.linear && (matrix.kind == KeptMatrix::Kind::step || (newton && !matrix.dampingAtIterate));
  if (state.rule.cycleCost < 0.0 || needsMatrix != (matrix.kind != KeptMatrix::Kind::none) ||
      (needsMatrix && !(matrix.timestep > 0.0)) || (solutionSize != 0 && solutionSize != shape.numFree) ||
      stepStartSize != (stepStartWanted ? shape.numDofs : 0) || iterateSize != (newton ? shape.numDofs : 0) ||
      (newton && shape.linear)) {
    in.fail("counts or sizes that do not fit");
  }
  if (encoded.size() - headerSize - solutionSize - stepStartSize - iterateSize != contactEntries * contactEntrySize) {
    in.fail("size");
  }
  state.previousSolution = in.vector(solutionSize);
  matrix.stepStart = in.vector(stepStartSize);
  matrix.iterate = in.vector(iterateSize);
  for (Eigen::Index k = 0; k < contactEntries; ++k) {
    matrix.contact.vertices.push_back(static_cast<int>(in.whole(static_cast<double>(shape.numDofs / 3 - 1), "vertex")));
    matrix.contact.stiffness.push_back(in.block());
    matrix.contact.damping.push_back(in.block());
  }
  if (!in.atEnd()) in.fail("size");
  return state;
}

}  // namespace asyncfem::detail
