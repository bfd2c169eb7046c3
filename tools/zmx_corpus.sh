#!/bin/sh
# zmx_corpus.sh - import every Zemax .zmx file under a directory and count
# the refusals by reason (issue 37's measure).
#
#   tools/zmx_corpus.sh [-s SAGITTA] [-l LIST.tsv] DIR...
#
# Each file is imported with "sagitta import FILE -o TMP.json"; a refusal's
# reason is the keyword its message names (the surface type for TYPE, "MODE
# NSC" for non-sequential files, "GLAS (missing glass)" for a glass the
# catalogs lack, "MNUM/<operand>" for a configuration operand).  Prints the
# totals, the sequential share and the reasons, most frequent first; -l
# writes one line per file: status, reason, path.
set -u
sag=./build/ui/sagitta
list=
while getopts s:l: o; do
    case $o in
    s) sag=$OPTARG ;;
    l) list=$OPTARG ;;
    *) echo "usage: $0 [-s SAGITTA] [-l LIST.tsv] DIR..." >&2; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || { echo "usage: $0 [-s SAGITTA] [-l LIST.tsv] DIR..." >&2; exit 2; }
[ -x "$sag" ] || { echo "$0: no sagitta program at $sag (build first, or give -s)" >&2; exit 2; }

# The catalogs of this tree, for a program copied elsewhere.
SAGITTA_LENSDB=${SAGITTA_LENSDB:-$(cd "$(dirname "$0")/.." && pwd)/lensdb}
export SAGITTA_LENSDB
tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT INT TERM
: > "$tmp/rows"
find "$@" -type f \( -iname '*.zmx' \) -print | LC_ALL=C sort > "$tmp/files"
while IFS= read -r f; do
    if timeout 60 "$sag" import "$f" -o "$tmp/out.json" > /dev/null 2> "$tmp/err"; then
        printf 'ok\t-\t%s\n' "$f" >> "$tmp/rows"
        continue
    fi
    rc=$?
    # The first message line that names this file: strip "sagitta: FILE:LINE: "
    # and "surface N: ", then keep what names the reason.
    line=$(grep -F -m1 "sagitta: $f:" "$tmp/err")
    msg=${line#"sagitta: $f:"}
    [ -n "$line" ] || msg=$(head -n1 "$tmp/err")
    reason=$(printf '%s\n' "$msg" | sed -e 's/^ *//' -e 's/^[0-9]*: //' -e 's/^surface [0-9]*: //' | awk '
        /^TYPE / { print "TYPE " $2; exit }
        /^GLAS:/ || /^material .* is not in the catalog/ { print "GLAS (missing glass)"; exit }
        /^MODE:/ { print "MODE NSC"; exit }
        /^MNUM: operand/ { sub(/^MNUM: operand /, ""); print "MNUM/" $1; exit }
        { sub(/:.*/, ""); print; exit }')
    [ "$rc" -eq 124 ] && reason="timeout"
    printf 'refused\t%s\t%s\n' "${reason:-exit $rc}" "$f" >> "$tmp/rows"
done < "$tmp/files"

total=$(wc -l < "$tmp/rows")
ok=$(grep -c '^ok' "$tmp/rows")
nsc=$(grep -c '	MODE NSC	' "$tmp/rows")
seq=$((total - nsc))
echo "files: $total  imported: $ok  non-sequential (MODE NSC): $nsc"
if [ "$seq" -gt 0 ]; then
    echo "sequential: $seq  imported: $ok ($(awk -v a="$ok" -v b="$seq" 'BEGIN { printf "%.1f", 100 * a / b }')%)"
fi
echo "refusals by reason:"
grep '^refused' "$tmp/rows" | cut -f2 | sort | uniq -c | sort -k1,1nr -k2
[ -z "$list" ] || cp "$tmp/rows" "$list"
