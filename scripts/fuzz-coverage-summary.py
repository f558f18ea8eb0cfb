#!/usr/bin/env python3
"""Summarise `llvm-cov export -summary-only` JSON (stdin) for scripts/fuzz-coverage.sh.

Usage: fuzz-coverage-summary.py TARGET REPO_ROOT

Prints one line `TOTAL <target> <covered> <lines> <percent> <linked>` and then, per source
file of the repository that the target entered, the lines covered out of the lines that file
has. TOTAL counts over those files only; <linked> is the line count of all the project code
linked into the target, most of which (the CLI, the network servers) no target input reaches.
"""
import json
import os
import sys


def main() -> None:
    target, repo = sys.argv[1], os.path.realpath(sys.argv[2])
    data = json.load(sys.stdin)
    entered = []
    linked = 0
    for export in data["data"]:
        for f in export["files"]:
            path = os.path.realpath(f["filename"])
            if not path.startswith(repo + os.sep):
                continue
            lines = f["summary"]["lines"]
            linked += lines["count"]
            if lines["covered"]:
                entered.append((os.path.relpath(path, repo), lines["covered"], lines["count"]))
    covered_all = sum(c for _, c, _ in entered)
    lines_all = sum(n for _, _, n in entered)
    pct = 100.0 * covered_all / lines_all if lines_all else 0.0
    print(f"TOTAL {target} {covered_all} {lines_all} {pct:.1f} {linked}")
    for path, covered, count in sorted(entered):
        print(f"  {path:<52} {covered:>6} / {count:<6} {100.0 * covered / count:5.1f}%")


if __name__ == "__main__":
    main()
