"""Real clients read a sticky-lips run's animation files (src/export.rs).

Usage:
    STICKY_LIPS_ANIM_OUT=RUN_DIR[:RUN_DIR...] [STICKY_LIPS_BIN=sticky-lips] pytest scripts/check_animation.py

For every run directory, at every frame of frames.pvd:
  * the skin's positions in skin.pc2 and skin.mdd (parsed here from their documented
    layouts; the MDD's frame times are the frames' times) are the run's frames mapped onto
    the user's mesh: the displacements of each frame's VTU (read with meshio), carried to the
    mesh's vertices by the skin mapping that `sticky-lips export RUN --skin-map` writes
    (bilinear weights on four model nodes, the jaw's rigid rotation for the vertices beside
    the model, the user's units and axes), computed here in NumPy, to 1e-6 m;
  * usd-core (PyPI, Pixar's USD) opens skin.usda: one time sample per frame, the stage's
    time codes per second equal to the frames' rate, the points at every time code the
    PC2's; the saliva mesh's per-face primvars `broken` and `moisture` equal the frames'
    `saliva_broken` and `saliva_moisture` cell data, and the broken count at the last frame
    the summary's;
  * Blender (PyPI `bpy`, headless, in its own process: scripts/blender_read_caches.py)
    imports skin.obj with a Mesh Cache modifier on skin.pc2, again with one on skin.mdd, and
    skin.usda with its USD importer; all three give the PC2's positions to 1e-6 m at every
    frame, and the imported rest mesh is skin.obj's;
  * where the skin is the model's own surface (the procedural mouth: summary
    export.json's `skin_is_model`), the PC2's positions are the frame's VTU points to 1e-6 m;
  * where the run directory holds `input.obj` (the user's mesh the face was made from, as
    the test command copies it), skin.obj's vertices are its vertices, in its order and
    units, to 1e-6 of its size;
  * where the run measured the lips, they unzip as claimed (the first column to open within
    0.2 of the half-width w of the centre, every column open at the end, Spearman rank
    correlation of opening time with |x| at least 0.6: the paper's claims C2 and C4).
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest
from pxr import Usd, UsdGeom

TOL_M = 1e-6
HERE = Path(__file__).resolve().parent


def sticky_lips_bin():
    b = os.environ.get("STICKY_LIPS_BIN") or str(HERE.parent / "target" / "debug" / "sticky-lips")
    if not Path(b).is_file():
        pytest.fail(f"no sticky-lips binary at {b} (set STICKY_LIPS_BIN)")
    return b


def rotation(axis, angle):
    """Rodrigues' rotation matrix (src/linalg.rs rotation_matrix)."""
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    t = 1.0 - c
    return np.array([[c + x * x * t, x * y * t - z * s, x * z * t + y * s],
                     [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
                     [z * x * t - y * s, z * y * t + x * s, c + z * z * t]])


def skin_positions(m, u, k):
    """The skin's vertices (user's units and axes) for nodal displacements `u` (m) at frame `k`
    of the skin map `m` (src/mesh/skin.rs Skin::positions, written again here)."""
    rest = np.asarray(m["rest"], dtype=np.float64)
    nodes = np.asarray(m["nodes"], dtype=np.int64)
    w = np.asarray(m["w"], dtype=np.float64)
    f = np.asarray(m["f"], dtype=np.float64)
    d = f[:, None] * np.einsum("vi,vik->vk", w, u[nodes])
    d[f <= 0.0] = 0.0
    if m["jaw_point"] is not None:
        g = (1.0 - f) * np.asarray(m["jaw"], dtype=np.float64)
        p = np.asarray(m["jaw_point"])
        r = rotation(m["jaw_axis"], m["jaw_angles"][k])
        rel = rest - p
        dj = rel @ r.T - rel
        d += np.where(g[:, None] > 0.0, g[:, None] * dj, 0.0)
    rows = np.asarray(m["rows"], dtype=np.float64)
    return (rest + d) @ rows / m["scale"]


def run_dirs():
    env = os.environ.get("STICKY_LIPS_ANIM_OUT", "")
    return [Path(p) for p in env.split(":") if p]


def frames_of(d: Path):
    root = ET.parse(d / "frames.pvd").getroot()
    return [(float(e.get("timestep")), e.get("file")) for e in root.iter("DataSet")]


def read_pc2(path: Path):
    b = path.read_bytes()
    assert b[:12] == b"POINTCACHE2\0"
    version, n, start, rate, samples = struct.unpack("<iiffi", b[12:32])
    assert (version, start, rate) == (1, 0.0, 1.0)
    data = np.frombuffer(b, dtype="<f4", offset=32)
    assert data.size == samples * n * 3
    return data.reshape(samples, n, 3).astype(np.float64)


def read_mdd(path: Path):
    b = path.read_bytes()
    frames, n = struct.unpack(">ii", b[:8])
    times = np.frombuffer(b, dtype=">f4", count=frames, offset=8).astype(np.float64)
    data = np.frombuffer(b, dtype=">f4", offset=8 + 4 * frames)
    assert data.size == frames * n * 3
    return times, data.reshape(frames, n, 3).astype(np.float64)


def read_obj_vertices(path: Path):
    return np.array([[float(x) for x in line.split()[1:4]]
                     for line in path.read_text().splitlines() if line.startswith("v ")])


@pytest.fixture(scope="module", params=run_dirs() or [None], ids=lambda p: str(p))
def run(request):
    if request.param is None:
        pytest.skip("STICKY_LIPS_ANIM_OUT is not set")
    d = request.param
    summary = json.loads((d / "summary.json").read_text())
    summary["export"] = json.loads((d / "export.json").read_text())
    return d, summary


def test_usd_core_reads_the_time_samples_of_every_frame(run):
    d, summary = run
    frames = frames_of(d)
    pc2 = read_pc2(d / "skin.pc2")
    times, mdd = read_mdd(d / "skin.mdd")
    assert pc2.shape[0] == len(frames) == summary["export"]["frames"]
    np.testing.assert_array_equal(pc2, mdd)
    np.testing.assert_allclose(times, [t for t, _ in frames], rtol=1e-6)
    stage = Usd.Stage.Open(str(d / "skin.usda"))
    assert stage, "usd-core could not open skin.usda"
    mpu = UsdGeom.GetStageMetersPerUnit(stage)
    assert stage.GetStartTimeCode() == 0 and stage.GetEndTimeCode() == len(frames) - 1
    fps = stage.GetTimeCodesPerSecond()
    if len(frames) > 1:
        span = frames[-1][0] - frames[0][0]
        assert abs(fps * span - (len(frames) - 1)) < 1e-6 * len(frames)
    skin = UsdGeom.Mesh(stage.GetPrimAtPath("/sticky_lips/skin"))
    pts = skin.GetPointsAttr()
    assert pts.GetNumTimeSamples() == len(frames)
    rest = np.array(pts.Get(), dtype=np.float64)
    np.testing.assert_array_equal(rest, read_obj_vertices(d / "skin.obj").astype(np.float32))
    for k in range(len(frames)):
        got = np.array(pts.Get(Usd.TimeCode(k)), dtype=np.float64)
        assert np.max(np.abs(got - pc2[k])) * mpu <= TOL_M, f"time code {k}"
    # the user's own faces (triangles, quads, ...), corner for corner as skin.obj has them
    faces = [[int(c.split("/")[0]) - 1 for c in line.split()[1:]]
             for line in (d / "skin.obj").read_text().splitlines() if line.startswith("f ")]
    assert list(skin.GetFaceVertexCountsAttr().Get()) == [len(f) for f in faces]
    assert list(skin.GetFaceVertexIndicesAttr().Get()) == [v for f in faces for v in f]


def test_usd_saliva_state_is_the_frames(run):
    d, summary = run
    stage = Usd.Stage.Open(str(d / "skin.usda"))
    prim = stage.GetPrimAtPath("/sticky_lips/saliva")
    if summary["saliva_elements"] == 0:
        assert not prim
        return
    mesh = UsdGeom.Mesh(prim)
    broken = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("broken")
    assert broken.GetInterpolation() == UsdGeom.Tokens.uniform
    frames = frames_of(d)
    n_faces = len(mesh.GetFaceVertexCountsAttr().Get())
    assert n_faces == summary["saliva_elements"] == summary["export"]["saliva_faces"]
    moisture = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("moisture")
    assert moisture.GetInterpolation() == UsdGeom.Tokens.uniform
    for k in range(len(frames)):
        cd = meshio.read(d / frames[k][1]).cell_data
        cells = cd["saliva_broken"][0]
        saliva = cells >= 0
        want = cells[saliva].astype(np.float64)
        got = np.array(broken.Get(Usd.TimeCode(k)), dtype=np.float64)
        np.testing.assert_array_equal(got, want, err_msg=f"broken, frame {k}")
        want_m = cd["saliva_moisture"][0][saliva].astype(np.float32)
        got_m = np.array(moisture.Get(Usd.TimeCode(k)), dtype=np.float32)
        np.testing.assert_array_equal(got_m, want_m, err_msg=f"moisture, frame {k}")
    assert int(np.sum(broken.Get(Usd.TimeCode(len(frames) - 1)))) == summary["broken_saliva"][-1]


def test_every_frame_is_the_run_through_the_skin_map(run, tmp_path):
    d, _ = run
    path = tmp_path / "skin_map.json"
    subprocess.run([sticky_lips_bin(), "export", str(d), "--skin-map", str(path)],
                   check=True, stdout=subprocess.DEVNULL)
    m = json.loads(path.read_text())
    frames = frames_of(d)
    assert m["times"] == [t for t, _ in frames]
    pc2 = read_pc2(d / "skin.pc2")
    _, mdd = read_mdd(d / "skin.mdd")
    assert pc2.shape[0] == len(frames) and pc2.shape[1] == len(m["rest"])
    mpu = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001, "in": 0.0254}[m["unit"]]
    assert abs(mpu - m["scale"]) <= 1e-12 * mpu
    moved = 0.0
    for k, (_, file) in enumerate(frames):
        u = np.asarray(meshio.read(d / file).point_data["displacement"], dtype=np.float64)
        want = skin_positions(m, u, k)
        for name, got in (("pc2", pc2[k]), ("mdd", mdd[k])):
            err = np.max(np.abs(got - want)) * mpu
            assert err <= TOL_M, f"{name} frame {k} ({file}): {err:.3e} m from the frame"
        moved = max(moved, np.max(np.abs(want - skin_positions(m, np.zeros_like(u), 0))) * mpu)
    # the frames move the skin: the check compares motion, not the rest state with itself
    assert moved > 1e-3, f"the skin moves by at most {moved:.3e} m"


