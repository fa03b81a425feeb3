"""The command line's outputs on a fixed set of commands, as one SHA-256 per file: run it with
the binary of two commits and compare the manifests, to show that a restructuring left every
output unchanged byte for byte.

    python scripts/cli_hashes.py --bin BIN --out DIR [--head DIR_WITH_head.obj_AND_rig.json] > manifest.txt
    diff manifest_before.txt manifest_after.txt

What is not compared byte for byte, because it changes from one run to the next whatever the
code: the wall times in the JSON files (the keys in `TIMING_KEYS`, at any depth: `wall_time`,
`stepping_time`, `element_updates_per_second`, `read_seconds`, `write_seconds`, `wall_time_s`)
and the output directory's own path where a file names it (replaced by `<OUT>`).
`--rehash` prints the manifest of an existing DIR again without running anything. Standard output is kept per
command, with any number followed by ` s` (a duration) replaced by `<T> s`.
"""

import argparse
import hashlib
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TIMING_KEYS = {"wall_time", "stepping_time", "element_updates_per_second", "read_seconds",
               "write_seconds", "wall_time_s"}


def commands(out, head):
    ex = os.path.join(HERE, "examples")
    nifty = os.path.join(HERE, "verification/reference/niftysim")
    cmds = [
        ["check", f"{ex}/cantilever.toml"],
        ["run", f"{ex}/cantilever.toml", "--out", f"{out}/cantilever", "--quiet"],
        ["run", f"{ex}/cantilever.toml", "--out", f"{out}/cantilever_f32", "--precision", "f32",
         "--threads", "2", "--quiet"],
        ["run", f"{nifty}/block4_compress.xml", "--niftysim-compat", "--out", f"{out}/block4", "--quiet"],
        ["equilibrium", f"{ex}/cantilever.toml", "--out", f"{out}/cantilever_static"],
        ["run", f"{ex}/sticky_slabs.toml", "--out", f"{out}/sticky_slabs", "--quiet"],
        ["blend", f"{ex}/cantilever.toml", "--shape", f"{out}/cantilever/final.vtu=0.5", "--out",
         f"{out}/cantilever_blend"],
        ["evaporation"],
        ["run", "--out", f"{out}/face_default", "--quiet"],
        ["export", f"{out}/face_default"],
        ["mouth", "--out", f"{out}/mouth"],
        ["paper", "--quick", "--only", "fig2", "--out", f"{out}/paper"],
    ]
    if head:
        cmds += [
            ["face", f"{head}/head.obj", "--rig", f"{head}/rig.json", "--units", "mm", "--up", "0,0,1",
             "--forward", "0,-1,0", "--resolution", "0.25", "--out", f"{out}/face"],
            ["face", f"{head}/head.obj", "--resolution", "0.25", "--out", f"{out}/face_detected"],
            ["run", f"{out}/face/scenario.toml", "--dt", "auto", "--quiet"],
        ]
    return cmds


def without_timings(v):
    if isinstance(v, dict):
        return {k: without_timings(x) for k, x in v.items() if k not in TIMING_KEYS}
    if isinstance(v, list):
        return [without_timings(x) for x in v]
    return v


def normalised(path, out):
    data = open(path, "rb").read()
    if path.endswith(".json"):
        data = json.dumps(without_timings(json.loads(data)), sort_keys=True).encode()
    if path.endswith((".json", ".toml", ".pvd", ".csv", ".md", ".txt", ".usda", ".xml")):
        data = data.replace(out.encode(), b"<OUT>")
    return data


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin")
    ap.add_argument("--out", required=True)
    ap.add_argument("--head", help="a directory with the MakeHuman head.obj and rig.json "
                    "(scripts/makehuman_face.py --head)")
    ap.add_argument("--rehash", action="store_true", help="only print DIR's manifest again")
    a = ap.parse_args()
    out = os.path.abspath(a.out)
    if not a.rehash:
        run_all(a.bin, out, a.head)
    for root, _, files in sorted(os.walk(out)):
        for name in sorted(files):
            p = os.path.join(root, name)
            rel = os.path.relpath(p, out)
            print(hashlib.sha256(normalised(p, out)).hexdigest(), rel)


def run_all(binary, out, head):
    os.makedirs(out, exist_ok=False)
    for k, c in enumerate(commands(out, head)):
        r = subprocess.run([os.path.abspath(binary)] + c, cwd=out, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"{' '.join(c)} failed ({r.returncode}):\n{r.stderr}")
        text = re.sub(r"[0-9.eE+-]+ (s\b|element-updates/s)", r"<T> \1", r.stdout.replace(out, "<OUT>"))
        with open(os.path.join(out, f"stdout_{k:02}_{c[0]}.txt"), "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
