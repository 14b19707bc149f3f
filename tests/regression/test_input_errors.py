# SPDX-License-Identifier: BSD-3-Clause
"""Bad input gets a clear error that names the file, the namelist group and the key (and
where the group's keys are described: doc/user/input.md, &group), exit code 2, and leaves
no output behind. Also the command line: --version, --help, --check.
usage: test_input_errors.py DEM WORKDIR"""
import concurrent.futures
import os
import re
import shutil
import subprocess
import sys

from regression_util import check, finish

dem, work = sys.argv[1], os.path.abspath(sys.argv[2])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

GOOD = """&run dt = 1e-7, t_end = 1e-5, gravity = 0, 0, 0 /
&output interval = 1e-6 /
&material name = 'glass', density = 2800.0, youngs_modulus = 48.0e9, poisson_ratio = 0.2 /
&material name = 'steel', density = 7200.0, youngs_modulus = 210.0e9, poisson_ratio = 0.2 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&pair materials = 'glass', 'steel', restitution = 0.5, friction = 0.3 /
&particle material = 'glass', radius = 0.01, position = 0, 0, 0.011, velocity = 0, 0, -1 /
&wall_plane material = 'steel', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.1 /
"""


def run(args, name):
    d = os.path.join(work, name)
    os.makedirs(d)
    r = subprocess.run([dem] + args, cwd=d, capture_output=True, text=True, timeout=300)
    return r, d


pending = []     # the bad cases' runs, made at once at the end (each dem start waits ~0.3 s)


def bad(name, text, group, key, extra=""):
    """A case whose text is `text` must fail naming the file, &group and key (checked by
    check_bad_cases)."""
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    pending.append((name, path, group, key, extra))


def check_bad_cases():
    """Run the cases that bad() wrote, eight at a time, and check each."""
    runs = [(case, args, case[0] + ("_check" if args[0] == "--check" else "_run"))
            for case in pending for args in (["--check", case[1]], [case[1]])]
    with concurrent.futures.ThreadPoolExecutor(8) as pool:
        results = list(pool.map(lambda x: run(x[1], x[2]), runs))
    for ((name, path, group, key, extra), _, _), (r, d) in zip(runs, results):
        msg = r.stderr
        check(r.returncode == 2, f"{name}: exit code {r.returncode}, expected 2 ({msg.strip()})")
        check(path in msg, f"{name}: message does not name the file: {msg.strip()}")
        if group:
            check("&" + group in msg, f"{name}: message does not name &{group}: {msg.strip()}")
            check(f"(doc/user/input.md, &{group})" in msg,
                  f"{name}: message does not say where &{group} is described: {msg.strip()}")
        if key:
            check(f"'{key}'" in msg, f"{name}: message does not name key '{key}': {msg.strip()}")
        if extra:
            check(extra in msg, f"{name}: message lacks '{extra}': {msg.strip()}")
        check("Traceback" not in msg and "Error termination" not in msg
              and "Backtrace" not in msg, f"{name}: crashed: {msg.strip()}")
        check(os.listdir(d) == [], f"{name}: left output behind: {os.listdir(d)}")


def sub(old, new):
    assert old in GOOD, old
    return GOOD.replace(old, new)


# the good case is good
path = os.path.join(work, "good.nml")
with open(path, "w") as f:
    f.write(GOOD)
r, d = run(["--check", path], "good_check")
check(r.returncode == 0, f"good case: --check failed: {r.stderr}")
for quantity in ("particles", "total mass", "Rayleigh time", "Hertz contact time",
                 "dt / Rayleigh time", "dt / contact time", "stability bound",
                 "estimated memory"):
    check(quantity in r.stdout, f"--check does not print {quantity}")
check(os.listdir(d) == [], "--check wrote output")

# missing file
r, d = run(["--check", os.path.join(work, "nowhere.nml")], "missing")
check(r.returncode == 2 and "nowhere.nml" in r.stderr, f"missing file: {r.stderr}")

# unknown key, wrong type, missing key
bad("unknown_key", sub("density = 2800.0", "densty = 2800.0"), "material", "densty")
bad("wrong_type_real", sub("density = 2800.0", "density = 'heavy'"), "material", "density")
bad("wrong_type_logical", sub("&output interval = 1e-6 /", "&output interval = 1e-6, "
    "trace_id = .true. /"), "output", "trace_id")
bad("wrong_type_vector", sub("position = 0, 0, 0.011", "position = 0, 'up', 0.011"),
    "particle", "position")
bad("missing_dt", sub("dt = 1e-7, ", ""), "run", "dt")
bad("missing_radius", sub("radius = 0.01, ", ""), "particle", "radius")
# values out of range
bad("negative_radius", sub("radius = 0.01", "radius = -0.01"), "particle", "radius")
bad("zero_radius", sub("radius = 0.01", "radius = 0"), "particle", "radius")
bad("zero_density", sub("density = 2800.0", "density = 0"), "material", "density")
bad("negative_density", sub("density = 2800.0", "density = -2800.0"), "material", "density")
bad("negative_modulus", sub("youngs_modulus = 48.0e9", "youngs_modulus = -48.0e9"),
    "material", "youngs_modulus")
bad("zero_modulus", sub("youngs_modulus = 48.0e9", "youngs_modulus = 0"), "material",
    "youngs_modulus")
for nu in ("0.5", "-1.0", "0.7"):
    bad("poisson_" + nu, sub("48.0e9, poisson_ratio = 0.2", "48.0e9, poisson_ratio = " + nu),
        "material", "poisson_ratio")
for e in ("0.0", "1.5", "-0.5"):
    bad("restitution_" + e, sub("'glass', 'glass', restitution = 0.5",
                                "'glass', 'glass', restitution = " + e), "pair", "restitution")
bad("negative_friction", sub("'glass', 'glass', restitution = 0.5, friction = 0.3",
                             "'glass', 'glass', restitution = 0.5, friction = -0.1"),
    "pair", "friction")
bad("negative_rolling_friction",
    sub("'glass', 'glass', restitution = 0.5, friction = 0.3",
        "'glass', 'glass', restitution = 0.5, friction = 0.3, rolling_friction = -0.1"),
    "pair", "rolling_friction")
bad("unknown_rolling_model",
    sub("'glass', 'glass', restitution = 0.5, friction = 0.3",
        "'glass', 'glass', restitution = 0.5, friction = 0.3, rolling_model = 'epsd9'"),
    "pair", "rolling_model", "'epsd9'")
bad("negative_cohesion",
    sub("'glass', 'steel', restitution = 0.5, friction = 0.3",
        "'glass', 'steel', restitution = 0.5, friction = 0.3, cohesion_energy_density = -1"),
    "pair", "cohesion_energy_density")
bad("unknown_normal_model", GOOD + "&contact_model normal_model = 'hook' /\n", "contact_model",
    "normal_model", "'hook'")
