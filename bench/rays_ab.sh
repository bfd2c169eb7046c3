#!/bin/sh
# rays_ab.sh - bench/rays_speed for two sagitta builds, round by round.
#
#   bench/rays_ab.sh RAYS_SPEED SAGITTA_A SAGITTA_B DESIGN RAYS.csv FORMAT [ROUNDS]
#
# Each round runs RAYS_SPEED (one round: the batch trace in memory, then
# SAGITTA trace --rays) for A, then for B, so both see the same load; it
# prints every round and then the medians of each build's batch and
# trace --rays CPU and wall times and their ratios, with the load average
# before and after.
set -eu
rs=$1
a=$2
b=$3
design=$4
rays=$5
fmt=$6
rounds=${7:-5}
tmp=$(mktemp /tmp/rays_ab.XXXXXX)
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
i=0
while [ $i -lt "$rounds" ]; do
    for s in A B; do
        if [ $s = A ]; then bin=$a; else bin=$b; fi
        "$rs" "$bin" "$design" "$rays" "$fmt" 1 > "$tmp.out"
        bw=$(sed -n 's/^batch trace: *wall \([0-9.]*\) s, cpu \([0-9.]*\) s.*/\1/p' "$tmp.out")
        bc=$(sed -n 's/^batch trace: *wall \([0-9.]*\) s, cpu \([0-9.]*\) s.*/\2/p' "$tmp.out")
        tw=$(sed -n 's/^trace --rays [a-z0-9]* *: wall \([0-9.]*\) s, cpu \([0-9.]*\) s.*/\1/p' "$tmp.out")
        tc=$(sed -n 's/^trace --rays [a-z0-9]* *: wall \([0-9.]*\) s, cpu \([0-9.]*\) s.*/\2/p' "$tmp.out")
        echo "$s $bw $bc $tw $tc" | tee -a "$tmp"
    done
    i=$((i + 1))
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
for s in A B; do
    grep "^$s " "$tmp" | awk -v s="$s" -v fmt="$fmt" '
        function med(a, n,   i, j, t) {
            for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
            return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2 }
        { n++; bw[n] = $2; bc[n] = $3; tw[n] = $4; tc[n] = $5 }
        END { mbw = med(bw, n); mbc = med(bc, n); mtw = med(tw, n); mtc = med(tc, n)
              printf "%s %-5s batch wall %.3f s cpu %.3f s   trace --rays wall %.3f s cpu %.3f s   ratio wall %.2f cpu %.2f\n",
                     s, fmt, mbw, mbc, mtw, mtc, mtw / mbw, mtc / mbc }'
done
rm -f "$tmp" "$tmp.out"
