#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Draws integratorBenchmark's figures with matplotlib from the CSV files it writes.

    /usr/bin/python3 scripts/plot-benchmark.py OUT [--title NAME]

OUT is integratorBenchmark's --out folder. Reads results.csv (one row per configuration),
vertex-displacement.csv and vertex-equal-cost.csv (long form: series,time,value) and
writes, as PNG (200 dpi) and PDF:
  pareto-<group>.{png,pdf}       error against median wall time per frame, log-log, for the
                                 error columns "all" and the first group; single-rate
                                 configurations of one integrator joined by a line, every
                                 multirate configuration its own marker, labelled with its
                                 label and ratios
  vertex-displacement.{png,pdf}  the displacement of one vertex over time
  vertex-equal-cost.{png,pdf}    the paper's equal-cost figure, when its CSV exists
Exit status 0 when drawn, 3 when matplotlib is missing (the message says how to install
it), 1 for unusable input.
"""
import argparse
import csv
import math
import pathlib
import sys

MISSING_MATPLOTLIB = 3
MULTIRATE = ("async", "multirate")


def read_rows(path):
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def is_multirate(row):
    return row["integrator"].startswith(MULTIRATE) or any(r.strip() not in ("", "1") for r in row.get("ratios", "").split(","))


def configuration_label(row):
    """A multirate row's label with its ratios, so two async rows never look the same."""
    label = row["label"]
    ratios = row.get("ratios", "").strip()
    if is_multirate(row) and ratios and ratios not in label:
        label += f" (ratios {ratios})"
    return label


def save(fig, folder, stem):
    written = []
    for extension in ("png", "pdf"):
        path = folder / f"{stem}.{extension}"
        fig.savefig(path, dpi=200, bbox_inches="tight")
        written.append(path)
    return written


def pareto(plt, folder, rows, group, title):
    column = "error_" + group
    fig, ax = plt.subplots(figsize=(8.0, 4.8))
    single = {}
    markers = "osD^v<>pPX*h"
    index = 0
    for row in rows:
        x, y = number(row["seconds_per_frame_median"]), number(row.get(column))
        if row.get("completed") != "1" or not (x > 0 and y > 0):
            continue
        if is_multirate(row):
            ax.plot([x], [y], linestyle="none", marker=markers[index % len(markers)], markersize=8,
                    color=f"C{(index + 1) % 10}", label=configuration_label(row))
            index += 1
        else:
            single.setdefault(row["integrator"], []).append((x, y))
    for k, (integrator, points) in enumerate(single.items()):
        ax.plot(*zip(*points), marker=".", linestyle="-", color="black" if k == 0 else f"C{(index + k + 1) % 10}",
                label=f"{integrator} (single rate)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time per frame (s, median)")
    ax.set_ylabel(f"relative L2 error of u ({group})")
    ax.set_title(f"Error against time per frame: {title}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="center left", bbox_to_anchor=(1.02, 0.5), fontsize="small")
    written = save(fig, folder, "pareto-" + group)
    plt.close(fig)
    return written


def trajectory(plt, folder, stem, ylabel, title):
    path = folder / (stem + ".csv")
    if not path.exists():
        return []
    series = {}
    for row in read_rows(path):
        series.setdefault(row["series"], ([], []))
        series[row["series"]][0].append(number(row["time"]))
        series[row["series"]][1].append(number(row["value"]))
    fig, ax = plt.subplots(figsize=(8.0, 4.8))
    for k, (name, (t, u)) in enumerate(series.items()):
        reference = k == 0
        ax.plot(t, u, color="black" if reference else f"C{(k - 1) % 10}", linewidth=2.0 if reference else 1.2,
                linestyle="-" if reference else ("-", "--", "-.", ":")[(k - 1) // 10 % 4], label=name)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="center left", bbox_to_anchor=(1.02, 0.5), fontsize="small")
    written = save(fig, folder, stem)
    plt.close(fig)
    return written


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", type=pathlib.Path, help="integratorBenchmark's --out folder")
    parser.add_argument("--title", default=None, help="scene name in the titles (default: the folder's name)")
    args = parser.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot-benchmark: no figures: matplotlib is missing (Debian: sudo apt-get install python3-matplotlib, "
              "or scripts/install-deps.sh); the CSV files are unchanged", file=sys.stderr)
        return MISSING_MATPLOTLIB
    results = args.folder / "results.csv"
    if not results.exists():
        print(f"plot-benchmark: {results}: no such file (run integratorBenchmark --out {args.folder} first)",
              file=sys.stderr)
        return 1
    title = args.title or args.folder.resolve().name
    rows = read_rows(results)
    groups = [name[len("error_"):] for name in (rows[0].keys() if rows else []) if name.startswith("error_")]
    written = []
    for group in dict.fromkeys(g for g in groups if g in ("all", groups[0])):
        written += pareto(plt, args.folder, rows, group, title)
    written += trajectory(plt, args.folder, "vertex-displacement", "|u| of the vertex", f"Displacement of one vertex: {title}")
    written += trajectory(plt, args.folder, "vertex-equal-cost", "displacement coordinate of the vertex",
                          f"Equal cost: {title}")
    for path in written:
        print(f"Wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