bad("unknown_tangential_model", GOOD + "&contact_model tangential_model = 'coloumb' /\n",
    "contact_model", "tangential_model", "'coloumb'")
bad("hooke_without_stiffness", GOOD + "&contact_model normal_model = 'hooke' /\n", "pair",
    "stiffness", "normal_model = 'hooke'")
bad("hooke_negative_stiffness",
    sub("'glass', 'glass', restitution = 0.5, friction = 0.3",
        "'glass', 'glass', restitution = 0.5, friction = 0.3, stiffness = -1")
    + "&contact_model normal_model = 'hooke' /\n", "pair", "stiffness")
bad("stiffness_with_hertz",
    sub("'glass', 'glass', restitution = 0.5, friction = 0.3",
        "'glass', 'glass', restitution = 0.5, friction = 0.3, stiffness = 1e6"),
    "pair", "stiffness", "normal_model = 'hooke'")
bad("undefined_pair", sub("&pair materials = 'glass', 'steel', restitution = 0.5, "
                          "friction = 0.3 /\n", ""), "pair", None, "'glass' and 'steel'")
bad("nan_position", sub("position = 0, 0, 0.011", "position = 0, NaN, 0.011"), "particle",
    "position", "finite")
bad("infinite_velocity", sub("velocity = 0, 0, -1", "velocity = 0, 0, -Inf"), "particle",
    "velocity", "finite")
bad("missing_position", sub("position = 0, 0, 0.011, ", ""), "particle", "position", "required")
bad("coincident_particles", GOOD + "&particle material = 'glass', radius = 0.01, position = "
    "0, 0, 0.012 /\n", None, None, "particles 1 and 2 overlap")
bad("nan_poisson", sub("48.0e9, poisson_ratio = 0.2", "48.0e9, poisson_ratio = NaN"),
    "material", "poisson_ratio")
bad("nan_radius", sub("radius = 0.01", "radius = NaN"), "particle", "radius")
bad("nan_restitution", sub("'glass', 'glass', restitution = 0.5", "'glass', 'glass', "
    "restitution = NaN"), "pair", "restitution")
bad("nan_gravity", sub("gravity = 0, 0, 0", "gravity = 0, 0, NaN"), "run", "gravity", "finite")
bad("unknown_material", sub("&particle material = 'glass'", "&particle material = 'gold'"),
    "particle", "material")
bad("dt_unstable", sub("dt = 1e-7", "dt = 1e-4"), "run", "dt", "stability bound")
# &insert radius distributions
INS = ("&insert n = 5, material = 'glass', box_min = -0.05, -0.05, 0.03, "
       "box_max = 0.05, 0.05, 0.08, ")
for name, keys in (("lognormal", "radius_distribution = 'lognormal', radius_mean = 2e-3, "
                    "radius_sd = 5e-4, radius_min = 1e-3, radius_max = 4e-3"),
                   ("discrete", "radius_distribution = 'discrete', radii = 1e-3, 2e-3, "
                    "fractions = 0.4, 0.6, fraction_by = 'number'")):
    path = os.path.join(work, f"good_{name}.nml")
    with open(path, "w") as f:
        f.write(GOOD + INS + keys + " /\n")
    r, d = run(["--check", path], f"good_{name}_check")
    check(r.returncode == 0, f"good {name} insert: --check failed: {r.stderr}")
FACE = ("radius_min = 1e-3, region = 'face', face_center = 0, 0, 0.1, face_normal = 0, 0, -1, "
        "velocity = 0, 0, -1")
path = os.path.join(work, "good_face.nml")
with open(path, "w") as f:
    f.write(GOOD + INS + FACE + ", rate = 10, face_width = 0.02, 0.02 /\n")
r, d = run(["--check", path], "good_face_check")
check(r.returncode == 0, f"good face insert: --check failed: {r.stderr}")
NORMAL = "radius_distribution = 'normal', radius_mean = 2e-3, radius_sd = 5e-4, "
DISCRETE = "radius_distribution = 'discrete', radii = 1e-3, 2e-3, "
for name, keys, key, extra in (
        ("size_unknown", "radius_distribution = 'gamma', radius_min = 1e-3",
         "radius_distribution", "gamma"),
        ("normal_no_mean", "radius_distribution = 'normal', radius_sd = 5e-4, "
         "radius_min = 1e-3, radius_max = 3e-3", "radius_mean", "required"),
        ("normal_no_max", NORMAL + "radius_min = 1e-3", "radius_max", "required"),
        ("normal_zero_sd", "radius_distribution = 'normal', radius_mean = 2e-3, radius_sd = 0, "
         "radius_min = 1e-3, radius_max = 3e-3", "radius_sd", "> 0"),
        ("normal_window", NORMAL + "radius_min = 1e-2, radius_max = 2e-2", "radius_sd",
         "less than 0.001"),
        ("uniform_radii", "radius_min = 1e-3, radii = 1e-3", "radii", "not used"),
        ("uniform_mean", "radius_min = 1e-3, radius_mean = 1e-3", "radius_mean", "not used"),
        ("uniform_fraction_by", "radius_min = 1e-3, fraction_by = 'mass'", "fraction_by",
         "not used"),
        ("discrete_min", DISCRETE + "fractions = 0.5, 0.5, radius_min = 1e-3", "radius_min",
         "not used"),
        ("discrete_no_radii", "radius_distribution = 'discrete', fractions = 1", "radii",
         "required"),
        ("discrete_negative", "radius_distribution = 'discrete', radii = 1e-3, -2e-3, "
         "fractions = 0.5, 0.5", "radii", "> 0"),
        ("discrete_count", DISCRETE + "fractions = 1", "fractions", "each radius"),
        ("discrete_sum", DISCRETE + "fractions = 0.3, 0.3", "fractions", "sum to 1"),
        ("discrete_by", DISCRETE + "fractions = 0.5, 0.5, fraction_by = 'volume'",
         "fraction_by", "volume"),
        ("inflow_both", "radius_min = 1e-3, rate = 10, mass_rate = 0.1", "mass_rate",
         "not both"),
        ("inflow_rate", "radius_min = 1e-3, rate = 0", "rate", "> 0"),
        ("inflow_no_rate", "radius_min = 1e-3, start = 0.1", "start", "'rate'"),
        ("inflow_end", "radius_min = 1e-3, rate = 10, start = 0.2, end = 0.1", "end",
         "> start"),
        ("inflow_end_duration", "radius_min = 1e-3, rate = 10, end = 0.2, duration = 0.1",
         "duration", "not both"),
        ("inflow_every", "radius_min = 1e-3, rate = 10, insert_every = -5", "insert_every",
         ">= 1"),
        ("face_no_rate", FACE + ", face_width = 0.02, 0.02", "region", "inflow"),
        ("face_no_width", FACE + ", rate = 10", "face_width", "two sides"),
        ("face_narrow", FACE + ", rate = 10, face_width = 0.02, 1e-3", "face_width", "wider"),
        ("face_no_center", FACE.replace("face_center = 0, 0, 0.1, ", "") +
         ", rate = 10, face_width = 0.02, 0.02", "face_center", "required"),
        ("face_zero_normal", FACE.replace("face_normal = 0, 0, -1", "face_normal = 0, 0, 0") +
         ", rate = 10, face_width = 0.02, 0.02", "face_normal", "non-zero"),
        ("face_axis", FACE + ", rate = 10, face_width = 0.02, 0.02, face_axis = 0, 0, 2",
         "face_axis", "along face_normal"),
        ("face_velocity", FACE.replace("velocity = 0, 0, -1", "velocity = 1, 0, 0") +
         ", rate = 10, face_width = 0.02, 0.02", "velocity", "into it"),
        ("spread_negative", "radius_min = 1e-3, velocity_spread = 0, -1, 0", "velocity_spread",
         ">= 0")):
    bad(name, GOOD + INS + keys + " /\n", "insert", key, extra)
