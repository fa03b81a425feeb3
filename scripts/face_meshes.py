"""Test meshes for `sticky-lips face`, derived from the MakeHuman head.

    python scripts/face_meshes.py HEAD_DIR OUT_DIR

HEAD_DIR holds head.obj and rig.json as `scripts/makehuman_face.py --head HEAD_DIR` writes
them (decimetres, y up, z forward). Writes OUT_DIR/NAME/{head.obj, rig.json, args} for each
variant below; `args` is the command line `sticky-lips face` needs for it (units and axes).
Every variant keeps only the vertices the head's faces use (the hm08 OBJ lists the body's).

  mm_zup   the head in millimetres with Blender's axes: z up, -y forward (x unchanged), the
           rig's hinge and blend shapes moved with it; vertex order and faces unchanged;
  cm_xfwd  in centimetres, z up, +x forward (a rotation of the axes), its unit not given:
           `face` detects it from the head's size;
  mm_zup_norig  mm_zup without its rig (no rig.json): `face` estimates the jaw.
"""

import json
import os
import sys


def compact(text, rig):
    """The head without the vertices no face uses (the hm08 OBJ lists the whole body's), as
    a user's own mesh would be: vertices renumbered in their order, texture coordinates
    alike, the rig's per-vertex arrays taken along."""
    lines = text.splitlines()
    verts = [ln for ln in lines if ln.startswith("v ")]
    uvs = [ln for ln in lines if ln.startswith("vt ")]
    faces = [ln for ln in lines if ln.startswith("f ")]
    used_v, used_t = set(), set()
    for f in faces:
        for c in f.split()[1:]:
            parts = c.split("/")
            used_v.add(int(parts[0]) - 1)
            if len(parts) > 1 and parts[1]:
                used_t.add(int(parts[1]) - 1)
    keep_v = sorted(used_v)
    keep_t = sorted(used_t)
    new_v = {o: i + 1 for i, o in enumerate(keep_v)}
    new_t = {o: i + 1 for i, o in enumerate(keep_t)}
    out = [verts[i] for i in keep_v] + [uvs[i] for i in keep_t]
    for f in faces:
        cs = []
        for c in f.split()[1:]:
            parts = c.split("/")
            v = str(new_v[int(parts[0]) - 1])
            cs.append(v + ("/" + str(new_t[int(parts[1]) - 1]) if len(parts) > 1 and parts[1] else ""))
        out.append("f " + " ".join(cs))
    r = dict(rig)
    if r.get("jaw_weight") is not None:
        r["jaw_weight"] = [rig["jaw_weight"][i] for i in keep_v]
    r["targets"] = {k: [t[i] for i in keep_v] for k, t in rig.get("targets", {}).items()}
    return "\n".join(out) + "\n", r


def transform_obj(text, f):
    out = []
    for line in text.splitlines():
        if line.startswith("v "):
            x = [float(t) for t in line.split()[1:4]]
            out.append("v " + " ".join(repr(c) for c in f(x)))
        else:
            out.append(line)
    return "\n".join(out) + "\n"


def mm_zup(p):
    # dm -> mm; model (x, y up, z forward) -> (x, -z, y): up +z, forward -y
    x, y, z = p
    return [100.0 * x, -100.0 * z, 100.0 * y]


def rot_zup(v):
    x, y, z = v
    return [x, -z, y]


def cm_xfwd(p):
    # dm -> cm; model (x left, y up, z forward) -> (z, x, y): forward +x, up +z, left +y
    x, y, z = p
    return [10.0 * z, 10.0 * x, 10.0 * y]


def rot_xfwd(v):
    x, y, z = v
    return [z, x, y]


VARIANTS = {
    "mm_zup": (mm_zup, lambda v: [100.0 * c for c in rot_zup(v)], rot_zup,
               ["--units", "mm", "--up", "0,0,1", "--forward", "0,-1,0"]),
    # no --units: `face` finds centimetres from the head's size
    "cm_xfwd": (cm_xfwd, lambda v: [10.0 * c for c in rot_xfwd(v)], rot_xfwd,
                ["--up", "0,0,1", "--forward", "1,0,0"]),
    # no rig: `face` estimates the jaw's weights and hinge (written without rig.json)
    "mm_zup_norig": (mm_zup, lambda v: [100.0 * c for c in rot_zup(v)], rot_zup,
                     ["--units", "mm", "--up", "0,0,1", "--forward", "0,-1,0"]),
}


def main(head_dir, out_dir):
    head, rig = compact(open(os.path.join(head_dir, "head.obj")).read(),
                        json.load(open(os.path.join(head_dir, "rig.json"))))
    for name, (point, offset, axis, args) in VARIANTS.items():
        d = os.path.join(out_dir, name)
        os.makedirs(d, exist_ok=True)
        with open(os.path.join(d, "head.obj"), "w") as f:
            f.write(transform_obj(head, point))
        r = dict(rig)
        if r.get("hinge_point") is not None:
            r["hinge_point"] = point(r["hinge_point"])
        if r.get("hinge_axis") is not None:
            r["hinge_axis"] = axis(r["hinge_axis"])
        r["targets"] = {k: [offset(v) for v in t] for k, t in rig.get("targets", {}).items()}
        if not name.endswith("_norig"):
            with open(os.path.join(d, "rig.json"), "w") as f:
                json.dump(r, f)
        with open(os.path.join(d, "args"), "w") as f:
            f.write(" ".join(args) + "\n")
        print(f"{d}: {' '.join(args)}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
