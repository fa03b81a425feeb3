#!/usr/bin/env bash
# Whole-process timing of NiftySim's timing_block20 model (20^3 = 8000 hexahedra, 1001
# iterations) with the release binary, next to NiftySim's own figures
# (../shared/oracle/niftysim/README.md: 0.27 us/element-step single-threaded float32 build,
# 0.22 us double build, 0.17 us with its 2-thread build).
#
#   scripts/time_niftysim_block.sh            # 5 repeats of f64/f32 x 1/2 threads
#   REPEATS=9 THREADS="1 2" PRECISIONS="f32" scripts/time_niftysim_block.sh
#   scripts/time_niftysim_block.sh --build    # cargo build --release first
#
# Runs are interleaved (round r runs every configuration once, in turn) so that load from
# other processes on a shared machine hits all configurations alike. For each configuration
# it prints the median process wall time, the median stepping-loop time (summary.json
# `stepping_time`: the stepping loop alone, without reading, precompute, the stability
# check or output) and the median us per element-step = stepping_time / (steps * elements).
# Needs bash and python3 (standard library only).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"

BIN="${BIN:-target/release/sticky-lips}"
MODEL="${MODEL:-../shared/oracle/niftysim/timing_block20.xml}"
REPEATS="${REPEATS:-5}"
THREADS="${THREADS:-1 2}"
PRECISIONS="${PRECISIONS:-f64 f32}"

if [[ "${1:-}" == "--build" ]]; then
    cargo build --release --bin sticky-lips
elif [[ -n "${1:-}" ]]; then
    echo "usage: $0 [--build]   (env: BIN MODEL REPEATS THREADS PRECISIONS)" >&2
    exit 2
fi
if [[ ! -x "$BIN" ]]; then
    echo "error: $BIN not found; build it with 'cargo build --release' or pass --build" >&2
    exit 1
fi
if [[ ! -f "$MODEL" ]]; then
    echo "error: model $MODEL not found" >&2
    exit 1
fi

tmp="$(mktemp -d "${TMPDIR:-/tmp}/time_niftysim_block.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
# A private copy, so that a concurrent `cargo build` cannot swap the binary mid-series.
cp "$BIN" "$tmp/sticky-lips"
results="$tmp/results.tsv"
: >"$results"

echo "binary:  $BIN ($(date -r "$BIN" '+%Y-%m-%d %H:%M:%S'))"
echo "model:   $MODEL"
echo "machine: $(nproc) cores, $(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n1)"
echo "date:    $(date '+%Y-%m-%d %H:%M:%S %Z'); load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "repeats: $REPEATS, interleaved over precision {${PRECISIONS// /,}} x threads {${THREADS// /,}}"
echo

for ((r = 1; r <= REPEATS; r++)); do
    for prec in $PRECISIONS; do
        for th in $THREADS; do
            out="$tmp/out_${prec}_${th}_$r"
            t0=$(date +%s%N)
            "$tmp/sticky-lips" run "$MODEL" --niftysim-compat --quiet \
                --precision "$prec" --threads "$th" --out "$out" >/dev/null
            t1=$(date +%s%N)
            python3 - "$out/summary.json" "$prec" "$th" "$r" "$t0" "$t1" >>"$results" <<'EOF'
import json, sys
path, prec, th, rep, t0, t1 = sys.argv[1:]
s = json.load(open(path))
assert s["precision"] == prec and s["threads"] == int(th), (s["precision"], s["threads"])
wall = (int(t1) - int(t0)) * 1e-9
print(prec, th, rep, f"{wall:.6f}", s["wall_time"], s["stepping_time"], s["steps"], s["num_elements"], sep="\t")
EOF
            rm -rf "$out"
            printf '.' >&2
        done
    done
done
echo >&2

python3 - "$results" <<'EOF'
import statistics, sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]) if l.strip()]
# NiftySim 2.5 on this machine kind (../shared/oracle/niftysim/README.md), us/element-step:
# 1 thread: stock float32 build 0.27, double build 0.22; 2-thread build (stock float32) 0.17.
nifty = {("f32", "1"): 0.27, ("f64", "1"): 0.22, ("f32", "2"): 0.17, ("f64", "2"): 0.17}
nifty_note = {("f32", "1"): "f32 build", ("f64", "1"): "double build",
              ("f32", "2"): "2-thread build", ("f64", "2"): "2-thread build (f32)"}
configs = []
for r in rows:
    if (r[0], r[1]) not in configs:
        configs.append((r[0], r[1]))
steps, ne = rows[0][6], rows[0][7]
print(f"timing_block20: {ne} hexahedra, {steps} iterations; medians over {len({r[2] for r in rows})} runs")
print()
hdr = ("precision", "threads", "process wall s", "stepping s", "us/elem-step",
       "Melem-upd/s", "NiftySim us/elem-step", "NiftySim/ours")
print("| " + " | ".join(hdr) + " |")
print("|" + "---|" * len(hdr))
for prec, th in configs:
    rs = [r for r in rows if (r[0], r[1]) == (prec, th)]
    wall = statistics.median(float(r[3]) for r in rs)
    step = statistics.median(float(r[5]) for r in rs)
    per = [float(r[5]) / (int(r[6]) * int(r[7])) * 1e6 for r in rs]
    us = statistics.median(per)
    lo, hi = min(per), max(per)
    ref = nifty.get((prec, th))
    refs = f"{ref:.2f} ({nifty_note[(prec, th)]})" if ref else "-"
    ratio = f"{ref / us:.2f}x" if ref else "-"
    print(f"| {prec} | {th} | {wall:.3f} | {step:.3f} | {us:.4f} [{lo:.4f}..{hi:.4f}] "
          f"| {1.0 / us:.2f} | {refs} | {ratio} |")
print()
print("us/elem-step: median [min..max] of stepping_time / (steps * elements).")
print("NiftySim/ours > 1 means this solver's stepping loop is faster than NiftySim's.")
EOF
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
