# tmuxlib.sh - what the tmux end-to-end scripts share: the environment, the
# private tmux server and scratch directory, their cleanup, and TAP output.
# Source it, then call tmux_setup NTESTS NAME.
#
# Sets SAGITTA (absolute), ROOT, WORK, T (the tmux command) and
# XDG_STATE_HOME (inside WORK, never the user's own).  A script may define
# diag_extra to add lines after a failure's screen dump, and set WHY to say
# why a check failed.

diag_extra() { :; }

tmux_setup() {
    NTESTS=$1
    ROOT=${SAGITTA_SOURCE_ROOT:-$(cd "$(dirname "$0")/../.." && pwd)}
    export SAGITTA_LENSDB=${SAGITTA_LENSDB:-$ROOT/lensdb}
    export SAGITTA_EXAMPLES=${SAGITTA_EXAMPLES:-$ROOT/examples}
    # A UTF-8 locale lets tmux and the editor agree on the ellipsis;
    # numbers are ASCII either way.
    export LC_ALL=C.UTF-8
    unset NO_COLOR TMUX

    echo "1..$NTESTS"
    if [ -z "$SAGITTA" ] || [ ! -x "$SAGITTA" ]; then
        echo "# no sagitta program given"
        i=1; while [ $i -le "$NTESTS" ]; do echo "not ok $i - program missing"; i=$((i + 1)); done
        exit 1
    fi
    case $SAGITTA in /*) ;; *) SAGITTA=$(pwd)/$SAGITTA ;; esac
    # Without tmux the cases are skipped, and counted as skips; in CI
    # (CI=true) a missing tool is a failure, never a suite that vanishes.
    if ! command -v tmux >/dev/null 2>&1; then
        case ${CI:-} in
        ''|0|false|no)
            i=1; while [ $i -le "$NTESTS" ]; do echo "ok $i # SKIP tmux is not installed"; i=$((i + 1)); done
            exit 0 ;;
        *)
            i=1; while [ $i -le "$NTESTS" ]; do echo "not ok $i - tmux is not installed (CI=$CI)"; i=$((i + 1)); done
            exit 1 ;;
        esac
    fi

    WORK=$(mktemp -d "${TMPDIR:-/tmp}/sg-$2-XXXXXX")
    export XDG_STATE_HOME="$WORK/state"
    T="tmux -L sg-$2-$$ -f /dev/null"
    # Under AddressSanitizer, LeakSanitizer's stop-the-world tracer can
    # deadlock at exit in a process whose terminal has just hung up, leaving
    # the editor spinning; the editor's leaks are checked outside tmux.
    ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
    export ASAN_OPTIONS
    trap tmux_cleanup EXIT
    trap 'exit 2' INT TERM HUP
    N=0
    FAILED=0
    WHY=
}

tmux_cleanup() {
    $T kill-server >/dev/null 2>&1
    # No editor this script started may outlive it.
    [ -f "$WORK/started" ] && xargs kill -9 <"$WORK/started" >/dev/null 2>&1
    rm -rf "$WORK"
}

# Records an editor's pid so tmux_cleanup can make sure it is gone.
started() { [ -n "$1" ] && echo "$1" >>"$WORK/started"; }

# Waits up to $2 seconds (default 10) for a line of the screen that
# matches the extended regex $1; WHY says what it waited for.
wait_re() {
    n=$(( ${2:-10} * 10 ))
    while [ "$n" -gt 0 ]; do
        screen | grep -qE -- "$1" && return 0
        sleep 0.1
        n=$((n - 1))
    done
    WHY="timed out waiting for a line like: $1"
    return 1
}

# Waits up to $2 seconds (default 10) for text $1 to leave the screen.
wait_gone() {
    n=$(( ${2:-10} * 10 ))
    while [ "$n" -gt 0 ]; do
        screen | grep -qF -- "$1" || return 0
        sleep 0.1
        n=$((n - 1))
    done
    WHY="timed out waiting for this to go: $1"
    return 1
}

# Waits up to $2 seconds (default 10) for text $1 on the screen.
wait_for() {
    n=$(( ${2:-10} * 10 ))
    while [ "$n" -gt 0 ]; do
        screen | grep -qF -- "$1" && return 0
        if ! $T has-session -t =main 2>/dev/null; then
            echo "# the tmux session is gone"
            return 1
        fi
        sleep 0.1
        n=$((n - 1))
    done
    echo "# timed out waiting for: $1"
    return 1
}

# Types a ':' command and Enter, from the spreadsheet.
command_line() {
    keys Escape
    type_text ":$1"
    keys Enter
}

# Starts the editor on file $1 in a window $2 x $3 as the session "main",
# with the environment assignments $4 (may be empty), replacing any
# earlier session, and records its pid.
start() {
    $T new-session -d -s fresh -x "$2" -y "$3" \
        "cd '$WORK' && $4 sh -c 'echo \$\$ >pid; exec \"\$0\" \"\$1\"' '$SAGITTA' '$1'; echo \"EXITED \$?\"; sleep 60"
    $T kill-session -t =main >/dev/null 2>&1
    $T rename-session -t =fresh main 2>/dev/null
    sleep 0.2
    started "$(cat "$WORK/pid" 2>/dev/null)"
}

screen() { $T capture-pane -p -t =main: 2>/dev/null; }
keys() { $T send-keys -t =main: "$@" 2>/dev/null; }
type_text() { $T send-keys -t =main: -l -- "$1" 2>/dev/null; }

ok() {
    N=$((N + 1))
    echo "ok $N - $1"
}
not_ok() {
    N=$((N + 1))
    FAILED=$((FAILED + 1))
    echo "not ok $N - $1"
    [ -n "$WHY" ] && echo "# $WHY"
    echo "# screen was:"
    screen | sed 's/^/#   /'
    diag_extra
}
# Runs a description, then a command that must succeed.
check() {
    d=$1
    shift
    WHY=
    if "$@"; then ok "$d"; else not_ok "$d"; fi
}
