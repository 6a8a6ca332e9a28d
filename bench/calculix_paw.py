#!/usr/bin/env python3
"""One snap-fit paw pushed over a fixed catch: vproto's quasistatic run against CalculiX (issue 10).

For each mesh size and friction coefficient asked for, this
1. runs `vproto run samples/paw_quasistatic.vp` (displacement-controlled, equilibrium with
   contact at each increment) with a fine increment and VTU export, which gives the tet10
   mesh vproto used and its reaction on the grip (history.csv: paw_rx, paw_rz);
2. writes the same problem as a CalculiX deck on the *same nodes and C3D10 elements*: the
   grip's nodes driven down (ux = uy = 0, uz ramped), the catch one C3D8 brick with every
   node held (a rigid block), contact SURFACE TO SURFACE (penalty, linear
   pressure-overclosure, Coulomb friction with a stick slope), the paw's faces near its tip
   the slave surface, the catch the master; small strain as vproto;
3. runs `ccx` and reads the grip's total reaction per increment (*NODE PRINT, TOTALS=ONLY);
4. compares the two curves against the drive's travel: the peak force to push the lead
   face over the catch's edge, the force while the hook's apex slides on the catch's face
   (a plateau), the lateral force there, and where the lead-face peak is.

Usage: python3 bench/calculix_paw.py [--mesh 0.1,0.07,0.05] [--mu 0,0.3] [--travel 0.7]
       [--penalty 1e13] [-o bench/results/paw_calculix.json]
(after scripts/setup.sh; installs Debian's calculix-ccx when it is missing)
"""
import argparse
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from calculix_compare import read_vtu  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
INCH = 0.0254
SAMPLE = os.path.join(ROOT, "samples", "paw_quasistatic.vp")

# the sample's geometry (inches), as its params give it
LENGTH, THICK, WIDTH = 2.0, 0.25, 0.5
HOOK_DEPTH, INTERFERENCE = 0.08, 0.06
CATCH = ((-1.0, -0.5, -0.7), (1.0 - (HOOK_DEPTH - INTERFERENCE), 1.0, 0.5))  # corner, size

# C3D10 faces by their corner nodes (CalculiX's numbering, 1-based in the element)
TET_FACES = {1: (0, 1, 2), 2: (0, 3, 1), 3: (1, 3, 2), 4: (2, 3, 0)}


def run_vproto(mesh_in, mu, travel_in, dt, work):
    out = os.path.join(work, "vproto")
    # the in-stroke only: the drive goes down by `travel` over its first second
    t_end = travel_in / 1.1
    started = time.perf_counter()
    subprocess.run([os.path.join(ROOT, "build/release/vproto"), "run", SAMPLE, "-o", out,
                    "--export", "vtu", "--frames", "2", "--no-render", "--quiet",
                    "--duration", repr(t_end), "--dt", repr(dt),
                    "--set", f"mesh={mesh_in}in", "--set", f"mu={mu}"], check=True)
    seconds = time.perf_counter() - started
    rows = list(csv.DictReader(open(os.path.join(out, "history.csv"))))
    # (travel, lateral force, force along the drive: the push) on the paw from its holder
    curve = [(float(r["t"]) * 1.1 * INCH, float(r["paw_rx"]), -float(r["paw_rz"])) for r in rows]
    vtu = os.path.join(out, "meshes", "paw_0000.vtu")
    nodes, elements, _, _ = read_vtu(vtu, fields=False)
    summary = json.load(open(os.path.join(out, "summary.json")))
    return nodes, elements, curve, seconds, summary


def boundary_faces(elements):
    count = {}
    for e, el in enumerate(elements):
        for f, corners in TET_FACES.items():
            key = tuple(sorted(el[c] for c in corners))
            count.setdefault(key, []).append((e, f))
    return [owners[0] for owners in count.values() if len(owners) == 1]


