#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The docs runner itself: a document whose output differs from its expect marker, one with
nothing to run, a replace marker whose text is not there and a malformed fragment fail;
one whose every command needs what the build lacks is skipped (77); python blocks, json
fragments, expect and replace markers work. Runs in a second (no program of the build)."""

import os
import subprocess
import sys
import tempfile

RUNNER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "runDocCommands.py")

CASES = [
    # (name, document text, expected exit status, text the output must contain)
    ("expect-mismatch", "<!-- docs-test: expect ^hello$ -->\n```sh\necho goodbye\n```\n", 1,
     "does not match the expect marker /^hello$/"),
    ("expect-match", "<!-- docs-test: expect ^hel+o$ -->\n```sh\necho hello\n```\n", 0, "1 commands run"),
    ("nothing-to-run", "Prose.\n\n```\nsynopsis only\n```\n", 1, "no command to run"),
    ("all-skipped-by-marker", "<!-- docs-test: skip installs things -->\n```sh\nfalse\n```\n", 1,
     "no command to run"),
    ("not-built", "```sh\nofflineSimulator x.json\n```\n", 77, "not in this build: offlineSimulator"),
    ("replace", "<!-- docs-test: replace --frames 90 => --frames 2 -->\n<!-- docs-test: expect ^run --frames 2$ -->\n"
     "```sh\necho run --frames 90\n```\n", 0, "echo run --frames 2"),
    ("replace-missing", "<!-- docs-test: replace --frames 9 => --frames 1 -->\n```sh\necho run\n```\n", 1,
     "'--frames 9' occurs in no command"),
    ("python", "<!-- docs-test: expect ^6$ -->\n```python\nprint(2 * 3)\n```\n", 0, "python block of 1 lines"),
    ("python-fails", "```python\nraise SystemExit(3)\n```\n", 1, "exit status 3"),
    ("module-not-built", "```sh\npython3 -c \"import asyncfem\"\n```\n", 77,
     "not in this build: the asyncfem Python module"),
    ("json-fragment", '```json\n"forces": [{"type": "pull"}]\n```\n', 0, "json block of 1 lines"),
    ("json-broken", '```json\n"forces": [{"type": }]\n```\n', 1, "does not parse as JSON"),
    ("unknown-marker", "<!-- docs-test: sometimes -->\n```sh\ntrue\n```\n", 1, "unknown or malformed"),
    ("failing-command", "```console\n$ exit 4\nexample output\n```\n", 1, "exit status 4"),
]


def run_case(folder, name, text):
    os.makedirs(os.path.join(folder, "docs"), exist_ok=True)
    document = os.path.join("docs", name + ".md")
    with open(os.path.join(folder, document), "w", encoding="utf-8") as handle:
        handle.write(text)
    os.makedirs(os.path.join(folder, "bin"), exist_ok=True)
    return subprocess.run([sys.executable, RUNNER, document, "--repository", folder, "--bin",
                           os.path.join(folder, "bin"), "--scratch", os.path.join(folder, "scratch", name),
                           "--python", sys.executable, "--not-built", "offlineSimulator"],
                          capture_output=True, text=True, timeout=60)


def main():
    failures = []
    with tempfile.TemporaryDirectory() as folder:
        for name, text, status, needle in CASES:
            result = run_case(folder, name, text)
            if result.returncode != status or needle not in result.stdout:
                failures.append(f"{name}: exit {result.returncode} (expected {status}), output lacks {needle!r}:\n"
                                f"{result.stdout}{result.stderr}")
    for failure in failures:
        print("FAIL", failure)
    print(f"{len(CASES) - len(failures)} of {len(CASES)} runner cases behave as documented")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
