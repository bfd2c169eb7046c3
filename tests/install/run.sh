#!/bin/sh
# run.sh BUILD_DIR SOURCE_DIR - install the build into a scratch DESTDIR and
# build tests/install/consumer.c against it through pkg-config, as a user's
# program would be; check that the library exports exactly the functions
# its installed header declares, and that the installed program, moved
# elsewhere, reads its own catalogs.  Prints TAP.
set -u
build=$1
src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM HUP

fail() { echo "not ok - $1"; echo "1..1"; exit 1; }

meson install -C "$build" --destdir "$tmp/root" --no-rebuild --quiet >"$tmp/install.log" 2>&1 ||
    { sed 's/^/# /' "$tmp/install.log"; fail "meson install"; }
pc=$(find "$tmp/root" -name sagitta.pc | head -n 1)
[ -n "$pc" ] || fail "no sagitta.pc installed"
lib=$(find "$tmp/root" -name 'libsagitta.so.*.*' | head -n 1)
[ -n "$lib" ] || fail "no libsagitta.so installed"
PKG_CONFIG_PATH=$(dirname "$pc")
PKG_CONFIG_SYSROOT_DIR=$tmp/root
export PKG_CONFIG_PATH PKG_CONFIG_SYSROOT_DIR
datadir=$(find "$tmp/root" -type d -path '*/share/sagitta' | head -n 1)

# shellcheck disable=SC2046
${CC:-cc} -std=c11 -Wall -Werror -D_DEFAULT_SOURCE -o "$tmp/consumer" "$src/tests/install/consumer.c" \
    $(pkg-config --cflags --libs sagitta) -lm 2>"$tmp/cc.log" ||
    { sed 's/^/# /' "$tmp/cc.log"; fail "consumer builds against the installed library"; }

# The library as installed, with no way back into the build tree.
env -u SAGITTA_LENSDB -u SAGITTA_EXAMPLES LD_LIBRARY_PATH="$(dirname "$lib")" \
    "$tmp/consumer" "$datadir" > "$tmp/out" 2>"$tmp/err"
rc=$?
sed 's/^/# /' "$tmp/err"
grep -v '^1\.\.' "$tmp/out" | grep -v '^TAP'
n=$(grep -c '^ok\|^not ok' "$tmp/out")

# The public API is exactly the installed header's declarations.
nm -D --defined-only "$lib" | awk '$2 == "T" { sub(/@.*/, "", $3); print $3 }' | sort > "$tmp/exported"
find "$tmp/root" -path '*/include/sagitta/*.h' -exec \
    sed -n 's/^SG_API[^(]*[^a-zA-Z0-9_]\(sg_[a-zA-Z0-9_]*\) *(.*/\1/p' {} + | sort -u > "$tmp/declared"
if [ -s "$tmp/declared" ] && cmp -s "$tmp/exported" "$tmp/declared"; then
    echo "ok - exported symbols are exactly the header's $(wc -l < "$tmp/declared") functions"
else
    echo "not ok - exported symbols differ from the header's declarations"
    diff "$tmp/declared" "$tmp/exported" | head -20 | sed 's/^/# /'
    rc=1
fi
soname=$(objdump -p "$lib" | awk '$1 == "SONAME" { print $2 }')
case $soname in
libsagitta.so.[0-9]*) echo "ok - soname $soname" ;;
*) echo "not ok - soname '$soname'"; rc=1 ;;
esac

# The program, moved elsewhere after installing, reads its own catalogs:
# without its SCHOTT.agf it cannot find N-BK7, though the source tree has it.
prefix=$(dirname "$(dirname "$datadir")")
mv "$prefix" "$tmp/moved"
out=$(cd / && env -u SAGITTA_LENSDB -u SAGITTA_EXAMPLES "$tmp/moved/bin/sagitta" paraxial \
    "$tmp/moved/share/sagitta/examples/singlet.json" 2>&1)
case $out in
*"Effective focal length  :  99.65169613381"*) echo "ok - the moved program finds its catalogs" ;;
*) echo "not ok - the moved program finds its catalogs"; echo "$out" | sed 's/^/# /'; rc=1 ;;
esac
rm "$tmp/moved/share/sagitta/lensdb/SCHOTT.agf"
if (cd / && env -u SAGITTA_LENSDB "$tmp/moved/bin/sagitta" paraxial \
    "$tmp/moved/share/sagitta/examples/singlet.json" >/dev/null 2>&1); then
    echo "not ok - the moved program reads no catalog but its own"; rc=1
else
    echo "ok - the moved program reads no catalog but its own"
fi
echo "1..$((n + 4))"
exit $rc
