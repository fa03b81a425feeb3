"""Load result: the run played on the head, and its saliva layer beside it.

The head gets a Mesh Cache modifier (last in its stack) reading `skin.pc2`; the saliva layer
is the `/sticky_lips/saliva` mesh of `skin.usda`, imported with Blender's USD importer (its
Mesh Sequence Cache reads the per-face `broken` primvar at every frame) and shown through a
geometry-nodes modifier that hides or colours the broken faces. Scene frame `f` plays cache
frame `(f - start) * frame_rate / (scene fps * slow motion)`, `start` the scene's first frame
when the run was started.

The caches are in the head's coordinates at the time it was exported (world space, in the
unit the scene named); where the head's transform was not the identity, or the unit was not
one `sticky-lips face` names, the PC2 the modifier reads is `skin_local.pc2`, the same frames
in the head's object space.
"""

import os
import struct

import bpy
import numpy as np
from mathutils import Matrix

from . import cli, common

PC2_HEADER = struct.Struct("<12siiffi")


def read_pc2(path):
    """(frames x vertices x 3 float32, start, sample rate) of a PC2 file."""
    with open(path, "rb") as f:
        raw = f.read()
    if len(raw) < PC2_HEADER.size:
        raise cli.CliError(f"{path} is too short to be a PC2 file")
    magic, version, nv, start, rate, ns = PC2_HEADER.unpack_from(raw)
    if magic != b"POINTCACHE2\0" or len(raw) != PC2_HEADER.size + 12 * nv * ns:
        raise cli.CliError(f"{path} is not a PC2 file of its stated size")
    frames = np.frombuffer(raw, dtype="<f4", offset=PC2_HEADER.size).reshape(ns, nv, 3)
    return frames, start, rate


def write_pc2(path, frames, start, rate):
    ns, nv, _ = frames.shape
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(PC2_HEADER.pack(b"POINTCACHE2\0", 1, nv, start, rate, ns))
        f.write(np.ascontiguousarray(frames, dtype="<f4").tobytes())
    os.replace(tmp, path)


def cache_rate(run):
    """Frames per simulated second of a run's caches, from the frame times in skin.mdd
    (big-endian: frame count, vertex count, then one time per frame)."""
    path = os.path.join(run, "skin.mdd")
    with open(path, "rb") as f:
        head = f.read(8)
        if len(head) < 8:
            raise cli.CliError(f"{path} is too short to be an MDD file")
        n, _ = struct.unpack(">ii", head)
        times = struct.unpack(f">{n}f", f.read(4 * n)) if n > 0 else ()
    if len(times) < 2 or not times[-1] > times[0]:
        return None
    return (len(times) - 1) / (times[-1] - times[0])


def local_matrix(meta):
    """The map from the exported head's coordinates to the head's object space, or None
    where it is the identity."""
    m = Matrix(meta["matrix_world"])
    k = meta["obj_per_blender_unit"]
    to_local = m.inverted() @ Matrix.Scale(1.0 / k, 4)
    if all(abs(to_local[i][j] - (1.0 if i == j else 0.0)) <= 1e-12 for i in range(4) for j in range(4)):
        return None
    return to_local


def clear(context, obj):
    """Removes what Load result added for `obj` (and shows the head again)."""
    mod = obj.modifiers.get(common.MODIFIER)
    if mod is not None:
        obj.modifiers.remove(mod)
    for suffix in (common.SALIVA_SUFFIX, common.USD_SKIN_SUFFIX):
        o = bpy.data.objects.get(obj.name + suffix)
        if o is not None:
            caches = {m.cache_file for m in o.modifiers if m.type == "MESH_SEQUENCE_CACHE" and m.cache_file}
            mesh = o.data
            bpy.data.objects.remove(o)
            if mesh is not None and mesh.users == 0:
                bpy.data.meshes.remove(mesh)
            unused = [c for c in caches if c.users == 0]
            if unused:
                bpy.data.batch_remove(unused)  # cache_files has no remove()
    if obj.get("sticky_lips_hidden"):
        obj.hide_render = False
        try:
            obj.hide_set(False)
        except RuntimeError:
            pass  # not in the current view layer
        del obj["sticky_lips_hidden"]


def _import_usd_prim(context, path, prim, name):
    """The mesh `prim` of the USD file `path`, imported as one object named `name`."""
    before = set(bpy.data.objects)
    wanted = {
        "prim_path_mask": prim,
        "set_frame_range": False,
        "apply_unit_conversion_scale": False,  # the object is placed by `_place`
        "import_materials": False,
        "create_collection": False,
    }
    # the options this Blender's importer has (they grew from 4.2 to 5.0)
    known = bpy.ops.wm.usd_import.get_rna_type().properties.keys()
    r = bpy.ops.wm.usd_import(filepath=path, **{k: v for k, v in wanted.items() if k in known})
    new = [o for o in bpy.data.objects if o not in before]
    meshes = [o for o in new if o.type == "MESH"]
    if "FINISHED" not in r or len(meshes) != 1:
        for o in new:
            bpy.data.objects.remove(o)
        raise cli.CliError(f"Blender's USD importer did not make one mesh of {prim} in {path}")
    ob = meshes[0]
    for o in new:
        if o is not ob:
            bpy.data.objects.remove(o)
    ob.name = name
    ob.parent = None
    return ob