bad("bad_integrator", sub("t_end = 1e-5,", "t_end = 1e-5, integrator = 'rk4',"), "run",
    "integrator")
bad("zero_normal", sub("normal = 0, 0, 1", "normal = 0, 0, 0"), "wall_plane", "normal")
# wall names, wall-load probes, wall oscillation and velocity tables (issue 32)
square_stl = os.path.join(work, "square.stl")
with open(square_stl, "w") as f:
    f.write("solid w\n facet normal 0 0 1\n  outer loop\n   vertex -1 -1 -1\n   vertex 1 -1 -1\n"
            "   vertex 1 1 -1\n  endloop\n endfacet\nendsolid w\n")
MESH = f"&wall_mesh material = 'steel', file = '{square_stl}', "
NAMED = sub("half_width = 0.1 /", "half_width = 0.1, name = 'floor' /")
bad("duplicate_wall_name", NAMED + MESH + "name = 'floor' /\n", "wall_mesh", "name",
    "names another wall")
bad("load_unknown_wall", NAMED + "&probe name = 'w', kind = 'wall_load', wall = 'roof' /\n",
    "probe", "wall", "'roof'")
bad("load_no_wall", sub("&wall_plane material = 'steel', point = 0, 0, 0, normal = 0, 0, 1, "
                        "half_width = 0.1 /\n", "&probe name = 'w', kind = 'wall_load' /\n"),
    "probe", "kind", "needs a wall")
bad("wall_mesh_unknown_key", GOOD + MESH + "wiggle = 1 /\n", "wall_mesh", "wiggle",
    "angular_velocity_table_time angular_velocity_table name)")
bad("load_zero_axis", GOOD + "&probe name = 'w', kind = 'wall_load', axis = 0, 0, 0 /\n",
    "probe", "axis", "non-zero")
bad("load_nan_point", GOOD + "&probe name = 'w', kind = 'wall_load', axis_point = 0, NaN, 0 /\n",
    "probe", "axis_point", "finite")
for name, keys, key, words in (
        ("oscillation_no_frequency", "oscillation_amplitude = 0, 0, 1e-3",
         "oscillation_frequency", "> 0"),
        ("oscillation_negative_frequency", "oscillation_frequency = -5",
         "oscillation_frequency", "finite"),
        ("oscillation_nan_amplitude", "oscillation_amplitude = 0, NaN, 1e-3, "
         "oscillation_frequency = 5", "oscillation_amplitude", "finite"),
        ("oscillation_nan_phase", "oscillation_amplitude = 0, 0, 1e-3, "
         "oscillation_frequency = 5, oscillation_phase = NaN", "oscillation_phase", "finite"),
        ("oscillation_ends_first", "oscillation_start = 1, oscillation_end = 0.5",
         "oscillation_end", "later"),
        ("table_one_time", "velocity_table_time = 0, velocity_table = 0, 0, 1",
         "velocity_table_time", "two times"),
        ("table_not_increasing", "velocity_table_time = 0, 0.2, 0.1, "
         "velocity_table = 0, 0, 1, 0, 0, 1, 0, 0, 1", "velocity_table_time", "increase"),
        ("table_short", "velocity_table_time = 0, 0.1, velocity_table = 0, 0, 1, 0, 0",
         "velocity_table", "3 value(s) per time"),
        ("table_no_times", "velocity_table = 0, 0, 1, 0, 0, 1", "velocity_table_time",
         "required"),
        ("table_nan_value", "velocity_table_time = 0, 0.1, velocity_table = 0, 0, 1, 0, NaN, 1",
         "velocity_table", "finite"),
        ("angular_table_short", "angular_velocity_table_time = 0, 0.1, 0.2, "
         "angular_velocity_table = 1, 2", "angular_velocity_table", "1 value(s) per time"),
        ("angular_table_long", "angular_velocity_table_time = 0, 0.1, "
         "angular_velocity_table = 1, 2, 3", "angular_velocity_table", "1 value(s) per time")):
    bad(name, GOOD + MESH + keys + " /\n", "wall_mesh", key, words)
CYL = "&wall_primitive material = 'steel', shape = 'cylinder', point = 0, 0, 0, "
RECT = ("&wall_primitive material = 'steel', shape = 'rectangle', point = 0, 0, -0.05, "
        "normal = 0, 0, 1, direction = 1, 0, 0, ")
for name, text, key, words in (
        ("primitive_shape", "&wall_primitive material = 'steel', shape = 'sphere', "
         "point = 0, 0, 0 /", "shape", "accepted: cylinder, cone, disc, rectangle, box"),
        ("primitive_cylinder_no_axis", CYL + "radius = 0.1 /", "axis", "required"),
        ("primitive_cylinder_zero_axis", CYL + "axis = 0, 0, 0, radius = 0.1 /", "axis", ""),
        ("primitive_cylinder_radius", CYL + "axis = 0, 0, 1, radius = -0.1 /", "radius", ""),
        ("primitive_cylinder_resolution", CYL + "axis = 0, 0, 1, radius = 0.1, resolution = 2 /",
         "resolution", "3 .."),
        ("primitive_cylinder_side", CYL + "axis = 0, 0, 1, radius = 0.1, side = 'both' /", "side",
         "accepted: inner, outer"),
        ("primitive_cylinder_normal", CYL + "axis = 0, 0, 1, radius = 0.1, normal = 0, 0, 1 /", "normal",
         "not used by this shape"),
        ("primitive_cylinder_motion", CYL + "axis = 0, 0, 1, radius = 0.1, rotation_axis = 0, 0, 0 /",
         "rotation_axis", ""),
        ("primitive_rectangle_direction", RECT.replace("direction = 1, 0, 0", "direction = 0, 0, 2")
         + "half_sizes = 0.1, 0.1 /", "direction", "along normal"),
        ("primitive_rectangle_sizes", RECT + "half_sizes = 0.1 /", "half_sizes", ""),
        ("primitive_rectangle_radius", RECT + "half_sizes = 0.1, 0.1, radius = 0.1 /", "radius",
         "not used by this shape"),
        ("primitive_rectangle_closed", RECT + "half_sizes = 0.1, 0.1, closed = .true. /", "closed",
         "for a cylinder, cone or box"),
        ("primitive_cone_radii", CYL.replace("cylinder", "cone") + "axis = 0, 0, 1, radius = 0, "
         "radius_top = 0 /", "radius_top", "not both be 0"),
        ("primitive_cone_no_top", CYL.replace("cylinder", "cone") + "axis = 0, 0, 1, "
         "radius = 0.1 /", "radius_top", "required"),
        ("primitive_cylinder_top", CYL + "axis = 0, 0, 1, radius = 0.1, radius_top = 0.2 /",
         "radius_top", "not used by this shape"),
        ("primitive_disc_hole", "&wall_primitive material = 'steel', shape = 'disc', point = "
         "0, 0, -0.05, normal = 0, 0, 1, radius = 0.1, inner_radius = 0.1 /", "inner_radius",
         "less than radius"),
        ("primitive_box_corners", "&wall_primitive material = 'steel', shape = 'box', "
         "box_min = -1, -1, -1, box_max = 1, -1, 1 /", "box_max", "exceed box_min"),
        ("primitive_box_closed", "&wall_primitive material = 'steel', shape = 'box', "
         "box_min = -1, -1, -1, box_max = 1, 1, 1, closed = .true. /", "closed", "is closed")):
    bad(name, GOOD + text + "\n", "wall_primitive", key, words)
