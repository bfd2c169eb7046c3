#!/usr/bin/env python3
"""test_offaxis.py SAGITTA EXAMPLES - analyses checked where users look:
full and intermediate fields, every wavelength, against computations made
here from the traced rays alone (sagitta trace's CSV), never from the
analysis's own code:

- the OPD column of sagitta trace at every wavelength, from each ray's
  optical path to the image and its direction, carried back to the
  reference sphere that sagitta(1) defines (centred on the primary chief
  ray's image point, through the paraxial exit pupil's axial point);
- the field-curve command's real image height, paraxial height and
  distortion at each of its fields up to full field: the real chief ray
  traced alone, the paraxial height scaled from sagitta paraxial's
  full-field height by tan(angle) (paraxial optics is linear in tan);
- the spot CSV of the full field at every wavelength: chief ray, centroid,
  RMS and GEO radius from the hexapolar pattern's rays traced here.
Prints TAP.
"""
import csv
import io
import json
import math
import subprocess
import sys
import tempfile

import tap
import os



def run(exe, args):
    p = subprocess.run([exe] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise SystemExit("sagitta %s: exit %d: %s" % (" ".join(args), p.returncode, p.stderr))
    return p.stdout


def image_rows(exe, design, rays, wave, tmp):
    """The image surface's row of each ray (hx, hy, px, py), at wavelength wave."""
    path = os.path.join(tmp, "rays.csv")
    with open(path, "w") as f:
        f.write("hx,hy,px,py\n")
        for r in rays:
            f.write("%r,%r,%r,%r\n" % r)
    out = run(exe, ["trace", design, "--rays", path, "--wave", str(wave), "--format", "csv"])
    last = {}
    for row in csv.DictReader(io.StringIO(out)):
        k = int(row.get("ray") or 0)
        if k not in last or int(row["surface"]) > int(last[k]["surface"]):
            last[k] = row
    return [last[k] for k in sorted(last)]


def vec(row, *keys):
    return [float(row[k]) for k in keys]


def hexapolar(n):
    pts = [(0.0, 0.0)]
    for i in range(1, n + 1):
        for j in range(6 * i):
            a = 2 * math.pi * j / (6 * i)
            pts.append((i / n * math.cos(a), i / n * math.sin(a)))
    return pts


def main():
    exe, examples = sys.argv[1], sys.argv[2]
    tmp = tempfile.mkdtemp()
    design = os.path.join(examples, "double_gauss.json")
    d = json.load(open(design))
    waves = [w["um"] for w in d["wavelengths"]["list"]]
    primary = d["wavelengths"]["primary"]
    par = json.loads(run(exe, ["paraxial", design, "--format", "json"]))
    print("TAP version 13")

    # --- OPD at every wavelength and field, from the rays' paths.
    E = (0.0, 0.0, par["exit_pupil_position"])
    pupil = [(0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (0.3, 0.5), (-0.7, -0.6), (0.5, -0.8)]
    for hy in (0.0, 0.6, 1.0):
        chief = image_rows(exe, design, [(0.0, hy, 0.0, 0.0)], primary, tmp)[0]
        C = vec(chief, "x", "y", "z")
        R = math.dist(C, E)

        def opl_to_sphere(row):
            P = vec(row, "x", "y", "z")
            dv = vec(row, "l", "m", "n")
            w = [P[i] - C[i] for i in range(3)]
            wd = sum(w[i] * dv[i] for i in range(3))
            disc = wd * wd - sum(x * x for x in w) + R * R
            best = None
            for t in (wd + math.sqrt(disc), wd - math.sqrt(disc)):
                Q = [P[i] - t * dv[i] for i in range(3)]
                if best is None or math.dist(Q, E) < best[0]:
                    best = (math.dist(Q, E), t)
            return float(row["opl"]) - best[1]   # image space is air

        ref = opl_to_sphere(chief)
        for wave in range(1, len(waves) + 1):
            lam = waves[wave - 1] * 1e-3        # millimetres
            rows = image_rows(exe, design, [(0.0, hy) + p for p in pupil], wave, tmp)
            bad = []
            for p, row in zip(pupil, rows):
                want = (ref - opl_to_sphere(row)) / lam
                got = float(row["opd_waves"])
                if abs(got - want) > 2e-7:
                    bad.append("pupil %r: %r, from the paths %r" % (p, got, want))
            tap.check(not bad, "trace's OPD at field hy=%g, wavelength %d, from the rays' paths" % (hy, wave),
                "\n".join(bad))
            # One ray alone takes the scalar OPD (the editor's), not the batch's.
            out = run(exe, ["trace", design, "--ray", "0,%r,0.3,0.5" % hy, "--wave", str(wave),
                            "--format", "csv"])
            row = [r for r in csv.DictReader(io.StringIO(out))][-1]
            want = (ref - opl_to_sphere(row)) / lam
            got = float(row["opd_waves"])
            tap.check(abs(got - want) <= 2e-7, "one ray's OPD at field hy=%g, wavelength %d" % (hy, wave),
                "%r, from the paths %r" % (got, want))

    # --- Field curve points up to full field, against the chief ray alone.
    fc = json.loads(run(exe, ["fieldcurve", design, "--format", "json"]))
    pts = fc["fields"]
    theta_max = max(abs(f["y"]) for f in d["fields"]["list"])
    bad = []
    rays = [(0.0, p["hy"], 0.0, 0.0) for p in pts]
    rows = image_rows(exe, design, rays, primary, tmp)
    for p, row in zip(pts, rows):
        real = float(row["y"])
        parax = par["paraxial_image_height"] * math.tan(math.radians(p["field"])) / \
            math.tan(math.radians(theta_max))
        dist = 100 * (real - parax) / parax if parax else 0.0
        if abs(p["real_y"] - real) > 1e-12 * abs(par["paraxial_image_height"]) or \
           abs(p["parax_y"] - parax) > 1e-12 * abs(par["paraxial_image_height"]) or \
           abs(p["distortion_pct"] - dist) > 1e-9:
            bad.append("hy %r: real %r (%r) parax %r (%r) distortion %r (%r)" %
                       (p["hy"], p["real_y"], real, p["parax_y"], parax, p["distortion_pct"], dist))
    tap.check(len(pts) > 2 and pts[-1]["hy"] == 1 and not bad,
        "fieldcurve's heights and distortion at %d fields up to full field" % len(pts), "\n".join(bad))

    # --- The spot CSV of the full field, every wavelength.
    out = run(exe, ["spot", design, "--field", "3", "--format", "csv"])
    table = list(csv.DictReader(io.StringIO(out)))
    hy = 1.0
    pat = hexapolar(6)
    ref = vec(image_rows(exe, design, [(0.0, hy, 0.0, 0.0)], primary, tmp)[0], "x", "y")
    poly = {"sw": 0.0, "r2": 0.0, "sx": 0.0, "sy": 0.0, "geo": 0.0}
    for row in table:
        if row["wave"] == "all":
            continue
        wave = int(row["wave"])
        chief = vec(image_rows(exe, design, [(0.0, hy, 0.0, 0.0)], wave, tmp)[0], "x", "y")
        rs = image_rows(exe, design, [(0.0, hy) + p for p in pat], wave, tmp)
        ok_rays = [vec(r, "x", "y") for r in rs if r["status"] == "OK"]
        n = len(ok_rays)
        cx = sum(p[0] for p in ok_rays) / n
        cy = sum(p[1] for p in ok_rays) / n
        rms = math.sqrt(sum((p[0] - ref[0]) ** 2 + (p[1] - ref[1]) ** 2 for p in ok_rays) / n)
        geo = max(math.hypot(p[0] - ref[0], p[1] - ref[1]) for p in ok_rays)
        wt = d["wavelengths"]["list"][wave - 1].get("weight", 1)
        poly["sw"] += wt * n
        poly["r2"] += wt * sum((p[0] - ref[0]) ** 2 + (p[1] - ref[1]) ** 2 for p in ok_rays)
        poly["sx"] += wt * sum(p[0] for p in ok_rays)
        poly["sy"] += wt * sum(p[1] for p in ok_rays)
        poly["geo"] = max(poly["geo"], geo)
        scale = abs(ref[1])
        want = {"rays": len(pat), "reached": n, "chief_x": chief[0], "chief_y": chief[1],
                "centroid_x": cx, "centroid_y": cy, "ref_x": ref[0], "ref_y": ref[1],
                "rms": rms, "geo": geo, "hy": hy, "hx": 0.0}
        bad = []
        for k, v in want.items():
            got = float(row[k])
            if abs(got - v) > 1e-12 * scale:
                bad.append("%s: %r, from the rays %r" % (k, got, v))
        tap.check(not bad, "spot CSV of the full field at wavelength %d against its traced rays" % wave,
            "\n".join(bad))

    # The polychromatic row: every wavelength's rays weighted by its weight.
    allrow = [r for r in table if r["wave"] == "all"]
    want = {"rms": math.sqrt(poly["r2"] / poly["sw"]), "geo": poly["geo"],
            "centroid_x": poly["sx"] / poly["sw"], "centroid_y": poly["sy"] / poly["sw"]}
    bad = []
    for k, v in want.items():
        got = float(allrow[0][k]) if allrow else float("nan")
        if not abs(got - v) <= 1e-12 * abs(ref[1]):
            bad.append("%s: %r, from the rays %r" % (k, got, v))
    tap.check(len(allrow) == 1 and not bad, "spot CSV of the full field, all wavelengths weighted", "\n".join(bad))

    return tap.finish()


if __name__ == "__main__":
    sys.exit(main())
