#!/bin/sh
# e2e_surprise.sh - keys that never surprise and text never cut silently
# (issue 30, items 13, 14, 16, 17, 19): the real editor runs in tmux, is
# typed at, and its screen and files are read back.  Output is TAP.
# Usage: e2e_surprise.sh PATH/TO/sagitta
#
# Independent references: the design files this script copies and what
# grep finds in the files the editor saves; the .zmx importer's own
# warnings from "sagitta import" (another program path) for what the
# editor must show; widths counted by awk.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 9 surprise

# Starts the editor on $1 in a $2 x $3 window as session main; a session
# "keep" holds the server up between editors.
start() {
    rm -f "$WORK/pid"
    $T has-session -t =keep 2>/dev/null ||
        $T new-session -d -s keep -x 40 -y 5 "sleep 600"
    $T kill-session -t =main >/dev/null 2>&1
    $T new-session -d -s main -x "${2:-110}" -y "${3:-30}" \
        "cd '$WORK' && sh -c 'echo \$\$ >pid; exec \"\$0\" \$1' '$SAGITTA' '$1'; st=\$?; printf '\\r\\n'; echo \"EXITED \$st\"; sleep 60"
    n=50
    while [ ! -s "$WORK/pid" ] && [ "$n" -gt 0 ]; do sleep 0.1; n=$((n - 1)); done
    started "$(cat "$WORK/pid" 2>/dev/null)"
}

# How many surfaces a saved design holds: one "stop" key each.
nsurf() { grep -c '"stop"' "$WORK/$1"; }

T0=$(date +%s)

# 1. Item 13: ':' typed first on a Comment cell opens the command line, so
# ":w" Enter right after committing a comment saves and leaves the comment.
colon_comment() {
    cp "$ROOT/examples/singlet.json" "$WORK/s.json"
    start s.json 100 30
    wait_for "s.json" 15 && wait_for "Surf" || return 1
    command_line "goto 1 comment"
    type_text "hello"
    keys Enter
    wait_for "s.json [+]" || return 1
    type_text ":w"
    keys Enter
    wait_for "saved s.json" || { WHY="':w' on the comment cell did not save"; return 1; }
    grep -q '"comment": "hello"' "$WORK/s.json" || { WHY="the comment is not hello"; return 1; }
    ! grep -q '":w"' "$WORK/s.json" || { WHY="the comment became :w"; return 1; }
    # On a Material cell ':' opens the line too: no glass "w" is looked up.
    command_line "goto 1 material"
    type_text ":set 1 thickness 4"
    keys Enter
    wait_for "s.json [+]" || return 1
    grep -q '"material": "N-BK7"' "$WORK/s.json" || return 1
    command_line "w"
    wait_for "saved s.json" || return 1
    grep -q '"thickness": 4,' "$WORK/s.json" && grep -q '"material": "N-BK7"' "$WORK/s.json"
}
check "':' first on a Comment or Material cell opens the command line" colon_comment

# 2. Item 13: a text that begins with ':' goes into the cell after F2.
colon_text() {
    command_line "goto 1 comment"
    keys F2 C-u
    type_text ":wq"
    keys Enter
    wait_for "s.json [+]" || return 1
    command_line "w"
    wait_for "saved s.json" || return 1
    grep -q '"comment": ":wq"' "$WORK/s.json" || { WHY="the comment is not :wq"; return 1; }
    screen | grep -q "EXITED" && { WHY="the editor quit"; return 1; }
    return 0
}
check "after F2 a comment may begin with ':'" colon_text

