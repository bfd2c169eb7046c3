#!/bin/sh
# e2e_keys.sh - keys do what they say, no work is lost and the screen shows
# what a Zemax user needs: the real editor runs in tmux, is typed at, and
# its screen and files are read back.  Output is TAP.
# Usage: e2e_keys.sh PATH/TO/sagitta
#
# Independent references: files written by this script (cp, printf),
# "sagitta paraxial" and "sagitta trace" (separate program paths), awk's
# arithmetic for Zemax's field normalization (6 / sqrt(6^2 + 6.5^2)), and
# the design's own text (the TMA's title) for where a cut may fall.
#
# Every wait is bounded; the private tmux server and the scratch directory
# (which also holds XDG_STATE_HOME) go on any exit.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 26 keys
RECDIR=$XDG_STATE_HOME/sagitta

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
wait_dead() {
    n=200
    while [ "$n" -gt 0 ]; do
        kill -0 "$1" 2>/dev/null || return 0
        case $(sed 's/.*) \(.\).*/\1/' "/proc/$1/stat" 2>/dev/null) in Z | X) return 0 ;; esac
        sleep 0.1
        n=$((n - 1))
    done
    WHY="process $1 is still alive"
    return 1
}
nrec() { ls "$RECDIR" 2>/dev/null | grep -c '\.sgrec$'; }

command_line() {
    keys Escape
    type_text ":$1"
    keys Enter
}

# Starts the editor on $1 (may be empty) in a $2 x $3 window as session
# $4 (default main).  A session "keep" holds the server up.
start() {
    s=${4:-main}
    rm -f "$WORK/pid.$s"
    $T has-session -t =keep 2>/dev/null ||
        $T new-session -d -s keep -x 40 -y 5 "sleep 600"
    $T kill-session -t "=$s" >/dev/null 2>&1
    $T new-session -d -s "$s" -x "${2:-110}" -y "${3:-30}" \
        "cd '$WORK' && ulimit -c 0; sh -c 'echo \$\$ >pid.$s; exec \"\$0\" \$1' '$SAGITTA' '$1'; st=\$?; printf '\\r\\n'; echo \"EXITED \$st\"; sleep 60"
    n=50
    while [ ! -s "$WORK/pid.$s" ] && [ "$n" -gt 0 ]; do sleep 0.1; n=$((n - 1)); done
    PID=$(cat "$WORK/pid.$s" 2>/dev/null)
    started "$PID"
}

# Quits the editor in session main, discarding changes.
stop() {
    command_line "quit!"
    wait_for "EXITED 0" 5
}

cp "$ROOT/examples/cassegrain.json" "$WORK/c.json"
cp "$ROOT/examples/tma.json" "$WORK/tma.json"
cp "$ROOT/examples/cooke_triplet.json" "$WORK/cooke.json"
T0=$(date +%s)

# 1. Ctrl-W (save as) onto an unrelated file asks; n keeps the file.
saveas_asks() {
    printf 'notes that are not a design\n' >"$WORK/notes.txt"
    start c.json 100 30
    wait_for "c.json" 15 && wait_for "Surf" || return 1
    command_line "set 3 radius -3900"
    wait_for "c.json [+]" || return 1
    keys C-w
    type_text "notes.txt"
    keys Enter
    wait_for "notes.txt already exists. Overwrite it? (y)es (n)o" || return 1
    keys n
    wait_for "not saved" || return 1
    [ "$(cat "$WORK/notes.txt")" = "notes that are not a design" ] || { WHY="notes.txt changed"; return 1; }
    command_line "save! notes.txt"
    wait_for "saved notes.txt" || return 1
    grep -q sagitta-design "$WORK/notes.txt" || { WHY="save! did not write"; return 1; }
}
check "save as (Ctrl-W) onto an existing file asks first; n keeps it; :save! writes" saveas_asks

