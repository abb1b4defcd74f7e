# SPDX-License-Identifier: BSD-3-Clause
"""The default scene (models/beam/beam.json) composed in Python: a cantilever with a stiff,
light tip, pulled down for 0.3 s and released, stepped asynchronously (the tip at 8 substeps
per large step), frames written to an .afsim file that frameRenderer and afsimTool read.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/default_scene.py [--frames 120] [--output beam.afsim]
"""
import argparse
import pathlib

import numpy as np

import asyncfem as af

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
parser = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
parser.add_argument("--frames", type=int, default=120, help="frames at 30 per second")
parser.add_argument("--output", default="beam.afsim")
args = parser.parse_args()

# The scene itself: about ten lines.
mesh = af.read_mesh(MODELS / "beam" / "beam.veg")
assembler = af.MatrixAssembler(mesh)
pull = np.zeros(mesh.num_dofs)
pull.reshape(-1, 3)[mesh.set_vertices("tip")] = np.array([0.0, -40.0, 0.0]) / len(mesh.set_vertices("tip"))
system = af.DynamicSystem(af.LinearForceModel(af.linear_stiffness_matrix(mesh, assembler)),
                          af.mass_matrix(mesh, assembler, af.MassType.consistent),
                          af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.set_vertices("root")),
                          external_force=lambda t, u, v: pull if t < 0.3 - 1e-12 else None)
tip = af.AsyncRegion("tip", af.region_vertices(mesh, element_sets=["tip"]), ratio=8)
integrator = af.AsyncBackwardEuler(mesh, system, 1 / 120, [tip])
with af.SimulationWriter(args.output, af.SimulationFileHeader(mesh.num_vertices, 1 / 30, 1 / 120)) as writer:
    for frame in range(args.frames):
        integrator.step(4)  # 4 large steps of 1/120 s per frame
        writer.append_frame(integrator.time, integrator.displacement)

lowest = integrator.displacement.reshape(-1, 3)[:, 1].min()
print(f"{args.frames} frames to {args.output}; t = {integrator.time:.3f} s, lowest vertex at {lowest:+.4f} m; "
      f"{integrator.stats.steps} large steps, {integrator.stats.solve_seconds:.2f} s in solves")
