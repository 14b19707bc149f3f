# SPDX-License-Identifier: BSD-3-Clause
"""The committed figures of the examples are those examples/make-figures drew from the
examples as they are now: for every example make-figures knows, its record
doc/figures/examples/EXAMPLE.sources (examples/figure_sources.py) names the commands
make-figures runs now, the SHA-256 of every file they read as it is now, and the SHA-256 of
every figure as committed; every PNG of doc/figures/examples/ and examples/ is a figure of a
record; every figure an example's README shows is one. And the check can fail: in a copy of
one example, recorded there, a namelist changed by one byte, a figure changed by one byte
and a command changed are each found.

usage: test_example_figures.py DEM WORKDIR   (DEM unused: nothing is run)"""
import glob
import os
import re
import shutil
import sys

from regression_util import ROOT, check, finish

sys.path.insert(0, os.path.join(ROOT, "examples"))
import figure_sources as fs  # noqa: E402  (make-figures' record of its figures)

work = os.path.abspath(sys.argv[2])
names = fs.examples()
check(len(names) == 8, f"make-figures knows the eight examples: {names}")
recorded = set()
for e in names:
    diff = fs.check(e)
    check(not diff, f"{e}: the figures are not those of the example as it is now "
          f"(examples/make-figures {e} draws them again):\n  " + "\n  ".join(diff))
    recorded.update(fs.figures(e))

pngs = {os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, "doc", "figures",
                                                                 "examples", "*.png"))
        + glob.glob(os.path.join(ROOT, "examples", "*", "*.png"))}
check(pngs == recorded, f"every committed PNG is a figure make-figures draws: not drawn "
      f"{sorted(pngs - recorded)}, drawn but not committed {sorted(recorded - pngs)}")
records = {os.path.basename(p)[:-len(".sources")]
           for p in glob.glob(os.path.join(ROOT, "doc", "figures", "examples", "*.sources"))}
check(records == set(names), f"a record for each example, none other: {sorted(records)}")

for e in names:
    readme = os.path.join(ROOT, "examples", e, "README.md")
    with open(readme) as f:
        shown = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", f.read())
    for link in shown:
        path = os.path.relpath(os.path.normpath(os.path.join(os.path.dirname(readme), link)),
                               ROOT)
        check(path in recorded, f"{e}: README.md shows {link}, a figure make-figures draws")

# the check finds a changed input, figure and command (a copy of the clumps example,
# recorded there)
shutil.rmtree(work, ignore_errors=True)
for part in ("examples/clumps", "scripts/post"):
    shutil.copytree(os.path.join(ROOT, part), os.path.join(work, part))
for part in ["examples/make-figures", "examples/figure_sources.py"] + [
        os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, "doc", "figures",
                                                                 "examples", "clumps*"))]:
    os.makedirs(os.path.dirname(os.path.join(work, part)), exist_ok=True)
    shutil.copy2(os.path.join(ROOT, part), os.path.join(work, part))
fs.record("clumps", "none", "none", work)
check(fs.check("clumps", work) == [], "the copy of the clumps example, recorded, is current")
for part, old, new in (("examples/clumps/clumps.nml", "t_end = 1.0", "t_end = 1.1"),
                       ("doc/figures/examples/clumps.png", None, None),
                       ("examples/make-figures", "clumps --time 0.6", "clumps --time 0.7")):
    path = os.path.join(work, part)
    with open(path, "rb") as f:
        saved = f.read()
    changed = saved + b"\0" if old is None else saved.replace(old.encode(), new.encode(), 1)
    with open(path, "wb") as f:
        f.write(changed)
    diff = fs.check("clumps", work)
    check(changed != saved and len(diff) == 2 and (part in diff[0] or old in diff[0]),
          f"a change of {part} is found: {diff}")
    with open(path, "wb") as f:
        f.write(saved)
print(f"{len(names)} examples, {len(recorded)} figures: each that of the example as it is")
finish()
