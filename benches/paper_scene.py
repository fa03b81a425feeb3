#!/usr/bin/env python3
"""Whole-process timings of the paper's scene (issue 30's target).

The scene: `paper/scenarios/table1.toml` (the MakeHuman face at full resolution, 3392
hexahedra, 1 s simulated, Table 1's physics), eq. 11's decay in physical time (`--dt`
converts Table 1's 0.99 per 1e-5 s into its decay time). Configurations, run in turn in each
round (so that load from other processes hits all alike), each a whole `sticky-lips run`
process on 2 threads:

  reference   f64 at Table 1's dt = 1e-5 s
  auto-f64    f64 at dt = "auto" (0.8 of the critical step)
  auto-f32    f32 at dt = "auto"
  sub-f64     f64 at dt = "auto" with the saliva subcycled (--subcycles auto: the large
              step 0.8 of min(tissue's critical step, 2 x the whole model's), substeps for
              the saliva)
  sub-f32     the same in f32
  sub-f32-2frames  the same with a frame at the start and the end only (the scene's
              [time] output_every raised; what recording 101 frames costs)
  before      sub-f32 with another build (BEFORE=path/to/sticky-lips; left out without it)

For each: the median process wall time, the run's own wall time and stepping time
(summary.json: from reading the scenario to the last frame, and the steps alone), the
animation files' and preview's time (the run's own log), and against the reference's last
run: the largest difference of a lip column's opening time (the zip front: the time its gap
first exceeds the open threshold, interpolated linearly between the frames, 10 ms apart) and
of the final displacements (relative to the largest).

    .venv/bin/python benches/paper_scene.py            # 3 rounds
    ROUNDS=5 .venv/bin/python benches/paper_scene.py
    ONLY=sub-f64,sub-f32 REF_DIR=target/bench-paper-scene/reference_2 .venv/bin/python benches/paper_scene.py
    BEFORE=../old/target/release/sticky-lips .venv/bin/python benches/paper_scene.py

Needs the release build (cargo build --release) and numpy + meshio (the test command's .venv).
"""
import json
import os
import re
import statistics
import subprocess
import sys
import time

import meshio
import numpy as np

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("BIN", os.path.join(HERE, "target/release/sticky-lips"))
SCENE = os.path.join(HERE, "paper/scenarios/table1.toml")
OUT = os.environ.get("OUT", os.path.join(HERE, "target/bench-paper-scene"))
ROUNDS = int(os.environ.get("ROUNDS", "3"))
CONFIGS = [
    ("reference", ["--dt", "1e-5", "--precision", "f64"]),
    ("auto-f64", ["--dt", "auto", "--precision", "f64"]),
    ("auto-f32", ["--dt", "auto", "--precision", "f32"]),
    ("sub-f64", ["--dt", "auto", "--subcycles", "auto", "--precision", "f64"]),
    ("sub-f32", ["--dt", "auto", "--subcycles", "auto", "--precision", "f32"]),
    ("sub-f32-2frames", ["--dt", "auto", "--subcycles", "auto", "--precision", "f32"]),
]
BEFORE = os.environ.get("BEFORE")
if BEFORE:
    CONFIGS.append(("before", ["--dt", "auto", "--subcycles", "auto", "--precision", "f32"]))
ONLY = os.environ.get("ONLY")  # e.g. ONLY=reference,sub-f32
if ONLY:
    CONFIGS = [c for c in CONFIGS if c[0] in ONLY.split(",")]


def two_frames_scene():
    """The scene with a frame at the start and at the end only."""
    path = os.path.join(OUT, "table1_2frames.toml")
    text = open(SCENE).read()
    assert "output_every = 1000\n" in text
    with open(path, "w") as f:
        f.write(text.replace("output_every = 1000\n", "output_every = 100000\n"))
    return path


def run(name, args, k):
    out = os.path.join(OUT, f"{name}_{k}")
    scene = two_frames_scene() if name.endswith("2frames") else SCENE
    binary = BEFORE if name == "before" else BIN
    t0 = time.perf_counter()
    p = subprocess.run(
        [binary, "run", scene, "--threads", "2", "--out", out] + args,
        capture_output=True, text=True, check=True,
    )
    wall = time.perf_counter() - t0
    s = json.load(open(os.path.join(out, "summary.json")))
    log = p.stdout + p.stderr
    m = re.search(r"skin\.usda \(.*?; ([0-9.]+) s\) and preview.*?\(([0-9.]+) s\)", log)
    files, preview = (float(m.group(1)), float(m.group(2))) if m else (float("nan"),) * 2
    return (out, wall, s["stepping_time"], s["steps"], s["dt"], files, preview,
            s.get("subcycles", 1), s["wall_time"])


def opening_times(out):
    m = json.load(open(os.path.join(out, "measures.json")))
    thr = m["open_threshold"]
    g = np.array([f["gap"] for f in m["frames"]])
    times = np.array([f["time"] for f in m["frames"]])
    d = g - g[0] - thr
    t = []
    for c in range(g.shape[1]):
        i = int(np.argmax(d[:, c] > 0))
        if d[i, c] <= 0:
            t.append(None)
        elif i == 0:
            t.append(float(times[0]))
        else:
            a, b = d[i - 1, c], d[i, c]
            t.append(float(times[i - 1] + (times[i] - times[i - 1]) * (-a) / (b - a)))
    return t


def final_u(out):
    return meshio.read(os.path.join(out, "final.vtu")).point_data["displacement"]


def main():
    os.makedirs(OUT, exist_ok=True)
    res = {n: [] for n, _ in CONFIGS}
    for k in range(ROUNDS):
        for name, args in CONFIGS:
            res[name].append(run(name, args, k))
            print(f"round {k}: {name}: {res[name][-1][1]:.2f} s", file=sys.stderr)
    # the reference run: this run's, or (ONLY without it) an earlier one's directory
    ref = res["reference"][-1][0] if "reference" in res else os.environ["REF_DIR"]
    t_ref, u_ref = opening_times(ref), final_u(ref)
    big = float(np.abs(u_ref).max())
    print(f"paper scene ({SCENE}), {ROUNDS} rounds, 2 threads; medians")
    print("| configuration | dt (s) | substeps | steps | frames | process wall (s) | run (s) | stepping (s) | animation files (s) | preview (s) | zip front max diff (s) | final displacement max diff / largest |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, _ in CONFIGS:
        r = res[name]
        out = r[-1][0]
        frames = json.load(open(os.path.join(out, "summary.json")))["frames"]
        med = lambda i: statistics.median(x[i] for x in r)
        if frames < 3:  # no zip front to compare
            print(f"| {name} | {r[-1][4]:.4g} | {r[-1][7]} | {r[-1][3]} | {frames} | {med(1):.2f} | {med(8):.2f} | {med(2):.2f} | {med(5):.2f} | {med(6):.2f} | - | - |")
            continue
        t = opening_times(out)
        dz = max((abs(a - b) if a is not None and b is not None else float("inf"))
                 if (a is not None or b is not None) else 0.0 for a, b in zip(t, t_ref))
        du = float(np.abs(final_u(out) - u_ref).max()) / big
        print(f"| {name} | {r[-1][4]:.4g} | {r[-1][7]} | {r[-1][3]} | {frames} | {med(1):.2f} | {med(8):.2f} | {med(2):.2f} | {med(5):.2f} | {med(6):.2f} | {dz:.3g} | {du:.3g} |")


if __name__ == "__main__":
    main()
