#!/bin/sh
# e2e_tol.sh - the Tolerance Data Editor on the screen: Ctrl-T opens it on
# the design's rows, :tol runs the sensitivity analysis and shows each
# row's criterion at its min and max; on Zemax's own SC_Tol_Cooke.zmx (41
# rows, tests/data/zmx/README.md) the status line counts the systems and
# Esc stops the run, keeping the rows done, with the design unchanged.
# Output is TAP.
# Usage: e2e_tol.sh PATH/TO/sagitta
#
# Independent reference: the criterion is the merit function, one EFFL
# row with target 0, so at TRAD's max (R1 60.5) it is the thick lens's
# focal length from its closed form (n 1.5, R2 -80, t 5).

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 6 tol

cat >"$WORK/lens.json" <<'EOF'
{"format": "sagitta-design", "units": "mm",
 "wavelengths": {"primary": 1, "list": [{"um": 0.5875618}]},
 "fields": {"type": "angle", "list": [{"y": 0}]},
 "aperture": {"type": "epd", "value": 10},
 "surfaces": [{"radius": "inf", "thickness": "inf"},
  {"radius": 60, "thickness": 5, "material": 1.5, "stop": true},
  {"radius": -80, "thickness": 45},
  {"radius": "inf", "thickness": 0}],
 "merit": {"operands": [{"type": "EFFL", "wave": 1, "target": 0, "weight": 1}]},
 "tolerances": {"operands": [{"type": "TRAD", "surface": 1, "min": -0.5, "max": 0.5}],
                "criterion": {"type": "merit"}}}
EOF
EFL=$(python3 -c 'n, r1, r2, t = 1.5, 60.5, -80.0, 5.0
print("%.17g" % (1 / ((n - 1) * (1 / r1 - 1 / r2 + (n - 1) * t / (n * r1 * r2)))))')

start lens.json 100 24
if wait_for "lens.json" 15 && wait_for "Surf"; then
    # 1. Ctrl-T: the row, no run yet.
    keys C-t
    wait_for "Tolerance Data Editor" >/dev/null
    sleep 0.3
    WHY="$(screen | grep '^1 *TRAD')"
    check "Ctrl-T shows the tolerance rows" \
        sh -c "$T capture-pane -p -t =main: | grep -q '^1 *TRAD *1 .*-0.5 *0.5'"
    # 2. :tol runs it: Crit(max) is the closed form to the digits shown.
    command_line "tol"
    wait_for "sensitivity: 1 rows" 60 >/dev/null
    sleep 0.3
    SHOWN=$(screen | grep "^1 *TRAD" | awk '{ print $NF }' | sed 's/…//')
    echo "# Crit(max) on screen $SHOWN, closed form $EFL"
    WHY="screen '$SHOWN', closed form $EFL"
    check ":tol shows the criterion at the max, the closed form" \
        python3 -c "import sys; s = '$SHOWN'; sys.exit(0 if s and abs(float(s) - $EFL) <= 10 ** -(len(s.split('.')[1]) if '.' in s else 0) else 1)"
    # 3. An edit of the row: the run belongs to another state, and says so.
    keys Right Right Right Right Right Enter
    wait_for ":tol set 1 max 0.5" >/dev/null
    keys BSpace
    type_text "6"
    keys Enter
    wait_for "tolerance row 1: max 0.56" >/dev/null
    check "an edit marks the run as another state's" \
        wait_for "another state of the design" 10
else
    not_ok "the lens opens"
    not_ok ":tol"
    not_ok "edit"
fi

cp "$(dirname "$0")/../data/zmx/sc_tol_cooke.zmx" "$WORK/cooke.zmx"
SUM0=$(cksum <"$WORK/cooke.zmx")
start cooke.zmx 120 30
if wait_for "cooke.zmx" 20 && wait_for "Surf"; then
    # 4. Zemax's 41 rows, read from the file's TOL lines.
    keys C-t
    wait_for "Tolerance Data Editor" >/dev/null
    check "the .zmx file's 41 tolerance rows show" wait_for "41 tolerance rows" 10
    # 5. :tol counts the systems on the status line; Esc stops it.
    command_line "tol"
    check ":tol shows the systems done on the status line" \
        wait_re "tolerancing: [0-9]+ of 82 systems" 60
    keys Escape
    STOPPED=no
    wait_re "tolerancing stopped: [0-9]+ of 41 rows done, kept" 60 >/dev/null && STOPPED=yes
    sleep 0.3
    # 6. The rows done show, the title says stopped, the file is as it was.
    SUM1=$(cksum <"$WORK/cooke.zmx")
    WHY="stopped: $STOPPED; $(screen | head -1)"
    check "Esc stops :tol, keeping the rows done, the file untouched" \
        sh -c "[ $STOPPED = yes ] && $T capture-pane -p -t =main: | grep -q 'stopped: the rows done' &&
               [ '$SUM0' = '$SUM1' ]"
else
    not_ok "the Cooke triplet opens"
    not_ok ":tol progress"
    not_ok "Esc stops :tol"
fi

[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
