#!/usr/bin/env python3
# qcon_ref.py - the values tests/test_shapes.c (qcon_forbes_values) checks the
# Q-type asphere against: its sag and slopes from the definition (Forbes,
# Opt. Express 15, 5218 (2007), eq. 2.3) with mpmath's own Jacobi polynomials
# and numerical derivatives, independent of sagitta's recurrence.  Prints
# x, y, z, dz/dx, dz/dy.
import mpmath as mp
mp.mp.dps = 60
# The surface's numbers as the test's doubles hold them, exactly.
R, k, rn = mp.mpf(40.0), mp.mpf(-0.7), mp.mpf(10.0)
a = [mp.mpf(v) for v in (2e-3, -5e-4, 1e-4, -3e-5, 1e-5, 4e-6)]
def sag(x, y):
    r2 = x * x + y * y
    c = 1 / R
    z = c * r2 / (1 + mp.sqrt(1 - (1 + k) * c * c * r2))
    u2 = r2 / (rn * rn)
    return z + u2 * u2 * sum(am * mp.jacobi(m, 0, 4, 2 * u2 - 1) for m, am in enumerate(a))
for (x, y) in ((mp.mpf(3), mp.mpf(4)), (mp.mpf(0), mp.mpf('9.5')), (mp.mpf('7.125'), mp.mpf('-6.25'))):
    z = sag(x, y)
    gx = mp.diff(lambda t: sag(t, y), x)
    gy = mp.diff(lambda t: sag(x, t), y)
    print(mp.nstr(x, 10), mp.nstr(y, 10), mp.nstr(z, 40), mp.nstr(gx, 40), mp.nstr(gy, 40))
