#!/bin/sh
# e2e.sh - runs the real sagitta editor inside tmux, types at it and reads
# the screen back.  Output is TAP.  Usage: e2e.sh PATH/TO/sagitta
#
# Independent references: Zemax's printed y on surface 8 of the Cassegrain
# (-162.77753496, the paper's Table 4), and "sagitta trace", a separate
# program path, for the ray the editor shows and exports.
#
# Every wait is bounded, and the private tmux server is killed on any exit.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 10 e2e

cp "$ROOT/examples/cassegrain.json" "$WORK/cassegrain.json"

# Waits up to $2 seconds (default 10) for fixed text $1 on the screen.
wait_for() {
    n=$(( ${2:-10} * 10 ))
    while [ "$n" -gt 0 ]; do
        if screen | grep -qF -- "$1"; then
            return 0
        fi
        # No session, or the editor gone: fail now rather than time out.
        if ! $T has-session -t =main 2>/dev/null; then
            echo "# the tmux session is gone"
            return 1
        fi
        case $1 in
        EXITED*) ;;
        *)
            if screen | grep -q '^EXITED'; then
                echo "# the editor exited"
                return 1
            fi
            ;;
        esac
        sleep 0.1
        n=$((n - 1))
    done
    echo "# timed out waiting for: $1"
    return 1
}

# Waits up to $2 seconds (default 5) for a line that is exactly $1.
wait_line() {
    n=$(( ${2:-5} * 10 ))
    while [ "$n" -gt 0 ]; do
        if screen | grep -qxF -- "$1"; then
            return 0
        fi
        sleep 0.1
        n=$((n - 1))
    done
    echo "# timed out waiting for the line: $1"
    return 1
}

# Waits until fixed text $1 is gone.
wait_gone() {
    n=$(( ${2:-10} * 10 ))
    while [ "$n" -gt 0 ]; do
        if ! screen | grep -qF -- "$1"; then
            return 0
        fi
        sleep 0.1
        n=$((n - 1))
    done
    echo "# timed out waiting for this to go: $1"
    return 1
}

command_line() { # runs a ':' command
    keys Escape
    type_text ":$1"
    keys Enter
}

# The full-precision y of the cursor's surface, from the detail panel.
detail_y() {
    screen | grep -o '\(^\| \)y=[^ ]*' | head -n 1 | sed 's/^ *y=//'
}

# y of surface $2 from "sagitta trace" CSV output in file $1.
csv_y() {
    # A normalized ray's rows: hx,hy,px,py,surface,x,y,...
    awk -F, -v s="$2" '$5 == s { print $7 }' "$1"
}

# Numeric equality of two decimal strings as doubles (awk reads them with
# strtod, so equal text means equal bits and vice versa for %.17g).
same_number() {
    awk -v a="$1" -v b="$2" 'BEGIN { exit !(a != "" && b != "" && a + 0 == b + 0) }'
}

# Starts the editor on $1 in a $2 x $3 window as session "main".  The new
# session exists before the old one goes, so the server never stops (a
# server restarting on the same socket can race with its predecessor).
start() { # file, width, height
    rm -f "$WORK/pid"
    $T new-session -d -s fresh -x "$2" -y "$3" \
        "cd '$WORK' && sh -c 'echo \$\$ >pid; exec \"\$0\" \"\$1\"' '$SAGITTA' '$1'; echo \"EXITED \$?\"; stty -a | tr ' ' '\\n' | grep -x -- '-\\{0,1\\}icanon'; sleep 60"
    $T kill-session -t =main >/dev/null 2>&1
    $T rename-session -t =fresh main 2>/dev/null
}

# ---------------------------------------------------------------------------
# 1. The Cassegrain opens and shows surface 8's y as -162.77753496...
start cassegrain.json 100 30
if wait_for "cassegrain.json" 15 && wait_for "Surf"; then
    command_line "ray 0 1 0 1"
    command_line "goto 8"
    if wait_for "Surface 8:" && wait_for "y=-162.77753496"; then
        Y0=$(detail_y)
        echo "# surface 8 y on screen: $Y0 (Zemax: -162.77753496)"
        ok "the Cassegrain opens and shows surface 8 y = -162.77753496..."
    else
        not_ok "the Cassegrain opens and shows surface 8 y = -162.77753496..."
    fi
else
    not_ok "the Cassegrain opens"
fi

# 2. Editing a radius changes the traced coordinates on screen.
command_line "goto 3 radius"
wait_for "Surface 3:" >/dev/null
type_text "-3900"
keys Enter
wait_for "surface 3 radius = -3900" >/dev/null
command_line "goto 8"
wait_for "Surface 8:" >/dev/null
sleep 0.2
Y1=$(detail_y)
# The same edit saved by batch mode, traced by "sagitta trace".
printf 'set 3 radius -3900\nsave %s\n' "$WORK/r3900.json" >"$WORK/r3900.cmd"
"$SAGITTA" edit "$WORK/cassegrain.json" --batch "$WORK/r3900.cmd" 2>/dev/null
"$SAGITTA" trace "$WORK/r3900.json" --ray 0,1,0,1 --format csv >"$WORK/r3900.csv" 2>/dev/null
Y1REF=$(csv_y "$WORK/r3900.csv" 8)
echo "# surface 8 y after radius 3 = -3900: $Y1 (sagitta trace of that design: $Y1REF)"
check "editing a radius changes the traced coordinates to what sagitta trace computes" \
    sh -c "[ -n '$Y1' ] && [ '$Y1' != '$Y0' ] && awk -v a='$Y1' -v b='$Y1REF' 'BEGIN { exit !(b != \"\" && a + 0 == b + 0) }'"

