// Campaign reports: <out>/report/ written from a finished campaign's folder
// (results.csv, results.json, report.md, report.html). See docs/campaigns.md
// and docs/report.md.
//
// Input, written by `pointbake campaign` (engine/campaign.h):
//
//   <out>/campaign.json
//     {"format": "pointbake-campaign", "version": 1,
//      "name": "demo",                          <- the campaign's name
//      "file": "/abs/configs/campaigns/demo.yaml",
//      "started": "2026-11-21T10:00:00Z", "total_wall_s": 312.5,
//      "host": {"cores": 2, "memory_bytes": 25769803776, "cpu": "model name"},
//      "runs": [
//        {"name": "synthetic-room/point_transfer",    <- unique, readable
//         "scene": "synthetic-room",                   <- the scene's name:
//         "scene_file": "/abs/configs/scenes/synthetic-room.yaml",
//         "workflow": "point_transfer",                <- the workflow's name:
//         "workflow_file": "/abs/configs/workflows/point_transfer.yaml",
//         "variant": "splat",          <- "" or the override's label
//         "sets": ["transfer.interpolation=splat"],    <- --set equivalents
//         "dir": "runs/synthetic-room/point_transfer", <- relative to <out>
//         "status": "ok" | "failed",   <- failed: some stage failed or the
//         "error": "...",              <- workflow did not load (message)
//         "warnings": 2},              <- stages' warnings (absent when 0)
//        ...]}
//
//   <out>/<run dir>/run.json: the run record (engine/run_record.h). Every
//   stage entry has "group" when the workflow gave the stage one (`group:`):
//     input       producing the scan (synthetic scan or reading the file);
//                 the same for every workflow: left out of construction time
//     points      point preparation (normals)
//     high_mesh   high-polygon mesh construction
//     low_mesh    low-polygon mesh construction
//     uv          UV unwrapping
//     bake        texture / normal map generation
//     io          export (writing the model)
//     evaluation  rendering, metrics, FPS estimate: not construction time
//     reference   the HPM reference chain inside another workflow: not this
//                 workflow's time
//   A stage's figures are its own ("status": "ran") or, for a cache hit
//   ("status": "hit"), those of the run that made the entry ("cached_run":
//   wall_s, user_s, sys_s, peak_rss_bytes, phases, counters). Construction
//   time per paper Fig. 7 component = for stages of groups points, high_mesh,
//   low_mesh, uv, bake, io: the stage's "io" phase time goes to I/O (reading
//   and writing meshes, maps, points), the rest of its wall time to its group.
//   Peak RAM = the largest peak_rss_bytes among those stages.
//
//   <out>/<run dir>/<named outputs> (the shipped workflows' `outputs:`;
//   any may be absent, e.g. when a stage failed or the scene has no truth):
//     frames/         `frames` artifact (frames.json + PNGs,
//                     stages/geometry/io/frames.h): this workflow's result
//     truth_frames/   the ground truth rendered (synthetic scenes only)
//     vs_hpm.json     metrics.image table against the HPM frames (absent in
//                     the HPM workflow itself): columns frame, psnr_db,
//                     ssim_luma, ssim_rgb, ms_ssim_luma, flip_mean; rows per
//                     frame then "mean"
//     flip_hpm/       FLIP error maps against HPM (frames artifact)
//     vs_truth.json, flip_truth/   the same against ground truth
//     scan_frames/    the scan drawn as splats (render.splats), shown beside
//                     the frames
//     vs_scan.json    metrics.image (v2) of the unlit frames against
//                     scan_frames: the covered_* columns, coverage_iou,
//                     hole_fraction, nearer_fraction, farther_fraction,
//                     splat_hole_fraction of row "mean"
//     flip_scan/      its covered-pixel FLIP maps (shown for scenes without
//                     ground truth, instead of flip_hpm)
//     coverage_scan/  its coverage maps (metrics.image `coverage`), shown
//                     under every run's frame, downscaled by rank
//     geometry.json   metrics.geometry (v2) with the scan: beyond_fraction of
//                     rows mesh_to_scan (invented area) and scan_to_mesh
//                     (missing), boundary_edges_per_1000_faces
//     fps.json        estimate.fps table, one row: device, triangles,
//                     texture_width, texture_height, texture_bytes,
//                     texture_budget_bytes, fits_texture_budget,
//                     triangles_per_s, refresh_hz, fps
//     model.glb       the exported model
//
// Output, <report_dir>/ (written to temporary names, then renamed; details,
// units and rules in docs/report.md):
//   results.json  {"format": "pointbake-report", "version": 1,
//                  "campaign": {name, file, started, total_wall_s},
//                  "host": (copied from campaign.json),
//                  "rows": [one per run, sorted by scene (manifest order),
//                  then workflow (hpm, lpm, remeshing, point_transfer, others
//                  alphabetically), then variant ("" first): name, scene,
//                  workflow, variant, display_name, status, time_s: {points,
//                  high_mesh, low_mesh, uv, io, bake, total} (a group no stage
//                  of the run belongs to is null), peak_ram_bytes, faces,
//                  texture_size: {width_px, height_px}, texture_bytes, fps,
//                  fits, device, vs_hpm: {psnr_db, ssim_luma, ssim_rgb,
//                  ms_ssim_luma, flip_mean}, vs_truth: {...}, vs_scan:
//                  {covered_psnr_db, covered_ssim_luma, covered_flip_mean,
//                  coverage_iou, hole_fraction, nearer_fraction,
//                  farther_fraction, splat_hole_fraction}, scan_geometry:
//                  {invented_area_fraction, missing_fraction,
//                  boundary_edges_per_1000_faces, back_face_fraction
//                  (run.json: render.frames' counter back_share of the
//                  stage "outputs" names for `frames`)}, warnings:
//                  [{stage, warning}] (the stages' warnings from run.json,
//                  failed runs included; [] when none), error (failed
//                  runs only)}],
//                  "speedups": {"versus": "point_transfer", "per_scene":
//                  [{scene, workflow, variant, ratio}], "geometric_mean":
//                  [{workflow, variant, ratio, scenes}]}}
//                  ratio = other run's total / point transfer's total (> 1:
//                  point transfer is faster); unknown values are null
//   results.csv   the same rows flattened, one header line; null = empty;
//                 `warnings` is the count
//   report.md     tables (times, RAM, quality, FPS, speed-ups), the warnings
//                 (run, stage, text), image links
//   report.html   self-contained (inline CSS/SVG, images as data: URIs; no
//                 network, no scripts): stacked time bars per scene,
//                 peak-RAM bars, the quality, against-the-scan and FPS
//                 tables, speed-up ratios, the warnings, and per scene the
//                 frames side by side (ground truth, the scan's splats, each
//                 workflow) with zoomed crops and FLIP maps
//   images/       the thumbnails, crops and FLIP maps report.md links to
//   viewer/       the 3-D viewer both reports link (index.html, viewer.js,
//                 models.json, three.js in lib/; report_viewer.cc,
//                 docs/viewer.md), served by `pointbake serve CAMPAIGN_DIR`
#pragma once

#include <string>

#include "base/status.h"

namespace pb {

struct ReportOptions {
  // Frames shown per scene in the side-by-side section (first N viewpoints).
  int max_viewpoints = 1;
  // Longest side of a frame thumbnail, pixels.
  int thumbnail_px = 320;
  // Side of a zoomed crop taken from the full-size frame, pixels (shown
  // enlarged, nearest neighbor).
  int crop_px = 96;
};

// Reads <campaign_dir>/campaign.json and the run folders it names and writes
// the report into `report_dir` (created if missing). Runs that failed appear
// with status "failed" and null figures. Errors (unreadable manifest,
// malformed run.json or table) name the file; options out of range
// (thumbnail_px < 16, crop_px < 4, max_viewpoints < 0) are Status::Invalid.
// Deterministic: the same campaign folder gives byte-identical files.
// Without three.js in tools/node_modules the report files are written and the
// result is Status::NotFound naming what to install.
Status WriteCampaignReport(const std::string& campaign_dir, const std::string& report_dir,
                           const ReportOptions& options = {});

}  // namespace pb