def catch_grid(spacing_in):
    """The catch as a grid of C3D8 bricks (every node held: a rigid block), fine along its two
    edges that can touch the paw (x = the face towards the paw, z = top and bottom): the
    nodes on those edges where the paw is (|y| <= 0.3 in) are contact points."""
    (cx, cy, cz), (sx, sy, sz) = CATCH
    xs = [cx, cx + sx / 2, cx + sx]
    zs = [cz, cz + sz / 2, cz + sz]
    ny = max(2, round(sy / spacing_in))
    ys = [cy + sy * k / ny for k in range(ny + 1)]
    index = {}
    nodes = []
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            for k, z in enumerate(zs):
                index[i, j, k] = len(nodes)
                nodes.append((x * INCH, y * INCH, z * INCH))
    bricks = []
    for i in range(2):
        for j in range(ny):
            for k in range(2):
                c = lambda a, b, d: index[i + a, j + b, k + d]
                bricks.append([c(0, 0, 0), c(1, 0, 0), c(1, 1, 0), c(0, 1, 0),
                               c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)])
    edges = [index[2, j, k] for j in range(ny + 1) for k in (0, 2) if abs(ys[j]) <= 0.3 + 1e-9]
    return nodes, bricks, edges


def write_deck(path, nodes, elements, mu, travel_m, penalty, e_mod, nu, increments, spacing_in):
    """Two node-to-face pairs, each with the normal of the face that is touched: the catch's
    edges against the paw's hook faces (the lead face riding over the top edge, the return
    face over the bottom one), and the hook's apex nodes against the catch's faces (the apex
    sliding on the face towards the paw). Face-to-face contact with the catch as master
    takes the catch's top-face normal where its edge presses the lead face, and jams."""
    n = len(nodes)
    top = max(p[2] for p in nodes)
    grip = [i for i, p in enumerate(nodes) if p[2] > top - 0.01 * INCH]
    apex_x = min(p[0] for p in nodes)
    apex = [i for i, p in enumerate(nodes) if p[0] < apex_x + 1e-4 * INCH]
    # the hook's faces: boundary faces whose corners all lie left of the paw's body (x < 0)
    hook = []
    for e, f in boundary_faces(elements):
        corners = [nodes[elements[e][c]] for c in TET_FACES[f]]
        if all(p[0] < -1e-6 * INCH for p in corners) or (
                all(p[0] < 1e-6 * INCH for p in corners) and any(p[0] < -1e-6 * INCH for p in corners)):
            hook.append((e, f))
    cnodes, bricks, edges = catch_grid(spacing_in)
    with open(path, "w") as f:
        f.write("*NODE, NSET=NALL\n")
        for i, p in enumerate(nodes):
            f.write(f"{i + 1}, {p[0]:.13g}, {p[1]:.13g}, {p[2]:.13g}\n")
        f.write("*NODE, NSET=CATCHN\n")
        for k, p in enumerate(cnodes):
            f.write(f"{n + k + 1}, {p[0]:.13g}, {p[1]:.13g}, {p[2]:.13g}\n")
        f.write("*ELEMENT, TYPE=C3D10, ELSET=PAW\n")
        for i, el in enumerate(elements):
            f.write(f"{i + 1}, " + ", ".join(str(v + 1) for v in el) + "\n")
        f.write("*ELEMENT, TYPE=C3D8, ELSET=CATCH\n")
        first = len(elements) + 1
        for k, b in enumerate(bricks):
            f.write(f"{first + k}, " + ", ".join(str(n + v + 1) for v in b) + "\n")
        f.write("*NSET, NSET=GRIP\n" + "".join(f"{i + 1},\n" for i in grip))
        f.write("*NSET, NSET=APEX\n" + "".join(f"{i + 1},\n" for i in apex))
        f.write("*NSET, NSET=EDGES\n" + "".join(f"{n + i + 1},\n" for i in edges))
        f.write("*SURFACE, NAME=HOOK, TYPE=ELEMENT\n" + "".join(f"{e + 1}, S{face}\n" for e, face in hook))
        f.write("*SURFACE, NAME=APEXS, TYPE=NODE\nAPEX\n*SURFACE, NAME=EDGESS, TYPE=NODE\nEDGES\n")
        # the catch's faces: top (S2), towards the paw (+x, S4), underside (S1) of its bricks
        faces = []
        for k, b in enumerate(bricks):
            pts = [cnodes[v] for v in b]
            if pts[4][2] > (CATCH[0][2] + CATCH[1][2]) * INCH - 1e-9:
                faces.append(f"{first + k}, S2")
            if pts[0][2] < CATCH[0][2] * INCH + 1e-9:
                faces.append(f"{first + k}, S1")
            if pts[1][0] > (CATCH[0][0] + CATCH[1][0]) * INCH - 1e-9:
                faces.append(f"{first + k}, S4")
        f.write("*SURFACE, NAME=CATCHS, TYPE=ELEMENT\n" + "".join(x + "\n" for x in faces))
        f.write(f"*MATERIAL, NAME=LDPE\n*ELASTIC\n{e_mod:.13g}, {nu:.13g}\n")
        f.write(f"*MATERIAL, NAME=STIFF\n*ELASTIC\n{e_mod * 1e3:.13g}, 0.3\n")
        f.write("*SOLID SECTION, ELSET=PAW, MATERIAL=LDPE\n*SOLID SECTION, ELSET=CATCH, MATERIAL=STIFF\n")
        f.write("*SURFACE INTERACTION, NAME=SI\n")
        f.write(f"*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{penalty:.6g}, 1e-3, {0.02 * INCH:.6g}\n")
        if mu > 0:
            f.write(f"*FRICTION\n{mu:.6g}, {penalty / 10:.6g}\n")
        f.write("*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE\nEDGESS, HOOK\nAPEXS, CATCHS\n")
        f.write("*BOUNDARY\nCATCHN, 1, 3, 0.\n")
        step = 1.0 / increments
        f.write(f"*STEP, INC=100000\n*STATIC\n{step:.6g}, 1., {step * 1e-3:.6g}, {step:.6g}\n")
        f.write(f"*BOUNDARY\nGRIP, 1, 2, 0.\nGRIP, 3, 3, {-travel_m:.13g}\n")
        f.write("*NODE PRINT, NSET=GRIP, TOTALS=ONLY\nRF\n*END STEP\n")
    return {"grip_nodes": len(grip), "apex_nodes": len(apex), "catch_edge_nodes": len(edges),
            "hook_faces": len(hook)}


