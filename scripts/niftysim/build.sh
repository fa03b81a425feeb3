#!/usr/bin/env bash
# Builds NiftySim's CPU solver from a source checkout, the way benches/README.md describes it
# ("NiftySim's timing block against NiftySim itself"):
#
#   the C++ files of NiftySim's own CMake list for a build without CUDA (source/CMakeLists.txt,
#   the ELSE(USE_CUDA) branch), source/niftysim.cpp and xmlParser/xmlParser.cpp, compiled with
#   g++ -std=gnu++98 -O3 -DNDEBUG -D_CMAKE_USED   (what its CMake files set for a Release build
#   with USE_CUDA, USE_VIZ and USE_BOOST off), no CUDA or VTK file.
#
#   scripts/niftysim/build.sh SRC_DIR OUT_DIR
#       SRC_DIR: a checkout of https://github.com/eloygarcia/niftysim (commit 999051dd recorded)
#       OUT_DIR: where the objects and binaries go (created)
#   env: JOBS (parallel compiles, default: number of CPUs), CXX (default g++),
#        BOOST=auto|yes|no (the two-thread builds; auto: when boost/thread.hpp is installed)
#
# Binaries written to OUT_DIR/bin:
#   niftysim_f32            stock build (NiftySim's real type is float)
#   niftysim_f64            the same sources with `float` redefined as `double` by a header that
#                           this script writes (OUT_DIR/niftysim_as_double.h) and passes with
#                           -include, so it comes before any line of NiftySim
#   niftysim_f32_print17,   as above, except that two printing functions print all digits:
#   niftysim_f64_print17    in copies of tledSolverCPU.cpp and tledSolver.cpp, the "%+10.5e"
#                           of `-print ND|NF|LNF|LNFS` becomes "%.17g" and the energies of
#                           `-print EK|ES` are printed with 17 significant digits instead of
#                           std::fixed with 6 decimals. Nothing that computes is changed.
#                           regenerate.sh uses these.
#   niftysim_f32_boost,     NiftySim's own CPU threading (-D_USE_BOOST_, linked with
#   niftysim_f64_boost      boost_thread/boost_date_time; it threads models over 1024 elements
#                           on boost::thread::hardware_concurrency() threads). Only when
#                           Boost.Thread is installed (Debian: apt-get install libboost-thread-dev).
#
# Needs: bash, g++ (12 was used), awk, sha256sum; git only to print the commit.
set -euo pipefail

