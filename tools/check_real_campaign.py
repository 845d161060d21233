#!/usr/bin/env python3
"""Checks a finished campaign on real scans against issue 15's goals.

Usage: tools/check_real_campaign.py CAMPAIGN_OUT_DIR [--scene NAME]... [--max-holes F]
           [--max-in-front F] [--max-back F] [--background R,G,B [--max-background F]]

Reads report/results.json and, for every scene (or those named), checks:
  - every shipped workflow's final mesh: invented area < 2 % of its area,
    hole pixels < --max-holes of the scan's sample footprint (metrics.image
    v4 hole_fraction: pixels a visible scan point projects into where the
    model shows background; default 0.002, issue 15's goal, met on the pump
    by every workflow since mesh.fit moves the final meshes onto the scan:
    0.01 % HPM, 0.05 % LPM and point transfer, 0.06 % Remeshing with
    mesh.fit version 2's outside_weight 0.75 and render.splats version 4's
    masks of the points moved onto their local surface, version 5 leaving
    out the stray returns (0.05 / 0.14 / 0.16 %
    with version 1's least squares and version 3's masks, 0.13 / 0.34 /
    0.49 % before the fit, their outline a pixel inside the outermost
    samples of curved pipes); ctest guards it with --max-holes 0.002,
    docs/real-scans.md). The line also gives the part
    enclosed by the model (background seen through it: missing faces), the
    part at its silhouette, and the count on the splats' disks (the old
    definition, splat_hole_fraction);
  - every workflow's surface in front of the scan (metrics.image's
    nearer_fraction: compared pixels where the model stands in front of the
    scan's own render by more than 5 % of its depth) at most --max-in-front
    (default 0.05; the real scenes: 0.0-1.3 %): a hull that screened Poisson
    wraps around returns in the air hides the scan from every view while
    the invented area, which counts those returns as scan points, stays
    low (a statue stand-in: 36-68 %, docs/real-scans.md, "Points in the
    air");
  - every workflow's faces seen from the back (back_face_fraction, the report's
    "Back faces %": render.frames' back_share:
    of the samples that hit the model, the share whose face turns its back
    to the eye) at most --max-back (default 0.10; the real scenes: 0.0-4.0
    %, the living room's oblique view seeing a side wall from outside; the
    synthetic rooms 0): render.frames draws both sides, a headset culls
    back faces and shows what lies behind there, so a model turned inside
    out (a statue's plinth with points.normals 3), whose backs are most of
    what a view from outside shows, looked right in every other figure;
  - the final low meshes' boundary edges per 1000 faces within 1.5x LPM's
    (met on the four real scenes: 1.06x, 1.12x, 1.02x, 0.93x with
    mesh.decimate version 5);
  - point transfer beats LPM on covered-pixel SSIM and FLIP against the scan,
    and its FLIP is at most Remeshing's (skipped, and said so, for a scan
    without colors or intensities: io.read_points paints it one grey, so
    every workflow's texture is that grey);
  - with --background R,G,B (the runs' render.frames drawn on that color,
    e.g. `set: { render.background: [255, 0, 255] }` in the campaign): the
    frames show that color on at most --max-background of the scan's sample
    footprint (pixels no sample of the model covers: missing faces, which a
    black background would hide among dark texels); the count on the scan
    render's disks is printed beside.
Prints one line per check and exits 1 if any fails.
"""
import argparse
import json
import os
import struct
import sys
import zlib

WORKFLOWS = ("hpm", "lpm", "remeshing", "point_transfer")