# 2. A save over a file changed on disk since it was read asks.
disk_changed() {
    cp "$ROOT/examples/cassegrain.json" "$WORK/d.json"
    command_line "open! d.json"
    wait_for "d.json: " || return 1
    command_line "set 3 radius -3900"
    wait_for "d.json [+]" || return 1
    # Another program rewrites it.
    cp "$ROOT/examples/singlet.json" "$WORK/d.json"
    command_line "w"
    wait_for "d.json changed on disk since it was read. Overwrite it?" || return 1
    keys n
    wait_for "not saved" || return 1
    cmp -s "$WORK/d.json" "$ROOT/examples/singlet.json" || { WHY="d.json was overwritten"; return 1; }
    command_line "w"
    wait_for "changed on disk" || return 1
    keys y
    wait_for "saved d.json" && wait_gone "d.json [+]" || return 1
    cmp -s "$WORK/d.json" "$ROOT/examples/singlet.json" && { WHY="y did not save"; return 1; }
    return 0
}
check "a save over a file changed on disk asks; n leaves it, y saves" disk_changed

# 3. A second editor on the same file warns at open, naming the first.
second_editor() {
    FIRST=$PID
    command_line "open! c.json"
    wait_for "c.json: " || return 1
    start c.json 150 30 second
    n=50
    while [ "$n" -gt 0 ]; do
        $T capture-pane -p -t =second: | grep -qF "c.json is open in another editor (pid $FIRST" && break
        sleep 0.1
        n=$((n - 1))
    done
    OUT=$($T capture-pane -p -t =second: | tail -n 1)
    echo "# second editor's status line: $OUT"
    $T send-keys -t =second: Escape ":quit!" Enter
    [ "$n" -gt 0 ] || { WHY="no warning in the second editor"; return 1; }
}
check "a second editor on the same file warns, naming the first one's pid" second_editor

# 4. Typing "primary" into a Comment puts it there and runs nothing.
comment_typing() {
    command_line "open! c.json"
    wait_for "c.json: " || return 1
    command_line "goto 2 comment"
    wait_for "Surface 2:" || return 1
    type_text "primary"
    keys Enter
    wait_for "surface 2 comment = primary" || return 1
    wait_for "precise" || { WHY="the method changed"; return 1; }
    command_line "w"
    wait_for "saved c.json" || return 1
    printf 'print cell 2 comment\nprint cell ima type\n' >"$WORK/p.cmd"
    BACK=$("$SAGITTA" edit "$WORK/c.json" --batch "$WORK/p.cmd" 2>&1)
    NS=$(grep -c '"type"' "$WORK/c.json")
    NS0=$(grep -c '"type"' "$ROOT/examples/cassegrain.json")
    echo "# comment back: $(echo $BACK); \"type\" keys: $NS (original $NS0)"
    [ "$(echo "$BACK" | head -n 1)" = "primary" ] && [ "$NS" -eq "$NS0" ] || return 1
    # Esc, then a key, is the key's command there.
    keys Escape c
    wait_for "ray Hx 0 Hy" || { WHY="Esc c did not run chief"; return 1; }
}
check "typing \"primary\" into a Comment puts it there and runs no command; Esc c is chief" comment_typing

# 5. Three steps of 0.1 give Hy 0.3, on screen and in an export.
decimal_steps() {
    # Off the Comment cell, where f would be typed.
    command_line "goto 2 radius"
    command_line "ray 0 0 0 1"
    keys f
    wait_for "step 0.1" || return 1
    keys Right
    keys Up Up Up
    wait_for "ray Hx 0 Hy 0.3 Px 0 Py 1" || return 1
    wait_re "Hy 0\\.3 " || return 1
    keys f
    command_line "export step.csv"
    wait_for "exported 1 ray" || return 1
    grep -q '0\.30000000000000004' "$WORK/step.csv" && { WHY="the export holds 0.30000000000000004"; return 1; }
    screen | grep -q '0\.30000000000000004' && { WHY="the screen shows 0.30000000000000004"; return 1; }
    return 0
}
check "three Up steps of 0.1 give Hy 0.3 exactly (screen, message, export)" decimal_steps

