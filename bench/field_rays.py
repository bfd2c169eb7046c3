#!/usr/bin/env python3
"""field_rays.py - a normalized ray list for bench/rays_speed.

    field_rays.py OUT.csv [RAYS_PER_FIELD [FIELDS [SEED]]]

Writes hx,hy,px,py rows: hx 0, hy k/(FIELDS-1) for FIELDS fields k
(default 10), RAYS_PER_FIELD rays each (default 100000), px and py
uniform in the unit disc (rejection sampling), every number written with
Python's repr (the shortest text that reads back to the same double).
bench/RESULTS.md's issue-18 figures use the defaults (F1E6.csv, 1e6 rays)."""
import random
import sys


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    per = int(sys.argv[2]) if len(sys.argv) > 2 else 100000
    nf = int(sys.argv[3]) if len(sys.argv) > 3 else 10
    rng = random.Random(int(sys.argv[4]) if len(sys.argv) > 4 else 18)
    with open(out, "w") as f:
        f.write("hx,hy,px,py\n")
        for k in range(nf):
            hy = k / (nf - 1) if nf > 1 else 0.0
            for _ in range(per):
                while True:
                    px = rng.uniform(-1.0, 1.0)
                    py = rng.uniform(-1.0, 1.0)
                    if px * px + py * py <= 1.0:
                        break
                f.write("%r,%r,%r,%r\n" % (0.0, hy, px, py))


if __name__ == "__main__":
    main()
