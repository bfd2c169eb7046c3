#!/bin/sh
# ci-extra.sh - the checks of issue 6 that need their own builds:
#
#  1. the whole project built with AddressSanitizer and UndefinedBehavior-
#     Sanitizer (meson -Db_sanitize=address,undefined) and its whole test
#     suite run with leak detection on and every UBSan finding fatal;
#  2. the command-line paths (trace on every example with every method and
#     format, paraxial, a ray list on two threads, and the error paths) run
#     under valgrind memcheck, which must find no error and no definite leak;
#  3. the portable build (-Dnative=false, the one valgrind runs, as a
#     distribution would build it): the whole test suite, which on x86-64
#     includes tests/test_isa, since such a build carries the vector trace
#     for three instruction sets (src/num/isa.h) and the variants this
#     processor can run must give the baseline's bits.
#
# Usage: tools/ci-extra.sh [--asan-dir DIR] [--plain-dir DIR] [--jobs N]
#                          [--skip-asan] [--skip-valgrind] [--skip-portable]
#                          [--meson-test]
#
# --asan-dir     sanitizer build (default build-asan in the source tree)
# --plain-dir    unsanitized build whose sagitta valgrind runs (default
#                build-valgrind, configured -Dnative=false, whose run-time
#                choice of instruction set follows what valgrind reports, so
#                that it meets no instruction it cannot decode)
# --jobs         ninja -j (default 2)
# --meson-test   as a meson test (suite 'extra'): skipped (77) unless
#                SAGITTA_CI_EXTRA=1, because it takes many minutes
#
# Sanitizer reports of every process, including the sagitta children the
# tests start, go to DIR/sanitizer-logs; valgrind logs to
# PLAIN/valgrind-logs.  The script prints a summary and exits 1 when any
# step failed, 77 when a step could not run (valgrind missing) and none
# failed.  With CI=true a missing tool is a failure, not a skip.
set -u

root=$(cd "$(dirname "$0")/.." && pwd)
asan_dir=$root/build-asan
plain_dir=$root/build-valgrind
jobs=2
do_asan=1
do_valgrind=1
do_portable=1

while [ $# -gt 0 ]; do
    case $1 in
    --asan-dir) asan_dir=$2; shift 2 ;;
    --plain-dir) plain_dir=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --skip-asan) do_asan=0; shift ;;
    --skip-valgrind) do_valgrind=0; shift ;;
    --skip-portable) do_portable=0; shift ;;
    --meson-test)
        if [ "${SAGITTA_CI_EXTRA:-0}" != 1 ]; then
            echo "ci-extra: set SAGITTA_CI_EXTRA=1 to run the sanitizer and valgrind pass"
            exit 77
        fi
        shift ;;
    -h|--help) sed -n '2,33p' "$0"; exit 0 ;;
    *) echo "ci-extra: unknown argument $1" >&2; exit 2 ;;
    esac