# 6. :print paraxial opens the system data: what sagitta paraxial prints.
sysdata() {
    command_line "print paraxial"
    wait_for "System data" || return 1
    "$SAGITTA" paraxial "$WORK/c.json" >"$WORK/par.txt" 2>/dev/null || return 1
    for k in "Entrance pupil position" "Entrance pupil diameter" "Exit pupil position" \
        "Exit pupil diameter" "Paraxial image height" "Object space NA" \
        "Paraxial working F/#" "Paraxial magnification"; do
        want=$(grep -F "$k" "$WORK/par.txt" | sed 's/.*:  //')
        screen | grep -F "$k" | grep -qF -- "$want" || { WHY="$k: want $want"; return 1; }
    done
    wait_for "Lens units              :  mm" || return 1
    keys Escape
    wait_gone "System data"
}
check ":print paraxial shows every value sagitta paraxial prints, and the units" sysdata

# 7. The field picker: field 2 of the TMA is (6, 6.5) deg.
field_pick() {
    command_line "open! tma.json"
    wait_for "tma.json: " || return 1
    command_line "field 2"
    wait_for "field 2 (6, 6.5 deg): Hx" || return 1
    HX=$(screen | sed -n 's/.*field 2 (6, 6.5 deg): Hx \([^ ]*\) Hy \([^ ]*\).*/\1/p')
    HY=$(screen | sed -n 's/.*field 2 (6, 6.5 deg): Hx \([^ ]*\) Hy \([^ ]*\).*/\2/p')
    echo "# field 2: Hx $HX Hy $HY"
    awk -v a="$HX" -v b="$HY" 'BEGIN { r = sqrt(6 * 6 + 6.5 * 6.5);
        exit !(a + 0 == 6 / r && b + 0 == 6.5 / r) }' || { WHY="not 6/sqrt(78.25), 6.5/sqrt(78.25)"; return 1; }
    wait_re "Fld 2 +Hx 0\\.678" || return 1
    keys f Left Left Up
    wait_for "field 1 (0, 0 deg)" || return 1
    keys f
}
check "field 2 of the TMA is one pick: Hx, Hy = (6, 6.5) / sqrt(78.25); Fld steps" field_pick

# 8. The paraxial line names its wavelength and the units.
parax_line() {
    wait_re "^at 1: 0\\.5875618um, mm:  EFL 1500 " || return 1
}
check "the paraxial line shows the lens units and its (primary) wavelength" parax_line

# 9. F, d, C as a preset; wavelengths reorder with < and >.
presets() {
    keys t
    wait_for "System settings" || return 1
    keys F
    wait_for "Wavelength 2 (primary)" || return 1
    wait_for "0.4861327 um" && wait_for "0.6562725 um" || return 1
    type_text ":wave C"
    keys Enter
    # Down to wavelength 3 (C) and move it up twice.
    n=0; while [ $n -lt 13 ]; do keys Down; n=$((n + 1)); done
    keys "<" "<"
    wait_re "Wavelength 1 +0\\.6562725 um" || return 1
    wait_re "Wavelength 3 \\(primary\\) +0\\.5875618 um" || return 1
    keys Escape
    wait_re "Wave 1: 0\\.6562725um" || return 1
}
check "F in settings gives F, d, C (primary d); < moves a wavelength, primary and ray follow" presets

# 10. :wave 1.5 is understood: a wavelength in um, not "not a number".
wave_um() {
    command_line "wave 1.5"
    wait_for "1.5 um is not a wavelength of the design" || return 1
    command_line "wavelength add 1.5"
    command_line "wave 1.5"
    wait_for "tracing at wavelength 4 (1.5 um)"
}
check ":wave 1.5 names the wavelength in um; after adding it, it traces there" wave_um

