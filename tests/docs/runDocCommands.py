#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Runs the snippets a Markdown document shows, as written, and fails on any that fails or
does not print what the document says it prints.

Which blocks run (the rule the documents follow):
  * Fenced blocks whose info string is sh, bash, shell or console are shell commands:
    - sh / bash / shell: every non-blank line that does not start with '#' is a command; a
      line ending in a backslash continues on the next one. Comments after a command are
      left to bash.
    - console: only lines starting with "$ " are commands (the prefix is dropped); the
      other lines are example output.
  * python blocks run as one script each with the Python the module was built for
    (--python), with the build's module folder on PYTHONPATH (--python-path); a block that
    imports asyncfem is skipped, and says so, when the build has no module.
  * json blocks are parsed (a fragment such as `"forces": [...]` as the members of an
    object); with a `scene` marker (below) they are also merged into a scene and run.
  * Untagged blocks (synopses, example output) and other languages (cpp: README's program
    is compiled by ReadmeExample.*) are not run, and are not counted.

Markers: HTML comments on the lines directly above a block (blank lines between them are
allowed), one per line; any other "docs-test:" comment is an error.
  <!-- docs-test: skip REASON -->       the block is not run (installs, builds, runs of
                                        minutes); the reason is required, and listed.
  <!-- docs-test: expect REGEX -->      the output of the block's commands (stdout and
                                        stderr, in order) must match REGEX (Python re,
                                        multi-line); several expect markers: all must match.
  <!-- docs-test: replace OLD => NEW --> the test runs the block's commands with OLD
                                        replaced by NEW (fewer frames or repeats than the
                                        document's full run); every OLD must occur.
  <!-- docs-test: scene BASE.json -->   a json fragment's top-level keys replace BASE's (a
                                        copy), and `offlineSimulator COPY --frames 2` runs it.

How they run: in document order, one after another, in one scratch folder laid out like a
fresh clone after the quick start: copies of models/ and the data folders below, and
build/bin linking to the build's programs (also first on PATH) and build/python to its
Python package, so "models/...", "./build/bin/..." and "PYTHONPATH=build/python" resolve as in the repository while nothing in the source tree is
written. Each command has a time limit.

Exit status: 0 when every command ran and passed; 1 after listing each failed command
with its exit status and the end of its output, or when a document has nothing to run
(a docs test that runs nothing would pass for nothing); 77 (reported as skipped) when
every block of the document needs a program this build does not have (--not-built).
"""

import argparse
import copy
import json
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
DATA_FOLDERS = ["models", "tests/benchmarks/scenes", "tests/benchmarks/configs", "tests/data"]
SHELL_LANGUAGES = {"sh", "bash", "shell", "console"}
RUN_LANGUAGES = SHELL_LANGUAGES | {"python", "json"}
MARKER = re.compile(r"^\s*<!--\s*docs-test:\s*(\w+)\b\s?(.*?)\s*-->\s*$")
ANY_MARKER = re.compile(r"^\s*<!--\s*docs-test:")
FENCE = re.compile(r"^(\s*)(```+|~~~+)\s*([^\s`]*)")
SKIPPED = 77


class Block:
    """A fenced block that runs, with its markers."""

    def __init__(self, line, language):
        self.line = line  # 1-based line of the fence
        self.language = language
        self.skip_reason = None
        self.expects = []
        self.replacements = []
        self.scene = None
        self.output = ""


class Command:
    def __init__(self, line, text, block):
        self.line = line  # 1-based line of the document where the command starts
        self.text = text
        self.block = block
        self.skip_reason = block.skip_reason
        self.script = None  # the text of a python or json block


def read_markers(path, lines, fence_index, errors):
    """The markers on the lines directly above a fence (blank lines allowed between)."""
    markers = []
    above = fence_index - 1
    while above >= 0:
        if not lines[above].strip():
            above -= 1
            continue
        found = MARKER.match(lines[above])
        if not found:
            break
        markers.append((above + 1, found.group(1), found.group(2).strip()))
        above -= 1
    return list(reversed(markers))


def apply_markers(path, block, markers, errors):
    for line, kind, argument in markers:
        where = f"{path}:{line}"
        if kind == "skip":
            block.skip_reason = argument
            if not argument:
                errors.append(f"{where}: a docs-test skip marker needs a reason")
        elif kind == "expect":
            try:
                block.expects.append(re.compile(argument, re.MULTILINE))
            except re.error as error:
                errors.append(f"{where}: docs-test expect: not a regular expression ({error})")
        elif kind == "replace" and " => " in argument:
            block.replacements.append(tuple(argument.split(" => ", 1)))
        elif kind == "scene" and argument:
            block.scene = argument
        else:
            errors.append(f"{where}: unknown or malformed docs-test marker '{kind} {argument}' "
                          "(skip REASON, expect REGEX, replace OLD => NEW, scene BASE.json)")
    if block.scene and block.language != "json":
        errors.append(f"{path}:{block.line}: a scene marker belongs on a json block")


def extract(path):
    """The commands of the document, each with its line and block, and the errors found."""
    with open(path, encoding="utf-8") as handle:
        lines = handle.read().split("\n")
    commands = []
    errors = []
    index = 0
    while index < len(lines):
        fence = FENCE.match(lines[index])
        if not fence:
            if ANY_MARKER.search(lines[index]) and not MARKER.match(lines[index]):
                errors.append(f"{path}:{index + 1}: malformed docs-test marker (one '<!-- docs-test: KIND ... -->' "
                              "per line)")
            index += 1
            continue
        marker, language = fence.group(2), fence.group(3).lower()
        markers = read_markers(path, lines, index, errors)
        end = index + 1
        while end < len(lines) and not lines[end].strip().startswith(marker[:3]):
            end += 1
        if language in RUN_LANGUAGES:
            block = Block(index + 1, language)
            apply_markers(path, block, markers, errors)
            commands.extend(block_commands(lines, index + 1, end, block))
        elif markers:
            errors.append(f"{path}:{markers[0][0]}: docs-test marker on a block that is never run "
                          f"({language or 'untagged'})")
        index = end + 1
    return commands, errors


def block_commands(lines, start, end, block):
    if block.language not in SHELL_LANGUAGES:
        command = Command(start + 1, f"{block.language} block of {end - start} lines", block)
        command.script = "\n".join(lines[start:end]) + "\n"
        return [command]
    commands = []
    pending = None
    pending_line = 0
    for number in range(start, end):
        line = lines[number]
        if pending is None:
            if block.language == "console":
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
        commands.append(Command(pending_line, pending.strip(), block))
        pending = None
    if pending is not None:
        commands.append(Command(pending_line, pending.strip(), block))
    return commands


def apply_replacements(commands, errors, document):
    """Each block's replace markers, on its shell commands; every OLD must occur in the block."""
    for block in {id(c.block): c.block for c in commands}.values():
        texts = "\n".join(c.text for c in commands if c.block is block)
        for old, new in block.replacements:
            if old not in texts:
                errors.append(f"{document}:{block.line}: docs-test replace: '{old}' occurs in no command of the block")
    for command in commands:
        for old, new in command.block.replacements:
            command.text = command.text.replace(old, new)


def mark_not_built(commands, not_built, module_built):
    """Skips the commands that need a program (or the Python module) this build lacks;
    returns how many it skipped that way."""
    count = 0
    for command in commands:
        if command.skip_reason is not None:
            continue
        text = command.script if command.script is not None else command.text
        missing = [name for name in not_built if re.search(r"(^|[\s/;&|])" + re.escape(name) + r"\b", text)]
        if command.block.scene:
            missing += [name for name in not_built if name == "offlineSimulator"]
        # A Python block or a shell command (python3 -c "import asyncfem ...") that needs the module.
        if not module_built and re.search(r"\bimport asyncfem\b", text):
            missing.append("the asyncfem Python module")
        if missing:
            command.skip_reason = "not in this build: " + ", ".join(missing)
            count += 1
    return count


def prepare_scratch(scratch, repository, bin_dir, python_path):
    if os.path.isdir(scratch):
        shutil.rmtree(scratch)
    os.makedirs(os.path.join(scratch, "build"))
    os.symlink(os.path.abspath(bin_dir), os.path.join(scratch, "build", "bin"))
    if python_path:
        os.symlink(os.path.abspath(python_path), os.path.join(scratch, "build", "python"))
    for folder in DATA_FOLDERS:
        source = os.path.join(repository, folder)
        if os.path.isdir(source):
            shutil.copytree(source, os.path.join(scratch, folder))


def tail(text, count):
    kept = text.strip().split("\n")[-count:]
    return "\n".join("      | " + line for line in kept)


def without_comments(text):
    """JSON text without // comments (scene files may carry them), strings left alone."""
    kept = []
    index, in_string = 0, False
    while index < len(text):
        char = text[index]
        if in_string:
            kept.append(char)
            if char == "\\":
                kept.append(text[index + 1])
                index += 1
            elif char == '"':
                in_string = False
        elif text.startswith("//", index):
            index = text.find("\n", index)
            if index < 0:
                break
            continue
        else:
            in_string = char == '"'
            kept.append(char)
        index += 1
    return "".join(kept)


def json_command(command, scratch):
    """The shell command that checks a json block: it must parse (a fragment as the members
    of an object), and with a scene marker run as part of that scene."""
    text = command.script.strip()
    try:
        value = json.loads(text if text.startswith("{") else "{" + text + "}")
    except json.JSONDecodeError as error:
        return None, f"does not parse as JSON ({error})"
    if not command.block.scene:
        return "true", None
    with open(os.path.join(scratch, command.block.scene), encoding="utf-8") as handle:
        scene = json.loads(without_comments(handle.read()))
    merged = copy.deepcopy(scene)
    merged.update(value)
    target = os.path.join(os.path.dirname(command.block.scene), f"docs-snippet-{command.line}.json")
    with open(os.path.join(scratch, target), "w", encoding="utf-8") as handle:
        json.dump(merged, handle, indent=1)
    return f"offlineSimulator {target} --frames 2 --output docs-snippet-{command.line}.afsim", None


def shell_of(command, scratch, python):
    """The bash command line that runs a command, or (None, error) when it cannot run."""
    if command.block.language == "python":
        path = os.path.join(scratch, f"docs-snippet-{command.line}.py")
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(command.script)
        return f"{python} {os.path.basename(path)}", None
    if command.block.language == "json":
        return json_command(command, scratch)
    return command.text, None


def run_one(shell, scratch, environment, timeout):
    """(status, output: stdout and stderr merged, seconds, CPU seconds) of one bash command."""
    begin = time.monotonic()
    cpu_before = resource.getrusage(resource.RUSAGE_CHILDREN)
    # Its own process group, so that a timeout stops everything the command started.
    process = subprocess.Popen(["bash", "-o", "pipefail", "-c", shell], cwd=scratch, env=environment,
                               stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               errors="replace", start_new_session=True)
    try:
        output, _ = process.communicate(timeout=timeout)
        status = process.returncode
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        output, _ = process.communicate()
        status = "timeout"
    cpu_after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (cpu_after.ru_utime - cpu_before.ru_utime) + (cpu_after.ru_stime - cpu_before.ru_stime)
    return status, output, time.monotonic() - begin, cpu


def check_expectations(commands, failures):
    """Each block whose commands all ran and passed must print what its expect markers say."""
    failed = {id(command.block) for command, _, _ in failures}
    for block in {id(c.block): c.block for c in commands}.values():
        ran = all(c.skip_reason is None for c in commands if c.block is block)
        if not block.expects or not ran or id(block) in failed:
            continue
        first = next(c for c in commands if c.block is block)
        for pattern in block.expects:
            if not pattern.search(block.output):
                failures.append((first, f"its output does not match the expect marker /{pattern.pattern}/",
                                 block.output))


def parse_arguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("document", help="Markdown file, relative to --repository")
    parser.add_argument("--repository", required=True, help="source tree (the documents and the data folders)")
    parser.add_argument("--bin", required=True, help="the build's bin folder")
    parser.add_argument("--scratch", required=True, help="folder to run in (deleted and recreated)")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds per command (default 120)")
    parser.add_argument("--list", action="store_true", help="print the commands and skips, run nothing")
    parser.add_argument("--python", default=sys.executable, help="interpreter for python blocks")
    parser.add_argument("--python-path", default="",
                        help="folder holding the asyncfem package (build/python); empty: not built")
    parser.add_argument("--not-built", default="",
                        help="comma-separated programs this build does not have: commands using them are "
                        "skipped with that reason (e.g. frameRenderer without ASYNCFEM_WITH_RENDER)")
    return parser.parse_args()


def run_commands(args, to_run):
    prepare_scratch(args.scratch, args.repository, args.bin, args.python_path)
    environment = dict(os.environ)
    environment["PATH"] = os.path.abspath(args.bin) + os.pathsep + environment.get("PATH", "")
    if args.python_path:
        environment["PYTHONPATH"] = os.path.abspath(args.python_path)
    environment.setdefault("OMP_WAIT_POLICY", "passive")
    environment.setdefault("MPLBACKEND", "Agg")
    failures = []
    cpu_total = 0.0
    for command in to_run:
        shell, error = shell_of(command, args.scratch, args.python)
        if error:
            failures.append((command, error, command.script))
            print(f"FAIL    0.0 s                {args.document}:{command.line}: {command.text}", flush=True)
            continue
        status, output, seconds, cpu = run_one(shell, args.scratch, environment, args.timeout)
        command.block.output += output
        cpu_total += cpu
        ok = status == 0
        print(f"{'ok  ' if ok else 'FAIL'} {seconds:6.1f} s ({cpu:6.1f} s CPU)  {args.document}:{command.line}: "
              f"{command.text}", flush=True)
        if not ok:
            reason = f"exceeded {args.timeout:g} s" if status == "timeout" else f"exit status {status}"
            failures.append((command, reason, output))
    return failures, cpu_total


def report(args, to_run, skipped, failures, seconds, cpu_total):
    print(f"\n{args.document}: {len(to_run)} commands run in {seconds:.1f} s ({cpu_total:.1f} s CPU), "
          f"{len(failures)} failed, {len(skipped)} skipped")
    for command in skipped:
        print(f"  skipped {args.document}:{command.line}: {command.text}\n    reason: {command.skip_reason}")
    if failures:
        print("\nFailed commands:")
        for command, reason, output in failures:
            print(f"  {args.document}:{command.line}: {command.text}\n    {reason}; end of its output:")
            print(tail(output, 15) if output and output.strip() else "      | (nothing)")


def main():
    args = parse_arguments()
    document = os.path.join(args.repository, args.document)
    commands, errors = extract(document)
    apply_replacements(commands, errors, args.document)
    for error in errors:
        print(error)
    if errors:
        return 1
    not_built = [name for name in args.not_built.split(",") if name]
    module_built = bool(args.python_path) and os.path.isdir(os.path.join(args.python_path, "asyncfem"))
    unbuilt = mark_not_built(commands, not_built, module_built)
    to_run = [c for c in commands if c.skip_reason is None]
    skipped = [c for c in commands if c.skip_reason is not None]
    if args.list:
        for command in commands:
            state = "skip (" + command.skip_reason + ")" if command.skip_reason else "run"
            print(f"{args.document}:{command.line}: {state}: {command.text}")
        print(f"{len(to_run)} to run, {len(skipped)} skipped")
        return 0
    if not to_run:
        report(args, to_run, skipped, [], 0.0, 0.0)
        if unbuilt:
            print(f"{args.document}: SKIPPED: every command needs what this build does not have")
            return SKIPPED
        print(f"{args.document}: FAILED: no command to run (a docs test that runs nothing checks nothing)")
        return 1
    started = time.monotonic()
    failures, cpu_total = run_commands(args, to_run)
    check_expectations(commands, failures)
    report(args, to_run, skipped, failures, time.monotonic() - started, cpu_total)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
