# SPDX-License-Identifier: BSD-3-Clause
"""No leaks: RSS stays bounded over 1,000 create/destroy cycles of the bound objects,
including Python force models and callbacks held by C++."""
import gc

import numpy as np

import asyncfem as af
from conftest import small_box


def rss_bytes():
    with open("/proc/self/statm") as statm:
        import os
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


class PythonModel(af.ForceModel):
    def __init__(self, stiffness):
        af.ForceModel.__init__(self)
        self.stiffness = stiffness

    def num_dofs(self):
        return self.stiffness.shape[0]

    def is_linear(self):
        return True

    def create_stiffness_matrix(self):
        return self.stiffness

    def internal_forces(self, u):
        return self.stiffness @ u

    def tangent_stiffness(self, u):
        return self.stiffness


def cycle(k, tmp_path):
    mesh = small_box(cells=3)
    assembler = af.MatrixAssembler(mesh)
    stiffness = af.linear_stiffness_matrix(mesh, assembler)
    mass = af.mass_matrix(mesh, assembler)
    free = af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.vertex_set("xmin"))
    pull = np.full(mesh.num_dofs, -1.0)
    model = PythonModel(stiffness) if k % 2 else af.LinearForceModel(stiffness)
    system = af.DynamicSystem(model, mass, free, external_force=lambda t, u, v: pull)
    integrator = af.BackwardEuler(system, 0.01)
    integrator.step(2)
    view = integrator.displacement
    corotational = af.CorotationalLinearFEM(mesh, assembler)
    corotational.forces_and_tangent(view)
    tip = mesh.vertex_set("xmax")
    multirate = af.AsyncBackwardEuler(mesh, system, 0.01, [af.AsyncRegion("tip", tip, 2)])
    multirate.set_substep_observer(lambda *args: None)
    multirate.step()
    solver = af.SparseSolver("cholmod")
    solver.compute(free.free_matrix(mass))
    solver.solve(np.ones(free.num_free))
    with af.SimulationWriter(tmp_path / "cycle.afsim", af.SimulationFileHeader(mesh.num_vertices, 0.1)) as writer:
        writer.append_frame(0.1, view)
    try:
        mesh.vertex_set("missing")
    except af.ValidationError:
        pass
    return float(view.sum())


def test_rss_bounded_over_1000_cycles(tmp_path):
    for k in range(100):  # warm-up: allocator pools, pybind11 type caches, imports
        cycle(k, tmp_path)
    gc.collect()
    before = rss_bytes()
    for k in range(1000):
        cycle(k, tmp_path)
    gc.collect()
    growth = rss_bytes() - before
    # One cycle allocates about 0.3 MB (K, M, the factors, async blocks); leaking even one
    # matrix per cycle would add tens of MB over 1,000 cycles. 8 MB leaves room for
    # allocator fragmentation.
    assert growth < 8 * 1024 * 1024, f"RSS grew by {growth / 2**20:.1f} MiB over 1,000 cycles"
