#!/usr/bin/env python3
"""many_surfaces.py - writes a long design for timing the editor's recompute.

    python3 bench/many_surfaces.py [N] > many.json

N surfaces in all (1000 by default): the object at infinity, N - 2 weak
menisci alternating between five catalog glasses and air (radii +-400 and
+-450/-380 mm, 2 mm of glass, 1 mm of air), stop on surface 1, and the image.
Built from examples/singlet.json's settings (wavelengths, fields, EPD 10).
"""
import json
import os
import sys

n = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
here = os.path.dirname(os.path.abspath(__file__))
d = json.load(open(os.path.join(here, '..', 'examples', 'singlet.json')))
glasses = ['N-BK7', 'N-SF5', 'N-LAK9', 'F2', 'N-SK16']
surfs = [d['surfaces'][0]]
for i in range(1, n - 1):
    s = dict(d['surfaces'][1])
    s['asphere'] = [0] * 8
    s['comment'] = ''
    s['stop'] = i == 1
    if i % 2 == 1:
        s['radius'] = 400.0 if (i // 2) % 2 == 0 else -400.0
        s['thickness'] = 2.0
        s['material'] = glasses[(i // 2) % len(glasses)]
    else:
        s['radius'] = 450.0 if (i // 2) % 2 == 0 else -380.0
        s['thickness'] = 1.0
        s['material'] = 'AIR'
    s['semi_diameter'] = 20
    s['sd_fixed'] = False
    surfs.append(s)
surfs.append(dict(d['surfaces'][-1]))
d['surfaces'] = surfs
d['title'] = '%d surfaces: alternating weak menisci in five glasses' % n
json.dump(d, sys.stdout, indent=1)
sys.stdout.write('\n')