bad("unknown_variant", GOOD + "&contact_model variant = 'lammps' /\n", "contact_model",
    "variant", "accepted: dem, liggghts, mercurydpm, yade")
bad("unknown_lever", GOOD + "&contact_model variant = 'liggghts', lever_torque = 'rim' /\n",
    "contact_model", "lever_torque", "accepted: radius, mid_overlap")
bad("unknown_history", GOOD + "&contact_model tangential_history = 'rotate' /\n",
    "contact_model", "tangential_history", "accepted: keep_length, project")
bad("unknown_group", GOOD + "&gravity g = 9.81 /\n", "gravity", None, "unknown namelist group")
bad("unclosed_group", GOOD + "&particle material = 'glass', radius = 0.01\n", "particle",
    None, "not closed")
bad("text_outside", "hello\n" + GOOD, None, None, "outside a namelist group")
bad("two_run_groups", GOOD + "&run dt = 1e-7, t_end = 1e-5 /\n", "run", None)
# run control and outputs of snapshots and checkpoints
RUN = "&run dt = 1e-7, t_end = 1e-5, gravity = 0, 0, 0 /"
OUT = "&output interval = 1e-6 /"
for key, value, group, line in (("max_speed", "0", "run", RUN),
                                ("wall_time_limit", "-1", "run", RUN),
                                ("progress_interval", "-0.5", "run", RUN),
                                ("imbalance_limit", "0.9", "run", RUN),
                                ("snapshot_interval", "-1e-6", "output", OUT),
                                ("checkpoint_interval", "-1", "output", OUT),
                                ("checkpoint_keep", "0", "output", OUT),
                                ("snapshot_force", "'yes'", "output", OUT)):
    bad(f"bad_{key}", sub(line, line[:-2] + f", {key} = {value} /"), group, key)

# directions given by tiny vectors are directions: a sphere resting on the plane of normal
# (0, 0, 1e-300) ends where it does on the plane of normal (0, 0, 1), byte for byte (a
# normalization that squared the components underflowed to 0/0: issue 30, item 7)
PLANE = """&run dt = 1e-5, t_end = 0.002, gravity = 0, 0, -9.81 /
&material name = 'glass', density = 2500, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'glass', point = 0, 0, 0, normal = 0, 0, {nz}, half_width = 0.05 /
&particle id = 1, material = 'glass', radius = 1e-3, position = 0, 0, 0.0011 /
"""
finals = []
for name, nz in (("normal_unit", "1"), ("normal_tiny", "1e-300")):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(PLANE.format(nz=nz))
    r, d = run([path], name)
    check(r.returncode == 0, f"{name}: exit {r.returncode}: {r.stderr.strip()}")
    final = os.path.join(d, "output", name, "final.csv")
    finals.append(open(final).read() if os.path.exists(final) else None)
check(finals[0] is not None and finals[0] == finals[1],
      "normal = 0, 0, 1e-300: the run differs from normal = 0, 0, 1")

# a sphere centred on a wall (no normal: NaN at the first step before, issue 30, item 7), or
# overlapping it by more than half its radius, is bad input naming where the particle and
# the wall were given; beyond 1 % of the radius (a bed at rest presses in less; the energy of
# a deeper overlap can throw the particle off at the first step) --check names the same in a
# note, and a run that then stops as unstable in its message; at 0.5 % (a settled bed's
# elastic contact) neither says anything
named = "particle 1 (the &particle group 1) overlaps the wall of the &wall_plane group 1 by " \
    "1.5000E-05 m, 1.5 % of its radius, at the start (a bed at rest"
for name, z, ok in (("on_plane", "0", False), ("deep_in_plane", "4.9e-4", False),
                    ("in_plane_1.5", "9.85e-4", True), ("in_plane_0.5", "9.95e-4", True)):
    text = PLANE.format(nz="1").replace("position = 0, 0, 0.0011", f"position = 0, 0, {z}")
    if ok:
        path = os.path.join(work, name + ".nml")
        with open(path, "w") as f:
            f.write(text)
        deep = name == "in_plane_1.5"
        r, _ = run(["--check", path], name + "check")
        check(r.returncode == 0 and (named in r.stdout) == deep,
              f"{name}: --check exit {r.returncode}, the note naming the particle and the wall "
              f"{'missing' if deep else 'given'}: {r.stdout.strip()} {r.stderr.strip()}")
        r, _ = run([path], name)
        if deep:        # (1.6e-7 J set free, the energy guard's room 2.5e-8 J)
            check(r.returncode == 3 and "unstable" in r.stderr and named in r.stderr,
                  f"{name}: the run stops as unstable naming the start's overlap: exit "
                  f"{r.returncode}: {r.stderr.strip()}")
        else:
            check(r.returncode == 0 and "overlaps the wall" not in r.stderr,
                  f"{name}: the run ends, silent: exit {r.returncode}: {r.stderr.strip()}")
    else:
        share = "100.0" if z == "0" else "51.0"
        bad(name, text, None, None, "particle 1 (the &particle group 1) overlaps the wall of "
            f"the &wall_plane group 1 by {'1.0000E-03' if z == '0' else '5.1000E-04'} m, "
            f"{share} % of its radius, at the start (more than half the radius is no contact)")
