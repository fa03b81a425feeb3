#!/usr/bin/env bash
# Whole-process timing of NiftySim's timing block (verification/reference/niftysim/
# timing_block20.xml: 8000 hexahedra, 1001 iterations) with NiftySim itself and with ours, side
# by side, as in benches/README.md ("NiftySim's timing block against NiftySim itself"):
#
#   NiftySim:  niftysim_fXX -x timing_block20.xml            (writes no files)
#              1 thread: niftysim_f32 / niftysim_f64 (build.sh's stock builds);
#              2 threads: niftysim_f32_boost / niftysim_f64_boost (NiftySim's Boost threading:
#              boost::thread::hardware_concurrency() threads, so 2 threads on a 2-core machine)
#   ours:      target/release/sticky-lips run timing_block20.xml --niftysim-compat --quiet
#                  --threads T --precision P --out TMP     (writes its 11 frames; TMP removed)
#
# Each pair runs both processes in turn (the order alternates from pair to pair), one warm-up
# pair first, then PAIRS counted pairs for every configuration, configurations interleaved.
# Prints per configuration the median [min..max] wall time of each, the ratio ours/NiftySim
# taken pair by pair (median [min..max]) and NiftySim/ours = 1 / that median; also the median
# peak resident memory (measured with GNU time, /usr/bin/time, when it is installed).
#
#   scripts/niftysim/time_block.sh NIFTY_BIN_DIR            # NIFTY_BIN_DIR: build.sh's OUT_DIR/bin
#   scripts/niftysim/time_block.sh NIFTY_BIN_DIR --build    # cargo build --release first
#   NIFTY_ONLY=1 scripts/niftysim/time_block.sh NIFTY_BIN_DIR   # NiftySim alone (no sticky-lips)
#   env: PAIRS (default 7), PRECISIONS (default "f32 f64"), THREADS (default "1 2"),
#        WAIT_QUIET (s, default 10: wait up to this long for idle CPUs before each pair; 0: never),
#        NIFTY_TIMER=1 (add NiftySim's -t and report its stepping-loop time), BIN (ours,
#        default target/release/sticky-lips)
# Needs bash and python3 (standard library only).
set -euo pipefail

