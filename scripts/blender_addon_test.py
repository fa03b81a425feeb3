"""The Blender extension (blender/), tested headless with the PyPI `bpy` as a user drives it.

    STICKY_LIPS_BIN=target/debug/sticky-lips .venv-anim/bin/python scripts/blender_addon_test.py \\
        ZIP HEAD_DIR OUT_DIR

ZIP is the extension built by scripts/build_blender_extension.py; HEAD_DIR holds the
MakeHuman head as scripts/makehuman_face.py --head writes it (head.obj in decimetres, y up,
and rig.json); OUT_DIR is made (Blender's user resources, the work directory, the runs).

 1. installs the zip into the user extension repository and enables it, as Preferences >
    Get Extensions > Install from Disk does (bpy.ops.extensions.package_install_files), in a
    user resource directory of its own (BLENDER_USER_RESOURCES), and sets the preference
    to the sticky-lips executable;
 2. imports head.obj the way an artist would (Blender's default OBJ axes: the head stands
    up, turned by its object transform), with the scene in decimetres (unit scale 0.1),
    24 fps, and skins it to an armature whose jaw bone sits on the rig's hinge (vertex group
    `jaw` of the rig's weights), the bone keyed open by 0.15 rad over 3 frames;
 3. Build model at resolution 0.25: the rig.json written holds the rig's jaw weights and its
    hinge (turned into world space), the preview object has the model's three groups;
 4. Simulate (0.25 s at 120 frames per second, the jaw from the bone's keys, stickiness per
    zone), polled until it ends by the function the add-on's timer runs: the progress seen
    rises to 100 %; blender.toml holds the bone's keys and the zones' values;
 5. Load result: the head has the Mesh Cache modifier; at scene frames 1, 4 and 7 (cache
    frames 0, 15 and 30) the evaluated head, in world space, is skin.pc2's frame to 1e-6 m;
    the saliva object shows the faces the USD's `broken` primvar has intact at that frame;
 6. Simulate again, 20 s long, the jaw given as an angle (blender.toml's [jaw]: angle,
    duration, smooth_step): the previous result is removed at the start (a re-run replaces
    it); Cancel once 12 frames are written: the run stops, the add-on exports the frames
    kept, and Load result plays them (cache frames 0, 10 and the last equal the PC2's to
    1e-6 m), one modifier and one saliva object on the head; with USD playback the imported
    skin.usda gives the same frames, the head hidden, and going back to PC2 undoes that;
 7. a run the CLI refuses (a resolution far beyond the machine's memory) ends with the
    CLI's message in the status line and the report;
 8. Build model again with vertex groups upper_lip and lower_lip on the contours found in
    step 3: rig.json names them, `face` takes the same contours, the loaded result is gone;
 9. Build model on a UV sphere (a head with no mouth): the operator fails with the CLI's
    readable message (no traceback).
Each step prints the seconds since the start. Timers do not run in bpy used as a module (no
event loop): the test calls the add-on's timer function itself, as Blender's would.
"""

import json
import os
import re
import struct
import sys
import time
from pathlib import Path

TOL_M = 1e-6
T0 = time.time()


def step(msg):
    print(f"[{time.time() - T0:6.1f} s] {msg}", flush=True)


def fail(msg):
    sys.exit(f"blender_addon_test.py: FAILED: {msg}")


def check(cond, msg):
    if not cond:
        fail(msg)


def setup_blender(out):
    """Blender's user resources in OUT (set before bpy is imported, which reads them)."""
    user = Path(out) / "blender-user"
    user.mkdir(parents=True, exist_ok=True)
    os.environ["BLENDER_USER_RESOURCES"] = str(user)
    import bpy  # noqa: F401

    return user


