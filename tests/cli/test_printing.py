#!/usr/bin/env python3
"""test_printing.py SAGITTA EXAMPLES - text reports print the digits a
value has, not its rounding noise (issue 30, item 11).

- semidiam: the Cassegrain's stop (surface 2, float by stop size, fixed at
  1500) bounds the marginal rays, which are aimed onto its edge, so its
  automatic semi-diameter is 1500 by construction; the aiming tolerance
  (1e-13 of the stop radius) leaves 12 significant digits, and the table
  must print "1500", not "1500.0000000000002".  No automatic value may
  print more than 12 significant digits.
Prints TAP.
"""
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
    return tap.finish()


if __name__ == "__main__":
    sys.exit(main())
