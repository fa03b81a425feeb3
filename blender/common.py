"""What the steps share: the work directory of an object, the executable, reports."""

import json
import os
import re
import sys
import tempfile

import bpy

from . import cli

# the names the add-on gives what it adds to a scene
MODIFIER = "Sticky Lips"
SALIVA_SUFFIX = ".sticky_lips_saliva"
MODEL_SUFFIX = ".sticky_lips_model"
USD_SKIN_SUFFIX = ".sticky_lips_usd"
NODE_GROUP = "Sticky Lips saliva"


def prefs(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def executable(context):
    p = prefs(context)
    return cli.find(bpy.path.abspath(p.executable) if p and p.executable else "")


def work_dir(context, obj):
    """The object's work directory (made if missing)."""
    s = context.scene.sticky_lips
    base = s.directory
    if base:
        base = bpy.path.abspath(base)
    elif bpy.data.filepath:
        base = os.path.join(os.path.dirname(bpy.data.filepath), "sticky_lips")
    else:
        base = os.path.join(tempfile.gettempdir(), "sticky_lips")
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", obj.name).strip("._") or "object"
    d = os.path.join(base, name)
    os.makedirs(d, exist_ok=True)
    return d


def read_json(path, hint):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except FileNotFoundError:
        raise cli.CliError(f"{path} is missing ({hint})")
    except ValueError as e:
        raise cli.CliError(f"{path} is not valid JSON ({e})")


def head_of(context):
    """The head the steps work on: the active object, or the head whose preview, saliva or
    USD object is active."""
    obj = context.active_object
    if obj is None:
        raise cli.CliError("select the head: there is no active object")
    for suffix in (MODEL_SUFFIX, SALIVA_SUFFIX, USD_SKIN_SUFFIX):
        if obj.name.endswith(suffix):
            head = bpy.data.objects.get(obj.name[: -len(suffix)])
            if head is not None:
                return head
    if obj.type != "MESH":
        raise cli.CliError(f"select the head: the active object {obj.name} is not a mesh")
    return obj


def write_json(path, data):
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1)
    os.replace(tmp, path)


def scene_fps(scene):
    return scene.render.fps / scene.render.fps_base


def report(kind, message):
    """A report from outside an operator (the job's timer): through a small operator in the
    first window, so that it reaches the status bar and the Info editor; printed on stderr
    where there is no window (background mode)."""
    wm = bpy.context.window_manager
    for win in wm.windows:
        try:
            with bpy.context.temp_override(window=win):
                bpy.ops.sticky_lips.report("EXEC_DEFAULT", kind=kind, message=message)
        except RuntimeError:
            pass  # an ERROR report raises here once it has been shown
        return
    print(f"Sticky Lips: {kind.lower()}: {message}", file=sys.stderr)


class STICKY_LIPS_OT_report(bpy.types.Operator):
    """Shows a message of a background job"""

    bl_idname = "sticky_lips.report"
    bl_label = "Sticky Lips report"
    bl_options = {"INTERNAL"}

    kind: bpy.props.EnumProperty(items=[("INFO", "Info", ""), ("WARNING", "Warning", ""), ("ERROR", "Error", "")])
    message: bpy.props.StringProperty()

    def execute(self, context):
        self.report({self.kind}, self.message)
        return {"FINISHED"}


def tag_redraw():
    wm = bpy.context.window_manager
    for win in wm.windows:
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()