def install(zip_path, executable):
    """The extension installed from its zip and enabled; its package and modules."""
    import bpy

    r = bpy.ops.extensions.package_install_files(filepath=str(zip_path), repo="user_default",
                                                 enable_on_install=True)
    check(r == {"FINISHED"}, f"installing {zip_path}: {r}")
    pkg = "bl_ext.user_default.sticky_lips"
    check(pkg in bpy.context.preferences.addons, f"{pkg} is not enabled after installing")
    bpy.context.preferences.addons[pkg].preferences.executable = str(executable)
    mods = {name: sys.modules[f"{pkg}.{name}"] for name in ("simulate", "result", "build")}
    return pkg, mods


def new_scene():
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.fps = 24
    sc.render.fps_base = 1.0
    sc.frame_start = 1
    sc.frame_end = 48
    sc.unit_settings.system = "METRIC"
    sc.unit_settings.scale_length = 0.1  # one Blender unit is a decimetre, as head.obj's
    return sc


def import_head(head_dir):
    """head.obj with Blender's default OBJ axes (-Z forward, Y up): the importer turns the
    y-up head upright by its object transform."""
    import bpy

    before = set(bpy.data.objects)
    bpy.ops.wm.obj_import(filepath=str(Path(head_dir) / "head.obj"))
    obj = next(o for o in bpy.data.objects if o not in before)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def obj_index_map(obj, head_obj):
    """For each vertex of the imported `obj`, its vertex index in the OBJ file `head_obj`
    (Blender's importer leaves out the vertices no face uses, as the MakeHuman head's many):
    matched by their coordinates (each written once, read into single precision alike)."""
    import numpy as np

    rows = [line.split()[1:4] for line in open(head_obj) if line.startswith("v ")]
    file_co = np.array(rows, dtype=np.float64).astype(np.float32)
    where = {}
    for i, c in enumerate(map(tuple, file_co.tolist())):
        where.setdefault(c, []).append(i)
    co = np.empty(3 * len(obj.data.vertices), dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    out = []
    for c in map(tuple, co.reshape(-1, 3).tolist()):
        hits = where.get(c)
        check(hits is not None and len(hits) == 1, f"vertex at {c} matches {hits} vertices of {head_obj}")
        out.append(hits[0])
    return out


def rig_jaw(obj, rig, open_angle, open_frames, index):
    """An armature with a bone `jaw` on the rig's hinge (its X axis the hinge axis), the
    rig's jaw weights as the vertex group `jaw` (`index`: each vertex's index in the rig),
    an Armature modifier, and the bone keyed
    from 0 at the scene's first frame to `open_angle` (rad, opening) `open_frames` later.
    Returns the armature and the hinge in world space (point, axis)."""
    import bpy
    from mathutils import Vector

    m = obj.matrix_world
    point = m @ Vector(rig["hinge_point"])
    axis = (m.to_3x3() @ Vector(rig["hinge_axis"])).normalized()
    arm_data = bpy.data.armatures.new("rig")
    arm = bpy.data.objects.new("rig", arm_data)
    bpy.context.scene.collection.objects.link(arm)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    b = arm_data.edit_bones.new("jaw")
    b.head = point
    # towards the chin: forward (-Y) and down, across the hinge axis
    b.tail = point + Vector((0.0, -0.6, -0.3))
    b.align_roll(axis.cross(b.vector).normalized())  # bone Z across, so bone X lies on the axis
    bpy.ops.object.mode_set(mode="OBJECT")
    bx = (arm.matrix_world @ arm_data.bones["jaw"].matrix_local).to_3x3() @ Vector((1, 0, 0))
    check(abs(abs(bx.dot(axis)) - 1.0) < 1e-6, f"the jaw bone's X axis {bx} is not the hinge axis {axis}")
    g = obj.vertex_groups.new(name="jaw")
    for v, i in enumerate(index):
        w = rig["jaw_weight"][i]
        if w > 0.0:
            g.add([v], w, "REPLACE")
    mod = obj.modifiers.new("Armature", "ARMATURE")
    mod.object = arm
    pb = arm.pose.bones["jaw"]
    pb.rotation_mode = "XYZ"
    sign = 1.0 if bx.dot(axis) > 0 else -1.0
    # a key on every frame of the opening (a straight ramp), so that the value at each
    # frame is the key's whatever the interpolation between keys
    start = bpy.context.scene.frame_start
    for k in range(open_frames + 1):
        pb.rotation_euler = (sign * open_angle * k / open_frames, 0.0, 0.0)
        pb.keyframe_insert("rotation_euler", frame=start + k)
    bpy.context.view_layer.objects.active = obj
    return arm, point, axis


def wait(simulate, on_poll=None, limit_s=600.0):
    """Calls the add-on's timer function until the job is over (bpy run as a module has no
    event loop to run timers); `on_poll` sees the window manager after each call."""
    import bpy

    t = time.time()
    while True:
        again = simulate.poll()
        if on_poll:
            on_poll(bpy.context.window_manager)
        if again is None:
            return
        if time.time() - t > limit_s:
            simulate.stop_all()
            fail(f"the job did not end within {limit_s} s")
        time.sleep(0.05)


def read_pc2(path):
    import numpy as np

    raw = Path(path).read_bytes()
    nv, ns = struct.unpack("<i", raw[16:20])[0], struct.unpack("<i", raw[28:32])[0]
    return np.frombuffer(raw[32:], dtype="<f4").reshape(ns, nv, 3).astype(np.float64)


def evaluated_world(obj):
    import bpy
    import numpy as np

    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    me = ev.to_mesh()
    co = np.empty(3 * len(me.vertices))
    me.vertices.foreach_get("co", co)
    n = len(me.polygons)
    ev.to_mesh_clear()
    m = np.array(obj.matrix_world)
    return co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3], n