# the same from a particle file (its line named), a clump file (the clump's line) and
# &insert, against named wall primitives (the wall's name and group named)
BOX = (PLANE.format(nz="1").replace(
    "&particle id = 1, material = 'glass', radius = 1e-3, position = 0, 0, 0.0011 /\n", "")
    + "&wall_primitive name = 'lid', shape = 'rectangle', material = 'glass', "
    "point = 0, 0, 0.02, normal = 0, 0, -1, direction = 1, 0, 0, half_sizes = 0.01, 0.01 /\n"
    + "&wall_primitive name = 'tube', shape = 'cylinder', material = 'glass', "
    "point = 0, 0, 0, axis = 0, 0, 0.02, radius = 0.01 /\n")
overlap_csv = os.path.join(work, "overlap.csv")
with open(overlap_csv, "w") as f:
    f.write("id,material,radius,x,y,z\n7,glass,0.001,0,0,0.005\n\n"
            "8,glass,0.001,0,0,0.0196\n")
bad("file_in_lid", BOX + f"&particle_file file = '{overlap_csv}' /\n", None, None,
    f"particle 8 (line 4 of {overlap_csv} (&particle_file)) overlaps the wall 'lid' of the "
    "&wall_primitive group 1 by 6.0000E-04 m, 60.0 % of its radius")
overlap_clumps = os.path.join(work, "overlap_clumps.csv")
with open(overlap_clumps, "w") as f:
    f.write("template,x,y,z,q0,q1,q2,q3\npair,0,0,0.005,1,0,0,0\npair,0.0087,0,0.01,1,0,0,0\n")
bad("clump_in_tube", BOX + "&clump_template name = 'pair', material = 'glass', members = "
    "0, 0, 0, 0.001, 0.001, 0, 0, 0.001 /\n" + f"&clump_file file = '{overlap_clumps}' /\n",
    None, None, f"(a member of the clump of line 3 of {overlap_clumps} (&clump_file)) "
    "overlaps the wall 'tube' of the &wall_primitive group 2 by")
bad("insert_in_tube", BOX + "&insert n = 5, material = 'glass', radius_min = 1e-3, "
    "box_min = -0.0111, -0.003, 0.003, box_max = -0.0089, 0.003, 0.017 /\n", None, None,
    "(placed by the &insert group 1) overlaps the wall 'tube' of the &wall_primitive group 2 by")

# files that are not regular files are refused at once (issue 30, item 8: /dev/zero as a
# particle file read for ever): the case file itself, a particle file, an STL file
for name, args in (("case_dev_zero", ["--check", "/dev/zero"]),
                   ("case_directory", ["--check", work])):
    r, _ = run(args, name)
    check(r.returncode == 2 and f"{args[1]}: the namelist file " in r.stderr,
          f"{name}: exit {r.returncode}: {r.stderr.strip()}")
stl_line = "&wall_mesh material = 'steel', file = '/dev/zero' /\n"
for name, text, what in (("particles_dev_zero", GOOD + "&particle_file file = '/dev/zero' /\n",
                          "/dev/zero: the particle file is empty or not a regular file"),
                         ("stl_dev_zero", GOOD + stl_line,
                          "/dev/zero: the STL file is empty or not a regular file")):
    bad(name, text, None, None, what)

# a missing final state of a run says what makes it (issue 33): the benchmark preparations'
# by the script that runs them, any other by the case whose output folder it is in
for name, folder, what in (("missing_prepared", "output/benchmark/prepare_drum_2",
                            "(scripts/bench/prepare-benchmark drum runs it"),
                           ("missing_final", "output/settle",
                            "run first the case whose &output dir is ")):
    bad(name, GOOD + f"&particle_file file = '{folder}/final.csv' /\n", "particle_file",
        "file", what)

# a UTF-8 byte-order mark (as some editors write) at the start of a case file or a particle
# file is not part of its first line (issue 30, item 9: "header has no column 'id'"); a
# garbage token of 5 MB in an STL file is quoted in its error by its first characters only
BOM = "\ufeff"
bom_csv = os.path.join(work, "bom.csv")
with open(bom_csv, "w", encoding="utf-8") as f:
    f.write(BOM + "id,material,radius,x,y,z\n1,glass,0.001,0,0,0.0011\n")
bom_case = os.path.join(work, "bom_case.nml")
with open(bom_case, "w", encoding="utf-8") as f:
    f.write(BOM + PLANE.format(nz="1").replace(
        "&particle id = 1, material = 'glass', radius = 1e-3, position = 0, 0, 0.0011 /",
        f"&particle_file file = '{bom_csv}' /"))
r, _ = run(["--check", bom_case], "bom")
check(r.returncode == 0, f"byte-order marks: --check exit {r.returncode}: {r.stderr.strip()}")
garbage_stl = os.path.join(work, "garbage.stl")
with open(garbage_stl, "w") as f:
    f.write("solid w\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 " + "7x" * 2500000
            + "\n")
bad("stl_garbage", GOOD + f"&wall_mesh material = 'steel', file = '{garbage_stl}' /\n", None,
    None, "(5000000 characters)")
r, _ = run(["--check", os.path.join(work, "stl_garbage.nml")], "stl_garbage_length")
check(len(r.stderr) < 2000, f"stl_garbage: the error is {len(r.stderr)} characters long")

# the rules of the input (doc/user/input.md, "Rules of the input"): what the namelist read
# alone let through (a vector given in part kept the rest of its default, a key given twice
# its last value, &end swallowed the next group) is refused, naming the group and the key
bad("vector_short", sub("gravity = 0, 0, 0", "gravity = -9.81"), "run", "gravity",
    "1 value given, 3 expected")
bad("vector_two", sub("velocity = 0, 0, -1", "velocity = 0, -1"), "particle", "velocity",
    "2 values given, 3 expected")
bad("vector_long", sub("velocity = 0, 0, -1", "velocity = 0, 0, -1, 5"), "particle",
    "velocity", "4 values given, 3 expected")
bad("vector_repeat_count", sub("velocity = 0, 0, -1", "velocity = 2*0"), "particle",
    "velocity", "2 values given, 3 expected")
bad("key_twice", sub("dt = 1e-7,", "dt = 1e-7,\n     dt = 2e-7,"), "run", "dt",
    "given twice (lines 1 and 2)")
bad("end_closing", sub("gravity = 0, 0, 0 /", "gravity = 0, 0, 0 &end"), "run", None,
    "group &run opened at line 1 is closed with '&end' at line 1")
bad("not_closed", sub("gravity = 0, 0, 0 /", "gravity = 0, 0, 0"), "run", None,
    "group &run opened at line 1 is not closed with '/' before &output at line 2")
bad("unquoted", sub("&particle material = 'glass'", "&particle material = glass"),
    "particle", "material", "quote it")
bad("long_dir", sub("&output interval = 1e-6 /", "&output interval = 1e-6, dir = '" +
                    "d" * 513 + "' /"), "output", "dir", "513 characters, at most 512")
