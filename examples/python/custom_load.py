# SPDX-License-Identifier: BSD-3-Clause
"""A load written in Python: a sideways gust on the beam's tip whose strength follows a
smooth pulse, plus air drag proportional to the tip's velocity (a state-dependent force).
The integrator calls the function once per step with (time, u, v); frames go to a .vtu
series that ParaView opens (frames.pvd, Warp By Vector with "displacement").

    PYTHONPATH=build/python /usr/bin/python3 examples/python/custom_load.py [--frames 60] [--output gust]
"""
import argparse
import pathlib

import numpy as np

import asyncfem as af

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


class Gust:
    """f(t, u, v): a pulse of peak `peak` newtons along z, centred at `centre` seconds, spread
    over the tip vertices, and drag -c v on them. Called once per step by the integrator."""

    def __init__(self, mesh, vertices, peak=30.0, centre=0.25, width=0.08, drag=2.0):
        self.vertices = vertices
        self.forces = np.zeros(mesh.num_dofs)
        self.peak, self.centre, self.width, self.drag = peak, centre, width, drag
        self.calls = 0

    def __call__(self, t, u, v):
        self.calls += 1
        per_vertex = self.peak * np.exp(-0.5 * ((t - self.centre) / self.width) ** 2) / len(self.vertices)
        tip = self.forces.reshape(-1, 3)
        tip[self.vertices] = -self.drag * v.reshape(-1, 3)[self.vertices] / len(self.vertices)
        tip[self.vertices, 2] += per_vertex
        return self.forces


def main():
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    parser.add_argument("--frames", type=int, default=60, help="frames at 30 per second")
    parser.add_argument("--output", default="gust", help="folder for the .vtu series")
    args = parser.parse_args()

    mesh = af.read_mesh(MODELS / "beam" / "beam.veg")
    assembler = af.MatrixAssembler(mesh)
    gust = Gust(mesh, mesh.set_vertices("tip"))
    system = af.DynamicSystem(af.CorotationalLinearFEM(mesh, assembler),
                              af.mass_matrix(mesh, assembler, af.MassType.consistent),
                              af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.set_vertices("root")),
                              external_force=gust)
    integrator = af.BackwardEuler(system, 1 / 240)
    series = af.VtuSeriesWriter(args.output)
    sideways = []
    for frame in range(args.frames):
        integrator.step(8)
        series.write_frame(frame, integrator.time, mesh, integrator.displacement)
        sideways.append(integrator.displacement.reshape(-1, 3)[:, 2].max())
    peak_frame = int(np.argmax(sideways))
    print(f"{args.frames} frames to {series.collection_path}; the gust was evaluated {gust.calls} times; "
          f"largest sideways displacement {max(sideways):.4f} m at frame {peak_frame}")


if __name__ == "__main__":
    main()
