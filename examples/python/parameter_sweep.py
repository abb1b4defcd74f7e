# SPDX-License-Identifier: BSD-3-Clause
"""A parameter sweep rendered as a contact sheet: the beam's body stiffness E takes a few
values (one row each), every row shows the beam at a few times after the pull (columns),
rendered off-screen into NumPy arrays and tiled into one PNG. Needs a build with rendering.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/parameter_sweep.py [--small] [--output sweep.png]
"""
import argparse
import sys

import numpy as np

import asyncfem as af


def simulate(youngs_modulus, cells, times, step):
    """Displacements of a generated beam with body stiffness E at the given times."""
    spec = af.BeamSpec()
    spec.cells_along_length = cells
    spec.body = af.Material("body", 1000.0, youngs_modulus, 0.45)
    mesh = af.make_beam_mesh(spec)
    assembler = af.MatrixAssembler(mesh)
    tip = mesh.set_vertices("tip")
    pull = np.zeros(mesh.num_dofs)
    pull.reshape(-1, 3)[tip] = np.array([0.0, -40.0, 0.0]) / len(tip)
    system = af.DynamicSystem(af.CorotationalLinearFEM(mesh, assembler),
                              af.mass_matrix(mesh, assembler, af.MassType.consistent),
                              af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.set_vertices("root")),
                              external_force=lambda t, u, v: pull if t < 0.3 - 1e-12 else None)
    integrator = af.BackwardEuler(system, step)
    frames = []
    for target in times:
        integrator.step(round((target - integrator.time) / step))
        frames.append(integrator.displacement.copy())
    return mesh, frames


def main():
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    parser.add_argument("--small", action="store_true", help="coarse meshes, small images (for the tests)")
    parser.add_argument("--output", default="sweep.png")
    args = parser.parse_args()
    if not af.has_render:
        print("asyncfem was built without rendering (ASYNCFEM_WITH_RENDER=OFF)", file=sys.stderr)
        return 2

    stiffnesses = [2.5e5, 1e6, 4e6] if args.small else [2.5e5, 5e5, 1e6, 2e6, 4e6]
    times = [0.1, 0.3, 0.5] if args.small else [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
    cells, width, height = (8, 96, 72) if args.small else (20, 240, 180)
    renderer = af.OffscreenRenderer(width, height, supersampling=1 if args.small else 2)
    style = af.RenderStyle()
    # One camera for every tile, fitted to the rest shape grown by the largest swing.
    camera = None
    rows = []
    for youngs_modulus in stiffnesses:
        mesh, frames = simulate(youngs_modulus, cells, times, 1 / 240)
        if camera is None:
            box = af.bounding_box(mesh)
            box.min, box.max = box.min - [0.0, 0.2, 0.0], box.max + [0.0, 0.1, 0.0]
            camera = af.fit_camera(box, width / height, view_direction=[0.0, 0.15, 1.0])
        tint = np.tile([0.62, 0.68, 0.78], (mesh.num_vertices, 1))
        tint[mesh.set_vertices("tip")] = [0.95, 0.55, 0.2]
        tiles = [renderer.render_mesh(mesh, u, camera=camera, style=style, colors=tint) for u in frames]
        rows.append(np.concatenate(tiles, axis=1))
        print(f"E = {youngs_modulus:8.3g} Pa: tip sag at t = {times[1]} s is "
              f"{-frames[1].reshape(-1, 3)[mesh.set_vertices('tip'), 1].mean():.4f} m")
    sheet = np.concatenate(rows, axis=0)
    af.write_png(args.output, sheet)
    print(f"contact sheet {sheet.shape[1]} x {sheet.shape[0]} ({len(stiffnesses)} stiffnesses x {len(times)} times) "
          f"written to {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