done
case $asan_dir in /*) ;; *) asan_dir=$PWD/$asan_dir ;; esac
case $plain_dir in /*) ;; *) plain_dir=$PWD/$plain_dir ;; esac

summary=""
failed=0
skipped=0
# In CI (CI=true) a missing tool fails; elsewhere it is reported as skipped.
case ${CI:-} in ''|0|false|no) ci=0 ;; *) ci=1 ;; esac
note() {
    summary="$summary$1
"
    echo "ci-extra: $1"
}

# Configures DIR with the given options unless it is already a build.
setup() {
    dir=$1
    shift
    if [ -f "$dir/build.ninja" ]; then
        meson configure "$dir" "$@" >/dev/null
    else
        meson setup "$dir" "$root" "$@" >/dev/null
    fi
}

# ---------------------------------------------------------------- sanitizers
if [ "$do_asan" = 1 ]; then
    logs=$asan_dir/sanitizer-logs
    if ! setup "$asan_dir" -Dnative=true -Db_sanitize=address,undefined -Db_lundef=false; then
        note "ASan+UBSan: meson setup failed"
        failed=1
    elif ! ninja -C "$asan_dir" -j "$jobs" > "$asan_dir/ci-extra-build.log" 2>&1; then
        tail -n 30 "$asan_dir/ci-extra-build.log"
        note "ASan+UBSan: build failed (see $asan_dir/ci-extra-build.log)"
        failed=1
    else
        rm -rf "$logs"
        mkdir -p "$logs"
        # log_path: the children the tests spawn report too, each to its
        # own file, even when the test only looks at their exit status.
        # The fuzz suite builds its own sanitized harnesses and this suite
        # would run itself, so both are left out.
        ASAN_OPTIONS="detect_leaks=1:log_path=$logs/asan" \
        LSAN_OPTIONS="suppressions=$root/tools/lsan.supp:print_suppressions=0" \
        UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:log_path=$logs/ubsan" \
        meson test -C "$asan_dir" --no-rebuild --print-errorlogs --timeout-multiplier 4 \
            --no-suite extra --no-suite fuzz > "$asan_dir/ci-extra-test.log" 2>&1
        rc=$?
        counts=$(grep -E '^(Ok|Expected Fail|Fail|Unexpected Pass|Skipped|Timeout): ' \
                 "$asan_dir/ci-extra-test.log" | tr -s ' ' | tr '\n' ' ')
        nrep=$(find "$logs" -type f | wc -l)
        # UBSan in a process that also has ASan may write to standard error
        # rather than its log_path; the test log keeps those.
        nub=$(grep -c 'runtime error:' "$asan_dir/ci-extra-test.log")
        if [ "$nub" -gt 0 ]; then
            echo "ci-extra: UBSan findings in the test log:"
            grep -A 3 'runtime error:' "$asan_dir/ci-extra-test.log" | head -n 40
        fi
        if [ "$nrep" -gt 0 ]; then
            echo "ci-extra: sanitizer reports:"
            for f in "$logs"/*; do
                echo "--- $f"
                grep -E 'ERROR|runtime error|SUMMARY|^    #[0-9] ' "$f" | head -n 12
            done
        fi
        if [ "$rc" -ne 0 ] || [ "$nrep" -gt 0 ] || [ "$nub" -gt 0 ]; then
            grep -E '^ *[0-9]+/[0-9]+ .*(FAIL|TIMEOUT|ERROR)' "$asan_dir/ci-extra-test.log" |
                sort -u | head -n 40
            note "ASan+UBSan: FAILED: meson test exit $rc; $counts; $nrep sanitizer report files in $logs; $nub UBSan findings in $asan_dir/ci-extra-test.log"
            failed=1
        else
            note "ASan+UBSan: whole suite passed: $counts; no sanitizer report"
        fi
    fi
fi

# ------------------------------------------------------------------ valgrind
if [ "$do_valgrind" = 1 ]; then
    if ! command -v valgrind >/dev/null 2>&1; then
        if [ "$ci" = 1 ]; then
            note "valgrind: not installed; FAILED (CI=$CI: a missing tool is an error)"
            failed=1
        else
            note "valgrind: not installed; skipped"
            skipped=1
        fi
    elif ! { [ -f "$plain_dir/build.ninja" ] || setup "$plain_dir" -Dnative=false; } ||
         ! ninja -C "$plain_dir" -j "$jobs" ui/sagitta > "$plain_dir/ci-extra-build.log" 2>&1; then
        note "valgrind: building $plain_dir/ui/sagitta failed"
        failed=1
    else
        exe=$plain_dir/ui/sagitta
        vlogs=$plain_dir/valgrind-logs
        tmp=$(mktemp -d "${TMPDIR:-/tmp}/sagitta-vg-XXXXXX")
        rm -rf "$vlogs"
        mkdir -p "$vlogs"
        export SAGITTA_LENSDB="${SAGITTA_LENSDB:-$root/lensdb}"
        nrun=0
        nbad=0
        bad=""

        # vg EXPECTED-STATUS NAME ARGS...: sagitta under memcheck; 1 is
        # memcheck's own status (sagitta never exits 1).
        vg() {
            want=$1
            name=$2
            shift 2
            nrun=$((nrun + 1))
            valgrind -q --leak-check=full --errors-for-leak-kinds=definite \
                --error-exitcode=1 --log-file="$vlogs/$name.log" \
                "$exe" "$@" > "$tmp/out" 2> "$tmp/err" < "${VG_STDIN:-/dev/null}"
            got=$?
            if [ "$got" -ne "$want" ] || [ -s "$vlogs/$name.log" ]; then
                nbad=$((nbad + 1))
                bad="$bad $name"
                echo "ci-extra: valgrind $name: exit $got (expected $want): sagitta $*"
                head -n 20 "$vlogs/$name.log"
                head -n 3 "$tmp/err"
            else
                rm -f "$vlogs/$name.log"
            fi
        }

        printf 'hx,hy,px,py\n0,0,0,0\n0,1,0,1\n0,1,0,-1\n0.5,0.5,0.7,-0.7\n0,0,1,0\n0,1,0,0\n' \
            > "$tmp/rays.csv"
        printf 'x,y,z,l,m,n\n0,0,-1,0,0,1\n0,2,-1,0,0.05,1\n' > "$tmp/start.csv"
        printf 'hx,hy,px,py\n0,0,zero,0\n' > "$tmp/bad.csv"
        printf '{\n  "surfaces": [,\n}\n' > "$tmp/syntax.json"
        printf '{"surfaces": [{}, {"radius": 50, "thickness": 5, "material": "NO-SUCH", "stop": true}, {}]}\n' \
            > "$tmp/glass.json"
        printf '{"surfaces": [{}, {"radius": 50, "thickness": "x", "stop": true}, {}]}\n' \
            > "$tmp/content.json"

        for ex in "$root"/examples/*.json; do
            b=$(basename "$ex" .json)
            for m in precise classic mpfr; do
                for f in text csv json; do
                    vg 0 "trace-$b-$m-$f" trace "$ex" --ray 0,1,0,1 --method "$m" --format "$f"
                done
            done
            vg 0 "start-$b" trace "$ex" --start 0,1,-1 --dir 0,0.01,1 --format csv
            vg 0 "paraxial-$b-text" paraxial "$ex"
            vg 0 "paraxial-$b-json" paraxial "$ex" --format json
            vg 0 "rays-$b-precise" trace "$ex" --rays "$tmp/rays.csv" --threads 2 --format csv
            vg 0 "rays-$b-mpfr" trace "$ex" --rays "$tmp/rays.csv" --threads 2 --method mpfr \
                --format json
            vg 0 "rays-$b-classic-out" trace "$ex" --rays "$tmp/rays.csv" --threads 2 \
                --method classic -o "$tmp/out.txt"
        done
        ex=$root/examples/singlet.json
        vg 0 rays-startdir trace "$ex" --rays "$tmp/start.csv" --threads 2
        VG_STDIN=$tmp/rays.csv vg 0 rays-stdin trace "$ex" --rays - --threads 2 --format csv
        # The error paths free what they allocated too.
        vg 3 err-missing trace "$tmp/none.json" --ray 0,0,0,0
        vg 3 err-syntax trace "$tmp/syntax.json" --ray 0,0,0,0
        vg 3 err-content paraxial "$tmp/content.json"
        vg 4 err-glass trace "$tmp/glass.json" --ray 0,0,0,0
        vg 3 err-csv trace "$ex" --rays "$tmp/bad.csv" --threads 2
        vg 3 err-output trace "$ex" --ray 0,0,0,0 -o "$tmp/no/such/dir"
        vg 2 err-option trace "$ex" --ray 0,1,x
        vg 2 err-wave paraxial "$ex" --wave 9
        vg 2 err-usage frobnicate
        vg 0 help --help
        rm -rf "$tmp"
        if [ "$nbad" -eq 0 ]; then
            note "valgrind memcheck: $nrun command lines, no error, no definite leak"
        else
            note "valgrind memcheck: FAILED in $nbad of $nrun command lines:$bad (logs in $vlogs)"
            failed=1
        fi
    fi
fi

# ------------------------------------------- the portable build's suite
# The build a distribution makes (-Dnative=false): the whole test suite,
# which in such a build on x86-64 includes tests/test_isa (the variants
# this processor can run give the baseline's bits).
if [ "$do_portable" = 1 ]; then
    plog=$plain_dir/ci-extra-portable.log
    if ! { [ -f "$plain_dir/build.ninja" ] || setup "$plain_dir" -Dnative=false; } ||
         ! meson configure "$plain_dir" -Dnative=false -Dtests=true >/dev/null 2>&1; then
        note "portable build: meson setup of $plain_dir failed"
        failed=1
    elif ! ninja -C "$plain_dir" -j "$jobs" > "$plain_dir/ci-extra-build.log" 2>&1; then
        tail -n 30 "$plain_dir/ci-extra-build.log"
        note "portable build: building $plain_dir failed (see $plain_dir/ci-extra-build.log)"
        failed=1
    else
        meson test -C "$plain_dir" --no-rebuild --print-errorlogs --num-processes "$jobs" \
            --no-suite extra --no-suite fuzz > "$plog" 2>&1
        rc=$?
        counts=$(grep -E '^(Ok|Expected Fail|Fail|Unexpected Pass|Skipped|Timeout): ' \
                 "$plog" | tr -s ' ' | tr '\n' ' ')
        if meson introspect "$plain_dir" --targets 2>/dev/null | grep -q '"test_isa"'; then
            isa="test_isa included"
        else
            isa="this compiler or processor family builds one instruction set: no test_isa"
        fi
        if [ "$rc" -ne 0 ]; then
            grep -E '^ *[0-9]+/[0-9]+ .*(FAIL|TIMEOUT|ERROR)' "$plog" | sort -u | head -n 40
            note "portable build (-Dnative=false): FAILED: meson test exit $rc; $counts (see $plog)"
            failed=1
        else
            note "portable build (-Dnative=false): whole suite passed: $counts; $isa"
        fi
    fi
fi

echo "ci-extra: summary"
printf '%s' "$summary" | sed 's/^/  /'
# 1 when a step failed; 77 (skipped, for meson) when a step could not run
# here and none failed.
if [ "$failed" = 1 ]; then
    exit 1
elif [ "$skipped" = 1 ]; then
    exit 77
fi
exit 0
