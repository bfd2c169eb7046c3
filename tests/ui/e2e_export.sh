#!/bin/sh
# e2e_export.sh - the editor's large exports on the screen, through tmux:
# grid 1001 (about 2.6 GB) states its size and asks; n writes nothing; y
# starts it with progress on the status line, and Esc cancels it leaving
# no file.  A grid 2 export writes the four rays.  Output is TAP.
# Usage: e2e_export.sh PATH/TO/sagitta

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 4 e2e-export

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

[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