def read_totals(path, travel_m):
    """(travel, rx, rz) per converged increment: the grip's total reaction."""
    text = open(path).read()
    out = [(0.0, 0.0, 0.0)]
    pattern = r"total force \(fx,fy,fz\) for set GRIP and time\s+(\S+)\s+([-+.\dEe]+)\s+([-+.\dEe]+)\s+([-+.\dEe]+)"
    for m in re.finditer(pattern, text):
        t = float(m.group(1))
        out.append((t * travel_m, float(m.group(2)), -float(m.group(4))))
    return out


def at(curve, s, column):
    """Linear interpolation of a curve's column at travel s."""
    for (s0, *a), (s1, *b) in zip(curve, curve[1:]):
        if s0 <= s <= s1:
            w = 0.0 if s1 == s0 else (s - s0) / (s1 - s0)
            return a[column] + w * (b[column] - a[column])
    return None


def figures(curve):
    """With this geometry (travel in inches): the lead face rides over the catch's top edge
    from 0.22 to 0.28 (the force rising to its peak where the apex reaches the edge), the
    apex slides on the catch's face from 0.28 to 0.78, and the return face slides off the
    bottom edge until 0.84, where the paw is home. Sampled peaks depend on the increment, so
    the lead face is also compared at a fixed travel (0.26, a step of either tool before the
    apex reaches the edge), interpolated; where the apex passes the edge is the first
    increment after the peak that carries less than half of it."""
    s = lambda inch: inch * INCH
    lead = [c for c in curve if c[0] <= s(0.38)]
    peak = max(lead, key=lambda c: c[2])
    slide = [c for c in curve if s(0.40) <= c[0] <= s(0.60)]
    mean = lambda k: sum(c[k] for c in slide) / len(slide) if slide else float("nan")
    after = [c for c in curve if c[0] > peak[0] and c[2] < 0.5 * peak[2]]
    out = {"lead_push_at_0.26in_N": at(curve, s(0.26), 1), "lead_lateral_at_0.26in_N": at(curve, s(0.26), 0),
           "peak_push_N": peak[2], "peak_travel_mm": peak[0] * 1e3,
           "apex_passes_edge_mm": [peak[0] * 1e3, after[0][0] * 1e3] if after else None,
           "sliding_push_N": mean(2), "sliding_lateral_N": mean(1)}
    # home: after the plateau, where the lateral force has fallen below 1 % of it
    home = [c for c in curve if c[0] > s(0.7) and abs(c[1]) < 0.01 * abs(out["sliding_lateral_N"])]
    out["home_travel_mm"] = home[0][0] * 1e3 if home else None
    out["last_travel_mm"] = curve[-1][0] * 1e3
    return out