def read_png(path):
    """(width, height, channels, rows) of an 8-bit, non-interlaced gray, RGB or
    RGBA PNG (what render.frames and render.splats write, gray: the sample
    masks); rows are bytes objects."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG")
    pos, idat, header = 8, [], None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", chunk)
        elif kind == b"IDAT":
            idat.append(chunk)
        elif kind == b"IEND":
            break
    width, height, depth, color, _, _, interlace = header
    if depth != 8 or color not in (0, 2, 6) or interlace:
        raise ValueError(f"{path}: only 8-bit gray/RGB/RGBA non-interlaced PNGs are read")
    channels = {0: 1, 2: 3, 6: 4}[color]
    raw = zlib.decompress(b"".join(idat))
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        previous = line
    return width, height, channels, rows


def background_pixels(run_dir, background):
    """Over the run's frames (render.frames, drawn with `background`): pixels
    whose color is exactly the background, i.e. where no sample of the model
    was drawn, counted on the scan's sample footprint (the frame's
    <name>.samples.png of scan_frames, render.splats v3: pixels into which a
    visible scan point projects; metrics.image's hole pixels) and on the scan
    render's disk footprint (alpha > 0; metrics.image's splat_hole_px).
    Returns (shown on samples, sample footprint, shown on disks, disk
    footprint); the sample figures are None without sample masks."""
    shown = footprint = disk_shown = disk_footprint = 0
    masks = True
    frames = os.path.join(run_dir, "frames")
    with open(os.path.join(run_dir, "scan_frames", "frames.json")) as f:
        scan_index = {e["file"]: e for e in json.load(f)["frames"]}
    for name in sorted(os.listdir(frames)):
        if not name.endswith(".png") or name not in scan_index:
            continue
        w, h, ch, rows = read_png(os.path.join(frames, name))
        sw, sh, sch, scan = read_png(os.path.join(run_dir, "scan_frames", name))
        if (w, h) != (sw, sh) or sch != 4:
            raise ValueError(f"{run_dir}: {name}: frame and scan render differ in size or lack alpha")
        samples = None
        if "samples" in scan_index[name]:
            mw, mh, mch, samples = read_png(os.path.join(run_dir, "scan_frames", scan_index[name]["samples"]))
            if (mw, mh, mch) != (w, h, 1):
                raise ValueError(f"{run_dir}: {name}: the sample mask is not one gray channel of the frame's size")
        else:
            masks = False
        bg = bytes(background)
        for y in range(h):
            row, ref = rows[y], scan[y]
            for x in range(w):
                is_bg = row[x * ch:x * ch + 3] == bg
                if ref[x * 4 + 3] != 0:
                    disk_footprint += 1
                    disk_shown += is_bg
                if samples is not None and samples[y][x] != 0:
                    footprint += 1
                    shown += is_bg
    if not masks:
        return None, None, disk_shown, disk_footprint
    return shown, footprint, disk_shown, disk_footprint


def hole_kinds(run_dir):
    """Pooled over the frames of the run's vs_scan.json (metrics.image v4):
    (enclosed, at the model's silhouette, footprint) pixels, or None."""
    try:
        with open(os.path.join(run_dir, "vs_scan.json")) as f:
            table = json.load(f)
        col = {c: i for i, c in enumerate(table["columns"])}
        rows = [r for r in table["rows"] if r[0] != "mean"]
        return tuple(sum(r[col[c]] for r in rows) for c in ("enclosed_hole_px", "silhouette_hole_px", "footprint_px"))
    except (OSError, KeyError, TypeError, ValueError):
        return None


def uniform_grey_scan(run_dir):
    """True if the run's io.read_points painted the scan one grey (no colors,
    no intensities in the file): its counter `uniform_grey`."""
    try:
        with open(os.path.join(run_dir, "run.json")) as f:
            stages = json.load(f)["stages"]
    except (OSError, ValueError, KeyError):
        return False
    for stage in stages:
        if stage.get("type") != "io.read_points":
            continue
        counters = stage.get("counters") or (stage.get("cached_run") or {}).get("counters") or {}
        if counters.get("uniform_grey"):
            return True
    return False


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out_dir")
    ap.add_argument("--scene", action="append", default=[])
    ap.add_argument("--max-holes", type=float, default=0.002,
                    help="largest hole-pixel fraction of the scan's footprint (default 0.002)")
    ap.add_argument("--max-in-front", type=float, default=0.05,
                    help="largest fraction of the compared pixels where a model stands in front of the scan "
                         "(default 0.05)")
    ap.add_argument("--background", default="",
                    help="R,G,B: the runs' render.frames were drawn on this (non-black) background; "
                         "check that the frames show it on at most --max-background of the scan's footprint")
    ap.add_argument("--max-back", type=float, default=0.10,
                    help="largest share of what a model's frames show that is a face's back (default 0.10)")
    ap.add_argument("--max-background", type=float, default=0.0,
                    help="largest fraction of the scan's footprint where the frames show the background (default 0)")
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
            disk = s.get("splat_hole_fraction")
            disk_text = f"; on the splats' disks: {100 * disk:.3f} %" if disk is not None else ""
            kinds = hole_kinds(os.path.join(args.out_dir, "runs", scene, w))
            if kinds and kinds[2]:
                disk_text = (f"; of the footprint pooled over the views, {100 * kinds[0] / kinds[2]:.3f} % enclosed "
                             f"by the model, {100 * kinds[1] / kinds[2]:.3f} % at its silhouette{disk_text}")
            check(holes is not None and holes < args.max_holes,
                  f"{scene}/{w}: hole pixels {100 * holes:.3f} % of the scan's sample footprint < "
                  f"{100 * args.max_holes:g} %" + (f" ({disk_text[2:]})" if disk_text else ""))
            back = g.get("back_face_fraction")  # render.frames' back_share (the report reads it)
            if back is None:
                print(f"skip  {scene}/{w}: no back faces figure (render.frames before version 2, or a report "
                      f"before the figure)")
            else:
                check(back <= args.max_back,
                      f"{scene}/{w}: faces seen from the back on {100 * back:.2f} % of what the frames show "
                      f"<= {100 * args.max_back:g} % (a headset culls back faces)")
            nearer = s.get("nearer_fraction")
            if nearer is None:
                print(f"skip  {scene}/{w}: no depth maps (render.frames and render.splats depth: true), "
                      "no surface in front of the scan")
            else:
                check(nearer <= args.max_in_front,
                      f"{scene}/{w}: surface in front of the scan on {100 * nearer:.2f} % of the compared pixels "
                      f"<= {100 * args.max_in_front:g} %")
        if args.background:
            bg = [int(v) for v in args.background.split(",")]
            for w, r in runs.items():
                run_dir = os.path.join(args.out_dir, "runs", scene, w)
                shown, footprint, disk_shown, disk_footprint = background_pixels(run_dir, bg)
                disk_fraction = disk_shown / disk_footprint if disk_footprint else 0.0
                disks = (f"on the splats' disks: {100 * disk_fraction:.3f} % of {disk_footprint} px "
                         f"({disk_shown} px)")
                if footprint is None:
                    check(disk_footprint > 0 and disk_fraction <= args.max_background,
                          f"{scene}/{w}: frames show the background {tuple(bg)} (no sample masks) {disks} "
                          f"<= {100 * args.max_background:g} %")
                    continue
                fraction = shown / footprint if footprint else 0.0
                check(footprint > 0 and fraction <= args.max_background,
                      f"{scene}/{w}: frames show the background {tuple(bg)} on {100 * fraction:.3f} % of the scan's "
                      f"sample footprint ({shown} of {footprint} px) <= {100 * args.max_background:g} %; {disks}")
        lpm_b = runs["lpm"]["scan_geometry"]["boundary_edges_per_1000_faces"]
        for w in ("remeshing", "point_transfer"):
            b = runs[w]["scan_geometry"]["boundary_edges_per_1000_faces"]
            check(b <= 1.5 * lpm_b, f"{scene}/{w}: boundary edges {b:.0f} per 1000 faces <= 1.5 x LPM's {lpm_b:.0f}")
        if uniform_grey_scan(os.path.join(args.out_dir, "runs", scene, "point_transfer")):
            print(f"skip  {scene}: the scan has no colors nor intensities (painted one grey): "
                  "no texture ranking")
            continue
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
