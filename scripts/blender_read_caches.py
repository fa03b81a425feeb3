"""Blender (PyPI `bpy`, headless) as a client of a sticky-lips run's animation files.

    python scripts/blender_read_caches.py RUN_DIR OUT.npz

In a fresh empty scene it
  1. imports RUN_DIR/skin.obj twice without axis conversion (forward +Y, up +Z: Blender's
     own axes, so the vertices keep the file's coordinates) and gives one copy a Mesh Cache
     modifier reading RUN_DIR/skin.pc2, the other one reading RUN_DIR/skin.mdd (no axis
     conversion either);
  2. imports RUN_DIR/skin.usda with Blender's USD importer (the scene takes the stage's
     frame rate, so that scene frame k is time code k);
then evaluates the three meshes at every scene frame from 0 to the caches' last and writes
the vertex positions (object-local coordinates, the files' units) to OUT.npz: `rest`
(vertices x 3, the imported OBJ), `pc2`, `mdd` and `usd` (frames x vertices x 3), and
`info` (a JSON string: Blender's version, the frame count, the scene's frame rate).
scripts/check_animation.py compares them with the run's own numbers.

Run it in its own process: bpy brings its own USD libraries, which must not meet usd-core's
in one interpreter.
"""

import json
import struct
import sys

import bpy
import numpy as np


def evaluated_vertices(obj):
    deps = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(deps)
    mesh = ev.to_mesh()
    co = np.empty(3 * len(mesh.vertices), dtype=np.float64)
    mesh.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    return co.reshape(-1, 3)


def obj_with_cache(run_dir, fmt):
    before = set(bpy.context.scene.objects)
    bpy.ops.wm.obj_import(filepath=f"{run_dir}/skin.obj", forward_axis="Y", up_axis="Z")
    obj = next(o for o in bpy.context.scene.objects if o not in before)
    mod = obj.modifiers.new(f"sticky_lips_{fmt}", "MESH_CACHE")
    mod.cache_format = fmt
    mod.filepath = f"{run_dir}/skin.{fmt.lower()}"
    mod.forward_axis = "POS_Y"
    mod.up_axis = "POS_Z"
    mod.frame_start = 0.0
    mod.frame_scale = 1.0
    return obj


def main(run_dir, out_path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    with open(f"{run_dir}/skin.pc2", "rb") as f:
        frames = struct.unpack("<i", f.read(32)[28:32])[0]
    pc2_obj = obj_with_cache(run_dir, "PC2")
    rest = np.array([list(v.co) for v in pc2_obj.data.vertices], dtype=np.float64)
    mdd_obj = obj_with_cache(run_dir, "MDD")
    before = set(scene.objects)
    bpy.ops.wm.usd_import(filepath=f"{run_dir}/skin.usda", set_frame_range=True)
    usd_obj = next(o for o in scene.objects
                   if o not in before and o.type == "MESH" and o.name.startswith("skin"))
    scene.frame_start = 0
    out = {"pc2": [], "mdd": [], "usd": []}
    for k in range(frames):
        scene.frame_set(k)
        out["pc2"].append(evaluated_vertices(pc2_obj))
        out["mdd"].append(evaluated_vertices(mdd_obj))
        out["usd"].append(evaluated_vertices(usd_obj))
    info = {"blender": bpy.app.version_string, "frames": frames, "fps": scene.render.fps,
            "usd_modifiers": [m.type for m in usd_obj.modifiers]}
    np.savez(out_path, rest=rest, info=json.dumps(info),
             **{name: np.array(v) for name, v in out.items()})


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
