"""The scenario the add-on runs: the one `sticky-lips face` wrote, with the panel's settings.

No bpy here: the settings come in as plain values, so that this module can be tested and
read without Blender.
"""

import json
import math
import re

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11 (Blender 4.2 ships 3.11: not expected)
    tomllib = None

ZONES = ("left", "centre", "right")

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def read(path):
    """The TOML file at `path` as a dict."""
    with open(path, "rb") as f:
        return tomllib.load(f)


def _key(k):
    return k if _BARE_KEY.match(k) else json.dumps(k)


def _value(v, where):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"{where}: {v} is not a number TOML can hold")
        return repr(v)
    if isinstance(v, str):
        # JSON's escapes are TOML basic-string escapes
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x, where) for x in v) + "]"
    raise TypeError(f"{where}: cannot write {type(v).__name__} as a TOML value")


def _is_table_array(v):
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def dumps(doc, _path=()):
    """`doc` (nested dicts, lists, numbers, strings) as TOML text: the values of a table
    first, then its sub-tables, then its arrays of tables."""
    out = []
    plain = {k: v for k, v in doc.items() if not isinstance(v, dict) and not _is_table_array(v)}
    for k, v in plain.items():
        out.append(f"{_key(k)} = {_value(v, '.'.join(_path + (k,)))}")
    for k, v in doc.items():
        if isinstance(v, dict):
            name = ".".join(_key(p) for p in _path + (k,))
            out.append("")
            out.append(f"[{name}]")
            body = dumps(v, _path + (k,))
            if body:
                out.append(body)
    for k, v in doc.items():
        if _is_table_array(v):
            name = ".".join(_key(p) for p in _path + (k,))
            for item in v:
                out.append("")
                out.append(f"[[{name}]]")
                body = dumps(item, _path + (k,))
                if body:
                    out.append(body)
    return "\n".join(out).strip("\n")


def for_blender(face, s):
    """The scenario for a run from Blender, from `face` (the dict of the `scenario.toml`
    that `sticky-lips face` wrote) and the settings `s`:

    * `title`;
    * `resolution`: the model's (`[mesh.face] resolution`);
    * `duration`: simulated seconds (`[time] total`);
    * `frame_rate`: frames written per simulated second (`[time] output_interval` is its
      inverse; the step is `"auto"`, a whole number of steps per frame);
    * `jaw`: `{"angle": rad, "open_time": s}` (a smooth opening from the start) or
      `{"keys": [[frame, rad], ...], "keys_fps": frames per simulated second}`;
    * `zones`: `{"left": (k_glue, moisture_um), "centre": ..., "right": ...}`: each third of
      the mouth gets a saliva material of its own (element sets `saliva_left`, ...).

    The face's saliva material and `[[saliva]]` table are the template of the three zones'.
    With the step `"auto"`, eq. 11's decay is given in seconds (the default: Table 1's), so a
    `decay_per_step` of the template is dropped.
    """
    doc = json.loads(json.dumps(face))  # a deep copy of plain data
    doc["title"] = s["title"]
    saliva = doc.get("saliva") or []
    if len(saliva) != 1:
        raise ValueError(f"the face's scenario has {len(saliva)} [[saliva]] tables; expected one")
    template = saliva[0]
    mats = doc.get("materials") or []
    try:
        sal_mat = next(m for m in mats if m.get("name") == template.get("material"))
    except StopIteration:
        raise ValueError(f"the face's scenario has no material `{template.get('material')}`")
    others = [m for m in mats if m is not sal_mat]
    zone_mats, zone_saliva = [], []
    for z in ZONES:
        k_glue, moisture = s["zones"][z]
        m = dict(sal_mat)
        m["name"] = f"saliva_{z}"
        m["elements"] = f"saliva_{z}"
        zone_mats.append(m)
        t = {k: v for k, v in template.items() if k not in ("decay_per_step", "decay_time")}
        t["material"] = m["name"]
        t["k_glue"] = float(k_glue)
        t["initial_moisture"] = float(moisture)
        zone_saliva.append(t)
    doc["materials"] = others + zone_mats
    doc["saliva"] = zone_saliva
    doc.setdefault("mesh", {}).setdefault("face", {})["resolution"] = float(s["resolution"])
    jaw = s["jaw"]
    if "keys" in jaw:
        keys = [[float(t), float(a)] for t, a in jaw["keys"]]
        if not keys:
            raise ValueError("the jaw has no keys")
        doc["jaw"] = {"keys": keys, "keys_fps": float(jaw["keys_fps"])}
    else:
        doc["jaw"] = {
            "angle": float(jaw["angle"]),
            "duration": float(jaw["open_time"]),
            "shape": "smooth_step",
        }
    if not s["duration"] > 0.0:
        raise ValueError(f"the duration must be positive (got {s['duration']} s)")
    if not s["frame_rate"] > 0.0:
        raise ValueError(f"the frame rate must be positive (got {s['frame_rate']})")
    doc["time"] = {
        "dt": "auto",
        "total": float(s["duration"]),
        "output_interval": 1.0 / float(s["frame_rate"]),
    }
    return doc
