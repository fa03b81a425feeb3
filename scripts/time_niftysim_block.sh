#!/usr/bin/env bash
# Whole-process timing of NiftySim's timing_block20 model (20^3 = 8000 hexahedra, 1001
# iterations) with the release binary, next to NiftySim's own figures
# (verification/reference/niftysim/README.md: 0.27 us/element-step single-threaded float32 build,
# 0.22 us double build, 0.17 us with its 2-thread build).
#
#   scripts/time_niftysim_block.sh            # 5 repeats of f64/f32 x 1/2 threads
#   REPEATS=9 THREADS="1 2" PRECISIONS="f32" WAIT_QUIET=0 scripts/time_niftysim_block.sh
#   scripts/time_niftysim_block.sh --build    # cargo build --release first
#   COMPARE="before=/path/to/old/sticky-lips" scripts/time_niftysim_block.sh
#       # also times another build, interleaved with BIN in the same rounds (before/after)
#
# Runs are interleaved (round r runs every configuration once, in turn) so that load from
# other processes on a shared machine hits all configurations alike. For each configuration
# it prints the median process wall time, the median stepping-loop time (summary.json
# `stepping_time`: the stepping loop alone, without reading, precompute, the stability
# check or output) and the median us per element-step = stepping_time / (steps * elements).
# On a shared machine each run first waits (up to WAIT_QUIET s, default 30) for the CPUs to
# go idle, and the table reports how many CPUs other processes kept busy during the runs.
# Needs bash and python3 (standard library only).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"

BIN="${BIN:-target/release/sticky-lips}"
MODEL="${MODEL:-verification/reference/niftysim/timing_block20.xml}"
REPEATS="${REPEATS:-5}"
THREADS="${THREADS:-1 2}"
PRECISIONS="${PRECISIONS:-f64 f32}"
# Before each run, wait up to this many seconds for the CPUs to go idle (0: do not wait).
WAIT_QUIET="${WAIT_QUIET:-30}"
# Other binaries to time in the same rounds: space-separated LABEL=PATH (BIN is "this").
COMPARE="${COMPARE:-}"

if [[ "${1:-}" == "--build" ]]; then
    cargo build --release --bin sticky-lips
elif [[ -n "${1:-}" ]]; then
    echo "usage: $0 [--build]   (env: BIN COMPARE MODEL REPEATS THREADS PRECISIONS WAIT_QUIET)" >&2
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
# Private copies, so that a concurrent `cargo build` cannot swap a binary mid-series.
mkdir "$tmp/bin"
cp "$BIN" "$tmp/bin/this"
labels="this"
for spec in $COMPARE; do
    label="${spec%%=*}"
    path="${spec#*=}"
    if [[ "$label" == "$spec" || ! "$label" =~ ^[A-Za-z0-9_.-]+$ || "$label" == "this" ]]; then
        echo "error: COMPARE entry '$spec' is not LABEL=PATH (LABEL: letters, digits, _ . -; not 'this')" >&2
        exit 2
    fi
    if [[ ! -x "$path" ]]; then
        echo "error: COMPARE: $path ($label) not found or not executable" >&2
        exit 1
    fi
    cp "$path" "$tmp/bin/$label"
    labels="$labels $label"
    echo "compare: $label = $path ($(date -r "$path" '+%Y-%m-%d %H:%M:%S'))"
done

