// SPDX-License-Identifier: BSD-3-Clause
// Regions owned by one process (AsyncOptions::Processes::regionDistribution): each region computed by
// its owner and what the others need of it summed over the processes.
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <string>

#include "detail/multirateSupport.hpp"
#include "detail/parallelTasks.hpp"
#include "twoLevelStepSolver.hpp"

namespace asyncfem {

using detail::TwoLevelStepSolver;

using detail::FastRegion;

// task(i) for every region this process owns (all of them when not distributed).
void TwoLevelStepSolver::runOwnedTasks(int threads, const std::function<void(int)>& task) {
  Impl& d = *impl_;
  if (!distributed()) {
    detail::parallelTasks(partition_.numRegions(), threads, task);
    return;
  }
  std::vector<std::exception_ptr> failures(d.regions.size());
  detail::parallelTasks(partition_.numRegions(), threads, [&](int i) {
    if (!d.regions[static_cast<std::size_t>(i)].owned) return;
    try {
      task(i);
    } catch (...) {
      failures[static_cast<std::size_t>(i)] = std::current_exception();
    }
  });
  for (std::size_t i = 0; i < failures.size(); ++i) {
    if (failures[i] && !heldFailure_) {
      heldFailure_ = failures[i];
      heldFailureRegion_ = static_cast<int>(i);
    }
  }
}

// Inside a catch block: holds the exception in flight (region: -1 when not known).
void TwoLevelStepSolver::holdFailure(int region) {
  if (heldFailure_) return;
  heldFailure_ = std::current_exception();
  heldFailureRegion_ = region;
}

// values summed over the processes, with two more entries that count the processes
// holding a failure and add up their failing regions (+1): every process then throws,
// the failing one its own exception, the others an Error naming the region.
void TwoLevelStepSolver::sumOverProcesses(std::vector<double>& values) {
  values.push_back(heldFailure_ ? 1.0 : 0.0);
  values.push_back(heldFailure_ ? heldFailureRegion_ + 1.0 : 0.0);
  options_.processes.regionDistribution.sum(values.data(), values.size());
  const double failed = values[values.size() - 2], region = values.back() - 1.0;
  values.resize(values.size() - 2);
  if (failed == 0.0) return;
  if (heldFailure_) {
    const std::exception_ptr failure = heldFailure_;
    heldFailure_ = nullptr;
    std::rethrow_exception(failure);
  }
  std::string which = "a fast region";
  if (failed == 1.0 && region >= 0.0 && region < partition_.numRegions()) {
    const int i = static_cast<int>(region);
    which = "fast region " + std::to_string(i) + " (" + partition_.region(i).name + ")";
  }
  throw Error("async integrator: " + which +
              ", computed by another process, failed in this step (that process reports why); every process stops "
              "here");
}

void TwoLevelStepSolver::assignRegionOwners() {
  Impl& d = *impl_;
  const int numRegions = partition_.numRegions();
  std::vector<std::vector<int>> regionDofs, interfaceDofs;
  for (int i = 0; i < numRegions; ++i) {
    regionDofs.push_back(partition_.regionDofs(i));
    interfaceDofs.push_back(partition_.interfaceDofs(i));
  }
  // A bad answer on one process must still reach the sum, or the others would wait there.
  std::vector<char> owned;
  std::vector<double> owners(static_cast<std::size_t>(numRegions), 0.0);
  try {
    owned = options_.processes.regionDistribution.ownedRegions(regionDofs, interfaceDofs);
    if (owned.size() != static_cast<std::size_t>(numRegions)) {
      throw ValidationError("async integrator: regionDistribution.ownedRegions answered for " +
                            std::to_string(owned.size()) + " regions, the partition has " + std::to_string(numRegions));
    }
    std::copy(owned.begin(), owned.end(), owners.begin());
  } catch (...) {
    holdFailure(-1);
  }
  sumOverProcesses(owners);
  for (int i = 0; i < numRegions; ++i) {
    const double count = owners[static_cast<std::size_t>(i)];
    if (count != 1.0) {
      throw ValidationError("async integrator: region " + std::to_string(i) + " (" + partition_.region(i).name +
                            ") has " + std::to_string(static_cast<int>(count)) +
                            " owners over the processes (regionDistribution.ownedRegions must give it exactly one)");
    }
    d.regions[static_cast<std::size_t>(i)].owned = owned[static_cast<std::size_t>(i)] != 0;
  }
}

// Each region's substitution flops, from its owner's factor (the rent-or-buy prices).
void TwoLevelStepSolver::priceSubstitutions() {
  Impl& d = *impl_;
  std::vector<double> flops(d.regions.size(), 0.0);
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    const FastRegion& rb = d.regions[i];
    if (rb.owned) flops[i] = rb.ratio * (rb.solver->stats().solveFlopsPerRhs + 2.0 * double(rb.G.nonZeros()));
  }
  if (distributed()) sumOverProcesses(flops);
  for (std::size_t i = 0; i < d.regions.size(); ++i) d.regions[i].substitutionFlops = flops[i];
}

