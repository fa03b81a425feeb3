#!/usr/bin/env python3
"""Tables and the issue-6 target verdicts from the criterion results of `benches/gpu.rs`.

    python3 scripts/gpu_bench_report.py [CRITERION_DIR] [--scene DIR ...] [--cpu-threads K]

CRITERION_DIR is where criterion wrote its results (default: $CRITERION_HOME, else
target/criterion). For every `STAGE/BACKEND-PRECISION/hex=N` id of `benches/gpu.rs` found there
it prints the median time per iteration (one step, or one dispatch of one kernel), the
element-updates per second (N / median) and, for `step/*`, the steps per second (1 / median).

Then the three real-GPU targets of issue 6, each with the figures it was judged on:

1. the paper's scene in real time: 100 000 steps of the mouth (`hex=mouth`) in at most 1 s,
   i.e. `step/gpu-f32/hex=mouth` <= 10 us; with `--scene DIR` (a `sticky-lips run` output of
   paper/scenarios/table1.toml) also the run's own `stepping_time` and `wall_time`;
2. at least 1e9 element-updates per second on 512k hexahedra (`step/gpu-f32/hex=512000`);
3. at least 20x the CPU path (`step/cpu-*`, which the bench runs on RAYON_NUM_THREADS threads;
   `--cpu-threads` only labels them) at each size, same precision.

A target whose figures are missing is reported as "not measured", never as met. Only the
median is used (criterion's `median.point_estimate`, in ns); its confidence interval is printed
next to it. Nothing here runs a benchmark.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

SCENE_STEPS = 100_000  # paper/scenarios/table1.toml: 1 s at dt = 1e-5 s (Table 1)
SCENE_WALL_S = 1.0
UPDATES_512K = 1e9
RATIO = 20.0
STAGES = ("host", "element_forces", "node_update", "step")


class Result:
    def __init__(self, stage: str, backend: str, size: str, elements: int, est: dict):
        self.stage, self.backend, self.size, self.elements = stage, backend, size, elements
        med = est["median"]
        self.ns = float(med["point_estimate"])
        ci = med.get("confidence_interval", {})
        self.lo = float(ci.get("lower_bound", self.ns))
        self.hi = float(ci.get("upper_bound", self.ns))

    @property
    def updates_per_s(self) -> float:
        return self.elements / self.ns * 1e9

    @property
    def steps_per_s(self) -> float:
        return 1e9 / self.ns


def load(root: Path) -> dict[tuple[str, str, str], Result]:
    """Every `benches/gpu.rs` result under `root`, keyed by (stage, backend, size)."""
    out = {}
    for bj in sorted(root.glob("*/*/*/new/benchmark.json")):
        try:
            meta = json.loads(bj.read_text())
            est = json.loads((bj.parent / "estimates.json").read_text())
        except (OSError, ValueError) as e:
            raise SystemExit(f"{bj.parent}: unreadable criterion result ({e})")
        stage, backend, size = meta.get("group_id"), meta.get("function_id"), meta.get("value_str")
        # benches/tled.rs writes `STAGE/PRECISION_threads=K/hex=N`: not ours
        if stage not in STAGES or not str(backend).startswith(("gpu-", "cpu-")):
            continue
        thr = meta.get("throughput") or {}
        if "Elements" not in thr:
            raise SystemExit(f"{bj}: no Elements throughput (not a benches/gpu.rs result?)")
        out[(stage, backend, size)] = Result(stage, backend, size, int(thr["Elements"]), est)
    return out


def size_key(size: str) -> tuple[int, int]:
    n = size.split("=", 1)[-1]
    return (1, 0) if n == "mouth" else (0, int(n))


def fmt_time(ns: float) -> str:
    for unit, scale in (("s", 1e9), ("ms", 1e6), ("us", 1e3)):
        if ns >= scale:
            return f"{ns / scale:.3g} {unit}"
    return f"{ns:.3g} ns"


def fmt_rate(x: float) -> str:
    for unit, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if x >= scale:
            return f"{x / scale:.3g} {unit}"
    return f"{x:.3g}"


def table(res: dict, cpu_threads: str) -> list[str]:
    sizes = sorted({k[2] for k in res}, key=size_key)
    lines = [
        "| id | median per call [95% CI] | element-updates/s | steps/s |",
        "|---|---|---|---|",
    ]
    order = {s: i for i, s in enumerate(STAGES)}
    for size in sizes:
        keys = sorted((k for k in res if k[2] == size), key=lambda k: (order[k[0]], k[1]))
        for k in keys:
            r = res[k]
            label = f"`{r.stage}/{r.backend}/{r.size}`"
            if r.backend.startswith("cpu-"):
                label += f" ({cpu_threads} threads)"
            steps = fmt_rate(r.steps_per_s) if r.stage == "step" else ""
            ups = fmt_rate(r.updates_per_s) if r.stage != "host" else ""
            ci = f"[{fmt_time(r.lo)}, {fmt_time(r.hi)}]"
            lines.append(f"| {label} | {fmt_time(r.ns)} {ci} | {ups} | {steps} |")
    return lines


def scene_figures(d: Path) -> tuple[str, float | None]:
    """`sticky-lips run` summary of the paper's scene: (description, stepping seconds)."""
    f = d / "summary.json"
    if not f.exists():
        return f"{d}: no summary.json (the run did not finish)", None
    try:
        s = json.loads(f.read_text())
    except (OSError, ValueError) as e:
        return f"{f}: unreadable ({e})", None
    steps = s.get("steps")
    step_t, wall_t = s.get("stepping_time"), s.get("wall_time")
    backend = s.get("backend", "?")
    prec = s.get("precision", "?")
    if steps != SCENE_STEPS or step_t is None:
        return f"{d}: {steps} steps, not the scene's {SCENE_STEPS} (cut short?)", None
    return (
        f"{d} ({backend} {prec}): stepping_time {step_t:.3f} s, wall_time {wall_t:.3f} s",
        float(step_t),
    )


