#!/usr/bin/env bash
# Mutation testing of the physics with cargo-mutants (crates.io): every mutant of the named
# files is built and tested; a mutant no test fails is "missed". The equivalent mutants (no
# test can tell them apart from the code) are listed with their reasons in
# verification/README.md.
#
#   bash scripts/mutants.sh                      # the saliva files, tested by the saliva tests
#   MUTANTS_FILES="src/tled/node_update.rs" MUTANTS_TESTS="tled:: time_integration" bash scripts/mutants.sh
#   bash scripts/mutants.sh --iterate            # only the mutants not caught last time
#
# MUTANTS_FILES: the files to mutate; MUTANTS_TESTS: test-name filters (space-separated, a test
# runs when its name contains one of them) for the unit tests and the verification target
# (empty: all of them). Mutants build with the `mutants` profile
# (opt-level 1, no debug info, no GPU feature: a mutant rebuilds in seconds). Results:
# target/mutants-out/mutants.out/{caught,missed,unviable,timeout}.txt, archived under
# verification/mutants/DATE_FILES/ (commit it with the tests it led to).
set -euo pipefail
cd "$(dirname "$0")/.."
FILES=${MUTANTS_FILES:-"src/material/saliva.rs src/tled/saliva_forces.rs"}
FILTER=${MUTANTS_TESTS-saliva}
if ! command -v cargo-mutants >/dev/null; then
  cargo install cargo-mutants --locked --version 27.1.0
fi
# one target directory for the copies cargo-mutants builds in: the dependencies are built once
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target}
args=()
for f in $FILES; do args+=(-f "$f"); done
filter=()
# shellcheck disable=SC2206
[ -n "$FILTER" ] && filter=(-- $FILTER)
mkdir -p target/mutants-out
started=$(date -u +%Y-%m-%dT%H:%M:%SZ)
# what the run mutates: the commit now, and whether the tree differs from it (cargo-mutants
# copies the tree as it is at the start)
commit=$(git rev-parse HEAD)
changed=()
[ -n "$(git status --porcelain --untracked-files=no)" ] && changed=(--tree-changed)
set +e
cargo mutants --profile mutants --no-default-features --features equilibrium "${args[@]}" "$@" \
  --output target/mutants-out --timeout 300 \
  -- --lib --test verification "${filter[@]}"
rc=$?
set -e
# Archive the outcome (verification/mutants/, committed): the command, cargo-mutants' version,
# the commit and machine, cargo-mutants' own outcomes.json, and per file the counts of caught,
# missed, unviable and timed-out mutants (scripts/mutants_archive.py; the table in
# verification/README.md is made from these archives by `python3 scripts/mutants_archive.py --table`).
# cargo-mutants exits 0 when every mutant was caught, 2 when some were missed, 3 on timeouts:
# all are outcomes worth keeping; anything else (a build that failed before testing) is not.
if [ "$rc" = 0 ] || [ "$rc" = 2 ] || [ "$rc" = 3 ]; then
  python3 scripts/mutants_archive.py target/mutants-out/mutants.out \
    --started "$started" --commit "$commit" "${changed[@]}" --version "$(cargo mutants --version)" \
    --command "MUTANTS_FILES=\"$FILES\" MUTANTS_TESTS=\"$FILTER\" bash scripts/mutants.sh $*"
fi
exit "$rc"