def lead_curve_difference(v, c):
    """The largest difference of the two curves over the lead face's rise (travel 0.235..0.26
    in, both interpolated at 26 points), relative to CalculiX's largest value there, for the
    push and the lateral force."""
    worst, scale = [0.0, 0.0], [0.0, 0.0]
    for k in range(26):
        s = (0.235 + 0.025 * k / 25) * INCH
        for col in (0, 1):
            a, b = at(v, s, col), at(c, s, col)
            if a is not None and b is not None:
                worst[col] = max(worst[col], abs(a - b))
                scale[col] = max(scale[col], abs(b))
    return {"lateral": worst[0] / scale[0], "push": worst[1] / scale[1]}


FORCES = ("lead_push_at_0.26in_N", "lead_lateral_at_0.26in_N", "peak_push_N", "sliding_push_N",
          "sliding_lateral_N", "home_travel_mm")


def compare(row):
    """The figures of both curves of a row, their ratios and the lead-face curves' difference."""
    v, c = (row["curves"][k] for k in ("vproto", "calculix"))
    travel = row["travel_in"] * INCH
    row["vproto"].update(figures(v), increments=len(v) - 1)
    row["calculix"].update(figures(c), increments=len(c) - 1, finished=c[-1][0] >= 0.999 * travel)
    if not row["calculix"]["finished"]:
        row["calculix"]["home_travel_mm"] = None
    vp, cc = row["vproto"], row["calculix"]
    row["difference"] = {k: vp[k] / cc[k] - 1 for k in FORCES
                         if vp.get(k) is not None and cc.get(k) is not None and abs(cc[k]) > 1e-3}
    row["lead_curve_difference"] = lead_curve_difference(v, c)


