#!/usr/bin/env python3
"""odd_rays.py - ray lists with odd values, for bench/rays_same.sh.

    odd_rays.py NORM.csv SD.csv [NNORM [NSD [SEED]]]

NORM.csv: hx,hy,px,py rows, mostly in a few fields (runs, as sets are),
with values drawn from odd texts: negative zero, subnormals, 1e-300,
25-digit decimals, exponent forms, integers, values beyond the pupil and
the field (up to 3), blanks around a field, a leading + or point, and
plain ones written with repr.  SD.csv:
x,y,z,l,m,n rows (start points near the axis, directions mostly forward,
some grazing or backward, unnormalized)."""
import random
import sys

ODD = ["-0", "0", "-0.0", "5e-324", "-4.9406564584124654e-324", "2.2250738585072009e-308",
       "1e-310", "1e-300", "0.1000000000000000055511151231257827", "0.3333333333333333333333333",
       "1E-5", "2.5e-1", "-7.5E-01", "1", "-1", "1.0000000000000002", "0.9999999999999999",
       "1.5", "-2", "3", "0.70710678118654757", "123456789012345678901234e-24",
       " 0.25", "0.125 ", "+0.5", ".5", "5.", "1e+2", "1e-0", "-.75E+0"]


def num(rng, scale):
    r = rng.random()
    if r < 0.15:
        return rng.choice(ODD)
    if r < 0.2:
        return repr(rng.uniform(-3, 3))
    return repr(rng.uniform(-scale, scale))


def main():
    norm, sd = sys.argv[1], sys.argv[2]
    nn = int(sys.argv[3]) if len(sys.argv) > 3 else 4000
    ns = int(sys.argv[4]) if len(sys.argv) > 4 else 3000
    rng = random.Random(int(sys.argv[5]) if len(sys.argv) > 5 else 1)
    with open(norm, "w") as f:
        f.write("hx,hy,px,py\n")
        hx, hy = "0", "0"
        for i in range(nn):
            if rng.random() < 0.02:
                hx, hy = num(rng, 1.0), num(rng, 1.0)
            f.write("%s,%s,%s,%s\n" % (hx, hy, num(rng, 1.0), num(rng, 1.0)))
    with open(sd, "w") as f:
        f.write("x,y,z,l,m,n\n")
        for i in range(ns):
            l, m = num(rng, 0.2), num(rng, 0.2)
            n = rng.choice(["1", "0.99", "-1", "0", "1e-9", repr(rng.uniform(0.5, 1))])
            if l in ("0", "-0", "-0.0") and m in ("0", "-0", "-0.0") and float(n) == 0:
                n = "1"
            f.write("%s,%s,%s,%s,%s,%s\n" % (num(rng, 5.0), num(rng, 5.0), num(rng, 1.0), l, m, n))


if __name__ == "__main__":
    main()
