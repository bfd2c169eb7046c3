#!/bin/sh
# rays_same.sh - "trace --rays" of two sagitta binaries, byte for byte.
#
#   bench/rays_same.sh OLD_SAGITTA NEW_SAGITTA [SCRATCH_DIR]
#
# Runs both on the same ray lists (written here by bench/odd_rays.py:
# normalized rays with odd values, negative zero, subnormals, 25-digit and
# exponent forms, fields and pupils beyond 1, and start/direction rays)
# through the five examples, in CSV, JSON and text, with the precise and
# classic methods, one and three threads, blocks of 7 rays (the seams),
# --global, and HDF5 (compared with h5dump, since the file's own bytes
# hold object times, and h5dump's first line the file's name); then 2e5 rays of bench/field_rays.py in CSV and
# JSON.  Prints each difference and a count; exits 1 on any.
set -u
old=$1
new=$2
dir=${3:-$(mktemp -d /tmp/rays_same.XXXXXX)}
here=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$dir"
python3 "$here/bench/odd_rays.py" "$dir/norm.csv" "$dir/sd.csv" 4000 3000 || exit 2
python3 "$here/bench/field_rays.py" "$dir/big.csv" 20000 10 || exit 2
head -301 "$dir/norm.csv" > "$dir/norm_small.csv"
head -201 "$dir/sd.csv" > "$dir/sd_small.csv"
n=0
bad=0
same() { # label, then the arguments after "trace"
    label=$1
    shift
    "$old" trace "$@" > "$dir/a" 2> "$dir/ae"
    ra=$?
    "$new" trace "$@" > "$dir/b" 2> "$dir/be"
    rb=$?
    n=$((n + 1))
    if [ $ra -ne $rb ] || ! cmp -s "$dir/a" "$dir/b" || ! cmp -s "$dir/ae" "$dir/be"; then
        echo "DIFFERS: $label (exit $ra vs $rb)"
        bad=$((bad + 1))
    fi
}
same_h5() {
    label=$1
    shift
    rm -f "$dir/a.h5" "$dir/b.h5"
    "$old" trace "$@" --format hdf5 -o "$dir/a.h5" 2> "$dir/ae"
    ra=$?
    "$new" trace "$@" --format hdf5 -o "$dir/b.h5" 2> "$dir/be"
    rb=$?
    n=$((n + 1))
    if [ $ra -ne $rb ] || ! cmp -s "$dir/ae" "$dir/be" ||
       ! h5dump "$dir/a.h5" > "$dir/a.dump" 2>&1 || ! h5dump "$dir/b.h5" > "$dir/b.dump" 2>&1 ||
       [ "$(sed 1d "$dir/a.dump" | cksum)" != "$(sed 1d "$dir/b.dump" | cksum)" ]; then
        echo "DIFFERS: $label hdf5 (exit $ra vs $rb)"
        bad=$((bad + 1))
    fi
}
for ex in singlet cooke_triplet double_gauss cassegrain tma; do
    d="$here/examples/$ex.json"
    for m in precise classic; do
        for th in 1 3; do
            for f in csv json; do
                same "$ex $m $f threads $th norm" "$d" --rays "$dir/norm.csv" --method $m --format $f --threads $th
                same "$ex $m $f threads $th sd" "$d" --rays "$dir/sd.csv" --method $m --format $f --threads $th
            done
            same "$ex $m text threads $th norm" "$d" --rays "$dir/norm_small.csv" --method $m --threads $th
            same "$ex $m text threads $th sd" "$d" --rays "$dir/sd_small.csv" --method $m --threads $th
        done
        SAGITTA_RAYS_BLOCK=7 same "$ex $m csv blocks of 7" "$d" --rays "$dir/norm.csv" --method $m --format csv --threads 3
        SAGITTA_RAYS_BLOCK=7 same "$ex $m json blocks of 7" "$d" --rays "$dir/norm.csv" --method $m --format json --threads 3
        same "$ex $m csv global" "$d" --rays "$dir/norm.csv" --method $m --format csv --global
        same "$ex $m json global 2" "$d" --rays "$dir/sd.csv" --method $m --format json --global 2
        same_h5 "$ex $m norm" "$d" --rays "$dir/norm.csv" --method $m
        same_h5 "$ex $m sd global" "$d" --rays "$dir/sd.csv" --method $m --global
    done
    same "$ex one ray csv" "$d" --ray 0,0.3,0.5,-0.25 --format csv
    same "$ex one ray json" "$d" --ray 0,0.3,0.5,-0.25 --format json
    same "$ex one ray text" "$d" --ray 0,0.3,0.5,-0.25
    head -2 "$dir/norm.csv" > "$dir/one.csv"
    same "$ex one-row list csv" "$d" --rays "$dir/one.csv" --format csv
done
for f in csv json; do
    for th in 1 2; do
        same "singlet 2e5 $f threads $th" "$here/examples/singlet.json" --rays "$dir/big.csv" --format $f --threads $th
        same "cooke 2e5 $f threads $th" "$here/examples/cooke_triplet.json" --rays "$dir/big.csv" --format $f --threads $th
    done
done
echo "$n comparisons, $bad differ"
[ $bad -eq 0 ]
