"""Builds the Blender extension's zip from blender/ (the add-on, pure Python).

    python scripts/build_blender_extension.py [--out DIR]      # default: target/blender

It runs Blender's own extension builder, `blender_ext.py build` (the program behind
`blender --command extension build`, which also validates the manifest), from the `bpy`
package of the interpreter that runs this script (the test command's .venv-anim). Without
`bpy` it says so and stops: a zip that Blender's builder has not checked is not written.
Prints the zip's path.
"""

import argparse
import glob
import os
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SOURCE = ROOT / "blender"


def blender_ext():
    """Blender's extension command line tool, from the installed `bpy` (found without
    importing bpy, which would start Blender)."""
    import importlib.util

    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        sys.exit(
            "build_blender_extension.py: no bpy in this interpreter; run it with the test "
            "command's .venv-anim/bin/python (scripts/requirements-anim.txt)"
        )
    base = spec.submodule_search_locations[0]
    found = glob.glob(os.path.join(base, "*", "scripts", "addons_core", "bl_pkg", "cli", "blender_ext.py"))
    if len(found) != 1:
        sys.exit(f"build_blender_extension.py: blender_ext.py not found (once) under {base}: {found}")
    return found[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(ROOT / "target" / "blender"), help="output directory")
    args = ap.parse_args()
    with open(SOURCE / "blender_manifest.toml", "rb") as f:
        manifest = tomllib.load(f)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    zip_path = out / f"{manifest['id']}-{manifest['version']}.zip"
    r = subprocess.run(
        [sys.executable, blender_ext(), "build", "--source-dir", str(SOURCE),
         "--output-filepath", str(zip_path)],
        capture_output=True, text=True,
    )
    if r.returncode != 0 or not zip_path.is_file():
        sys.stderr.write(r.stdout + r.stderr)
        sys.exit(f"build_blender_extension.py: Blender's builder refused blender/ (status {r.returncode})")
    print(zip_path)


if __name__ == "__main__":
    main()
