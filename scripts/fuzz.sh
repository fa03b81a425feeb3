#!/usr/bin/env bash
# The fuzz targets (fuzz/fuzz_targets/, libFuzzer through cargo-fuzz): every parser of the
# project's inputs fed with mutated inputs, starting from the committed corpus.
#
#   bash scripts/fuzz.sh              # each target for FUZZ_SECONDS (default 30) seconds (CI)
#   FUZZ_SECONDS=3600 bash scripts/fuzz.sh scenario_toml
#
# cargo-fuzz needs a nightly compiler's flags (-Zsanitizer); on the stable toolchain this
# project uses, RUSTC_BOOTSTRAP=1 unlocks them. New inputs found interesting go to a scratch
# corpus (target/fuzz-corpus/NAME), not into the committed one; a crash leaves its input in
# fuzz/artifacts/NAME/ and fails the script. To keep a find: add it to
# verification/catalogue/ with the message it must give, and to fuzz/corpus/NAME/.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH=${FUZZ_SECONDS:-30}
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(scenario_toml niftysim_xml obj vtu cli_values checkpoint keys rig_json sweep_spec lip_finder)
if ! command -v cargo-fuzz >/dev/null; then
  cargo install cargo-fuzz --locked --version 0.13.2
fi
export RUSTC_BOOTSTRAP=1
if ! cargo fuzz build -O -a; then
  echo "fuzz: FAILED: the fuzz targets did not build (cargo fuzz build -O -a)" >&2
  exit 1
fi
for t in "${TARGETS[@]}"; do
  scratch=target/fuzz-corpus/$t
  mkdir -p "$scratch" "fuzz/artifacts/$t"
  echo "== fuzz $t for $SECONDS_EACH s"
  # -rss_limit_mb: the targets cap models at 256 MiB (STICKY_LIPS_MEMORY_MB); -timeout: an
  # input that takes more than 10 s is reported as a hang.
  # Only libFuzzer's summary and error lines are shown (the `|| true` inside the braces: no
  # line matching is not a failure); the status that counts is cargo fuzz run's, which
  # pipefail makes the pipeline's: non-zero on a crash, a hang, an out-of-memory, a leak or a
  # build failure.
  rc=0
  cargo fuzz run -O -a "$t" "$scratch" "fuzz/corpus/$t" -- \
    -max_total_time="$SECONDS_EACH" -rss_limit_mb=2048 -timeout=10 \
    -max_len=65536 -print_final_stats=1 2>&1 |
    { grep -E "^(#[0-9]+ *DONE|stat::number_of_executed_units|stat::new_units_added|==|SUMMARY|Done)|panicked|ERROR|ALARM|Test unit written" || true; } ||
    rc=$?
  if [ "$rc" != 0 ]; then
    echo "fuzz $t: FAILED: cargo fuzz run exited with status $rc (a crash, a hang, out of memory, a leak or a build failure; the input, if one was saved, is in fuzz/artifacts/$t/)" >&2
    exit 1
  fi
  if ls "fuzz/artifacts/$t"/* >/dev/null 2>&1; then
    echo "fuzz $t: FAILED: crash inputs in fuzz/artifacts/$t" >&2
    exit 1
  fi
done
echo "fuzz: every target ran $SECONDS_EACH s without a crash"
