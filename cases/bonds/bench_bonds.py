# SPDX-License-Identifier: BSD-3-Clause
"""The cost per bond, dem beside Yade, one core each: a cantilever of N spheres (N - 1
bonds, the beam of dem_bonds.py made long), sphere 0 clamped, gravity, no damping, STEPS
steps; dem on one rank, Yade with -j1 (yade_chain.py), alternating A B A B. From the
repository root:

    .venv/bin/python cases/bonds/bench_bonds.py --dem build/dem [--yade yade]
        [--spheres 2001] [--steps 20000] [--repeat 2] [--work DIR] [--out FILE]

Each run's ns per bond-step is the time of its steps over (steps x bonds): dem's own
`timing:` line (the time-step loop), Yade's O.run (set-up excluded); the table also gives
the whole process's wall and CPU time (start-up and set-up included) and dem's phases. Both
run under `nice -n 0`; dem writes one series row at the end and no snapshot (&run
progress_interval = 0)."""
import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bond_cases as bc  # noqa: E402
from dem_bonds import case_text, chain  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def timed(cmd, cwd):
    """Run cmd; its result, wall time [s] and CPU time (user + system) [s]."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stdout}\n{r.stderr}")
    return r, wall, cpu


def run_dem(dem, work, n, steps):
    t_end = steps * bc.DT
    with open(os.path.join(work, "chain.nml"), "w") as f:
        f.write(case_text("chain", t_end, t_end, chain(n), "", bc.G))
    r, wall, cpu = timed(["nice", "-n", "0", dem, "chain.nml"], work)
    m = re.search(r"timing: (\d+) steps of (\d+) particles in\s+(\S+) s", r.stdout)
    phases = {p: float(s) for p, s in re.findall(r"timing:\s+(\w+)\s+(\S+) s", r.stdout)}
    bonds = int(re.search(r"bonds\s+(\d+)", r.stdout).group(1))
    loop = float(m.group(3))
    return {"code": "dem", "steps": int(m.group(1)), "bonds": bonds, "loop_s": loop,
            "process_s": wall, "process_cpu_s": cpu,
            "ns_per_bond_step": loop / (int(m.group(1)) * bonds) * 1e9, "phases_s": phases}


def run_yade(yade, work, n, steps):
    out = os.path.join(work, "yade_chain.json")
    _, wall, cpu = timed(["nice", "-n", "0", yade, "-n", "-x", "-j1",
                          os.path.join(HERE, "yade_chain.py"), str(n), str(steps), "--out", out],
                         work)
    with open(out) as f:
        y = json.load(f)
    return {"code": "Yade " + y["yade"], "steps": y["steps"], "bonds": y["bonds"],
            "loop_s": y["wall_s"], "process_s": wall, "process_cpu_s": cpu,
            "ns_per_bond_step": y["ns_per_bond_step"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dem", required=True, help="the dem executable")
    ap.add_argument("--yade", default="yade", help="the Yade executable")
    ap.add_argument("--spheres", type=int, default=2001)
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=2, help="A B pairs")
    ap.add_argument("--work", default="output/bonds/bench")
    ap.add_argument("--out", help="write the runs here (JSON)")
    a = ap.parse_args()
    dem = os.path.abspath(a.dem)
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    runs = []
    for _ in range(a.repeat):
        runs.append(run_dem(dem, a.work, a.spheres, a.steps))
        runs.append(run_yade(a.yade, a.work, a.spheres, a.steps))
    print(f"{a.spheres} spheres, {a.steps} steps, one core each (A B A B)\n")
    print("| run | code | bonds | steps | time of the steps [s] | ns per bond-step "
          "| process: wall [s] | process: CPU [s] |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for k, r in enumerate(runs):
        print(f"| {k + 1} | {r['code']} | {r['bonds']} | {r['steps']} | {r['loop_s']:.3f} "
              f"| {r['ns_per_bond_step']:.1f} | {r['process_s']:.2f} "
              f"| {r['process_cpu_s']:.2f} |")
    names = list(runs[0]["phases_s"])
    print("\ndem's phases [s]:\n")
    print("| run | " + " | ".join(names) + " |")
    print("| --- |" + " --- |" * len(names))
    for k, r in enumerate(runs):
        if "phases_s" in r:
            print(f"| {k + 1} | " + " | ".join(f"{r['phases_s'][p]:.3f}" for p in names)
                  + " |")
    if a.out:
        with open(a.out, "w") as f:
            f.write(json.dumps({"spheres": a.spheres, "steps": a.steps, "runs": runs},
                               indent=1) + "\n")


if __name__ == "__main__":
    main()
