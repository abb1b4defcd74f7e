#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Time per step and peak memory of nonlinear backward Euler as the mesh grows.

Runs build/bin/offlineSimulator on generated bridge-like boxes (aspect 4:1:1, clamped at
x = 0, sagging under gravity, rubber E = 5e5, nu = 0.45) of about 12k, 100k, 375k and 1M
tets, for each force model and linear-solve path asked for, reads the per-phase times
from the run summary and the peak resident memory from the kernel (wait4), and prints a
Markdown table per step plus the growth exponent of each phase, the slope of a
least-squares line through log(time) against log(tets).

  scripts/scale-study.py                       # 12k, 100k; corotational and neo-Hookean
  scripts/scale-study.py --sizes 8,16,25,35    # up to 1M tets (minutes per run, ~10 GiB)
  scripts/scale-study.py --paths default,exact --threads 2

Columns per step are the run's totals over its steps (the factorization column amortizes
the run's factorizations); the exponents are also given per factorization and per
right-hand side (one forward and back substitution), which do not depend on how many
factorizations the kept-factor policy chose at each size.

Sizes are n of a 4n x n x n box (6 tets per cube: 24 n^3 tets). Every configuration runs
--steps steps in one frame, so the default path factors once per run (at the frame start)
and solves the rest with PCG on that factor; the exact path factors at every step.
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile

PHASES = ["forces", "assembly", "factorization", "solve"]
MODELS = {"corotational": {"type": "corotational"}, "neo-hookean": {"type": "neo-hookean"},
          "stvk": {"type": "stvk"}, "mooney-rivlin": {"type": "mooney-rivlin"}}


def scene(cells, model, path, steps):
    return {
        "mesh": {"generator": "box", "size": [4.0, 1.0, 1.0], "cells": [4 * cells, cells, cells],
                 "material": {"name": "rubber", "density": 1000, "youngsModulus": 5e5, "poissonRatio": 0.45}},
        "fixed": {"sets": ["xmin"]},
        "gravity": [0, 0, -9.81],
        "mass": "consistent",
        "forceModel": MODELS[model],
        "integrator": {"name": "backward-euler", "stepsPerFrame": steps,
                       "options": {"reuseFactor": path == "default"}},
        "frames": {"rate": 100.0 / steps, "count": 1},
    }


def parse_summary(text):
    """Per-frame phase times (s), set-up time (s), factorizations, tets, free DOFs."""
    out = {}
    for phase in PHASES + ["per frame", "other"]:
        match = re.search(r"^\s+" + phase + r"\s+([0-9.]+) ms", text, re.M)
        if match is None:
            raise RuntimeError("no '%s' line in the run summary:\n%s" % (phase, text))
        out[phase] = float(match.group(1)) * 1e-3
    match = re.search(r"^\s+setup\s+([0-9.]+) s", text, re.M)
    out["setup"] = float(match.group(1)) if match else float("nan")
    match = re.search(r"\((\d+) factorizations? in the run\)", text)
    out["factorizations"] = int(match.group(1)) if match else 0
    match = re.search(r"solve\s+[0-9.]+ ms\s+\((\d+) right-hand sides?\)", text)
    out["rhs"] = int(match.group(1)) if match else 0
    match = re.search(r"(\d+) vertices, (\d+) elements, (\d+) fixed vertices", text)
    out["vertices"], out["tets"], out["fixed"] = (int(g) for g in match.groups())
    return out


