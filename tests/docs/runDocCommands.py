#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Runs the shell commands a Markdown document shows, as written, and fails on any that fails.

Which lines are commands (the rule the documents follow):
  * Only fenced blocks whose info string is sh, bash, shell or console are read; untagged
    blocks (synopses, example output) and other languages are never run.
  * sh / bash / shell blocks: every non-blank line that does not start with '#' is a
    command; a line ending in a backslash continues on the next one. Comments after a
    command are left to bash.
  * console blocks: only lines starting with "$ " are commands (the prefix is dropped);
    the other lines are example output.
  * A block directly preceded by the line <!-- docs-test: skip REASON --> is not run
    (installs, builds, benchmarks of minutes). The reason is required; skipped commands
    are listed with it and counted.

How they run: in document order, one after another, with bash, in one scratch folder
laid out like a fresh clone after the quick start: copies of models/ and the data folders
below, and build/bin linking to the build's programs (also first on PATH), so "models/..."
and "./build/bin/..." resolve as in the repository while nothing in the source tree is
written. Each command has a time limit. Exit status 0 when every command exits 0; else 1,
after listing each failed command with its exit status and the end of its output.
"""

import argparse
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import time

# Folders a documented command may read (copied, so commands that regenerate files in
# them write to the copy).
DATA_FOLDERS = ["models", "tests/benchmarks/scenes", "tests/data"]
RUN_LANGUAGES = {"sh", "bash", "shell", "console"}
SKIP_MARKER = re.compile(r"^\s*<!--\s*docs-test:\s*skip\b(.*?)-->\s*$")
ANY_MARKER = re.compile(r"<!--\s*docs-test:")
FENCE = re.compile(r"^(\s*)(```+|~~~+)\s*([^\s`]*)")


class Command:
    def __init__(self, line, text, skip_reason):
        self.line = line  # 1-based line of the document where the command starts
        self.text = text
        self.skip_reason = skip_reason


def extract(path):
    """The commands of the document, each with its line and its skip reason (or None)."""
    with open(path, encoding="utf-8") as handle:
        lines = handle.read().split("\n")
    commands = []
    errors = []
    index = 0
    while index < len(lines):
        fence = FENCE.match(lines[index])
        if not fence:
            if ANY_MARKER.search(lines[index]) and not SKIP_MARKER.match(lines[index]):
                errors.append(f"{path}:{index + 1}: unknown docs-test marker (only '<!-- docs-test: skip REASON -->')")
            index += 1
            continue
        marker, language = fence.group(2), fence.group(3).lower()
        # The block's skip marker: the nearest non-blank line above the fence.
        above = index - 1
        while above >= 0 and not lines[above].strip():
            above -= 1
        skip = SKIP_MARKER.match(lines[above]) if above >= 0 else None
        skip_reason = None
        if skip:
            skip_reason = skip.group(1).strip()
            if not skip_reason:
                errors.append(f"{path}:{above + 1}: a docs-test skip marker needs a reason")
        body_start = index + 1
        end = body_start
        while end < len(lines) and not lines[end].strip().startswith(marker[:3]):
            end += 1
        if language in RUN_LANGUAGES:
            commands.extend(block_commands(lines, body_start, end, language, skip_reason))
        elif skip:
            errors.append(f"{path}:{above + 1}: skip marker on a block that is never run ({language or 'untagged'})")
        index = end + 1
    return commands, errors


def block_commands(lines, start, end, language, skip_reason):
    commands = []
    pending = None
    pending_line = 0
    for number in range(start, end):
        line = lines[number]
        if pending is None:
            if language == "console":
                if not line.startswith("$ "):
                    continue
                line = line[2:]
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            pending, pending_line = "", number + 1
        if line.rstrip().endswith("\\"):
            pending += line.rstrip()[:-1] + " "
            continue
        pending += line
        commands.append(Command(pending_line, pending.strip(), skip_reason))
        pending = None
    if pending is not None:
        commands.append(Command(pending_line, pending.strip(), skip_reason))
    return commands


def prepare_scratch(scratch, repository, bin_dir):
    if os.path.isdir(scratch):
        shutil.rmtree(scratch)
    os.makedirs(os.path.join(scratch, "build"))
    os.symlink(os.path.abspath(bin_dir), os.path.join(scratch, "build", "bin"))
    for folder in DATA_FOLDERS:
        source = os.path.join(repository, folder)
        if os.path.isdir(source):
            shutil.copytree(source, os.path.join(scratch, folder))


def tail(text, count):
    kept = text.strip().split("\n")[-count:]
    return "\n".join("      | " + line for line in kept)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("document", help="Markdown file, relative to --repository")
    parser.add_argument("--repository", required=True, help="source tree (the documents and the data folders)")
    parser.add_argument("--bin", required=True, help="the build's bin folder")
    parser.add_argument("--scratch", required=True, help="folder to run in (deleted and recreated)")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds per command (default 120)")
    parser.add_argument("--list", action="store_true", help="print the commands and skips, run nothing")
    parser.add_argument("--not-built", default="",
                        help="comma-separated programs this build does not have: commands using them are "
                        "skipped with that reason (e.g. frameRenderer without ASYNCFEM_WITH_RENDER)")
    args = parser.parse_args()

    document = os.path.join(args.repository, args.document)
    commands, errors = extract(document)
    for error in errors:
        print(error)
    if errors:
        return 1
    not_built = [name for name in args.not_built.split(",") if name]
    for command in commands:
        missing = [name for name in not_built if re.search(r"(^|[\s/;&|])" + re.escape(name) + r"\b", command.text)]
        if command.skip_reason is None and missing:
            command.skip_reason = "not in this build: " + ", ".join(missing)

    to_run = [c for c in commands if c.skip_reason is None]
    skipped = [c for c in commands if c.skip_reason is not None]
    if args.list:
        for command in commands:
            state = "skip (" + command.skip_reason + ")" if command.skip_reason else "run"
            print(f"{args.document}:{command.line}: {state}: {command.text}")
        print(f"{len(to_run)} to run, {len(skipped)} skipped")
        return 0

    prepare_scratch(args.scratch, args.repository, args.bin)
    environment = dict(os.environ)
    environment["PATH"] = os.path.abspath(args.bin) + os.pathsep + environment.get("PATH", "")
    environment.setdefault("OMP_WAIT_POLICY", "passive")
    failures = []
    cpu_total = 0.0
    started = time.monotonic()
    for command in to_run:
        begin = time.monotonic()
        cpu_before = resource.getrusage(resource.RUSAGE_CHILDREN)
        # Its own process group, so that a timeout stops everything the command started.
        process = subprocess.Popen(["bash", "-o", "pipefail", "-c", command.text], cwd=args.scratch, env=environment,
                                   stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True, errors="replace", start_new_session=True)
        try:
            standard_output, error_output = process.communicate(timeout=args.timeout)
            status = process.returncode
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            standard_output, error_output = process.communicate()
            status = "timeout"
        if not error_output.strip():
            error_output = standard_output
        seconds = time.monotonic() - begin
        cpu_after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (cpu_after.ru_utime - cpu_before.ru_utime) + (cpu_after.ru_stime - cpu_before.ru_stime)
        cpu_total += cpu
        ok = status == 0
        print(f"{'ok  ' if ok else 'FAIL'} {seconds:6.1f} s ({cpu:6.1f} s CPU)  {args.document}:{command.line}: "
              f"{command.text}", flush=True)
        if not ok:
            failures.append((command, status, error_output))
    total = time.monotonic() - started

    print(f"\n{args.document}: {len(to_run)} commands run in {total:.1f} s ({cpu_total:.1f} s CPU), {len(failures)} failed, "
          f"{len(skipped)} skipped")
    for command in skipped:
        print(f"  skipped {args.document}:{command.line}: {command.text}\n    reason: {command.skip_reason}")
    if failures:
        print("\nFailed commands:")
        for command, status, error_output in failures:
            reason = f"exceeded {args.timeout:g} s" if status == "timeout" else f"exit status {status}"
            print(f"  {args.document}:{command.line}: {command.text}\n    {reason}; end of its output:")
            print(tail(error_output, 15) if error_output.strip() else "      | (nothing)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