def test_blender_plays_the_pc2_the_mdd_and_the_usd(run, tmp_path):
    d, _ = run
    pc2 = read_pc2(d / "skin.pc2")
    out = tmp_path / "blender.npz"
    subprocess.run([sys.executable, str(HERE / "blender_read_caches.py"), str(d), str(out)],
                   check=True, stdout=subprocess.DEVNULL)
    b = np.load(out)
    info = json.loads(str(b["info"]))
    stage = Usd.Stage.Open(str(d / "skin.usda"))
    mpu = UsdGeom.GetStageMetersPerUnit(stage)
    rest = read_obj_vertices(d / "skin.obj")
    assert np.max(np.abs(b["rest"] - rest)) * mpu <= TOL_M
    assert info["frames"] == pc2.shape[0]
    for name in ("pc2", "mdd", "usd"):
        got = b[name]
        assert got.shape == pc2.shape, name
        err = np.max(np.abs(got - pc2), axis=(1, 2)) * mpu
        k = int(np.argmax(err))
        assert err[k] <= TOL_M, f"Blender {info['blender']} {name} at frame {k}: {err[k]:.3e} m"
    # the frames are not the rest state: the check compares motion, not copies of the rest
    assert np.max(np.abs(pc2[-1] - pc2[0])) * mpu > 1e-4


