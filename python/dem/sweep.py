# SPDX-License-Identifier: BSD-3-Clause
"""Parameter sweeps: a case run once per value of namelist keys, each run in a folder of its
own, a measure taken of each (doc/user/python.md)."""
import os
import re

from .run import Run

_KEY = re.compile(r"([A-Za-z_]\w*)\s*=")


def _literal(value):
    """A Python value as a namelist value: strings quoted, logicals .true./.false., lists
    and tuples as comma-separated values."""
    if isinstance(value, bool):
        return ".true." if value else ".false."
    if isinstance(value, str):
        return "'" + value.replace("'", "''") + "'"
    if isinstance(value, (list, tuple)):
        return ", ".join(_literal(v) for v in value)
    if hasattr(value, "tolist"):                         # NumPy scalars and arrays
        return _literal(value.tolist())
    return repr(value)


def _groups(text):
    """(name, start, end) of every namelist group of `text`: text[start:end] runs from just
    after '&name' to its closing '/' (excluded). Quotes and '!' comments are skipped."""
    found = []
    k, n = 0, len(text)
    while k < n:
        c = text[k]
        if c == "!":
            k = text.find("\n", k)
            k = n if k < 0 else k
        elif c == "&":
            m = re.match(r"&(\w+)", text[k:])
            start = k + m.end()
            j, quote = start, None
            while j < n:
                d = text[j]
                if quote:
                    quote = None if d == quote else quote
                elif d in "'\"":
                    quote = d
                elif d == "!":
                    j = text.find("\n", j)
                    j = n if j < 0 else j
                    continue
                elif d == "/":
                    break
                j += 1
            found.append((m.group(1).lower(), start, j))
            k = j + 1
        else:
            k += 1
    return found


def _outside_quotes(body):
    """The spans of `body` outside quotes and comments, as a string of the same length with
    the quoted and commented characters replaced by spaces (to search keys in)."""
    out, quote, comment = [], None, False
    for d in body:
        if comment:
            comment = d != "\n"
            out.append(d if not comment else " ")
        elif quote:
            quote = None if d == quote else quote
            out.append(" ")
        elif d in "'\"":
            quote = d
            out.append(" ")
        elif d == "!":
            comment = True
            out.append(" ")
        else:
            out.append(d)
    return "".join(out)


def _set_in_group(body, key, value):
    """The group body with `key = value` (an existing key's values replaced, else added)."""
    plain = _outside_quotes(body)
    keys = list(_KEY.finditer(plain))
    for i, m in enumerate(keys):
        if m.group(1).lower() == key.lower():
            end = keys[i + 1].start() if i + 1 < len(keys) else len(body)
            tail = body[m.end():end]
            # keep the separator and spacing before the next key
            stripped = tail.rstrip()
            sep = ""
            if i + 1 < len(keys):
                sep = "," if stripped.endswith(",") else ""
            return (body[:m.end()] + " " + value + sep + tail[len(stripped):] + body[end:])
    body = body.rstrip()
    comma = "," if keys else ""
    return f"{body}{comma} {key} = {value} "


def set_values(text, changes):
    """The case text with namelist values changed: `changes` maps 'group.key' to a value
    (a number, string, logical or list) and sets the key in every &group of that name (a
    group absent from the case is added at the end)."""
    for spec, value in changes.items():
        group, _, key = spec.partition(".")
        if not key:
            raise ValueError(f"{spec!r}: expected 'group.key', as 'pair.friction'")
        literal = _literal(value)
        spans = [s for s in _groups(text) if s[0] == group.lower()]
        if not spans:
            text = text.rstrip("\n") + f"\n&{group} {key} = {literal} /\n"
            continue
        for name, start, end in reversed(spans):
            text = text[:start] + _set_in_group(text[start:end], key, literal) + text[end:]
    return text


def _absolute_files(text, folder):
    """File names of the case (keys `file` and `*_file`) made absolute, relative to
    `folder` (the original case's), so that the case can be written elsewhere."""
    def absolute(m):
        name = m.group(3)
        if os.path.isabs(name):
            return m.group(0)
        return f"{m.group(1)}{m.group(2)}{os.path.join(folder, name)}{m.group(2)}"
    return re.sub(r"(\b\w*file\s*=\s*)(['\"])([^'\"]*)\2", absolute, text, flags=re.I)


def write_case(case, changes, path, output_dir=None):
    """Write to `path` the case file `case` with `changes` (as set_values), its relative
    file names made absolute, and its &output dir set to `output_dir` when given (with
    overwrite, so that a sweep can be run again)."""
    with open(case) as f:
        text = f.read()
    text = _absolute_files(text, os.path.dirname(os.path.abspath(case)))
    changes = dict(changes)
    if output_dir is not None:
        changes.setdefault("output.dir", os.path.abspath(output_dir))
        changes.setdefault("output.overwrite", True)
    with open(path, "w") as f:
        f.write(set_values(text, changes))
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
