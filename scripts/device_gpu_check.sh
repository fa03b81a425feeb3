#!/usr/bin/env bash
# The GPU checks of issue 6 on a machine with a real GPU, in one call of about 6 minutes, from
# the bundle that `scripts/device_bundle.sh` made (`.device/`: no Rust or network needed there).
#
#   bash scripts/device_gpu_check.sh     # results in $OUT (default ./device-results)
#
# 1. the GPU verification suite (`verification/gpu.rs`) with STICKY_LIPS_REQUIRE_GPU=1;
# 2. the paper's scene (paper/scenarios/table1.toml, the MakeHuman face: 3392 hexahedra, 100 000 steps, 1 s
#    simulated) through the CLI: GPU f32, GPU f64 (if the adapter has SHADER_F64) and the CPU
#    on 2 threads; wall and stepping times from each summary.json (target: GPU <= 1 s);
# 3. `benches/gpu.rs` (criterion) on blocks of 1k, 8k, 64k and 512k hexahedra and the mouth,
#    the CPU ids on 2 threads (RAYON_NUM_THREADS=2; targets: >= 1e9 element-updates/s at 512k,
#    >= 20x the CPU's 2-thread step).
# 4. scripts/gpu_bench_report.py: the table (time, element-updates/s, steps/s) and a verdict on
#    each target from 2. and 3. ("not measured" where a figure is missing).
# SIZES and SCENE_TIMEOUT (s, default 120) override for a dry run (e.g. on lavapipe).
# Each part has its own time limit and a failing part does not stop the others. At most 8
# files come back from $OUT: env.txt, verification_gpu.log, paper_scene.log, bench_gpu.log,
# report.md.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
B="$ROOT/.device"
R="${OUT:-$ROOT/device-results}"
mkdir -p "$R"
[ -x "$B/bin/sticky-lips" ] || { echo "no bundle at $B: run scripts/device_bundle.sh first" >&2; exit 2; }

# Vulkan: the machine's loader, else the bundled Debian one; NVIDIA's ICD where the image keeps it
if ! ldconfig -p | grep -q 'libvulkan.so.1'; then
  for f in "$B"/gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
NV_ICD=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$NV_ICD" ] && ! ls /usr/share/vulkan/icd.d/nvidia* >/dev/null 2>&1; then
  export VK_DRIVER_FILES="$NV_ICD"
fi
# the binaries read the checkout by the absolute path they were built in
MANIFEST=$(cat "$B/manifest_dir")
if [ "$MANIFEST" != "$ROOT" ] && [ ! -e "$MANIFEST" ]; then
  mkdir -p "$(dirname "$MANIFEST")" && ln -s "$ROOT" "$MANIFEST"
fi
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}" STICKY_LIPS_REQUIRE_GPU=1
export CRITERION_HOME=/tmp/criterion
rm -rf "$CRITERION_HOME" /tmp/scene-*  # a rerun on a warm machine reports this run only

{
  echo "bundle commit: $(cat "$B/commit")"
  date -u
  nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,memory.total --format=csv 2>&1
  lscpu 2>/dev/null | grep -E '^(Model name|CPU\(s\))'
  ldconfig -p | grep libvulkan
  echo "VK_DRIVER_FILES=${VK_DRIVER_FILES:-}"
} > "$R/env.txt" 2>&1
cat "$R/env.txt"

part() { printf '\n==> [%ss] %s\n' "$SECONDS" "$*"; }

part "GPU verification suite"
timeout 150 "$B/bin/verification" gpu:: --nocapture --test-threads 1 2>&1 |
  grep -av 'XDG_RUNTIME_DIR' | tee "$R/verification_gpu.log" | grep -a 'test result\|FAILED\|panicked'

part "the paper's scene through the CLI"
{
  for cfg in "gpu f32" "gpu f64" "cpu f64"; do
    set -- $cfg
    out="/tmp/scene-$1-$2"
    echo "--- sticky-lips run paper/scenarios/table1.toml --backend $1 --precision $2 --threads 2"
    start=$EPOCHREALTIME
    timeout "${SCENE_TIMEOUT:-120}" "$B/bin/sticky-lips" run paper/scenarios/table1.toml --out "$out" \
      --backend "$1" --precision "$2" --threads 2 --quiet 2>&1 | grep -av XDG_RUNTIME_DIR
    echo "process wall $(python3 -c "print(round($EPOCHREALTIME - $start, 3))") s"
    python3 - "$out/summary.json" <<'EOF'
import json, sys
try:
    s = json.load(open(sys.argv[1]))
except Exception as e:
    print("no summary:", e); sys.exit()
keep = {k: s[k] for k in s if any(w in k for w in ("step", "time", "updates", "frames", "backend", "precision", "threads"))
        and not isinstance(s[k], (list, dict))}
print(json.dumps(keep, indent=1))
EOF
  done
} 2>&1 | tee "$R/paper_scene.log"

part "criterion: benches/gpu.rs (CPU ids on 2 threads)"
RAYON_NUM_THREADS=2 STICKY_LIPS_BENCH_SIZES="${SIZES:-1000,8000,64000,512k,mouth}" \
  timeout 330 "$B/bin/bench-gpu" --bench 2>&1 | grep -av XDG_RUNTIME_DIR |
  grep -a -E 'gpu benchmarks on|SKIPPED|^[a-z_]+/|time:|thrpt:' | tee "$R/bench_gpu.log"

part "report: the issue-6 targets"
python3 scripts/gpu_bench_report.py "$CRITERION_HOME" --cpu-threads 2 \
  --scene /tmp/scene-gpu-f32 --scene /tmp/scene-gpu-f64 --scene /tmp/scene-cpu-f64 2>&1 | tee "$R/report.md"

part "done"
ls -la "$R"