usage() {
    cat >&2 <<EOF
usage: $0 NIFTY_BIN_DIR [--build]
  NIFTY_BIN_DIR  folder with niftysim_f32, niftysim_f64 (and *_boost for 2 threads): build.sh's OUT_DIR/bin
  --build        run 'cargo build --release' first (otherwise target/release/sticky-lips must exist)
  env: PAIRS=7 PRECISIONS="f32 f64" THREADS="1 2" WAIT_QUIET=10 NIFTY_TIMER=0|1 NIFTY_ONLY=0|1 BIN=...
EOF
    exit 2
}
[[ $# -ge 1 && $# -le 2 ]] || usage
[[ $# -eq 1 || "$2" == "--build" ]] || usage
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
NBIN="$(cd "$1" 2>/dev/null && pwd)" || { echo "error: $1 is not a directory" >&2; exit 1; }
cd "$repo"

MODEL="verification/reference/niftysim/timing_block20.xml"
BIN="${BIN:-target/release/sticky-lips}"
PAIRS="${PAIRS:-7}"
PRECISIONS="${PRECISIONS:-f32 f64}"
THREADS="${THREADS:-1 2}"
WAIT_QUIET="${WAIT_QUIET:-10}"
NIFTY_TIMER="${NIFTY_TIMER:-0}"
NIFTY_ONLY="${NIFTY_ONLY:-0}"

if [[ "${2:-}" == "--build" ]]; then
    [[ "$NIFTY_ONLY" == 1 ]] && { echo "error: --build with NIFTY_ONLY=1 makes no sense" >&2; exit 2; }
    cargo build --release --bin sticky-lips
fi
[[ -f "$MODEL" ]] || { echo "error: $MODEL not found" >&2; exit 1; }

tmp="$(mktemp -d "${TMPDIR:-/tmp}/niftysim_time_block.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/bin"
# private copies, so that a rebuild cannot swap a binary in the middle of a series
for p in $PRECISIONS; do
    for t in $THREADS; do
        case "$t" in
            1) name="niftysim_$p" ;;
            2) name="niftysim_${p}_boost" ;;
            *) echo "error: THREADS may hold 1 and 2 (NiftySim's Boost build takes all cores)" >&2; exit 2 ;;
        esac
        [[ -x "$NBIN/$name" ]] || { echo "error: $NBIN/$name not found (build.sh builds the *_boost ones when libboost-thread-dev is installed)" >&2; exit 1; }
        cp "$NBIN/$name" "$tmp/bin/$name"
    done
done
if [[ "$NIFTY_ONLY" != 1 ]]; then
    if [[ ! -x "$BIN" ]]; then
        echo "error: $BIN not found: build it with 'cargo build --release' or pass --build (or NIFTY_ONLY=1)" >&2
        exit 1
    fi
    cp "$BIN" "$tmp/bin/sticky-lips"
    echo "ours:     $BIN ($(date -r "$BIN" '+%Y-%m-%d %H:%M:%S'))"
fi
echo "NiftySim: $NBIN"
[[ -f "$NBIN/BUILD_INFO" ]] && grep -E '^(commit|compiler|flags) ' "$NBIN/BUILD_INFO" | sed 's/^/          /'
echo "model:    $MODEL"
echo "machine:  $(nproc) cores, $(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n1)"
echo "date:     $(date '+%Y-%m-%d %H:%M:%S %Z'); load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "pairs:    1 warm-up + $PAIRS counted, precision {${PRECISIONS// /,}} x threads {${THREADS// /,}}; WAIT_QUIET=$WAIT_QUIET s"
if [[ " $THREADS " == *" 2 "* && "$(nproc)" != 2 ]]; then
    echo "note:     NiftySim's Boost build runs $(nproc) threads here (hardware_concurrency), not 2"
fi
echo

python3 - "$tmp" "$MODEL" "$PAIRS" "$PRECISIONS" "$THREADS" "$WAIT_QUIET" "$NIFTY_TIMER" "$NIFTY_ONLY" <<'PYTHON'
import os, re, shutil, statistics, subprocess, sys, time

tmp, model, pairs, precisions, threads, wait_quiet, nifty_timer, nifty_only = sys.argv[1:]
pairs, wait_quiet = int(pairs), float(wait_quiet)
nifty_timer, nifty_only = nifty_timer == "1", nifty_only == "1"
configs = [(p, t) for p in precisions.split() for t in threads.split()]
model = os.path.abspath(model)
tick = os.sysconf("SC_CLK_TCK")


def busy_jiffies():
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return sum(v) - v[3] - v[4]


def total_jiffies():
    with open("/proc/stat") as f:
        return sum(int(x) for x in f.readline().split()[1:])


def wait_until_quiet(limit):
    """Waits (at most `limit` s) until the CPUs are < 5 % busy over 1 s."""
    t0 = time.time()
    while time.time() - t0 < limit:
        b0, a0 = busy_jiffies(), total_jiffies()
        time.sleep(1)
        b1, a1 = busy_jiffies(), total_jiffies()
        if (b1 - b0) < 0.05 * max(1, a1 - a0):
            return


# Peak resident memory: the ru_maxrss that wait4 reports for a child of this script includes the
# pages of the python process it was forked from (about 14 MiB), so it is measured by GNU time,
# a small parent, when /usr/bin/time is installed (otherwise not reported).
GNU_TIME = "/usr/bin/time" if os.access("/usr/bin/time", os.X_OK) else None


def run(argv, cwd):
    """(wall s, peak resident MiB or None, stdout) of one whole process; appends the CPUs other
    processes kept busy meanwhile to `others`."""
    rss_file = os.path.join(tmp, "rss")
    if GNU_TIME:
        argv = [GNU_TIME, "-f", "%M", "-o", rss_file] + argv
    with open(os.path.join(tmp, "stdout"), "w+b") as fo, open(os.path.join(tmp, "stderr"), "w+b") as fe:
        b0 = busy_jiffies()
        t0 = time.perf_counter()
        proc = subprocess.Popen(argv, cwd=cwd, stdout=fo, stderr=fe)
        _, status, ru = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        b1 = busy_jiffies()
        own = (ru.ru_utime + ru.ru_stime) * tick
        others.append(max(0.0, (b1 - b0) - own) / tick / wall)
        proc.returncode = os.waitstatus_to_exitcode(status)
        fo.seek(0)
        fe.seek(0)
        out, err = fo.read().decode(), fe.read().decode()
    if proc.returncode != 0:
        sys.exit(f"error: {' '.join(argv)} failed ({proc.returncode}):\n{err[-2000:]}")
    rss = None
    if GNU_TIME:
        with open(rss_file) as f:
            rss = int(f.read().split()[-1]) / 1024.0
    return wall, rss, out


def nifty(prec, th, cwd):
    name = f"niftysim_{prec}" + ("_boost" if th == "2" else "")
    argv = [os.path.join(tmp, "bin", name), "-x", model] + (["-t"] if nifty_timer else [])
    wall, rss, out = run(argv, cwd)
    ms = None
    if nifty_timer:
        m = re.search(r"Execution time:\s*([0-9.eE+-]+)\s*ms", out)
        ms = float(m.group(1)) if m else None
    return wall, rss, ms


def ours(prec, th, cwd):
    dest = os.path.join(tmp, "ours_out")
    argv = [os.path.join(tmp, "bin", "sticky-lips"), "run", model, "--niftysim-compat", "--quiet",
            "--threads", th, "--precision", prec, "--out", dest]
    wall, rss, _ = run(argv, cwd)
    shutil.rmtree(dest, ignore_errors=True)
    return wall, rss


others = []
cwd = os.path.join(tmp, "cwd")
os.makedirs(cwd)
rows = {c: [] for c in configs}
for k in range(pairs + 1):  # k == 0: the warm-up pair
    for prec, th in configs:
        if wait_quiet > 0:
            wait_until_quiet(wait_quiet)
        if nifty_only:
            n = nifty(prec, th, cwd)
            o = None
        elif k % 2 == 0:
            n = nifty(prec, th, cwd)
            o = ours(prec, th, cwd)
        else:
            o = ours(prec, th, cwd)
            n = nifty(prec, th, cwd)
        if k > 0:
            rows[(prec, th)].append((n, o))
        print("." if k > 0 else "w", end="", file=sys.stderr, flush=True)
print(file=sys.stderr)
if os.listdir(cwd):
    print(f"note: files written in the working directory: {os.listdir(cwd)}")


def med_rss(xs):
    xs = [x for x in xs if x is not None]
    return f"{statistics.median(xs):.1f}" if xs else "-"


def mmm(xs, f="{:.3f}"):
    return f"{f.format(statistics.median(xs))} [{f.format(min(xs))}..{f.format(max(xs))}]"


print(f"timing_block20, whole processes, {pairs} counted pairs per row")
print()
if nifty_only:
    hdr = ["precision", "threads", "NiftySim, wall s median [min..max]", "NiftySim peak RSS MiB"]
else:
    hdr = ["precision", "threads", "ours, wall s median [min..max]", "NiftySim, wall s median [min..max]",
           "ours / NiftySim (wall), median [min..max]", "NiftySim / ours", "peak RSS MiB, ours / NiftySim"]
if nifty_timer:
    hdr.append("NiftySim -t loop ms, median")
print("| " + " | ".join(hdr) + " |")
print("|" + "---|" * len(hdr))
for prec, th in configs:
    rs = rows[(prec, th)]
    n = [r[0][0] for r in rs]
    n_rss = med_rss(r[0][1] for r in rs)
    cells = [prec, th]
    if not nifty_only:
        o = [r[1][0] for r in rs]
        o_rss = med_rss(r[1][1] for r in rs)
        ratio = [b / a for a, b in zip(n, o)]
        cells += [mmm(o), mmm(n), mmm(ratio), f"{1.0 / statistics.median(ratio):.2f}x",
                  f"{o_rss} / {n_rss}"]
    else:
        cells += [mmm(n), n_rss]
    if nifty_timer:
        ms = [r[0][2] for r in rs if r[0][2] is not None]
        cells.append(f"{statistics.median(ms):.0f}" if ms else "-")
    print("| " + " | ".join(cells) + " |")
print()
print(f"other load: median {statistics.median(others):.2f} CPUs [max {max(others):.2f}] kept busy by other processes during the runs (0 = quiet)")
print("ours / NiftySim: the ratio of the two wall times of each pair; NiftySim / ours = 1 / its median.")
PYTHON
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
