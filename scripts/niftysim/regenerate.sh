#!/usr/bin/env bash
# Runs the five NiftySim models of verification/reference/niftysim/ with NiftySim's double and
# float builds, writes what NiftySim's own command line prints in the format of the committed
# reference files, and compares each regenerated file with the committed one.
#
#   scripts/niftysim/regenerate.sh SRC_DIR OUT_DIR   # builds first (build.sh SRC_DIR OUT_DIR/build)
#   scripts/niftysim/regenerate.sh BIN_DIR OUT_DIR   # BIN_DIR: build.sh's OUT_DIR/bin
#   env: MODELS="hex1_stretch block4_compress"  (default: every *.xml there but timing_block20)
#
# Each model runs as
#   niftysim_fXX_print17 -x MODEL.xml -v -print ND -print NF -print EK -print ES
# (build.sh: the stock solver, only the printing functions print 17 significant digits) in an
# empty working directory. Written under OUT_DIR:
#   raw/out_fXX/MODEL.stdout     NiftySim's output as printed
#   out_fXX/MODEL_U.txt          `node ux uy uz` (0-based node; NiftySim prints 1-based) from
#                                `-print ND`: the displacements after the last iteration. f64:
#                                %.17g, f32: %.9g, as the committed files
#   out_fXX/MODEL_info.txt       the committed keys, from -v (NumSteps, nodes, elements), the XML
#                                (dt, T), NiftySim's loop (steps_executed = NumSteps + 1,
#                                final_time_of_U = steps_executed * dt), -print EK/ES (energies,
#                                %.9g) and the exit status
#   out_fXX/MODEL_F_print.txt    `node fx fy fz` from `-print NF`: NiftySim's force array F after
#                                the run, i.e. the internal forces of the state BEFORE the last
#                                iteration (compared with the committed MODEL_Fint.txt, which
#                                holds the forces of the final state, to show the difference)
#   comparison.txt               the table printed at the end
# out_f64 is compared bit for bit with the committed out_f64; out_f32 after rounding both to
# float32; the rows of the committed MODEL_hist.txt at the last iteration are compared with the
# regenerated U as well. Exit status 1 when a regenerated U or info file, or those history rows,
# differ from the committed ones.
# Needs bash and python3 (standard library only).
set -euo pipefail