# 3. Undo restores them.
keys u
wait_for "undid 1 change" >/dev/null
command_line "goto 8"
wait_for "Surface 8:" >/dev/null
sleep 0.2
Y2=$(detail_y)
echo "# surface 8 y after undo: $Y2"
check "undo restores the coordinates exactly" sh -c "[ -n '$Y2' ] && [ '$Y2' = '$Y0' ]"

# 4. Setting Hy and Py in the ray selector changes the ray.  Hy != Py, so
# a swap of the two would trace another ray.
keys f Right
type_text "0.25"
keys Enter
keys Right Right
type_text "0.75"
keys Enter f
command_line "goto 8"
wait_for "Hy 0.25" >/dev/null
wait_for "Py 0.75" >/dev/null
sleep 0.2
Y3=$(detail_y)
"$SAGITTA" trace "$WORK/cassegrain.json" --ray 0,0.25,0,0.75 --format csv >"$WORK/half.csv" 2>/dev/null
YREF=$(csv_y "$WORK/half.csv" 8)
echo "# ray (0, 0.25, 0, 0.75): screen y = $Y3, sagitta trace y = $YREF"
if [ "$Y3" != "$Y0" ] && same_number "$Y3" "$YREF"; then
    ok "setting Hy and Py changes the ray to what sagitta trace computes"
else
    not_ok "setting Hy and Py changes the ray to what sagitta trace computes"
fi

# 5. Export writes a CSV whose numbers equal "sagitta trace".
command_line "ray 0 1 0 1"
command_line "export ray.csv csv"
wait_for "exported 1 ray to ray.csv" >/dev/null
"$SAGITTA" trace "$WORK/cassegrain.json" --ray 0,1,0,1 --format csv >"$WORK/ref.csv" 2>/dev/null
grep -E '^[0-9]' "$WORK/ray.csv" 2>/dev/null >"$WORK/a.txt"
grep -E '^[0-9]' "$WORK/ref.csv" >"$WORK/b.txt"
ROWS=$(wc -l <"$WORK/b.txt")
echo "# exported $(wc -l <"$WORK/a.txt") rows; sagitta trace wrote $ROWS"
check "export writes a CSV whose numbers equal sagitta trace" \
    sh -c "[ $ROWS -gt 0 ] && cmp -s '$WORK/a.txt' '$WORK/b.txt'"

# 6. Save writes a file that loads back bit-exact.
command_line "set 3 radius -3846.0000000000005"
wait_for "[+]" >/dev/null
command_line "save saved.json"
wait_for "saved saved.json" >/dev/null
wait_gone "[+]" >/dev/null
# The same edit made in batch mode and saved must give the same bytes, and
# the file must read back with the 17-digit value intact.
printf 'set 3 radius -3846.0000000000005\nsave %s\n' "$WORK/batch.json" >"$WORK/save.cmd"
"$SAGITTA" edit "$WORK/cassegrain.json" --batch "$WORK/save.cmd" 2>"$WORK/err.txt"
printf 'print cell 3 radius\n' >"$WORK/print.cmd"
BACK=$("$SAGITTA" edit "$WORK/saved.json" --batch "$WORK/print.cmd" 2>&1)
echo "# saved.json reads back radius 3 = $BACK"
check "save writes a file that loads back bit-exact" \
    sh -c "[ -s '$WORK/saved.json' ] && cmp -s '$WORK/saved.json' '$WORK/batch.json' && [ '$BACK' = '-3846.0000000000005' ]"

# 7. Quitting with unsaved changes asks first; cancel keeps the editor.
# The cursor is in the Comment cell, where q types; Esc, q is the command.
command_line "set 3 comment changed"
wait_for "[+]" >/dev/null
keys Escape q
if wait_for "Unsaved changes" 5; then
    keys c
    if wait_gone "Unsaved changes" 5 && ! screen | grep -q "EXITED"; then
        keys Escape q
        wait_for "Unsaved changes" 5 >/dev/null
        keys n
        if wait_for "EXITED 0" 5; then
            ok "quit with unsaved changes asks first; n quits without saving"
        else
            not_ok "quit with unsaved changes asks first; n quits without saving"
        fi
    else
        not_ok "cancel keeps the editor running"
    fi
else
    not_ok "quit with unsaved changes asks first"
fi

# 8. The terminal is restored after quitting (canonical mode back on).
# The shell after the editor prints stty's canonical-mode flag.
check "the terminal is restored on quit" wait_line icanon

# 9. It works in 80x24 and survives resizing.
start cassegrain.json 80 24
if wait_for "cassegrain.json" 15 && wait_for "Surf"; then
    $T resize-window -t =main: -x 120 -y 40 2>/dev/null
    sleep 0.3
    $T resize-window -t =main: -x 80 -y 24 2>/dev/null
    command_line "goto 8"
    if wait_for "Surface 8:" && wait_for "EFL" && ! screen | grep -q "EXITED"; then
        ok "works in 80x24 and after resizing"
    else
        not_ok "works in 80x24 and after resizing"
    fi
else
    not_ok "works in 80x24"
fi

# 10. SIGTERM ends it with the terminal restored.
CHILD=$(cat "$WORK/pid" 2>/dev/null)
started "$CHILD"
if [ -n "$CHILD" ]; then
    kill -TERM "$CHILD" 2>/dev/null
    if wait_for "EXITED 143" 5 && wait_line icanon; then
        ok "SIGTERM exits (status 143) with the terminal restored"
    else
        not_ok "SIGTERM exits (status 143) with the terminal restored"
    fi
else
    not_ok "SIGTERM: cannot find the editor's process"
fi

[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
