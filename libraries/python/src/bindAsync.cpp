// SPDX-License-Identifier: BSD-3-Clause
// libraries/asyncIntegrator: fast regions, their partition, options and the asynchronous
// implicit backward Euler integrator.

#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/asyncIntegrator/stepSolver.hpp>
#include <integrators.hpp>
#include <limits>

namespace asyncfem::python {

namespace {

SubstepObserver observerFromPython(const py::object& callable) {
  if (callable.is_none()) return {};
  if (!PyCallable_Check(callable.ptr())) {
    throw py::value_error("observer: expected a callable f(region, substep, time, u_region, v_region)");
  }
  auto function = std::make_shared<PythonReference>(callable);
  return [function](int region, int substep, double time, const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
    py::gil_scoped_acquire gil;
    function->get()(region, substep, time, Eigen::VectorXd(u), Eigen::VectorXd(v));
  };
}

// The asynchronous integrator's regions, their vertex selection and the partition.
void bindRegions(py::module_& module) {
  py::class_<AsyncRegion>(module, "AsyncRegion", "A fast region S_i: vertices stepped at hL / ratio")
      .def(py::init([](std::string name, const py::handle& vertices, int ratio) {
             return AsyncRegion{std::move(name), indexListArgument(vertices, "vertices"), ratio};
           }),
           py::arg("name"), py::arg("vertices"), py::arg("ratio"))
      .def_readwrite("name", &AsyncRegion::name)
      .def_property(
          "vertices", [](const AsyncRegion& region) { return intArray(region.vertices); },
          [](AsyncRegion& region, const py::handle& vertices) {
            region.vertices = indexListArgument(vertices, "vertices");
          })
      .def_readwrite("ratio", &AsyncRegion::ratio);

  module.def(
      "region_vertices",
      [](const TetMesh& mesh, std::vector<std::string> vertexSets, std::vector<std::string> elementSets,
         const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& boxes, const py::handle& vertices) {
        RegionSelector selector;
        selector.vertexSets = std::move(vertexSets);
        selector.elementSets = std::move(elementSets);
        for (const auto& [min, max] : boxes) {
          selector.boxMin.push_back(min);
          selector.boxMax.push_back(max);
        }
        selector.vertices = indexListArgument(vertices, "vertices");
        return intArray(regionVertices(mesh, selector));
      },
      py::arg("mesh"), py::arg("vertex_sets") = std::vector<std::string>{},
      py::arg("element_sets") = std::vector<std::string>{},
      py::arg("boxes") = std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>{},
      py::arg("vertices") = std::vector<int>{},
      "sorted union of the vertex sets, the vertices of the element sets, the vertices inside the (min, max) "
      "boxes and the ids");

  py::class_<RegionPartition>(module, "RegionPartition", "Free DOFs split into fast regions S_i and the rest L")
      .def(py::init([](const TetMesh& mesh, const FreeDofs& freeDofs, std::vector<AsyncRegion> regions) {
             return RegionPartition(mesh, freeDofs, std::move(regions));
           }),
           py::arg("mesh"), py::arg("free_dofs"), py::arg("regions"))
      .def_property_readonly("num_regions", &RegionPartition::numRegions)
      .def(
          "region",
          [](const RegionPartition& partition, int i) {
            checkIndex(i, partition.numRegions(), "region");
            return partition.region(i);
          },
          py::arg("index"), "the AsyncRegion i")
      .def(
          "region_dofs",
          [](const RegionPartition& partition, int i) {
            checkIndex(i, partition.numRegions(), "region");
            return intArray(partition.regionDofs(i));
          },
          py::arg("index"), "the free DOFs of region S_i (full numbering)")
      .def(
          "interface_dofs",
          [](const RegionPartition& partition, int i) {
            checkIndex(i, partition.numRegions(), "region");
            return intArray(partition.interfaceDofs(i));
          },
          py::arg("index"), "the interface DOFs I_i of region i: DOFs of L in elements touching S_i")
      .def_property_readonly("large_dofs", [](const RegionPartition& p) { return intArray(p.largeDofs()); })
      .def_property_readonly("interface_elements",
                             [](const RegionPartition& p) { return intArray(p.interfaceElements()); })
      .def_property_readonly(
          "vertex_region", [](const RegionPartition& p) { return intArray(p.vertexRegion()); },
          "region of every vertex: i for S_i, -1 for L")
      .def_property_readonly("touching", &RegionPartition::touching,
                             "whether an element joins two fast regions (then the hierarchy solve runs)")
      .def_property_readonly(
          "levels", [](const RegionPartition& p) { return intArray(p.levels()); },
          "the distinct steps per large step, ascending (1 first when L has a vertex)");
}

// The asynchronous integrator's solver options and run-time region policies.
void bindAsyncOptions(py::module_& module) {
  py::enum_<SchurMode>(module, "SchurMode",
                       "How the Schur complement of the interface is formed: low-rank update, LU or symmetric")
      .value("low_rank", SchurMode::lowRank)
      .value("lu", SchurMode::lu)
      .value("symmetric", SchurMode::symmetric);
  py::enum_<AsyncSolveMethod>(module, "AsyncSolveMethod",
                              "structured (block elimination, the default), naive (one big solve, for reference) or "
                              "hierarchy (the time-local step system, what touching or nested regions run)")
      .value("structured", AsyncSolveMethod::structured)
      .value("hierarchy", AsyncSolveMethod::hierarchy)
      .value("naive", AsyncSolveMethod::naive);
  py::enum_<NestedSolve>(module, "NestedSolve",
                         "The hierarchy solve: level by level where the ratios form a chain (automatic), or one LU")
      .value("automatic", NestedSolve::automatic)
      .value("structured", NestedSolve::structured)
      .value("lu", NestedSolve::lu);
  py::enum_<AsyncStepSolver>(module, "AsyncStepSolver", "The step solver an AsyncBackwardEuler partition runs")
      .value("structured_schur", AsyncStepSolver::structuredSchur)
      .value("naive_lu", AsyncStepSolver::naiveLU)
      .value("hierarchy", AsyncStepSolver::hierarchy);
  py::enum_<RecoveryMode>(module, "RecoveryMode",
                          "How the fast regions' states are recovered after the interface solve")
      .value("automatic", RecoveryMode::automatic)
      .value("substitution", RecoveryMode::substitution)
      .value("dense_z", RecoveryMode::denseZ);
  py::enum_<ZSolve>(module, "ZSolve",
                    "How a set-up computes each region's Z and Schur correction: automatic (by flop price), "
                    "substitution (m |I| solves) or modes (one dense eigendecomposition of the region)")
      .value("automatic", ZSolve::automatic)
      .value("substitution", ZSolve::substitution)
      .value("modes", ZSolve::modes);
  py::enum_<AsyncCoupling>(module, "AsyncCoupling",
                           "stable (energy never grows, the default) or paper (the publication's coupling)")
      .value("stable", AsyncCoupling::stable)
      .value("paper", AsyncCoupling::paper);
  py::class_<AsyncOptions>(
      module, "AsyncOptions",
      "Solver options of AsyncBackwardEuler: coupling, Schur mode, method, recovery, region solver")
      .def(py::init([](AsyncCoupling coupling, SchurMode schur, AsyncSolveMethod method, RecoveryMode recovery,
                       SolverKind regionSolver, bool prediction) {
             AsyncOptions options;
             options.coupling = coupling;
             options.schur = schur;
             options.method = method;
             options.recovery = recovery;
             options.regionSolver = regionSolver;
             options.contact.substepStatePrediction = prediction;
             return options;
           }),
           py::arg("coupling") = AsyncCoupling::stable, py::arg("schur") = SchurMode::lowRank,
           py::arg("method") = AsyncSolveMethod::structured, py::arg("recovery") = RecoveryMode::automatic,
           py::arg("region_solver") = SolverKind::cholmod, py::arg("substep_state_prediction") = false)
      .def_readwrite("coupling", &AsyncOptions::coupling)
      .def_readwrite("schur", &AsyncOptions::schur)
      .def_readwrite("method", &AsyncOptions::method)
      .def_readwrite("recovery", &AsyncOptions::recovery)
      .def_readwrite("z_solve", &AsyncOptions::zSolve,
                     "ZSolve: Z by substitution or from the regions' modes (scene key zSolve)")
      .def_readwrite("nested_solve", &AsyncOptions::nestedSolve,
                     "how the hierarchy solve solves (regions that touch or nest, or method hierarchy)")
      .def_readwrite("region_solver", &AsyncOptions::regionSolver)
      .def_readwrite("dense_region_dofs", &AsyncOptions::denseRegionDofs)
      .def_property(
          "substep_state_prediction", [](const AsyncOptions& o) { return o.contact.substepStatePrediction; },
          [](AsyncOptions& o, decltype(AsyncOptions::Contact::substepStatePrediction) value) {
            o.contact.substepStatePrediction = value;
          })
      .def_property(
          "contact_tolerance", [](const AsyncOptions& o) { return o.contact.tolerance; },
          [](AsyncOptions& o, decltype(AsyncOptions::Contact::tolerance) value) { o.contact.tolerance = value; })
      .def_property(
          "contact_iterations", [](const AsyncOptions& o) { return o.contact.iterations; },
          [](AsyncOptions& o, decltype(AsyncOptions::Contact::iterations) value) { o.contact.iterations = value; })
      .def_property(
          "certify_contact_free", [](const AsyncOptions& o) { return o.contact.certifyContactFree; },
          [](AsyncOptions& o, decltype(AsyncOptions::Contact::certifyContactFree) value) {
            o.contact.certifyContactFree = value;
          });

  py::class_<ScheduledRegion>(module, "ScheduledRegion",
                              "A fast region of the schedule policy: vertices at ratio from start to end (s)")
      .def(py::init([](std::string name, const py::handle& vertices, int ratio, double start, double end) {
             return ScheduledRegion{std::move(name), start, end, indexListArgument(vertices, "vertices"), ratio};
           }),
           py::arg("name"), py::arg("vertices"), py::arg("ratio"), py::arg("start") = 0.0,
           py::arg("end") = std::numeric_limits<double>::infinity())
      .def_readwrite("name", &ScheduledRegion::name)
      .def_readwrite("start", &ScheduledRegion::start)
      .def_readwrite("end", &ScheduledRegion::end)
      .def_readwrite("ratio", &ScheduledRegion::ratio)
      .def_property_readonly("vertices", [](const ScheduledRegion& r) { return intArray(r.vertices); });
  py::class_<RunTimeRegionOptions>(module, "RunTimeRegionOptions",
                                   "Policies of run-time regions (docs/asynchronous-integrator.md, Run-time regions)")
      .def(py::init<>())
      .def_readwrite("contact", &RunTimeRegionOptions::contact, "follow contact (needs obstacles in the system)")
      .def_readwrite("contact_ratio", &RunTimeRegionOptions::contactRatio)
      .def_readwrite("contact_margin", &RunTimeRegionOptions::contactMargin, "length")
      .def_readwrite("contact_lookahead", &RunTimeRegionOptions::contactLookahead, "large steps")
      .def_readwrite("contact_rings", &RunTimeRegionOptions::contactRings)
      .def_readwrite("contact_slack", &RunTimeRegionOptions::contactSlack, "extra rings of a new contact region")
      .def_readwrite("indicator", &RunTimeRegionOptions::indicator,
                     "mark where the large step errs: |v_k - 2 v_(k-1) + v_(k-2)| / 2 against the tolerance")
      .def_readwrite("indicator_tolerance", &RunTimeRegionOptions::indicatorTolerance,
                     "fraction of the RMS vertex speed")
      .def_readwrite("indicator_ratio", &RunTimeRegionOptions::indicatorRatio, "largest ratio it asks for")
      .def_readwrite("indicator_rings", &RunTimeRegionOptions::indicatorRings)
      .def_readwrite("schedule", &RunTimeRegionOptions::schedule, "list of ScheduledRegion")
      .def_readwrite("min_dwell", &RunTimeRegionOptions::minDwell, "large steps")
      .def_readwrite("shrink_factor", &RunTimeRegionOptions::shrinkFactor)
      .def_readwrite("cache_size", &RunTimeRegionOptions::cacheSize)
      .def_readwrite("nest", &RunTimeRegionOptions::nest,
                     "touching regions keep their own ratios (the hierarchy solve) instead of being merged");
  py::class_<RepartitionRecord>(module, "RepartitionRecord", "One change of partition at a large-step boundary")
      .def_readonly("time", &RepartitionRecord::time)
      .def_readonly("step", &RepartitionRecord::step)
      .def_readonly("reason", &RepartitionRecord::reason)
      .def_readonly("regions", &RepartitionRecord::regions)
      .def_readonly("fast_vertices", &RepartitionRecord::fastVertices)
      .def_readonly("interface_dofs", &RepartitionRecord::interfaceDofs)
      .def_readonly("moved_vertices", &RepartitionRecord::movedVertices)
      .def_readonly("seconds", &RepartitionRecord::seconds)
      .def_readonly("reused", &RepartitionRecord::reused);
}

// The asynchronous integrator itself.
void bindAsyncIntegrator(py::module_& module) {
  py::class_<AsyncBackwardEuler, Integrator>(
      module, "AsyncBackwardEuler",
      "Asynchronous implicit backward Euler: fast regions take ratio substeps per large step, coupled implicitly")
      .def(py::init([](const TetMesh& mesh, const PythonDynamicSystem& system, double largeTimestep,
                       std::vector<AsyncRegion> regions, AsyncOptions options) {
             DynamicSystem copy = checkedSystem(system);
             py::gil_scoped_release release;
             return std::make_unique<AsyncBackwardEuler>(mesh, std::move(copy), largeTimestep, std::move(regions),
                                                         options);
           }),
           py::arg("mesh"), py::arg("system"), py::arg("large_timestep"), py::arg("regions"),
           py::arg("options") = AsyncOptions{})
      .def_property_readonly("partition", &AsyncBackwardEuler::partition, py::return_value_policy::reference_internal)
      .def_property_readonly("options", &AsyncBackwardEuler::options)
      .def_property_readonly("step_solver", &AsyncBackwardEuler::stepSolver,
                             "the step solver of the partition in use (chosen at each set-up)")
      .def(
          "set_substep_observer",
          [](AsyncBackwardEuler& integrator, const py::object& callable) {
            integrator.setSubstepObserver(observerFromPython(callable));
          },
          py::arg("observer"),
          "callable(region, substep, time, u_region, v_region) after each large step for every substep "
          "(None removes it)")
      .def_property_readonly("schur_asymmetry", &AsyncBackwardEuler::schurAsymmetry)
      .def_property_readonly("z_column_seconds", &AsyncBackwardEuler::zColumnSeconds)
      .def_property_readonly("schur_mode_used", &AsyncBackwardEuler::schurModeUsed)
      .def_property_readonly(
          "z_modal_regions", [](const AsyncBackwardEuler& a) { return a.runStats().zModalRegions; },
          "regions whose Z came from their modes in the last set-up or rebuild (AsyncOptions.z_solve)")
      .def("solve_floor_seconds", &AsyncBackwardEuler::solveFloorSeconds, py::arg("repeats") = 5,
           py::call_guard<py::gil_scoped_release>(),
           "seconds of the solves one large step cannot avoid (median of repeats), the floor a step is compared with")
      .def_property_readonly("factor_non_zeros", &AsyncBackwardEuler::factorNonZeros)
      .def("set_up", &AsyncBackwardEuler::setUp, py::arg("partition"), py::call_guard<py::gil_scoped_release>(),
           "take another partition of the same mesh from the next step on")
      .def("set_run_time_regions", &AsyncBackwardEuler::setRunTimeRegions, py::arg("options"),
           py::call_guard<py::gil_scoped_release>(),
           "choose the regions at every large-step boundary with these policies (RunTimeRegionOptions)")
      .def_property_readonly("repartitions", &AsyncBackwardEuler::repartitions,
                             "every change of partition so far (RepartitionRecord)");
}

// Proposed regions: the options and the proposal (what a scene's "regions": "auto" and
// proposeRegions use).
void bindRegionProposal(py::module_& module) {
  // Proposed regions (what a scene's "regions": "auto" and proposeRegions use).
  module.def("element_max_frequencies", &elementMaxFrequencies, py::arg("mesh"),
             py::call_guard<py::gil_scoped_release>(), "omega_e per element (rad/s), lumped element mass");
  py::class_<RegionProposalOptions>(module, "RegionProposalOptions",
                                    "Settings of propose_regions (the scene's integrator.options.auto)")
      .def(py::init<>())
      .def_readwrite("large_timestep", &RegionProposalOptions::largeTimestep, "hL (s)")
      .def_readwrite("target_omega_h", &RegionProposalOptions::targetOmegaH,
                     "target omega h in every region; <= 0: relative mode")
      .def_readwrite("relative_threshold", &RegionProposalOptions::relativeThreshold,
                     "relative mode: elements above this multiple of the median element frequency become fast")
      .def_readwrite("grow_layers", &RegionProposalOptions::growLayers, "vertex rings added around each region")
      .def_readwrite("max_ratio", &RegionProposalOptions::maxRatio, "largest ratio m proposed")
      .def_readwrite("modal_check", &RegionProposalOptions::modalCheck,
                     "withdraw the regions when no visible mode lives in them (needs stiffness and mass)")
      .def_readwrite("frame_rate", &RegionProposalOptions::frameRate, "frames per second, for the visibility test")
      .def_readwrite("modal_count", &RegionProposalOptions::modalCount, "modes computed first by the modal check")
      .def_readwrite("max_modal_count", &RegionProposalOptions::maxModalCount,
                     "modes computed at most (doubled while the highest is still visible)")
      .def_readwrite("max_regions", &RegionProposalOptions::maxRegions,
                     "regions kept at most; the others move to capped_regions")
      .def_readwrite("cost_check", &RegionProposalOptions::costCheck,
                     "withdraw the regions unless async is estimated cheaper than single-rate")
      .def_readwrite("cost_margin", &RegionProposalOptions::costMargin, "async must cost below this times single-rate")
      .def_readwrite("nonlinear", &RegionProposalOptions::nonlinear,
                     "corotational forces: both sides refactor every step in the cost model");
  py::class_<ProposedRegion>(module, "ProposedRegion", "One region of an RegionProposal with its statistics")
      .def_readonly("region", &ProposedRegion::region, "the AsyncRegion")
      .def_readonly("max_frequency", &ProposedRegion::maxFrequency, "max omega_e over its elements (rad/s)")
      .def_readonly("num_elements", &ProposedRegion::numElements, "elements with every vertex in the region")
      .def_readonly("num_interface_dofs", &ProposedRegion::numInterfaceDofs, "|I| once partitioned")
      .def_readonly("ratio_from_elements", &ProposedRegion::ratioFromElements,
                    "the element criterion's ratio when the modal check raised it, else 0");
  py::class_<RegionProposalCost>(module, "RegionProposalCost",
                                 "The cost check of a proposal: flops per large step of async against single-rate")
      .def_readonly("evaluated", &RegionProposalCost::evaluated, "whether the check ran")
      .def_readonly("free_dofs", &RegionProposalCost::freeDofs, "free DOFs of the problem")
      .def_readonly("large_dofs", &RegionProposalCost::largeDofs, "|L| once the regions are taken out")
      .def_readonly("interface_dofs", &RegionProposalCost::interfaceDofs, "sum of |I_i|")
      .def_readonly("single_rate_substeps", &RegionProposalCost::singleRateSubsteps,
                    "single-rate steps per large step (the largest ratio)")
      .def_readonly("single_rate_flops", &RegionProposalCost::singleRateFlops, "per large step")
      .def_readonly("async_flops", &RegionProposalCost::asyncFlops, "per large step, steady state")
      .def_readonly("async_cheaper", &RegionProposalCost::asyncCheaper, "the verdict of the check")
      .def_readonly("decision", &RegionProposalCost::decision, "one line: the numbers and what was decided")
      .def("ratio", &RegionProposalCost::ratio, "async flops / single-rate flops");
  py::class_<RegionProposal>(module, "RegionProposal",
                             "What propose_regions proposes, withdraws and why (as_dict: the proposeRegions "
                             "--json document)")
      .def_readonly("regions", &RegionProposal::regions, "the kept regions (ProposedRegion)")
      .def_readonly("withdrawn_regions", &RegionProposal::withdrawnRegions,
                    "regions the modal check withdrew (no visible mode lives in them)")
      .def_readonly("cost_withdrawn_regions", &RegionProposal::costWithdrawnRegions, "regions the cost check withdrew")
      .def_readonly("capped_regions", &RegionProposal::cappedRegions, "regions beyond max_regions")
      .def_readonly("large_region_max_frequency", &RegionProposal::largeRegionMaxFrequency,
                    "max omega_e over the elements left in L (rad/s)")
      .def_readonly("large_timestep", &RegionProposal::largeTimestep, "hL (s)")
      .def_readonly("target_omega_h", &RegionProposal::targetOmegaH, "the target omega h in effect")
      .def_readonly("modal_seconds", &RegionProposal::modalSeconds, "time of the modal check's eigensolves")
      .def_property_readonly(
          "has_modal_report", [](const RegionProposal& proposal) { return proposal.modalReport.has_value(); },
          "whether the modal check ran")
      .def_readonly("modal_report", &RegionProposal::modalReport,
                    "the modal check's RegionModeReport of the proposed regions, or None")
      .def_readonly("cost", &RegionProposal::cost, "the cost check (RegionProposalCost)")
      .def("summary", &regionProposalSummary, "one line: the regions kept, or which check withdrew them and why")
      .def("async_regions", &RegionProposal::asyncRegions, "the proposed regions, ready for AsyncBackwardEuler");
}

// propose_regions, the proposal itself.
void bindProposeRegions(py::module_& module) {
  module.def(
      "propose_regions",
      [](const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options,
         const std::optional<Eigen::SparseMatrix<double>>& stiffness,
         const std::optional<Eigen::SparseMatrix<double>>& mass) {
        if (stiffness.has_value() != mass.has_value()) {
          throw py::value_error("stiffness, mass: give both (for the modal check) or neither");
        }
        py::gil_scoped_release release;
        return stiffness ? proposeRegions(mesh, freeDofs, options, *stiffness, *mass)
                         : proposeRegions(mesh, freeDofs, options);
      },
      py::arg("mesh"), py::arg("free_dofs"), py::arg("options") = RegionProposalOptions{},
      py::arg("stiffness") = py::none(), py::arg("mass") = py::none(),
      "fast regions and ratios from the element frequencies (modal check with K and M, full 3n matrices)");
}

}  // namespace

void bindAsync(py::module_& module) {
  bindRegions(module);
  bindAsyncOptions(module);
  bindAsyncIntegrator(module);
  bindRegionProposal(module);
  bindProposeRegions(module);
}

}  // namespace asyncfem::python