def markdown(results):
    lines = ["| mesh (in) | nodes | mu | push at 0.26 in (N) vproto / ccx | lateral at 0.26 in (N) | "
             "lead-face rise, largest difference | sliding push (N) | sliding lateral (N) | "
             "apex passes the edge (mm) vproto / ccx | peak push, sampled (N) vproto / ccx | "
             "home (mm) | vproto s | ccx s |", "|" + "---|" * 13]
    for r in results:
        v, c, d = r["vproto"], r["calculix"], r["difference"]

        def pair(k, f="%.4g"):
            if abs(c[k]) < 1e-3 and abs(v[k]) < 1e-3:
                return "0 / 0"
            return (f % v[k]) + " / " + (f % c[k]) + (" (%+.2f %%)" % (100 * d[k]) if k in d else "")

        span = lambda x: "%.2f-%.2f" % tuple(x[k] for k in range(2)) if x else "-"
        home = ("%.2f" % v["home_travel_mm"] if v["home_travel_mm"] else "-") + " / " + (
            "%.2f" % c["home_travel_mm"] if c.get("home_travel_mm") else
            "stopped at %.2f" % c["last_travel_mm"] if not c["finished"] else "-")
        lines.append(f"| {r['mesh_in']} | {r['nodes']} | {r['mu']} | {pair('lead_push_at_0.26in_N')} | "
                     f"{pair('lead_lateral_at_0.26in_N')} | {100 * max(r['lead_curve_difference'].values()):.2f} % | "
                     f"{pair('sliding_push_N')} | {pair('sliding_lateral_N')} | "
                     f"{span(v['apex_passes_edge_mm'])} / {span(c['apex_passes_edge_mm'])} | "
                     f"{v['peak_push_N']:.3f} / {c['peak_push_N']:.3f} | {home} | "
                     f"{v['seconds']:.1f} | {c['seconds']:.0f} |")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="0.1,0.07,0.05", help="mesh sizes, inches")
    ap.add_argument("--mu", default="0,0.3")
    ap.add_argument("--travel", type=float, default=0.9, help="inches (home at 0.84)")
    ap.add_argument("--dt", type=float, default=0.002, help="vproto's increment, s (1.1 in/s)")
    ap.add_argument("--increments", type=int, default=400, help="CalculiX's largest increment: 1/N")
    ap.add_argument("--penalty", type=float, default=1e11, help="N/m per contact node")
    ap.add_argument("-o", dest="out", default=os.path.join(ROOT, "bench", "results", "paw_calculix.json"))
    ap.add_argument("--keep", action="store_true", help="keep the work folder")
    ap.add_argument("--merge", nargs="+", help="only recompute and merge these result files into -o")
    a = ap.parse_args()
    if a.merge:
        results = [r for path in a.merge for r in json.load(open(path))["results"]]
        for r in results:
            r.setdefault("travel_in", json.load(open(a.merge[0])).get("travel_in", 0.9))
            compare(r)
        write(a.out, results)
        return
    if not shutil.which("ccx"):
        subprocess.run(["apt-get", "install", "-y", "-qq", "calculix-ccx"], check=True,
                       env=dict(os.environ, DEBIAN_FRONTEND="noninteractive"), stdout=subprocess.DEVNULL)
    results = []
    for mesh in [float(x) for x in a.mesh.split(",")]:
        for mu in [float(x) for x in a.mu.split(",")]:
            work = tempfile.mkdtemp(prefix="vproto_paw_")
            nodes, elements, vcurve, t_vproto, summary = run_vproto(mesh, mu, a.travel, a.dt, work)
            deck = os.path.join(work, "paw")
            counts = write_deck(deck + ".inp", nodes, elements, mu, a.travel * INCH, a.penalty,
                                0.25e9, 0.44, a.increments, mesh / 8)
            started = time.perf_counter()
            run = subprocess.run(["ccx", "-i", "paw"], cwd=work, stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, text=True,
                                 env=dict(os.environ, OMP_NUM_THREADS="2"))
            t_ccx = time.perf_counter() - started
            ccurve = read_totals(deck + ".dat", a.travel * INCH)
            row = {"mesh_in": mesh, "mu": mu, "travel_in": a.travel, "penalty": a.penalty,
                   "nodes": len(nodes), "elements": len(elements), "contact": counts,
                   "vproto": {"seconds": t_vproto,
                              "max_penetration_m": summary["elastic_contact"]["max_penetration"]},
                   "calculix": {"seconds": t_ccx, "exit_code": run.returncode},
                   "curves": {"vproto": vcurve, "calculix": ccurve}}
            compare(row)
            if not row["calculix"]["finished"]:  # where its Newton iterations stopped converging
                row["calculix"]["log_tail"] = run.stdout[-600:]
            results.append(row)
            print(json.dumps({k: row[k] for k in row if k != "curves"}), flush=True)
            if a.keep:
                print("kept", work)
            else:
                shutil.rmtree(work)
    write(a.out, results)


def write(path, results):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        json.dump({"sample": "samples/paw_quasistatic.vp", "machine": os.uname().nodename,
                   "results": results}, f, indent=1)
    with open(os.path.splitext(path)[0] + ".md", "w") as f:
        f.write(markdown(results))
    print(markdown(results))


if __name__ == "__main__":
    main()
