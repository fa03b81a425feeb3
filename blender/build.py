"""Build model: the active mesh, as Blender evaluates it, made into a sticky-lips model.

The head is written in world space (its object transform applied) in the unit the scene's
unit scale names, with Blender's axes (Z up, -Y forward), so that `sticky-lips face` sees it
as it stands in the scene. Its rig (`rig.json`): the lips from the vertex groups `upper_lip`
and `lower_lip` when the head has both, the jaw's weights and hinge from an armature's jaw
bone when the head is skinned to one. The model's groups (upper face, lower face, saliva)
come back as a preview object.
"""

import math
import os
import shutil

import bpy
import numpy as np
from mathutils import Vector

from . import cli, common, result

UP = (0.0, 0.0, 1.0)
FORWARD = (0.0, -1.0, 0.0)

# the unit names `sticky-lips face --units` takes, with their metres
UNITS = (("m", 1.0), ("dm", 0.1), ("cm", 0.01), ("mm", 0.001), ("in", 0.0254))

LIP_GROUPS = ("upper_lip", "lower_lip")


def scene_units(scene):
    """(unit name, OBJ units per Blender unit) for the scene's unit scale: the named unit of
    that many metres when there is one (the coordinates are written as they are), else
    metres (the coordinates are written times the scale)."""
    us = scene.unit_settings
    metres = us.scale_length if us.system != "NONE" else 1.0
    if not (metres > 0.0 and math.isfinite(metres)):
        raise cli.CliError(f"the scene's unit scale {metres} is not a positive number")
    for name, m in UNITS:
        # Blender keeps the scale in single precision (0.1 is 0.10000000149...)
        if abs(metres - m) <= 1e-6 * m:
            return name, 1.0
    return "m", metres


def find_armature(obj):
    for m in obj.modifiers:
        if m.type == "ARMATURE" and m.object is not None and m.show_viewport:
            return m.object
    if obj.parent is not None and obj.parent.type == "ARMATURE":
        return obj.parent
    return None


def find_jaw_bone(obj, arm, name):
    """The jaw bone: `name` if given, else a bone called jaw (any case), else one with jaw in
    its name, that has a vertex group on the head. None if there is none."""
    if arm is None:
        if name:
            raise cli.CliError(f"the jaw bone `{name}` is set but {obj.name} has no armature")
        return None
    bones = arm.data.bones
    groups = {g.name for g in obj.vertex_groups}
    if name:
        if name not in bones:
            raise cli.CliError(f"the armature {arm.name} has no bone `{name}`")
        if name not in groups:
            raise cli.CliError(f"the jaw bone `{name}` has no vertex group on {obj.name} (its skinning weights)")
        return bones[name]
    cands = [b for b in bones if b.name.lower() == "jaw"] + [b for b in bones if "jaw" in b.name.lower()]
    for b in cands:
        if b.name in groups:
            return b
    return None


def hinge(arm, bone, obj_per_bu):
    """The jaw's hinge in the exported head's coordinates: the bone's head and its local X
    axis in world space, the axis turned towards +X (the subject's left, since the face looks
    along -Y); and the sign that turns the bone's own X rotation into a rotation about it."""
    mw = arm.matrix_world @ bone.matrix_local
    point = mw.translation * obj_per_bu
    axis = (mw.to_3x3().normalized() @ Vector((1.0, 0.0, 0.0))).normalized()
    sign = 1.0
    if axis.x < 0.0:
        axis, sign = -axis, -1.0
    return [float(x) for x in point], [float(x) for x in axis], sign


def jaw_angle(pose_bone, sign):
    """The jaw bone's rotation about its own X axis (rad, the twist of its pose rotation),
    times `sign` (from `hinge`)."""
    q = pose_bone.matrix_basis.to_quaternion()
    a = 2.0 * math.atan2(q.x, q.w)
    return sign * ((a + math.pi) % (2.0 * math.pi) - math.pi)


