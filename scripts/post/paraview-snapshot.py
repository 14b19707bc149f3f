#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""A picture of a run: loads its snapshots.xmf, draws the particles as spheres of their
radius coloured by their speed and the walls as a translucent surface, and writes a PNG.

  xvfb-run -a -s "-screen 0 1280x1024x24" pvpython scripts/post/paraview-snapshot.py output/pour
  .venv/bin/python scripts/post/paraview-snapshot.py output/pour         # VTK's Python wheel

usage: paraview-snapshot.py RUN [--png FILE] [--time T] [--size W H] [--view V]
                            [--walls surface|edges|none] [--title TEXT] [--backend B]
  RUN       a run's output folder (or its snapshots.xmf)
  --png     the picture (default RUN/snapshot.png)
  --time    the snapshot nearest this time [s] (default: the last)
  --size    width and height in pixels (default 1000 750)
  --view    iso (default), front (looking along +y, z up), top (looking down), side (along -x)
  --walls   how the walls are drawn: a translucent surface (default), their edges, or not
  --title   a line of text at the top left (default: the time, the particle count and the
            particles' materials by name, from the index's material table)
  --backend paraview, vtk or auto (default: ParaView where paraview.simple can be imported)

Under pvpython or pvbatch it builds a ParaView pipeline (XDMFReader, ExtractBlock, a
Calculator for the speed, a sphere Glyph scaled by `radius` with factor 2); under any other
Python it uses VTK (vtkXdmfReader, vtkGlyph3D) with off-screen rendering (EGL or OSMesa, no
X server needed). Both draw the same scene from the same camera. Debian's pvpython needs an X
server: without a display (DISPLAY not set) the script runs itself again under
`xvfb-run -a -s "-screen 0 1280x1024x24"` (with xvfb-run's default 8-bit screen it fails now
and then; scripts/install/install-deps installs xvfb beside ParaView), and the vtk module
Debian's python3-paraview puts into the system's Python needs one too. doc/user/output.md,
sections ParaView and Pictures without a display."""
import argparse
import math
import os
import shutil
import sys
import xml.etree.ElementTree as ET

try:
    from paraview import simple as pvs          # pvpython, pvbatch
except Exception:                               # none, or Debian's beside VTK's wheel in a venv
    pvs = None

DIRECTIONS = {"iso": ((1.0, -1.6, 0.9), (0, 0, 1)), "front": ((0, -1.0, 0), (0, 0, 1)),
              "top": ((0, 0, 1.0), (0, 1, 0)), "side": ((1.0, 0, 0), (0, 0, 1))}


def parse():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("run")
    p.add_argument("--png")
    p.add_argument("--time", type=float)
    p.add_argument("--size", type=int, nargs=2, default=[1000, 750])
    p.add_argument("--view", choices=sorted(DIRECTIONS), default="iso")
    p.add_argument("--walls", choices=["surface", "edges", "none"], default="surface")
    p.add_argument("--title")
    p.add_argument("--backend", choices=["auto", "paraview", "vtk"], default="auto")
    a = p.parse_args()
    a.xmf = a.run if a.run.endswith(".xmf") else os.path.join(a.run, "snapshots.xmf")
    if not os.path.isfile(a.xmf):
        sys.exit(f"paraview-snapshot: {a.xmf}: no such file (a run with "
                 "&output snapshot_interval > 0 writes it)")
    a.png = a.png or os.path.join(os.path.dirname(os.path.abspath(a.xmf)), "snapshot.png")
    return a


def index(xmf):
    """The times of the index and its material table {index: name} (empty for an index
    written before the table was added)."""
    root = ET.parse(xmf).getroot()
    domain = root.find("Domain")
    names = {}
    for info in domain.findall("Information"):
        if info.get("Name") == "materials":
            for entry in info.get("Value").split(";"):
                k, name = entry.strip().split(" ", 1)
                names[int(k)] = name
    times = [float(g.find("Time").get("Value")) for g in domain.find("Grid").findall("Grid")]
    return times, names


def pick(times, t):
    if t is None:
        return times[-1]
    return min(times, key=lambda s: abs(s - t))


def particle_materials(xmf, t):
    """The material indices of the particles of the snapshot at time t, read from its HDF5
    file (None without h5py)."""
    try:
        import h5py
    except ImportError:
        return None
    root = ET.parse(xmf).getroot()
    for grid in root.find("Domain").find("Grid").findall("Grid"):
        if float(grid.find("Time").get("Value")) == t:
            for item in grid.iter("DataItem"):
                name, dataset = item.text.strip().split(":")
                if dataset == "/particles/material":
                    path = os.path.join(os.path.dirname(os.path.abspath(xmf)), name)
                    with h5py.File(path) as f:
                        return sorted(set(int(m) for m in f[dataset][()]))
    return None


def camera(bounds, view):
    """Focal point, position and view-up for the bounds (xmin, xmax, ...) seen from `view`."""
    c = [(bounds[2 * k] + bounds[2 * k + 1]) / 2 for k in range(3)]
    size = max(bounds[2 * k + 1] - bounds[2 * k] for k in range(3))
    d, up = DIRECTIONS[view]
    n = math.sqrt(sum(x * x for x in d))
    pos = [c[k] + 2.2 * size * d[k] / n for k in range(3)]
    return c, pos, list(up)


def title_text(a, t, n, mats, names):
    if a.title is not None:
        return a.title
    used = ", ".join(names.get(int(m), str(int(m))) for m in sorted(set(mats)))
    return f"t = {t:.3g} s, {n} particles ({used}), coloured by speed [m/s]"


def with_paraview(a, t, names):
    reader = pvs.XDMFReader(FileNames=[os.path.abspath(a.xmf)])
    # the blocks are named after the time's index (particles3, walls3): chosen by prefix
    particles = pvs.ExtractBlock(Input=reader,
                                 Selectors=["//*[starts-with(name(), 'particles')]"])
    speed = pvs.Calculator(Input=particles, ResultArrayName="speed", Function="mag(velocity)")
    speed.UpdatePipeline(t)
    glyph = pvs.Glyph(Input=speed, GlyphType="Sphere")
    glyph.ScaleArray = ["POINTS", "radius"]
    glyph.ScaleFactor = 2.0                  # ParaView's sphere glyph has radius 0.5
    glyph.GlyphMode = "All Points"
    glyph.GlyphType.ThetaResolution = 16
    glyph.GlyphType.PhiResolution = 12
    glyph.UpdatePipeline(t)
    view = pvs.CreateView("RenderView")
    view.ViewSize = list(a.size)
    view.ViewTime = t
    view.OrientationAxesVisibility = 0
    view.Background = [1, 1, 1]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    shown = pvs.Show(glyph, view)
    pvs.ColorBy(shown, ("POINTS", "speed"))
    n = speed.GetDataInformation().DataInformation.GetNumberOfPoints()
    vmax, mats = 0.0, []
    if n:
        vmax = speed.PointData["speed"].GetRange()[1]
        mats = particle_materials(a.xmf, t)
        if mats is None:                     # no h5py: the indices in the range
            lo, hi = speed.PointData["material"].GetRange()
            mats = list(range(int(lo), int(hi) + 1))
    lut = pvs.GetColorTransferFunction("speed")
    lut.ApplyPreset("Turbo" if "Turbo" in pvs.GetLookupTableNames() else "Jet", True)
    lut.RescaleTransferFunction(0.0, max(vmax, 1e-6))
    bar = pvs.GetScalarBar(lut, view)
    bar.Title, bar.ComponentTitle = "speed [m/s]", ""
    bar.TitleColor = bar.LabelColor = [0, 0, 0]
    shown.SetScalarBarVisibility(view, True)
    bounds = list(glyph.GetDataInformation().GetBounds())
    if a.walls != "none":
        walls = pvs.ExtractBlock(Input=reader, Selectors=["//*[starts-with(name(), 'walls')]"])
        walls.UpdatePipeline(t)
        drawn = walls
        if a.walls == "edges":              # the outlines and creases, not every triangle
            # each triangle has corners of its own: merged first, so that shared edges are
            # not boundaries
            drawn = pvs.FeatureEdges(Input=pvs.Clean(Input=pvs.ExtractSurface(Input=walls)))
            drawn.BoundaryEdges, drawn.FeatureEdges = 1, 1
            drawn.NonManifoldEdges, drawn.ManifoldEdges = 0, 0
            drawn.Coloring = 0
        w = pvs.Show(drawn, view)
        w.ColorArrayName = ['POINTS', '']
        w.AmbientColor = w.DiffuseColor = [0.4, 0.4, 0.45]
        if a.walls == "surface":
            w.AmbientColor = w.DiffuseColor = [0.55, 0.55, 0.6]
            w.Opacity = 0.25
        wb = walls.GetDataInformation().GetBounds()
        if wb[0] <= wb[1]:
            bounds = [min(bounds[k], wb[k]) if k % 2 == 0 else max(bounds[k], wb[k])
                      for k in range(6)]
    text = pvs.Text(Text=title_text(a, t, n, mats, names))
    td = pvs.Show(text, view)
    td.Color, td.FontSize, td.WindowLocation = [0, 0, 0], 14, "Upper Left Corner"
    focal, pos, up = camera(bounds, a.view)
    view.CameraFocalPoint, view.CameraPosition, view.CameraViewUp = focal, pos, up
    view.CameraParallelProjection = 0
    view.ResetCamera(False)
    pvs.Render(view)
    pvs.SaveScreenshot(a.png, view, ImageResolution=list(a.size))
    return n


def with_vtk(a, t, names):
    import vtk
    from vtk.util import numpy_support
    import numpy as np
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(a.xmf)
    reader.UpdateInformation()
    reader.UpdateTimeStep(t)
    out = reader.GetOutputDataObject(0)
    blocks = {}
    for k in range(out.GetNumberOfBlocks()):
        name = out.GetMetaData(k).Get(vtk.vtkCompositeDataSet.NAME()).split("[")[0]
        blocks[name] = out.GetBlock(k)
    particles = blocks.get("particles")
    n = particles.GetNumberOfPoints() if particles is not None else 0
    ren = vtk.vtkRenderer()
    ren.SetBackground(1, 1, 1)
    vmax, mats = 0.0, []
    bounds = None
    if n:
        pd = particles.GetPointData()
        vel = numpy_support.vtk_to_numpy(pd.GetArray("velocity"))
        values = np.sqrt((vel ** 2).sum(axis=1))
        speed = numpy_support.numpy_to_vtk(values, deep=True)
        speed.SetName("speed")
        pd.AddArray(speed)
        vmax = float(values.max())
        mats = list(numpy_support.vtk_to_numpy(pd.GetArray("material")))
        sphere = vtk.vtkSphereSource()
        sphere.SetRadius(1.0)
        sphere.SetThetaResolution(16)
        sphere.SetPhiResolution(12)
        glyph = vtk.vtkGlyph3D()
        glyph.SetInputData(particles)
        glyph.SetSourceConnection(sphere.GetOutputPort())
        glyph.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS,
                                     "radius")
        glyph.SetScaleModeToScaleByScalar()
        glyph.SetScaleFactor(1.0)
        glyph.SetColorModeToColorByScalar()
        glyph.OrientOff()
        glyph.Update()
        lut = vtk.vtkLookupTable()
        lut.SetHueRange(0.667, 0.0)
        lut.SetRange(0.0, max(vmax, 1e-6))
        lut.Build()
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputConnection(glyph.GetOutputPort())
        mapper.SetScalarModeToUsePointFieldData()
        mapper.SelectColorArray("speed")
        mapper.SetLookupTable(lut)
        mapper.SetScalarRange(0.0, max(vmax, 1e-6))
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        ren.AddActor(actor)
        bounds = list(glyph.GetOutput().GetBounds())
        bar = vtk.vtkScalarBarActor()
        bar.SetLookupTable(lut)
        bar.SetTitle("speed [m/s]")
        for prop in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
            prop.SetColor(0, 0, 0)
        bar.SetWidth(0.08)
        bar.SetPosition(0.9, 0.1)
        ren.AddViewProp(bar)
    walls = blocks.get("walls")
    if walls is not None and walls.GetNumberOfCells() and a.walls != "none":
        surface = vtk.vtkDataSetSurfaceFilter()
        surface.SetInputData(walls)
        if a.walls == "edges":
            clean = vtk.vtkCleanPolyData()          # shared corners merged
            clean.SetInputConnection(surface.GetOutputPort())
            edges = vtk.vtkFeatureEdges()
            edges.SetInputConnection(clean.GetOutputPort())
            edges.BoundaryEdgesOn()
            edges.FeatureEdgesOn()
            edges.ManifoldEdgesOff()
            edges.NonManifoldEdgesOff()
            edges.ColoringOff()
            surface = edges
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputConnection(surface.GetOutputPort())
        mapper.ScalarVisibilityOff()
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        actor.GetProperty().SetColor(0.55, 0.55, 0.6)
        if a.walls == "surface":
            actor.GetProperty().SetOpacity(0.25)
        ren.AddActor(actor)
        wb = walls.GetBounds()
        bounds = list(wb) if bounds is None else [
            min(bounds[k], wb[k]) if k % 2 == 0 else max(bounds[k], wb[k]) for k in range(6)]
    text = vtk.vtkTextActor()
    text.SetInput(title_text(a, t, n, mats, names))
    text.GetTextProperty().SetColor(0, 0, 0)
    text.GetTextProperty().SetFontSize(14)
    text.SetDisplayPosition(10, a.size[1] - 24)
    ren.AddViewProp(text)
    window = vtk.vtkRenderWindow()
    if window.GetClassName() == "vtkXOpenGLRenderWindow" and not os.environ.get("DISPLAY"):
        sys.exit(f"paraview-snapshot: the vtk module of {sys.executable} renders through an "
                 "X server, and there is no display (DISPLAY is not set): run it under "
                 "xvfb-run -a -s \"-screen 0 1280x1024x24\", or with a vtk that renders "
                 "off-screen (pip install vtk)")
    window.SetOffScreenRendering(1)
    window.AddRenderer(ren)
    window.SetSize(*a.size)
    if bounds is not None:
        focal, pos, up = camera(bounds, a.view)
        cam = ren.GetActiveCamera()
        cam.SetFocalPoint(*focal)
        cam.SetPosition(*pos)
        cam.SetViewUp(*up)
        ren.ResetCamera()
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.ReadFrontBufferOff()
    grab.Update()
    png = vtk.vtkPNGWriter()
    png.SetFileName(a.png)
    png.SetInputConnection(grab.GetOutputPort())
    png.Write()
    return n


def under_xvfb():
    """ParaView renders through an X server (it stops with SIGSEGV without one): the same
    command again under xvfb-run, once."""
    xvfb, pv = shutil.which("xvfb-run"), shutil.which("pvpython")
    if os.environ.get("DEM_UNDER_XVFB") or xvfb is None or pv is None:
        sys.exit("paraview-snapshot: ParaView renders through an X server and there is no "
                 "display (DISPLAY is not set) and no xvfb-run: install xvfb "
                 "(scripts/install/install-deps), or run .venv/bin/python "
                 "scripts/post/paraview-snapshot.py (VTK's off-screen rendering)")
    os.environ["DEM_UNDER_XVFB"] = "1"
    os.execv(xvfb, [xvfb, "-a", "-s", "-screen 0 1280x1024x24", pv, os.path.abspath(__file__),
                    *sys.argv[1:]])


def main():
    a = parse()
    times, names = index(a.xmf)
    if not times:
        sys.exit(f"paraview-snapshot: {a.xmf} lists no snapshot")
    t = pick(times, a.time)
    if a.backend == "paraview" and pvs is None:
        sys.exit("paraview-snapshot: no paraview.simple here (run it with pvpython)")
    paraview = pvs is not None and a.backend != "vtk"
    if paraview and not os.environ.get("DISPLAY"):
        under_xvfb()
    n = (with_paraview if paraview else with_vtk)(a, t, names)
    print(f"paraview-snapshot: {a.png}: t = {t:g} s, {n} particles "
          f"({'ParaView' if paraview else 'VTK'})")


if __name__ == "__main__":
    main()
