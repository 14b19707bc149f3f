# SPDX-License-Identifier: BSD-3-Clause
"""Stokes settling of a glass sphere in a viscous fluid, driven from Python (the worked
example of doc/user/python.md): the fluid's drag beta (u_f - v), beta = 6 pi mu R, and the
buoyancy rho_f V g are given to the DEM, which adds gravity; after 18 relaxation times the
sphere falls at the analytical terminal velocity 2 (rho_p - rho_f) g R^2 / (9 mu).

    python3 settling.py [folder]       (on several ranks: mpirun -np 2 python3 settling.py)
"""
import math
import os
import sys

import dem

mu, rho_f = 1.0, 1000.0                      # the fluid: viscosity [Pa s], density [kg/m^3]
rho_p, radius, g = 2500.0, 1e-3, 9.81        # the sphere
folder = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "settling")
case = os.path.join(folder, "settling.nml")
os.makedirs(folder, exist_ok=True)
with open(case, "w") as f:                   # (every rank writes the same text)
    f.write(f"""&run dt = 3e-5, t_end = 1.0, gravity = 0, 0, {-g} /
&output dir = '{folder}/output', interval = 1e-3, overwrite = .true. /
&material name = 'glass', density = {rho_p}, youngs_modulus = 1e7, poisson_ratio = 0.25 /
&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /
&particle id = 1, material = 'glass', radius = {radius}, position = 0, 0, 0 /
""")

volume = 4.0 / 3.0 * math.pi * radius**3
beta = 6.0 * math.pi * mu * radius          # Stokes drag coefficient [kg/s]
tau = rho_p * volume / beta                 # relaxation time [s]
v_t = 2.0 * (rho_p - rho_f) * g * radius**2 / (9.0 * mu)

with dem.Run(case) as run:                   # MPI_COMM_WORLD
    for step in range(1, 101):               # 10 ms: 18 relaxation times
        run.set_drag(beta, [0.0, 0.0, 0.0])              # still fluid, every owned sphere
        run.set_force([0.0, 0.0, rho_f * volume * g])    # buoyancy
        run.advance(1e-4)                                # the fluid step: 4 DEM sub-steps
        p = run.views()                                  # no copy: valid until the next advance
        if len(p.gid) and step % 20 == 0:
            print(f"t = {run.time:.4f} s  z = {p.x[0, 2] * 1e3:8.4f} mm  "
                  f"v_z = {p.v[0, 2] * 1e3:8.5f} mm/s")
    if run.count:
        v = run.particles().v[0, 2]
        print(f"terminal velocity: simulated {-v * 1e3:.6f} mm/s, "
              f"analytical {v_t * 1e3:.6f} mm/s")