def verdict(ok: bool | None) -> str:
    return "not measured" if ok is None else ("met" if ok else "NOT met")


def targets(res: dict, scenes: list[Path], cpu_threads: str) -> list[str]:
    lines = []
    r = res.get(("step", "gpu-f32", "hex=mouth"))
    per_step = None if r is None else r.ns * 1e-9
    ok = None if r is None else per_step * SCENE_STEPS <= SCENE_WALL_S
    lines.append(f"1. paper's scene in real time (<= {SCENE_WALL_S:g} s for {SCENE_STEPS} steps): "
                 f"{verdict(ok)}")
    if r is not None:
        lines.append(f"   - `step/gpu-f32/hex=mouth`: {fmt_time(r.ns)} a step, "
                     f"x {SCENE_STEPS} = {per_step * SCENE_STEPS:.3g} s")
    for d in scenes:
        text, t = scene_figures(d)
        lines.append(f"   - {text}" + ("" if t is None else f" ({'<=' if t <= SCENE_WALL_S else '>'} "
                                                            f"{SCENE_WALL_S:g} s stepping)"))
    r = res.get(("step", "gpu-f32", "hex=512000"))
    ok = None if r is None else r.updates_per_s >= UPDATES_512K
    lines.append(f"2. >= {UPDATES_512K:.0e} element-updates/s at 512k hexahedra: {verdict(ok)}")
    if r is not None:
        lines.append(f"   - `step/gpu-f32/hex=512000`: {fmt_rate(r.updates_per_s)} element-updates/s")
    sizes = sorted({k[2] for k in res if k[0] == "step"}, key=size_key)
    pairs = []
    for size in sizes:
        for prec in ("f32", "f64"):
            g, c = res.get(("step", f"gpu-{prec}", size)), res.get(("step", f"cpu-{prec}", size))
            if g is not None and c is not None:
                pairs.append((size, prec, c.ns / g.ns))
    ok = None if not pairs else all(x >= RATIO for _, _, x in pairs)
    lines.append(f"3. >= {RATIO:g}x the CPU path on {cpu_threads} threads, every size and precision: "
                 f"{verdict(ok)}")
    for size, prec, x in pairs:
        lines.append(f"   - `{size}` {prec}: GPU {x:.3g}x the CPU")
    return lines


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    default = os.environ.get("CRITERION_HOME", "target/criterion")
    ap.add_argument("criterion_dir", nargs="?", default=default)
    ap.add_argument("--scene", action="append", default=[], type=Path,
                    help="output directory of a `sticky-lips run` of the paper's scene")
    ap.add_argument("--cpu-threads", default="RAYON_NUM_THREADS",
                    help="the thread count the CPU ids ran on (a label only)")
    a = ap.parse_args(argv)
    root = Path(a.criterion_dir)
    if not root.is_dir():
        print(f"{root}: no criterion results (run benches/gpu.rs first)", file=sys.stderr)
        return 2
    res = load(root)
    if not res:
        print(f"{root}: no benches/gpu.rs results", file=sys.stderr)
        return 2
    print(f"# benches/gpu.rs results in {root}\n")
    print("\n".join(table(res, a.cpu_threads)))
    print("\n## Issue 6 targets (real GPU)\n")
    print("\n".join(targets(res, a.scene, a.cpu_threads)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
