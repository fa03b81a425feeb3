"""The lip gap of the quick face over time, one line per column along the mouth's width:
the picture of the README's "From Python" section (paper/figures/python_lip_gap.png).

    python python/examples/lip_gap.py [OUT.png] [--out RUN_DIR]

Runs the default job (the MakeHuman face at the quick resolution, the paper's fig4_sticky)
through the package, as the README's five lines do, and draws its measures with matplotlib.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import sticky_lips  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("png", nargs="?", default=REPO / "paper" / "figures" / "python_lip_gap.png", type=Path)
    ap.add_argument("--out", type=Path, help="the run's directory (default: a temporary one)")
    args = ap.parse_args()

    t0 = time.monotonic()
    run = sticky_lips.Scenario.quick_face().run(args.out)
    m = run.measures
    print(f"{run.summary['steps']} steps, {len(m.times)} frames in {time.monotonic() - t0:.1f} s")

    fig, ax = plt.subplots(figsize=(7, 4), dpi=120)
    # the columns coloured by their distance from the mouth's centre: the centre opens first
    off = abs(m.x - m.center)
    cmap = plt.get_cmap("viridis")
    for c in range(len(m.x)):
        ax.plot(m.times * 1e3, m.gap[:, c] * 1e3, color=cmap(off[c] / off.max()), lw=1)
    ax.axhline(m.open_threshold * 1e3, color="0.5", ls="--", lw=0.8, label="open threshold")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("lip gap (mm)")
    ax.set_title("Quick face: lip gap per column (sticky_lips.Scenario.quick_face().run())")
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0, off.max() * 1e3))
    fig.colorbar(sm, ax=ax, label="column's distance from the centre (mm)")
    ax.legend(loc="upper left")
    fig.tight_layout()
    args.png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.png)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
