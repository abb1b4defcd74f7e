#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""scripts/plot-benchmark.py on a small integratorBenchmark output: every figure comes as a
PNG of a useful size and a PDF, and the two async rows get their own legend entries.
Exit 77 (ctest: SKIPPED) when matplotlib is missing, after saying so.

    python3 plotBenchmarkCheck.py SCRIPT SCRATCH_FOLDER
"""
import pathlib
import shutil
import struct
import subprocess
import sys

script, folder = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
shutil.rmtree(folder, ignore_errors=True)
folder.mkdir(parents=True)
header = ("label,integrator,timestep,steps_per_frame,ratios,completed,failed_frame,seconds_per_frame_median,"
          "seconds_per_frame_min,repeats,setup_seconds,first_frame_seconds,factorizations_per_frame,solves_per_frame,"
          "factor_flops_per_frame,solve_flops_per_frame,factor_nonzeros,error_tip,error_all\n")
rows = [
    '"backward-euler spf=1",backward-euler,0.0333,1,"",1,-1,0.0011,0.0011,1,0.05,0.001,0,1,0,1e6,1e5,0.51,0.52',
    '"backward-euler spf=4",backward-euler,0.0083,4,"",1,-1,0.0035,0.0035,1,0.05,0.003,0,4,0,4e6,1e5,0.19,0.19',
    '"backward-euler spf=16",backward-euler,0.0021,16,"",1,-1,0.012,0.012,1,0.05,0.01,0,16,0,1.6e7,1e5,0.05,0.06',
    '"fast tip",async,0.0083,4,"1,4",1,-1,0.0096,0.0096,1,0.05,0.01,1,8,1e6,8e6,2e5,0.17,0.17',
    '"fast tip",async,0.0083,4,"1,8",1,-1,0.026,0.026,1,0.05,0.02,1,12,1e6,1.2e7,2e5,0.16,0.16',
]
(folder / "results.csv").write_text(header + "\n".join(rows) + "\n")
series = ["series,time,value"]
for name, scale in (("reference", 1.0), ("backward-euler spf=4", 0.8), ("fast tip ratio 4", 0.9)):
    series += [f'"{name}",{k / 30},{scale * (k % 7) / 7}' for k in range(30)]
(folder / "vertex-displacement.csv").write_text("\n".join(series) + "\n")

result = subprocess.run([sys.executable, str(script), str(folder), "--title", "check"], capture_output=True,
                        text=True)
if result.returncode == 3:
    print("SKIP: matplotlib is missing:", result.stderr.strip())
    sys.exit(77)
assert result.returncode == 0, result.stderr
for stem in ("pareto-all", "pareto-tip", "vertex-displacement"):
    png, pdf = folder / f"{stem}.png", folder / f"{stem}.pdf"
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", png
    width, height = struct.unpack(">II", data[16:24])
    assert width >= 1000 and height >= 600 and len(data) > 20000, (png, width, height, len(data))
    assert pdf.read_bytes()[:5] == b"%PDF-" and pdf.stat().st_size > 5000, pdf
    assert f"Wrote {png}" in result.stdout, result.stdout
assert not (folder / "vertex-equal-cost.png").exists()  # no CSV, no figure
print("plot-benchmark: figures of", folder, "checked")

# The two async rows share their label: their ratios keep them apart in the legend.
import importlib.util  # noqa: E402

spec = importlib.util.spec_from_file_location("plot_benchmark", script)
module = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
labels = [module.configuration_label(row) for row in module.read_rows(folder / "results.csv")]
assert labels[3] == "fast tip (ratios 1,4)" and labels[4] == "fast tip (ratios 1,8)", labels
assert labels[0] == "backward-euler spf=1", labels

# Without its input: a clear message.
missing = subprocess.run([sys.executable, str(script), str(folder / "nothere")], capture_output=True, text=True)
assert missing.returncode == 1 and "results.csv: no such file" in missing.stderr, missing.stderr
