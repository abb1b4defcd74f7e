#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Draws the centre-of-mass height over time from benchmarkAdaptive's --csv file.

    /usr/bin/python3 scripts/plot-adaptive.py com.csv OUT.png [--title TEXT]

Draws the reference, single-rate backward Euler at hL, the single-rate run of the
equal-cost verdict and the adaptive async run (the roles benchmarkAdaptive writes), one
line each, labelled with their configurations, and writes OUT.png (150 dpi). Exit status
0 when drawn, 3 when matplotlib is missing (the message says how to install it), 1 for
unusable input.
"""
import argparse
import csv
import sys

MISSING_MATPLOTLIB = 3
ROLES = ("reference", "single-rate", "equal-cost", "adaptive")
STYLES = {
    "reference": {"color": "black", "linewidth": 2.0},
    "single-rate": {"color": "tab:blue", "linestyle": "--"},
    "equal-cost": {"color": "tab:green", "linestyle": "-."},
    "adaptive": {"color": "tab:orange"},
}


def read_series(path):
    """{role: (label, [times], [values])} for the roles drawn."""
    series = {}
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames != ["series", "role", "time", "value"]:
            raise ValueError(f"{path}: expected the columns series,role,time,value, got {reader.fieldnames}")
        for line, row in enumerate(reader, start=2):
            if row["role"] not in ROLES:
                continue
            try:
                time, value = float(row["time"]), float(row["value"])
            except ValueError as error:
                raise ValueError(f"{path}:{line}: {error}") from None
            label, times, values = series.setdefault(row["role"], (row["series"], [], []))
            times.append(time)
            values.append(value)
    if "reference" not in series or "adaptive" not in series:
        raise ValueError(f"{path}: needs a reference and an adaptive series (benchmarkAdaptive --csv writes both)")
    return series


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv")
    parser.add_argument("output")
    parser.add_argument("--title", default="")
    parser.add_argument("--ylabel", default="centre-of-mass height (m)",
                        help="y axis label (the series is what benchmarkAdaptive tracked)")
    args = parser.parse_args()
    try:
        series = read_series(args.csv)
    except (OSError, ValueError) as error:
        print(f"plot-adaptive: {error}", file=sys.stderr)
        return 1
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot-adaptive: needs matplotlib: apt-get install python3-matplotlib (then run /usr/bin/python3)",
              file=sys.stderr)
        return MISSING_MATPLOTLIB
    fig, ax = plt.subplots(figsize=(7.0, 3.6))
    for role in ROLES:
        if role in series:
            label, times, values = series[role]
            ax.plot(times, values, label=label, **STYLES[role])
    ax.set_xlabel("time (s)")
    ax.set_ylabel(args.ylabel)
    if args.title:
        ax.set_title(args.title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.output, dpi=150)
    return 0


if __name__ == "__main__":
    sys.exit(main())
