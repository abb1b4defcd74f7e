// SPDX-License-Identifier: BSD-3-Clause
// AsyncOptions::Processes::regionDistribution: fast regions computed by one process each, what the
// others need summed over the processes. The processes here are threads of this test, each
// with its own integrator and its own copy of the system, joined by an in-process sum (the
// MPI version is petscBackend's makePetscRegionDistribution, tested under mpiexec).
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdio>
#include <exception>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

/// An in-process stand-in for MPI_Allreduce over `size` participants, each on its own
/// thread: each deposits its values, and every participant adds the deposits in
/// participant order, so all receive the same sums. The participants take turns between
/// sums (one runs at a time), as separate processes would not share the BLAS and CHOLMOD
/// of one process: two threads calling them at the same moment may round differently.
/// A participant that waits more than a minute throws instead of hanging.
class ThreadGroup {
 public:
  explicit ThreadGroup(int size)
      : size_(size), slots_(static_cast<std::size_t>(size)), turns_(static_cast<std::size_t>(size)) {}

  void sum(int me, double* values, std::size_t count) {
    std::unique_lock<std::mutex>* turn = turns_[static_cast<std::size_t>(me)];  // null outside run()
    if (turn != nullptr) turn->unlock();
    std::vector<double> total(count, 0.0);
    {
      std::unique_lock<std::mutex> lock(mutex_);
      slots_[static_cast<std::size_t>(me)].assign(values, values + count);
      arrive(lock);
      for (const std::vector<double>& slot : slots_) {
        if (slot.size() != count) throw std::runtime_error("ThreadGroup: participants summed different counts");
        for (std::size_t k = 0; k < count; ++k) total[k] += slot[k];
      }
      arrive(lock);  // every participant has read the deposits before the next sum
    }
    if (turn != nullptr) turn->lock();
    std::copy(total.begin(), total.end(), values);
  }

  /// Runs body(me) on size threads, one at a time between sums; rethrows the first
  /// exception after all are joined.
  void run(const std::function<void(int)>& body) {
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(size_));
    std::vector<std::thread> threads;
    for (int me = 0; me < size_; ++me) {
      threads.emplace_back([&, me] {
        std::unique_lock<std::mutex> turn(turn_);
        turns_[static_cast<std::size_t>(me)] = &turn;
        try {
          body(me);
        } catch (...) {
          errors[static_cast<std::size_t>(me)] = std::current_exception();
        }
      });
    }
    for (std::thread& t : threads) t.join();
    for (const std::exception_ptr& error : errors)
      if (error) std::rethrow_exception(error);
  }

 private:
  void arrive(std::unique_lock<std::mutex>& lock) {
    const long long generation = generation_;
    if (++arrived_ == size_) {
      arrived_ = 0;
      ++generation_;
      ready_.notify_all();
    } else if (!ready_.wait_for(lock, std::chrono::minutes(1), [&] { return generation_ != generation; })) {
      throw std::runtime_error("ThreadGroup: a participant never arrived");
    }
  }

  int size_;
  std::vector<std::vector<double>> slots_;
  std::vector<std::unique_lock<std::mutex>*> turns_;
  std::mutex mutex_, turn_;
  std::condition_variable ready_;
  int arrived_ = 0;
  long long generation_ = 0;
};

/// Participant me of group owns the regions i with i % size == me.
AsyncOptions distributedOptions(ThreadGroup& group, int me, int size) {
  AsyncOptions options;
  options.processes.regionDistribution.ownedRegions = [me, size](const std::vector<std::vector<int>>& regionDofs,
                                                                 const std::vector<std::vector<int>>&) {
    std::vector<char> owned(regionDofs.size());
    for (std::size_t i = 0; i < owned.size(); ++i) owned[i] = static_cast<int>(i) % size == me ? 1 : 0;
    return owned;
  };
  options.processes.regionDistribution.sum = [&group, me](double* values, std::size_t count) {
    group.sum(me, values, count);
  };
  return options;
}

/// As distributedOptions, but participant me claims every region when claim, none otherwise.
AsyncOptions claimingAll(ThreadGroup& group, int me, int size, bool claim) {
  AsyncOptions options = distributedOptions(group, me, size);
  options.processes.regionDistribution.ownedRegions = [claim](const std::vector<std::vector<int>>& regionDofs,
                                                              const std::vector<std::vector<int>>&) {
    return std::vector<char>(regionDofs.size(), claim ? 1 : 0);
  };
  return options;
}

