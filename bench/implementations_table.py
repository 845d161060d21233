#!/usr/bin/env python3
"""The table of docs/implementations.md from a finished campaign folder of
configs/campaigns/implementations.yaml (or the same workflows on other scenes).

Usage: bench/implementations_table.py OUT_DIR

For each scene, one row per run: the stage the run varies (the baseline run
gives one row per stage it compares: outliers, normals, low_poisson), that
stage's wall time, CPU time and peak RSS from the run record of the run that
computed it, its result size (points kept, or faces), and the quality of the
whole run: the reconstructed mesh's distance to the analytic truth
(metrics.geometry, mesh_to_truth mean and rms, mm) and the frames of the
point-transfer model against the truth's (metrics.image mean PSNR, SSIM
luma, FLIP). Prints Markdown.
"""
import json
import os
import sys

STAGES = {"outliers": "points.outliers", "smooth": "points.smooth", "normals": "points.normals",
          "low_poisson": "mesh.poisson"}


def table_rows(path):
    with open(path) as f:
        table = json.load(f)
    return [dict(zip(table["columns"], row)) for row in table["rows"]]


def main(out_dir):
    runs_dir = os.path.join(out_dir, "runs")
    print("| scene | stage | implementation | wall s | CPU s | peak MiB | result | mesh→truth mean / rms mm "
          "| PSNR dB | SSIM | FLIP |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for scene in sorted(os.listdir(runs_dir)):
        runs = sorted(os.listdir(os.path.join(runs_dir, scene)), key=lambda r: (len(r), r))
        for run in runs:
            folder = os.path.join(runs_dir, scene, run)
            with open(os.path.join(folder, "run.json")) as f:
                record = json.load(f)
            stages = {s["stage"]: s for s in record["stages"]}
            geometry = {r["direction"]: r for r in table_rows(os.path.join(folder, "geometry.json"))}
            image = {r["frame"]: r for r in table_rows(os.path.join(folder, "vs_truth.json"))}
            g = geometry["mesh_to_truth"]
            m = image["mean"]
            quality = (f"{g['mean_m'] * 1e3:.2f} / {g['rms_m'] * 1e3:.2f} | {m['psnr_db']:.2f} | "
                       f"{m['ssim_luma']:.4f} | {m['flip_mean']:.4f}")
            if "+" in run:
                variant = run.split("+", 1)[1]
                label = variant.split(",")[0]
                varied = {"poisson": "low_poisson"}.get(label, label)
                if varied not in STAGES:
                    sys.exit(f"{folder}: the run's label '{label}' names no compared stage; label "
                             "each variant with the stage it varies (outliers, smooth, normals, "
                             "poisson), as configs/campaigns/implementations.yaml does")
                names = [varied]
                value = variant.split("=", 1)[1]
            else:
                names = ["outliers", "normals", "low_poisson", "smooth"]
                value = None
            for name in names:
                s = stages[name]
                params = s.get("params", {})
                implementation = value or params.get("implementation") or {
                    "outliers": "own", "normals": "own", "low_poisson": "open3d", "smooth": "off"}[name]
                if name == "smooth":
                    implementation = "off" if value is None else f"PCL MLS, {value} spacings"
                c = s.get("counters", {})
                if name in ("outliers",):
                    result = f"{int(c.get('points_out', 0))} points"
                elif name == "low_poisson":
                    result = f"{int(c.get('faces_out', 0))} faces"
                elif name == "smooth":
                    result = f"{c['mean_shift_mm']:.2f} mm mean shift" if "mean_shift_mm" in c else "—"
                else:
                    result = f"{int(c.get('points', 0))} points"
                if s["status"] != "ran":
                    timing = "(cached) | | "
                else:
                    timing = (f"{s['wall_s']:.2f} | {s['user_s'] + s['sys_s']:.2f} | "
                              f"{s['peak_rss_bytes'] / 2**20:.0f}")
                print(f"| {scene} | {STAGES[name]} | {implementation} | {timing} | {result} | {quality} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
