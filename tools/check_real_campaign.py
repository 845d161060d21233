#!/usr/bin/env python3
"""Checks a finished campaign on real scans against issue 15's goals.

Usage: tools/check_real_campaign.py CAMPAIGN_OUT_DIR [--scene NAME]... [--max-holes F]

Reads report/results.json and, for every scene (or those named), checks:
  - every shipped workflow's final mesh: invented area < 2 % of its area,
    hole pixels < --max-holes of the scan render's footprint (default 0.002,
    issue 15's goal, which the pump does not meet yet: about 2.3-2.9 %, in
    thin and sparsely scanned parts that mesh.trim removes; ctest guards the
    current level with --max-holes 0.04, docs/real-scans.md);
  - the final low meshes' boundary edges per 1000 faces within 1.5x LPM's;
  - point transfer beats LPM on covered-pixel SSIM and FLIP against the scan,
    and its FLIP is at most Remeshing's.
Prints one line per check and exits 1 if any fails.
"""
import argparse
import json
import os
import sys

WORKFLOWS = ("hpm", "lpm", "remeshing", "point_transfer")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out_dir")
    ap.add_argument("--scene", action="append", default=[])
    ap.add_argument("--max-holes", type=float, default=0.002,
                    help="largest hole-pixel fraction of the scan's footprint (default 0.002)")
    args = ap.parse_args()
    path = os.path.join(args.out_dir, "report", "results.json")
    with open(path) as f:
        results = json.load(f)
    rows = {}
    for r in results["rows"]:
        if r.get("variant"):
            continue
        rows[(r["scene"], r["workflow"])] = r
    scenes = args.scene or sorted({s for s, _ in rows})
    failures = 0

    def check(ok, text):
        nonlocal failures
        print(("ok    " if ok else "FAIL  ") + text)
        failures += 0 if ok else 1

    for scene in scenes:
        runs = {w: rows.get((scene, w)) for w in WORKFLOWS}
        for w, r in runs.items():
            check(r is not None and r.get("status") == "ok", f"{scene}/{w}: ran")
        if any(r is None or r.get("status") != "ok" for r in runs.values()):
            continue
        for w, r in runs.items():
            g, s = r["scan_geometry"], r["vs_scan"]
            inv, holes = g["invented_area_fraction"], s["hole_fraction"]
            check(inv is not None and inv < 0.02, f"{scene}/{w}: invented area {100 * inv:.2f} % < 2 %")
            check(holes is not None and holes < args.max_holes,
                  f"{scene}/{w}: hole pixels {100 * holes:.3f} % < {100 * args.max_holes:g} %")
        lpm_b = runs["lpm"]["scan_geometry"]["boundary_edges_per_1000_faces"]
        for w in ("remeshing", "point_transfer"):
            b = runs[w]["scan_geometry"]["boundary_edges_per_1000_faces"]
            check(b <= 1.5 * lpm_b, f"{scene}/{w}: boundary edges {b:.0f} per 1000 faces <= 1.5 x LPM's {lpm_b:.0f}")
        pt, lpm, rem = (runs[w]["vs_scan"] for w in ("point_transfer", "lpm", "remeshing"))
        check(pt["covered_ssim_luma"] > lpm["covered_ssim_luma"],
              f"{scene}: point transfer SSIM {pt['covered_ssim_luma']:.3f} > LPM {lpm['covered_ssim_luma']:.3f}")
        check(pt["covered_flip_mean"] < lpm["covered_flip_mean"],
              f"{scene}: point transfer FLIP {pt['covered_flip_mean']:.3f} < LPM {lpm['covered_flip_mean']:.3f}")
        check(pt["covered_flip_mean"] <= rem["covered_flip_mean"],
              f"{scene}: point transfer FLIP {pt['covered_flip_mean']:.3f} <= Remeshing {rem['covered_flip_mean']:.3f}")
    print(f"{failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