bad("steps_overflow", sub("t_end = 1e-5", "t_end = 1e30"), "run", "t_end", "steps of dt")
bad("divisions_real", sub("half_width = 0.1 /", "half_width = 0.1, divisions = 1e5 /"),
    "wall_plane", "divisions", "an integer is expected")
bad("divisions_range", sub("half_width = 0.1 /", "half_width = 0.1, divisions = 100000 /"),
    "wall_plane", "divisions", "1 .. 32767")
bad("divisions_memory", sub("half_width = 0.1 /", "half_width = 0.1, divisions = 32767 /"),
    "wall_plane", "divisions", "MiB of this machine")
bad("bins_range", GOOD + "&probe name = 'h', kind = 'histogram', time = 0, v_min = 0, "
    "v_max = 1, bins = 2000000000 /\n", "probe", "bins", "1 .. 10000000")
# cylinder probe regions, and the outlets' columns of probes.csv
CYL = GOOD + "&probe name = 'c', kind = 'count', region = 'cylinder', "
bad("cylinder_no_base", CYL + "cylinder_radius = 0.1 /\n", "probe", "cylinder_base", "required")
bad("cylinder_no_radius", CYL + "cylinder_base = 0, 0, 0 /\n", "probe", "cylinder_radius",
    "required")
bad("cylinder_radius", CYL + "cylinder_base = 0, 0, 0, cylinder_radius = -1 /\n", "probe",
    "cylinder_radius", "must be > 0")
bad("cylinder_axis", CYL + "cylinder_base = 0, 0, 0, cylinder_radius = 1, "
    "cylinder_axis = 0, 0, 0 /\n", "probe", "cylinder_axis", "non-zero")
bad("cylinder_nan_base", CYL + "cylinder_base = 0, NaN, 0, cylinder_radius = 1 /\n", "probe",
    "cylinder_base", "finite")
bad("cylinder_height", CYL + "cylinder_base = 0, 0, 0, cylinder_radius = 1, "
    "cylinder_height = 0 /\n", "probe", "cylinder_height", "must be > 0")
bad("probe_region", GOOD + "&probe name = 'c', kind = 'count', region = 'sphere' /\n", "probe",
    "region", "all, box, cylinder")
bad("probe_name", GOOD + "&probe name = 'a b', kind = 'count' /\n", "probe", "name",
    "letters, digits and _ only")
bad("coarse_grain_name", GOOD + "&coarse_grain name = 'x-y', box_min = 0, 0, 0, "
    "box_max = 1, 1, 1, cells = 2, 2, 2, width = 0.1 /\n", "coarse_grain", "name",
    "letters, digits and _ only")
bad("probe_outflow_name", GOOD + "&outlet region = 'plane', point = 0, 0, -1, "
    "normal = 0, 0, -1 /\n&probe name = 'outflow', kind = 'count' /\n", "probe", "name",
    "outflow_<material>")
bad("insert_memory", GOOD + INS.replace("n = 5", "n = 2000000000") + "radius_min = 1e-3 /\n",
    "insert", "n", "MiB of this machine")
bad("insert_behind_wall", GOOD + INS.replace("0.03, box_max", "-0.02, box_max") +
    "radius_min = 1e-3 /\n", "wall_plane", None, "reaches 2.0000E-02 m behind this wall")
bad("ids_overflow", sub("&particle material", "&particle id = 9223372036854775805, material")
    + INS + "radius_min = 1e-3 /\n", "insert", "n", "largest id")
bad("tiny_radius", sub("t_end = 1e-5,", "t_end = 1e-5, allow_unstable = .true.,")
    .replace("radius = 0.01", "radius = 1e-300"), None, "radius", "out of range")
bad("spinning_light", sub("velocity = 0, 0, -1", "velocity = 0, 0, -1, angular_velocity = "
                          "1e300, 0, 0"), None, "angular_velocity", "out of range")
bad("spinning", sub("velocity = 0, 0, -1", "velocity = 0, 0, -1, angular_velocity = 1e7, "
                    "0, 0"), "run", "max_speed", "rim speed")
# a component by its subscript, and a list given in part, are read
path = os.path.join(work, "good_parts.nml")
with open(path, "w") as f:
    f.write(sub("gravity = 0, 0, 0", "gravity(3) = 0") + INS + "radius_distribution = "
            "'discrete', radii = 1e-3, 2e-3, fractions = 0.4, 0.6, fraction_by = 'number' /\n")
r, _ = run(["--check", path], "good_parts")
check(r.returncode == 0, f"a vector's component, a list in part: --check failed: {r.stderr}")
# an &insert box in front of the floor, touching it, is accepted
path = os.path.join(work, "good_touching.nml")
with open(path, "w") as f:
    f.write(GOOD + INS.replace("0.03, box_max", "0.0, box_max") + "radius_min = 1e-3 /\n")
r, _ = run(["--check", path], "good_touching")
check(r.returncode == 0, f"an &insert box touching a wall: --check failed: {r.stderr}")

# --check prints the particles' radii and the box of the particles and of the walls, and warns
# where the walls span more than 1e4 diameters of the largest particle (a file in millimetres)
# or less than one (radii in millimetres); the good case's plane, 0.2 m square, spans
# 0.2 sqrt(2) = 0.2828 m, 14.1 diameters of its sphere
for name, text, words, warning in (
        ("scene_good", GOOD, ["particle radii        1.00000E-02 to  1.00000E-02 m",
                              "walls within          -1.0000E-01 -1.0000E-01  0.0000E+00 to"
                              "  1.0000E-01  1.0000E-01  0.0000E+00 m",
                              "particles within      -1.0000E-02 -1.0000E-02  1.0000E-03 to"],
         None),
        # the plane 200 m square: 282.84 m over 0.02 m diameters
        ("scene_mm", sub("half_width = 0.1", "half_width = 100"), [],
         "the walls span 1.414E+04 diameters"),
        # a sphere of radius 2 above the 0.2 m square
        ("scene_radius_mm", sub("radius = 0.01, position = 0, 0, 0.011",
                                "radius = 2, position = 0, 0, 2.5"), [],
         "the walls span less than the diameter of the largest particle")):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text)
    r, _ = run(["--check", path], name)
    check(r.returncode == 0, f"{name}: --check exit {r.returncode}: {r.stderr.strip()}")
    for w in words:
        check(w in r.stdout, f"{name}: --check does not print '{w}': {r.stdout}")
    if warning:
        check("warning: " + warning in r.stdout, f"{name}: no warning '{warning}': {r.stdout}")
    else:
        check("warning" not in r.stdout, f"{name}: a warning: {r.stdout}")