echo "binary:  $BIN ($(date -r "$BIN" '+%Y-%m-%d %H:%M:%S'))"
echo "model:   $MODEL"
echo "machine: $(nproc) cores, $(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n1)"
echo "date:    $(date '+%Y-%m-%d %H:%M:%S %Z'); load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "repeats: $REPEATS, interleaved over precision {${PRECISIONS// /,}} x threads {${THREADS// /,}}; WAIT_QUIET=$WAIT_QUIET s"
echo

python3 - "$tmp" "$MODEL" "$REPEATS" "$PRECISIONS" "$THREADS" "$WAIT_QUIET" "$labels" <<'PYTHON'
import json, os, shutil, statistics, subprocess, sys, time

tmp, model, repeats, precisions, threads, wait_quiet, labels = sys.argv[1:]
repeats, wait_quiet = int(repeats), float(wait_quiet)
labels = labels.split()
configs = [(b, p, t) for p in precisions.split() for t in threads.split() for b in labels]
tick = os.sysconf("SC_CLK_TCK")


def busy_jiffies():
    """(busy, total) jiffies of all CPUs since boot, from /proc/stat."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return sum(v) - v[3] - v[4], sum(v)


def wait_until_quiet(limit):
    """Waits (at most `limit` s) until the CPUs are < 5 % busy over 2 s."""
    t0 = time.time()
    while time.time() - t0 < limit:
        b0, a0 = busy_jiffies()
        time.sleep(2)
        b1, a1 = busy_jiffies()
        if (b1 - b0) < 0.05 * max(1, a1 - a0):
            return


rows = []
for rep in range(1, repeats + 1):
    for binary, prec, th in configs:
        out = os.path.join(tmp, f"out_{binary}_{prec}_{th}_{rep}")
        if wait_quiet > 0:
            wait_until_quiet(wait_quiet)
        b0, _ = busy_jiffies()
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            [os.path.join(tmp, "bin", binary), "run", model, "--niftysim-compat", "--quiet",
             "--precision", prec, "--threads", th, "--out", out],
            stdout=subprocess.DEVNULL)
        _, status, ru = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        b1, _ = busy_jiffies()
        if status != 0:
            sys.exit(f"error: run {binary} {prec}/{th} (repeat {rep}) failed with status {status}")
        s = json.load(open(os.path.join(out, "summary.json")))
        assert s["precision"] == prec and s["threads"] == int(th), (s["precision"], s["threads"])
        own = (ru.ru_utime + ru.ru_stime) * tick
        # CPUs kept busy by other processes during the run (0 = a quiet machine)
        others = max(0.0, (b1 - b0) - own) / tick / wall
        rows.append(dict(binary=binary, prec=prec, th=th, wall=wall, stepping=s["stepping_time"],
                         steps=s["steps"], ne=s["num_elements"], others=others))
        shutil.rmtree(out)
        print(".", end="", file=sys.stderr, flush=True)
print(file=sys.stderr)

# NiftySim 2.5 on this machine kind (verification/reference/niftysim/README.md), us/element-step:
# 1 thread: stock float32 build 0.27, double build 0.22; 2-thread build (float32) 0.17.
nifty = {("f32", "1"): (0.27, "f32 build"), ("f64", "1"): (0.22, "double build"),
         ("f32", "2"): (0.17, "2-thread build"), ("f64", "2"): (0.17, "2-thread f32 build")}
print(f"timing_block20: {rows[0]['ne']} hexahedra, {rows[0]['steps']} iterations; "
      f"medians over {repeats} runs each")
print()
QUIET = 0.15  # a run is "quiet" when other processes used fewer CPUs than this
hdr = ("binary", "precision", "threads", "process wall s", "stepping s", "us/elem-step [min..max]",
       "Melem-upd/s", "other load", "quiet runs: us/elem-step (n)", "NiftySim us/elem-step",
       "NiftySim/ours")
print("| " + " | ".join(hdr) + " |")
print("|" + "---|" * len(hdr))
for binary, prec, th in configs:
    rs = [r for r in rows if (r["binary"], r["prec"], r["th"]) == (binary, prec, th)]
    per = [r["stepping"] / (r["steps"] * r["ne"]) * 1e6 for r in rs]
    us = statistics.median(per)
    ref = nifty.get((prec, th))
    refs = f"{ref[0]:.2f} ({ref[1]})" if ref else "-"
    ratio = f"{ref[0] / us:.2f}x" if ref else "-"
    quiet = [p for p, r in zip(per, rs) if r["others"] < QUIET]
    qs = f"{statistics.median(quiet):.4f} ({len(quiet)})" if quiet else "- (0)"
    print(f"| {binary} | {prec} | {th} | {statistics.median(r['wall'] for r in rs):.3f} "
          f"| {statistics.median(r['stepping'] for r in rs):.3f} "
          f"| {us:.4f} [{min(per):.4f}..{max(per):.4f}] | {1.0 / us:.2f} "
          f"| {statistics.median(r['others'] for r in rs):.2f} | {qs} | {refs} | {ratio} |")
print()
print("us/elem-step: stepping_time / (steps * elements) from summary.json (the stepping loop")
print("alone); process wall s: the whole process (read, precompute, stability check, output).")
print("other load: median CPUs kept busy by other processes during the runs (0 = quiet; on a")
print("2-core machine 1.0 leaves a 2-thread run one core); quiet runs: the median over the runs")
print(f"with other load < {QUIET} CPUs. NiftySim/ours (all runs' median) > 1: ours is faster.")
if len(labels) > 1:
    print()
    print("Side by side (same rounds): median us/elem-step of each binary over 'this' (> 1: 'this' is faster)")
    for prec in precisions.split():
        for th in threads.split():
            med = {b: statistics.median(r["stepping"] / (r["steps"] * r["ne"]) for r in rows
                                        if (r["binary"], r["prec"], r["th"]) == (b, prec, th))
                   for b in labels}
            others = ", ".join(f"{b} {med[b] / med['this']:.2f}x" for b in labels[1:])
            print(f"  {prec} {th} thread(s): {others}")
PYTHON
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
