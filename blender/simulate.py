"""Simulate: `sticky-lips run --progress json` in a separate process, polled from a timer.

Blender stays usable while it runs: `poll` (registered with `bpy.app.timers`) reads the
JSON lines that arrived, shows the progress (the window manager's progress indicator, the
panel's bar and status line) and, once the process has exited, reports how it ended. Cancel
sends SIGINT: the run stops between two steps keeping its complete frames, and `sticky-lips
export` then writes the animation files of that partial run, so that Load result plays it.
"""

import atexit
import math
import os
import shutil

import bpy

from . import build, cli, common, result, scenario

POLL_SECONDS = 0.25

# the one job at a time: a dict (see `_start`) or None
JOB = None


def running():
    return JOB is not None


def jaw_keys(context, meta, s, fps_sim):
    """The jaw bone's rotation about its hinge at every scene frame from the scene's start
    to the end of the simulated time: `[[frame - start, rad], ...]`."""
    scene = context.scene
    arm = scene.objects.get(meta["armature"] or "")
    if arm is None or not meta["jaw_bone"]:
        raise cli.CliError(
            "Jaw bone keys: the model was built without a jaw bone (none found on the head's armature)"
        )
    if not (arm.animation_data and arm.animation_data.action):
        raise cli.CliError(f"Jaw bone keys: the armature {arm.name} has no action (no keys)")
    pb = arm.pose.bones.get(meta["jaw_bone"])
    if pb is None:
        raise cli.CliError(f"Jaw bone keys: the armature {arm.name} has no bone {meta['jaw_bone']} any more")
    start = scene.frame_start
    last = start + math.ceil(s.duration * fps_sim - 1e-9)
    keep = scene.frame_current, scene.frame_subframe
    keys = []
    try:
        for f in range(start, last + 1):
            scene.frame_set(f)
            keys.append([float(f - start), build.jaw_angle(pb, meta["jaw_sign"])])
    finally:
        scene.frame_set(keep[0], subframe=keep[1])
    return keys


def write_scenario(context, obj, work):
    """`model/blender.toml` from the face's scenario and the panel; returns its path and what
    Load result needs to map the cache to scene frames."""
    s = context.scene.sticky_lips
    meta = common.read_json(os.path.join(work, "blender.json"), "Build model first")
    model = os.path.join(work, "model")
    face_toml = os.path.join(model, "scenario.toml")
    if not os.path.isfile(face_toml):
        raise cli.CliError(f"no model of {obj.name}: Build model first")
    fps_sim = common.scene_fps(context.scene) * s.slow_motion
    if s.jaw_source == "BONE":
        jaw = {"keys": jaw_keys(context, meta, s, fps_sim), "keys_fps": fps_sim}
    else:
        jaw = {"angle": s.jaw_angle, "open_time": s.jaw_open_time}
    settings = {
        "title": f"{obj.name} from Blender",
        "resolution": s.resolution,
        "duration": s.duration,
        "frame_rate": s.frame_rate,
        "jaw": jaw,
        "zones": {
            "left": (s.k_glue_left, s.moisture_left),
            "centre": (s.k_glue_centre, s.moisture_centre),
            "right": (s.k_glue_right, s.moisture_right),
        },
    }
    try:
        doc = scenario.for_blender(scenario.read(face_toml), settings)
        text = scenario.dumps(doc)
    except (ValueError, TypeError) as e:
        raise cli.CliError(str(e))
    path = os.path.join(model, "blender.toml")
    with open(path, "w", encoding="utf-8") as f:
        f.write(f"# written by the Sticky Lips add-on from scenario.toml (sticky-lips face) and its panel\n{text}\n")
    run_meta = {
        "frame_start": context.scene.frame_start,
        "slow_motion": s.slow_motion,
        "frame_rate": s.frame_rate,
        "scene_fps": common.scene_fps(context.scene),
    }
    return path, run_meta


def _status_bar(text):
    """`text` in the status bar of every window (None: Blender's own again)."""
    for win in bpy.context.window_manager.windows:
        try:
            win.workspace.status_text_set_internal(text)
        except (AttributeError, RuntimeError, TypeError):
            pass


def _set_progress(p, status=None):
    wm = bpy.context.window_manager
    wm.sticky_lips_progress = p
    if status is not None:
        wm.sticky_lips_status = status
    try:
        wm.progress_update(int(round(100 * p)))
    except RuntimeError:
        pass
    _status_bar(f"Sticky Lips: {100 * p:.0f} %  {wm.sticky_lips_status}")
    common.tag_redraw()


def _progress_text(ev):
    left = ev.get("seconds_left")
    eta = f", {left:.0f} s left" if isinstance(left, (int, float)) and math.isfinite(left) else ""
    return f"t = {ev['time']:.4f} of {ev['end_time']:.4f} s, {ev['frames']} frames{eta}"


