#!/usr/bin/env python3
"""Same mesh, same element, same loads: vproto's static FE against CalculiX (issue 3).

Runs `vproto run` in static mode with VTU export, reads the final VTU (nodes, tet4/tet10
elements, nodal loads, held nodes, displacements), writes the identical problem as a
CalculiX input deck (C3D4/C3D10 share VTK's node order), runs `ccx`, and reports the
largest nodal displacement difference relative to the largest displacement.

Usage: python3 bench/calculix_compare.py [SCRIPT.vp] [--set NAME=EXPR ...]
(after scripts/setup.sh; installs Debian's calculix-ccx when it is missing)
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read_vtu(path, fields=True):
    """vproto's VTU: ASCII arrays, or raw appended blocks (UInt64 byte count, then data).
    The nodal loads and held marks are written by static runs only (fields=False skips them)."""
    import struct
    raw = open(path, "rb").read()
    marker = b'<AppendedData encoding="raw">'
    head, appended = raw, b""
    if marker in raw:
        at = raw.index(marker)
        head = raw[:at] + b"</VTKFile>"
        appended = raw[raw.index(b"_", at) + 1:]
    piece = ET.fromstring(head).find("UnstructuredGrid/Piece")
    arrays = {}
    for da in piece.iter("DataArray"):
        name = da.get("Name") or "Points"
        comps = int(da.get("NumberOfComponents", "1"))
        if da.get("format") == "appended":
            offset = int(da.get("offset"))
            (size,) = struct.unpack_from("<Q", appended, offset)
            code = {"Float64": "d", "Int64": "q"}[da.get("type")]
            values = list(struct.unpack_from("<%d%s" % (size // 8, code), appended, offset + 8))
        else:
            values = [float(x) for x in da.text.split()]
        arrays[name] = [values[i:i + comps] for i in range(0, len(values), comps)] if comps > 1 else values
    n = int(piece.get("NumberOfPoints"))
    conn = [int(x) for x in arrays["connectivity"]]
    per = len(conn) // int(piece.get("NumberOfCells"))
    elements = [conn[i:i + per] for i in range(0, len(conn), per)]
    deformed = arrays["Points"]
    u = arrays["displacement"]
    nodes = [[deformed[i][k] - u[i][k] for k in range(3)] for i in range(n)]
    if not fields:
        return nodes, elements, u, arrays
    return nodes, elements, u, arrays["load"], arrays["held"]


def write_inp(path, nodes, elements, load, held, e, nu):
    etype = "C3D10" if len(elements[0]) == 10 else "C3D4"
    with open(path, "w") as f:
        f.write("*NODE, NSET=NALL\n")
        for i, p in enumerate(nodes):
            f.write(f"{i + 1}, {p[0]:.17g}, {p[1]:.17g}, {p[2]:.17g}\n")
        f.write(f"*ELEMENT, TYPE={etype}, ELSET=EALL\n")
        for i, el in enumerate(elements):
            f.write(f"{i + 1}, " + ", ".join(str(v + 1) for v in el) + "\n")
        f.write("*NSET, NSET=HELD\n")
        for i, h in enumerate(held):
            if h > 0.5:
                f.write(f"{i + 1},\n")
        f.write(f"*MATERIAL, NAME=M\n*ELASTIC\n{e:.17g}, {nu:.17g}\n*SOLID SECTION, ELSET=EALL, MATERIAL=M\n")
        f.write("*STEP\n*STATIC\n*BOUNDARY\nHELD, 1, 3, 0.\n*CLOAD\n")
        for i, fv in enumerate(load):
            for k in range(3):
                if fv[k] != 0.0:
                    f.write(f"{i + 1}, {k + 1}, {fv[k]:.17g}\n")
        f.write("*NODE PRINT, NSET=NALL\nU\n*END STEP\n")


def read_dat(path, n):
    u = [None] * n
    text = open(path).read()
    block = text.split("displacements (vx,vy,vz)")[-1]
    for line in block.splitlines():
        m = re.match(r"\s*(\d+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$", line)
        if m:
            u[int(m.group(1)) - 1] = [float(m.group(k)) for k in (2, 3, 4)]
    return u


def main():
    args = sys.argv[1:]
    script = args[0] if args and not args[0].startswith("--") else os.path.join(ROOT, "samples", "cantilever.vp")
    extra = args[1:] if args and not args[0].startswith("--") else args
    if not shutil.which("ccx"):
        subprocess.run(["apt-get", "install", "-y", "-qq", "calculix-ccx"], check=True,
                       env=dict(os.environ, DEBIAN_FRONTEND="noninteractive"), stdout=subprocess.DEVNULL)
    work = tempfile.mkdtemp(prefix="vproto_ccx_")
    out = os.path.join(work, "vproto")
    t0 = time.perf_counter()
    subprocess.run([os.path.join(ROOT, "build/release/vproto"), "run", script, "-o", out, "--export", "vtu",
                    "--frames", "2", "--no-render", "--quiet"] + extra, check=True)
    t_vproto = time.perf_counter() - t0
    summary = json.load(open(os.path.join(out, "summary.json")))
    build = json.load(open(os.path.join(out, "build.json")))
    vtus = sorted(f for f in os.listdir(os.path.join(out, "meshes")) if f.endswith("_0001.vtu"))
    results = []
    for vtu in vtus:
        body = vtu[: -len("_0001.vtu")]
        entry = next(b for b in build["bodies"] if b["name"] == body)
        nodes, elements, u, load, held = read_vtu(os.path.join(out, "meshes", vtu))
        e, nu = entry["youngs_modulus"], entry["poisson_ratio"]
        deck = os.path.join(work, body)
        write_inp(deck + ".inp", nodes, elements, load, held, e, nu)
        t1 = time.perf_counter()
        subprocess.run(["ccx", "-i", body], cwd=work, check=True, stdout=subprocess.DEVNULL)
        t_ccx = time.perf_counter() - t1
        uc = read_dat(deck + ".dat", len(nodes))
        scale = max(abs(c) for row in uc for c in row)
        diff = max(abs(u[i][k] - uc[i][k]) for i in range(len(nodes)) for k in range(3))
        results.append({"body": body, "nodes": len(nodes), "elements": len(elements),
                        "element": "tet10" if len(elements[0]) == 10 else "tet4",
                        "max_relative_difference": diff / scale,
                        "vproto_seconds_whole_run": t_vproto, "calculix_seconds": t_ccx})
    print(json.dumps({"script": script, "results": results}, indent=2))
    shutil.rmtree(work)
    bad = [r for r in results if r["max_relative_difference"] > 1e-6]
    sys.exit(1 if bad or not results else 0)


if __name__ == "__main__":
    main()
