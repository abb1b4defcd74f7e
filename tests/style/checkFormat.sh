#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Fails when a tracked C++ file differs from what the committed .clang-format produces,
# and lists the files. Exit 77 (reported by ctest as skipped, never as passed) when the
# pinned clang-format is missing or the tree is not a git checkout.
set -uo pipefail
src="$1"
fmt=""
for c in clang-format-14 clang-format; do
  if command -v "$c" >/dev/null && "$c" --version | grep -q "version 14\."; then fmt="$c"; break; fi
done
if [[ -z "$fmt" ]]; then echo "checkFormat: clang-format 14 not found (scripts/install-deps.sh installs it)"; exit 77; fi
cd "$src" || exit 1
if ! files=$(git ls-files '*.cpp' '*.hpp' '*.h' 2>/dev/null); then echo "checkFormat: not a git checkout"; exit 77; fi
bad=()
checked=0
for f in $files; do
  checked=$((checked + 1))
  "$fmt" --dry-run -Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done
if ((${#bad[@]})); then
  echo "checkFormat: ${#bad[@]} of $checked files differ from .clang-format (fix: $fmt -i FILE):"
  printf '  %s\n' "${bad[@]}"
  exit 1
fi
echo "checkFormat: $checked files match .clang-format"
