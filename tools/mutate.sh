#!/bin/sh
# mutate.sh - mutation testing: does the test suite notice a wrong engine?
#
#   tools/mutate.sh [--list FILE] [--dir DIR] [--jobs N] [--timeout S]
#                   [--only NAME[,NAME...]] [--kind KIND[,KIND...]] [--keep]
#                   [--out FILE] [--probe-only]
#   tools/mutate.sh --check [--list FILE]
#
# Copies the working tree (tracked and untracked, not ignored files) into a
# scratch directory DIR (default: a new one under ${TMPDIR:-/tmp}), builds
# it once with meson and checks that the unmutated suite passes there.  Then
# for each mutant of FILE (default tools/mutants.txt; see its header for
# the format) it puts the mutant into its source file, rebuilds (ninja only
# recompiles that file and relinks), runs the suite with a per-mutant
# timeout, and restores the file.  A mutant is
#
#   KILLED      the build succeeded and the suite failed (or timed out);
#   SURVIVED    the suite passed with the mutant in: a blind spot, unless
#               the mutant is equivalent (cannot change any output).  Its
#               detail says whether it changed the output of a probe set
#               (every example by every method, wavelengths 1 and 2, 1 and 3
#               threads, on asymmetric rays; paraxial; verify on each
#               example and both experiments) against the unmutated build;
#   NO-COMPILE  the mutated source did not build;
#   STALE       its original text is not in the file exactly once: the code
#               moved, so the list needs updating.
#
# The suite is `meson test` without the 'extra' suite (tools/ci-extra.sh
# rebuilds the project), the 'fuzz' suite (it builds its own harnesses
# and looks for crashes, not values) and the 'lint' suite (its check that
# every mutant's text is in the source fails on any mutated tree),
# stopping at the first failing test.
# The per-mutant timeout (default 600 s) covers the build and the tests.
# Results go to FILE (default build-mutate/results.tsv in the source tree,
# ignored by git), one TAB-separated line a mutant, and a summary to
# standard output;
# the exit status is 0 when no mutant survived or went stale, 1 otherwise,
# 2 when the unmutated build or suite fails.  --keep leaves DIR (and a
# later run with --dir DIR reuses its build); otherwise it is removed.  --only and --kind pick mutants by name or kind.
# --probe-only runs no tests: each mutant is CHANGED or UNCHANGED, by
# whether it changes an output of the probe set (to sort survivors into
# blind spots and equivalent mutants without running the suite again).
# MESON_ARGS adds options to the scratch build's setup.
# --check builds and runs nothing: it exits 1 when a mutant is STALE or
# malformed (the suite runs it, so code that moves takes its mutants along).
set -u

root=$(cd "$(dirname "$0")/.." && pwd)
list=$root/tools/mutants.txt
dir=""
jobs=2
tmo=600
only=""
kinds=""
keep=0
probe_only=0
check=0
out=$root/build-mutate/results.tsv

while [ $# -gt 0 ]; do
    case $1 in
    --list) list=$2; shift 2 ;;
    --dir) dir=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --timeout) tmo=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    --kind) kinds=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    --probe-only) probe_only=1; shift ;;
    --check) check=1; shift ;;
    --out) out=$2; shift 2 ;;
    -h|--help) sed -n '2,43p' "$0"; exit 0 ;;
    *) echo "mutate: unknown argument $1" >&2; exit 2 ;;
    esac
