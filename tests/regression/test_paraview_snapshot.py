# SPDX-License-Identifier: BSD-3-Clause
"""scripts/post/paraview-snapshot.py on a small run (60 spheres and two clumps falling into a
box), with each backend that is installed: ParaView's pvpython (with an Xvfb server when there is no
display) and each Python with a vtk module (this Python, .venv's, /usr/bin/python3; with
--backend vtk; tried without a display first; a vtk that renders through X, with no display
and no Xvfb, must stop with a clear error instead); each must write a PNG of the size asked for
that is not blank (more than 50 colours; more than 2 % of the pixels neither the white
background nor one flat colour) and say how many particles it drew. Also the XDMF index's
material table: its Information element names the materials of the snapshot's
/materials/name, in order, and the walls carry their material as a cell attribute. Exits 77
(CTest's SKIP_RETURN_CODE) when neither backend is found.
The run holds two clumps of three spheres too (66 particles): each Python's VTK XDMF reader
must give the orientation as four scalars a particle, orientation_q0 .. orientation_q3, equal
to the snapshot's /particles/orientation (VTK 9.1's reader took a 4-component 'Vector' as 3
components, and a 'Matrix' as one matrix that it failed to allocate for a few thousand
particles).
usage: test_paraview_snapshot.py DEM WORKDIR"""
import os
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import h5py
import numpy as np

from regression_util import ROOT, check, finish

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
SCRIPT = os.path.join(ROOT, "scripts", "post", "paraview-snapshot.py")

CASE = """&run dt = 1e-5, t_end = 0.05 /
&output dir = 'out', snapshot_interval = 0.025 /
&material name = 'glass beads', density = 2500.0, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&material name = 'steel<&>', density = 7800.0, youngs_modulus = 2e11, poisson_ratio = 0.3 /
&pair materials = 'glass beads', 'glass beads', restitution = 0.5, friction = 0.5 /
&pair materials = 'glass beads', 'steel<&>', restitution = 0.5, friction = 0.5 /
&wall_plane material = 'steel<&>', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.02 /
&wall_plane material = 'steel<&>', point = -0.02, 0, 0.02, normal = 1, 0, 0,
            half_width = 0.02 /
&insert n = 60, material = 'glass beads', radius_min = 1.5e-3, radius_max = 2e-3,
        box_min = -0.018, -0.018, 0.002, box_max = 0.018, 0.018, 0.03,
        velocity = 0, 0, -0.5 /
&clump_template name = 'rod', material = 'glass beads',
    members = -0.0015, 0, 0, 0.0015,   0, 0, 0, 0.0015,   0.0015, 0, 0, 0.0015 /
&clump template = 'rod', position = -0.01, 0, 0.035, orientation = 0.8, 0.6, 0, 0 /
&clump template = 'rod', position = 0.01, 0, 0.035 /
"""
with open(os.path.join(work, "small.nml"), "w") as f:
    f.write(CASE)
r = subprocess.run([dem, "small.nml"], cwd=work, capture_output=True, text=True, timeout=300)
check(r.returncode == 0, f"dem small.nml: exit {r.returncode}: {r.stderr[-2000:]}")
out = os.path.join(work, "out")
snaps = sorted(os.listdir(os.path.join(out, "snapshots")))
with h5py.File(os.path.join(out, "snapshots", snaps[-1]), "r") as h5:   # t = 0.05 s
    last_orientation = h5["particles/orientation"][()]

# the material table of the index (names with XML's special characters, escaped)
root = ET.parse(os.path.join(out, "snapshots.xmf")).getroot()
info = root.find("Domain").find("Information")
check(info is not None and info.get("Name") == "materials" and
      info.get("Value") == "1 glass beads; 2 steel<&>",
      f"snapshots.xmf: the material table ({None if info is None else info.attrib})")
walls = [g for g in root.iter("Grid") if g.get("Name") == "walls"]
check(walls and all(any(a.get("Name") == "material" and a.get("Center") == "Cell" and
                        a.find("DataItem").text.endswith(":/walls/material")
                        for a in g.findall("Attribute")) for g in walls),
      "snapshots.xmf: every walls grid has the cell attribute material (/walls/material)")


def png_pixels(path):
    """Width, height and the RGB pixels (0 to 255) of a PNG."""
    with open(path, "rb") as f:
        check(f.read(8) == b"\x89PNG\r\n\x1a\n", f"{path}: a PNG")
    from matplotlib.image import imread
    img = np.round(imread(path)[:, :, :3] * 255).astype(np.int64)
    return img.shape[1], img.shape[0], img


class Display:
    """An X server of our own (Xvfb, 24-bit, no authorisation, on a free display number)
    for the backends that need one when there is none: steadier than xvfb-run, whose
    authorisation files and 8-bit default screen failed now and then beside other runs."""
    def __init__(self):
        self.proc, self.env = None, None

    def get(self):
        if self.env is not None or not shutil.which("Xvfb"):
            return self.env
        for n in range(140, 200):
            if not os.path.exists(f"/tmp/.X{n}-lock") and \
                    not os.path.exists(f"/tmp/.X11-unix/X{n}"):
                break
        self.proc = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "1280x1024x24",
                                      "-nolisten", "tcp"], stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL)
        for _ in range(100):
            if os.path.exists(f"/tmp/.X11-unix/X{n}"):
                break
            time.sleep(0.1)
        time.sleep(0.5)
        self.env = dict(os.environ, DISPLAY=f":{n}")
        return self.env

    def close(self):
        if self.proc is not None:
            self.proc.terminate()
            self.proc.wait()


