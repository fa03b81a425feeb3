"""Archive one cargo-mutants run under verification/mutants/, and tabulate the archives.

    python3 scripts/mutants_archive.py MUTANTS_OUT --started UTC --commit SHA [--tree-changed] \
        --version "cargo-mutants X" --command CMD
    python3 scripts/mutants_archive.py --table        # the Markdown table of every archive

MUTANTS_OUT is cargo-mutants' output folder (target/mutants-out/mutants.out), holding
caught.txt, missed.txt, unviable.txt and timeout.txt (one mutant a line, `FILE:LINE:COL: what`)
and outcomes.json. The archive, verification/mutants/STARTED_FILES/, holds:
  run.json      the command, cargo-mutants' version, the git commit the run started from (and
                whether the tree had uncommitted changes then), the machine (processor,
                cores), start and end time, and per mutated file the counts of caught,
                missed, unviable and timed-out mutants;
  missed.txt, timeout.txt, unviable.txt, caught.txt   cargo-mutants' lists, as written;
  outcomes.json cargo-mutants' own record, as written.
Standard library only (scripts/mutants.sh runs it with the system's python3).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import re
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ARCHIVE = ROOT / "verification" / "mutants"
KINDS = ("caught", "missed", "unviable", "timeout")


def lines_of(path: Path) -> list[str]:
    return [l for l in path.read_text().splitlines() if l.strip()] if path.exists() else []


def processor() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def archive(out: Path, started: str, commit: str, tree_changed: bool, version: str,
            command: str) -> Path:
    counts: dict[str, dict[str, int]] = {}
    for kind in KINDS:
        for line in lines_of(out / f"{kind}.txt"):
            f = line.split(":", 1)[0]
            counts.setdefault(f, {k: 0 for k in KINDS})[kind] += 1
    if not counts:
        sys.exit(f"{out}: no mutant outcomes (caught/missed/unviable/timeout.txt are empty)")
    files = sorted(counts)
    label = "+".join(Path(f).stem for f in files)
    stamp = started.replace(":", "").replace("-", "")
    dest = ARCHIVE / f"{stamp}_{label}"
    dest.mkdir(parents=True, exist_ok=False)
    for name in [f"{k}.txt" for k in KINDS] + ["outcomes.json"]:
        if (out / name).exists():
            shutil.copyfile(out / name, dest / name)
    run = {
        "command": command,
        "cargo_mutants": version,
        "commit": commit,
        "tree_changed": tree_changed,
        "processor": processor(),
        "cores": os.cpu_count(),
        "started": started,
        "ended": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "files": {f: counts[f] for f in files},
        "total": {k: sum(c[k] for c in counts.values()) for k in KINDS},
    }
    (dest / "run.json").write_text(json.dumps(run, indent=2) + "\n")
    print(f"mutants: archived in {dest.relative_to(ROOT)}: {run['total']}")
    return dest


def table() -> str:
    rows = ["| run | file | caught | missed | unviable | timeout | cargo-mutants | command |",
            "|---|---|---|---|---|---|---|---|"]
    for run_json in sorted(ARCHIVE.glob("*/run.json")):
        run = json.loads(run_json.read_text())
        for f, c in run["files"].items():
            rows.append(f"| `{run_json.parent.name}` | `{f}` | {c['caught']} | {c['missed']} | "
                        f"{c['unviable']} | {c['timeout']} | {run['cargo_mutants']} | "
                        f"`{run['command']}` |")
    return "\n".join(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", nargs="?", type=Path)
    ap.add_argument("--started")
    ap.add_argument("--commit", help="the commit the run started from (git rev-parse HEAD then)")
    ap.add_argument("--tree-changed", action="store_true",
                    help="the work tree had uncommitted changes when the run started")
    ap.add_argument("--version")
    ap.add_argument("--command")
    ap.add_argument("--table", action="store_true")
    a = ap.parse_args()
    if a.table:
        print(table())
        return
    if not (a.out and a.started and a.commit and a.version and a.command):
        ap.error("MUTANTS_OUT, --started, --commit, --version and --command are needed to archive")
    if not re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", a.started):
        ap.error(f"--started {a.started!r} is not a UTC time YYYY-MM-DDTHH:MM:SSZ")
    archive(a.out, a.started, a.commit, a.tree_changed, a.version, a.command)


if __name__ == "__main__":
    main()
