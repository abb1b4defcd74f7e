#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""scripts/plot-adaptive.py on a small benchmarkAdaptive --csv file: the figure is a PNG of
a useful size; a file without an adaptive series and one with a bad number are refused with
the file (and line) named. Exit 77 (ctest: SKIPPED) when matplotlib is missing.

    python3 plotAdaptiveCheck.py SCRIPT SCRATCH_FOLDER
"""
import pathlib
import shutil
import struct
import subprocess
import sys

script, folder = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
shutil.rmtree(folder, ignore_errors=True)
folder.mkdir(parents=True)
rows = ["series,role,time,value"]
for name, role, scale in (("reference", "reference", 1.0), ("backward Euler, hL/1", "single-rate", 0.8),
                          ("backward Euler, hL/16", "equal-cost", 0.97), ("async, adaptive", "adaptive", 0.82),
                          ("async, fixed", "fixed", 0.9)):
    rows += [f'"{name}",{role},{k / 240},{0.45 - scale * abs((k - 60) / 200)}' for k in range(1, 121)]
good = folder / "com.csv"
good.write_text("\n".join(rows) + "\n")


def run(csv, png):
    return subprocess.run([sys.executable, str(script), str(csv), str(png), "--title", "check"], capture_output=True,
                          text=True)


result = run(good, folder / "com.png")
if result.returncode == 3:
    print("SKIP: matplotlib is missing:", result.stderr.strip())
    sys.exit(77)
assert result.returncode == 0, result.stderr
data = (folder / "com.png").read_bytes()
assert data[:8] == b"\x89PNG\r\n\x1a\n"
width, height = struct.unpack(">II", data[16:24])
assert width >= 900 and height >= 450 and len(data) > 20000, (width, height, len(data))

no_adaptive = folder / "no-adaptive.csv"
no_adaptive.write_text("\n".join(r for r in rows if ",adaptive," not in r) + "\n")
result = run(no_adaptive, folder / "x.png")
assert result.returncode == 1 and "needs a reference and an adaptive series" in result.stderr, result.stderr
bad = folder / "bad.csv"
bad.write_text(rows[0] + '\n"reference",reference,0.1,oops\n')
result = run(bad, folder / "y.png")
assert result.returncode == 1 and f"{bad}:2:" in result.stderr, result.stderr
assert not (folder / "x.png").exists() and not (folder / "y.png").exists()
print("plot-adaptive: figure and errors checked in", folder)