def _time_map(ob, frame_start, scale):
    """The USD object's cache looks up time code `(frame - frame_start) * scale` (Blender
    reads time code k at scene frame k unless told otherwise): a driver on its frame."""
    for m in ob.modifiers:
        if m.type == "MESH_SEQUENCE_CACHE" and m.cache_file:
            cf = m.cache_file
            cf.override_frame = True
            cf.driver_remove("frame")
            d = cf.driver_add("frame").driver
            d.type = "SCRIPTED"
            d.expression = f"(frame - {frame_start!r}) * {scale!r}"


def saliva_node_group():
    """Geometry nodes: the faces whose `broken` attribute is over 0.5 get the material
    "Sticky Lips broken saliva", and are deleted when the input Hide Broken is on."""
    ng = bpy.data.node_groups.get(common.NODE_GROUP)
    if ng is not None:
        return ng
    ng = bpy.data.node_groups.new(common.NODE_GROUP, "GeometryNodeTree")
    ng.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    hide = ng.interface.new_socket("Hide Broken", in_out="INPUT", socket_type="NodeSocketBool")
    hide.default_value = True
    ng.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    n = ng.nodes
    gin = n.new("NodeGroupInput")
    gout = n.new("NodeGroupOutput")
    attr = n.new("GeometryNodeInputNamedAttribute")
    attr.data_type = "FLOAT"
    attr.inputs["Name"].default_value = "broken"
    cmp = n.new("FunctionNodeCompare")
    cmp.data_type = "FLOAT"
    cmp.operation = "GREATER_THAN"
    cmp.inputs[1].default_value = 0.5
    setm = n.new("GeometryNodeSetMaterial")
    setm.inputs["Material"].default_value = _material("Sticky Lips broken saliva", (0.9, 0.1, 0.1, 1.0))
    both = n.new("FunctionNodeBooleanMath")
    both.operation = "AND"
    delete = n.new("GeometryNodeDeleteGeometry")
    delete.domain = "FACE"
    link = ng.links.new
    link(attr.outputs["Attribute"], cmp.inputs[0])
    link(gin.outputs["Geometry"], setm.inputs["Geometry"])
    link(cmp.outputs["Result"], setm.inputs["Selection"])
    link(cmp.outputs["Result"], both.inputs[0])
    link(gin.outputs["Hide Broken"], both.inputs[1])
    link(setm.outputs["Geometry"], delete.inputs["Geometry"])
    link(both.outputs["Boolean"], delete.inputs["Selection"])
    link(delete.outputs["Geometry"], gout.inputs["Geometry"])
    for i, node in enumerate((gin, attr, cmp, both, setm, delete, gout)):
        node.location = (200 * i, 0)
    return ng


def _material(name, colour):
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.diffuse_color = colour
    return mat


def update_saliva_display(context):
    hide = context.scene.sticky_lips.saliva_display == "HIDE"
    for o in context.scene.objects:
        if o.name.endswith(common.SALIVA_SUFFIX):
            mod = o.modifiers.get(common.MODIFIER)
            if mod is not None:
                _set_hide(mod, hide)
                o.update_tag()


def _set_hide(mod, hide):
    ident = next(i.identifier for i in mod.node_group.interface.items_tree
                 if getattr(i, "in_out", None) == "INPUT" and i.name == "Hide Broken")
    mod[ident] = hide


