#!/usr/bin/env python3
"""FE speed against CalculiX on the same meshes (issue 3).

For each mesh size of a steel block 0.4 x 0.1 x 0.1 m (tet10, clamped at one end, 10 kN
on the other), bench/fe_bench meshes, assembles, factors and solves it stage by stage
(nnz of the factor, peak memory, a Newmark step against the bandwidth bound of two
triangular solves) and writes the identical problem as a CalculiX deck; `ccx` then solves
that deck (whole process, its own input parsing and output included) and the nodal
displacements of both are compared.

Usage: python3 bench/fe_speed.py [--sizes 0.02,0.014,0.01,0.0075,0.0066] [--ccx-threads N]
                                [--solver auto|cholmod|petsc] [--ranks N] [--steps N]
(--ranks N runs fe_bench under mpirun -np N: the PETSc backend shares the solve)
(after scripts/setup.sh; installs Debian's calculix-ccx when it is missing). Writes
bench/results/fe_speed.json and prints a table.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FE_BENCH = os.path.join(ROOT, "build", "release", "bench", "fe_bench")


def run_measured(cmd, cwd, env=None):
    """Wall time and peak resident memory (bytes) of one child process."""
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{out.decode(errors='replace')[-2000:]}")
    return wall, usage.ru_maxrss * 1024, out.decode(errors="replace")


def read_ccx_displacements(path, count):
    u = [None] * count
    with open(path) as f:
        inside = False
        for line in f:
            if "displacements" in line:
                inside = True
                continue
            parts = line.split()
            if inside and len(parts) == 4:
                u[int(parts[0]) - 1] = [float(x) for x in parts[1:]]
    return u


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="0.02,0.014,0.01,0.0075,0.0066")
    ap.add_argument("--ccx-threads", type=int, default=2)
    ap.add_argument("--solver", default="cholmod")
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--steps", type=int, default=20, help="Newmark steps timed (0: none)")
    args = ap.parse_args()
    if not os.path.exists(FE_BENCH):
        sys.exit("build first: bash scripts/setup.sh")
    if shutil.which("ccx") is None:
        subprocess.run(["apt-get", "install", "-y", "calculix-ccx"], check=True,
                       stdout=subprocess.DEVNULL)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in [float(s) for s in args.sizes.split(",")]:
            inp, sol = os.path.join(tmp, "block.inp"), os.path.join(tmp, "vproto.u")
            cmd = [FE_BENCH, "--size", str(size), "--inp", inp, "--solution", sol,
                   "--solver", args.solver, "--steps", str(args.steps)]
            if args.ranks > 1:
                cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np",
                       str(args.ranks)] + cmd
            wall, rss, out = run_measured(cmd, tmp)
            r = json.loads(out[out.index("{"):])
            r["fe_bench_wall_s"] = wall
            env = dict(os.environ, OMP_NUM_THREADS=str(args.ccx_threads),
                       CCX_NPROC_EQUATION_SOLVER=str(args.ccx_threads))
            ccx_wall, ccx_rss, _ = run_measured(["ccx", "block"], tmp, env)
            r["ccx_wall_s"] = ccx_wall
            r["ccx_peak_memory_bytes"] = ccx_rss
            # agreement: largest nodal difference over the largest displacement
            mine = [float(x) for x in open(sol).read().split()]
            theirs = read_ccx_displacements(os.path.join(tmp, "block.dat"), len(mine) // 3)
            scale = max(abs(x) for x in mine)
            diff = max(abs(mine[3 * i + k] - theirs[i][k]) for i in range(len(theirs)) for k in range(3))
            r["ccx_max_difference_relative"] = diff / scale
            r["static_over_ccx"] = r["static_total_s"] / ccx_wall
            results.append(r)
            print(f"h={size:<7} dofs={r['dofs']:>7} {r['backend']} x{r['ranks']} it={r['iterations']} "
                  f"nnzL={r['nnz_L']:.3g} ({r['ordering']}) "
                  f"mesh {r['mesh_s']:.2f}s assemble {r['assemble_s']:.2f}s "
                  f"analyse {r['analyze_s']:.2f}s factor {r['factor_s']:.2f}s solve {r['solve_s']:.3f}s "
                  f"| static {r['static_total_s']:.2f}s vs ccx {ccx_wall:.2f}s = {r['static_over_ccx']:.2f}x "
                  f"| mem {r['peak_memory_static_bytes'] / 1e9:.2f} GB vs ccx {ccx_rss / 1e9:.2f} GB "
                  f"| step {1e3 * r['dynamic_step_s']:.1f} ms = {r['step_over_bound']:.2f}x bound "
                  f"({r['read_bandwidth_GBps']:.1f} GB/s) | ccx diff {r['ccx_max_difference_relative']:.1e}",
                  flush=True)
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "fe_speed.json"), "w") as f:
        json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
