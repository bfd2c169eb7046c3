#!/usr/bin/env python3
"""test_wavefront_big.py SAGITTA EXAMPLES - the wavefront command where
users push it: a fine grid in bounded memory, and Zernike terms that a
system's symmetry makes zero printed as 0, not as rounding noise.

- Memory: the map and its validity are the only storage that grows with
  the grid (9 bytes a point; the picture's raster is at most 1024 across);
  at --grid 2048 the whole program must stay under that plus 40 MB (it
  took 167 MB when the points were copied three times over, 84 MB with a
  full-size raster).  Skipped under ASan, whose shadow memory is not the
  program's.
- Symmetry: on axis the Cassegrain is rotationally symmetric, so every
  Fringe term with m != 0 is exactly zero (a closed fact, not a computed
  value); terms with m == 0 (Z1, Z4, Z9, Z16) carry the spherical
  aberration and are not zero.  No coefficient may print as -0.
Prints TAP.
"""
import json
import os
import resource
import subprocess
import sys

import tap


def main():
    exe, examples = sys.argv[1], sys.argv[2]
    cass = os.path.join(examples, "cassegrain.json")

    g = 2048
    ldd = subprocess.run(["ldd", exe], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                         text=True).stdout
    if "libasan" in ldd:
        tap.check(True, "wavefront --grid %d in bounded memory # SKIP under ASan" % g)
    else:
        p = subprocess.run([exe, "wavefront", cass, "--grid", str(g)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        rss_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
        limit = 9.0 * g * g / 2 ** 20 + 40.0
        tap.check(p.returncode == 0 and rss_mb < limit,
                  "wavefront --grid %d in %.0f MB of memory (limit %.0f MB)" % (g, rss_mb, limit),
                  "exit %d, %.0f MB\n%s" % (p.returncode, rss_mb, p.stderr))

    p = subprocess.run([exe, "wavefront", cass, "--format", "json"],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    z = json.loads(p.stdout)["zernike"]
    # Fringe (n, m) of Z1..Z37 by Wyant and Creath's table: m == 0 at these.
    radial = {1, 4, 9, 16, 25, 36, 37}
    bad = ["Z%d = %r" % (j + 1, c) for j, c in enumerate(z["coef"])
           if (j + 1) not in radial and c != 0.0]
    tap.check(not bad, "on-axis Cassegrain: every non-radial Zernike term is 0", "\n".join(bad))
    bad = ["Z%d = %r" % (j, z["coef"][j - 1]) for j in (1, 4, 9, 16)
           if not abs(z["coef"][j - 1]) > 1e-6]
    tap.check(not bad, "on-axis Cassegrain: spherical terms Z1, Z4, Z9, Z16 are not noise",
              "\n".join(bad))
    text = subprocess.run([exe, "wavefront", cass], stdout=subprocess.PIPE, text=True).stdout
    rows = [l.split() for l in text.splitlines() if l.startswith("  Z")]
    bad = [" ".join(r) for r in rows if r[-1].startswith("-0") and float(r[-1]) == 0.0]
    bad += [" ".join(r) for r in rows if int(r[0][1:]) not in radial and r[-1] != "0"]
    tap.check(len(rows) == 37 and not bad, "text: non-radial terms print as 0, never -0",
              "\n".join(bad) or "%d rows" % len(rows))
    return tap.finish()


if __name__ == "__main__":
    sys.exit(main())
