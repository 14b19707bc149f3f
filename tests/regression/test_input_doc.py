# SPDX-License-Identifier: BSD-3-Clause
"""The input reference doc/user/input.md lists exactly the namelist groups and keys that dem
accepts, in their order. They are asked of the program, from its messages: an unknown group's
lists the groups (dem_input's table, whose names are checked here against the `namelist`
statements of io/), an unknown key's lists the keys of its group, which dem draws from the
group's `namelist` statement, the one declaration of its keys (io/dem_input_group.f90).
usage: test_input_doc.py DEM WORKDIR"""
import glob
import os
import re
import shutil
import subprocess
import sys

from regression_util import ROOT, check, finish

dem, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

# a valid case, read up to its last group
GOOD = """&run dt = 1e-7, t_end = 1e-5, gravity = 0, 0, 0 /
&output interval = 1e-6 /
&material name = 'glass', density = 2800.0, youngs_modulus = 48.0e9, poisson_ratio = 0.2 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&particle material = 'glass', radius = 0.01, position = 0, 0, 0.011 /
"""


def refusal(name, text):
    """dem --check's message on the case `text`."""
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    r = subprocess.run([dem, "--check", path], cwd=work, capture_output=True, text=True,
                       timeout=60)
    check(r.returncode == 2, f"{name}: exit code {r.returncode}, expected 2 ({r.stderr.strip()})")
    return r.stderr


# the groups, in order
msg = refusal("unknown_group", GOOD + "&no_such_group /\n")
m = re.search(r"unknown namelist group \(accepted: ([^)]*)\)", msg)
check(m is not None, f"an unknown group's message lists no groups: {msg.strip()}")
groups = [g.strip().lstrip("&") for g in m.group(1).split(",")] if m else []
named = set()
for path in glob.glob(os.path.join(ROOT, "io", "*.f90")):
    with open(path) as f:
        named |= set(re.findall(r"^\s*namelist\s*/(\w+)/", f.read(), re.M | re.I))
check(sorted(groups) == sorted(named),
      f"the groups dem accepts {groups} are those of the namelist statements {sorted(named)}")

# each group's keys, in order: an unknown key put into the group's first occurrence in GOOD,
# or into a group of its own
declared = {}
for group in groups:
    if re.search(rf"^&{group} ", GOOD, re.M):
        text = re.sub(rf"^&{group} ", f"&{group} no_such_key = 1, ", GOOD, count=1, flags=re.M)
    else:
        text = GOOD + f"&{group} no_such_key = 1 /\n"
    msg = refusal(group, text)
    m = re.search(rf"&{group}: unknown key 'no_such_key' \(accepted: ([\w ]+)\)", msg)
    check(m is not None, f"&{group}: the message lists no keys: {msg.strip()}")
    declared[group] = m.group(1).split() if m else []

# doc/user/input.md: a section per group with a table row per key
with open(os.path.join(ROOT, "doc", "user", "input.md")) as f:
    doc = f.read()
sections = dict(re.findall(r"^## &(\w+)[^\n]*\n(.*?)(?=^## |\Z)", doc, re.S | re.M))
check(set(sections) == set(declared), f"doc sections {sorted(sections)} vs {sorted(declared)}")
for group, keys in declared.items():
    documented = re.findall(r"^\| `(\w+)` \|", sections.get(group, ""), re.M)
    check(documented == keys, f"&{group}: doc/user/input.md lists {documented}, dem {keys}")
finish()
