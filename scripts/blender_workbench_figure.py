"""The README's picture of the Blender extension: the MakeHuman head after Build model,
Simulate and Load result, rendered with Blender's workbench engine at the middle frame.

    STICKY_LIPS_BIN=target/release/sticky-lips .venv-anim/bin/python \\
        scripts/blender_workbench_figure.py ZIP HEAD_DIR OUT.png

ZIP and HEAD_DIR as for scripts/blender_addon_test.py (whose scene set-up this script
uses: the extension installed from its zip, the head imported with Blender's default OBJ
axes in a decimetre scene, a jaw bone on the rig's hinge). The jaw opens by 0.15 rad over
0.3 s as a value (the panel's Angle), the model at resolution 0.5, 0.36 s simulated at 240
frames per second (the lips peel apart around 0.18 s: the middle frame); the saliva's broken
faces are hidden, the intact ones blue. The camera looks at the mouth from the front, a
little from the subject's right and below.
Writes OUT.png and OUT.json (what was rendered: settings, frame, broken saliva faces).
"""

import json
import math
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import blender_addon_test as t  # noqa: E402


def main(zip_path, head_dir, out_png):
    out_png = Path(out_png).resolve()
    root = Path(__file__).resolve().parent.parent
    work_root = root / "target" / "blender-figure"  # Blender's user resources, the run
    exe = os.environ.get("STICKY_LIPS_BIN") or str(root / "target/release/sticky-lips")
    t.check(Path(exe).is_file(), f"no sticky-lips executable at {exe} (set STICKY_LIPS_BIN)")
    t.setup_blender(work_root)
    import bpy
    from mathutils import Vector

    sc = t.new_scene()
    _, mods = t.install(zip_path, exe)
    s = sc.sticky_lips
    s.directory = str(work_root / "work")
    head = t.import_head(head_dir)
    rig = json.loads((Path(head_dir) / "rig.json").read_text())
    t.rig_jaw(head, rig, 0.15, 3, t.obj_index_map(head, Path(head_dir) / "head.obj"))
    bpy.context.view_layer.objects.active = head

    s.resolution = 0.5
    t.check(bpy.ops.sticky_lips.build_model() == {"FINISHED"}, "Build model failed")
    s.duration = 0.36
    s.frame_rate = 240.0
    s.jaw_source = "VALUE"
    s.jaw_angle = 0.15
    s.jaw_open_time = 0.3
    s.saliva_display = "HIDE"
    t.check(bpy.ops.sticky_lips.simulate() == {"FINISHED"}, "Simulate failed to start")
    t.wait(mods["simulate"])
    wm = bpy.context.window_manager
    t.check(wm.sticky_lips_status.startswith("finished"), wm.sticky_lips_status)
    t.check(bpy.ops.sticky_lips.load_result() == {"FINISHED"}, "Load result failed")
    preview = bpy.data.objects.get(head.name + ".sticky_lips_model")
    preview.hide_set(True)

    work = work_root / "work" / head.name
    frames = t.read_pc2(work / "run" / "skin.pc2").shape[0]
    mid = (frames - 1) // 2
    # 240 cache frames per second at 24 scene frames per second: cache frame k at scene
    # frame 1 + k / 10; the middle frame's scene frame, as a frame and a subframe
    f = 1 + mid * 24.0 / 240.0
    sc.frame_set(int(math.floor(f)), subframe=f - math.floor(f))

    face = json.loads((work / "model" / "face.json").read_text())
    mx, my, mz = face["mouth_center"]  # model frame, metres
    scale = face["input"]["scale"]
    mouth = Vector((mx, -mz, my)) / scale  # Blender units (decimetres, Z up, -Y forward)

    mat = bpy.data.materials.new("skin")
    mat.diffuse_color = (0.8, 0.62, 0.55, 1.0)
    head.data.materials.clear()
    head.data.materials.append(mat)
    head.data.shade_smooth()
    cam_data = bpy.data.cameras.new("camera")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = 0.95
    cam = bpy.data.objects.new("camera", cam_data)
    sc.collection.objects.link(cam)
    eye = mouth + Vector((-0.6, -3.0, -0.45))
    cam.location = eye
    cam.rotation_euler = (mouth - eye).to_track_quat("-Z", "Y").to_euler()
    sc.camera = cam
    r = sc.render
    r.engine = "BLENDER_WORKBENCH"
    r.resolution_x, r.resolution_y = 720, 480
    r.film_transparent = False
    sc.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("background")
    world.color = (0.16, 0.17, 0.19)
    sc.world = world
    shading = sc.display.shading
    shading.light = "STUDIO"
    shading.color_type = "MATERIAL"
    shading.show_cavity = True
    shading.show_specular_highlight = False
    r.image_settings.file_format = "PNG"
    r.image_settings.compression = 100
    r.filepath = str(out_png)
    bpy.ops.render.render(write_still=True)

    usd = work / "run" / "skin.usda"
    broken = t.usd_broken(usd, mid)
    info = {
        "made_by": "scripts/blender_workbench_figure.py",
        "blender": bpy.app.version_string,
        "settings": {"resolution": 0.5, "duration_s": 0.36, "frame_rate": 240.0, "jaw_angle_rad": 0.15,
                     "jaw_open_time_s": 0.3, "k_glue": 0.1, "moisture_um": 100.0},
        "frames": frames,
        "rendered_cache_frame": mid,
        "rendered_time_s": mid / 240.0,
        "saliva_faces": len(broken),
        "saliva_broken_at_that_frame": int(sum(1 for b in broken if b >= 0.5)),
    }
    out_png.with_suffix(".json").write_text(json.dumps(info, indent=2) + "\n")
    print(json.dumps(info))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