def run_one(simulator, cells, model, path, steps, threads, folder):
    scene_path = os.path.join(folder, "scale-%d-%s-%s.json" % (cells, model, path))
    with open(scene_path, "w") as f:
        json.dump(scene(cells, model, path, steps), f)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    with tempfile.TemporaryFile() as captured:
        process = subprocess.Popen([simulator, scene_path, "--output", scene_path + ".afsim"], stdout=captured,
                                   stderr=subprocess.STDOUT, env=env)
        _, status, usage = os.wait4(process.pid, 0)
        captured.seek(0)
        text = captured.read().decode(errors="replace")
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError("%s failed:\n%s" % (scene_path, text))
    row = parse_summary(text)
    row["peak_mib"] = usage.ru_maxrss / 1024.0
    # CPU seconds of the whole process: on a shared machine the single-threaded runs' CPU
    # time is what the run cost, where wall time also counts waiting for a core.
    row["cpu_s"] = usage.ru_utime + usage.ru_stime
    # One frame: the per-frame figures are the run's totals. Per factorization and per
    # right-hand side (a PCG iteration's substitution pair) they compare across sizes even
    # where the number of factorizations differs.
    row["one factorization"] = row["factorization"] / max(row["factorizations"], 1)
    row["one solve"] = row["solve"] / max(row["rhs"], 1)
    for phase in PHASES + ["per frame", "other"]:
        row[phase] /= steps  # one frame of `steps` steps: per frame -> per step
    for name in (scene_path, scene_path + ".afsim", scene_path + ".afsim.checkpoint"):
        if os.path.exists(name):
            os.remove(name)
    return row


def slope(xs, ys):
    lx = [math.log(x) for x in xs]
    ly = [math.log(max(y, 1e-9)) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    den = sum((a - mx) ** 2 for a in lx)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / den if den > 0 else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--simulator", default="build/bin/offlineSimulator")
    parser.add_argument("--sizes", default="8,16", help="n of each 4n x n x n box, comma-separated")
    parser.add_argument("--models", default="corotational,neo-hookean")
    parser.add_argument("--paths", default="default", help="default (kept factor + PCG) and/or exact")
    parser.add_argument("--steps", type=int, default=10, help="steps per run (one frame)")
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    models = args.models.split(",")
    paths = args.paths.split(",")
    for model in models:
        if model not in MODELS:
            parser.error("unknown model %s (known: %s)" % (model, ", ".join(MODELS)))
    for path in paths:
        if path not in ("default", "exact"):
            parser.error("unknown path %s (default or exact)" % path)

    with open("/proc/loadavg") as f:
        load_start = " ".join(f.read().split()[:3])
    print("scale study: %d steps per run, OMP_NUM_THREADS=%d, load at start %s" % (args.steps, args.threads,
                                                                                   load_start))
    print()
    print("| model | path | tets | free DOFs | forces | assembly | factorization | solve | step | "
          "factorizations | set-up | process CPU | peak RSS |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    results = {}
    with tempfile.TemporaryDirectory() as folder:
        for model in models:
            for path in paths:
                for cells in sizes:
                    r = run_one(args.simulator, cells, model, path, args.steps, args.threads, folder)
                    results.setdefault((model, path), []).append(r)
                    print("| %s | %s | %d | %d | %.1f ms | %.1f ms | %.1f ms | %.1f ms | %.1f ms | %d | %.1f s | "
                          "%.1f s | %.0f MiB |" %
                          (model, path, r["tets"], 3 * (r["vertices"] - r["fixed"]), 1e3 * r["forces"],
                           1e3 * r["assembly"], 1e3 * r["factorization"], 1e3 * r["solve"],
                           1e3 * r["per frame"], r["factorizations"], r["setup"], r["cpu_s"], r["peak_mib"]),
                          flush=True)
    with open("/proc/loadavg") as f:
        load_end = " ".join(f.read().split()[:3])
    print()
    print("growth exponents (time ~ tets^p, least squares over the sizes; load at end %s):" % load_end)
    print()
    print("| model | path | forces | assembly | factorization | solve | step | one factorization | one solve | peak RSS |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for (model, path), rows in results.items():
        if len(rows) < 2:
            continue
        tets = [r["tets"] for r in rows]
        keys = PHASES + ["per frame", "one factorization", "one solve", "peak_mib"]
        exps = [slope(tets, [r[k] for r in rows]) for k in keys]
        print("| %s | %s | %s |" % (model, path, " | ".join("%.2f" % e for e in exps)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
