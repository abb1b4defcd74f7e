# SPDX-License-Identifier: BSD-3-Clause
"""Overhead of stepping from Python against stepping in a C++ loop, on the default scene.

The same integrator object advances `--steps` steps three ways, alternated over `--repeats`
rounds (medians reported): `integrator.step(n)`, one call whose loop runs in C++ (what a C++
program does), against `for k in range(n): integrator.step()` from Python, and the Python
loop with the scene's pull written as a Python function (one Python call per step). On a
loaded machine the step times vary by more than the overhead, so the overhead of the
Python call itself (`step(0)`: argument conversion, GIL release and re-acquisition, no step)
is also measured over 20,000 calls and given as a fraction of the C++ step.

    PYTHONPATH=build/python /usr/bin/python3 tests/python/benchmark_stepping.py [--steps 60] [--repeats 5]
"""
import argparse
import os
import pathlib
import statistics
import sys
import time

import asyncfem as af

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
sys.path.insert(0, str(MODELS.parent / "examples" / "python"))
import async_vs_single_rate  # noqa: E402


def beam(mesh, python_pull):
    """The default scene's system with the pull acting at every step (so every step does the
    same work): as a Python function, or none at all for the C++ loop."""
    system = async_vs_single_rate.beam_system(mesh, pull_until=float("inf"))
    if not python_pull:
        system.external_force = None
    return system


def per_step(run, steps):
    start = time.perf_counter()
    run(steps)
    return (time.perf_counter() - start) / steps


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    mesh = af.read_mesh(MODELS / "beam" / "beam.veg")
    tip = af.region_vertices(mesh, element_sets=["tip"])
    cases = {
        "async, hL = 1/120 s, tip m = 8": lambda system: af.AsyncBackwardEuler(mesh, system, 1 / 120,
                                                                                [af.AsyncRegion("tip", tip, 8)]),
        "backward Euler, h = 1/600 s": lambda system: af.BackwardEuler(system, 1 / 600),
    }
    print(f"nproc {os.cpu_count()}, load {open('/proc/loadavg').read().split()[:3]}, "
          f"{args.steps} steps x {args.repeats} rounds, medians")
    print("| integrator | C++ loop ms/step | Python loop ms/step | Python / C++ | Python loop + Python load ms/step "
          "| ratio | call overhead us | overhead / C++ step |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for label, make in cases.items():
        native = make(beam(mesh, python_pull=False))
        with_load = make(beam(mesh, python_pull=True))
        native.step(3)  # warm-up: factorizations and first-step work
        with_load.step(3)
        timings = {"cpp": [], "python": [], "load": []}

        def python_loop(integrator):
            def run(steps):
                for _ in range(steps):
                    integrator.step()
            return run

        for _ in range(args.repeats):
            timings["cpp"].append(per_step(native.step, args.steps))
            timings["python"].append(per_step(python_loop(native), args.steps))
            timings["load"].append(per_step(python_loop(with_load), args.steps))
        cpp, python, load = (1e3 * statistics.median(timings[key]) for key in ("cpp", "python", "load"))
        calls = 20000
        start = time.perf_counter()
        for _ in range(calls):
            native.step(0)
        overhead = 1e6 * (time.perf_counter() - start) / calls
        print(f"| {label} | {cpp:.3f} | {python:.3f} | {python / cpp:.3f} | {load:.3f} | {load / cpp:.3f} "
              f"| {overhead:.2f} | {overhead / (1e3 * cpp):.5f} |")


if __name__ == "__main__":
    main()