# an &insert region = 'mesh' must be a closed surface: a cube of 12 triangles is, and --check
# says so; the same cube without its lid (its 2 top triangles) has the 4 edges of its rim in
# one triangle only, and is refused
CUBE = [((0, 0, 0), (1, 1, 0), (1, 0, 0)), ((0, 0, 0), (0, 1, 0), (1, 1, 0)),
        ((0, 0, 1), (1, 0, 1), (1, 1, 1)), ((0, 0, 1), (1, 1, 1), (0, 1, 1)),
        ((0, 0, 0), (1, 0, 0), (1, 0, 1)), ((0, 0, 0), (1, 0, 1), (0, 0, 1)),
        ((0, 1, 0), (1, 1, 1), (1, 1, 0)), ((0, 1, 0), (0, 1, 1), (1, 1, 1)),
        ((0, 0, 0), (0, 0, 1), (0, 1, 1)), ((0, 0, 0), (0, 1, 1), (0, 1, 0)),
        ((1, 0, 0), (1, 1, 1), (1, 0, 1)), ((1, 0, 0), (1, 1, 0), (1, 1, 1))]
for name, tris in (("cube", CUBE), ("cube_open", CUBE[:2] + CUBE[4:])):
    with open(os.path.join(work, name + ".stl"), "w") as f:
        f.write("solid c\n" + "".join(
            " facet normal 0 0 0\n  outer loop\n" + "".join(
                f"   vertex {x * 0.04 - 0.02} {y * 0.04 - 0.02} {z * 0.04 + 0.03}\n"
                for x, y, z in t) + "  endloop\n endfacet\n" for t in tris) + "endsolid c\n")
MESH_INS = ("&insert n = 5, material = 'glass', radius_min = 1e-3, region = 'mesh', "
            "mesh_file = '{}' /\n")
path = os.path.join(work, "good_mesh_region.nml")
with open(path, "w") as f:
    f.write(GOOD + MESH_INS.format(os.path.join(work, "cube.stl")))
r, _ = run(["--check", path], "good_mesh_region")
check(r.returncode == 0 and "insert region        mesh of 12 triangles, closed (" in r.stdout,
      f"a closed mesh region: --check exit {r.returncode}, {r.stderr.strip()} {r.stdout}")
bad("mesh_region_open", GOOD + MESH_INS.format(os.path.join(work, "cube_open.stl")), "insert",
    "mesh_file", "the surface is not closed (4 edges belong to one triangle only)")

# particle files: every field read whole, at any length, and wholly a number
CSV_CASE = sub("&particle material = 'glass', radius = 0.01, position = 0, 0, 0.011, "
               "velocity = 0, 0, -1 /", "&particle_file file = '{csv}' /")
for name, row, ok, words in (
        ("csv_padded", "1,glass," + " " * 70 + "1e-3,0,0,0.011,0,0,-1", True, "1.000E-03 m"),
        ("csv_unit", "1,glass,0.01,0,0,0.011,0.5 m/s,0,-1", False, "p_csv_unit.csv:2: "
         "column 'vx': '0.5 m/s' is not a finite number"),
        ("csv_long_garbage", "1,glass,0.01" + "7" * 100 + "x,0,0,0.011,0,0,-1", False,
         "p_csv_long_garbage.csv:2: column 'radius'"),
        ("csv_id", "1.5,glass,0.01,0,0,0.011,0,0,-1", False, "column 'id'")):
    csv = os.path.join(work, f"p_{name}.csv")
    with open(csv, "w") as f:
        f.write("id,material,radius,x,y,z,vx,vy,vz\n" + row + "\n")
    text = CSV_CASE.format(csv=csv)
    if ok:
        path = os.path.join(work, name + ".nml")
        with open(path, "w") as f:
            f.write(text)
        r, _ = run(["--check", path], name)
        check(r.returncode == 0 and words in r.stdout,
              f"{name}: exit {r.returncode}, {r.stderr.strip()} (radius {words} expected)")
    else:
        bad(name, text, "particle_file", "file", words)

# the memory estimate of --check is within a factor of 2 of the peak resident size on a
# large mesh (issue 30, item 8: a plane of 18 million triangles reached 5.9 GB with 1.4 GB
# estimated, and a plane's corners on the stack crashed it): a plane of a million triangles
big = os.path.join(work, "big_plane.nml")
with open(big, "w") as f:
    f.write(PLANE.format(nz="1").replace("half_width = 0.05", "half_width = 0.05, "
                                         "divisions = 700").replace("t_end = 0.002",
                                                                     "t_end = 2e-5"))
r, _ = run([big], "big_plane")
estimate = re.search(r"estimated memory +(\S+) MiB", r.stdout)
peak = re.search(r"memory: peak resident +(\S+) MiB", r.stdout)
check(r.returncode == 0 and estimate and peak, f"big plane: exit {r.returncode} "
      f"{r.stderr.strip()}, or no estimate or peak printed")
if estimate and peak:
    ratio = float(peak.group(1)) / float(estimate.group(1))
    print(f"big plane: estimated {estimate.group(1)} MiB, peak resident {peak.group(1)} MiB")
    check(0.5 <= ratio <= 2.0, f"big plane: peak / estimate = {ratio:.3g}, outside 0.5..2")

# command line
r, _ = run(["--version"], "version")
check(r.returncode == 0 and r.stdout.startswith("dem "), f"--version: {r.stdout} {r.stderr}")
r, _ = run(["--help"], "help")
check(r.returncode == 0 and "usage" in r.stdout, "--help")
r, _ = run([], "noargs")
check(r.returncode == 2 and "usage" in r.stderr.lower() + "--help", "no arguments")
r, _ = run(["--frobnicate"], "badoption")
check(r.returncode == 2 and "unknown option" in r.stderr, "unknown option")
# clumps (&clump_template, &clump)
CT = ("&clump_template name = 'd', material = 'glass', "
      "members = -0.005, 0, 0, 0.006,  0.005, 0, 0, 0.006 /\n")
CL = "&clump template = 'd', position = 0, 0, 0.1 /\n"
with open(os.path.join(work, "good_clump.nml"), "w") as f:
    f.write(GOOD + CT + CL)
r, d = run(["--check", os.path.join(work, "good_clump.nml")], "good_clump")
check(r.returncode == 0 and "clumps               1" in r.stdout,
      f"good clump: --check failed or does not print the clumps: {r.stderr} {r.stdout}")
bad("clump_unknown_template", GOOD + CT + CL.replace("'d'", "'e'"), "clump", "template")
bad("clump_orientation", GOOD + CT + CL.replace("/", ", orientation = 1, 1, 0, 0 /"),
    "clump", "orientation", "unit quaternion")
bad("clump_position", GOOD + CT + CL.replace("position = 0, 0, 0.1", "velocity = 1, 0, 0"),
    "clump", "position")
bad("clump_members_part", GOOD + CT.replace("0.005, 0, 0, 0.006 /", "0.005, 0 /") + CL,
    "clump_template", "members")
bad("clump_members_radius", GOOD + CT.replace("0.005, 0, 0, 0.006 /", "0.005, 0, 0, 0 /")
    + CL, "clump_template", "members", "member 2")