def load(context, obj):
    """Loads the run of `obj` (see the module's text); returns a line saying what was loaded."""
    s = context.scene.sticky_lips
    work = common.work_dir(context, obj)
    meta = common.read_json(os.path.join(work, "blender.json"), "Build model first")
    run_meta = common.read_json(os.path.join(work, "run.json"), "Simulate first")
    run = os.path.join(work, "run")
    pc2 = os.path.join(run, "skin.pc2")
    usd = os.path.join(run, "skin.usda")
    if not (os.path.isfile(pc2) and os.path.isfile(usd)):
        raise cli.CliError(f"no animation files in {run}: Simulate first (or wait for it to finish)")
    rate = cache_rate(run) or run_meta["frame_rate"]
    scene = context.scene
    scale = rate / (common.scene_fps(scene) * run_meta["slow_motion"])
    start = run_meta["frame_start"]
    clear(context, obj)
    to_local = local_matrix(meta)
    frames, pc2_start, pc2_rate = read_pc2(pc2)
    if frames.shape[1] != meta["vertices"]:
        raise cli.CliError(f"{pc2} has {frames.shape[1]} vertices; the head was exported with {meta['vertices']}")
    parts = []
    if s.playback == "PC2":
        path = pc2
        if to_local is not None:
            m = np.array(to_local, dtype=np.float64)
            local = frames.astype(np.float64) @ m[:3, :3].T + m[:3, 3]
            path = os.path.join(run, "skin_local.pc2")
            write_pc2(path, local, pc2_start, pc2_rate)
        mod = obj.modifiers.new(common.MODIFIER, "MESH_CACHE")
        mod.cache_format = "PC2"
        mod.filepath = path
        mod.forward_axis = "POS_Y"
        mod.up_axis = "POS_Z"
        mod.interpolation = "LINEAR"
        mod.time_mode = "FRAME"
        mod.play_mode = "SCENE"
        mod.deform_mode = "OVERWRITE"
        # Blender reads cache frame (scene frame * frame_scale - frame_start)
        mod.frame_scale = scale
        mod.frame_start = start * scale
        parts.append(f"Mesh Cache {os.path.basename(path)} on {obj.name}")
    else:
        skin = _import_usd_prim(context, usd, "/sticky_lips/skin", obj.name + common.USD_SKIN_SUFFIX)
        _place(skin, obj, meta)
        _time_map(skin, start, scale)
        for mat in obj.data.materials:
            skin.data.materials.append(mat)
        obj["sticky_lips_hidden"] = True
        obj.hide_set(True)
        obj.hide_render = True
        parts.append(f"skin.usda as {skin.name} ({obj.name} hidden)")
    with open(usd, encoding="utf-8") as f:
        has_saliva = 'def Mesh "saliva"' in f.read()
    if has_saliva:
        sal = _import_usd_prim(context, usd, "/sticky_lips/saliva", obj.name + common.SALIVA_SUFFIX)
        _place(sal, obj, meta)
        _time_map(sal, start, scale)
        sal.data.materials.clear()
        sal.data.materials.append(_material("Sticky Lips saliva", (0.3, 0.6, 1.0, 1.0)))
        sal.data.materials.append(_material("Sticky Lips broken saliva", (0.9, 0.1, 0.1, 1.0)))
        mod = sal.modifiers.new(common.MODIFIER, "NODES")
        mod.node_group = saliva_node_group()
        _set_hide(mod, s.saliva_display == "HIDE")
        parts.append(f"saliva layer {sal.name}")
    obj["sticky_lips_run"] = run
    # the importer made its objects active and selected: the head is the one to work on
    for o in context.view_layer.objects.selected:
        o.select_set(False)
    if obj.visible_get():
        obj.select_set(True)
    context.view_layer.objects.active = obj
    return f"{'; '.join(parts)}; {frames.shape[0]} frames at {rate:g} per simulated second, scene frame {start} = frame 0"


def _place(ob, head, meta):
    """A USD object (the exported head's coordinates) under the head, where the head was
    when it was exported: it follows the head if the head moves later."""
    for coll in list(ob.users_collection):
        coll.objects.unlink(ob)
    for coll in head.users_collection:
        coll.objects.link(ob)
    k = meta["obj_per_blender_unit"]
    ob.parent = head
    ob.matrix_parent_inverse = Matrix(meta["matrix_world"]).inverted()
    ob.matrix_basis = Matrix.Scale(1.0 / k, 4)


class STICKY_LIPS_OT_load_result(bpy.types.Operator):
    """Play the run on the head (Mesh Cache modifier) with its saliva layer; replaces a loaded result"""

    bl_idname = "sticky_lips.load_result"
    bl_label = "Load result"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.active_object is not None

    def execute(self, context):
        from . import simulate

        try:
            obj = common.head_of(context)
            if simulate.running():
                raise cli.CliError("a simulation is running: wait for it or cancel it")
            line = load(context, obj)
        except cli.CliError as e:
            self.report({"ERROR"}, f"Load result: {e}")
            return {"CANCELLED"}
        context.window_manager.sticky_lips_status = "loaded: " + line
        self.report({"INFO"}, f"Load result: {line}")
        return {"FINISHED"}


class STICKY_LIPS_OT_clear_result(bpy.types.Operator):
    """Remove the loaded result (modifier, saliva object) from the head"""

    bl_idname = "sticky_lips.clear_result"
    bl_label = "Clear result"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.active_object is not None

    def execute(self, context):
        try:
            clear(context, common.head_of(context))
        except cli.CliError as e:
            self.report({"ERROR"}, f"Clear result: {e}")
            return {"CANCELLED"}
        return {"FINISHED"}


classes = (STICKY_LIPS_OT_load_result, STICKY_LIPS_OT_clear_result)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
