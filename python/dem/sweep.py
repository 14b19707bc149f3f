# SPDX-License-Identifier: BSD-3-Clause
"""Parameter sweeps: a case run once per value of namelist keys, each run in a folder of its
own, a measure taken of each (doc/user/python.md)."""
import io
import os

import f90nml
from f90nml.scanner import scan

from .run import Run


def _plain(value):
    """A value as f90nml writes it: NumPy scalars and arrays as Python numbers and lists,
    tuples as lists."""
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, tuple):
        value = list(value)
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


def _pieces(text):
    """The text cut, by f90nml's scanner (quotes and '!' comments are its tokens), into
    [name, piece] pairs: a namelist group from its '&name' to its closing '/' (included),
    name in lower case; the text between groups (comments, blank lines) with name None.
    The pieces put together are the text."""
    pieces, tokens, name = [], [], None
    for token in scan(iter(text.splitlines(True))):
        if name is None and token == "&":
            if tokens:
                pieces.append([None, "".join(tokens)])
            tokens, name = [token], ""
            continue
        tokens.append(token)
        if name == "" and token.strip():
            name = token.lower()
        elif name and token == "/":
            pieces.append([name, "".join(tokens)])
            tokens, name = [], None
    if tokens:
        if name is not None:
            raise ValueError(f"namelist group &{name} has no closing '/'")
        pieces.append([None, "".join(tokens)])
    return pieces


def _patch(name, piece, values):
    """The text of the group `name` with `values` (key: value) set by f90nml: an existing
    key's values replaced in place, a new key added before the '/'; the rest (layout,
    comments) kept."""
    out = io.StringIO()
    # f90nml writes a token when it reads the next: the newline makes it write the '/'
    f90nml.Parser().read(io.StringIO(piece + "\n"), {name: values}, out)
    return out.getvalue()[:-1]


def _edit(text, edit):
    """The text with every group patched by edit(name, group), which gets the group's values
    as f90nml reads them (a Namelist, keys in lower case) and returns the keys to set (a
    dict, maybe empty)."""
    pieces = _pieces(text)
    for piece in pieces:
        name = piece[0]
        if name is not None:
            values = edit(name, f90nml.reads(piece[1])[name])
            if values:
                piece[1] = _patch(name, piece[1], values)
    return "".join(p for _, p in pieces)


def set_values(text, changes):
    """The case text with namelist values changed: `changes` maps 'group.key' to a value
    (a number, string, logical or list) and sets the key in every &group of that name (a
    group absent from the case is added at the end). Comments and layout are kept."""
    by_group = {}
    for spec, value in changes.items():
        group, _, key = spec.partition(".")
        if not key or not group:
            raise ValueError(f"{spec!r}: expected 'group.key', as 'pair.friction'")
        by_group.setdefault(group.lower(), {})[key.lower()] = _plain(value)
    seen = set()

    def edit(name, group):
        seen.add(name)
        return by_group.get(name)
    text = _edit(text, edit)
    for group, values in by_group.items():
        if group not in seen:
            text = text.rstrip("\n") + "\n" + str(f90nml.Namelist({group: values})) + "\n"
    return text


def _absolute_files(text, folder):
    """File names of the case (keys `file` and `*_file`) made absolute, relative to
    `folder` (the original case's), so that the case can be written elsewhere."""
    def edit(name, group):
        return {key: os.path.join(folder, value) for key, value in group.items()
                if key.endswith("file") and isinstance(value, str)
                and not os.path.isabs(value)}
    return _edit(text, edit)


def write_case(case, changes, path, output_dir=None):
    """Write to `path` the case file `case` with `changes` (as set_values), its relative
    file names made absolute, and its &output dir set to `output_dir` when given (with
    overwrite, so that a sweep can be run again). A case f90nml cannot read raises
    ValueError naming the file."""
    with open(case) as f:
        text = f.read()
    changes = dict(changes)
    if output_dir is not None:
        changes.setdefault("output.dir", os.path.abspath(output_dir))
        changes.setdefault("output.overwrite", True)
    try:
        text = set_values(_absolute_files(text, os.path.dirname(os.path.abspath(case))),
                          changes)
    except ValueError as e:
        raise ValueError(f"{case}: {e}") from None
    with open(path, "w") as f:
        f.write(text)
    return path


def _rank(comm):
    """This process's rank in `comm` (0 without mpi4py and without a communicator)."""
    if comm is not None and hasattr(comm, "Get_rank"):
        return comm.Get_rank()
    try:
        from mpi4py import MPI
        return MPI.COMM_WORLD.Get_rank()
    except ImportError:
        return 0


def _barrier(comm):
    """Wait for every rank (only with mpi4py: without it a run has one rank)."""
    try:
        from mpi4py import MPI
    except ImportError:
        return
    (comm if comm is not None and hasattr(comm, "Barrier") else MPI.COMM_WORLD).Barrier()


def sweep(case, key, values, measure, work_dir="sweep", until=None, comm=None,
          library=None):
    """Run the case once per value of `key` ('group.key', as 'pair.friction'; or a tuple
    of keys that all take the value) and return [(value, measure(run)), ...].

    Each run's case and outputs go to work_dir/<k> (k = 0, 1, ...). With `until` [s], the
    run is first advanced to that time (in one advance, sub-stepped at the case's dt); then
    measure(run) is called with the open run, may advance it further and read it, and its
    result is kept; the run is closed after it. Collective: on several ranks every rank runs
    every case, and measure is called on every rank."""
    keys = (key,) if isinstance(key, str) else tuple(key)
    results = []
    for k, value in enumerate(values):
        folder = os.path.abspath(os.path.join(work_dir, str(k)))
        path = os.path.join(folder, os.path.basename(case))
        if _rank(comm) == 0:
            os.makedirs(folder, exist_ok=True)
            write_case(case, {name: value for name in keys}, path,
                       output_dir=os.path.join(folder, "output"))
        _barrier(comm)
        with Run(path, comm=comm, library=library) as run:
            if until is not None and until > run.time:
                run.advance(until - run.time)
            results.append((value, measure(run)))
    return results