usage() {
    cat >&2 <<EOF
usage: $0 SRC_DIR|BIN_DIR OUT_DIR
  SRC_DIR  NiftySim source checkout: build.sh builds it into OUT_DIR/build first
  BIN_DIR  a folder with niftysim_f32_print17 and niftysim_f64_print17 (build.sh's OUT_DIR/bin)
  OUT_DIR  where the regenerated files go (created)
  env: MODELS="name ..." (default: the five models of verification/reference/niftysim)
EOF
    exit 2
}
[[ $# -eq 2 ]] || usage
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
REF="$repo/verification/reference/niftysim"
[[ -d "$1" ]] || { echo "error: $1 is not a directory" >&2; exit 1; }
mkdir -p "$2"
OUT="$(cd "$2" && pwd)"

if [[ -f "$1/source/CMakeLists.txt" ]]; then
    "$here/build.sh" "$1" "$OUT/build"
    BIN="$OUT/build/bin"
elif [[ -x "$1/niftysim_f64_print17" ]]; then
    BIN="$(cd "$1" && pwd)"
elif [[ -x "$1/bin/niftysim_f64_print17" ]]; then
    BIN="$(cd "$1/bin" && pwd)"
else
    echo "error: $1 is neither a NiftySim checkout nor a folder with niftysim_f64_print17" >&2
    usage
fi
for b in f32 f64; do
    [[ -x "$BIN/niftysim_${b}_print17" ]] || { echo "error: $BIN/niftysim_${b}_print17 not found" >&2; exit 1; }
done

if [[ -z "${MODELS:-}" ]]; then
    MODELS="$(cd "$REF" && ls *.xml | sed 's/\.xml$//' | grep -v '^timing_block20$' | tr '\n' ' ')"
fi
echo "binaries: $BIN"
[[ -f "$BIN/BUILD_INFO" ]] && sed 's/^/  /' "$BIN/BUILD_INFO"
echo "models:   $MODELS"
echo "output:   $OUT"

work="$(mktemp -d "${TMPDIR:-/tmp}/niftysim_regen.XXXXXX")"
trap 'rm -rf "$work"' EXIT
for b in f64 f32; do
    mkdir -p "$OUT/raw/out_$b" "$OUT/out_$b"
    for m in $MODELS; do
        [[ -f "$REF/$m.xml" ]] || { echo "error: $REF/$m.xml not found" >&2; exit 1; }
        rm -rf "$work/run" && mkdir "$work/run"
        t0=$EPOCHREALTIME
        set +e
        (cd "$work/run" && "$BIN/niftysim_${b}_print17" -x "$REF/$m.xml" -v \
            -print ND -print NF -print EK -print ES) >"$OUT/raw/out_$b/$m.stdout" 2>"$OUT/raw/out_$b/$m.stderr"
        rc=$?
        set -e
        echo "$rc" >"$OUT/raw/out_$b/$m.rc"
        printf '  %-20s %s  exit %d  %.2f s\n' "$m" "$b" "$rc" "$(awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { print b - a }')"
        if [[ -n "$(ls -A "$work/run")" ]]; then
            echo "  note: NiftySim wrote files: $(ls "$work/run" | tr '\n' ' ')"
        fi
    done
done

python3 - "$REF" "$OUT" "$MODELS" <<'PYTHON'
import math, os, re, struct, sys

ref, out, models = sys.argv[1], sys.argv[2], sys.argv[3].split()


def f32(x):
    """x rounded to the nearest float32 (as a Python float)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def bits64(x):
    return struct.pack("<d", x)


def bits32(x):
    return struct.pack("<f", x)


def section(text, title):
    """Rows `i  a  b  c` (1-based i) of NiftySim's printed table titled `title`."""
    lines = text.splitlines()
    try:
        start = lines.index(title)
    except ValueError:
        sys.exit(f"error: no '{title}' section in NiftySim's output")
    rows = []
    for line in lines[start + 2:]:
        if line.startswith("-----") or not line.strip() or line.startswith("Sums"):
            break
        f = line.split()
        rows.append((int(f[0]) - 1, float(f[1]), float(f[2]), float(f[3])))
    return rows


def value(text, pattern, conv=float):
    m = re.search(pattern, text, re.M)
    if not m:
        sys.exit(f"error: '{pattern}' not found in NiftySim's output")
    return conv(m.group(1))


def xml_value(xml, tag):
    return float(re.search(rf"<{tag}>\s*([^<\s]+)\s*</{tag}>", xml).group(1))


def fmt(x, build):
    return "%.17g" % x if build == "f64" else "%.9g" % f32(x)


def write_table(path, rows, build):
    with open(path, "w") as f:
        for r in rows:
            f.write(str(r[0]) + " " + " ".join(fmt(v, build) for v in r[1:]) + "\n")


def read_table(path):
    rows = []
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        f = line.split()
        rows.append((int(f[0]), [float(v) for v in f[1:]]))
    return rows


def compare_values(pairs, build):
    """(components, identical components, max |d|, max |d| / max |old|) over (new, old)
    pairs; f32 after rounding both to float32."""
    n = same = 0
    dmax = umax = 0.0
    for x, y in pairs:
        if build == "f32":
            x, y = f32(x), f32(y)
            eq = bits32(x) == bits32(y)
        else:
            eq = bits64(x) == bits64(y)
        n += 1
        same += eq
        dmax = max(dmax, abs(x - y))
        umax = max(umax, abs(y))
    return n, same, dmax, dmax / umax if umax > 0 else 0.0


def compare_tables(new, old, build):
    """compare_values over two tables with the same rows; None where the rows differ."""
    a, b = read_table(new), read_table(old)
    if [r[0] for r in a] != [r[0] for r in b]:
        return None
    return compare_values(((x, y) for (_, va), (_, vb) in zip(a, b) for x, y in zip(va, vb)),
                          build)


results = []  # (model, build, file, n, same, dabs, drel, text_identical)
bad = 0
for build in ("f64", "f32"):
    for m in models:
        raw = os.path.join(out, "raw", f"out_{build}", m)
        text = open(raw + ".stdout").read()
        rc = int(open(raw + ".rc").read())
        xml = open(os.path.join(ref, m + ".xml")).read()
        odir = os.path.join(out, f"out_{build}")
        cdir = os.path.join(ref, f"out_{build}")

        # displacements
        u = section(text, "Nodal Displacements (ALL)")
        write_table(os.path.join(odir, f"{m}_U.txt"), u, build)
        # NiftySim's force array after the run (the state before the last iteration)
        fp = section(text, "Nodal Forces (ALL)")
        write_table(os.path.join(odir, f"{m}_F_print.txt"), fp, build)

        # info
        dt, T = xml_value(xml, "TimeStep"), xml_value(xml, "TotalTime")
        nsteps = value(text, r"^# Steps:\s*(\d+)", int)
        info = [
            ("model", f"{m}.xml"),
            ("sizeof_float_in_build", "8" if build == "f64" else "4"),
            ("dt", "%.17g" % dt),
            ("T", "%.17g" % T),
            ("NumSteps", str(nsteps)),
            ("steps_executed", str(nsteps + 1)),
            ("final_time_of_U", "%.17g" % ((nsteps + 1) * dt)),
            ("num_nodes", str(value(text, r"^Nodes:\s*(\d+)", int))),
            ("num_elements", str(value(text, r"^Elements:\s*(\d+)", int))),
            ("kinetic_energy_final", "%.9g" % value(text, r"^E kinetic:\s*(\S+)")),
            ("strain_energy_final", "%.9g" % value(text, r"^E strain:\s*(\S+)")),
            ("exit_code", str(rc)),
        ]
        with open(os.path.join(odir, f"{m}_info.txt"), "w") as f:
            for k, v in info:
                f.write(f"{k} {v}\n")

        for name, committed in ((f"{m}_U.txt", f"{m}_U.txt"),
                                (f"{m}_F_print.txt", f"{m}_Fint.txt")):
            new, old = os.path.join(odir, name), os.path.join(cdir, committed)
            c = compare_tables(new, old, build)
            if c is None:
                sys.exit(f"error: {new} and {old} list different nodes")
            text_same = open(new).read() == open(old).read()
            results.append((m, build, f"{name} vs {committed}", *c, text_same))
            if name.endswith("_U.txt") and c[1] != c[0]:
                bad += 1
        # the committed history's rows of the last iteration hold the same numbers as U
        hist = [l.split() for l in open(os.path.join(cdir, f"{m}_hist.txt")) if not l.startswith("#")]
        last = [h for h in hist if int(h[0]) == nsteps + 1]
        unew = {r[0]: r[1] for r in read_table(os.path.join(odir, f"{m}_U.txt"))}
        n, same, dmax, rel = compare_values(
            ((x, y) for h in last
             for x, y in zip(unew[int(h[2])], (float(v) for v in h[3:6]))), build)
        results.append((m, build, f"{m}_U.txt vs {m}_hist.txt rows of step {nsteps + 1}", n, same,
                        dmax, rel, None))
        if same != n or n == 0:
            bad += 1
        # info, key by key
        new, old = os.path.join(odir, f"{m}_info.txt"), os.path.join(cdir, f"{m}_info.txt")
        kv_new = dict(l.split(None, 1) for l in open(new).read().splitlines())
        kv_old = dict(l.split(None, 1) for l in open(old).read().splitlines())
        diff = [k for k in kv_old if kv_new.get(k) != kv_old[k]] + [k for k in kv_new if k not in kv_old]
        results.append((m, build, f"{m}_info.txt", len(kv_old), len(kv_old) - len(diff), None,
                        ",".join(diff) or None, open(new).read() == open(old).read()))
        if diff:
            bad += 1

lines = []
lines.append("| model | build | regenerated vs committed | values | bit-identical | max abs diff | max rel diff | file identical |")
lines.append("|---|---|---|---:|---:|---:|---:|---|")
for m, build, what, n, same, dabs, drel, text_same in results:
    if dabs is None:  # info: drel holds the differing keys
        lines.append(f"| {m} | {build} | {what} | {n} keys | {same} | - | {'differs: ' + drel if drel else '-'} | {'yes' if text_same else 'no'} |")
    else:
        ident = "-" if text_same is None else ("yes" if text_same else "no")
        lines.append(f"| {m} | {build} | {what} | {n} | {same} ({'yes' if same == n else 'no'}) "
                     f"| {dabs:.3g} | {drel:.3g} | {ident} |")
lines.append("")
lines.append("bit-identical: f64 as doubles, f32 after rounding both sides to float32. max rel diff =")
lines.append("max |new - committed| / max |committed| over the file. F_print is NiftySim's force array")
lines.append("after the run (forces of the state before the last iteration); the committed Fint holds the")
lines.append("forces of the final state, so they are not expected to agree.")
table = "\n".join(lines)
print()
print(table)
with open(os.path.join(out, "comparison.txt"), "w") as f:
    f.write(table + "\n")
if bad:
    print(f"\n{bad} regenerated U/info file(s) or history rows differ from the committed ones")
    sys.exit(1)
print("\nevery regenerated U and info file equals the committed one, and so do the history rows of the last iteration")
PYTHON