def test_a_skin_that_is_the_model_surface_follows_the_frames(run):
    d, summary = run
    if not summary["export"]["skin_is_model"]:
        pytest.skip("the skin is not the model's own surface")
    pc2 = read_pc2(d / "skin.pc2")
    frames = frames_of(d)
    for k in range(len(frames)):
        pts = meshio.read(d / frames[k][1]).points
        n = pc2.shape[1]
        assert np.max(np.abs(pc2[k] - pts[:n])) <= TOL_M, f"frame {k}"


def test_the_jaw_opening_unzips_the_lips(run):
    """Where the run measured the lips (mouth and face models), with the zip front the paper's
    claims use (src/measures.rs ZipFront, scripts/face_meshes.py zip_times): the first column
    to open lies within 0.2 of the half-width w of the centre (claim C2), the Spearman rank
    correlation of opening time with |x| is at least 0.6 (C4), and every column is open at the
    end. Printed with -s. Skipped, after printing, where the run holds `unzips_off_centre`
    (runs measured not to: the file says what was measured)."""
    sys.path.insert(0, str(HERE))
    from face_meshes import FIRST_OPENING_MAX, zip_times
    d, _ = run
    if not (d / "measures.json").exists():
        pytest.skip("no lip measures")
    m = json.loads((d / "measures.json").read_text())
    first, rho, n_open, n = zip_times(m)
    print(f"{d}: first opening at "
          + (f"t = {first[0]:.3f} s, |x - c| = {first[1]:.2f} w" if first else "none")
          + f"; Spearman(|x|, t) = {rho}; columns open at the end {n_open}/{n}")
    if (d / "unzips_off_centre").exists():
        pytest.skip("known not to unzip from the centre: "
                    + (d / "unzips_off_centre").read_text().strip())
    assert first is not None and first[1] <= FIRST_OPENING_MAX + 1e-9, first
    assert rho is not None and rho >= 0.6, rho
    assert n_open == n and m["frames"][-1]["open_fraction"] > 0.99


def test_the_rest_mesh_is_the_users_mesh(run):
    d, _ = run
    if not (d / "input.obj").exists():
        pytest.skip("no input.obj in the run directory")
    want = read_obj_vertices(d / "input.obj")
    got = read_obj_vertices(d / "skin.obj")
    assert got.shape == want.shape
    size = np.max(np.abs(want))
    assert np.max(np.abs(got - want)) <= 1e-6 * size


if __name__ == "__main__":
    if len(sys.argv) > 1:
        os.environ["STICKY_LIPS_ANIM_OUT"] = ":".join(sys.argv[1:])
    sys.exit(pytest.main([__file__, "-q"]))
