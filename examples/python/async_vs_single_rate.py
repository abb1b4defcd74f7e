# SPDX-License-Identifier: BSD-3-Clause
"""Async against single-rate backward Euler on the default beam: the vertical displacement of
a tip vertex over time for async (hL = 1/120 s, tip at hL/8), backward Euler at hL and at
hS = hL/8, plotted with matplotlib (Agg backend, PNG out) with the time each run took.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/async_vs_single_rate.py [--seconds 2] [--output tip.png]
"""
import argparse
import pathlib
import time

# asyncfem first: it sets OMP_WAIT_POLICY=passive before the OpenMP runtime loads, and
# matplotlib loads that runtime too (imported first, idle threads spin: 3-4x slower).
import asyncfem as af  # isort: skip
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def beam_system(mesh, pull_until=0.3):
    """The default scene's system: clamped root, tip pulled down with 40 N until pull_until."""
    assembler = af.MatrixAssembler(mesh)
    tip = mesh.set_vertices("tip")
    pull = np.zeros(mesh.num_dofs)
    pull.reshape(-1, 3)[tip] = np.array([0.0, -40.0, 0.0]) / len(tip)
    return af.DynamicSystem(af.LinearForceModel(af.linear_stiffness_matrix(mesh, assembler)),
                            af.mass_matrix(mesh, assembler, af.MassType.consistent),
                            af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.set_vertices("root")),
                            external_force=lambda t, u, v: pull if t < pull_until - 1e-12 else None)


def run(integrator, seconds, dof, sample_every):
    """Times and the displacement of one DOF, sampled every `sample_every` steps."""
    times, values = [0.0], [0.0]
    start = time.perf_counter()
    steps = round(seconds / integrator.timestep)
    for k in range(steps // sample_every):
        integrator.step(sample_every)
        times.append(integrator.time)
        values.append(integrator.displacement[dof])
    return np.array(times), np.array(values), time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    parser.add_argument("--seconds", type=float, default=2.0, help="simulated time")
    parser.add_argument("--output", default="tip.png")
    args = parser.parse_args()

    mesh = af.read_mesh(MODELS / "beam" / "beam.veg")
    system = beam_system(mesh)
    positions = mesh.rest_positions
    tip_vertex = int(np.argmax(positions[:, 0] - 1e-3 * positions[:, 1]))  # far end, lowest
    dof = 3 * tip_vertex + 1
    large, ratio = 1 / 120, 8
    region = af.AsyncRegion("tip", af.region_vertices(mesh, element_sets=["tip"]), ratio)
    runs = {
        f"async (hL = 1/120 s, tip at hL/{ratio})": run(af.AsyncBackwardEuler(mesh, system, large, [region]),
                                                          args.seconds, dof, 1),
        "backward Euler at hL": run(af.BackwardEuler(system, large), args.seconds, dof, 1),
        f"backward Euler at hL/{ratio}": run(af.BackwardEuler(system, large / ratio), args.seconds, dof, ratio),
    }
    figure, axes = plt.subplots(figsize=(8, 4.5))
    for label, (times, values, seconds) in runs.items():
        axes.plot(times, values, label=f"{label}: {seconds:.2f} s")
        print(f"{label:38s} {seconds:7.2f} s wall, tip y at the end {values[-1]:+.5f} m")
    axes.set_xlabel("time (s)")
    axes.set_ylabel(f"vertical displacement of vertex {tip_vertex} (m)")
    axes.set_title("Cantilever with a stiff, light tip: pulled for 0.3 s, released")
    axes.legend()
    figure.tight_layout()
    figure.savefig(args.output, dpi=100)
    print(f"plot written to {args.output}")


if __name__ == "__main__":
    main()
