#!/bin/sh
# e2e_rows.sh - every row of the lens data editor, not only the cursor's:
# each visible surface's comment, radius, thickness, material, semi-diameter
# and conic read off the screen equal the design file's values for that
# surface, at 140x60 (every surface in view) and at 80x24 after scrolling
# to the image and back.  Output is TAP.
# Usage: e2e_rows.sh PATH/TO/sagitta
#
# Independent reference: the design file itself, read by Python's json
# module; a number on screen may be cut (an ellipsis) or shortened to its
# column, so it must equal the file's value to the digits it shows.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 4 rows

cp "$ROOT/examples/double_gauss.json" "$WORK/dg.json"

# Checks the sheet's rows on the screen against the design; prints how many
# rows it checked, or the first disagreement, and fails on any.
check_rows() {
    screen >"$WORK/screen.txt"
    python3 - "$WORK/dg.json" "$WORK/screen.txt" "$1" <<'EOF'
import json, math, re, sys
design = json.load(open(sys.argv[1]))["surfaces"]
lines = open(sys.argv[2], encoding="utf-8").read().split("\n")
need = int(sys.argv[3])
head = next(i for i, l in enumerate(lines) if l.startswith("Surf ") and "Radius" in l)
h = lines[head]
# Numbers are right-aligned to their heading's end; text starts at its heading.
def span_end(name):
    return h.index(name) + len(name)
cols = ["Radius", "Thickness", "Material", "Semi-Dia", "Conic"]
present = [c for c in cols if c in h]
def cell(line, name):
    k = present.index(name)
    if name == "Material":
        start = h.index(name)
        nxt = present[k + 1] if k + 1 < len(present) else None
        end = h.index(nxt) if nxt else len(line)
        # The next column's numbers may start before its heading.
        return line[start:end].split("  ")[0].strip()
    # The last item before the heading's end (a solve's letter or a fixed
    # semi-diameter's U follows its number after one blank).
    return re.split(r"\s{2,}", line[:span_end(name)].strip())[-1]
def same_number(shown, value, what):
    value = float("inf") if value in ("inf", "Infinity") else float(value)
    if shown == "Infinity":
        return math.isinf(value) or value == 0.0
    cut = shown.endswith("…")
    s = shown.rstrip("…").rstrip("U").strip()
    x = float(s)
    m = re.match(r"-?(\d*)\.?(\d*)(?:e([-+]?\d+))?$", s)
    exp = int(m.group(3) or 0)
    unit = 10.0 ** (exp - len(m.group(2)))
    # Shown to its last digit: within half a unit, or a unit when cut.
    return abs(x - value) <= (1.0 if cut else 0.5) * unit * (1 + 1e-12)
checked = 0
for line in lines[head + 1:]:
    m = re.match(r"^(OBJ|STO|IMA)?\s*(\d+) (\S+)\s", line)
    if not m:
        break
    k = int(m.group(2))
    s = design[k]
    want = {"Radius": s.get("radius", "inf"), "Thickness": s.get("thickness", 0),
            "Material": s.get("material", ""), "Semi-Dia": s.get("semi_diameter", 0),
            "Conic": s.get("conic", 0)}
    for name in present:
        shown = cell(line, name)
        if name == "Material":
            w = want[name] if want[name] not in ("AIR", "air") else ""
            ok = shown == w or (shown.endswith("…") and w.startswith(shown[:-1]))
        else:
            ok = shown != "" and same_number(shown, want[name], name)
        if not ok:
            print("surface %d %s: screen %r, file %r" % (k, name, shown, want[name]))
            sys.exit(1)
    checked += 1
print("%d rows" % checked)
sys.exit(0 if checked >= need else 1)
EOF
}

start dg.json 140 60
if wait_for "dg.json" 15 && wait_for "Surf"; then
    sleep 0.3
    R=$(check_rows 17)
    WHY="$R"
    echo "# 140x60: $R"
    check "at 140x60 every surface's row shows its own values" sh -c "[ '$R' = '17 rows' ]"
    # The cursor down to surface 9: the rows above and below keep theirs.
    n=0; while [ $n -lt 9 ]; do keys Down; n=$((n + 1)); done
    sleep 0.3
    R=$(check_rows 17)
    WHY="$R"
    check "with the cursor on surface 9 every other row keeps its values" sh -c "[ '$R' = '17 rows' ]"
else
    not_ok "the double Gauss opens at 140x60"
    not_ok "cursor on surface 9"
fi

start dg.json 80 24
if wait_for "dg.json" 15 && wait_for "Surf"; then
    # Down to the image: the sheet scrolls; every row in view is checked.
    n=0; while [ $n -lt 16 ]; do keys Down; n=$((n + 1)); done
    wait_for "IMA" >/dev/null
    sleep 0.3
    R=$(check_rows 5)
    WHY="$R"
    echo "# 80x24 at the image: $R"
    check "at 80x24, scrolled to the image, every row in view shows its own values" \
        sh -c "case '$R' in *' rows') true ;; *) false ;; esac"
    # Back up to the object: scrolled the other way.
    n=0; while [ $n -lt 16 ]; do keys Up; n=$((n + 1)); done
    wait_for "OBJ" >/dev/null
    sleep 0.3
    R=$(check_rows 5)
    WHY="$R"
    check "at 80x24, scrolled back to the object, every row in view shows its own values" \
        sh -c "case '$R' in *' rows') true ;; *) false ;; esac"
else
    not_ok "the double Gauss opens at 80x24"
    not_ok "scrolled back"
fi

[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
