#!/bin/sh
# bench/ktx2_loss.sh CAMPAIGN_DIR [OUT_DIR]
#
# What the mobile-ready models (model_ktx2.glb: Basis Universal maps) lose
# against the PNG ones (model.glb), as the 3-D viewer shows them: screenshots
# of both from each scene's first viewpoint (tools/check_viewer.py, headless
# Chromium), then `pointbake compare` (PSNR, SSIM, FLIP) of the KTX2
# screenshot against the PNG one, and the GPU texture memory of both (the
# PNG maps as RGBA8 with mips, the KTX2 maps transcoded: estimate.fps).
# Needs build/pointbake, build/tests/viewer_compare and Chromium. Prints one
# table row per model (docs/export.md has the last run).
set -eu
campaign=$1
out=${2:-build/ktx2_loss}
root=$(cd "$(dirname "$0")/.." && pwd)
pb=$root/build/pointbake
python3 "$root/tools/check_viewer.py" "$pb" "$root/build/tests/viewer_compare" "$campaign" "$out/png" >/dev/null || true
python3 "$root/tools/check_viewer.py" "$pb" "$root/build/tests/viewer_compare" "$campaign" "$out/ktx2" --textures ktx2 >/dev/null || true
python3 - "$pb" "$campaign" "$out" <<'PYTHON'
import json, os, subprocess, sys
pb, campaign, out = sys.argv[1:4]
png = {r["run"]: r for r in json.load(open(os.path.join(out, "png", "summary.json")))["results"]}
ktx2 = {r["run"]: r for r in json.load(open(os.path.join(out, "ktx2", "summary.json")))["results"]}
def rgba8_bytes(w, h):  # RGBA8 with a full mip chain
    total = 0
    while True:
        total += 4 * w * h
        if w == 1 and h == 1: return total
        w, h = max(1, w // 2), max(1, h // 2)
print("| run | .glb PNG / KTX2 (MB) | GPU maps PNG (RGBA8) / KTX2 (MB) | ratio | FLIP KTX2 vs PNG | PSNR dB | SSIM | viewer SSIM vs reference PNG / KTX2 |")
print("|---|---|---|---|---|---|---|---|")
runs = json.load(open(os.path.join(campaign, "campaign.json")))["runs"]
for run in runs:
    name = run["name"]
    if name not in png or name not in ktx2: continue
    d = os.path.join(campaign, run["dir"])
    fps = json.load(open(os.path.join(d, "fps.json")))
    row = dict(zip(fps["columns"], fps["rows"][0]))
    maps = 2 if os.path.exists(os.path.join(d, "model.glb")) else 0
    png_gpu = maps * rgba8_bytes(row["texture_width"], row["texture_height"])
    r = subprocess.run([pb, "compare", png[name]["screenshot"], ktx2[name]["screenshot"], "--json"], capture_output=True, text=True)
    m = json.loads(r.stdout)
    print("| %s | %.2f / %.2f | %.1f / %.1f | %.1f× | %.4f | %.1f | %.4f | %.3f / %.3f |" % (
        name, os.path.getsize(os.path.join(d, "model.glb")) / 1e6, os.path.getsize(os.path.join(d, "model_ktx2.glb")) / 1e6,
        png_gpu / 1e6, row["texture_bytes"] / 1e6, png_gpu / max(1, row["texture_bytes"]),
        m.get("flip_mean", float("nan")), m.get("psnr_db", float("nan")), m.get("ssim_luma", float("nan")),
        png[name]["ssim_covered"], ktx2[name]["ssim_covered"]))
PYTHON
