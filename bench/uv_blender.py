# Times Blender's Smart UV Project (the paper's unwrapper) on a PLY mesh.
#   blender -b --factory-startup --python bench/uv_blender.py -- mesh.ply [angle_deg] [margin] [out.ply]
# Prints one line: faces, import time, smart_project time (the figure
# compared in docs/uv.md). With out.ply, writes the unwrapped mesh (UVs as
# s, t; vertices split at seams) for uv_atlas_test's measuring tool.
import sys
import time

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
path = argv[0]
angle_deg = float(argv[1]) if len(argv) > 1 else 66.0
margin = float(argv[2]) if len(argv) > 2 else 0.001
out = argv[3] if len(argv) > 3 else None

bpy.ops.wm.read_factory_settings(use_empty=True)
start = time.perf_counter()
bpy.ops.import_mesh.ply(filepath=path)
imported = time.perf_counter() - start
obj = bpy.context.selected_objects[0]
bpy.context.view_layer.objects.active = obj
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
start = time.perf_counter()
bpy.ops.uv.smart_project(angle_limit=angle_deg * 3.141592653589793 / 180.0, island_margin=margin)
unwrapped = time.perf_counter() - start
bpy.ops.object.mode_set(mode="OBJECT")
if out:
    bpy.ops.export_mesh.ply(filepath=out, use_selection=True, use_normals=False, use_uv_coords=True,
                            use_colors=False)
print("blender smart_project: faces %d, import %.3f s, unwrap %.3f s (angle %.0f deg, margin %.4f)"
      % (len(obj.data.polygons), imported, unwrapped, angle_deg, margin))
