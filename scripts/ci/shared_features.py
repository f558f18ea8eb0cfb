#!/usr/bin/env python3
"""Checks that the root workspace and the two built apart from it (python/: the extension
module; fuzz/: the cargo-fuzz targets) resolve every dependency they share with the same version
and features, and build them with the same dev profile.

They share target/, and cargo reuses a dependency's build only when its features, and those of
everything below it, agree; one drifting package (say a new root dependency turning on
`num-traits/default`) silently makes CI compile rapier twice. The crate workspace-hack/ pins the
union and each folder's Cargo.toml repeats the root's [profile.dev] tables; this script names
what is missing. Python >= 3.11 (tomllib).

Usage, from the repository root: python3 scripts/ci/shared_features.py
Exit status 0 when the graphs agree, 1 with one line per drifting package otherwise.
"""
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def resolved_features(cwd, extra):
    """{"name vX.Y.Z": {feature sets}} as `cargo tree` resolves them for a build of cwd."""
    run = subprocess.run(
        ["cargo", "tree", "--locked", "-e", "normal,build,dev", "--prefix", "none",
         "-f", "{p}|{f}", *extra],
        cwd=cwd, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"cargo tree in {cwd} failed (exit {run.returncode}):\n{run.stderr}")
    out = run.stdout
    graph = {}
    for line in out.splitlines():
        if "|" not in line:
            continue
        package, features = line.split("|", 1)
        # "serde v1.0.1 (/path)" or "... (proc-macro)": keep name and version.
        name_version = " ".join(package.split()[:2])
        # cargo tree appends " (*)" to a package it has already printed.
        features = features.replace(" (*)", "").strip()
        graph.setdefault(name_version, set()).add(features)
    return graph


def compare(root, other, folder):
    """Lines naming each package `other` resolves unlike `root`."""
    drift = []
    for package in sorted(root.keys() & other.keys()):
        if root[package] != other[package]:
            drift.append(f"{folder}: {package}: root workspace {sorted(root[package])}, "
                         f"{folder} {sorted(other[package])}")
    root_versions = {p.split()[0]: p for p in root}
    for package in sorted(other.keys() - root.keys()):
        name = package.split()[0]
        if name in root_versions and not any(p.split()[0] == name for p in other if p in root):
            drift.append(f"{folder}: {package}: locked at another version than in the root "
                         f"workspace ({root_versions[name]})")
    return drift


def dev_profile(manifest, built=None):
    """The `[profile.dev]` table of a Cargo.toml, per-package overrides included; with `built`
    (the package names a folder builds), only the overrides of packages it builds: the root's
    override of its own harness crate means nothing to a folder that never builds it."""
    with open(manifest, "rb") as f:
        profile = dict(tomllib.load(f).get("profile", {}).get("dev", {}))
    if built is not None and "package" in profile:
        profile["package"] = {name: table for name, table in profile["package"].items()
                              if name in built}
    return profile


def main():
    root = resolved_features(ROOT, ["--workspace"])
    drift, shared = [], 0
    for folder in ("python", "fuzz"):
        other = resolved_features(ROOT / folder, [])
        drift += compare(root, other, f"{folder}/")
        shared += len(root.keys() & other.keys())
        # The opt-level of a dependency is part of its build's identity as much as features.
        built = {package.split()[0] for package in other}
        if dev_profile(ROOT / folder / "Cargo.toml", built) != dev_profile(ROOT / "Cargo.toml",
                                                                          built):
            drift.append(f"{folder}/Cargo.toml: [profile.dev] tables differ from the root "
                         "Cargo.toml's (copy them over)")
    if drift:
        print("shared dependencies resolve differently than in the root workspace, so "
              "these builds cannot reuse the root's (add the missing features to "
              "workspace-hack/Cargo.toml, align the folder's Cargo.lock or its profile):", file=sys.stderr)
        for line in drift:
            print(f"  {line}", file=sys.stderr)
        return 1
    print(f"python/ and fuzz/ resolve their {shared} shared dependencies as the root does")
    return 0


if __name__ == "__main__":
    sys.exit(main())
