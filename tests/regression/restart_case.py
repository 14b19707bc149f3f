"""A small case with many contacts and a moving wall, shared by the checkpoint and snapshot
tests: 200 soft spheres (E = 10 MPa, so that dt can be large) inserted at random in a box of
four planes, falling onto a square STL floor that rises between 0.05 s and 0.15 s and spins
about z from 0.1 s: particle-particle and particle-wall contacts with sliding and history."""
import os

FLOOR = [((-0.06, -0.06, 0.0), (0.06, -0.06, 0.0), (0.06, 0.06, 0.0)),
         ((-0.06, -0.06, 0.0), (0.06, 0.06, 0.0), (-0.06, 0.06, 0.0))]
FLOOR_VELOCITY = (0.0, 0.0, 0.01)      # m/s, between 0.05 s and 0.15 s
FLOOR_SPIN = 5.0                       # rad/s about z through the origin, from 0.1 s
BODY = """&material name = 'soft', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.2 /
&material name = 'wall', rigid = .true. /
&pair materials = 'soft', 'soft', restitution = 0.3, friction = 0.3 /
&pair materials = 'soft', 'wall', restitution = 0.3, friction = 0.3 /
"""
INSERT = """&insert n = 200, material = 'soft', radius_min = 0.004, radius_max = 0.005, region = 'box',
        box_min = -0.045, -0.045, 0.005, box_max = 0.045, 0.045, 0.15, seed = 7,
        velocity = 0.1, 0, -0.2 /
"""
WALLS = """&wall_plane material = 'wall', point = -0.05, 0, 0.1, normal = 1, 0, 0, half_width = 0.1 /
&wall_plane material = 'wall', point = 0.05, 0, 0.1, normal = -1, 0, 0, half_width = 0.1 /
&wall_plane material = 'wall', point = 0, -0.05, 0.1, normal = 0, 1, 0, half_width = 0.1 /
&wall_plane material = 'wall', point = 0, 0.05, 0.1, normal = 0, -1, 0, half_width = 0.1 /
&wall_mesh file = 'floor.stl', material = 'wall', velocity = 0, 0, 0.01, velocity_start = 0.05,
           velocity_end = 0.15, rotation_axis = 0, 0, 1, rotation_point = 0, 0, 0,
           angular_velocity = 5, rotation_start = 0.1 /
"""


def write_case(work, name, run="", output="", dt=2e-5, t_end=0.2,
               integrator="symplectic_euler", particles=INSERT):
    """Write floor.stl and NAME.nml into work; return the case path. `run` and `output` are
    extra keys of &run and &output, `particles` the groups that make the particles;
    outputs go to work/out_NAME."""
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "floor.stl"), "w") as f:
        f.write("solid floor\n")
        for tri in FLOOR:
            f.write(" facet normal 0 0 1\n  outer loop\n")
            for v in tri:
                f.write("   vertex %r %r %r\n" % v)
            f.write("  endloop\n endfacet\n")
        f.write("endsolid floor\n")
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(f"&run dt = {dt!r}, t_end = {t_end!r}, integrator = '{integrator}' {run} /\n")
        f.write(f"&output dir = 'out_{name}', interval = 0.01 {output} /\n")
        f.write(BODY + particles + WALLS)
    return path


def datasets(group, prefix=""):
    """Names of all datasets under an h5py group."""
    import h5py
    names = []
    for key, item in group.items():
        if isinstance(item, h5py.Group):
            names += datasets(item, prefix + "/" + key)
        else:
            names.append(prefix + "/" + key)
    return names


def same_bits(a, b):
    """True if two arrays have the same shape, type and bits (so -0.0 != 0.0, NaN == NaN)."""
    import numpy as np
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
