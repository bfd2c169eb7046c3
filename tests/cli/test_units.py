#!/usr/bin/env python3
"""test_units.py SAGITTA EXAMPLES - every analysis in every lens unit.

A design in centimetres, inches or metres is the same lens as the
millimetre design with every length divided by the unit's size in mm
(radius, thickness, semi-diameter, an EPD, object-height fields, and each
even-asphere coefficient a_i of r^(2i+2) multiplied by k^(2i+1)).  So
every length an analysis prints must be the millimetre design's divided by
k, and everything else (waves, F-numbers, normalized coordinates,
percentages, ray counts) must be the same.  That scaling law is the
independent fact this test checks; it caught nothing when written, and is
here so that an analysis that forgets the unit somewhere (an OPD that
divides a length in lens units by a wavelength in mm, say) fails.

Every numeric key of every JSON output is classified below as a length or
not; a key the test has not classified fails it, so a new output is
checked too.  Prints TAP.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import tap

UNITS = {"cm": 10.0, "in": 25.4, "m": 1000.0}

# Lengths in lens units, by JSON key.
LENGTH = {
    # paraxial
    "bfl", "efl", "entrance_pupil_diameter", "entrance_pupil_position",
    "exit_pupil_diameter", "exit_pupil_position", "image_distance",
    "paraxial_image_height", "stop_radius", "total_track",
    # spot, fan
    "airy_radius", "centroid_x", "centroid_y", "chief_x", "chief_y", "geo",
    "ref_x", "ref_y", "rms", "ex", "ey",
    # wavefront
    "sphere_radius",
    # seidel: the sums, the transverse aberrations and the invariant
    "SI", "SII", "SIII", "SIV", "SV", "CI", "CII", "TAST", "TAXC", "TDIS",
    "TLAC", "TPFC", "TSCO", "TSFC", "TSPH", "TTCO", "TTFC", "lagrange",
    "wave_lens_units",
    # fieldcurve
    "parax_y", "real_y", "sag_focus", "tan_focus",
    # semidiam, layout
    "auto", "set", "semi_diameter", "y", "z", "z0",
}
# The same in every unit: waves, wavelengths in µm, ratios, normalized
# coordinates, counts and indices.
SAME = {
    "wave", "wavelength_um", "um", "image_fnum", "working_fnum",
    "magnification", "object_na", "field", "hx", "hy", "px", "py", "density",
    "rays", "rays_per_cell", "reached", "opd", "coef", "fit_rms", "grid",
    "map", "pv_centroid", "pv_chief", "rms_centroid", "rms_chief",
    "W020", "W040", "W111", "W131", "W220M", "W220P", "W220S", "W220T",
    "W222", "W311", "colour_long_um", "colour_short_um", "nu_image",
    "surface", "distortion_pct", "van", "vcx", "vcy", "vdx", "vdy",
    "grid_rays_passing",
}

# Aberrations in waves: their noise floor is the OPD's, not their own.
WAVES = {"opd", "coef", "fit_rms", "map", "pv_centroid", "pv_chief",
         "rms_centroid", "rms_chief"}

# Bounds on rounding (a Zernike coefficient's error): they depend on the
# numbers each unit rounds, so they are not exact copies; both must be
# small noise floors of the same size.
BOUNDS = {"coef_bound"}

COMMANDS = [
    ["paraxial"], ["spot"], ["spot", "--reference", "centroid"], ["fan"],
    ["fan", "--opd"], ["wavefront"], ["wavefront", "--wave", "1"],
    ["seidel"], ["fieldcurve"], ["semidiam"], ["vignetting"], ["layout"],
]



def scaled(design, unit, k):
    d = json.loads(json.dumps(design))
    d["units"] = unit
    for s in d["surfaces"]:
        for key in ("radius", "thickness", "semi_diameter"):
            if isinstance(s.get(key), (int, float)):
                s[key] = s[key] / k
        if s.get("type") == "even_asphere":
            s["asphere"] = [a * k ** (2 * i + 1) for i, a in enumerate(s.get("asphere", []))]
        elif any(s.get("asphere") or []):
            raise SystemExit("test_units: cannot scale %s's terms" % s.get("type"))
    if d["aperture"]["type"] == "epd":
        d["aperture"]["value"] /= k
    if d["fields"]["type"] != "angle":
        for f in d["fields"]["list"]:
            f["x"] /= k
            f["y"] /= k
    return d


def leaves(x, key, out):
    """(key, value) of every number in x, in document order."""
    if isinstance(x, dict):
        for k2, v in x.items():
            leaves(v, k2, out)
    elif isinstance(x, list):
        for v in x:
            leaves(v, key, out)
    elif isinstance(x, (int, float)) and not isinstance(x, bool):
        out.append((key, float(x)))
    return out


def run(exe, args, path):
    p = subprocess.run([exe] + args + [path, "--format", "json"],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return p.returncode, p.stdout, p.stderr


def compare(base, other, k, lengths):
    """Mismatches between the mm output and another unit's, as text;
    lengths are the keys that are lengths in this output."""
    a = leaves(base, "", [])
    b = leaves(other, "", [])
    if len(a) != len(b):
        return "%d numbers in mm, %d here" % (len(a), len(b))
    scale = {}
    for key, v in a:
        if math.isfinite(v):
            scale[key] = max(scale.get(key, 0.0), abs(v))
    # A length that is rounding noise about zero (a centroid on a symmetric
    # axis) is compared against the output's largest length, not its own.
    floor = 1e-12 * max([abs(v) for key, v in a if key in lengths and math.isfinite(v)] or [0.0])
    # The OPD is exact to about 1e-10 waves; a fit's residual of 1e-13
    # waves is noise in any unit.
    wfloor = max(1e-12 * max([abs(v) for key, v in a if key in WAVES and math.isfinite(v)] or [0.0]),
                 1e-13)
    bad = []
    for (ka, va), (kb, vb) in zip(a, b):
        if ka != kb:
            return "keys differ: %s against %s" % (ka, kb)
        if ka in lengths:
            want = va / k
            tol = (1e-8 * scale.get(ka, 0.0) + floor) / k
        elif ka in BOUNDS:
            if not (0.0 <= va <= 1e-6 and 0.0 <= vb <= 1e-6 and 0.5 * va <= vb <= 2.0 * va):
                bad.append("%s: %r, mm %r: not a noise floor" % (ka, vb, va))
            continue
        elif ka in SAME:
            want = va
            tol = 1e-8 * scale.get(ka, 0.0) + (wfloor if ka in WAVES else 0.0)
        else:
            return "key %r is neither a length nor unit-free: classify it in test_units.py" % ka
        if math.isfinite(want) or math.isfinite(vb):
            if not (abs(vb - want) <= tol):
                bad.append("%s: %r, want %r (mm %r)" % (ka, vb, want, va))
    return "\n".join(bad[:5]) + ("\n... %d in all" % len(bad) if len(bad) > 5 else "")


def main():
    exe, examples = sys.argv[1], sys.argv[2]
    print("TAP version 13")
    tmp = tempfile.mkdtemp()
    for name in ("double_gauss", "cassegrain", "tma"):
        src = os.path.join(examples, name + ".json")
        design = json.load(open(src))
        base = {}
        for cmd in COMMANDS:
            rc, out, err = run(exe, cmd, src)
            base[" ".join(cmd)] = (rc, json.loads(out) if rc == 0 else None, err)
        for unit, k in UNITS.items():
            path = os.path.join(tmp, "%s_%s.json" % (name, unit))
            json.dump(scaled(design, unit, k), open(path, "w"))
            for cmd in COMMANDS:
                c = " ".join(cmd)
                rc0, j0, err0 = base[c]
                rc, out, err = run(exe, cmd, path)
                what = "%s of %s in %s" % (c, name, unit)
                if rc0 != 0 or rc != 0:
                    tap.check(rc == rc0, what + " (exit %d, mm %d)" % (rc, rc0), err or err0)
                    continue
                lengths = set(LENGTH)
                # fieldcurve's "field" is the field coordinate itself, a
                # length unless the fields are angles.
                if cmd[0] == "fieldcurve" and design["fields"]["type"] != "angle":
                    lengths.add("field")
                msg = compare(j0, json.loads(out), k, lengths)
                tap.check(not msg, what, msg)
    return tap.finish()


if __name__ == "__main__":
    sys.exit(main())