# 11. A glass outside its range warns on the status line and in the results.
glass_range() {
    command_line "open! cooke.json"
    wait_for "cooke.json: " || return 1
    command_line "wavelength add 3"
    wait_re "warning: surface [0-9]+: wavelength 3 um is outside the range" || return 1
    command_line "wave 4"
    wait_for "OK range" || return 1
    command_line "wave 1"
    wait_gone "OK range"
}
check "a wavelength beyond a glass's range warns on the status line and in the results" glass_range

# 12. Cycling the aperture type never sticks.
aperture_cycle() {
    command_line "open! c.json"
    wait_for "c.json: " || return 1
    keys t
    wait_for "System settings" || return 1
    keys PageUp Down Down
    PREV=$(screen | sed -n 's/^ *Aperture type  *\([a-z]*\).*/\1/p')
    SEEN=$PREV
    for i in 1 2 3 4; do
        keys Right
        sleep 0.3
        CUR=$(screen | sed -n 's/^ *Aperture type  *\([a-z]*\).*/\1/p')
        [ "$CUR" != "$PREV" ] || { WHY="stuck at $CUR"; return 1; }
        SEEN="$SEEN $CUR"
        PREV=$CUR
    done
    echo "# aperture types in turn: $SEEN"
    keys Escape
}
check "cycling the aperture type moves on every press" aperture_cycle

# 13. Asphere terms on a STANDARD surface are dim, with a note.
asphere_dim() {
    $T resize-window -t =main: -x 250 -y 30 2>/dev/null
    command_line "set 1 a2 1e-09"
    command_line "set 1 type standard"
    wait_for "ignored (shown dim)" || return 1
    # Surface 1's 1e-09 is drawn dim (SGR 2) once the cursor is elsewhere.
    command_line "goto 2 radius"
    sleep 0.3
    $T capture-pane -e -p -t =main: | grep -F "1e-09" | grep -q "$(printf '\033')\\[[0-9;]*2[0-9;]*m *1e-09" ||
        { WHY="1e-09 is not dim"; return 1; }
    $T resize-window -t =main: -x 110 -y 30 2>/dev/null
}
check "r^n terms of a STANDARD surface are dim, and making it STANDARD says so" asphere_dim

# 14. Infinite values show as the CLI shows them.
infinity() {
    command_line "open! tma.json"
    wait_for "tma.json: " || return 1
    command_line "goto 0"
    wait_for "-Infinity" || return 1
    screen | grep -E "^ +0 " | grep -q -- "-Infinity"
}
check "infinite values show as -Infinity, as sagitta trace prints them" infinity

# 14b. Space toggles a frame change's order and after mode, as Enter on a
# choice would; the columns carry Zemax's headings and a coordinate
# break's after cells are dim.
frame_space() {
    $T resize-window -t =main: -x 250 -y 30 2>/dev/null
    command_line "open! c.json"
    wait_for "c.json: " || return 1
    command_line "goto 2 aorder"
    # The cursor's column is in view, so its heading shows, whatever the
    # horizontal scroll the resize left.
    wait_for "Aft Ord" || { WHY="no Aft Ord heading"; return 1; }
    keys Space
    wait_for "surface 2 aorder = 1" || return 1
    command_line "goto 2 after"
    keys Space
    wait_for "surface 2 after = reverse" || return 1
    keys Space
    wait_for "surface 2 after = explicit" || return 1
    $T resize-window -t =main: -x 110 -y 30 2>/dev/null
}
check "Space toggles a frame change's order and after mode; Zemax's headings show" frame_space

