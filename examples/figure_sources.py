#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The record of where each example's figures come from: doc/figures/examples/EXAMPLE.sources,
written by examples/make-figures after it has made the example's figures, holds

  command LINE        each command make-figures ran (examples/make-figures --commands EXAMPLE)
  input SHA256 PATH   each file those commands read: every file of examples/EXAMPLE/ but its
                      README.md and its PNG files, every file its namelists name (`file`,
                      `mesh_file`), and scripts/post/paraview-snapshot.py when a command
                      draws a picture
  figure SHA256 PATH  each figure they wrote (the --png of each command)

and, as comments, the solver's version and the Python that drew the pictures. `check` finds
what differs from the tree now: a namelist, a data file, a script, a command or a figure
changed since the figures were made (tests/regression/test_example_figures.py).

usage: .venv/bin/python examples/figure_sources.py record EXAMPLE [--solver S] [--pictures P]
       .venv/bin/python examples/figure_sources.py check [EXAMPLE ...]
(from the repository root)"""
import argparse
import hashlib
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PICTURES = "scripts/post/paraview-snapshot.py"


def examples(root=ROOT):
    """The examples make-figures knows, in its order."""
    return run_make_figures(root, "--list").split()


def run_make_figures(root, *args):
    r = subprocess.run(["bash", os.path.join(root, "examples", "make-figures"), *args],
                       cwd=root, capture_output=True, text=True, check=True)
    return r.stdout


def sha256(path):
    if not os.path.isfile(path):
        return "missing"
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def inputs(example, commands, root=ROOT):
    """The files the example's commands read, as paths from the repository root."""
    folder = os.path.join(root, "examples", example)
    found = set()
    for name in os.listdir(folder):
        path = os.path.join(folder, name)
        if os.path.isfile(path) and name != "README.md" and not name.endswith(".png"):
            found.add(path)
            if name.endswith(".nml"):
                with open(path) as f:
                    text = f.read()
                for m in re.finditer(r"\b(?:mesh_)?file\s*=\s*'([^']+)'", text):
                    found.add(os.path.normpath(os.path.join(folder, m.group(1))))
    if any("${snap[@]}" in c for c in commands):
        found.add(os.path.join(root, PICTURES))
    return sorted(os.path.relpath(p, root) for p in found)


def expected(example, root=ROOT):
    """The record's lines (comments left out) for the tree as it is now."""
    commands = run_make_figures(root, "--commands", example).splitlines()
    figures = [m.group(1) for c in commands for m in re.finditer(r"--png (\S+)", c)]
    return ([f"command {c}" for c in commands]
            + [f"input {sha256(os.path.join(root, p))} {p}"
               for p in inputs(example, commands, root)]
            + [f"figure {sha256(os.path.join(root, p))} {p}" for p in figures])


def record_path(example, root=ROOT):
    return os.path.join(root, "doc", "figures", "examples", f"{example}.sources")


def recorded(example, root=ROOT):
    """The committed record's lines, comments left out (None: there is none)."""
    path = record_path(example, root)
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        return [line.rstrip("\n") for line in f if line.strip() and not line.startswith("#")]


def figures(example, root=ROOT):
    """The figures the example's record names."""
    return [line.split()[2] for line in recorded(example, root) or []
            if line.startswith("figure ")]


def check(example, root=ROOT):
    """What differs between the example's record and the tree: a list of lines, each
    '- LINE' (recorded, not so now) or '+ LINE' (so now, not recorded); [] when current."""
    old = recorded(example, root)
    if old is None:
        return [f"no {os.path.relpath(record_path(example, root), root)}"]
    new = expected(example, root)
    return ([f"- {line}" for line in old if line not in new]
            + [f"+ {line}" for line in new if line not in old])


def record(example, solver, pictures, root=ROOT):
    lines = expected(example, root)
    missing = [line for line in lines if line.startswith("figure missing")]
    if missing:
        sys.exit(f"figure_sources.py: {example}: {', '.join(missing)}")
    with open(record_path(example, root), "w") as f:
        f.write(f"# examples/make-figures {example}: its commands, the SHA-256 of the files "
                "they read and of the figures they wrote\n"
                f"# (examples/figure_sources.py); solver: {solver}; pictures: {pictures}\n")
        f.write("".join(line + "\n" for line in lines))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("action", choices=["record", "check"])
    ap.add_argument("example", nargs="*")
    ap.add_argument("--solver", default="unknown", help="the solver's --version")
    ap.add_argument("--pictures", default="unknown", help="the Python that drew pictures")
    a = ap.parse_args()
    if a.action == "record":
        for e in a.example:
            record(e, a.solver, a.pictures)
        return 0
    stale = 0
    for e in a.example or examples():
        diff = check(e)
        print(f"{e}: {'current' if not diff else 'not current'}")
        for line in diff:
            print("   ", line)
        stale += bool(diff)
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