bad("clump_mass_alone", GOOD + CT.replace("/", ", mass = 1e-3 /") + CL, "clump_template",
    "mass", "given together")
bad("clump_template_twice", GOOD + CT + CT + CL, "clump_template", "name")
bad("clump_rigid", GOOD + "&material name = 'wall', rigid = .true. /\n"
    + CT.replace("'glass'", "'wall'") + CL, "clump_template", "material", "rigid")
# clumps from files (&clump_template file, &clump_file)
for name, text in (("members_bad.csv", "x,y,z,radius\n-0.005 0 0 0.006\n0.005, 0, 0\n"),
                   ("members_radius.csv", "-0.005,0,0,0.006\n0.005,0,0,-1\n"),
                   ("clumps_good.csv", "d,0,0,0.1,1,0,0,0\n"),
                   ("clumps_bad.csv", "template,x,y,z,q0,q1,q2,q3\nd,0,0,0.1,1,0,0,0\n"
                                      "d,0,0,one,1,0,0,0\n"),
                   ("clumps_columns.csv", "d 0 0 0.1 1 0 0 0 0 0 0 0 0 0\n"),
                   ("clumps_template.csv", "\nd,0,0,0.1,1,0,0,0\ne,0,0,0.2,1,0,0,0\n"),
                   ("clumps_quaternion.csv", "d,0,0,0.1,1,0,0,0\nd,0,0,0.2,1,1,0,0\n")):
    with open(os.path.join(work, name), "w") as f:
        f.write(text)
CTF = "&clump_template name = 'd', material = 'glass', file = 'members.csv' /\n"
CF = "&clump_file file = 'clumps_good.csv' /\n"
with open(os.path.join(work, "members.csv"), "w") as f:
    f.write("x,y,z,radius\n-0.005,0,0,0.006\n0.005,0,0,0.006\n")
with open(os.path.join(work, "good_clump_files.nml"), "w") as f:
    f.write(GOOD + CTF + CF)
r, d = run(["--check", os.path.join(work, "good_clump_files.nml")], "good_clump_files")
check(r.returncode == 0 and "clumps               1" in r.stdout,
      f"good clump files: --check failed or does not print the clumps: {r.stderr} {r.stdout}")
bad("clump_members_file_missing", GOOD + CTF.replace("members.csv", "none.csv") + CL,
    "clump_template", "file", "none.csv: the members file does not exist")
bad("clump_members_file_line", GOOD + CTF.replace("members.csv", "members_bad.csv") + CL,
    "clump_template", "file", "members_bad.csv:3: 3 values; 4 are expected")
bad("clump_members_file_radius", GOOD + CTF.replace("members.csv", "members_radius.csv")
    + CL, "clump_template", "file", "members_radius.csv:2: column 'radius'")
bad("clump_members_and_file", GOOD + CT.replace("/", ", file = 'members.csv' /") + CL,
    "clump_template", "members", "not both")
bad("clump_no_members", GOOD + "&clump_template name = 'd', material = 'glass' /\n" + CL,
    "clump_template", "file", "is required")
bad("clump_file_missing", GOOD + CT + CF.replace("clumps_good", "none"), "clump_file",
    "file", "none.csv: the clumps file does not exist")
bad("clump_file_no_file", GOOD + CT + "&clump_file /\n", "clump_file", "file", "required")
bad("clump_file_number", GOOD + CT + CF.replace("good", "bad"), "clump_file", "file",
    "clumps_bad.csv:3: column 'z': 'one' is not a finite number")
bad("clump_file_columns", GOOD + CT + CF.replace("good", "columns"), "clump_file", "file",
    "clumps_columns.csv:1: 14 values; 8 are expected")
bad("clump_file_template", GOOD + CT + CF.replace("good", "template"), "clump_file", "file",
    "clumps_template.csv:3: column 'template': 'e' is not a &clump_template's name")
bad("clump_file_quaternion", GOOD + CT + CF.replace("good", "quaternion"), "clump_file",
    "file", "clumps_quaternion.csv:2: columns 'q0' to 'q3': not a unit quaternion")
# bonds (&bond), fixed particles, local damping
PAIR2 = ("&particle id = 2, material = 'glass', radius = 0.01, position = 0.02, 0, 0.011 /\n"
         "&particle id = 3, material = 'glass', radius = 0.01, position = 0.1, 0, 0.011 /\n")
BOND = "&bond modulus = 1e8 /\n"
with open(os.path.join(work, "good_bond.nml"), "w") as f:
    f.write(GOOD + PAIR2 + BOND)
r, d = run(["--check", os.path.join(work, "good_bond.nml")], "good_bond")
check(r.returncode == 0 and "bonds                1 " in r.stdout,
      f"good bond: --check failed or does not print the bond: {r.stderr} {r.stdout}")
with open(os.path.join(work, "pairs_bad.csv"), "w") as f:
    f.write("id1,id2\n1,2\n1,7\n")
with open(os.path.join(work, "pairs_text.csv"), "w") as f:
    f.write("1,2\none,two\n")
bad("bond_modulus", GOOD + PAIR2 + "&bond /\n", "bond", "modulus")
bad("bond_material", GOOD + PAIR2 + BOND.replace("/", ", materials = 'glass', 'sand' /"),
    "bond", "materials", "not a defined material")
bad("bond_radius_ratio", GOOD + PAIR2 + BOND.replace("/", ", radius_ratio = 1.5 /"), "bond",
    "radius_ratio")
bad("bond_distribution", GOOD + PAIR2 + BOND.replace("/", ", strength_distribution = 'gauss' /"),
    "bond", "strength_distribution")
bad("bond_spread", GOOD + PAIR2 + BOND.replace("/", ", tensile_strength = 1e5, "
    "strength_distribution = 'weibull' /"), "bond", "strength_spread")
bad("bond_region", GOOD + PAIR2 + BOND.replace("/", ", region_min = 0, 0, 0 /"), "bond",
    "region_max")
bad("bond_no_pair", GOOD + BOND, "bond", "gap", "no pair to bond")
bad("bond_file_missing", GOOD + PAIR2 + BOND.replace("/", ", file = 'none.csv' /"), "bond",
    "file", "none.csv")
bad("bond_file_id", GOOD + PAIR2 + BOND.replace("/", ", file = 'pairs_bad.csv' /"), "bond",
    "file", "names no particle")
bad("bond_file_text", GOOD + PAIR2 + BOND.replace("/", ", file = 'pairs_text.csv' /"), "bond",
    "file", "pairs_text.csv:2")
bad("bond_file_and_gap", GOOD + PAIR2 + BOND.replace("/", ", file = 'pairs_bad.csv', "
    "gap = 0.001 /"), "bond", "file")
bad("run_local_damping", GOOD.replace("gravity = 0, 0, 0 /", "gravity = 0, 0, 0, "
    "local_damping = 1.0 /"), "run", "local_damping")

check_bad_cases()
finish()
