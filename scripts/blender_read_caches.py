"""Blender (PyPI `bpy`, headless) as a client of a sticky-lips run's animation files.

    python scripts/blender_read_caches.py RUN_DIR FRAME OUT.json

In a fresh empty scene it
  1. imports RUN_DIR/skin.obj without axis conversion (forward +Y, up +Z: Blender's own
     axes, so the vertices keep the file's coordinates) and adds a Mesh Cache modifier
     reading RUN_DIR/skin.pc2 (no axis conversion either), then evaluates the mesh at scene
     frame FRAME;
  2. imports RUN_DIR/skin.usda with Blender's USD importer and evaluates the `skin` mesh at
     the same frame;
and writes both vertex lists (object-local coordinates, the files' units) to OUT.json with
Blender's version. scripts/check_animation.py compares them with the run's own numbers.

Run it in its own process: bpy brings its own USD libraries, which must not meet usd-core's
in one interpreter.
"""

import json
import sys

import bpy


def evaluated_vertices(obj):
    deps = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(deps)
    mesh = ev.to_mesh()
    out = [list(v.co) for v in mesh.vertices]
    ev.to_mesh_clear()
    return out


def main(run_dir, frame, out_path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    # 1. OBJ + PC2 through the Mesh Cache modifier
    bpy.ops.wm.obj_import(filepath=f"{run_dir}/skin.obj", forward_axis="Y", up_axis="Z")
    obj = bpy.context.selected_objects[0]
    mod = obj.modifiers.new("sticky_lips", "MESH_CACHE")
    mod.cache_format = "PC2"
    mod.filepath = f"{run_dir}/skin.pc2"
    mod.forward_axis = "POS_Y"
    mod.up_axis = "POS_Z"
    mod.frame_start = 0.0
    mod.frame_scale = 1.0
    scene.frame_start = 0
    scene.frame_set(frame)
    pc2 = evaluated_vertices(obj)
    rest = [list(v.co) for v in obj.data.vertices]
    # 2. USD (its own stage frame rate: the scene takes it so frame k is time code k)
    bpy.ops.wm.usd_import(filepath=f"{run_dir}/skin.usda", set_frame_range=True)
    usd_obj = next(o for o in bpy.context.scene.objects if o.type == "MESH" and o.name.startswith("skin") and o is not obj)
    scene.frame_set(frame)
    usd = evaluated_vertices(usd_obj)
    with open(out_path, "w") as f:
        json.dump({"blender": bpy.app.version_string, "frame": frame, "fps": scene.render.fps,
                   "rest": rest, "pc2": pc2, "usd": usd,
                   "usd_modifiers": [m.type for m in usd_obj.modifiers]}, f)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3])