display = Display()


def xvfb(cmd):
    """The command with our X server when there is no display and Xvfb is there."""
    if os.environ.get("DISPLAY") or not shutil.which("Xvfb"):
        return None
    return cmd


def backends():
    """(name, command, fallback command or None) of each backend found: pvpython needs a
    display (Debian's is built for X); VTK's wheel renders off-screen without one (EGL or
    OSMesa): tried without a display first, then with Xvfb."""
    found, seen = [], set()
    pv = shutil.which("pvpython")
    if pv and (os.environ.get("DISPLAY") or shutil.which("Xvfb")):
        found.append(("pvpython", None, [pv, SCRIPT]))
    for py in (sys.executable, os.path.join(ROOT, ".venv", "bin", "python"), "/usr/bin/python3"):
        if not os.path.exists(py):
            continue
        # (--backend vtk: the VTK path also where paraview.simple could be imported)
        r = subprocess.run([py, "-c", "import vtkmodules; print(vtkmodules.__file__)"],
                           capture_output=True, text=True)
        if r.returncode == 0 and r.stdout not in seen:
            seen.add(r.stdout)
            cmd = [py, SCRIPT, "--backend", "vtk"]
            found.append((f"vtk ({py}: {os.path.dirname(r.stdout.strip())})", cmd, xvfb(cmd)))
    return found


# the orientation array of the last step's particles as VTK's XDMF reader gives it
READ_ORIENTATION = """
import sys
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
r = vtkXdmfReader()
r.SetFileName(sys.argv[1])
r.UpdateInformation()
r.UpdateTimeStep(0.05)
it = r.GetOutputDataObject(0).NewIterator()
it.InitTraversal()
d = it.GetCurrentDataObject().GetPointData()
for q in range(4):
    a = d.GetArray(f"orientation_q{q}")
    print(a.GetNumberOfComponents(), a.GetNumberOfTuples(),
          *(repr(a.GetValue(i)) for i in range(a.GetNumberOfTuples())))
"""


def draw(cmd, png, env=None):
    return subprocess.run(cmd + [out, "--png", png, "--size", "640", "480"],
                          capture_output=True, text=True, timeout=600, env=env)


found = backends()
if not found:
    print("SKIPPED: neither pvpython (with a display or Xvfb) nor a Python with the vtk "
          "module is installed (scripts/install/install-deps installs vtk into .venv)")
    sys.exit(77)
for k, (name, cmd, fallback) in enumerate(found):
    png = os.path.join(work, f"picture_{k}.png")
    if cmd is not None:
        r = draw(cmd, png)
        if r.returncode < 0:            # killed by a signal: pvpython under a new Xvfb can
            time.sleep(2.0)             # abort while the server starts (a loaded machine)
            r = draw(cmd, png)
    if (cmd is None or r.returncode != 0) and fallback:
        if cmd is not None:
            print(f"{name}: failed without a display (exit {r.returncode}); again with Xvfb")
        r = draw(fallback, png, display.get())
        if r.returncode != 0:           # (a loaded machine: the new server not ready yet)
            time.sleep(2.0)
            r = draw(fallback, png, display.get())
    if cmd is not None and r.returncode != 0 and not fallback:
        # a vtk that renders through X (Debian's), no display and no Xvfb: the script must
        # say so and stop, not crash
        check(r.returncode == 1 and "renders through an X server" in r.stderr,
              f"{name}: without a display, a clear error (exit {r.returncode}): "
              f"{r.stdout[-1500:]}{r.stderr[-1500:]}")
        print(f"{name}: needs an X server; no display and no Xvfb here: not drawn")
        continue
    check(r.returncode == 0 and os.path.exists(png),
          f"{name}: exit {r.returncode}, {png} written: {r.stdout[-1500:]}{r.stderr[-1500:]}")
    if r.returncode != 0 or not os.path.exists(png):
        continue
    check("66 particles" in r.stdout, f"{name}: says it drew the 66 particles: {r.stdout}")
    if cmd is not None:               # a Python with vtk: how its XDMF reader takes the index
        q = subprocess.run([cmd[0], "-c", READ_ORIENTATION, os.path.join(out, "snapshots.xmf")],
                           capture_output=True, text=True, timeout=300)
        got = [line.split() for line in q.stdout.splitlines()]
        ok = len(got) == 4 and all(g[:2] == ["1", "66"] and len(g) == 68 for g in got)
        check(ok, f"{name}: the reader gives orientation_q0 .. q3, one component and 66 "
              f"particles each: {q.stdout[:300]!r} {q.stderr[-500:]!r}")
        if ok:
            read = np.array([[float(v) for v in g[2:]] for g in got]).T
            check(np.array_equal(read, last_orientation),
                  f"{name}: the reader's orientation is the snapshot's /particles/orientation")
    w, h, img = png_pixels(png)
    check((w, h) == (640, 480), f"{name}: {w} x {h} pixels, 640 x 480 asked")
    flat = img.reshape(-1, 3)
    colours, counts = np.unique(flat[:, 0] * 65536 + flat[:, 1] * 256 + flat[:, 2],
                                return_counts=True)
    drawn = 1 - counts.max() / len(flat)
    check(len(colours) > 50 and drawn > 0.02,
          f"{name}: not blank ({len(colours)} colours, {drawn:.1%} of the pixels drawn)")
    print(f"{name}: {png}: {w} x {h}, {len(colours)} colours, {drawn:.1%} drawn")
display.close()
finish()
