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
# json module.  :opt on a slow triplet (a dense default merit): the
# status line shows each cycle's merit, Esc stops it with the best design
# so far kept (the file saved then differs from the start), and one u
# brings back the start (saved again: the radius of the file above).
# A zoom's title bar names its configuration and Ctrl-A shows the next.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 10 merit

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

cat >"$WORK/slow.json" <<'EOF'
{"format": "sagitta-design", "version": 6, "units": "mm",
 "wavelengths": {"primary": 1, "list": [{"um": 0.5875618}]},
 "fields": {"type": "angle", "list": [{"y": 0}, {"y": 5}, {"y": 10}, {"y": 14}, {"y": 17}, {"y": 20}]},
 "aperture": {"type": "epd", "value": 12.5},
 "surfaces": [{"radius": "inf", "thickness": "inf"},
  {"radius": 25, "thickness": 4.831, "material": 1.691, "solves": {"radius": {"type": "variable"}}},
  {"radius": 7331.288, "thickness": 6.5, "solves": {"radius": {"type": "variable"}}},
  {"radius": -23, "thickness": 0.975, "material": 1.6727, "stop": true, "solves": {"radius": {"type": "variable"}}},
  {"radius": 23, "thickness": 4.4, "solves": {"radius": {"type": "variable"}}},
  {"radius": 80, "thickness": 3.127, "material": 1.691, "solves": {"radius": {"type": "variable"}}},
  {"radius": -21, "thickness": 41, "solves": {"radius": {"type": "variable"},
   "thickness": {"type": "marginal_height", "value": 0}}},
  {"radius": "inf", "thickness": 0}],
 "merit": {"default": {"criterion": "spot", "reference": "centroid", "rings": 20, "arms": 16},
           "operands": [{"type": "EFFL", "wave": 1, "target": 50, "weight": 1}]}}
EOF
R1() { python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["surfaces"][1]["radius"])' "$WORK/slow.json"; }

start slow.json 100 30
if wait_for "slow.json" 15 && wait_for "Surf"; then
    # 6. :opt: the status line shows the cycles and their merit.
    command_line "opt"
    check ":opt shows each cycle's merit on the status line" \
        wait_re "optimizing: cycle [0-9]+, merit [0-9.e+-]+" 60
    # 7. Esc stops it; the best design so far is the design (saved: the
    # front radius moved).
    keys Escape
    STOPPED=no
    wait_for "optimization stopped after" 60 >/dev/null && STOPPED=yes
    command_line "w"
    wait_for "saved" >/dev/null
    RS=$(R1)
    WHY="stopped: $STOPPED; front radius saved after the stop: '$RS'"
    check "Esc stops :opt and keeps the best design so far" \
        sh -c "[ $STOPPED = yes ] && [ -n '$RS' ] && [ '$RS' != '25' ] && [ '$RS' != '25.0' ]"
    # 8. One u is the start again.
    keys u
    wait_for "undo" >/dev/null
    command_line "w"
    sleep 0.5
    wait_for "saved" >/dev/null
    RU=$(R1)
    WHY="front radius saved after one undo: '$RU'"
    check "one u undoes the stopped optimization" sh -c "[ '$RU' = '25' ] || [ '$RU' = '25.0' ]"
else
    not_ok "the slow triplet opens"
    not_ok "Esc stops :opt"
    not_ok "one u undoes it"
fi

cat >"$WORK/zoom.json" <<'EOF'
{"format": "sagitta-design", "version": 6, "units": "mm",
 "wavelengths": {"primary": 1, "list": [{"um": 0.5875618}]},
 "fields": {"type": "angle", "list": [{"y": 0}]},
 "aperture": {"type": "epd", "value": 8},
 "surfaces": [{"radius": "inf", "thickness": "inf"},
  {"radius": 60, "thickness": 4, "material": 1.5, "stop": true},
  {"radius": -120, "thickness": 10},
  {"radius": 80, "thickness": 3, "material": 1.6},
  {"radius": -300, "thickness": 40},
  {"radius": "inf", "thickness": 0}],
 "configurations": {"count": 2, "operands": [{"type": "THIC", "surface": 2, "values": [10, 30]}]}}
EOF

start zoom.json 100 30
if wait_for "zoom.json" 15 && wait_for "Surf"; then
    # 9. The title names the configuration; Ctrl-A shows the next, and
    # the file saved then holds its values and its number.
    WHY=
    check "the title bar shows config 1/2" wait_re "zoom.json.*config 1/2" 10
    keys C-a
    wait_for "configuration 2 of 2" >/dev/null
    command_line "w"
    wait_for "saved" >/dev/null
    CS=$(python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); print(d["configurations"].get("current"), d["surfaces"][2]["thickness"])' "$WORK/zoom.json")
    WHY="saved current and thickness: '$CS'"
    check "Ctrl-A shows configuration 2 (title config 2/2, saved as current 2, thickness 30)" \
        sh -c "$T capture-pane -p -t =main: | grep -q 'config 2/2' && { [ '$CS' = '2 30' ] || [ '$CS' = '2 30.0' ]; }"
else
    not_ok "the title shows the configuration"
    not_ok "Ctrl-A"
fi

[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