# 3. Item 14: inf, infinity and -inf typed into number cells are values:
# i inserts no surface and n asks nothing.
inf_typed() {
    before=$(nsurf s.json)
    command_line "set 0 thickness 1000"
    command_line "goto 1 radius"
    type_text "inf"
    keys Enter
    wait_for "surface 1 radius = " || return 1
    command_line "goto 0 thickness"
    type_text "infinity"
    keys Enter
    wait_for "surface 0 thickness = " || return 1
    screen | grep -q "Unsaved changes will be lost" && { WHY="n asked to discard"; return 1; }
    command_line "goto 2 conic"
    type_text "nan"
    keys Enter
    wait_for "not a finite number" || return 1
    keys Escape
    command_line "w"
    wait_for "saved s.json" || return 1
    after=$(nsurf s.json)
    got=$(printf 'print cell 1 radius\nprint cell 0 thickness\n' |
        "$SAGITTA" edit "$WORK/s.json" --batch - 2>&1 | tr '\n' ' ')
    echo "# surfaces before $before, after $after; radius 1, thickness 0: $got"
    [ "$before" -eq "$after" ] || { WHY="a surface was inserted"; return 1; }
    [ "$got" = "Infinity Infinity " ] || { WHY="inf or infinity was not set"; return 1; }
}
check "inf, infinity and nan typed in number cells type, running no command" inf_typed

# 4. Item 14: on the Type cell the first letter of a type types: e makes an
# even asphere (not the examples list), s STANDARD (not the stop).
type_letters() {
    command_line "goto 2 type"
    type_text "evenasph"
    keys Enter
    wait_for "surface 2 type" || return 1
    command_line "w"
    wait_for "saved s.json" || return 1
    grep -q '"type": "even_asphere"' "$WORK/s.json" || { WHY="no even asphere"; return 1; }
    command_line "goto 2 type"
    type_text "s"
    keys Enter
    command_line "w"
    wait_for "saved s.json" || return 1
    ! grep -q '"type": "even_asphere"' "$WORK/s.json" || { WHY="s did not type STANDARD"; return 1; }
    # The stop stayed on surface 1.
    awk '/"stop": true/ { n++ } END { exit n == 1 ? 0 : 1 }' "$WORK/s.json" || return 1
    command_line "quit!"
    wait_for "EXITED 0" 5
}
check "on the Type cell e and s type a type name, running no command" type_letters

# 5. Item 16: a .zmx's import warnings show at open; at 80 columns the
# status line is cut with an ellipsis and points to :messages, which shows
# each warning whole.  The reference: "sagitta import"'s own warnings.
zmx_warnings() {
    cp "$ROOT/tests/data/zmx/US05331467-1.zmx" "$WORK/u.zmx"
    # Only the reading's warnings, which name the file's lines; writing the
    # JSON adds one of its own (the Zemax lines JSON does not keep).
    (cd "$WORK" && "$SAGITTA" import u.zmx -o u.json 2>&1 >/dev/null) |
        sed -n 's/^sagitta: warning: \(u\.zmx:\)/\1/p' >"$WORK/warn.txt"
    nw=$(wc -l <"$WORK/warn.txt")
    echo "# sagitta import gives $nw warnings"
    [ "$nw" -ge 2 ] || { WHY="the reference has no warnings"; return 1; }
    start u.zmx 80 24
    wait_for "$nw warnings reading the file" 15 || return 1
    last=$(screen | grep -v '^ *$' | tail -n 1)
    echo "# status line: $last"
    case $last in *"… :messages") ;; *) WHY="the cut has no ellipsis and :messages"; return 1 ;; esac
    command_line "messages"
    wait_for "Messages, the newest last" || return 1
    joined=$(screen | tr '\n' ' ' | tr -s ' ')
    while IFS= read -r w; do
        w=$(printf '%s' "$w" | tr -s ' ')
        case $joined in *"warning: $w"*) ;; *) WHY="not shown whole: $w"; return 1 ;; esac
    done <"$WORK/warn.txt"
    keys Escape
    wait_gone "Messages, the newest last" || return 1
    command_line "quit!"
    wait_for "EXITED 0" 5
}
check ".zmx import warnings show at open; :messages shows each whole (80x24)" zmx_warnings

