"""The panel in the 3D view's sidebar (N), tab "Sticky Lips"."""

import bpy

from . import simulate


class STICKY_LIPS_PT_panel(bpy.types.Panel):
    bl_label = "Sticky Lips"
    bl_idname = "STICKY_LIPS_PT_panel"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Sticky Lips"

    def draw(self, context):
        layout = self.layout
        s = context.scene.sticky_lips
        wm = context.window_manager
        obj = context.active_object
        layout.label(text=f"Head: {obj.name}" if obj is not None and obj.type == "MESH" else "Select the head (a mesh)",
                     icon="MESH_DATA")

        box = layout.box()
        box.label(text="1. Model", icon="MOD_MESHDEFORM")
        box.prop(s, "resolution")
        box.prop(s, "jaw_bone")
        box.prop(s, "directory")
        box.operator("sticky_lips.build_model", icon="MESH_ICOSPHERE")

        box = layout.box()
        box.label(text="2. Simulate", icon="PHYSICS")
        box.prop(s, "duration")
        row = box.row(align=True)
        row.prop(s, "frame_rate")
        row.prop(s, "slow_motion")
        box.prop(s, "jaw_source", expand=True)
        if s.jaw_source == "VALUE":
            row = box.row(align=True)
            row.prop(s, "jaw_angle")
            row.prop(s, "jaw_open_time")
        col = box.column(align=True)
        col.label(text="Stickiness (K glue, moisture um)")
        for zone in ("right", "centre", "left"):
            row = col.row(align=True)
            row.label(text=zone.capitalize())
            row.prop(s, f"k_glue_{zone}", text="K")
            row.prop(s, f"moisture_{zone}", text="M")
        row = box.row(align=True)
        if simulate.running():
            row.operator("sticky_lips.cancel", icon="CANCEL")
        else:
            row.operator("sticky_lips.simulate", icon="PLAY")
        if simulate.running() or wm.sticky_lips_progress > 0.0:
            box.progress(factor=wm.sticky_lips_progress, type="BAR",
                         text=f"{100 * wm.sticky_lips_progress:.0f} %")

        box = layout.box()
        box.label(text="3. Result", icon="MOD_MESHDEFORM")
        box.prop(s, "playback")
        box.prop(s, "saliva_display")
        row = box.row(align=True)
        row.operator("sticky_lips.load_result", icon="IMPORT")
        row.operator("sticky_lips.clear_result", icon="X")

        if wm.sticky_lips_status:
            col = layout.column(align=True)
            for line in _wrap(wm.sticky_lips_status, 48):
                col.label(text=line)


def _wrap(text, width):
    words, line, out = text.split(), "", []
    for w in words:
        if line and len(line) + 1 + len(w) > width:
            out.append(line)
            line = w
        else:
            line = f"{line} {w}" if line else w
    if line:
        out.append(line)
    return out[:8]


classes = (STICKY_LIPS_PT_panel,)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
