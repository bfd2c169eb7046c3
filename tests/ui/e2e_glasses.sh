#!/bin/sh
# e2e_glasses.sh - the glass picker at 80x24: ":glasses ND VD" opens the
# list nearest first, each glass with its index at the primary wavelength;
# the arrows and Enter make one the material of the cursor's surface; Esc
# leaves without a change; ":glasses NAME" lists by name.  Output is TAP.
# Usage: e2e_glasses.sh PATH/TO/sagitta
#
# Independent reference: the catalog's own figures (lensdb/SCHOTT.agf: N-F2
# has nd 1.62005, F2 nd 1.62004, vd 36.37; between them lensdb/CDGM.agf's
# F4GTI, nd 1.62005, vd 36.4308, and lensdb/HIKARI.agf's J-F2, nd 1.62004,
# vd 36.3968), and the material written to the saved design file.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 5 glasses

cp "$ROOT/examples/singlet.json" "$WORK/singlet.json"

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

command_line() {
    keys Escape
    type_text ":$1"
    keys Enter
}

$T new-session -d -s main -x 80 -y 24 \
    "cd '$WORK' && sh -c 'echo \$\$ >pid; exec \"\$0\" \"\$1\"' '$SAGITTA' singlet.json; echo \"EXITED \$?\"; sleep 60"
sleep 0.3
started "$(cat "$WORK/pid" 2>/dev/null)"
wait_for "LA1509" 10 >/dev/null

# The singlet's primary wavelength is d (0.5875618 um), so each n shown is
# the catalog nd to its 5 decimals.
first_is_nf2() {
    wait_for 'Glasses for "1.62005 36.43"' 5 &&
        screen | grep -Eq '^ +1  N-F2 +SCHOTT +nd 1\.62005  vd  36\.43  n 1\.62005'
}
# Characters, not bytes: the title bar's ellipsis is three bytes.
narrow() {
    [ "$(screen | python3 -c 'import sys; print(sum(len(l.rstrip("\n")) > 80 for l in sys.stdin))')" -eq 0 ]
}
row2_is_f2() { wait_for "Surf" 5 && screen | grep -Eq '^ +2 STANDARD .* F2 '; }
saved_f2() { grep -q '"material": "F2"' "$WORK/singlet.json"; }
# lensdb/SCHOTT.agf names N-SF1, N-SF10, N-SF11, N-SF14, N-SF15 and N-SF19.
by_name() { wait_for 'Glasses for "n-sf1"' 5 && screen | grep -Eq '^ +1  N-SF1 ' &&
    screen | grep -Eq '^ +2  N-SF10 ' && screen | grep -Eq '^ +3  N-SF11 '; }

command_line "goto 2"
command_line "glasses 1.62005 36.43"
check "glasses 1.62005 36.43 opens the list, N-F2 first with n = nd" first_is_nf2
check "no line is wider than 80 columns" narrow

# Down past F4GTI and J-F2 to F2 (nd 1.62004, vd 36.37), Enter: surface 2's
# material.
keys Down
sleep 0.2
keys Down
sleep 0.2
keys Down
sleep 0.2
keys Enter
sleep 0.5
check "Enter makes F2 the material of surface 2" row2_is_f2

# Esc leaves a list without a change; the design saved has F2.
command_line "glasses n-bk"
sleep 0.3
keys Escape
sleep 0.3
command_line "w"
sleep 0.5
check "Esc changes nothing; the saved design has F2 after surface 2" saved_f2

command_line "glasses n-sf1"
check "glasses n-sf1 lists N-SF1, N-SF10, N-SF11 by name" by_name
keys Escape
command_line "q!"
[ "$FAILED" -eq 0 ]
