#!/bin/sh
# run.sh - build the libFuzzer harnesses with clang and run each one.
#
#   tests/fuzz/run.sh [EXECUTIONS] [--build-dir DIR] [--jobs N] [--trace]
#                     [--fork N] [HARNESS...]
#
# EXECUTIONS (default 20000) is passed to each harness as -runs.  The
# harnesses and the engine and command-line sources they need are compiled
# with -fsanitize=fuzzer,address,undefined into DIR (default: build-fuzz in
# the source tree, or $SAGITTA_FUZZ_BUILD); every UBSan finding aborts.  Each
# harness runs on a fresh copy of its seed corpus in tests/fuzz/corpus, so
# the seeds stay as committed.  A crash, leak, sanitizer report or timeout
# leaves its input in DIR/artifacts and makes the script exit 1.  Without a
# clang that can link -fsanitize=fuzzer the script exits 77 (skipped), or 1
# when CI is set (CI=true): in CI a missing tool fails.
# --trace also traces the designs fuzz_design reads (SAGITTA_FUZZ_TRACE=1).
# --fork N runs N worker processes that go on after a crash, for long runs
# that collect every distinct finding (libFuzzer -fork, -ignore_crashes).
# The runs use a fixed -seed, so a smoke run is repeatable.
set -u

here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
runs=20000
build=${SAGITTA_FUZZ_BUILD:-$root/build-fuzz}
jobs=2
harnesses=""
fork=0
seed=${SAGITTA_FUZZ_SEED:-1}

while [ $# -gt 0 ]; do
    case $1 in
    --build-dir) build=$2; shift 2 ;;
    --build-dir=*) build=${1#*=}; shift ;;
    --jobs) jobs=$2; shift 2 ;;
    --jobs=*) jobs=${1#*=}; shift ;;
    --trace) export SAGITTA_FUZZ_TRACE=1; shift ;;
    --fork) fork=$2; shift 2 ;;
    --fork=*) fork=${1#*=}; shift ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    [0-9]*) runs=$1; shift ;;
    fuzz_*) harnesses="$harnesses $1"; shift ;;
    *) echo "run.sh: unknown argument $1" >&2; exit 2 ;;
    esac
done
[ -n "$harnesses" ] || harnesses="fuzz_design fuzz_csvrays fuzz_args fuzz_zmx fuzz_zar"

CC=${FUZZ_CC:-clang}
mkdir -p "$build/obj" "$build/artifacts" || exit 1

# A clang whose libFuzzer runtime is missing cannot run anything here.
if ! command -v "$CC" >/dev/null 2>&1 ||
   ! "$CC" -fsanitize=fuzzer "$here/probe.c" -o "$build/probe" >/dev/null 2>&1; then
    case ${CI:-} in
    ''|0|false|no)
        echo "run.sh: $CC cannot link -fsanitize=fuzzer; fuzzing skipped"
        exit 77 ;;
    esac
    echo "run.sh: $CC cannot link -fsanitize=fuzzer; CI=$CI, so this fails" >&2
    exit 1
fi

# The one configuration header the sources need, as meson would write it.
cat > "$build/sg_config.h.new" <<EOF
#pragma once
#define SG_SOURCE_LENSDB "$root/lensdb"
#define SG_INSTALL_LENSDB "/usr/local/share/sagitta/lensdb"
#define SG_SOURCE_EXAMPLES "$root/examples"
#define SG_INSTALL_EXAMPLES "/usr/local/share/sagitta/examples"
#define SG_INSTALL_DATADIR "/usr/local/share/sagitta"
#define SG_INSTALL_BINDIR "/usr/local/bin"
#define SG_INSTALL_LIBDIR "/usr/local/lib"
#define SG_BUILD_ROOT "$root"
EOF
if cmp -s "$build/sg_config.h.new" "$build/sg_config.h"; then
    rm -f "$build/sg_config.h.new"
else
    mv "$build/sg_config.h.new" "$build/sg_config.h"
fi