def _finish(status, kind=None, message=None):
    global JOB
    JOB = None
    wm = bpy.context.window_manager
    wm.sticky_lips_status = status
    try:
        wm.progress_end()
    except RuntimeError:
        pass
    _status_bar(None)
    common.tag_redraw()
    if kind:
        common.report(kind, message or status)


def poll():
    """One look at the job (the timer's function): None once it is over, else the seconds
    until the next look."""
    global JOB
    job = JOB
    if job is None:
        return None
    p = job["process"]
    done = p.poll()
    if job["phase"] == "run":
        for ev in p.events[job["seen"]:]:
            if ev.get("event") == "progress" and ev.get("steps"):
                _set_progress(min(1.0, ev["step"] / ev["steps"]), _progress_text(ev))
        job["seen"] = len(p.events)
    if not done:
        return POLL_SECONDS
    last = p.last or {}
    if job["phase"] == "run":
        if p.returncode == 0 and last.get("event") == "finished":
            _finish(f"finished: {last.get('frames')} frames, {last.get('simulated_time'):.4f} s simulated in "
                    f"{last.get('wall_time'):.1f} s; Load result plays it", "INFO",
                    f"Simulate: {job['object']} finished ({last.get('frames')} frames)")
            return None
        if p.returncode == 130 or last.get("event") == "interrupted":
            # the frames written so far: their animation files, so that the run loads
            try:
                exe = job["exe"]
                JOB = dict(job, phase="export", process=cli.Job([exe, "export", job["run"]]),
                           interrupted=last)
            except cli.CliError as e:
                _finish(f"cancelled; export failed: {e}", "ERROR", f"Simulate: {e}")
                return None
            _set_progress(bpy.context.window_manager.sticky_lips_progress,
                          "cancelled: writing the animation files of the frames kept")
            return POLL_SECONDS
        msg = p.error_text()
        _finish(f"failed: {msg}", "ERROR", f"Simulate: {msg}")
        return None
    # the export of a cancelled run
    if p.returncode != 0:
        msg = p.error_text()
        _finish(f"cancelled; export failed: {msg}", "ERROR", f"Simulate (export of the cancelled run): {msg}")
        return None
    it = job.get("interrupted") or {}
    t = it.get("time")
    at = f" at t = {t:.4f} s" if isinstance(t, (int, float)) else ""
    _finish(f"cancelled{at}: the frames written so far are kept; Load result plays them", "WARNING",
            f"Simulate: {job['object']} cancelled{at}; the partial result is loadable")
    return None


def stop_all():
    """Unregistering: a running job is stopped (its process killed)."""
    global JOB
    if JOB is not None:
        JOB["process"].kill()
        JOB = None
    if bpy.app.timers.is_registered(poll):
        bpy.app.timers.unregister(poll)


@atexit.register
def _kill_at_exit():
    """Blender quits: the run it started does not go on without it."""
    if JOB is not None:
        JOB["process"].kill()


class STICKY_LIPS_OT_simulate(bpy.types.Operator):
    """Run the model in the background (sticky-lips run); Blender stays usable"""

    bl_idname = "sticky_lips.simulate"
    bl_label = "Simulate"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and not running()

    def execute(self, context):
        global JOB
        try:
            obj = common.head_of(context)
            exe = common.executable(context)
            work = common.work_dir(context, obj)
            path, run_meta = write_scenario(context, obj, work)
            # a re-run replaces the previous result
            result.clear(context, obj)
            run = os.path.join(work, "run")
            shutil.rmtree(run, ignore_errors=True)
            common.write_json(os.path.join(work, "run.json"), run_meta)
            proc = cli.Job([exe, "run", path, "--out", run, "--progress", "json"])
        except cli.CliError as e:
            self.report({"ERROR"}, f"Simulate: {e}")
            return {"CANCELLED"}
        JOB = {"process": proc, "phase": "run", "seen": 0, "object": obj.name, "run": run, "exe": exe}
        context.window_manager.progress_begin(0, 100)
        _set_progress(0.0, "starting")
        if not bpy.app.timers.is_registered(poll):
            # persistent: the run goes on when another file is opened, and so does its polling
            bpy.app.timers.register(poll, first_interval=POLL_SECONDS, persistent=True)
        self.report({"INFO"}, f"Simulate: {obj.name} running in the background")
        return {"FINISHED"}


class STICKY_LIPS_OT_cancel(bpy.types.Operator):
    """Stop the simulation, keeping the frames written so far (playable with Load result)"""

    bl_idname = "sticky_lips.cancel"
    bl_label = "Cancel"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return running() and JOB["phase"] == "run"

    def execute(self, context):
        JOB["process"].interrupt()
        context.window_manager.sticky_lips_status = "cancelling: the run stops after its current step"
        return {"FINISHED"}


classes = (STICKY_LIPS_OT_simulate, STICKY_LIPS_OT_cancel)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
