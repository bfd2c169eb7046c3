#!/bin/sh
# e2e_recovery.sh - no edit is lost: the real editor runs in tmux, a radius
# is edited and not saved, and the editor dies six ways: SIGTERM, SIGHUP,
# the tmux session closed under it (with and without the SIGHUP that
# brings), SIGKILL and SIGSEGV.  Each time the next start must offer the
# recovery file, bring the edit back on y, and save it to the original
# file.  Output is TAP.  Usage: e2e_recovery.sh PATH/TO/sagitta
#
# Independent references: the value typed (-3900, against the file's -3846),
# and a copy of the design given the same edit by a batch script (a
# separate program path); the recovered and saved file must equal it byte
# for byte.
#
# Every wait is bounded; the private tmux server and the scratch directory
# (which also holds XDG_STATE_HOME) go on any exit.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 24 rec
RECDIR=$XDG_STATE_HOME/sagitta

diag_extra() {
    echo "# recovery directory:"
    ls -l "$RECDIR" 2>&1 | sed 's/^/#   /'
}

# Waits up to $2 seconds (default 10) for fixed text $1 on the screen.
wait_for() {
    n=$(( ${2:-10} * 10 ))
    while [ "$n" -gt 0 ]; do
        screen | grep -qF -- "$1" && return 0
        sleep 0.1
        n=$((n - 1))
    done
    WHY="timed out waiting for: $1"
    return 1
}

# Waits up to 5 s for process $1 to be gone (a zombie counts as gone).
wait_dead() {
    # Up to 20 s: under AddressSanitizer the leak check at exit alone can
    # take seconds on a loaded machine.
    n=200
    while [ "$n" -gt 0 ]; do
        if ! kill -0 "$1" 2>/dev/null; then return 0; fi
        case $(sed 's/.*) \(.\).*/\1/' "/proc/$1/stat" 2>/dev/null) in Z | X) return 0 ;; esac
        sleep 0.1
        n=$((n - 1))
    done
    WHY="process $1 is still alive"
    return 1
}

# Waits up to 5 s until the recovery directory holds exactly $1 files.
nrec() { ls "$RECDIR" 2>/dev/null | grep -c '\.sgrec$'; }
wait_nrec() {
    n=50
    while [ "$n" -gt 0 ]; do
        [ "$(nrec)" -eq "$1" ] && return 0
        sleep 0.1
        n=$((n - 1))
    done
    WHY="the recovery directory holds $(nrec) files, not $1"
    return 1
}

command_line() {
    keys Escape
    type_text ":$1"
    keys Enter
}

# Starts the editor (arguments $1, may be empty) in the scratch directory
# as session "main", in a window $2 x $3 (default 110 x 30).  A session "keep" holds the server up, so closing
# "main" never restarts the server on the same socket.
start() {
    rm -f "$WORK/pid"
    $T has-session -t =keep 2>/dev/null ||
        $T new-session -d -s keep -x 40 -y 5 "sleep 600"
    $T kill-session -t =main >/dev/null 2>&1
    if [ "$START_MODE" = setsid ]; then
        # A session of its own, without a controlling terminal: when the
        # terminal goes no SIGHUP comes, and only the dead input says so.
        run="setsid sh -c '\"\$0\" \$1 0<&3 3<&- & echo \$! >pid; wait \$!' '$SAGITTA' '$1' 3<&0"
    else
        run="sh -c 'echo \$\$ >pid; exec \"\$0\" \$1' '$SAGITTA' '$1'"
    fi
    # An editor killed outright leaves the terminal raw and its cursor
    # anywhere, so the status line starts at column 0 of a line of its own.
    $T new-session -d -s main -x "${2:-110}" -y "${3:-30}" \
        "cd '$WORK' && ulimit -c 0; $run; st=\$?; printf '\\r\\n'; echo \"EXITED \$st\"; stty -a | tr ' ' '\\n' | grep -x -- '-\\{0,1\\}icanon'; sleep 60"
    n=50
    while [ ! -s "$WORK/pid" ] && [ "$n" -gt 0 ]; do sleep 0.1; n=$((n - 1)); done
    PID=$(cat "$WORK/pid" 2>/dev/null)
    started "$PID"
}

# The line of surface 3 in the spreadsheet shows radius $1.
radius3_is() {
    wait_re "^ +3 STANDARD .* $1 +3689 " 5
}

# The reference: the original design with the same edit, made in batch mode.
cp "$ROOT/examples/cassegrain.json" "$WORK/orig.json"
printf 'set 3 radius -3900\nsave %s\n' "$WORK/ref.json" >"$WORK/ref.cmd"
"$SAGITTA" edit "$WORK/orig.json" --batch "$WORK/ref.cmd" >/dev/null 2>&1
printf 'print cell 3 radius\n' >"$WORK/print.cmd"

