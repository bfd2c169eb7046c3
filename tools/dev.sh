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
set -eu

here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
build=${BUILD_DIR:-build}

packages="gcc meson ninja-build pkg-config libmpfr-dev libgmp-dev libcjson-dev \
libcmocka-dev libncurses-dev tmux python3 clang libclang-rt-14-dev valgrind"

deps() {
    missing=""
    for p in $packages; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" ||
            missing="$missing $p"
    done
    [ -z "$missing" ] && return 0
    echo "dev.sh: installing:$missing" >&2
    if [ "$(id -u)" -eq 0 ]; then
        sudo=""
    else
        sudo="sudo"
    fi
    $sudo apt-get update -qq
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $missing >/dev/null
}

build() {
    deps
    if [ ! -f "$build/build.ninja" ]; then
        # shellcheck disable=SC2086
        meson setup "$build" ${MESON_ARGS:-}
    fi
    ninja -C "$build"
}

# Prints "N passed, N failed" from meson's log, counting each TAP case.
summary() {
    python3 - "$build/meson-logs/testlog.json" <<'PY'
import json, re, sys
passed = failed = 0
for line in open(sys.argv[1]):
    t = json.loads(line)
    cases = re.findall(r"^(ok|not ok)\b", t.get("stdout") or "", re.M)
    if cases:
        passed += sum(c == "ok" for c in cases)
        failed += sum(c == "not ok" for c in cases)
        if t["result"] not in ("OK", "SKIP") and "not ok" not in cases:
            failed += 1
    elif t["result"] in ("OK", "EXPECTEDFAIL"):
        passed += 1
    elif t["result"] != "SKIP":
        failed += 1
print(f"{passed} passed, {failed} failed")
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