class _RestState:
    """Evaluates the head as it rests: the add-on's own modifier off, the armature in its
    rest position; both put back on exit."""

    def __init__(self, obj, arm):
        self.obj, self.arm = obj, arm

    def __enter__(self):
        self.mod = self.obj.modifiers.get(common.MODIFIER)
        self.mod_was = self.mod.show_viewport if self.mod else None
        if self.mod:
            self.mod.show_viewport = False
        self.pose_was = self.arm.data.pose_position if self.arm else None
        if self.arm:
            self.arm.data.pose_position = "REST"
        bpy.context.view_layer.update()
        return self

    def __exit__(self, *exc):
        if self.mod:
            self.mod.show_viewport = self.mod_was
        if self.arm:
            self.arm.data.pose_position = self.pose_was
        bpy.context.view_layer.update()
        return False


def export_head(context, obj, path, obj_per_bu, jaw_bone):
    """Writes the evaluated head to `path` (OBJ, world space times `obj_per_bu`); returns its
    vertex count, the members of the lip groups and the jaw group's weights."""
    dg = context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    me = ev.to_mesh(preserve_all_data_layers=True, depsgraph=dg)
    try:
        n = len(me.vertices)
        if n == 0 or len(me.polygons) == 0:
            raise cli.CliError(f"{obj.name} has no faces to make a model of")
        co = np.empty(3 * n, dtype=np.float64)
        me.vertices.foreach_get("co", co)
        co = co.reshape(n, 3)
        m = np.array(obj.matrix_world, dtype=np.float64)
        world = (co @ m[:3, :3].T + m[:3, 3]) * obj_per_bu
        counts = np.empty(len(me.polygons), dtype=np.int64)
        me.polygons.foreach_get("loop_total", counts)
        corners = np.empty(len(me.loops), dtype=np.int64)
        me.loops.foreach_get("vertex_index", corners)
        # vertex groups as the evaluated mesh carries them (same order as the written vertices)
        names = {g.index: g.name for g in obj.vertex_groups}
        wanted = set(LIP_GROUPS) | ({jaw_bone.name} if jaw_bone else set())
        members = {g: [] for g in LIP_GROUPS}
        jaw = np.zeros(n) if jaw_bone else None
        if wanted & set(names.values()):
            for v in me.vertices:
                for g in v.groups:
                    name = names.get(g.group)
                    if name in members and g.weight > 0.5:
                        members[name].append(v.index)
                    if jaw_bone is not None and name == jaw_bone.name:
                        jaw[v.index] = g.weight
    finally:
        ev.to_mesh_clear()
    lines = [f"# {obj.name} from Blender {bpy.app.version_string}: world space, Z up, -Y forward"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in world.tolist()]
    start = 0
    one_based = (corners + 1).tolist()
    for c in counts.tolist():
        lines.append("f " + " ".join(map(str, one_based[start : start + c])))
        start += c
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="ascii") as f:
        f.write("\n".join(lines))
        f.write("\n")
    os.replace(tmp, path)
    return n, members, jaw


def make_preview(context, obj, model_dir, scale_back):
    """The model's outer surface (`model.obj`: model frame, metres, y up, z forward) as an
    object beside the head, one material per group. `scale_back`: Blender units per metre."""
    verts, faces, groups, names = [], [], [], []
    current = 0
    with open(os.path.join(model_dir, "model.obj"), encoding="utf-8") as f:
        for line in f:
            if line.startswith("v "):
                x, y, z = map(float, line.split()[1:4])
                # model frame (x left, y up, z forward) to Blender's (x left, z up, -y forward)
                verts.append((x * scale_back, -z * scale_back, y * scale_back))
            elif line.startswith("g ") or line.startswith("usemtl "):
                name = line.split(None, 1)[1].strip()
                if name not in names:
                    names.append(name)
                current = names.index(name)
            elif line.startswith("f "):
                faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
                groups.append(current)
    name = obj.name + common.MODEL_SUFFIX
    old = bpy.data.objects.get(name)
    if old is not None:
        bpy.data.objects.remove(old)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    colours = {
        "upper_face": (0.85, 0.55, 0.45, 1.0),
        "lower_face": (0.65, 0.35, 0.3, 1.0),
        "saliva": (0.25, 0.55, 0.95, 1.0),
    }
    for g in names:
        mat = bpy.data.materials.get("Sticky Lips " + g) or bpy.data.materials.new("Sticky Lips " + g)
        mat.diffuse_color = colours.get(g, (0.7, 0.7, 0.7, 1.0))
        mesh.materials.append(mat)
    mesh.polygons.foreach_set("material_index", groups)
    mesh.update()
    pv = bpy.data.objects.new(name, mesh)
    for coll in obj.users_collection:
        coll.objects.link(pv)
    pv.hide_render = True
    pv.display_type = "SOLID"
    return pv