usage() {
    cat >&2 <<EOF
usage: $0 SRC_DIR OUT_DIR
  SRC_DIR  NiftySim source checkout (has source/CMakeLists.txt and xmlParser/xmlParser.cpp)
  OUT_DIR  output folder; binaries land in OUT_DIR/bin
  env: JOBS=N  CXX=g++  BOOST=auto|yes|no
EOF
    exit 2
}
[[ $# -eq 2 ]] || usage
SRC="$(cd "$1" 2>/dev/null && pwd -P)" || { echo "error: $1 is not a directory" >&2; exit 1; }
for f in source/CMakeLists.txt source/niftysim.cpp xmlParser/xmlParser.cpp; do
    [[ -f "$SRC/$f" ]] || { echo "error: $SRC/$f not found: not a NiftySim checkout" >&2; exit 1; }
done
mkdir -p "$2"
OUT="$(cd "$2" && pwd -P)"
CXX="${CXX:-g++}"
JOBS="${JOBS:-$(nproc)}"
BOOST="${BOOST:-auto}"
RECORDED_COMMIT=999051dd

# ---- which commit --------------------------------------------------------------------------
commit="unknown (not a git checkout)"
# (only when SRC_DIR is the top of its own git tree, not a folder inside another repository)
if [[ "$(git -C "$SRC" rev-parse --show-toplevel 2>/dev/null || true)" == "$SRC" ]] &&
    git -C "$SRC" rev-parse --verify -q HEAD >/dev/null 2>&1; then
    commit="$(git -C "$SRC" rev-parse HEAD)"
    if [[ -n "$(git -C "$SRC" status --porcelain --untracked-files=no 2>/dev/null)" ]]; then
        commit="$commit (with local changes)"
    fi
fi
echo "NiftySim source: $SRC"
echo "commit:          $commit"
if [[ "$commit" != "$RECORDED_COMMIT"* ]]; then
    echo "warning: the recorded reference build used commit $RECORDED_COMMIT" >&2
fi
echo "compiler:        $($CXX --version | head -n1)"

# ---- the file list: NiftySim's CMake list for a build without CUDA --------------------------
# In source/CMakeLists.txt, after `ELSE(USE_CUDA)`, the names between
# `SET( CPP_SOURCE_FILES_WITH_HEADERS` and the closing `)` (each NAME means NAME.cpp).
mapfile -t names < <(awk '
    /^ELSE *\( *USE_CUDA *\)/ { in_else = 1; next }
    in_else && /SET *\( *CPP_SOURCE_FILES_WITH_HEADERS/ { in_list = 1; next }
    in_list && /^[ \t]*\)/ { exit }
    in_list { sub(/#.*/, ""); for (i = 1; i <= NF; i++) print $i }
' "$SRC/source/CMakeLists.txt")
if [[ ${#names[@]} -lt 50 ]]; then
    echo "error: could not read the CPU file list from $SRC/source/CMakeLists.txt (${#names[@]} names)" >&2
    exit 1
fi
sources=()
for n in "${names[@]}"; do
    [[ -f "$SRC/source/$n.cpp" ]] || { echo "error: $SRC/source/$n.cpp (listed in CMakeLists.txt) not found" >&2; exit 1; }
    sources+=("source/$n.cpp")
done
sources+=("source/niftysim.cpp" "xmlParser/xmlParser.cpp")
echo "sources:         ${#sources[@]} .cpp files (${#names[@]} of the CMake CPU list + niftysim.cpp + xmlParser.cpp)"

BASEFLAGS=(-std=gnu++98 -O3 -DNDEBUG -D_CMAKE_USED -I"$SRC/source" -I"$SRC/xmlParser")
echo "flags:           ${BASEFLAGS[*]:0:4}"

# ---- Boost ---------------------------------------------------------------------------------
have_boost=no
if echo '#include <boost/thread.hpp>
#include <boost/date_time/posix_time/posix_time.hpp>
int main() { return boost::thread::hardware_concurrency() > 0 ? 0 : 1; }' |
    "$CXX" -x c++ - -o "$OUT/.boost_probe" -lboost_thread -lboost_date_time -lpthread >/dev/null 2>&1; then
    have_boost=yes
fi
rm -f "$OUT/.boost_probe"
case "$BOOST" in
    auto) do_boost=$have_boost ;;
    yes) [[ $have_boost == yes ]] || { echo "error: BOOST=yes but Boost.Thread is not usable (apt-get install libboost-thread-dev)" >&2; exit 1; }
         do_boost=yes ;;
    no) do_boost=no ;;
    *) usage ;;
esac
echo "boost builds:    $do_boost"

# ---- the double-precision header -----------------------------------------------------------
# NiftySim has no precision switch: every real is `float`. This header, included before every
# translation unit, first includes the standard (and Boost) headers NiftySim uses, so that they
# are parsed with their own `float`, then declares std::min/std::max for a double and a float
# (after the redefinition, a call such as std::min(x, 1.0f) has a double and a float argument,
# which the standard templates cannot deduce), and finally defines the macro.
# Generated files are replaced only when their text changes, so that a second run of this
# script recompiles nothing that is up to date.
replace_if_changed() {  # replace_if_changed FILE: stdin becomes FILE's text
    cat >"$1.new"
    if cmp -s "$1.new" "$1" 2>/dev/null; then rm -f "$1.new"; else mv "$1.new" "$1"; fi
}
HDR="$OUT/niftysim_as_double.h"
replace_if_changed "$HDR" <<'EOF'
/* Written by sticky-lips scripts/niftysim/build.sh: compiles NiftySim with double as its real
 * type. Passed to g++ with -include, so it precedes every line of NiftySim. */
#ifndef NIFTYSIM_AS_DOUBLE_H
#define NIFTYSIM_AS_DOUBLE_H
#ifdef __cplusplus
/* 1. Every standard header NiftySim includes, parsed while `float` is still float. */
#include <algorithm>
#include <cassert>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <deque>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stack>
#include <string>
#include <typeinfo>
#include <utility>
#include <vector>
#include <float.h>
#include <math.h>
#include <memory.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>
#include <wctype.h>
#if defined __GNUC__ && !defined __llvm__ && !defined __GXX_EXPERIMENTAL_CXX0X__
#include <tr1/unordered_map> /* tledHelper.h's hash map in C++98 mode */
#endif
#ifdef _USE_BOOST_
#include <boost/thread.hpp>
#include <boost/date_time/posix_time/posix_time.hpp>
#endif
/* 2. std::min/std::max of a double and a float (a float literal such as 1.0f stays float). */
namespace std {
inline double min(double a, float b) { return b < a ? double(b) : a; }
inline double min(float a, double b) { return b < double(a) ? b : double(a); }
inline double max(double a, float b) { return a < b ? double(b) : a; }
inline double max(float a, double b) { return double(a) < b ? b : double(a); }
}
/* 3. The real type. */
#define float double
#endif
#endif
EOF

# ---- the print patch (the *_print17 binaries) ----------------------------------------------
PATCHED="$OUT/print17"
mkdir -p "$PATCHED"
sed 's/%+10\.5e/%.17g/g' "$SRC/source/tledSolverCPU.cpp" | replace_if_changed "$PATCHED/tledSolverCPU.cpp"
sed 's/cout\.setf(ios::fixed, ios::floatfield);/cout.unsetf(ios::floatfield); cout.precision(17);/' \
    "$SRC/source/tledSolver.cpp" | replace_if_changed "$PATCHED/tledSolver.cpp"
n1=$(grep -c '%\.17g' "$PATCHED/tledSolverCPU.cpp" || true)
n2=$(grep -c 'cout.precision(17)' "$PATCHED/tledSolver.cpp" || true)
if [[ $n1 -lt 5 || $n2 -ne 2 ]]; then
    echo "error: the print patch did not apply (tledSolverCPU.cpp: $n1 lines, tledSolver.cpp: $n2)" >&2
    exit 1
fi
echo "print17 patch:   $n1 printf lines in tledSolverCPU.cpp, 2 energy prints in tledSolver.cpp"
echo "                 (diff -u $SRC/source/tledSolverCPU.cpp $PATCHED/tledSolverCPU.cpp)"

# ---- compile -------------------------------------------------------------------------------
# compile VARIANT EXTRA_FLAGS...: every source into OUT/obj-VARIANT/, JOBS at a time.
compile() {
    local variant="$1"; shift
    local objdir="$OUT/obj-$variant"
    mkdir -p "$objdir"
    { printf '%s\n' "${BASEFLAGS[@]}" "$@"; echo "$SRC_HASH"; sha256sum "$HDR" "$PATCHED"/*.cpp | cut -c1-64; } >"$objdir/flags.new"
    # a change of flags, of any source or header file, or of the generated files rebuilds everything
    if ! cmp -s "$objdir/flags.new" "$objdir/flags" 2>/dev/null; then rm -f "$objdir"/*.o; fi
    mv "$objdir/flags.new" "$objdir/flags"
    local list=("${sources[@]}")
    list+=("@print17/tledSolverCPU.cpp" "@print17/tledSolver.cpp")
    printf '%s\n' "${list[@]}" | xargs -P "$JOBS" -I{} bash -c '
        set -euo pipefail
        f="$1"; objdir="$2"; src="$3"; out="$4"; shift 4
        if [[ "$f" == @print17/* ]]; then in="$out/print17/${f#@print17/}"; o="$objdir/print17_$(basename "${f%.cpp}").o"
        else in="$src/$f"; o="$objdir/$(basename "${f%.cpp}").o"; fi
        if [[ -f "$o" && "$o" -nt "$in" ]]; then exit 0; fi
        if ! "$CXX" "$@" -c "$in" -o "$o.tmp" 2>"$o.log"; then
            echo "error: compiling $in failed:" >&2; cat "$o.log" >&2; exit 255
        fi
        mv "$o.tmp" "$o"
    ' _ {} "$objdir" "$SRC" "$OUT" "${BASEFLAGS[@]}" "$@"
    echo "  compiled $variant ($(ls "$objdir"/*.o | wc -l) objects)"
}
# link NAME VARIANT PRINT17(yes|no) LIBS...
link() {
    local name="$1" variant="$2" print17="$3"; shift 3
    local objdir="$OUT/obj-$variant" objs=() o
    for o in "$objdir"/*.o; do
        case "$(basename "$o")" in
            print17_*) [[ $print17 == yes ]] && objs+=("$o") ;;
            tledSolverCPU.o|tledSolver.o) [[ $print17 == yes ]] || objs+=("$o") ;;
            *) objs+=("$o") ;;
        esac
    done
    "$CXX" -O3 "${objs[@]}" -o "$OUT/bin/$name" "$@"
    echo "  linked  bin/$name"
}
SRC_HASH="$(cd "$SRC" && find source xmlParser -type f \( -name '*.cpp' -o -name '*.h' -o -name '*.tpp' \) | LC_ALL=C sort | xargs sha256sum | sha256sum | cut -c1-64)"
export CXX
mkdir -p "$OUT/bin"
t0=$SECONDS
compile f32
link niftysim_f32 f32 no
link niftysim_f32_print17 f32 yes
compile f64 -include "$HDR"
link niftysim_f64 f64 no
link niftysim_f64_print17 f64 yes
if [[ $do_boost == yes ]]; then
    compile f32-boost -D_USE_BOOST_
    link niftysim_f32_boost f32-boost no -lboost_thread -lboost_date_time -lpthread
    compile f64-boost -D_USE_BOOST_ -include "$HDR"
    link niftysim_f64_boost f64-boost no -lboost_thread -lboost_date_time -lpthread
fi

# ---- record what was built -----------------------------------------------------------------
{
    echo "commit $commit"
    echo "source $SRC"
    echo "compiler $($CXX --version | head -n1)"
    echo "flags ${BASEFLAGS[*]:0:4}"
    echo "sources ${#sources[@]}"
    echo "boost $do_boost"
    echo "date $(date -u '+%Y-%m-%dT%H:%M:%SZ')"
    echo "sources_sha256 $(cd "$SRC" && sha256sum "${sources[@]}" | sha256sum | cut -c1-16)"
} >"$OUT/bin/BUILD_INFO"
echo "built in $((SECONDS - t0)) s: $(cd "$OUT/bin" && ls niftysim_* | tr '\n' ' ')"
echo "build record: $OUT/bin/BUILD_INFO"