done
case $list in /*) ;; *) list=$PWD/$list ;; esac
case $out in /*) ;; *) out=$PWD/$out ;; esac
[ -f "$list" ] || { echo "mutate: no mutant list $list" >&2; exit 2; }
if [ "$check" = 1 ]; then
    python3 - "$root" "$list" <<'PY'
import os, sys
root, path = sys.argv[1:3]
un = lambda s: s.replace("\\n", "\n").replace("\\t", "\t")
bad, n, names = 0, 0, set()
for lineno, line in enumerate(open(path), 1):
    if line.startswith("#") or not line.strip():
        continue
    f = line.rstrip("\n").split("\t")
    n += 1
    if len(f) != 5 or not all(f):
        print(f"{path}:{lineno}: malformed (five TAB-separated fields)")
        bad += 1
        continue
    name, kind, rel, orig, rep = f
    if name in names:
        print(f"{path}:{lineno}: {name}: name used twice")
        bad += 1
    names.add(name)
    src = os.path.join(root, rel)
    if not os.path.isfile(src):
        print(f"{path}:{lineno}: {name}: no file {rel}")
        bad += 1
        continue
    c = open(src).read().count(un(orig))
    if c != 1:
        print(f"{path}:{lineno}: {name}: STALE, its original occurs {c} times in {rel}")
        bad += 1
print(f"mutate: {n} mutants, {bad} stale or malformed")
sys.exit(1 if bad else 0)
PY
    exit $?
fi
if [ -z "$dir" ]; then
    dir=$(mktemp -d "${TMPDIR:-/tmp}/sagitta-mutate-XXXXXX")
else
    mkdir -p "$dir"
fi
case $dir in /*) ;; *) dir=$PWD/$dir ;; esac
src=$dir/src-tree
build=$dir/build
results=$dir/mutate-results.tsv
log=$dir/logs
mkdir -p "$log"

cleanup() {
    [ "$keep" = 1 ] || rm -rf "$dir"
}

# The scratch tree: what git would commit now, uncommitted edits included.
# A DIR from an earlier run keeps its build: only files whose bytes differ
# are copied (with a new time stamp, so ninja rebuilds just those).
mkdir -p "$src"
(cd "$root" && git ls-files -z --cached --others --exclude-standard) |
    python3 -c '
import os, shutil, sys
root, dst = sys.argv[1:3]
for rel in sys.stdin.buffer.read().decode().split("\0"):
    a, b = os.path.join(root, rel), os.path.join(dst, rel)
    if not rel or not os.path.isfile(a):
        continue
    if os.path.isfile(b) and open(a, "rb").read() == open(b, "rb").read():
        continue
    os.makedirs(os.path.dirname(b), exist_ok=True)
    shutil.copy(a, b)
' "$root" "$src"
commit=$(cd "$root" && git rev-parse --short HEAD)
dirty=$(cd "$root" && git status --porcelain --untracked-files=no | wc -l)

suite() { # runs the suite in $build with timeout $1; returns its status
    timeout "$1" meson test -C "$build" --no-rebuild --num-processes "$jobs" --maxfail 1 \
        --no-suite extra --no-suite fuzz --no-suite lint > "$2" 2>&1
}

echo "mutate: scratch tree $src (commit $commit$([ "$dirty" -gt 0 ] && echo ", $dirty files modified"))"
# shellcheck disable=SC2086
if ! { [ -f "$build/build.ninja" ] || meson setup "$build" "$src" -Dnative=true ${MESON_ARGS:-} > "$log/setup.log" 2>&1; } ||
   ! ninja -C "$build" -j "$jobs" > "$log/build.log" 2>&1; then
    tail -n 20 "$log/setup.log" "$log/build.log" 2>/dev/null
    echo "mutate: the unmutated tree does not build (see $log)" >&2
    keep=1
    exit 2
fi
t0=$(date +%s)
if [ "$probe_only" = 1 ]; then
    :
elif ! suite 1800 "$log/baseline.log"; then
    grep -E '^ *[0-9]+/[0-9]+ ' "$log/baseline.log" | grep -v ' OK ' | head
    echo "mutate: the unmutated suite fails (see $log/baseline.log)" >&2
    keep=1
    exit 2
fi
[ "$probe_only" = 1 ] || echo "mutate: unmutated suite passes in $(( $(date +%s) - t0 )) s"

# inches SRC DEST: the design SRC (surfaces without aspheric terms, an EPD
# aperture) written in inches, every length divided by 25.4, so that a
# probe meets a unit other than the millimetre.
inches() {
    python3 - "$1" "$2" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
mm = 25.4
d["units"] = "in"
d["title"] = d.get("title", "") + " (in inches)"
for s in d["surfaces"]:
    for k in ("radius", "thickness", "semi_diameter"):
        if isinstance(s.get(k), (int, float)):
            s[k] = s[k] / mm
if d["aperture"]["type"] == "epd":
    d["aperture"]["value"] /= mm
if d["fields"]["type"] != "angle":
    for f in d["fields"]["list"]:
        f["x"] /= mm
        f["y"] /= mm
json.dump(d, open(sys.argv[2], "w"), indent=1)
PY
}

# probe DIR: the program's outputs on a fixed set of commands, for telling
# a survivor that changes an output from one that (on this set) does not:
# every example traced by every method and wavelength 1 and 2 on a grid of
# asymmetric rays, with 1 and 3 threads, plus paraxial and verify; and
# every analysis (spot, fans, OPD fans, wavefront, Seidel, field curves,
# semi-diameters, vignetting, layout) at every field and wavelength, as
# CSV or JSON, on each example and on the double Gauss in inches (an
# off-axis, polychromatic design in another unit), and the editor's batch
# mode exporting its ray table and views.
probe() {
    pd=$1
    exe=$build/ui/sagitta
    rm -rf "$pd"
    mkdir -p "$pd"
    printf 'hx,hy,px,py\n' > "$pd/rays.csv"
    for h in 0,0 0,0.7 0.3,1 -0.6,0.2; do
        for p in 0,0 0.7,-0.2 -0.3,0.9 0.5,0.5 1,0 0,-1 0.05,0.999; do
            echo "$h,$p" >> "$pd/rays.csv"
        done
    done
    export SAGITTA_LENSDB="$src/lensdb"
    inches "$src/examples/double_gauss.json" "$pd/dg_inch.json"
    for ex in "$src"/examples/*.json "$pd/dg_inch.json"; do
        b=$(basename "$ex" .json)
        for a in "spot --format csv" "spot --reference centroid --format json" \
                 "fan --format csv" "fan --opd --format csv" "wavefront --format json" \
                 "seidel --format json" "fieldcurve --format csv" "semidiam --format json" \
                 "vignetting --format json" "layout --format json"; do
            # shellcheck disable=SC2086
            "$exe" $a "$ex" > "$pd/$b-$(echo "$a" | tr ' ' '_').out" 2>&1
            echo "exit $?" >> "$pd/$b-$(echo "$a" | tr ' ' '_').out"
        done
        nf=$(python3 -c 'import json, sys; print(len(json.load(open(sys.argv[1]))["fields"]["list"]))' "$ex")
        for f in $(seq 1 "$nf"); do
            "$exe" wavefront "$ex" --field $f --wave 1 --format json > "$pd/$b-wf-f$f.json" 2>&1
            echo "exit $?" >> "$pd/$b-wf-f$f.json"
        done
        # The editor at the last field and wavelength 1, off axis in the
        # pupil: the ray, a fan and a grid, as CSV and JSON.
        printf 'field %s\nwave 1\nray 0.3 1 0.5 -0.7\nexport - csv ray\nexport - csv fan 7\nexport - json grid 5\nexport - text ray\n' "$nf" \
            > "$pd/script"
        "$exe" "$ex" --batch "$pd/script" > "$pd/$b-ed.log" 2>&1
        echo "exit $?" >> "$pd/$b-ed.log"
    done
    rm -f "$pd/script"
    for ex in "$src"/examples/*.json "$pd/dg_inch.json"; do
        b=$(basename "$ex" .json)
        for m in precise classic mpfr; do
            for w in 1 2; do
                for th in 1 3; do
                    "$exe" trace "$ex" --rays "$pd/rays.csv" --method $m --wave $w \
                        --threads $th --format csv > "$pd/$b-$m-w$w-t$th.csv" 2>&1
                    echo "exit $?" >> "$pd/$b-$m-w$w-t$th.csv"
                done
            done
        done
        "$exe" paraxial "$ex" --format json > "$pd/$b-paraxial.json" 2>&1
        echo "exit $?" >> "$pd/$b-paraxial.json"
        "$exe" verify "$ex" --format json > "$pd/$b-verify.json" 2>&1
        echo "exit $?" >> "$pd/$b-verify.json"
    done
    "$exe" verify --experiment table1 --format json > "$pd/table1.json" 2>&1
    echo "exit $?" >> "$pd/table1.json"
    "$exe" verify --experiment table2 --count 2000 --format json > "$pd/table2.json" 2>&1
    echo "exit $?" >> "$pd/table2.json"
    rm -f "$pd/rays.csv" "$pd/dg_inch.json"
}
probe "$dir/probe-base"

# apply FILE ORIGINAL REPLACEMENT: 0 done, 3 original not there once.
apply() {
    python3 - "$@" <<'PY'
import sys
path, orig, rep = sys.argv[1:4]
un = lambda s: s.replace("\\n", "\n").replace("\\t", "\t")
orig, rep = un(orig), un(rep)
text = open(path).read()
if text.count(orig) != 1:
    sys.exit(3)
open(path, "w").write(text.replace(orig, rep))
PY
}

printf 'name\tkind\tfile\tresult\tseconds\tdetail\n' > "$results"
n=0
tab=$(printf '\t')
grep -v -e '^#' -e '^[[:space:]]*$' "$list" > "$dir/list"
while IFS="$tab" read -r name kind file orig rep; do
    if [ -n "$only" ] && ! echo ",$only," | grep -q ",$name,"; then continue; fi
    if [ -n "$kinds" ] && ! echo ",$kinds," | grep -q ",$kind,"; then continue; fi
    n=$((n + 1))
    t1=$(date +%s)
    f=$src/$file
    detail=""
    if [ -z "$rep" ] || [ ! -f "$f" ]; then
        res=STALE
        detail="no such file or malformed line"
    else
        cp -p "$f" "$dir/orig"
        apply "$f" "$orig" "$rep" < /dev/null
        rc=$?
        if [ "$rc" -ne 0 ]; then
            res=STALE
            detail="original text not found exactly once"
        elif ! timeout "$tmo" ninja -C "$build" -j "$jobs" > "$log/$name.build" 2>&1; then
            res=NO-COMPILE
            detail=$(grep -m1 'error' "$log/$name.build" | cut -c1-120)
        elif [ "$probe_only" = 1 ]; then
            probe "$dir/probe-mut"
            changed=$(cd "$dir/probe-base" && for x in *; do
                          cmp -s "$x" "$dir/probe-mut/$x" || echo "$x"; done)
            if [ -z "$changed" ]; then
                res=UNCHANGED
            else
                res=CHANGED
                detail="$(echo "$changed" | wc -l) probe files, e.g. $(echo "$changed" | head -n 3 | tr '\n' ' ')"
            fi
        else
            left=$((tmo - ($(date +%s) - t1)))
            [ "$left" -lt 60 ] && left=60
            suite "$left" "$log/$name.test" < /dev/null
            rc=$?
            if [ "$rc" -eq 0 ]; then
                res=SURVIVED
                probe "$dir/probe-mut"
                changed=$(cd "$dir/probe-base" && for x in *; do
                              cmp -s "$x" "$dir/probe-mut/$x" || echo "$x"; done)
                if [ -z "$changed" ]; then
                    detail="no output changed on the probe set"
                else
                    detail="output changed: $(echo "$changed" | wc -l) probe files, e.g. $(echo "$changed" | head -n 3 | tr '\n' ' ')"
                fi
            else
                res=KILLED
                if [ "$rc" -eq 124 ]; then
                    detail="timeout"
                else
                    detail=$(grep -E '^ *[0-9]+/[0-9]+ ' "$log/$name.test" |
                             grep -E 'FAIL|ERROR|TIMEOUT' | head -n 1 |
                             sed 's/^ *[0-9]*\/[0-9]* *//; s/  */ /g')
                fi
            fi
        fi
        # The original back, with a new time stamp so ninja rebuilds it.
        cp "$dir/orig" "$f"
        touch "$f"
    fi
    secs=$(( $(date +%s) - t1 ))
    printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$kind" "$file" "$res" "$secs" "$detail" >> "$results"
    printf 'mutate: %-32s %-10s %-10s %4ss  %s\n' "$name" "$kind" "$res" "$secs" "$detail"
