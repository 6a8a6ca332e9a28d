#!/usr/bin/env bash
# CSG speed benchmark (issue 2): the 49-hole plate built whole-process by vproto, by
# Manifold (npm manifold-3d under Node) and by OpenSCAD (Debian openscad), side by side
# in one run. Prints a table and writes bench/results/plate49.json.
# Usage: bash bench/plate49_peers.sh [repeats]   (after scripts/setup.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
repeats="${1:-5}"
vproto=build/release/vproto
[ -x "$vproto" ] || { echo "build vproto first: bash scripts/setup.sh" >&2; exit 2; }

# peers: install what is missing (Debian openscad, npm manifold-3d into bench/node_modules)
command -v openscad >/dev/null || { DEBIAN_FRONTEND=noninteractive apt-get install -y -qq openscad >/dev/null; }
[ -d bench/node_modules/manifold-3d ] || (cd bench && npm install --silent --no-save manifold-3d@3 >/dev/null)

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export LC_ALL=C

# median wall time of a command over N runs, each from a clean state (no vproto cache)
median() {
  local n=$1; shift
  python3 - "$n" "$@" <<'PY'
import subprocess, sys, time, statistics, shutil, os
n = int(sys.argv[1]); cmd = sys.argv[2:]
times = []
for _ in range(n):
    out = os.environ.get("CLEAN_DIR")
    if out: shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    times.append(time.perf_counter() - t0)
print(f"{statistics.median(times):.4f}")
PY
}

t_vproto=$(CLEAN_DIR="$work/vp" median "$repeats" "$vproto" build bench/models/plate49.vp -o "$work/vp" --quiet)
t_manifold=$(median "$repeats" node bench/plate49_manifold.mjs "$work/manifold.stl")
t_openscad=$(median 1 openscad -o "$work/openscad.stl" bench/models/plate49.scad)

rm -rf "$work/vp"  # the report below wants the CSG time, not a cache hit
"$vproto" build bench/models/plate49.vp -o "$work/vp" --quiet
python3 - "$work" "$t_vproto" "$t_manifold" "$t_openscad" <<'PY'
import json, sys, subprocess, os
work, tv, tm, to = sys.argv[1], *map(float, sys.argv[2:])
b = json.load(open(f"{work}/vp/build.json"))["bodies"][0]
res = {
  "model": "100x100x10 mm box minus 7x7 r=4 mm 64-segment cylinders",
  "seconds_whole_process": {"vproto": tv, "manifold_node": tm, "openscad": to},
  "vproto_over_manifold": tv / tm, "openscad_over_vproto": to / tv,
  "vproto_csg_seconds": json.load(open(f"{work}/vp/build.json"))["timings"]["csg"],
  "vproto_volume_m3": b["volume"], "vproto_triangles": b["triangles"],
}
os.makedirs("bench/results", exist_ok=True)
json.dump(res, open("bench/results/plate49.json", "w"), indent=2)
print(f"{'tool':<14}{'seconds':>10}")
for k, v in res["seconds_whole_process"].items(): print(f"{k:<14}{v:>10.3f}")
print(f"vproto / manifold = {tv/tm:.2f} (target <= 3)")
print(f"openscad / vproto = {to/tv:.1f} (target >= 50)")
PY
