#!/usr/bin/env python3
"""optiland_cassegrain.py - the paper's Cassegrain (examples/cassegrain.json)
built in optiland and traced there, for the speed comparison in
bench/RESULTS.md: rays per second and ray-surfaces per second of
optiland's trace_generic (NumPy backend, one process) on N rays of the
edge field, and the chief ray's image point beside sagitta's.

  PYTHONPATH=/path/to/optiland /usr/bin/python3 bench/optiland_cassegrain.py [N]

optiland is not a dependency of sagitta: clone it
(https://github.com/HarrisonKramer/optiland) and install numpy, scipy,
matplotlib, pandas, pyyaml and tabulate (Debian's python3-* packages).
The prescription is the example's, surface for surface; glasses are
optiland's catalogue SILICA and N-BK7 (sagitta's SILICA and BK7 rows).
"""
import json
import math
import os
import sys
import time

from optiland import optic
from optiland.materials import Material

here = os.path.dirname(os.path.abspath(__file__))
design = json.load(open(os.path.join(here, "..", "examples", "cassegrain.json")))
n = int(sys.argv[1]) if len(sys.argv) > 1 else 1000000

lens = optic.Optic()
mats = {"SILICA": Material("SILICA"), "BK7": Material("N-BK7")}
surfs = design["surfaces"]
for i, s in enumerate(surfs):
    r = s["radius"]
    r = math.inf if r == "inf" else float(r)
    t = s["thickness"]
    kw = {"index": i, "radius": r, "conic": float(s.get("conic", 0))}
    if i < len(surfs) - 1:
        kw["thickness"] = float(t)
    m = s.get("material", "")
    if m == "MIRROR":
        kw["material"] = "mirror"
    elif m:
        kw["material"] = mats[m]
    if s.get("stop"):
        kw["is_stop"] = True
    lens.add_surface(**kw)
lens.set_aperture(aperture_type="float_by_stop_size", value=1500.0)
lens.set_field_type(field_type="object_height")
lens.add_field(y=0.0)
lens.add_field(y=4.0e6)
lens.add_wavelength(value=0.5875618, is_primary=True)

# The chief ray of the edge field, for the agreement check.
chief = lens.trace_generic(0.0, 1.0, 0.0, 0.0, 0.5875618)
print("optiland chief ray (0, 1, 0, 0) at the image: x %.12g y %.12g" %
      (float(chief.x[0]), float(chief.y[0])))

# N rays over the pupil (a Vogel spiral, as sagitta's bench --spot), field (0, 1).
import numpy as np
k = np.arange(n) + 0.5
rho = np.sqrt(k / n)
phi = k * math.pi * (3.0 - math.sqrt(5.0))
px, py = rho * np.cos(phi), rho * np.sin(phi)
hx, hy = np.zeros(n), np.ones(n)
best = math.inf
for rep in range(3):
    t0 = time.process_time()
    rays = lens.trace_generic(hx, hy, px, py, 0.5875618)
    best = min(best, time.process_time() - t0)
ok = int(np.count_nonzero(np.isfinite(np.asarray(rays.y))))
nsurf = len(surfs)
print("optiland trace_generic: %d rays, %d reached the image, CPU %.3f s (best of 3): "
      "%.3g rays/s, %.3g ray-surfaces/s (%d surfaces after the object)" %
      (n, ok, best, n / best, n * (nsurf - 1) / best, nsurf - 1))
