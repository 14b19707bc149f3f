# SPDX-License-Identifier: BSD-3-Clause
"""A friction sweep with dem.sweep (doc/user/python.md): a glass sphere launched sliding at
v0 = 0.1 m/s along a rigid floor, without spin, for three friction coefficients. Friction
slows it and spins it up until it rolls, at 5/7 v0 whatever mu, after t_r = 2 v0 / (7 mu g),
having slid 12 v0^2 / (49 mu g); the table compares the run with those formulas at 80 ms.

    python3 friction_sweep.py [folder]
"""
import os
import sys

import dem

v0, radius, g, t = 0.1, 1e-3, 9.81, 0.08
folder = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "friction_sweep")
os.makedirs(folder, exist_ok=True)
case = os.path.join(folder, "sliding.nml")
with open(case, "w") as f:
    f.write(f"""&run dt = 1e-6, t_end = 1.0, gravity = 0, 0, {-g} /
&output interval = 1e-3 /
&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&material name = 'rigid', rigid = .true. /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&pair materials = 'glass', 'rigid', restitution = 0.5, friction = 0.3 /
&wall_plane material = 'rigid', point = 0, 0, 0, normal = 0, 0, 1, half_width = 0.05 /
&particle id = 1, material = 'glass', radius = {radius}, position = 0, 0, {radius - 3.5e-7},
          velocity = {v0}, 0, 0 /
""")


def measure(run):
    """Where the sphere is and how it moves at the end (one sphere, on one rank)."""
    p = run.particles()
    return (p.x[0, 0], p.v[0, 0], p.w[0, 1] * radius) if run.count else None


results = dem.sweep(case, "pair.friction", [0.1, 0.2, 0.4], measure,
                    work_dir=os.path.join(folder, "runs"), until=t)
print("   mu   x [mm] (theory)    v [m/s] (theory)   w R [m/s]")
for mu, r in results:
    if r is None:
        continue
    x, v, w_r = r
    t_r = 2 * v0 / (7 * mu * g)
    x_theory = 12 * v0**2 / (49 * mu * g) + 5 / 7 * v0 * (t - t_r)
    print(f"{mu:5.2f}  {x * 1e3:7.3f} ({x_theory * 1e3:7.3f})  {v:.5f} ({5 / 7 * v0:.5f})"
          f"   {w_r:.5f}")