struct BarRun {
  Eigen::VectorXd displacement, velocity;
  long long factorizations = 0;
};

/// Two regions that do not touch (the plane x = 0.375 at ratio 8, the stiff tip x >= 0.875
/// at ratio 4) for 5 steps, then the tip alone at ratio 6 for 4 more (a new partition).
BarRun runBar(const test::TestSystem& ts, const AsyncOptions& options) {
  const double hL = 5e-3;
  const std::vector<AsyncRegion> two{{"plane", test::verticesOnPlanes(ts.mesh, {0.375}), 8},
                                     {"tip", test::verticesBeyond(ts.mesh, 0.875), 4}};
  AsyncBackwardEuler integrator(ts.mesh, ts.system, hL, two, options);
  integrator.setState(ts.u0, ts.v0);
  for (int k = 0; k < 5; ++k) integrator.step();
  integrator.setUp(RegionPartition(ts.mesh, ts.system.freeDofs, {{"tip", test::verticesBeyond(ts.mesh, 0.875), 6}}));
  for (int k = 0; k < 4; ++k) integrator.step();
  return {integrator.displacement(), integrator.velocity(), integrator.stats().factorizations};
}

// Two processes, each computing one region, run the one-process run's arithmetic: every sum
// adds the owner's values to zeros and the interface rows are subtracted in the same order,
// so the trajectories are equal bit for bit (linear, corotational with the lagged H^{LL*},
// and the quick set-up's deflated CG); and each process made fewer factorizations than the
// one-process run (it skipped the other region's A^S).
TEST(AsyncRegionDistribution, TwoProcessesFollowTheOneProcessRun) {
  struct Case {
    ForceModelType model;
    bool quickSetUp;
    const char* name;
  };
  // The quick set-up solves L's system by deflated CG on the whole system's factor; its
  // products with H^{LL*} go through the distributed substitutions too.
  for (const Case c :
       {Case{ForceModelType::linear, false, "linear"}, Case{ForceModelType::corotational, false, "corotational"},
        Case{ForceModelType::linear, true, "linear, quick set-up"}}) {
    SCOPED_TRACE(c.name);
    const ProblemSettings settings = test::testSettings(c.model, 0.3, 2e-3);
    AsyncOptions local;
    local.keptFactors.quickSetUp = c.quickSetUp;
    const BarRun reference = runBar(test::makeTestSystem(settings), local);
    ThreadGroup group(2);
    std::vector<BarRun> runs(2);
    group.run([&](int me) {
      const test::TestSystem ts = test::makeTestSystem(settings);  // each process its own force model
      AsyncOptions options = distributedOptions(group, me, 2);
      options.keptFactors.quickSetUp = c.quickSetUp;
      runs[static_cast<std::size_t>(me)] = runBar(ts, options);
    });
    const double scale = reference.displacement.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    for (const BarRun& run : runs) {
      EXPECT_EQ(run.displacement, reference.displacement);
      EXPECT_EQ(run.velocity, reference.velocity);
      EXPECT_LT(run.factorizations, reference.factorizations);
    }
    EXPECT_EQ(runs[0].displacement, runs[1].displacement);
    EXPECT_EQ(runs[0].velocity, runs[1].velocity);
  }
}

