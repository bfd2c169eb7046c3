#!/usr/bin/env python3
"""shapes.py - writes designs whose surfaces are the shapes of src/shape/shape.h,
for timing their traces.

    python3 bench/shapes.py DIR

Writes into DIR:

  cooke_odd.json, cooke_toroid.json, cooke_biconic.json, cooke_fringe.json,
  cooke_standard.json, cooke_xy.json: examples/cooke_triplet.json with each
  of its six lens surfaces made an odd asphere (small r^3 and r^4 terms), a
  toroid (radius of rotation 1.05 times the radius), a biconic (x radius
  1.05 times the radius, x conic -0.2), a Zernike Fringe or Standard sag
  (small terms up to Z16 about a decenter) or an XY polynomial (small
  terms to order 4), normalized on 8 mm;

  cass_odd.json, cass_tor.json, cass_bic.json, cass_zf.json, cass_xy.json:
  examples/cassegrain.json (real aiming) with its primary made an odd
  asphere (b3, b4, b5 = 2e-13, -1e-17, 1e-21), a toroid (radius of
  rotation -10400 mm about the y curve's conic), a biconic (x radius
  -10450 mm, x conic -1), a Zernike Fringe sag (terms 4, 5, 8, 9 of 2e-4
  to 1e-3 mm on 1500 mm) or an XY polynomial (terms to the 4th order).

The shapes stay close to the originals, so every ray of the bench reaches
the image; they exercise each shape's kernel, not a real design.
"""
import json
import os
import sys

out = sys.argv[1] if len(sys.argv) > 1 else '.'
here = os.path.dirname(os.path.abspath(__file__))
base = json.load(open(os.path.join(here, '..', 'examples', 'cooke_triplet.json')))
cass = json.load(open(os.path.join(here, '..', 'examples', 'cassegrain.json')))


def make(name, shape):
    d = json.loads(json.dumps(base))
    for i, s in enumerate(d['surfaces'][1:-1], start=1):
        if s['radius'] == 'inf':
            continue
        r = float(s['radius'])
        sign = 1.0 if i % 2 else -1.0
        if shape == 'odd':
            s['type'] = 'odd_asphere'
            s['odd'] = [0, 0, sign * 2e-6, 1e-6, 0, 0, 0, 0]
        elif shape == 'toroid':
            s['type'] = 'toroidal'
            s['radius_x'] = 1.05 * r
            s['asphere'] = [0, sign * 1e-6, 0, 0, 0, 0, 0, 0]
        elif shape == 'biconic':
            s['type'] = 'biconic'
            s['radius_x'] = 1.05 * r
            s['conic_x'] = -0.2
        elif shape in ('fringe', 'standard'):
            s['type'] = 'zernike_' + shape
            s['norm_radius'] = 8.0
            s['terms'] = [sign * 1e-4 / (1 + k) for k in range(16)]
            s['zernike_decenter_x'] = 0.1
            s['zernike_decenter_y'] = -0.2
        elif shape == 'xy':
            s['type'] = 'xy_polynomial'
            s['norm_radius'] = 8.0
            s['terms'] = [sign * 1e-4 / (1 + k) for k in range(14)]
    d['title'] = 'Cooke triplet, lens surfaces made %s (bench/shapes.py)' % shape
    with open(os.path.join(out, 'cooke_%s.json' % name), 'w') as f:
        json.dump(d, f, indent=1)
        f.write('\n')


for n in ('odd', 'toroid', 'biconic', 'fringe', 'standard', 'xy'):
    make(n, n)


def make_cass(name, shape):
    d = json.loads(json.dumps(cass))
    p = d['surfaces'][2]
    if shape == 'odd':
        p['type'] = 'odd_asphere'
        p['odd'] = [0, 0, 2e-13, -1e-17, 1e-21, 0, 0, 0]
    elif shape == 'tor':
        p['type'] = 'toroidal'
        p['radius_x'] = -10400
    elif shape == 'bic':
        p['type'] = 'biconic'
        p['radius_x'] = -10450
        p['conic_x'] = -1
    elif shape == 'zf':
        p['type'] = 'zernike_fringe'
        p['norm_radius'] = 1500
        p['terms'] = [0, 0, 0, 1e-3, 5e-4, 0, 0, 2e-4, 3e-4]
    elif shape == 'xy':
        p['type'] = 'xy_polynomial'
        p['norm_radius'] = 1500
        p['terms'] = [0, 0, 2e-4, 0, 1e-4, 5e-5, 0, 5e-5, 0, 2e-5, 0, 1e-5, 0, 1e-5]
    d['title'] = 'Cassegrain, primary made %s (bench/shapes.py)' % shape
    with open(os.path.join(out, 'cass_%s.json' % name), 'w') as f:
        json.dump(d, f, indent=1)
        f.write('\n')


for n in ('odd', 'tor', 'bic', 'zf', 'xy'):
    make_cass(n, n)