done < "$dir/list"
# The last restore rebuilt nothing yet; leave the build consistent.
ninja -C "$build" -j "$jobs" > /dev/null 2>&1

if [ "$probe_only" = 1 ]; then
    nch=$(grep -c "${tab}CHANGED${tab}" "$results")
    nun=$(grep -c "${tab}UNCHANGED${tab}" "$results")
    echo "mutate: $n mutants probed on commit $commit, $(date -u +%Y-%m-%d): $nch change an output, $nun change none"
    grep "${tab}UNCHANGED${tab}" "$results" | cut -f1 | sed 's/^/  unchanged: /'
    mkdir -p "$(dirname "$out")" && cp "$results" "$out" && echo "mutate: results in $out"
    cleanup
    exit 0
fi
nk=$(grep -c "${tab}KILLED${tab}" "$results")
ns=$(grep -c "${tab}SURVIVED${tab}" "$results")
nc=$(grep -c "${tab}NO-COMPILE${tab}" "$results")
nst=$(grep -c "${tab}STALE${tab}" "$results")
echo "mutate: $n mutants on commit $commit, $(date -u +%Y-%m-%d): $nk killed, $ns survived, $nc no-compile, $nst stale"
if [ "$ns" -gt 0 ]; then
    echo "mutate: surviving mutants:"
    grep "${tab}SURVIVED${tab}" "$results" | cut -f1,2,3 | sed 's/^/  /'
fi
if [ "$nst" -gt 0 ]; then
    echo "mutate: stale mutants (update $list):"
    grep "${tab}STALE${tab}" "$results" | cut -f1,3 | sed 's/^/  /'
fi
mkdir -p "$(dirname "$out")" && cp "$results" "$out" && echo "mutate: results in $out"
cleanup
[ "$ns" -eq 0 ] && [ "$nst" -eq 0 ]
