"""The input reference doc/user/input.md lists exactly the namelist groups and keys that
io/dem_input.f90 declares (its `namelist /group/ ...` statements and its `input_groups`
table, which gives the accepted keys in error messages).
usage: test_input_doc.py DEM WORKDIR   (neither is used)"""
import os
import re

from regression_util import ROOT, check, finish

source = open(os.path.join(ROOT, "io", "dem_input.f90")).read()
doc = open(os.path.join(ROOT, "doc", "user", "input.md")).read()

# namelist statements (with continuation lines)
declared = {}
for m in re.finditer(r"namelist\s*/(\w+)/\s*((?:[^\n&]*&\s*\n)*[^\n]*)", source):
    declared[m.group(1)] = re.findall(r"\w+", m.group(2).replace("&", " "))
check(len(declared) == 13, f"found {len(declared)} namelist groups in the source")

# the input_groups table
joined = re.sub(r"' // &\s*\n\s*'", "", source)      # continued string literals
table = dict(re.findall(r"'(\w+): ([\w ]+)'", joined))
check(set(table) == set(declared), f"input_groups {sorted(table)} vs namelists {sorted(declared)}")
for group, keys in declared.items():
    check(table.get(group, "").split() == keys,
          f"&{group}: input_groups lists {table.get(group)}, the namelist {keys}")

# doc/user/input.md: a section per group with a table row per key
sections = dict(re.findall(r"^## &(\w+)[^\n]*\n(.*?)(?=^## |\Z)", doc, re.S | re.M))
check(set(sections) == set(declared), f"doc sections {sorted(sections)} vs {sorted(declared)}")
for group, keys in declared.items():
    documented = re.findall(r"^\| `(\w+)` \|", sections.get(group, ""), re.M)
    check(documented == keys, f"&{group}: doc/user/input.md lists {documented}, the source {keys}")
finish()