# The engine's directories are all on the include path, as src/meson.build
# puts them.
srcinc=""
for d in "$root"/src/*/; do
    srcinc="$srcinc -I${d%/}"
done
cflags="-std=c11 -D_POSIX_C_SOURCE=200809L -O1 -g -fno-omit-frame-pointer
 -ffp-contract=off -fno-math-errno -fno-sanitize-recover=all
 -I$build -I$root/src$srcinc -I$root/ui $(pkg-config --cflags hdf5) $(pkg-config --cflags gsl)"
cflags_lib="$cflags -fsanitize=fuzzer-no-link,address,undefined"
libs="-lcjson -lfftw3 -lmpfr -lgmp -lm -lpthread $(pkg-config --libs hdf5) $(pkg-config --libs gsl)"

# ui/numfmt.c's power-of-ten table, made as meson makes it.
if [ ! -f "$build/numfmt_pow10.h" ] || [ "$root/ui/gen_pow10.c" -nt "$build/numfmt_pow10.h" ]; then
    if ! $CC -O1 "$root/ui/gen_pow10.c" -o "$build/gen_pow10" -lgmp ||
       ! "$build/gen_pow10" "$build/numfmt_pow10.h"; then
        echo "run.sh: generating numfmt_pow10.h failed" >&2
        exit 1
    fi
fi

# Compiles src/*/*.c and the command-line modules once, rebuilding an object
# when its source or any header is newer.
newest_header=$(ls -t "$root"/src/*.h "$root"/src/*/*.h "$root"/ui/*.h "$build/sg_config.h" | head -n 1)
objs=""
pids=""
n=0
status=0
for src in "$root"/src/*/*.c "$root"/ui/args.c "$root"/ui/csvrays.c "$root"/ui/report.c \
           "$root"/ui/outfile.c "$root"/ui/safetext.c "$root"/ui/progress.c \
           "$root"/ui/numfmt.c "$root"/ui/h5rays.c "$root"/ui/h5util.c \
           "$root"/ui/cli.c; do
    dir=$(basename "$(dirname "$src")")
    obj="$build/obj/$dir-$(basename "$src" .c).o"
    objs="$objs $obj"
    if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ "$newest_header" -nt "$obj" ]; then
        # shellcheck disable=SC2086
        $CC $cflags_lib -c "$src" -o "$obj" &
        pids="$pids $!"
        n=$((n + 1))
        if [ "$n" -ge "$jobs" ]; then
            for p in $pids; do wait "$p" || status=1; done
            pids=""
            n=0
        fi
    fi
done
for p in $pids; do wait "$p" || status=1; done
if [ "$status" -ne 0 ]; then
    echo "run.sh: compiling the sources failed" >&2
    exit 1
fi

for h in $harnesses; do
    if [ ! -f "$build/$h" ] || [ "$here/$h.c" -nt "$build/$h" ] ||
       [ -n "$(find "$build/obj" -newer "$build/$h" -name '*.o' | head -n 1)" ]; then
        # shellcheck disable=SC2086
        $CC $cflags -fsanitize=fuzzer,address,undefined "$here/$h.c" $objs $libs \
            -o "$build/$h" || { echo "run.sh: building $h failed" >&2; exit 1; }
    fi
done

# Runs every harness; the glass catalog is the source tree's.
export SAGITTA_LENSDB="${SAGITTA_LENSDB:-$root/lensdb}"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}"
failed=0
summary=""
for h in $harnesses; do
    work="$build/corpus-run/$h"
    rm -rf "$work"
    mkdir -p "$work"
    cp "$here/corpus/$h/"* "$work/" 2>/dev/null
    opts=""
    [ -f "$here/$h.dict" ] && opts="-dict=$here/$h.dict"
    [ "$fork" -gt 0 ] && opts="$opts -fork=$fork -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1"
    log="$build/$h.log"
    before=$(ls "$build/artifacts" | grep -c "^$h-")
    start=$(date +%s)
    # -timeout: a single input that runs for 10 s is a hang.
    # shellcheck disable=SC2086
    "$build/$h" -runs="$runs" -seed="$seed" -timeout=10 -rss_limit_mb=2560 -max_len=65536 \
        -print_final_stats=1 -artifact_prefix="$build/artifacts/$h-" $opts "$work" \
        > "$log" 2>&1
    rc=$?
    secs=$(( $(date +%s) - start ))
    found=$(( $(ls "$build/artifacts" | grep -c "^$h-") - before ))
    done_runs=$(sed -n 's/^Done \([0-9]*\) runs.*/\1/p' "$log" | tail -n 1)
    [ -n "$done_runs" ] || done_runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    # Fork mode reports "#RUNS: cov: ..." lines instead.
    [ -n "$done_runs" ] || done_runs=$(sed -n 's/^#\([0-9]*\): cov:.*/\1/p' "$log" | tail -n 1)
    cov=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1)
    if [ "$rc" -eq 0 ] && [ "$found" -eq 0 ]; then
        line="$h: ${done_runs:-?} executions in ${secs} s, ${cov:-cov: ?}, no crash"
    else
        failed=1
        art=$(grep -o "$build/artifacts/[^ ]*" "$log" | tail -n 1)
        line="$h: CRASH (exit $rc, $found new inputs in $build/artifacts) after ${done_runs:-?} executions in ${secs} s; first: ${art:-?}; log: $log"
        grep -E 'ERROR|runtime error|fuzz_[a-z]*: |SUMMARY' "$log" | head -n 8 | sed 's/^/    /'
    fi
    echo "$line"
    summary="$summary$line
"
done
printf '%s' "$summary" > "$build/summary.txt"
exit $failed
