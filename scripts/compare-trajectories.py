#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Trajectory regression between two builds of the toolkit.

    scripts/compare-trajectories.py run --bin BUILD/bin --out DIR [--frames N]
    scripts/compare-trajectories.py compare DIR_BEFORE DIR_AFTER [--tolerance 1e-13]

`run` simulates every shipped scene (models/*/*.json and tests/benchmarks/scenes/*.json)
under a set of variants (the scene as shipped; backward Euler, trapezoidal, the uncoupled
multirate integrator and Schroeder et al. 2011 on it; the paper's coupling; corotational
forces with the lagged and the rebuilt Schur factor; neo-Hookean forces under the scene's
integrator and under backward Euler) for a few frames each,
writing DIR/CASE.afsim. `compare` reads two such folders and reports, per case, the
largest difference of displacement and velocity over all frames relative to the largest
magnitude in the first run; it exits 1 when a case differs by more than the tolerance or
is missing. The .afsim layout is the one of docs/simulation-output.md.
"""
import argparse
import pathlib
import re
import struct
import subprocess
import sys
import tempfile

import numpy as np

REPOSITORY = pathlib.Path(__file__).resolve().parent.parent

# (name, command-line arguments, scene text edits as (pattern, replacement) regexes)
VARIANTS = [
    ("shipped", [], []),
    ("backward-euler", ["--integrator", "backward-euler"], []),
    ("trapezoidal", ["--integrator", "trapezoidal"], []),
    ("uncoupled", ["--integrator", "multirate-uncoupled"], []),
    ("schroeder2011", ["--integrator", "schroeder2011"], []),
    ("paper", [], [(r'"options"\s*:\s*\{', '"options": {"coupling": "paper", ')]),
    ("corotational", [], [(r'"forceModel"\s*:\s*\{[^}]*\}', '"forceModel": {"type": "corotational"}')]),
    ("corotational-rebuilt", [],
     [(r'"forceModel"\s*:\s*\{[^}]*\}', '"forceModel": {"type": "corotational"}'),
      (r'"options"\s*:\s*\{', '"options": {"laggedSchur": false, ')]),
    ("neo-hookean-be", ["--integrator", "backward-euler"],
     [(r'"forceModel"\s*:\s*\{[^}]*\}', '"forceModel": {"type": "neo-hookean"}')]),
    ("neo-hookean", [], [(r'"forceModel"\s*:\s*\{[^}]*\}', '"forceModel": {"type": "neo-hookean"}')]),
]


def scenes():
    found = sorted(REPOSITORY.glob("models/*/*.json")) + sorted(REPOSITORY.glob("tests/benchmarks/scenes/*.json"))
    return [path for path in found if '"integrator"' in path.read_text()]


def variant_scene(scene, edits, folder):
    """The scene text with edits applied and mesh paths made absolute, in folder; None
    when an edit finds nothing to change (the variant does not apply)."""
    text = scene.read_text()
    for pattern, replacement in edits:
        text, count = re.subn(pattern, replacement, text, count=1)
        if count == 0:
            return None
    text = re.sub(r'"file"\s*:\s*"([^"/][^"]*)"', lambda m: '"file": "%s"' % (scene.parent / m.group(1)), text)
    path = folder / scene.name
    path.write_text(text)
    return path


def run(args):
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    simulator = pathlib.Path(args.bin) / "offlineSimulator"
    failures = 0
    with tempfile.TemporaryDirectory() as scratch:
        for scene in scenes():
            for name, extra, edits in VARIANTS:
                folder = pathlib.Path(scratch) / name
                folder.mkdir(exist_ok=True)
                path = variant_scene(scene, edits, folder)
                if path is None:
                    continue
                case = "%s--%s" % (scene.stem, name)
                command = [str(simulator), str(path), "-o", str(out / (case + ".afsim")), "--frames",
                           str(args.frames), "-q", "--no-stability-check"] + extra
                result = subprocess.run(command, capture_output=True, text=True)
                status = "ok" if result.returncode == 0 else "exit %d" % result.returncode
                (out / (case + ".log")).write_text(result.stdout + result.stderr)
                print("%-45s %s" % (case, status), flush=True)
                failures += result.returncode != 0
    return 0


def read_afsim(path):
    data = path.read_bytes()
    if data[:8] != b"AFEMSIM\0":
        raise ValueError("%s: not an .afsim file" % path)
    header_size = struct.unpack_from("<I", data, 12)[0]
    vertices = struct.unpack_from("<Q", data, 16)[0]
    flags = struct.unpack_from("<Q", data, 40)[0]
    record = struct.unpack_from("<Q", data, 48)[0]
    frames = (len(data) - header_size) // record
    values = 3 * vertices * (2 if flags & 1 else 1)
    states = np.empty((frames, values))
    for k in range(frames):
        start = header_size + k * record + 16
        states[k] = np.frombuffer(data, dtype="<f8", count=values, offset=start)
    return states


def compare(args):
    before, after = pathlib.Path(args.before), pathlib.Path(args.after)
    worst, bad = 0.0, 0
    for path in sorted(before.glob("*.afsim")):
        other = after / path.name
        if not other.exists():
            print("%-45s missing in %s" % (path.stem, after))
            bad += 1
            continue
        a, b = read_afsim(path), read_afsim(other)
        if a.shape != b.shape:
            print("%-45s frames or sizes differ: %s against %s" % (path.stem, a.shape, b.shape))
            bad += 1
            continue
        scale = max(np.abs(a).max(), 1e-300) if a.size else 1.0
        difference = np.abs(a - b).max() / scale if a.size else 0.0
        worst = max(worst, difference)
        verdict = "ok" if difference <= args.tolerance else "DIFFERS"
        bad += difference > args.tolerance
        print("%-45s %3d frames  max relative difference %.3e  %s" % (path.stem, a.shape[0], difference, verdict))
    print("%d cases, %d over the tolerance %.0e; largest relative difference %.3e" %
          (len(list(before.glob("*.afsim"))), bad, args.tolerance, worst))
    return 1 if bad else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("run", help="simulate every case with one build")
    p.add_argument("--bin", required=True, help="the build's bin folder (holds offlineSimulator)")
    p.add_argument("--out", required=True, help="folder for CASE.afsim and CASE.log")
    p.add_argument("--frames", type=int, default=12, help="frames per case (default 12)")
    p = sub.add_parser("compare", help="compare two folders written by run")
    p.add_argument("before")
    p.add_argument("after")
    p.add_argument("--tolerance", type=float, default=1e-13,
                   help="largest accepted difference relative to the largest magnitude (default 1e-13)")
    args = parser.parse_args()
    return run(args) if args.command == "run" else compare(args)


if __name__ == "__main__":
    sys.exit(main())
