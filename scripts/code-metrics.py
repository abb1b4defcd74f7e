#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Function lengths over libraries/ and utilities/ (outside the Python bindings), from
Universal Ctags' extents (end - start + 1 lines per function definition):

    scripts/code-metrics.py [--list N]

prints the count, the median, the 95th percentile and the longest, the functions over
120 lines, and with --list the N longest.
"""
import argparse
import json
import pathlib
import subprocess
import sys

REPOSITORY = pathlib.Path(__file__).resolve().parent.parent


def functions():
    command = ["ctags", "-R", "--languages=C++", "--kinds-C++=f", "--fields=+ne", "--output-format=json", "-f", "-",
               "libraries", "utilities"]
    output = subprocess.run(command, cwd=REPOSITORY, capture_output=True, text=True, check=True).stdout
    for line in output.splitlines():
        tag = json.loads(line)
        if "end" not in tag or tag["path"].startswith("libraries/python/"):
            continue
        yield tag["end"] - tag["line"] + 1, "%s:%d %s" % (tag["path"], tag["line"], tag["name"])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--list", type=int, default=0, help="also list the N longest functions")
    args = parser.parse_args()
    found = sorted(functions(), reverse=True)
    lengths = sorted(length for length, _ in found)
    if not lengths:
        print("no functions found (is Universal Ctags installed?)")
        return 1
    percentile = lengths[min(len(lengths) - 1, int(0.95 * len(lengths)))]
    over = [f for f in found if f[0] > 120]
    print("functions %d, median %d lines, 95th percentile %d lines, longest %d lines, over 120 lines: %d" %
          (len(lengths), lengths[len(lengths) // 2], percentile, lengths[-1], len(over)))
    for length, where in found[:max(args.list, len(over))]:
        print("  %4d  %s" % (length, where))
    return 0


if __name__ == "__main__":
    sys.exit(main())