// A region whose owner fails (here its A^S is not positive definite: that process's M^{SS}
// is negated and scaled by 1e6, so it outweighs the stiff tip's hS^2 K^{SS}) stops every
// process at the same sum: the owner with its own error, the other with an Error naming
// the region; neither waits for the other.
TEST(AsyncRegionDistribution, AFailingRegionStopsEveryProcess) {
  const test::TestSystem healthy = test::makeTestSystem(0.3, 2e-3);
  const std::vector<AsyncRegion> tip{{"tip", test::verticesBeyond(healthy.mesh, 0.875), 4}};
  ThreadGroup group(2);
  std::vector<std::string> messages(2);
  group.run([&](int me) {
    test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
    if (me == 1) {  // M^{SS} times -1e6, the rest (everything both processes compute) unchanged
      std::vector<char> inTip(static_cast<std::size_t>(ts.system.mass.rows()), 0);
      for (const int v : tip[0].vertices)
        for (int c = 0; c < 3; ++c) inTip[static_cast<std::size_t>(3 * v + c)] = 1;
      for (int column = 0; column < ts.system.mass.outerSize(); ++column)
        for (Eigen::SparseMatrix<double>::InnerIterator it(ts.system.mass, column); it; ++it)
          if (inTip[static_cast<std::size_t>(it.row())] && inTip[static_cast<std::size_t>(column)])
            it.valueRef() *= -1e6;
    }
    const AsyncOptions options = claimingAll(group, me, 2, me == 1);
    try {
      AsyncBackwardEuler integrator(ts.mesh, ts.system, 5e-3, tip, options);
      integrator.step();
    } catch (const Error& error) {
      messages[static_cast<std::size_t>(me)] = error.what();
    }
  });
  EXPECT_NE(messages[0].find("fast region 0 (tip), computed by another process, failed"), std::string::npos)
      << messages[0];
  EXPECT_NE(messages[1].find("not positive definite"), std::string::npos) << messages[1];
}

// A region claimed by both processes (or by none) is an error on every process, naming the
// region; so is an answer for the wrong number of regions (on every process, even when one
// process alone answers wrongly), and a distribution with one of its two members, or with
// the paper's coupling.
TEST(AsyncRegionDistribution, EveryRegionNeedsExactlyOneOwner) {
  const test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
  const std::vector<AsyncRegion> tip{{"tip", test::verticesBeyond(ts.mesh, 0.875), 4}};
  ThreadGroup group(2);
  std::vector<std::string> messages(2);
  group.run([&](int me) {
    const AsyncOptions options = claimingAll(group, me, 2, true);
    try {
      AsyncBackwardEuler integrator(ts.mesh, ts.system, 5e-3, tip, options);
    } catch (const ValidationError& error) {
      messages[static_cast<std::size_t>(me)] = error.what();
    }
  });
  for (const std::string& message : messages) {
    EXPECT_NE(message.find("region 0 (tip) has 2 owners"), std::string::npos) << message;
  }
  // Only process 1 answers for the wrong number of regions: it reports that, process 0 stops
  // at the same sum instead of waiting for it.
  ThreadGroup pair(2);
  std::vector<std::string> stops(2);
  pair.run([&](int me) {
    AsyncOptions options = claimingAll(pair, me, 2, me == 0);
    if (me == 1) {
      options.processes.regionDistribution.ownedRegions = [](const std::vector<std::vector<int>>&,
                                                             const std::vector<std::vector<int>>&) {
        return std::vector<char>(3, 0);
      };
    }
    try {
      AsyncBackwardEuler integrator(ts.mesh, ts.system, 5e-3, tip, options);
    } catch (const Error& error) {
      stops[static_cast<std::size_t>(me)] = error.what();
    }
  });
  EXPECT_NE(stops[0].find("computed by another process, failed"), std::string::npos) << stops[0];
  EXPECT_NE(stops[1].find("answered for 3 regions, the partition has 1"), std::string::npos) << stops[1];
  ThreadGroup alone(1);
  AsyncOptions options = distributedOptions(alone, 0, 1);
  options.processes.regionDistribution.ownedRegions =
      [](const std::vector<std::vector<int>>&, const std::vector<std::vector<int>>&) { return std::vector<char>(); };
  try {
    AsyncBackwardEuler integrator(ts.mesh, ts.system, 5e-3, tip, options);
    ADD_FAILURE() << "an answer for no region was accepted";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("answered for 0 regions, the partition has 1"), std::string::npos)
        << error.what();
  }
  options = distributedOptions(alone, 0, 1);
  options.processes.regionDistribution.sum = nullptr;
  EXPECT_THROW(AsyncBackwardEuler(ts.mesh, ts.system, 5e-3, tip, options), ValidationError);
  options = distributedOptions(alone, 0, 1);
  options.coupling = AsyncCoupling::paper;
  EXPECT_THROW(AsyncBackwardEuler(ts.mesh, ts.system, 5e-3, tip, options), ValidationError);
}

}  // namespace
}  // namespace asyncfem