# 6. Item 16: batch mode prints the warnings to stderr and :messages lists
# them on stdout.
batch_messages() {
    out=$(cd "$WORK" && printf 'messages\n' | "$SAGITTA" edit u.zmx --batch - 2>"$WORK/err.txt")
    while IFS= read -r w; do
        printf '%s\n' "$out" | grep -qxF "warning: $w" || { WHY="stdout lacks: $w"; return 1; }
        grep -qxF "sagitta edit: warning: $w" "$WORK/err.txt" || { WHY="stderr lacks: $w"; return 1; }
    done <"$WORK/warn.txt"
}
check "batch: a .zmx's warnings on stderr, :messages lists them" batch_messages

# 7. Item 17, at 80x24: a solve's letter stays when its number is cut; the
# ray's status shows; the paraxial line ends in an ellipsis and F3 where it
# is cut, never mid-number; the detail panel keeps the direction's bound.
narrow() {
    cp "$ROOT/examples/cooke_triplet.json" "$WORK/ck.json"
    start ck.json 80 24
    wait_for "ck.json" 15 && wait_for "Surf" || return 1
    command_line "solve 6 thickness marginal_height 0"
    wait_for "ck.json [+]" || return 1
    command_line "goto 6 thickness"
    sleep 0.3
    row=$(screen | grep -E '^ +6 STANDARD')
    echo "# row 6: $row"
    printf '%s\n' "$row" | grep -qE ' 41\.[0-9]*… M ' || { WHY="no '… M' in row 6"; return 1; }
    ray=$(screen | grep '^Ray ')
    echo "# ray line: $ray"
    printf '%s\n' "$ray" | grep -qE ' OK *$' || { WHY="the ray's status is not shown"; return 1; }
    par=$(screen | grep -E '^(at )?2: 0\.5875618um')
    echo "# paraxial line: $par"
    case $par in
    *"track "[0-9]*) ;; # whole
    *"… F3") ;;
    *) WHY="the paraxial line is cut without an ellipsis"; return 1 ;;
    esac
    # No number on it is cut: each field's value is followed by a blank or
    # the end, as "sagitta paraxial" writes them whole.
    printf '%s\n' "$par" | grep -qE '(EFL|BFL|EPD|track) [0-9.]+…' && { WHY="a number was cut"; return 1; }
    screen | grep -q 'dir bound=' || { WHY="the direction's bound is not shown"; return 1; }
    return 0
}
check "80x24: solve letter, ray status, paraxial line and dir bound are never cut silently" narrow

# 8. Item 17: the ray selector uses the width a terminal has: at 200
# columns Hx shows every digit typed, at 80 it ends in an ellipsis.
ray_width() {
    command_line "hx 0.123456789"
    wait_re '^Ray .*Hx 0\.123[0-9]*… ' || return 1
    command_line "quit!"
    wait_for "EXITED 0" 5 || return 1
    start ck.json 200 30
    wait_for "ck.json" 15 && wait_for "Surf" || return 1
    command_line "hx 0.123456789"
    wait_re '^Ray .*Hx 0\.123456789 ' || return 1
    command_line "quit!"
    wait_for "EXITED 0" 5
}
check "the ray selector shows all the digits at 200 columns, an ellipsis at 80" ray_width

# 9. Item 17: a question wider than the status line keeps its start and
# its end, where the answers are, with an ellipsis between (an export onto
# an existing file with a long name asks to replace it).
long_question() {
    long=replace_me_$(printf '%080d' 0).csv
    : >"$WORK/$long"
    start s.json 80 24
    wait_for "s.json" 15 && wait_for "Surf" || return 1
    command_line "export $long"
    wait_re 'Replace it\? \(y\)es \(n\)o *$' || return 1
    last=$(screen | grep -v '^ *$' | tail -n 1)
    echo "# question line: $last"
    case $last in "export: "*"…"*"(y)es (n)o") ;; *) WHY="not its start, an ellipsis and its answers: $last"; return 1 ;; esac
    keys n
    wait_gone "Replace it?" || return 1
    [ ! -s "$WORK/$long" ] || { WHY="the file was replaced"; return 1; }
    command_line "quit!"
    wait_for "EXITED 0" 5
}
check "a question wider than the line keeps its start and answers, an ellipsis between (80x24)" long_question

echo "# $(( $(date +%s) - T0 )) s"
[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