def usd_broken(usda, timecode):
    """The `broken` primvar of the saliva mesh at a time code, from the USD text."""
    text = Path(usda).read_text()
    i = text.index("primvars:broken.timeSamples")
    block = text[i:text.index("}", i)]
    m = re.search(rf"^\s*{timecode}: \[([^\]]*)\]", block, re.M)
    check(m is not None, f"no time sample {timecode} of primvars:broken in {usda}")
    return [float(x) for x in m.group(1).split(",")]


def compare_frames(head, pc2, pairs, metres_per_unit, what):
    import bpy

    sc = bpy.context.scene
    worst = 0.0
    for f, k in pairs:
        sc.frame_set(f)
        world, _ = evaluated_world(head)
        d = float(abs(world - pc2[k]).max()) * metres_per_unit
        worst = max(worst, d)
        check(d <= TOL_M, f"{what}: scene frame {f}: the head is {d:.3e} m from skin.pc2 frame {k}")
    return worst


def main(zip_path, head_dir, out):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    exe = os.environ.get("STICKY_LIPS_BIN") or str(Path(__file__).resolve().parent.parent / "target/debug/sticky-lips")
    check(Path(exe).is_file(), f"no sticky-lips executable at {exe} (set STICKY_LIPS_BIN)")
    setup_blender(out)
    import bpy
    import numpy as np

    # an empty scene first: loading factory settings would turn extensions off again
    sc = new_scene()
    step(f"Blender {bpy.app.version_string} (bpy, background); installing {zip_path}")
    pkg, mods = install(zip_path, exe)
    simulate = mods["simulate"]
    s = sc.sticky_lips
    s.directory = str(out / "work")
    head = import_head(head_dir)
    rig = json.loads((Path(head_dir) / "rig.json").read_text())
    index = obj_index_map(head, Path(head_dir) / "head.obj")
    arm, hinge_point, hinge_axis = rig_jaw(head, rig, 0.15, 3, index)
    check(any(abs(head.matrix_world[i][j] - (i == j)) > 0.5 for i in range(3) for j in range(3)),
          "the imported head has no rotation: the world-transform path is not exercised")

    step("Build model (resolution 0.25)")
    s.resolution = 0.25
    check(bpy.ops.sticky_lips.build_model() == {"FINISHED"}, "Build model did not finish")
    work = out / "work" / head.name
    written = json.loads((work / "rig.json").read_text())
    w = np.array(written["jaw_weight"])
    check(w.shape == (len(index),), f"{len(w)} jaw weights for {len(index)} vertices")
    dw = float(abs(w - np.array(rig["jaw_weight"])[index]).max())
    check(dw <= 1e-6, f"jaw weights differ from the rig's by {dw} (vertex group weights are float32)")
    dp = float(abs(np.array(written["hinge_point"]) - np.array(hinge_point)).max())
    check(dp * 0.1 <= TOL_M, f"the hinge is {dp * 0.1:.3e} m from the rig's (in world space)")
    da = float(abs(np.array(written["hinge_axis"]) - np.array(hinge_axis)).max())
    check(da <= 1e-6, f"the hinge axis {written['hinge_axis']} is not the rig's {list(hinge_axis)}")
    preview = bpy.data.objects.get(head.name + ".sticky_lips_model")
    check(preview is not None, "no preview object")
    names = sorted(m.name for m in preview.data.materials)
    check(names == ["Sticky Lips lower_face", "Sticky Lips saliva", "Sticky Lips upper_face"],
          f"the preview's groups: {names}")
    nv_model = sum(1 for line in open(work / "model" / "model.obj") if line.startswith("v "))
    check(len(preview.data.vertices) == nv_model, "the preview is not model.obj")

    step("Simulate (0.25 s, 120 frames/s, jaw from the bone's keys)")
    s.duration = 0.25
    s.frame_rate = 120.0
    s.slow_motion = 1.0
    s.jaw_source = "BONE"
    s.k_glue_left, s.k_glue_centre, s.k_glue_right = 0.08, 0.1, 0.12
    s.moisture_left, s.moisture_centre, s.moisture_right = 100.0, 90.0, 100.0
    seen = []
    check(bpy.ops.sticky_lips.simulate() == {"FINISHED"}, "Simulate did not start")
    check(simulate.running(), "no job after Simulate")
    wait(simulate, lambda wm: seen.append(wm.sticky_lips_progress))
    wm = bpy.context.window_manager
    check(wm.sticky_lips_status.startswith("finished"), f"the run did not finish: {wm.sticky_lips_status}")
    check(all(b >= a for a, b in zip(seen, seen[1:])), f"the progress went back: {seen}")
    check(seen and seen[-1] == 1.0, f"the progress did not reach 100 %: {seen[-3:]}")
    check(len({p for p in seen if p < 1.0}) >= 2, f"the progress was not seen rising: {sorted(set(seen))}")
    step(f"progress seen: {len(seen)} polls, {len(set(seen))} values, {100 * seen[0]:.0f} % .. {100 * seen[-1]:.0f} %")
    import tomllib

    toml = tomllib.loads((work / "model" / "blender.toml").read_text())
    keys = toml["jaw"]["keys"]
    check(toml["jaw"]["keys_fps"] == 24.0, f"keys_fps {toml['jaw']['keys_fps']}")
    expect = [[float(f), 0.15 * min(f, 3) / 3] for f in range(7)]
    check(len(keys) == 7 and all(abs(a[0] - b[0]) < 1e-12 and abs(a[1] - b[1]) < 1e-6 for a, b in zip(keys, expect)),
          f"the jaw keys {keys} are not the bone's {expect}")
    zones = {t["material"]: (t["k_glue"], t["initial_moisture"]) for t in toml["saliva"]}
    # the panel's values are single precision
    want = {"saliva_left": (0.08, 100.0), "saliva_centre": (0.1, 90.0), "saliva_right": (0.12, 100.0)}
    check(zones.keys() == want.keys() and all(abs(zones[z][i] - want[z][i]) <= 1e-6 * want[z][i]
                                              for z in want for i in (0, 1)),
          f"the zones' saliva: {zones}")

    step("Load result")
    check(bpy.ops.sticky_lips.load_result() == {"FINISHED"}, "Load result did not finish")
    mod = head.modifiers.get("Sticky Lips")
    check(mod is not None and mod.type == "MESH_CACHE", "no Mesh Cache modifier on the head")
    check(head.modifiers[-1] == mod, "the Mesh Cache modifier is not last in the stack")
    run = work / "run"
    pc2 = read_pc2(run / "skin.pc2")
    check(pc2.shape[0] == 31, f"{pc2.shape[0]} frames in skin.pc2 (0.25 s at 120 per second: 31)")
    worst = compare_frames(head, pc2, [(1, 0), (4, 15), (7, 30)], 0.1, "Load result")
    step(f"the head at scene frames 1, 4, 7 is skin.pc2's frames 0, 15, 30 to {worst:.2e} m "
         f"(modifier reads {Path(mod.filepath).name})")
    saliva = bpy.data.objects.get(head.name + ".sticky_lips_saliva")
    check(saliva is not None, "no saliva object")
    for f, k in [(1, 0), (4, 15), (7, 30)]:
        sc.frame_set(f)
        _, faces = evaluated_world(saliva)
        intact = sum(1 for b in usd_broken(run / "skin.usda", k) if b < 0.5)
        check(faces == intact, f"scene frame {f}: the saliva shows {faces} faces; {intact} are intact at frame {k}")
    step(f"the saliva object shows the intact faces of cache frames 0, 15, 30 "
         f"({sum(1 for b in usd_broken(run / 'skin.usda', 30) if b < 0.5)} left at the end)")
    s.saliva_display = "COLOUR"
    sc.frame_set(7)
    _, faces = evaluated_world(saliva)
    check(faces == len(usd_broken(run / "skin.usda", 30)), "with Colour every saliva face is shown")
    s.saliva_display = "HIDE"

    step("Simulate again (20 s, the jaw at an angle), then Cancel")
    s.duration = 20.0
    s.jaw_source = "VALUE"
    s.jaw_angle = 0.12
    s.jaw_open_time = 0.3
    check(bpy.ops.sticky_lips.simulate() == {"FINISHED"}, "the second Simulate did not start")
    jaw = tomllib.loads((work / "model" / "blender.toml").read_text())["jaw"]
    check(jaw.keys() == {"angle", "duration", "shape"} and abs(jaw["angle"] - 0.12) < 1e-6
          and abs(jaw["duration"] - 0.3) < 1e-6 and jaw["shape"] == "smooth_step", f"[jaw] {jaw}")
    check(head.modifiers.get("Sticky Lips") is None and bpy.data.objects.get(head.name + ".sticky_lips_saliva") is None,
          "the previous result is still loaded after a re-run started")
    t = time.time()
    while True:
        simulate.poll()
        last = simulate.JOB["process"].last if simulate.JOB else None
        if last and last.get("frames", 0) >= 12:
            break
        check(simulate.running(), f"the long run ended before it could be cancelled: {wm.sticky_lips_status}")
        check(time.time() - t < 300, "no 12 frames within 300 s")
        time.sleep(0.05)
    check(bpy.ops.sticky_lips.cancel() == {"FINISHED"}, "Cancel failed")
    wait(simulate)
    check(wm.sticky_lips_status.startswith("cancelled at t = "), f"after Cancel: {wm.sticky_lips_status}")
    summary = json.loads((run / "summary.json").read_text())
    step(f"cancelled: {wm.sticky_lips_status}")
    check(bpy.ops.sticky_lips.load_result() == {"FINISHED"}, "Load result of the cancelled run failed")
    pc2 = read_pc2(run / "skin.pc2")
    n = pc2.shape[0]
    check(12 <= n < 2401, f"the cancelled run's cache has {n} frames")
    # scene frames 1 and 3 are cache frames 0 and 10; past the cache's end the modifier holds
    # its last frame
    frames = [(1, 0), (3, 10), (2 + (n - 1) // 5, n - 1)]
    worst = compare_frames(head, pc2, frames, 0.1, "Load result (cancelled run)")
    check(len([m for m in head.modifiers if m.type == "MESH_CACHE"]) == 1, "more than one Mesh Cache modifier")
    check(len([o for o in bpy.data.objects if o.name.startswith(head.name + ".sticky_lips_saliva")]) == 1,
          "more than one saliva object")
    step(f"the partial run ({n} frames, summary: {json.dumps({k: summary.get(k) for k in ('interrupted', 'steps')})}) "
         f"plays: frames {[k for _, k in frames]} to {worst:.2e} m")

    step("Load result with USD playback, then back to the Mesh Cache")
    s.playback = "USD"
    check(bpy.ops.sticky_lips.load_result() == {"FINISHED"}, "Load result (USD) failed")
    skin = bpy.data.objects.get(head.name + ".sticky_lips_usd")
    check(skin is not None, "no USD object")
    check(head.modifiers.get("Sticky Lips") is None and head.hide_render and not head.visible_get(),
          "the head is still shown (or still has its modifier) with USD playback")
    worst = compare_frames(skin, pc2, frames, 0.1, "USD playback")
    s.playback = "PC2"
    check(bpy.ops.sticky_lips.load_result() == {"FINISHED"}, "Load result (PC2 again) failed")
    check(bpy.data.objects.get(head.name + ".sticky_lips_usd") is None and head.visible_get()
          and not head.hide_render and head.modifiers.get("Sticky Lips") is not None,
          "going back to PC2 did not remove the USD object and show the head")
    step(f"skin.usda imported: frames {[k for _, k in frames]} equal the PC2's to {worst:.2e} m")

    step("a run the CLI refuses: its error ends the job")
    s.duration = 0.25
    s.resolution = 100000.0  # a model far over the machine's memory: the run refuses it
    check(bpy.ops.sticky_lips.simulate() == {"FINISHED"}, "Simulate did not start")
    wait(simulate)
    check(wm.sticky_lips_status.startswith("failed: ") and "mesh.face.resolution" in wm.sticky_lips_status,
          f"the refused run: {wm.sticky_lips_status}")
    check("Traceback" not in wm.sticky_lips_status, "a traceback in the status")
    step(f"status: {wm.sticky_lips_status[:160]}")
    s.resolution = 0.25

    step("Build model with the lips named by vertex groups upper_lip and lower_lip")
    face = json.loads((work / "model" / "face.json").read_text())
    named = {g: [face["source_vertex"][v] for v in face[c]]
             for g, c in (("upper_lip", "upper_contour"), ("lower_lip", "lower_contour"))}
    for g, vs in named.items():
        head.vertex_groups.new(name=g).add(vs, 1.0, "REPLACE")
    bpy.context.view_layer.objects.active = head
    check(bpy.ops.sticky_lips.build_model() == {"FINISHED"}, "Build model with lip groups failed")
    written = json.loads((work / "rig.json").read_text())
    for g, vs in named.items():
        check(sorted(written.get(g, [])) == sorted(set(vs)), f"rig.json's {g} is not the vertex group's")
    again = json.loads((work / "model" / "face.json").read_text())
    for g, c in (("upper_lip", "upper_contour"), ("lower_lip", "lower_contour")):
        check([again["source_vertex"][v] for v in again[c]] == named[g],
              f"the {c} through the named vertices differs from the one found")
    check(head.modifiers.get("Sticky Lips") is None and not (work / "run").exists(),
          "a new model left the old run loaded")
    step(f"named lips ({len(named['upper_lip'])} and {len(named['lower_lip'])} vertices) give the contours found before")

    step("Build model on a head with no mouth (a UV sphere)")
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, location=(3.0, 0.0, 0.0))
    sphere = bpy.context.active_object
    try:
        bpy.ops.sticky_lips.build_model()
    except RuntimeError as e:
        msg = str(e)
    else:
        fail("Build model on a sphere succeeded")
    check("Traceback" not in msg and "no mouth found" in msg and "upper_lip" in msg,
          f"the error is not the readable one: {msg!r}")
    check(msg.startswith("Error: Build model: "), f"not an operator report: {msg!r}")
    step(f"refused: {msg.strip()[:200]} ...")
    check(sphere.modifiers.get("Sticky Lips") is None, "the sphere got a modifier")
    step("all checks passed")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
