#!/usr/bin/env bash
# Prepares `.device/` (git-ignored): what `scripts/device_gpu_check.sh` needs on a machine with
# a GPU that has no Rust toolchain and no network (this workplace's `device` tool; any Linux
# x86-64 machine with a Vulkan driver will do).
#
#   bash scripts/device_bundle.sh        # here, with Rust and network
#   # then, on the GPU machine, in a copy of this checkout with .device/ beside it:
#   bash scripts/device_gpu_check.sh     # results under $OUT (default ./device-results)
#
# It holds stripped builds of the CLI (release), the GPU benchmark (bench profile) and the
# verification suite (test profile) and the Vulkan loader packages (Debian's libvulkan1 and
# friends, unpacked there only if the machine lacks a loader). The NiftySim reference data the
# suite reads is part of the checkout (verification/reference/niftysim).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
B="$ROOT/.device"
rm -rf "$B"
mkdir -p "$B/bin" "$B/gl"

exe_of() { # the test or bench executable cargo built, from its JSON messages
  python3 -c '
import json, sys
want = sys.argv[1]
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == want and m.get("executable"):
        print(m["executable"])
' "$1"
}

echo "==> building (release CLI, bench profile gpu benchmark, test profile verification suite)"
cargo build --release --quiet
cp target/release/sticky-lips "$B/bin/sticky-lips"
bench=$(cargo bench --bench gpu --no-run --message-format=json 2>/dev/null | exe_of gpu)
cp "$bench" "$B/bin/bench-gpu"
tests=$(cargo test --test verification --no-run --message-format=json 2>/dev/null | exe_of verification)
cp "$tests" "$B/bin/verification"
strip "$B"/bin/*

# the binaries name files by the checkout's absolute path (env!("CARGO_MANIFEST_DIR"))
echo "$ROOT" > "$B/manifest_dir"
git rev-parse HEAD > "$B/commit"
git diff --quiet HEAD || echo "(with uncommitted changes)" >> "$B/commit"

echo "==> Vulkan loader packages (apt-get download, amd64)"
mkdir -p /tmp/amd64-lists/partial
o="-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64-lists"
# shellcheck disable=SC2086
apt-get $o update -qq
# shellcheck disable=SC2086
(cd "$B/gl" && apt-get $o download -qq libvulkan1)

du -sh "$B" "$B"/* "$B"/bin/*
echo "bundle ready: $B (commit $(head -1 "$B/commit"))"