// Every C_i from its owner (the others hold zeros).
void TwoLevelStepSolver::shareCorrections() {
  Impl& d = *impl_;
  std::vector<double> all;
  for (const FastRegion& rb : d.regions)
    all.insert(all.end(), rb.correction.data(), rb.correction.data() + rb.correction.size());
  sumOverProcesses(all);
  std::size_t at = 0;
  for (FastRegion& rb : d.regions) {
    std::copy_n(all.data() + at, rb.correction.size(), rb.correction.data());
    at += static_cast<std::size_t>(rb.correction.size());
  }
}

// target -= the interface rows of every region's last substitution (interfaceRow) at its
// interface positions; distributed, from the owners' rows summed over the processes (only
// the sum of |I_i| values travels, not vectors of L's size).
void TwoLevelStepSolver::subtractOwnedInterfaceRows(Eigen::VectorXd& target) {
  Impl& d = *impl_;
  const int numRegions = partition_.numRegions();
  if (!distributed()) {
    for (int i = 0; i < numRegions; ++i) {
      const FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
      const std::vector<int>& pos = partition_.interfacePositions(i);
      for (std::size_t k = 0; k < pos.size(); ++k) target[pos[k]] -= rb.interfaceRow[static_cast<Eigen::Index>(k)];
    }
    return;
  }
  // Every region's rows, concatenated in region order (sizes |I_i| known to every process):
  // the owner fills its segment, the sum hands it to all, and the subtraction below runs in
  // the order of the one-process path.
  d.interfaceSum.clear();
  for (int i = 0; i < numRegions; ++i) {
    const FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::size_t size = partition_.interfacePositions(i).size();
    if (rb.owned) {
      d.interfaceSum.insert(d.interfaceSum.end(), rb.interfaceRow.data(), rb.interfaceRow.data() + size);
    } else {
      d.interfaceSum.insert(d.interfaceSum.end(), size, 0.0);
    }
  }
  sumOverProcesses(d.interfaceSum);
  std::size_t at = 0;
  for (int i = 0; i < numRegions; ++i) {
    const std::vector<int>& pos = partition_.interfacePositions(i);
    for (std::size_t k = 0; k < pos.size(); ++k) target[pos[k]] -= d.interfaceSum[at + k];
    at += pos.size();
  }
}

// X_m and sum_r X_r of every region from its owner, for the new state.
void TwoLevelStepSolver::shareRecoveries() {
  Impl& d = *impl_;
  std::vector<double> all;
  for (FastRegion& rb : d.regions) {
    const auto sizeS = static_cast<Eigen::Index>(rb.systemMatrix.rows());
    if (!rb.owned) {
      rb.xLast.setZero(sizeS);
      rb.xSum.setZero(sizeS);
    } else if (rb.substituted) {
      rb.xLast = rb.x.col(rb.ratio - 1);
      rb.xSum = rb.x.rowwise().sum();
    }
    all.insert(all.end(), rb.xLast.data(), rb.xLast.data() + sizeS);
    all.insert(all.end(), rb.xSum.data(), rb.xSum.data() + sizeS);
  }
  sumOverProcesses(all);
  std::size_t at = 0;
  for (FastRegion& rb : d.regions) {
    const auto sizeS = static_cast<std::size_t>(rb.systemMatrix.rows());
    std::copy_n(all.data() + at, sizeS, rb.xLast.data());
    std::copy_n(all.data() + at + sizeS, sizeS, rb.xSum.data());
    at += 2 * sizeS;
    if (!rb.owned) rb.substituted = false;
  }
}

}  // namespace asyncfem
