#!/bin/sh
# dev.sh - set up, build, run and test sagitta on a Debian machine.
#
#   tools/dev.sh run [DESIGN.json]   install what is missing, build, open the editor
#   tools/dev.sh test                install what is missing, build, run every test
#   tools/dev.sh build               install what is missing and build
#   tools/dev.sh deps                only install the Debian packages
#
# BUILD_DIR (default: build) selects the build directory and MESON_ARGS adds
# options to its first setup, e.g. MESON_ARGS=-Db_sanitize=address,undefined.
# The build is for this processor (-Dnative=true) unless MESON_ARGS sets
# -Dnative.
set -eu

here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
build=${BUILD_DIR:-build}

packages="gcc meson ninja-build pkg-config libmpfr-dev libgmp-dev libcjson-dev libfftw3-dev libcairo2-dev \
libcmocka-dev libncurses-dev tmux python3 clang libclang-rt-14-dev valgrind \
libhdf5-dev hdf5-tools libgsl-dev openmpi-bin libopenmpi-dev \
locales"

# A comma-decimal locale, for the test that numbers are read with '.'
# whatever LC_NUMERIC is (tests/test_material.c).
locale_name=de_DE.UTF-8

deps() {
    missing=""
    for p in $packages; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" ||
            missing="$missing $p"
    done
    if [ "$(id -u)" -eq 0 ]; then
        sudo=""
    else
        sudo="sudo"
    fi
    if [ -n "$missing" ]; then
        echo "dev.sh: installing:$missing" >&2
        $sudo apt-get update -qq
        # shellcheck disable=SC2086
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $missing >/dev/null
    fi
    if ! locale -a 2>/dev/null | grep -qix "$(echo "$locale_name" | sed 's/UTF-8/utf8/')"; then
        echo "dev.sh: generating the $locale_name locale" >&2
        $sudo localedef -i "${locale_name%%.*}" -c -f UTF-8 "$locale_name"
    fi
}

build() {
    deps
    if [ ! -f "$build/build.ninja" ]; then
        # A local build is for this processor unless MESON_ARGS says
        # otherwise; meson's own default is the portable build.
        case " ${MESON_ARGS:-} " in
        *-Dnative=*) native="" ;;
        *) native=-Dnative=true ;;
        esac
        # shellcheck disable=SC2086
        meson setup "$build" $native ${MESON_ARGS:-}
    fi
    ninja -C "$build"
}

# Prints "N passed, N failed, N skipped" from meson's log, counting each TAP
# case.  Skips are counted as skips, not passes: a TAP line with a "# SKIP"
# directive, a test that exits 77, and a cmocka case that printed a line
# "# SKIP reason" and returned (cmocka's own skip() reads as a failure to
# meson).  CI reads the last line: it starts with "N passed, N failed".
summary() {
    python3 - "$build/meson-logs/testlog.json" <<'PY'
import json, re, sys
passed = failed = skipped = 0
names = []
for line in open(sys.argv[1]):
    t = json.loads(line)
    cases = re.findall(r"^(ok|not ok)\b(.*)$", t.get("stdout") or "", re.M)
    if cases:
        for verdict, rest in cases:
            if re.search(r"#\s*skip", rest, re.I):
                skipped += 1
                names.append(t["name"] + ":" + rest.strip())
            elif verdict == "ok":
                passed += 1
            else:
                failed += 1
        for reason in re.findall(r"^# SKIP\b(.*)$", t.get("stdout") or "", re.M):
            passed -= 1
            skipped += 1
            names.append(t["name"] + ": " + reason.strip())
        if t["result"] not in ("OK", "SKIP") and all(v == "ok" for v, _ in cases):
            failed += 1
    elif t["result"] in ("OK", "EXPECTEDFAIL"):
        passed += 1
    elif t["result"] == "SKIP":
        skipped += 1
        names.append(t["name"])
    else:
        failed += 1
for n in names:
    print("skipped:", n)
print(f"{passed} passed, {failed} failed, {skipped} skipped")
PY
}

case "${1:-}" in
deps)
    deps
    ;;
build)
    build
    ;;
run)
    build
    shift
    exec "$build/ui/sagitta" "${1:-examples/cassegrain.json}"
    ;;
test)
    build
    rc=0
    meson test -C "$build" --print-errorlogs --num-processes 2 || rc=$?
    summary
    exit "$rc"
    ;;
*)
    echo "usage: tools/dev.sh run [DESIGN.json] | test | build | deps" >&2
    exit 2
    ;;
esac
