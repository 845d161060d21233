#!/usr/bin/env bash
# The scaling benchmark of issue 8: point transfer vs Remeshing vs HPM on the
# synthetic room at several scan sizes (default 10^6, 3·10^6, 10^7, 3·10^7
# points), construction time (the report's Fig. 7 grouping, evaluation and the
# scan itself excluded) and peak RAM, as one campaign on this machine. Meshes
# keep the paper's proportions (low: one face per ~120 points, at least 8,000;
# high: one per ~6.5; Poisson depth 9 up to 3·10^6 points, 10 above), maps
# 4096², frames 512². Writes the Markdown table (with the machine) to
# docs/bench-scaling.md unless PB_SCALING_DOC is set to another file; the
# whole campaign (report included) stays in PB_BENCH_DIR (default a temporary
# folder, removed at the end). Asserts nothing; exits non-zero when a run
# failed (the table, written anyway, lists it).
# Usage: bench/scaling.sh [POINTS...]          e.g. bench/scaling.sh 1000000 3000000
set -euo pipefail
cd "$(dirname "$0")/.."
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(1000000 3000000 10000000 30000000)
bin=build/pointbake
[ -x "$bin" ] || { echo "build first: .ci/setup" >&2; exit 1; }
work=${PB_BENCH_DIR:-$(mktemp -d)}
mkdir -p "$work/scenes"
[ -n "${PB_BENCH_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
doc=${PB_SCALING_DOC:-docs/bench-scaling.md}
root=$(pwd)
# shellcheck source=bench/room_scene.sh
source bench/room_scene.sh

scene_list=""
for n in "${sizes[@]}"; do
  write_room_scene "$n" "$work/scenes/room-$n.yaml"
  scene_list+="  - scenes/room-$n.yaml"$'\n'
done
cat > "$work/scaling.yaml" <<YAML
name: scaling
description: point transfer vs Remeshing vs HPM at ${sizes[*]} points
scenes:
$scene_list
workflows:
  - $root/configs/workflows/hpm.yaml
  - $root/configs/workflows/remeshing.yaml
  - $root/configs/workflows/point_transfer.yaml
YAML
# One stage at a time, so each stage's time and peak RAM are its own. A
# failed run (the campaign then exits non-zero) still gets the table, which
# lists it, and the script exits with the campaign's status after it.
campaign_status=0
"$bin" campaign "$work/scaling.yaml" --jobs 1 --cache "$work/cache" --out "$work/out" -q || campaign_status=$?
[ -f "$work/out/report/results.json" ] || exit "$campaign_status"
python3 - "$work/out" "$doc" "${sizes[@]}" <<'PY'
import json, os, platform, subprocess, sys
out, doc, sizes = sys.argv[1], sys.argv[2], [int(s) for s in sys.argv[3:]]
results = json.load(open(os.path.join(out, "report", "results.json")))
campaign = json.load(open(os.path.join(out, "campaign.json")))
rows = {(r["scene"], r["workflow"]): r for r in results["rows"]}
def cpu():
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor()
host = campaign["host"]
lines = [
    "# Scaling: point transfer vs Remeshing vs HPM",
    "",
    "Written by `bench/scaling.sh` (" + campaign["started"] + "). Machine: " + cpu() + ", " +
    str(host["cores"]) + " cores, " + "%.1f GiB RAM" % (host["memory_bytes"] / 2**30) +
    ", Debian 12; stages one at a time (`--jobs 1`), each on all cores.",
    "",
    "The synthetic room scanned with N points; meshes in the paper's proportions (low: N/120 faces, "
    "at least 8,000; high: N/6.5; Poisson depth 9 up to 3·10⁶ points, 10 above; low depth 8); "
    "maps 4096². Time = construction time (normals, meshes, UV, baking, I/O; the report's grouping, "
    "docs/report.md), without producing the scan and without evaluation. Peak RAM = the largest "
    "stage's peak RSS. Ratios in one run are the meaningful figures: other work may have shared "
    "the machine.",
    "",
    "| points | HPM time | Remeshing time | point transfer time | HPM / transfer | Remeshing / transfer | HPM peak RAM | Remeshing peak RAM | transfer peak RAM |",
    "|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
]
def t(r): return r and r["time_s"]["total"]
def fmt_s(v): return "—" if v is None else ("%.1f s" % v if v < 600 else "%.1f min" % (v / 60))
def fmt_b(v): return "—" if v is None else "%.2f GiB" % (v / 2**30) if v >= 2**30 else "%.0f MiB" % (v / 2**20)
def ratio(a, b): return "—" if a is None or b in (None, 0) else "%.1f×" % (a / b)
for n in sizes:
    h, m, p = (rows.get(("room-%d" % n, w)) for w in ("hpm", "remeshing", "point_transfer"))
    lines.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
        "{:,}".format(n), fmt_s(t(h)), fmt_s(t(m)), fmt_s(t(p)), ratio(t(h), t(p)), ratio(t(m), t(p)),
        fmt_b(h and h["peak_ram_bytes"]), fmt_b(m and m["peak_ram_bytes"]), fmt_b(p and p["peak_ram_bytes"])))
lines += ["", "Per component (seconds):", "",
          "| points | workflow | normals | high mesh | low mesh | UV | I/O | baking | total |",
          "|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
for n in sizes:
    for w in ("hpm", "remeshing", "point_transfer"):
        r = rows.get(("room-%d" % n, w))
        if not r: continue
        ts = r["time_s"]
        cells = ["—" if ts[k] is None else "%.1f" % ts[k] for k in ("points", "high_mesh", "low_mesh", "uv", "io", "bake", "total")]
        lines.append("| %s | %s | %s |" % ("{:,}".format(n), w, " | ".join(cells)))
failed = [r["name"] for r in campaign["runs"] if r["status"] != "ok"]
if failed:
    lines += ["", "Failed runs: " + ", ".join(failed) + "."]
open(doc, "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
echo "table written to $doc"
exit "$campaign_status"
