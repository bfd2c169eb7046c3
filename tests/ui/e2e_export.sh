#!/bin/sh
# e2e_export.sh - the editor's large exports on the screen, through tmux:
# grid 1001 (about 2.6 GB) states its size and asks; n writes nothing; y
# starts it with progress on the status line, and Esc cancels it leaving
# no file.  A grid 2 export writes the four rays.  Then "trace --rays" on a
# terminal: a long run shows its progress on standard error and erases it
# at the end, and shows none when CI is set.  Output is TAP.
# Usage: e2e_export.sh PATH/TO/sagitta

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 6 e2e-export

cp "$ROOT/examples/cassegrain.json" "$WORK/cassegrain.json"

wait_for() { # fixed text, seconds (10)
    n=$(( ${2:-10} * 10 ))
    while [ "$n" -gt 0 ]; do
        if screen | grep -qF -- "$1"; then
            return 0
        fi
        if ! $T has-session -t =main 2>/dev/null || screen | grep -q '^EXITED'; then
            echo "# the editor is gone"
            return 1
        fi
        sleep 0.1
        n=$((n - 1))
    done
    echo "# timed out waiting for: $1"
    return 1
}

command_line() {
    keys Escape
    type_text ":$1"
    keys Enter
}

$T new-session -d -s main -x 100 -y 30 \
    "cd '$WORK' && sh -c 'echo \$\$ >pid; exec \"\$0\" \"\$1\"' '$SAGITTA' cassegrain.json; echo \"EXITED \$?\"; sleep 60"
wait_for "cassegrain.json" 15
started "$(cat "$WORK/pid" 2>/dev/null)"

# 1. The size first, then n: nothing written.
command_line "export big.csv grid 1001"
if wait_for "Write it? (y)es (n)o" && screen | grep -q "about [0-9.]* GB"; then
    keys n
    if wait_for "cancelled" && [ ! -e "$WORK/big.csv" ]; then
        ok "a 2.6 GB export states its size and asks; n writes nothing"
    else
        WHY="no 'cancelled', or big.csv exists"
        not_ok "a 2.6 GB export states its size and asks; n writes nothing"
    fi
else
    not_ok "a 2.6 GB export states its size and asks; n writes nothing"
fi

# 2. y starts it, with progress on the status line.
command_line "export big.csv grid 1001"
wait_for "Write it? (y)es (n)o" >/dev/null
keys y
if wait_for "Esc cancels" 30 && screen | grep -q "exporting big.csv: [0-9]*% ("; then
    ok "the export shows its progress"
else
    not_ok "the export shows its progress"
fi

# 3. Esc cancels it; neither the file nor a temporary is left.
keys Escape
if wait_for "export cancelled after" 20 && [ ! -e "$WORK/big.csv" ] &&
    ! ls -a "$WORK" | grep -q '^\.sagitta-'; then
    ok "Esc cancels the export and leaves no file"
else
    WHY=$(ls -a "$WORK" | tr '\n' ' ')
    not_ok "Esc cancels the export and leaves no file"
fi

# 4. grid 2 is the four rays at (+-0.5, +-0.5), each row naming its ray.
command_line "export g2.csv grid 2"
if wait_for "exported 4 rays" && head -n 1 "$WORK/g2.csv" | grep -q '^ray,hx,hy,px,py,surface,' &&
    [ "$(cut -d, -f4,5 "$WORK/g2.csv" | sort -u | grep -c '0\.5')" -eq 4 ]; then
    ok "grid 2 exports four rays with hx, hy, px, py"
else
    not_ok "grid 2 exports four rays with hx, hy, px, py"
fi

# 5. trace --rays with standard error on the terminal: progress, erased.
# Enough rays that the run outlasts the progress line's first delay: with
# the faster formatting, 60,000 finished before it showed.
awk 'BEGIN { srand(5); print "hx,hy,px,py";
             for (i = 0; i < 300000; i++) printf "0,%.3f,%.6f,%.6f\n", (i % 3) / 2, 2 * rand() - 1, 2 * rand() - 1 }' \
    >"$WORK/rays.csv"
$T new-session -d -s run -x 100 -y 10 \
    "cd '$WORK' && env -u CI '$SAGITTA' trace cassegrain.json --rays rays.csv --format csv -o out.csv --threads 1; echo \"DONE \$?\"; sleep 60"
seen=0
n=600
while [ "$n" -gt 0 ]; do
    S=$($T capture-pane -p -t =run: 2>/dev/null)
    if echo "$S" | grep -q "sagitta: trace: *[0-9.]*%, [0-9]* rays"; then seen=1; fi
    if echo "$S" | grep -q "^DONE"; then break; fi
    sleep 0.1
    n=$((n - 1))
done
S=$($T capture-pane -p -t =run: 2>/dev/null)
if [ $seen -eq 1 ] && echo "$S" | grep -q "^DONE 0" && ! echo "$S" | grep -q "sagitta: trace:"; then
    ok "trace --rays shows its progress on a terminal and erases it"
else
    WHY="progress seen: $seen; screen: $(echo "$S" | tr '\n' '|')"
    not_ok "trace --rays shows its progress on a terminal and erases it"
fi
$T kill-session -t =run >/dev/null 2>&1

# 6. With CI set, none, though standard error is the terminal.
$T new-session -d -s run -x 100 -y 10 \
    "cd '$WORK' && CI=1 '$SAGITTA' trace cassegrain.json --rays rays.csv --format csv -o out.csv --threads 1; echo \"DONE \$?\"; sleep 60"
seen=0
n=600
while [ "$n" -gt 0 ]; do
    S=$($T capture-pane -p -t =run: 2>/dev/null)
    if echo "$S" | grep -q "sagitta: trace:"; then seen=1; fi
    if echo "$S" | grep -q "^DONE"; then break; fi
    sleep 0.1
    n=$((n - 1))
done
if [ $seen -eq 0 ] && echo "$S" | grep -q "^DONE 0"; then
    ok "with CI set, trace --rays shows no progress"
else
    WHY="progress seen: $seen"
    not_ok "with CI set, trace --rays shows no progress"
fi
$T kill-session -t =run >/dev/null 2>&1

[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