# 15. The title is cut at a word.
title_cut() {
    stop || return 1
    start tma.json 80 24
    wait_for "tma.json" 15 && wait_for "Surf" || return 1
    FULL=$(sed -n 's/^ *"title": "\(.*\)",$/\1/p' "$WORK/tma.json")
    SHOWN=$(screen | head -n 1 | sed 's/^ sagitta  tma.json  - //; s/\xe2\x80\xa6.*//; s/~ .*//')
    echo "# title shown: \"$SHOWN\""
    case $FULL in "$SHOWN"*) ;; *) WHY="not a prefix of the title"; return 1 ;; esac
    NEXT=$(printf '%s' "$FULL" | cut -c $(( ${#SHOWN} + 1 )))
    [ "$NEXT" = " " ] || { WHY="cut inside a word (next: '$NEXT')"; return 1; }
}
check "at 80 columns the title is cut at a word, not inside one" title_cut

# 16. A resize from narrow to wide drops a stale horizontal scroll.
resize_scroll() {
    command_line "goto 1 a16"
    wait_for "Surf  <" || return 1
    # Wider, the columns before r^16 come back into view.
    $T resize-window -t =main: -x 250 -y 30 2>/dev/null
    wait_re "Conic .* r\^16" || return 1
    $T resize-window -t =main: -x 80 -y 24 2>/dev/null
    sleep 0.3
}
check "after a resize the spreadsheet scrolls afresh (no stale <)" resize_scroll

# 17. Help: the # key's line, xfan, long lines wrapped.
help_screen() {
    $T resize-window -t =main: -x 80 -y 24 2>/dev/null
    sleep 0.3
    keys F1
    wait_for "sagitta help" || return 1
    n=0
    while [ $n -lt 3 ]; do keys PageDown; n=$((n + 1)); done
    keys Home
    wait_re "^  # +digits of agreement" || return 1
    wait_for "xfan N" || return 1
    # The export line is longer than 80 columns: its end shows on the next row.
    wait_re "^ {6,}[^ ].*grid N\\]\\)" || return 1
    keys Escape
    wait_gone "sagitta help"
}
check "help: the # key's line is there, xfan is listed, long lines wrap" help_screen

# 18. A terminal too small says which size it needs.
too_small() {
    $T resize-window -t =main: -x 30 -y 10 2>/dev/null
    wait_for "Need 50x14," || return 1
    wait_for "have 30x10." || return 1
    $T resize-window -t =main: -x 80 -y 24 2>/dev/null
    wait_for "Surf"
}
check "a too-small terminal is told the size needed, in its own width" too_small

# 19. More than 1000 surfaces: IMA 1001, not IMA1001.
many_surfaces() {
    stop || return 1
    {
        i=0
        while [ $i -lt 999 ]; do echo "insert 1"; i=$((i + 1)); done
        echo "save big.json"
    } >"$WORK/big.cmd"
    (cd "$WORK" && "$SAGITTA" edit --batch big.cmd) || { WHY="batch failed"; return 1; }
    start big.json 100 30
    wait_for "big.json" 15 && wait_for "Surf" || return 1
    command_line "goto ima"
    wait_re "^IMA 1001 " || return 1
    screen | grep -q "IMA1001" && { WHY="IMA1001"; return 1; }
    return 0
}
check "with 1002 surfaces the labels read IMA 1001, with the blank" many_surfaces

# 20. :save to a read-only file refuses with a message.
readonly_save() {
    cp "$ROOT/examples/cassegrain.json" "$WORK/ro.json"
    chmod 444 "$WORK/ro.json"
    command_line "open! ro.json"
    wait_for "ro.json: " || return 1
    command_line "set 3 radius -3900"
    command_line "w"
    wait_for "not saved: ro.json is read-only" || return 1
    cmp -s "$WORK/ro.json" "$ROOT/examples/cassegrain.json" || { WHY="ro.json changed"; return 1; }
    wait_for "ro.json [+]"
}
check "saving over a read-only file is refused with a message; the edit stays" readonly_save

# 21. A hard-linked file keeps its links when saved.
hard_link() {
    cp "$ROOT/examples/cassegrain.json" "$WORK/h1.json"
    ln -f "$WORK/h1.json" "$WORK/h2.json"
    command_line "open! h1.json"
    wait_for "h1.json: " || return 1
    command_line "set 3 radius -3900"
    command_line "w"
    wait_for "saved h1.json" || return 1
    [ "$(stat -c %i "$WORK/h1.json")" = "$(stat -c %i "$WORK/h2.json")" ] || { WHY="the link broke"; return 1; }
    cmp -s "$WORK/h1.json" "$WORK/h2.json"
}
check "saving a hard-linked file keeps the link (both names see the save)" hard_link

# 22-24. The recovery question: type-ahead is dropped, only its answers
# count, and deleting takes a second yes.
make_orphan() {
    stop
    rm -f "$RECDIR"/*.sgrec
    cp "$ROOT/examples/cassegrain.json" "$WORK/r.json"
    start r.json 110 30
    wait_for "r.json" 15 && wait_for "Surf" || return 1
    command_line "set 3 radius -3900"
    wait_for "r.json [+]" || return 1
    n=50; while [ "$(nrec)" -ne 1 ] && [ $n -gt 0 ]; do sleep 0.1; n=$((n - 1)); done
    kill -KILL "$PID"
    wait_dead "$PID"
}
typeahead() {
    make_orphan || return 1
    # Keys sent at once, before the question can show: none may answer it.
    rm -f "$WORK/pid.main"
    $T kill-session -t =main >/dev/null 2>&1
    $T new-session -d -s main -x 110 -y 30 \
        "cd '$WORK' && sh -c 'sleep 0.5; echo \$\$ >pid.main; exec \"\$0\" r.json' '$SAGITTA'; echo \"EXITED \$?\"; sleep 60"
    type_text ":wn"
    keys d D r n y
    wait_for "Recover unsaved changes to r.json" 15 || return 1
    PID=$(cat "$WORK/pid.main")
    started "$PID"
    sleep 0.5
    [ "$(nrec)" -ge 1 ] || { WHY="type-ahead deleted the recovery file"; return 1; }
    wait_for "Recover unsaved changes to r.json"
}
check "keys typed before the recovery question are dropped; the file stays" typeahead
only_answers() {
    type_text "xq:wyn"
    keys Enter
    sleep 0.5
    wait_for "Recover unsaved changes to r.json" || return 1
    [ "$(nrec)" -ge 1 ] || { WHY="the file went"; return 1; }
    keys d
    wait_for "Delete the recovery file and its unsaved changes for good?" || return 1
    keys Escape
    wait_for "Recover unsaved changes to r.json" || return 1
    [ "$(nrec)" -ge 1 ] || { WHY="n then Esc deleted the file"; return 1; }
}
check "the question ignores other keys, y and n too; d asks again and Esc goes back" only_answers
confirmed_delete() {
    keys d
    wait_for "for good?" || return 1
    keys D
    wait_for "deleted " || return 1
    n=50; while [ "$(nrec)" -ne 0 ] && [ $n -gt 0 ]; do sleep 0.1; n=$((n - 1)); done
    [ "$(nrec)" -eq 0 ] || { WHY="the file is still there"; return 1; }
    stop
}
check "d, then a capital D, deletes the recovery file" confirmed_delete

# 25. Quitting with unsaved changes, y saves: a design without a name asks
# for one, and a name that exists asks before it is replaced; then it quits.
quit_saves() {
    printf 'old\n' >"$WORK/taken.json"
    start "" 100 30
    wait_for "new design" 15 || return 1
    command_line "set 1 radius 55.5"
    wait_for "[new design] [+]" || return 1
    keys Escape q
    wait_for "Save before quitting?" || return 1
    keys y
    wait_re "^:wq *$" || return 1
    type_text "taken.json"
    keys Enter
    wait_for "taken.json already exists. Overwrite it?" || return 1
    keys y
    wait_for "EXITED 0" 5 || return 1
    grep -q sagitta-design "$WORK/taken.json" || { WHY="taken.json was not saved"; return 1; }
}
check "quit, y: asks a name, asks before replacing it, saves, quits" quit_saves

echo "# $(( $(date +%s) - T0 )) s"
[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
