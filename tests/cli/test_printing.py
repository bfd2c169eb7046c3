#!/usr/bin/env python3
"""test_printing.py SAGITTA EXAMPLES - text reports print the digits a
value has, not its rounding noise (issue 30, item 11).

- semidiam: the Cassegrain's stop (surface 2, float by stop size, fixed at
  1500) bounds the marginal rays, which are aimed onto its edge, so its
  automatic semi-diameter is 1500 by construction; the aiming tolerance
  (1e-13 of the stop radius) leaves 12 significant digits, and the table
  must print "1500", not "1500.0000000000002".  No automatic value may
  print more than 12 significant digits.
- seidel: the Cassegrain's primary mirror is its stop, so the chief ray
  meets it at height 0 and its distortion (SV, W311, TDIS) is zero; a
  mirror at the stop also has SIII = -SIV (Welford's formulas with n' = -n
  and ybar = 0), so its sagittal curvature (W220S, TSFC) is zero.  These
  must print as 0 (they printed -1.55e-15 and the like: rounding noise),
  while SIII and SIV themselves are not zero.
Prints TAP.
"""
import json
import os
import re
import subprocess
import sys

import tap


def sig_digits(s):
    m = s.lstrip("-").replace(".", "").lstrip("0")
    return len(m.rstrip("0")) if "." not in s else len(m)


def main():
    exe, examples = sys.argv[1], sys.argv[2]
    cass = os.path.join(examples, "cassegrain.json")
    out = subprocess.run([exe, "semidiam", cass], stdout=subprocess.PIPE, text=True).stdout
    rows = [l.split() for l in out.splitlines() if re.match(r"^\d+\s", l)]
    stop = [r for r in rows if r[0] == "2"]
    tap.check(stop and stop[0][1] == "1500" and stop[0][2] == "1500",
              "semidiam: the Cassegrain's stop prints 1500 (automatic and set)",
              " ".join(stop[0]) if stop else out)
    bad = [" ".join(r) for r in rows if sig_digits(r[1]) > 12]
    tap.check(rows and not bad, "semidiam: automatic values carry at most 12 significant digits",
              "\n".join(bad))
    js = json.loads(subprocess.run([exe, "seidel", cass, "--format", "json"],
                                   stdout=subprocess.PIPE, text=True).stdout)
    s2 = [r for r in js["surfaces"] if r["surface"] == 2][0]
    zero = {"sums": ["SV"], "waves": ["W311", "W220S"], "transverse": ["TDIS", "TSFC"]}
    bad = ["%s %s = %r" % (g, k, s2[g][k]) for g, ks in zero.items() for k in ks
           if s2[g][k] != 0]
    bad += ["sums %s = %r" % (k, s2["sums"][k]) for k in ("SIII", "SIV")
            if not abs(s2["sums"][k]) > 1e-3]
    tap.check(not bad, "seidel: the mirror at the stop has zero distortion and sagittal "
              "curvature, printed 0", "\n".join(bad))
    text = subprocess.run([exe, "seidel", cass], stdout=subprocess.PIPE, text=True).stdout
    tap.check(re.search(r"-0\.0+e[+-]00", text) is None, "seidel text: no -0")
    return tap.finish()


if __name__ == "__main__":
    sys.exit(main())