class STICKY_LIPS_OT_build_model(bpy.types.Operator):
    """Make a sticky-lips model of the active mesh (sticky-lips face), shown as a preview object"""

    bl_idname = "sticky_lips.build_model"
    bl_label = "Build model"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return context.active_object is not None

    def execute(self, context):
        try:
            self._build(context)
        except cli.CliError as e:
            self.report({"ERROR"}, f"Build model: {e}")
            return {"CANCELLED"}
        return {"FINISHED"}

    def _build(self, context):
        from . import simulate

        obj = common.head_of(context)
        if simulate.running():
            raise cli.CliError("a simulation is running: cancel it first")
        s = context.scene.sticky_lips
        exe = common.executable(context)
        unit, obj_per_bu = scene_units(context.scene)
        arm = find_armature(obj)
        bone = find_jaw_bone(obj, arm, s.jaw_bone)
        work = common.work_dir(context, obj)
        # a new model replaces the old one, its run and what was loaded from it
        result.clear(context, obj)
        for d in ("model", "run"):
            shutil.rmtree(os.path.join(work, d), ignore_errors=True)
        head = os.path.join(work, "head.obj")
        with _RestState(obj, arm):
            n, members, jaw = export_head(context, obj, head, obj_per_bu, bone)
        rig = {"source": f"Blender {bpy.app.version_string}: {obj.name}"}
        have = [g for g in LIP_GROUPS if g in obj.vertex_groups]
        if len(have) == 1:
            missing = [g for g in LIP_GROUPS if g not in have][0]
            raise cli.CliError(f"{obj.name} has a vertex group {have[0]} but no {missing}: name both lips or neither")
        if len(have) == 2:
            for g in LIP_GROUPS:
                if not members[g]:
                    raise cli.CliError(f"the vertex group {g} of {obj.name} has no vertex of weight above 0.5")
                rig[g] = members[g]
        sign = 1.0
        if bone is not None:
            point, axis, sign = hinge(arm, bone, obj_per_bu)
            rig["jaw_weight"] = [float(w) for w in jaw]
            rig["hinge_point"] = point
            rig["hinge_axis"] = axis
        rig_path = os.path.join(work, "rig.json")
        common.write_json(rig_path, rig)
        model = os.path.join(work, "model")
        args = [exe, "face", head, "--rig", rig_path, "--units", unit,
                "--up", ",".join(map(str, UP)), "--forward", ",".join(map(str, FORWARD)),
                "--resolution", repr(float(s.resolution)), "--out", model]
        context.window_manager.progress_begin(0, 1)
        try:
            out = cli.run(args)
        except cli.CliError as e:
            msg = str(e)
            if "no mouth found" in msg:
                msg = msg.rstrip(". ") + ". In Blender: give the head vertex groups upper_lip and lower_lip (the lips' inner edges)."
            raise cli.CliError(msg)
        finally:
            context.window_manager.progress_end()
        common.write_json(os.path.join(work, "blender.json"), {
            "object": obj.name,
            "vertices": n,
            "unit": unit,
            "obj_per_blender_unit": obj_per_bu,
            "matrix_world": [list(r) for r in obj.matrix_world],
            "resolution": float(s.resolution),
            "jaw_bone": bone.name if bone else None,
            "armature": arm.name if (arm and bone) else None,
            "jaw_sign": sign,
            "lips": "vertex groups" if len(have) == 2 else "found by sticky-lips face",
        })
        face = common.read_json(os.path.join(model, "face.json"), "written by sticky-lips face")
        scale = face["input"]["scale"]  # metres per unit of head.obj
        make_preview(context, obj, model, 1.0 / (scale * obj_per_bu))
        context.window_manager.sticky_lips_status = "model built: " + " ".join(
            line for line in out.splitlines() if line.startswith("face: resolution")
        )
        self.report({"INFO"}, f"Build model: {obj.name} made into a model in {model}")


classes = (STICKY_LIPS_OT_build_model,)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
