#!/bin/sh
# e2e_merit.sh - the Merit Function Editor on the screen at 80x24: Ctrl-E
# opens it on the design's rows, Enter edits the cell under the cursor on
# the ':' line, the value follows, u undoes, Esc closes, and the file saved
# holds the edited row.  Output is TAP.
# Usage: e2e_merit.sh PATH/TO/sagitta
#
# Independent reference: the lens's focal length from its closed form
# (a thick lens of index 1.5, R1 60, R2 -80, t 5: f = 69.3975903614...),
# against the EFFL value the editor shows; the saved file read by Python's
# json module.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 5 merit

cat >"$WORK/lens.json" <<'EOF'
{"format": "sagitta-design", "version": 6, "units": "mm",
 "wavelengths": {"primary": 1, "list": [{"um": 0.5875618}]},
 "fields": {"type": "angle", "list": [{"y": 0}, {"y": 2}]},
 "aperture": {"type": "epd", "value": 10},
 "surfaces": [{"radius": "inf", "thickness": "inf"},
  {"radius": 60, "thickness": 5, "material": 1.5, "stop": true},
  {"radius": -80, "thickness": 65},
  {"radius": "inf", "thickness": 0}],
 "merit": {"operands": [{"type": "EFFL", "wave": 1, "target": 70, "weight": 1},
                        {"type": "TTHI", "surf1": 1, "surf2": 2, "target": 70, "weight": 0}]}}
EOF
EFL=$(python3 -c 'n, r1, r2, t = 1.5, 60.0, -80.0, 5.0
print("%.17g" % (1 / ((n - 1) * (1 / r1 - 1 / r2 + (n - 1) * t / (n * r1 * r2)))))')

start lens.json 80 24
if wait_for "lens.json" 15 && wait_for "Surf"; then
    # 1. Ctrl-E: the rows, EFFL's value the closed form to the digits shown.
    keys C-e
    wait_for "Merit Function Editor" >/dev/null
    sleep 0.3
    SHOWN=$(screen | grep "^1 *EFFL" | awk '{ print $7 }' | sed 's/…//')
    echo "# EFFL on screen $SHOWN, closed form $EFL"
    WHY="screen '$SHOWN', closed form $EFL"
    check "Ctrl-E shows the merit rows, EFFL the thick lens's focal length" \
        python3 -c "import sys; s = '$SHOWN'; sys.exit(0 if s and abs(float(s) - $EFL) <= 10 ** -(len(s.split('.')[1]) if '.' in s else 0) else 1)"
    # 2. Right to Target, Enter: the ':' line holds merit set 1 target 70.
    keys Right Right Right Right Right Right Right Enter
    wait_for ":merit set 1 target 70" >/dev/null
    # The ':' line opens over the Merit Function Editor, not the sheet.
    check "Enter on a cell puts its value on the ':' line, over the editor" \
        sh -c "$T capture-pane -p -t =main: | grep -q ':merit set 1 target 70' &&
               $T capture-pane -p -t =main: | grep -q 'Merit Function Editor' &&
               ! $T capture-pane -p -t =main: | grep -q '^ *Surf'"
    # 3. A new target: the row and the merit follow.
    keys BSpace BSpace
    type_text "65"
    keys Enter
    wait_for "merit row 1: target 65" >/dev/null
    sleep 0.3
    WHY="$(screen | grep '^1 *EFFL')"
    # The command's message shows under the editor's rows.
    check "the edited target shows in its row, and the command's message under it" \
        sh -c "screen() { $T capture-pane -p -t =main:; }; screen | grep -q '^1 *EFFL .* 65 ' &&
               screen | grep -q 'merit row 1: target 65'"
    # 4. u undoes the edit, Esc closes, :w saves; the file has target 70.
    keys u
    wait_for "undo" >/dev/null
    keys Escape
    wait_for "Surf" >/dev/null
    command_line "w"
    wait_for "saved" >/dev/null
    T70=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["merit"]["operands"][0]["target"])' "$WORK/lens.json")
    WHY="saved target '$T70'"
    check "u undoes it, and the saved file keeps the target 70" sh -c "[ '$T70' = '70' ] || [ '$T70' = '70.0' ]"
    # 5. :merit opens it too, and i inserts a row.
    command_line "merit"
    wait_for "Merit Function Editor" >/dev/null
    keys i
    wait_for "BLNK inserted" >/dev/null
    check ":merit opens the editor and i inserts a row" \
        sh -c "$T capture-pane -p -t =main: | grep -q '^1 *BLNK'"
else
    not_ok "the lens opens at 80x24"
    not_ok "Enter edits"
    not_ok "target"
    not_ok "undo and save"
    not_ok ":merit and i"
fi

[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
