#!/bin/sh
# kernel_ab.sh - the precise batch trace alone of two builds, alternated.
#
#   bench/kernel_ab.sh BUILD_A BUILD_B [ROUNDS [RAYS [REPEAT]]]
#
# BUILD_A and BUILD_B are meson build directories (release builds, say of
# an old commit in a git worktree and of this tree).  bench/kernel_speed.c
# is compiled against each build's engine library; then, on the
# Cassegrain, the double Gauss and the TMA of examples/, each round runs
# A and then B (RAYS rays, default 4000, the minimum CPU time of REPEAT
# traces, default 50, one thread), so both see the same load.  Prints
# each build's best and worst figure over ROUNDS rounds (default 7) in
# million ray-surfaces per second, B's best over A's, whether the two
# builds' rows are identical (when their row layouts match), and the load
# average before and after.
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
a=$(cd "$1" && pwd)
b=$(cd "$2" && pwd)
rounds=${3:-7}
rays=${4:-4000}
rep=${5:-50}
tmp=$(mktemp -d /tmp/kernel_ab.XXXXXX)
export SAGITTA_LENSDB=${SAGITTA_LENSDB:-$here/lensdb}

# kernel_speed against the engine library of build $1, as $2.
build() {
    src=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['directories']['source'])" \
        "$1/meson-info/meson-info.json")
    args=$(sed -n '/^build ui\/sagitta:/,/^$/s/^ LINK_ARGS = //p' "$1/build.ninja")
    libs=""
    for w in $args; do
        case $w in
        ui/*) ;;
        src/*.a) libs="$libs $1/$w" ;;
        *) libs="$libs $w" ;;
        esac
    done
    # shellcheck disable=SC2086
    cc -O2 -I"$src/src" -I"$1" -o "$2" "$here/bench/kernel_speed.c" $libs
}
build "$a" "$tmp/A"
build "$b" "$tmp/B"
echo "A: $a"
echo "B: $b"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
for d in cassegrain double_gauss tma; do
    i=0
    while [ "$i" -lt "$rounds" ]; do
        for s in A B; do
            echo "$s $("$tmp/$s" "$here/examples/$d.json" "$rays" "$rep" "$tmp/$s.rows")" >> "$tmp/$d"
        done
        i=$((i + 1))
    done
    same=differ
    if [ "$(wc -c < "$tmp/A.rows")" != "$(wc -c < "$tmp/B.rows")" ]; then
        same="not comparable (row layouts differ)"
    elif cmp -s "$tmp/A.rows" "$tmp/B.rows"; then
        same=identical
    fi
    awk -v d="$d" -v same="$same" '
        { v = $4; if (!($1 in best) || v > best[$1]) best[$1] = v
          if (!($1 in worst) || v < worst[$1]) worst[$1] = v }
        END { printf "%-13s A best %6.2f worst %6.2f   B best %6.2f worst %6.2f   B/A %.3f   rows %s\n",
                     d, best["A"], worst["A"], best["B"], worst["B"], best["B"] / best["A"], same }' "$tmp/$d"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
rm -rf "$tmp"
