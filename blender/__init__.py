"""Sticky Lips for Blender: the active head made into a sticky-lips model, simulated by the
`sticky-lips` command line in a separate process, and played back on the head.

The panel is in the 3D view's sidebar (N), tab "Sticky Lips": Build model, Simulate (with
Cancel), Load result. Each step's files are in a work directory per object (the setting
Directory, by default `sticky_lips/` next to the blend file):

    OBJECT/head.obj, rig.json, blender.json   the head as exported (world space) and its rig
    OBJECT/model/                             what `sticky-lips face` wrote; blender.toml
    OBJECT/run/, run.json                     the run (frames, skin.pc2, skin.usda, ...) and
                                              the scene's frame and rate when it started
"""

import bpy

from . import build, common, result, simulate, ui


class StickyLipsPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    executable: bpy.props.StringProperty(
        name="sticky-lips executable",
        description="The sticky-lips command line program; empty: the one found on PATH",
        subtype="FILE_PATH",
        default="",
    )

    def draw(self, context):
        self.layout.prop(self, "executable")


def _k_glue(zone):
    return bpy.props.FloatProperty(
        name=f"K glue {zone}",
        description=f"Maximum glue strength K of eq. (7) in the {zone} third of the mouth (Table 1: 0.1)",
        default=0.1,
        min=0.0,
        soft_max=1.0,
    )


def _moisture(zone):
    return bpy.props.FloatProperty(
        name=f"Moisture {zone}",
        description=(
            f"Initial saliva moisture (um of film) in the {zone} third (Table 1: 100); the glue "
            "is strongest at the critical moisture (100 um) and gone above it"
        ),
        default=100.0,
        min=0.0,
        soft_max=150.0,
    )


class StickyLipsSettings(bpy.types.PropertyGroup):
    directory: bpy.props.StringProperty(
        name="Directory",
        description="Where the model and the runs are written (one folder per object); empty: "
        "sticky_lips next to the blend file, or the temporary directory for an unsaved file",
        subtype="DIR_PATH",
        default="",
    )
    resolution: bpy.props.FloatProperty(
        name="Resolution",
        description="The model's resolution (1: the paper's 3392 hexahedra; 0.25: a quick model of 864)",
        default=0.5,
        min=0.05,
        soft_min=0.25,
        soft_max=1.0,
    )
    duration: bpy.props.FloatProperty(
        name="Duration (s)",
        description="Simulated time, in seconds",
        default=0.6,
        min=0.001,
        soft_max=5.0,
    )
    frame_rate: bpy.props.FloatProperty(
        name="Cache rate (frames/s)",
        description="Frames written per simulated second",
        default=240.0,
        min=1.0,
        soft_max=2000.0,
    )
    slow_motion: bpy.props.FloatProperty(
        name="Slow motion",
        description="Scene seconds per simulated second (1: real time)",
        default=1.0,
        min=0.01,
        soft_max=20.0,
    )
    jaw_source: bpy.props.EnumProperty(
        name="Jaw",
        items=[
            ("VALUE", "Angle", "The jaw opens smoothly to an angle"),
            ("BONE", "Jaw bone keys", "The rotation keys of the armature's jaw bone, one key per scene frame"),
        ],
        default="VALUE",
    )
    jaw_angle: bpy.props.FloatProperty(
        name="Jaw angle",
        description="How far the jaw opens (positive opens)",
        subtype="ANGLE",
        default=0.15,
        soft_min=0.0,
        soft_max=0.5,
    )
    jaw_open_time: bpy.props.FloatProperty(
        name="Opening time (s)",
        description="Simulated seconds the jaw takes to open (smooth step from the start)",
        default=0.5,
        min=0.001,
    )
    jaw_bone: bpy.props.StringProperty(
        name="Jaw bone",
        description="The armature's jaw bone; empty: a bone named jaw (or with jaw in its name) "
        "that has a vertex group on the head",
        default="",
    )
    k_glue_left: _k_glue("left")
    k_glue_centre: _k_glue("centre")
    k_glue_right: _k_glue("right")
    moisture_left: _moisture("left")
    moisture_centre: _moisture("centre")
    moisture_right: _moisture("right")
    playback: bpy.props.EnumProperty(
        name="Play with",
        items=[
            ("PC2", "Mesh Cache (PC2)", "A Mesh Cache modifier on the head reads skin.pc2"),
            ("USD", "USD import", "skin.usda imported as an object of its own (the head is hidden)"),
        ],
        default="PC2",
    )
    saliva_display: bpy.props.EnumProperty(
        name="Broken saliva",
        items=[
            ("HIDE", "Hide", "Faces of broken saliva disappear"),
            ("COLOUR", "Colour", "Faces of broken saliva turn red"),
        ],
        default="HIDE",
        update=lambda self, context: result.update_saliva_display(context),
    )


classes = (StickyLipsPreferences, StickyLipsSettings, common.STICKY_LIPS_OT_report)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.sticky_lips = bpy.props.PointerProperty(type=StickyLipsSettings)
    # what a running job shows (not saved with the file)
    bpy.types.WindowManager.sticky_lips_progress = bpy.props.FloatProperty(
        name="Progress", min=0.0, max=1.0, subtype="FACTOR"
    )
    bpy.types.WindowManager.sticky_lips_status = bpy.props.StringProperty(name="Status")
    build.register()
    simulate.register()
    result.register()
    ui.register()


def unregister():
    simulate.stop_all()
    ui.unregister()
    result.unregister()
    simulate.unregister()
    build.unregister()
    del bpy.types.WindowManager.sticky_lips_status
    del bpy.types.WindowManager.sticky_lips_progress
    del bpy.types.Scene.sticky_lips
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