# Opens a fresh copy of the design, edits surface 3's radius by typing into
# its cell, and waits until the recovery file exists.
edit_copy() {
    # Each case starts from an empty directory, so one failure does not
    # spill into the next.
    rm -f "$RECDIR"/*.sgrec
    cp "$WORK/orig.json" "$WORK/c.json"
    start c.json
    wait_for "c.json" 15 && wait_for "Surf" || return 1
    command_line "goto 3 radius"
    wait_for "Surface 3:" || return 1
    type_text "-3900"
    keys Enter
    wait_for "surface 3 radius = -3900" && wait_for "c.json [+]" && wait_nrec 1
}

# After a kill: the editor is gone, the recovery file stays, and (for the
# signals it can catch) the exit status and the terminal modes are right.
died_well() { # expected "EXITED N" text or "", whether to check stty
    wait_dead "$PID" || return 1
    if [ -n "$1" ]; then
        wait_for "$1" 5 || return 1
    fi
    if [ "$2" = stty ]; then
        wait_re '^icanon$' 5 || { WHY="the terminal was left in raw mode"; return 1; }
    fi
    [ "$(nrec)" -eq 1 ] || { WHY="$(nrec) recovery files after the kill"; return 1; }
    grep -q "\"pid\":$PID," "$RECDIR"/*.sgrec || { WHY="the file is not the dead editor's"; return 1; }
}

recovered() {
    start c.json
    wait_for "Recover unsaved changes to c.json from" 15 || return 1
    wait_for "(r)ecover / (d)iscard / (l)ater" || return 1
    keys r
    wait_for "recovered unsaved changes to" || return 1
    radius3_is -3900 || return 1
    wait_for "c.json [+]" || return 1
    # The dead editor's file is gone; ours, with the same content, took over.
    wait_nrec 1 && ! grep -q "\"pid\":$OLDPID," "$RECDIR"/*.sgrec
}

saved_back() {
    command_line "w"
    wait_for "saved " || return 1
    wait_gone "c.json [+]" || return 1
    wait_nrec 0 || return 1
    cmp -s "$WORK/c.json" "$WORK/ref.json" || { WHY="c.json differs from ref.json"; return 1; }
    BACK=$("$SAGITTA" edit "$WORK/c.json" --batch "$WORK/print.cmd" 2>&1)
    echo "# the saved file reads back radius 3 = $BACK (typed -3900; the original is -3846)"
    [ "$BACK" = "-3900" ] || return 1
    keys q
    wait_for "EXITED 0" 5 && wait_nrec 0
}

round() { # name, kill action, expected exit text, stty|-, start mode
    name=$1
    if [ "$5" = setsid ] && ! command -v setsid >/dev/null 2>&1; then
        for t in "dies" "offers recovery" "saves"; do
            N=$((N + 1))
            echo "ok $N # SKIP $name: $t (no setsid program)"
        done
        return
    fi
    START_MODE=$5
    edit_copy
    rc=$?
    START_MODE=
    if [ $rc -eq 0 ]; then
        OLDPID=$PID
        case $2 in
        pane) $T kill-session -t =main 2>/dev/null ;;
        *) kill "-$2" "$PID" 2>/dev/null ;;
        esac
        check "$name: the editor dies and its recovery file stays" died_well "$3" "$4"
    else
        not_ok "$name: editing a radius writes a recovery file"
        OLDPID=$PID
    fi
    check "$name: the next start offers recovery; r shows radius -3900, modified" recovered
    check "$name: save writes the recovered edit to the file; no recovery file remains" \
        saved_back
}

T0=$(date +%s)

# 1-18. Six ways to die mid-edit.
round "SIGTERM" TERM "EXITED 143" stty
round "SIGHUP" HUP "EXITED 129" stty
round "terminal closed (tmux kill-session)" pane "" -
round "terminal closed, no SIGHUP sent (setsid)" pane "" - setsid
round "SIGKILL" KILL "EXITED 137" -
# A crash: the handler gives the terminal back with async-signal-safe calls
# only, then dies of the signal.
round "SIGSEGV (a crash)" SEGV "EXITED 139" stty

# 19. "later" keeps the file, and the design opens as it is on disk.
later() {
    edit_copy || return 1
    kill -TERM "$PID"
    wait_dead "$PID" || return 1
    start c.json
    wait_for "Recover unsaved changes to c.json" 15 || return 1
    keys l
    wait_for "kept for later" || return 1
    radius3_is -3846 || return 1
    wait_gone "c.json [+]" || return 1
    # Quitting cleanly removes only this editor's own file.
    keys q
    wait_for "EXITED 0" 5 && wait_nrec 1
}
check "l (later) keeps the recovery file and opens the file as saved" later

# 20. Batch mode never asks: it warns, naming the file, and goes on.
batch_warns() {
    REC=$(ls "$RECDIR"/*.sgrec 2>/dev/null)
    OUT=$("$SAGITTA" edit "$WORK/c.json" --batch "$WORK/print.cmd" 2>"$WORK/err.txt")
    RC=$?
    echo "# batch: exit $RC, stdout $OUT, stderr: $(cat "$WORK/err.txt")"
    [ "$RC" -eq 0 ] && [ "$OUT" = "-3846" ] && grep -q "warning: .*$REC" "$WORK/err.txt" &&
        [ "$(nrec)" -eq 1 ]
}
check "--batch warns naming the recovery file, and runs the script" batch_warns

# 21. d (discard), then a capital D, deletes it; y and n answer nothing,
# and a lower-case d a second time deletes nothing.  In 80 columns the
# answers come first, so they show.
discard() {
    start c.json 80 24
    wait_for "Recover unsaved changes? (r)ecover / (d)iscard / (l)ater: c.json" 15 || return 1
    keys y n
    sleep 0.5
    wait_for "(r)ecover / (d)iscard / (l)ater" || { WHY="y or n answered the question"; return 1; }
    radius3_is -3846 || return 1
    keys d
    wait_for "Delete the recovery file" || return 1
    keys d y n
    sleep 0.5
    [ "$(nrec)" -eq 1 ] || { WHY="d, y or n deleted the file"; return 1; }
    wait_for "Delete the recovery file" || return 1
    keys b
    wait_for "(r)ecover / (d)iscard / (l)ater" || return 1
    keys d
    wait_for "D (capital) deletes" || return 1
    keys D
    wait_for "deleted " || return 1
    wait_nrec 0 && radius3_is -3846 && wait_gone "c.json [+]" || return 1
    keys q
    wait_for "EXITED 0" 5
}
check "d then a capital D deletes the recovery file; y, n and a second d do not (80x24)" discard

# 22. A design never saved is recovered by a start without a file.
untitled() {
    rm -f "$RECDIR"/*.sgrec
    start ""
    wait_for "new design" 15 || return 1
    command_line "set 1 radius 55.5"
    wait_for "[new design] [+]" || return 1
    wait_nrec 1 || return 1
    kill -HUP "$PID"
    wait_dead "$PID" && wait_for "EXITED 129" 5 || return 1
    OLDPID=$PID
    start ""
    wait_for "Recover unsaved changes to an untitled design" 15 || return 1
    keys r
    wait_for "recovered an untitled design" || return 1
    wait_re "^[A-Z]* +1 STANDARD .* 55\\.5 " 5 && wait_for "[new design] [+]" || return 1
    command_line "w new.json"
    wait_for "saved new.json" && wait_nrec 0 || return 1
    BACK=$(printf 'print cell 1 radius\n' | "$SAGITTA" edit "$WORK/new.json" --batch - 2>&1)
    echo "# the untitled design, recovered and saved, reads back radius 1 = $BACK"
    [ "$BACK" = "55.5" ] || return 1
    keys q
    wait_for "EXITED 0" 5
}
check "an untitled design is recovered by a start without a file (after SIGHUP)" untitled

# 23. A clean quit that discards the edits leaves nothing behind.
clean_quit() {
    edit_copy || return 1
    command_line "quit!"
    wait_for "EXITED 0" 5 && wait_nrec 0 && cmp -s "$WORK/c.json" "$WORK/orig.json"
}
check "quit! after edits removes the recovery file and leaves the file alone" clean_quit

# 24. A save that fails (the name is a directory) says so, changes nothing
# on disk and keeps the edit, modified and protected.
failed_save() {
    edit_copy || return 1
    mkdir -p "$WORK/adir"
    command_line "w adir"
    wait_for "not saved: adir" || return 1
    wait_for "c.json [+]" && radius3_is -3900 && wait_nrec 1 || return 1
    [ -d "$WORK/adir" ] && [ -z "$(ls -A "$WORK/adir")" ] || { WHY="adir changed"; return 1; }
    ls "$WORK" | grep -q '^adir\.' && { WHY="a temporary file was left"; return 1; }
    cmp -s "$WORK/c.json" "$WORK/orig.json" || { WHY="c.json changed"; return 1; }
    command_line "quit!"
    wait_for "EXITED 0" 5 && wait_nrec 0
}
check "a failed save reports it, leaves the files alone and keeps the edit" failed_save

echo "# $(( $(date +%s) - T0 )) s"
[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
