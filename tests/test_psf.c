/*
 * test_psf.c - the FFT PSF, Strehl ratio and FFT MTF against closed forms.
 *
 * 1. A paraboloid mirror on axis with the object at infinity is perfect:
 *    its MTF is the circular pupil's, 2/pi (phi - cos phi sin phi) with
 *    cos phi = nu / nu_c, nu_c = 1 / (lambda F#), tangential, sagittal and
 *    the diffraction limit; its Strehl ratio is 1; its PSF is Airy's,
 *    (2 J1(v) / v)^2 with v = pi r / (lambda F#), at the grid's points.
 * 2. Three wavelengths: the perfect system's polychromatic MTF is the
 *    weighted sum of the circular pupil's MTF at each wavelength's cutoff.
 * 3. The same paraboloid with its image plane dz beyond the focus: the
 *    Strehl ratio against |int_0^1 exp(i 2 pi W(rho)) 2 rho d rho|^2, W
 *    from the exact geometry of the defocused sphere (written out in
 *    test_wavefront.c, opd_fan_defocus), integrated here by Gauss-Legendre,
 *    and against (sin(pi W020) / (pi W020))^2 for W020 the edge OPD.
 */
#define _XOPEN_SOURCE 700 /* j1 */
#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static const double PI = 3.14159265358979323846;

/* Object at infinity; surface 1 the stop, flat, at the vertex of a
 * paraboloid of focal length f; the image dz beyond its focus. */
static sg_system *paraboloid(double f, double epd, double dz)
{
    sg_system *sys = sg_system_new();
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 4), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].radius = INFINITY;
    sys->surf[1].thickness = 0.0;
    sys->surf[2].radius = -2.0 * f;
    sys->surf[2].conic = -1.0;
    sys->surf[2].mat.kind = SG_MAT_MIRROR;
    sys->surf[2].thickness = -(f + dz);
    sys->stop = 1;
    sys->aper_type = SG_APER_EPD;
    sys->aper_value = epd;
    sys->field_type = SG_FIELD_ANGLE;
    sys->nfield = 1;
    sys->field[0].x = sys->field[0].y = 0.0;
    sys->field[0].weight = 1.0;
    return sys;
}

/* The circular pupil's MTF at nu / nu_c = x. */
static double mtf_circle(double x)
{
    double phi;
    if (x >= 1.0)
        return 0.0;
    phi = acos(x);
    return 2.0 / PI * (phi - cos(phi) * sin(phi));
}

static void perfect_mtf(void **state)
{
    const double f = 200.0, epd = 20.0;
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    sg_mtf_opts o;
    sg_mtf m;
    sg_diag d;
    double lambda_mm = sys->wave[0].um * 1e-3, nuc = 1.0 / (lambda_mm * f / epd);
    double worst = 0.0;
    int j;
    (void)state;
    sg_mtf_opts_init(&o);
    o.sampling = 128;
    sg_diag_clear(&d);
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    assert_int_equal(m.nfield, 1);
    assert_true(fabs(m.cutoff / nuc - 1.0) < 1e-9);
    assert_true(fabs(m.freq[m.npts - 1] / nuc - 1.0) < 1e-9);
    for (j = 0; j < m.npts; j++) {
        double want = mtf_circle(m.freq[j] / nuc);
        worst = fmax(worst, fabs(m.tan[j] - want));
        worst = fmax(worst, fabs(m.sag[j] - want));
        worst = fmax(worst, fabs(m.dl[j] - want));
    }
    print_message("# perfect F/%g, sampling %d: MTF against 2/pi (phi - cos phi sin phi): "
                  "largest difference %.3g\n", f / epd, o.sampling, worst);
    /* The grid's disk is the circle to about one sample in 128. */
    assert_true(worst < 0.002);
    sg_mtf_free(&m);

    /* --max-frequency: half the cutoff, the same curve. */
    o.max_frequency = nuc / 2;
    o.sampling = 64;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    worst = 0.0;
    for (j = 0; j < m.npts; j++)
        worst = fmax(worst, fabs(m.tan[j] - mtf_circle(m.freq[j] / nuc)));
    assert_true(fabs(m.freq[m.npts - 1] - nuc / 2) < 1e-9 * nuc);
    print_message("# sampling 64 to half the cutoff: largest difference %.3g\n", worst);
    assert_true(worst < 0.004);
    sg_mtf_free(&m);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* Vignetting factor VCY = 0.5 on the perfect paraboloid: the pupil is an
 * ellipse half as tall, so the tangential MTF (along y) is the circle's
 * with half the cutoff and the sagittal one the circle's. */
static void compressed_pupil(void **state)
{
    const double f = 200.0, epd = 20.0;
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    sg_mtf_opts o;
    sg_mtf m;
    sg_psf_opts po;
    sg_psf p;
    sg_diag d;
    double nuc = 1.0 / (sys->wave[0].um * 1e-3 * f / epd), worst = 0.0;
    int j;
    (void)state;
    sys->field[0].vcy = 0.5;
    sg_mtf_opts_init(&o);
    o.sampling = 128;
    sg_diag_clear(&d);
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    for (j = 0; j < m.npts; j++) {
        worst = fmax(worst, fabs(m.tan[j] - mtf_circle(m.freq[j] / (0.5 * nuc))));
        worst = fmax(worst, fabs(m.sag[j] - mtf_circle(m.freq[j] / nuc)));
    }
    print_message("# VCY 0.5: MTF against the circle's at half and full cutoff: largest "
                  "difference %.3g\n", worst);
    assert_true(worst < 0.003);
    sg_mtf_free(&m);
    /* The PSF grid is twice as coarse along y. */
    sg_psf_opts_init(&po);
    po.sampling = 32;
    assert_int_equal(sg_psf_compute(sys, cat, &po, &p, &d), SG_OK);
    assert_true(fabs(p.spacing_y_um / p.spacing_x_um - 2.0) < 1e-12);
    sg_psf_free(&p);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* A slit |x| <= half the pupil's radius on the stop: the sagittal MTF
 * (along x) ends at half the cutoff, the pupil's width there, while the
 * tangential one does not.  (A central obscuration: annular_pupil.) */
static void slit_pupil(void **state)
{
    const double f = 200.0, epd = 20.0;
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    sg_mtf_opts o;
    sg_mtf m;
    sg_diag d;
    double nuc = 1.0 / (sys->wave[0].um * 1e-3 * f / epd);
    int j;
    (void)state;
    sg_mtf_opts_init(&o);
    sg_diag_clear(&d);
    sys->surf[1].aperture = SG_APERTURE_RECTANGULAR;
    sys->surf[1].ap_xhalf = epd / 4;
    sys->surf[1].ap_yhalf = epd;
    o.sampling = 128;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    for (j = 0; j < m.npts; j++) {
        double x = m.freq[j] / nuc;
        if (x > 0.51)
            assert_true(m.sag[j] < 1e-9);
        if (x > 0.51 && x < 0.9)
            assert_true(m.tan[j] > 0.01);
    }
    sg_mtf_free(&m);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

static void perfect_psf(void **state)
{
    const double f = 200.0, epd = 20.0;
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    sg_psf_opts o;
    sg_psf p;
    sg_diag d;
    double lf = sys->wave[0].um * f / epd, worst = 0.0; /* lambda F#, um */
    int i, j, c;
    (void)state;
    sg_psf_opts_init(&o);
    o.sampling = 128;
    sg_diag_clear(&d);
    assert_int_equal(sg_psf_compute(sys, cat, &o, &p, &d), SG_OK);
    assert_int_equal(p.size, 256);
    /* The grid: lambda F# (N - 1) / (2N). */
    assert_true(fabs(p.spacing_x_um / (lf * 127.0 / 256.0) - 1.0) < 1e-9);
    assert_true(fabs(p.strehl - 1.0) < 1e-9 && fabs(p.strehl_exact - 1.0) < 1e-9);
    assert_true(fabs(p.peak - 1.0) < 1e-9);
    c = p.size / 2;
    /* Airy's pattern out to the third dark ring. */
    for (j = -12; j <= 12; j++)
        for (i = -12; i <= 12; i++) {
            double r = hypot(i * p.spacing_x_um, j * p.spacing_y_um), v = PI * r / lf;
            double want = v == 0.0 ? 1.0 : pow(2.0 * j1(v) / v, 2);
            worst = fmax(worst, fabs(p.psf[(size_t)(c + j) * p.size + c + i] - want));
        }
    print_message("# perfect PSF against Airy: largest difference %.3g\n", worst);
    assert_true(worst < 0.002);
    sg_psf_free(&p);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

static void polychromatic_mtf(void **state)
{
    const double f = 200.0, epd = 20.0;
    const double um[3] = { 0.4861327, 0.5875618, 0.6562725 }, wt[3] = { 1.0, 2.0, 0.5 };
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    sg_mtf_opts o;
    sg_mtf m;
    sg_diag d;
    double worst = 0.0;
    int j, w;
    (void)state;
    sys->nwave = 3;
    for (w = 0; w < 3; w++) {
        sys->wave[w].um = um[w];
        sys->wave[w].weight = wt[w];
    }
    sys->primary_wave = 1;
    sg_mtf_opts_init(&o);
    o.sampling = 128;
    sg_diag_clear(&d);
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    /* The shortest wavelength's cutoff. */
    assert_true(fabs(m.cutoff * um[0] * 1e-3 * f / epd - 1.0) < 1e-9);
    for (j = 0; j < m.npts; j++) {
        double want = 0.0;
        for (w = 0; w < 3; w++)
            want += wt[w] * mtf_circle(m.freq[j] * um[w] * 1e-3 * f / epd);
        want /= wt[0] + wt[1] + wt[2];
        worst = fmax(worst, fabs(m.tan[j] - want));
        worst = fmax(worst, fabs(m.sag[j] - want));
    }
    print_message("# three wavelengths: MTF against the weighted sum of the circle's: largest "
                  "difference %.3g\n", worst);
    assert_true(worst < 0.002);
    sg_mtf_free(&m);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* The perfect system's PSF in three wavelengths: each wavelength's Airy
 * pattern carries unit energy times its weight, so its peak is
 * proportional to w / lambda^2; the sum is normalized to peak 1.  The FFT
 * PSF at N = 128, the Huygens PSF at N = 64. */
static void polychromatic_psf(void **state)
{
    const double f = 200.0, epd = 20.0;
    const double um[3] = { 0.4861327, 0.5875618, 0.6562725 }, wt[3] = { 1.0, 2.0, 0.5 };
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    sg_psf_opts o;
    sg_psf p;
    sg_diag d;
    double worst = 0.0, norm = 0.0;
    int i, w, c;
    (void)state;
    sys->nwave = 3;
    for (w = 0; w < 3; w++) {
        sys->wave[w].um = um[w];
        sys->wave[w].weight = wt[w];
        norm += wt[w] / (um[w] * um[w]);
    }
    sys->primary_wave = 1;
    sg_psf_opts_init(&o);
    o.sampling = 128;
    sg_diag_clear(&d);
    assert_int_equal(sg_psf_compute(sys, cat, &o, &p, &d), SG_OK);
    assert_true(fabs(p.spacing_x_um / (um[0] * f / epd * 127.0 / 256.0) - 1.0) < 1e-9);
    c = p.size / 2;
    for (i = 0; i <= 12; i++) {
        double r = i * p.spacing_x_um, want = 0.0;
        for (w = 0; w < 3; w++) {
            double v = PI * r / (um[w] * f / epd);
            want += wt[w] / (um[w] * um[w]) * (v == 0.0 ? 1.0 : pow(2.0 * j1(v) / v, 2));
        }
        want /= norm;
        worst = fmax(worst, fabs(p.psf[(size_t)c * p.size + c + i] - want));
        worst = fmax(worst, fabs(p.psf[(size_t)(c - i) * p.size + c] - want));
    }
    print_message("# three wavelengths: PSF against the weighted Airy patterns: largest "
                  "difference %.3g\n", worst);
    assert_true(worst < 0.003);
    assert_true(fabs(p.strehl - 1.0) < 1e-9);
    sg_psf_free(&p);
    o.sampling = 64;
    o.method = SG_PSF_HUYGENS;
    assert_int_equal(sg_psf_compute(sys, cat, &o, &p, &d), SG_OK);
    c = p.size / 2;
    worst = 0.0;
    for (i = 0; i < c; i++) {
        double r = i * p.spacing_x_um, want = 0.0;
        for (w = 0; w < 3; w++) {
            double v = PI * r / (um[w] * f / epd);
            want += wt[w] / (um[w] * um[w]) * (v == 0.0 ? 1.0 : pow(2.0 * j1(v) / v, 2));
        }
        want /= norm;
        worst = fmax(worst, fabs(p.psf[(size_t)c * p.size + c + i] - want));
    }
    print_message("# three wavelengths: Huygens PSF against the weighted Airy patterns: "
                  "largest difference %.3g\n", worst);
    assert_true(worst < 0.005);
    sg_psf_free(&p);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* The defocused paraboloid's OPD in waves at pupil radius rho (0 to 1). */
static double defocus_w(double f, double epd, double dz, double lambda_mm, double rho)
{
    double h = rho * epd / 2, th = 2.0 * atan(h / (2.0 * f)), s;
    s = -dz * cos(th) + sqrt((f + dz) * (f + dz) - dz * dz * sin(th) * sin(th));
    return (s - f) / lambda_mm;
}

static void defocus_strehl(void **state)
{
    /* 20-point Gauss-Legendre on [-1, 1], composite over 50 panels of [0, 1]. */
    static const double gx[10] = { 0.0765265211334973, 0.2277858511416451, 0.3737060887154195,
                                   0.5108670019508271, 0.6360536807265150, 0.7463319064601508,
                                   0.8391169718222188, 0.9122344282513259, 0.9639719272779138,
                                   0.9931285991850949 };
    static const double gw[10] = { 0.1527533871307258, 0.1491729864726037, 0.1420961093183820,
                                   0.1316886384491766, 0.1181945319615184, 0.1019301198172404,
                                   0.0832767415767048, 0.0626720483341091, 0.0406014298003869,
                                   0.0176140071391521 };
    const double f = 200.0, epd = 20.0, w020s[3] = { 0.1, 0.5, 0.8 };
    sg_catalog *cat = tu_catalog();
    int t;
    (void)state;
    for (t = 0; t < 3; t++) {
        double lambda_mm = 0.5875618e-3, F = f / epd, dz = 8.0 * w020s[t] * lambda_mm * F * F;
        sg_system *sys = paraboloid(f, epd, dz);
        double complex sum = 0.0;
        double want, w020, sinc, strehl_int;
        sg_psf_opts o;
        sg_psf p;
        sg_diag d;
        int k, q;
        assert_true(fabs(sys->wave[0].um * 1e-3 - lambda_mm) < 1e-15);
        for (k = 0; k < 50; k++)
            for (q = 0; q < 20; q++) {
                double x = q < 10 ? -gx[q] : gx[q - 10], wq = gw[q < 10 ? q : q - 10];
                double rho = (k + 0.5 + 0.5 * x) / 50.0;
                double W = defocus_w(f, epd, dz, lambda_mm, rho);
                sum += wq * 0.5 / 50.0 * 2.0 * rho * cexp(I * 2.0 * PI * W);
            }
        strehl_int = creal(sum) * creal(sum) + cimag(sum) * cimag(sum);
        w020 = fabs(defocus_w(f, epd, dz, lambda_mm, 1.0));
        sinc = pow(sin(PI * w020) / (PI * w020), 2);
        sg_psf_opts_init(&o);
        o.sampling = 256;
        sg_diag_clear(&d);
        assert_int_equal(sg_psf_compute(sys, cat, &o, &p, &d), SG_OK);
        want = strehl_int;
        print_message("# defocus W020 %.4f waves: Strehl %.6f (exact mean %.6f), integral "
                      "%.6f, (sin(pi W020)/(pi W020))^2 %.6f\n", w020, p.strehl, p.strehl_exact,
                      strehl_int, sinc);
        /* The two definitions are one number at the chief ray's point. */
        assert_true(fabs(p.strehl - p.strehl_exact) < 1e-9);
        assert_true(fabs(p.strehl - want) < 1.5e-3);
        assert_true(fabs(want - sinc) < 1e-3);
        sg_psf_free(&p);
        if (t == 1) {
            /* The diffraction limit is the same pupil unaberrated. */
            sg_mtf_opts mo;
            sg_mtf m;
            double nuc = 1.0 / (lambda_mm * F), worst = 0.0;
            int j;
            sg_mtf_opts_init(&mo);
            mo.sampling = 128;
            assert_int_equal(sg_mtf_compute(sys, cat, &mo, &m, &d), SG_OK);
            for (j = 0; j < m.npts; j++)
                worst = fmax(worst, fabs(m.dl[j] - mtf_circle(m.freq[j] / nuc)));
            assert_true(worst < 0.002);
            /* Half a wave of defocus: at half the cutoff the MTF is well below it. */
            assert_true(m.tan[m.npts / 2] < m.dl[m.npts / 2] - 0.1);
            assert_true(fabs(m.tan[m.npts / 2] - m.sag[m.npts / 2]) < 1e-6);
            sg_mtf_free(&m);
        }
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

/* 20-point Gauss-Legendre on [-1, 1]: the positive nodes and weights. */
static const double GX[10] = { 0.0765265211334973, 0.2277858511416451, 0.3737060887154195,
                               0.5108670019508271, 0.6360536807265150, 0.7463319064601508,
                               0.8391169718222188, 0.9122344282513259, 0.9639719272779138,
                               0.9931285991850949 };
static const double GW[10] = { 0.1527533871307258, 0.1491729864726037, 0.1420961093183820,
                               0.1316886384491766, 0.1181945319615184, 0.1019301198172404,
                               0.0832767415767048, 0.0626720483341091, 0.0406014298003869,
                               0.0176140071391521 };

/* int_a^b g by 20-point Gauss-Legendre over np panels. */
static double gl_int(double (*g)(double, const double *), const double *par, double a,
                     double b, int np)
{
    double s = 0.0, h = (b - a) / np;
    int k, q;
    for (k = 0; k < np; k++)
        for (q = 0; q < 20; q++) {
            double x = q < 10 ? -GX[q] : GX[q - 10], w = GW[q < 10 ? q : q - 10];
            s += w * 0.5 * h * g(a + h * (k + 0.5 + 0.5 * x), par);
        }
    return s;
}

static double j1j1_over_t(double t, const double *eps)
{
    return t == 0.0 ? 0.0 : j1(t) * j1(*eps * t) / t;
}

/* The encircled energy of an annular pupil, outer radius 1 and inner eps,
 * within v = pi r / (lambda F#) (Mahajan, JOSA 1986, 3, 470, eq. 16):
 *   [1 - J0^2(v) - J1^2(v) + eps^2 (1 - J0^2(eps v) - J1^2(eps v))
 *    - 4 eps int_0^v J1(t) J1(eps t) / t dt] / (1 - eps^2);
 * eps 0 is Rayleigh's 1 - J0^2 - J1^2. */
static double ee_annulus(double v, double eps)
{
    double e = 1.0 - j0(v) * j0(v) - j1(v) * j1(v);
    if (eps == 0.0)
        return e;
    e += eps * eps * (1.0 - j0(eps * v) * j0(eps * v) - j1(eps * v) * j1(eps * v));
    e -= 4.0 * eps * gl_int(j1j1_over_t, &eps, 0.0, v, 40);
    return e / (1.0 - eps * eps);
}

/* The perfect paraboloid and the same with a central obscuration of eps
 * (an annular stop): the diffraction and limit curves against Mahajan's
 * closed form; the circle's at its first two dark rings, 0.838 and 0.910. */
static void encircled_airy(void **state)
{
    const double f = 200.0, epd = 20.0, epss[2] = { 0.0, 0.4 };
    sg_catalog *cat = tu_catalog();
    int t, j;
    (void)state;
    for (t = 0; t < 2; t++) {
        sg_system *sys = paraboloid(f, epd, 0.0);
        double lf = sys->wave[0].um * f / epd, worst = 0.0, v;
        sg_ee_opts o;
        sg_ee e;
        sg_diag d;
        if (epss[t] > 0.0) {
            sys->surf[1].aperture = SG_APERTURE_CIRCULAR;
            sys->surf[1].ap_rmin = epss[t] * epd / 2;
            sys->surf[1].ap_rmax = epd;
        }
        sg_ee_opts_init(&o);
        o.sampling = 128;
        o.max_radius_um = 8.0 * lf;
        o.npts = 81;
        sg_diag_clear(&d);
        assert_int_equal(sg_ee_compute(sys, cat, &o, &e, &d), SG_OK);
        assert_int_equal(e.nfield, 1);
        assert_int_equal(e.npts, 81);
        assert_true(fabs(e.radius_um[80] - 8.0 * lf) < 1e-9 * lf);
        for (j = 0; j < e.npts; j++) {
            double want = ee_annulus(PI * e.radius_um[j] / lf, epss[t]);
            worst = fmax(worst, fabs(e.diffraction[j] - want));
            worst = fmax(worst, fabs(e.limit[j] - want));
        }
        print_message("# encircled energy, obscuration %g, sampling 128: largest difference "
                      "from Mahajan's closed form %.3g\n", epss[t], worst);
        assert_true(worst < 0.003);
        sg_ee_free(&e);
        if (t == 0) {
            /* The first and second dark rings exactly: 0.838 and 0.910. */
            const double vz[2] = { 3.8317059702075123, 7.0155866698156188 };
            const double ez[2] = { 0.838, 0.910 };
            for (j = 0; j < 2; j++) {
                v = vz[j];
                o.max_radius_um = v * lf / PI;
                o.npts = 2;
                assert_int_equal(sg_ee_compute(sys, cat, &o, &e, &d), SG_OK);
                print_message("# ring %d: %.5f\n", j + 1, e.diffraction[1]);
                assert_true(fabs(e.diffraction[1] - ez[j]) < 0.002);
                assert_true(fabs(e.diffraction[0]) < 1e-12);
                sg_ee_free(&e);
            }
        }
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

/* The Airy pattern's energy in a square of half-width a, by quadrature of
 * (2 J1(v) / v)^2 over [0, a]^2 (four quadrants), over its total
 * 4 (lambda F#)^2 / pi. */
static double airy_sq_row(double x, const double *par)
{
    double y = par[1], v = PI * hypot(x, y) / par[0];
    return v == 0.0 ? 1.0 : pow(2.0 * j1(v) / v, 2);
}

static double airy_sq_col(double y, const double *par)
{
    double p2[2] = { par[0], y };
    return gl_int(airy_sq_row, p2, 0.0, par[1], 12);
}

static void ensquared_airy(void **state)
{
    const double f = 200.0, epd = 20.0;
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    double lf = sys->wave[0].um * f / epd, worst = 0.0;
    sg_ee_opts o;
    sg_ee e;
    sg_diag d;
    int j;
    (void)state;
    sg_ee_opts_init(&o);
    o.sampling = 128;
    o.kind = SG_EE_ENSQUARED;
    o.max_radius_um = 4.0 * lf;
    o.npts = 9;
    sg_diag_clear(&d);
    assert_int_equal(sg_ee_compute(sys, cat, &o, &e, &d), SG_OK);
    for (j = 0; j < e.npts; j++) {
        double par[2] = { lf, e.radius_um[j] };
        double want = 4.0 * gl_int(airy_sq_col, par, 0.0, e.radius_um[j], 12) /
                      (4.0 * lf * lf / PI);
        worst = fmax(worst, fabs(e.diffraction[j] - want));
    }
    print_message("# ensquared energy against the Airy pattern's quadrature: largest "
                  "difference %.3g\n", worst);
    assert_true(worst < 0.003);
    sg_ee_free(&e);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* Three wavelengths: the perfect system's curve is the weighted sum of
 * each wavelength's Airy energy. */
static void encircled_polychromatic(void **state)
{
    const double f = 200.0, epd = 20.0;
    const double um[3] = { 0.4861327, 0.5875618, 0.6562725 }, wt[3] = { 1.0, 2.0, 0.5 };
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    double worst = 0.0;
    sg_ee_opts o;
    sg_ee e;
    sg_diag d;
    int j, w;
    (void)state;
    sys->nwave = 3;
    for (w = 0; w < 3; w++) {
        sys->wave[w].um = um[w];
        sys->wave[w].weight = wt[w];
    }
    sys->primary_wave = 1;
    sg_ee_opts_init(&o);
    o.sampling = 128;
    o.npts = 41;
    sg_diag_clear(&d);
    assert_int_equal(sg_ee_compute(sys, cat, &o, &e, &d), SG_OK);
    /* Automatic: five rings of the longest wavelength (the rays meet at a point). */
    assert_true(fabs(e.radius_um[40] - 5.0 * um[2] * f / epd) < 1e-9);
    for (j = 0; j < e.npts; j++) {
        double want = 0.0;
        for (w = 0; w < 3; w++)
            want += wt[w] * ee_annulus(PI * e.radius_um[j] / (um[w] * f / epd), 0.0);
        want /= wt[0] + wt[1] + wt[2];
        worst = fmax(worst, fabs(e.diffraction[j] - want));
    }
    print_message("# three wavelengths: encircled energy against the weighted Airy sum: "
                  "largest difference %.3g\n", worst);
    assert_true(worst < 0.003);
    sg_ee_free(&e);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* The paraboloid's image dz beyond its focus: the ray at pupil height h
 * crosses it at r = h dz / (f - h^2 / 4f) (the mirror's point lies
 * h^2 / 4f nearer the focus), so the rays within r are those within
 *   h(r) = 2 f (sqrt(dz^2 + r^2) - dz) / r
 * and a uniform grid of rays puts (h(r) / H)^2 of them there. */
static void encircled_geometric_disc(void **state)
{
    const double f = 200.0, epd = 20.0, dz = 2.0;
    sg_system *sys = paraboloid(f, epd, dz);
    sg_catalog *cat = tu_catalog();
    double worst = 0.0, rdisc = (epd / 2) * dz / (f - (epd / 2) * (epd / 2) / (4.0 * f)) * 1e3;
    sg_ee_opts o;
    sg_ee e;
    sg_diag d;
    int j;
    (void)state;
    sg_ee_opts_init(&o);
    o.sampling = 64;
    o.rays = 400;
    o.max_radius_um = 1.2 * rdisc;
    o.npts = 61;
    sg_diag_clear(&d);
    assert_int_equal(sg_ee_compute(sys, cat, &o, &e, &d), SG_OK);
    for (j = 1; j < e.npts; j++) {
        double r = e.radius_um[j] * 1e-3, h = 2.0 * f * (sqrt(dz * dz + r * r) - dz) / r;
        double want = fmin(1.0, pow(h / (epd / 2), 2));
        worst = fmax(worst, fabs(e.geometric[j] - want));
    }
    print_message("# defocused paraboloid, %d x %d rays: geometric encircled energy against "
                  "the disc's: largest difference %.3g\n", o.rays, o.rays, worst);
    assert_true(worst < 0.002);
    assert_true(e.geometric[0] < 1e-3);
    assert_true(fabs(e.geometric[e.npts - 1] - 1.0) < 1e-12);
    /* About 8.5 waves of defocus: diffraction's curve is near the rays';
     * the limit is still Airy's. */
    worst = 0.0;
    for (j = 0; j < e.npts; j++) {
        double lf = sys->wave[0].um * f / epd;
        assert_true(fabs(e.diffraction[j] - e.geometric[j]) < 0.1);
        worst = fmax(worst, fabs(e.limit[j] - ee_annulus(PI * e.radius_um[j] / lf, 0.0)));
    }
    assert_true(worst < 0.003);
    sg_ee_free(&e);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* The area common to two circles of radii a and b, centres s apart. */
static double lens_area(double a, double b, double s)
{
    double ca, cb;
    if (s >= a + b)
        return 0.0;
    if (s <= fabs(a - b))
        return PI * fmin(a, b) * fmin(a, b);
    ca = acos((s * s + a * a - b * b) / (2.0 * s * a));
    cb = acos((s * s + b * b - a * a) / (2.0 * s * b));
    return a * a * (ca - cos(ca) * sin(ca)) + b * b * (cb - cos(cb) * sin(cb));
}

/* The MTF of an annulus of radii eps and 1 at nu / nu_c = x: the area
 * common to it and its copy shifted by 2x, over its area (the overlap of
 * annuli from those of the circles: outer-outer, less twice outer-inner,
 * plus inner-inner). */
static double mtf_annulus(double x, double eps)
{
    double s = 2.0 * x;
    return (lens_area(1.0, 1.0, s) - 2.0 * lens_area(1.0, eps, s) + lens_area(eps, eps, s)) /
           (PI * (1.0 - eps * eps));
}

/* The paraboloid with a central obscuration of eps on its stop: the MTF,
 * tangential, sagittal and the diffraction limit, is the annulus's; the
 * PSF is the annular Airy pattern
 *   ((2 J1(v) / v - eps^2 2 J1(eps v) / (eps v)) / (1 - eps^2))^2,
 * peak and Strehl ratio 1; defocused by W020 waves (edge), the Strehl
 * ratio is (sin(pi W020 (1 - eps^2)) / (pi W020 (1 - eps^2)))^2, the
 * mean of exp(i 2 pi W020 u) over u = rho^2 from eps^2 to 1. */
static void annular_pupil(void **state)
{
    const double f = 200.0, epd = 20.0, eps = 0.4;
    sg_catalog *cat = tu_catalog();
    sg_mtf_opts mo;
    sg_mtf m;
    sg_psf_opts po;
    sg_psf p;
    sg_diag d;
    double nuc, lf, worst = 0.0;
    int i, j, t, c;
    (void)state;
    for (t = 0; t < 2; t++) {
        double lambda_mm = 0.5875618e-3, F = f / epd, w020 = 0.3;
        double dz = t ? 8.0 * w020 * lambda_mm * F * F : 0.0;
        sg_system *sys = paraboloid(f, epd, dz);
        sys->surf[1].aperture = SG_APERTURE_CIRCULAR;
        sys->surf[1].ap_rmin = eps * epd / 2;
        sys->surf[1].ap_rmax = epd;
        nuc = 1.0 / (lambda_mm * F);
        lf = sys->wave[0].um * F;
        sg_diag_clear(&d);
        sg_psf_opts_init(&po);
        po.sampling = 128;
        assert_int_equal(sg_psf_compute(sys, cat, &po, &p, &d), SG_OK);
        if (t == 0) {
            sg_mtf_opts_init(&mo);
            mo.sampling = 128;
            assert_int_equal(sg_mtf_compute(sys, cat, &mo, &m, &d), SG_OK);
            for (j = 0; j < m.npts; j++) {
                double want = mtf_annulus(m.freq[j] / nuc, eps);
                worst = fmax(worst, fabs(m.tan[j] - want));
                worst = fmax(worst, fabs(m.sag[j] - want));
                worst = fmax(worst, fabs(m.dl[j] - want));
            }
            print_message("# annulus eps %g: MTF against the overlap of annuli: largest "
                          "difference %.3g\n", eps, worst);
            assert_true(worst < 0.003);
            /* Not the full circle's: the annulus lifts high frequencies. */
            assert_true(m.tan[3 * m.npts / 4] > mtf_circle(0.75) + 0.02);
            sg_mtf_free(&m);
            assert_true(fabs(p.strehl - 1.0) < 1e-9 && fabs(p.peak - 1.0) < 1e-9);
            worst = 0.0;
            c = p.size / 2;
            for (j = -12; j <= 12; j++)
                for (i = -12; i <= 12; i++) {
                    double r = hypot(i * p.spacing_x_um, j * p.spacing_y_um), v = PI * r / lf;
                    double a = v == 0.0 ? 1.0 - eps * eps
                                        : 2.0 * j1(v) / v - 2.0 * eps * j1(eps * v) / v;
                    double want = pow(a / (1.0 - eps * eps), 2);
                    worst = fmax(worst, fabs(p.psf[(size_t)(c + j) * p.size + c + i] - want));
                }
            print_message("# annulus eps %g: PSF against the annular Airy pattern: largest "
                          "difference %.3g\n", eps, worst);
            assert_true(worst < 0.003);
        } else {
            double w = fabs(defocus_w(f, epd, dz, lambda_mm, 1.0)) -
                       fabs(defocus_w(f, epd, dz, lambda_mm, 0.0));
            double x = PI * w * (1.0 - eps * eps), want = pow(sin(x) / x, 2);
            print_message("# annulus eps %g, defocus %.4f waves: Strehl %.6f, closed form "
                          "%.6f\n", eps, w, p.strehl, want);
            assert_true(fabs(p.strehl - p.strehl_exact) < 1e-9);
            assert_true(fabs(p.strehl - want) < 2e-3);
        }
        sg_psf_free(&p);
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

/* The Huygens PSF: on the perfect paraboloid, Airy's pattern; defocused by
 * W020 = 0.5 and 1.5 waves, the FFT PSF's values at the same points (the
 * Huygens grid defaults to the FFT's spacing) and the Strehl ratio of the
 * integral (defocus_strehl).  The two differ by the Fraunhofer
 * approximation the FFT makes and the sampling: at F/10 well under 1% of
 * the peak. */
static void huygens_psf(void **state)
{
    const double f = 200.0, epd = 20.0, w020s[3] = { 0.0, 0.5, 1.5 };
    sg_catalog *cat = tu_catalog();
    int t;
    (void)state;
    for (t = 0; t < 3; t++) {
        double lambda_mm = 0.5875618e-3, F = f / epd, dz = 8.0 * w020s[t] * lambda_mm * F * F;
        double lf = lambda_mm * 1e3 * F, worst = 0.0, wfft = 0.0;
        sg_system *sys = paraboloid(f, epd, dz);
        sg_psf_opts o;
        sg_psf h, p;
        sg_diag d;
        int i, j, ch, cp;
        sg_psf_opts_init(&o);
        o.sampling = 64;
        sg_diag_clear(&d);
        assert_int_equal(sg_psf_compute(sys, cat, &o, &p, &d), SG_OK);
        o.method = SG_PSF_HUYGENS;
        assert_int_equal(sg_psf_compute(sys, cat, &o, &h, &d), SG_OK);
        assert_int_equal(h.size, 64);
        assert_true(fabs(h.spacing_x_um - p.spacing_x_um) < 1e-12);
        ch = h.size / 2;
        cp = p.size / 2;
        for (j = -ch; j < ch; j++)
            for (i = -ch; i < ch; i++) {
                double v = PI * hypot(i, j) * h.spacing_x_um / lf;
                double hv = h.psf[(size_t)(ch + j) * h.size + ch + i];
                wfft = fmax(wfft, fabs(hv - p.psf[(size_t)(cp + j) * p.size + cp + i]));
                if (t == 0)
                    worst = fmax(worst, fabs(hv - (v == 0.0 ? 1.0 : pow(2.0 * j1(v) / v, 2))));
            }
        print_message("# Huygens PSF, defocus %.1f waves: largest difference from the FFT PSF "
                      "%.3g, from Airy %.3g; Strehl %.6f (FFT %.6f)\n", w020s[t], wfft, worst,
                      h.strehl, p.strehl);
        assert_true(wfft < 0.005);
        assert_true(fabs(h.strehl - p.strehl) < 0.002);
        assert_true(fabs(h.strehl_exact - p.strehl_exact) < 1e-12);
        if (t == 0)
            assert_true(worst < 0.005 && fabs(h.strehl - 1.0) < 1e-9);
        sg_psf_free(&h);
        sg_psf_free(&p);
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

/* An off-axis field of the paraboloid has coma: the Huygens and FFT PSFs
 * agree point for point (so neither is turned over), and the PSF's first
 * moment about the chief ray's point is the rays' centroid (the mean
 * transverse aberration: the mean wavefront slope, for a uniform pupil). */
static void huygens_coma(void **state)
{
    const double f = 200.0, epd = 20.0;
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    sg_psf_opts o;
    sg_psf h, p;
    sg_spot_opts so;
    sg_spot sp;
    sg_diag d;
    double wfft = 0.0, m0 = 0.0, my = 0.0, mx = 0.0, ray_y;
    int i, j, ch, cp;
    (void)state;
    sys->nfield = 1;
    sys->field[0].y = 0.5;
    sg_psf_opts_init(&o);
    o.sampling = 64;
    sg_diag_clear(&d);
    assert_int_equal(sg_psf_compute(sys, cat, &o, &p, &d), SG_OK);
    o.method = SG_PSF_HUYGENS;
    assert_int_equal(sg_psf_compute(sys, cat, &o, &h, &d), SG_OK);
    ch = h.size / 2;
    cp = p.size / 2;
    for (j = -ch; j < ch; j++)
        for (i = -ch; i < ch; i++) {
            double hv = h.psf[(size_t)(ch + j) * h.size + ch + i];
            wfft = fmax(wfft, fabs(hv - p.psf[(size_t)(cp + j) * p.size + cp + i]));
        }
    for (j = -cp; j < cp; j++)
        for (i = -cp; i < cp; i++) {
            double v = p.psf[(size_t)(cp + j) * p.size + cp + i];
            m0 += v;
            mx += v * i * p.spacing_x_um;
            my += v * j * p.spacing_y_um;
        }
    sg_spot_opts_init(&so);
    so.pattern = SG_PUPIL_SQUARE;
    so.density = 200;
    sg_spot_compute(sys, cat, &so, &sp, &d);
    ray_y = (sp.cell[0].centroid_y - sp.cell[0].chief_y) * 1e3;
    print_message("# coma (field 0.5 deg): Huygens against FFT: largest difference %.3g; Strehl "
                  "%.4f; FFT PSF centroid (%.4g, %.4g) um, rays' centroid %.4g um\n", wfft,
                  p.strehl, mx / m0, my / m0, ray_y);
    assert_true(p.strehl < 0.97);
    assert_true(wfft < 0.005);
    assert_true(fabs(my / m0 - ray_y) < 0.05 * fabs(ray_y));
    assert_true(fabs(mx / m0) < 1e-9);
    sg_spot_free(&sp);
    sg_psf_free(&h);
    sg_psf_free(&p);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* sqrt(R^2 - x^2) cos(2 pi nu x), par = (R, nu). */
static double strip_cos(double x, const double *par)
{
    return sqrt(par[0] * par[0] - x * x) * cos(2.0 * PI * par[1] * x);
}

/* The geometric MTF of the paraboloid 2 mm beyond its focus: the rays
 * fill a disc of diameter D (nearly uniformly: the mapping r(h) of
 * encircled_geometric_disc departs from a straight line by h^2 / 4f^2,
 * 6e-4), whose transform is 2 J1(pi D nu) / (pi D nu), tangential and
 * sagittal alike.  With 8.5 waves of defocus the FFT MTF approaches it at
 * low frequencies, as geometrical optics is the limit of diffraction for
 * large aberrations (to 0.053 below 1.5 / D here). */
/* The Huygens MTF (the Huygens PSF's transform), from closed forms:
 * the perfect paraboloid's is the circle's, 2/pi (phi - cos phi sin phi);
 * with 4.25 waves of defocus its low frequencies are the blur disc's
 * |2 J1(pi D nu) / (pi D nu)|, as the FFT MTF's are (geometric_mtf_defocus);
 * a frequency past the image grid's Nyquist frequency is refused. */
static void huygens_mtf(void **state)
{
    const double f = 200.0, epd = 20.0, dz = 2.0;
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    double lambda_mm = sys->wave[0].um * 1e-3, nuc = 1.0 / (lambda_mm * f / epd);
    double D = 2.0 * (epd / 2) * dz / (f - (epd / 2) * (epd / 2) / (4.0 * f));
    double worst = 0.0, low = 0.0;
    sg_mtf_opts o;
    sg_mtf m;
    sg_diag d;
    int j;
    (void)state;
    sg_mtf_opts_init(&o);
    o.sampling = 64;
    o.method = SG_MTF_HUYGENS;
    o.image_size = 128;
    sg_diag_clear(&d);
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    assert_int_equal(m.method, SG_MTF_HUYGENS);
    assert_int_equal(m.image_size, 128);
    for (j = 0; j < m.npts; j++) {
        double want = mtf_circle(m.freq[j] / nuc);
        worst = fmax(worst, fabs(m.tan[j] - want));
        worst = fmax(worst, fabs(m.sag[j] - want));
    }
    print_message("# Huygens MTF, perfect F/%g, 64 x 64 pupil onto 128 x 128 image points "
                  "%.4g um apart: largest difference from the circle's %.3g\n", f / epd,
                  m.image_delta_um, worst);
    /* The image grid holds the Airy pattern to about 31 lambda F# on each
     * side; the energy beyond (about 1 / (pi^2 31), 0.003) and the pupil
     * grid's disk (0.002, perfect_mtf) set the error. */
    assert_true(worst < 0.006);
    assert_int_equal(d.nwarn, 0);
    sg_mtf_free(&m);

    /* Refused: a 3 um grid samples up to 166.67 cycles/mm, just below the
     * cutoff 1 / (lambda F#) = 170.2. */
    o.image_size = 0;
    o.image_delta_um = 3.0;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "samples frequencies up to 166.667 cycles/mm"));
    /* 2.9 um samples 172.4: answered. */
    o.image_delta_um = 2.9;
    o.image_size = 32;
    o.sampling = 32;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    sg_mtf_free(&m);
    o.sampling = 64;
    sg_system_free(sys);

    sys = paraboloid(f, epd, dz);
    sg_diag_clear(&d);
    o.sampling = 96;
    o.image_size = 128;
    o.image_delta_um = 4.0;
    o.max_frequency = 1.5 / D;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    for (j = 0; j < m.npts; j++) {
        double x = PI * D * m.freq[j], want = x == 0.0 ? 1.0 : fabs(2.0 * j1(x) / x);
        low = fmax(low, fabs(m.tan[j] - want));
        low = fmax(low, fabs(m.sag[j] - want));
    }
    print_message("# Huygens MTF, %.4g mm blur disc, below 1.5 / D: largest difference from "
                  "|2 J1(pi D nu) / (pi D nu)| %.3g\n", D, low);
    assert_true(low < 0.06);
    if (d.nwarn)
        print_message("# warning: %s\n", d.warn[0]);
    assert_int_equal(d.nwarn, 0);
    sg_mtf_free(&m);
    /* A grid 128 um wide cuts the 200 um disc: said, not hidden. */
    o.image_size = 32;
    sg_diag_clear(&d);
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    assert_true(d.nwarn >= 1);
    assert_non_null(strstr(d.warn[d.nwarn - 1], "reaches the edge of its 32 x 32 image grid"));
    sg_mtf_free(&m);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

static void geometric_mtf_defocus(void **state)
{
    const double f = 200.0, epd = 20.0, dz = 2.0;
    sg_system *sys = paraboloid(f, epd, dz);
    sg_catalog *cat = tu_catalog();
    double D = 2.0 * (epd / 2) * dz / (f - (epd / 2) * (epd / 2) / (4.0 * f)), worst = 0.0;
    double low = 0.0;
    sg_mtf_opts o;
    sg_mtf g, m;
    sg_diag d;
    int j;
    (void)state;
    sg_mtf_opts_init(&o);
    o.sampling = 256;
    o.max_frequency = 6.0 / D;
    o.method = SG_MTF_GEOMETRIC;
    sg_diag_clear(&d);
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &g, &d), SG_OK);
    for (j = 0; j < g.npts; j++) {
        double x = PI * D * g.freq[j], want = x == 0.0 ? 1.0 : fabs(2.0 * j1(x) / x);
        worst = fmax(worst, fabs(g.tan[j] - want));
        worst = fmax(worst, fabs(g.sag[j] - want));
    }
    print_message("# geometric MTF, a %.4g mm blur disc, 256 x 256 rays: largest difference "
                  "from |2 J1(pi D nu) / (pi D nu)| %.3g\n", D, worst);
    assert_true(worst < 0.005);
    /* The diffraction limit is still the circle's. */
    assert_true(fabs(g.dl[1] - mtf_circle(g.freq[1] / g.cutoff)) < 0.002);
    sg_mtf_free(&g);
    /* Three weighted wavelengths: a mirror's rays are the same in each, so
     * the weighted sum is the same disc's MTF. */
    sys->nwave = 3;
    sys->wave[1].um = 0.4861327;
    sys->wave[2].um = 0.6562725;
    sys->wave[0].weight = 1.0;
    sys->wave[1].weight = 2.0;
    sys->wave[2].weight = 0.5;
    o.sampling = 64;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &g, &d), SG_OK);
    for (j = 0; j < g.npts; j += 8) {
        double x = PI * D * g.freq[j], want = x == 0.0 ? 1.0 : fabs(2.0 * j1(x) / x);
        assert_true(fabs(g.tan[j] - want) < 0.01);
    }
    sys->nwave = 1;
    o.method = SG_MTF_FFT;
    o.sampling = 128;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_OK);
    for (j = 0; j < m.npts && m.freq[j] < 1.5 / D; j++) {
        double x = PI * D * m.freq[j], want = x == 0.0 ? 1.0 : fabs(2.0 * j1(x) / x);
        low = fmax(low, fabs(m.tan[j] - want));
    }
    print_message("# the FFT MTF below 1.5 / D against the disc's: largest difference %.3g\n",
                  low);
    assert_true(low < 0.06);
    sg_mtf_free(&m);
    sg_mtf_free(&g);
    /* A slit |x| <= a quarter of the pupil on the stop: the rays fill the
     * disc's strip |x| <= D/4, so the sagittal MTF is the transform of the
     * strip's width sqrt(R^2 - x^2) (R = D/2) over |x| <= R/2, by
     * quadrature, and the tangential one is another curve. */
    sys->surf[1].aperture = SG_APERTURE_RECTANGULAR;
    sys->surf[1].ap_xhalf = epd / 4;
    sys->surf[1].ap_yhalf = epd;
    o.method = SG_MTF_GEOMETRIC;
    o.sampling = 256;
    o.max_frequency = 12.0 / D;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &g, &d), SG_OK);
    worst = 0.0;
    low = 0.0;
    for (j = 0; j < g.npts; j += 5) {
        double par[2] = { D / 2, g.freq[j] };
        double want = fabs(gl_int(strip_cos, par, 0.0, D / 4, 20) /
                           gl_int(strip_cos, (double[2]){ D / 2, 0.0 }, 0.0, D / 4, 20));
        worst = fmax(worst, fabs(g.sag[j] - want));
        low = fmax(low, fabs(g.tan[j] - want));
    }
    print_message("# slit: geometric sagittal MTF against the strip's transform: largest "
                  "difference %.3g (tangential %.3g)\n", worst, low);
    assert_true(worst < 0.005);
    assert_true(low > 0.1);
    sg_mtf_free(&g);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* 2 h(x) cos(4 pi W020 s x), h the half height of two unit circles
 * shifted by s: par = (s, W020). */
static double defocus_otf_x(double x, const double *par)
{
    double s = par[0], u = fabs(x) + s / 2, h2 = 1.0 - u * u;
    return h2 <= 0.0 ? 0.0 : 2.0 * sqrt(h2) * cos(4.0 * PI * par[1] * s * x);
}

/* 2 rho cos and sin of 2 pi W(rho), W the paraboloid's exact defocus:
 * par = (f, epd, dz, lambda_mm). */
static double defocus_re(double rho, const double *par)
{
    return 2.0 * rho * cos(2.0 * PI * defocus_w(par[0], par[1], par[2], par[3], rho));
}

static double defocus_im(double rho, const double *par)
{
    return 2.0 * rho * sin(2.0 * PI * defocus_w(par[0], par[1], par[2], par[3], rho));
}

/* The through-focus MTF of the perfect paraboloid at half its cutoff:
 * with the image dz from focus the pupil has defocus W020 (its edge OPD,
 * from the exact geometry), and the OTF at nu = (s / 2) nu_c is Hopkins'
 *   (1 / pi) int over the overlap of the pupil and its copy shifted by s
 *   of exp(i 2 pi W020 ((x + s/2)^2 - (x - s/2)^2)) = (1 / pi) int 2 h(x)
 *   cos(4 pi W020 s x) dx,
 * by quadrature; the Strehl ratio is |int_0^1 exp(i 2 pi W(rho)) 2 rho
 * drho|^2 with the exact W, (sin(pi W020) / (pi W020))^2 to its rho^4
 * part. */
static void through_focus(void **state)
{
    const double f = 200.0, epd = 20.0;
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    double lambda_mm = sys->wave[0].um * 1e-3, F = f / epd, nuc = 1.0 / (lambda_mm * F);
    double worst = 0.0, ws = 0.0;
    sg_tf_opts o;
    sg_tf t;
    sg_diag d;
    int k;
    (void)state;
    sg_tf_opts_init(&o);
    o.mtf.sampling = 128;
    o.frequency = 0.5 * nuc;
    o.range = 8.0 * 1.0 * lambda_mm * F * F; /* one wave of W020 either side */
    o.steps = 9;
    sg_diag_clear(&d);
    assert_int_equal(sg_tf_compute(sys, cat, &o, &t, &d), SG_OK);
    assert_int_equal(t.nsteps, 9);
    assert_true(fabs(t.shift[0] + o.range) < 1e-15 && fabs(t.shift[8] - o.range) < 1e-15);
    for (k = 0; k < t.nsteps; k++) {
        double w020 = defocus_w(f, epd, t.shift[k], lambda_mm, 1.0);
        double par[2] = { 1.0, w020 }, lim = 1.0 - par[0] / 2;
        double want = fabs(gl_int(defocus_otf_x, par, -lim, lim, 40)) / PI;
        double q[4] = { f, epd, t.shift[k], lambda_mm };
        double re = gl_int(defocus_re, q, 0.0, 1.0, 20), im = gl_int(defocus_im, q, 0.0, 1.0, 20);
        double sinc = re * re + im * im;
        worst = fmax(worst, fabs(t.tan[k] - want));
        worst = fmax(worst, fabs(t.sag[k] - want));
        ws = fmax(ws, fabs(t.strehl[k] - sinc));
    }
    print_message("# through focus, +-1 wave of defocus at half the cutoff: MTF against "
                  "Hopkins' integral: largest difference %.3g; Strehl against the integral: "
                  "%.3g\n", worst, ws);
    assert_true(worst < 0.003);
    /* The grid's stair-stepped disc at N = 128 (defocus_strehl: 1.5e-3 at
     * 256). */
    assert_true(ws < 0.005);
    /* In focus it is the circle's. */
    assert_true(fabs(t.tan[4] - mtf_circle(0.5)) < 0.002);
    sg_tf_free(&t);
    o.steps = 1;
    assert_int_equal(sg_tf_compute(sys, cat, &o, &t, &d), SG_ERANGE);
    o.steps = 5;
    o.frequency = 0.0;
    assert_int_equal(sg_tf_compute(sys, cat, &o, &t, &d), SG_ERANGE);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* Several frequencies in one run: at each, Hopkins' integral as above,
 * with s = 2 nu / nu_c (0.25, 0.5 and 0.75 of the cutoff, asked for out
 * of order); the layout is [(field * nfreq + q) * nsteps + k]. */
static void through_focus_frequencies(void **state)
{
    const double f = 200.0, epd = 20.0, frac[3] = { 0.75, 0.25, 0.5 };
    sg_system *sys = paraboloid(f, epd, 0.0);
    sg_catalog *cat = tu_catalog();
    double lambda_mm = sys->wave[0].um * 1e-3, F = f / epd, nuc = 1.0 / (lambda_mm * F);
    double worst = 0.0;
    sg_tf_opts o;
    sg_tf t;
    sg_diag d;
    int k, q;
    (void)state;
    sg_tf_opts_init(&o);
    o.mtf.sampling = 128;
    o.nfrequency = 3;
    for (q = 0; q < 3; q++)
        o.frequencies[q] = frac[q] * nuc;
    o.range = 8.0 * 1.0 * lambda_mm * F * F;
    o.steps = 5;
    sg_diag_clear(&d);
    assert_int_equal(sg_tf_compute(sys, cat, &o, &t, &d), SG_OK);
    assert_int_equal(t.nfreq, 3);
    assert_int_equal(t.nfield, 1);
    for (q = 0; q < 3; q++) {
        assert_true(t.freq[q] == frac[q] * nuc);
        for (k = 0; k < t.nsteps; k++) {
            double w020 = defocus_w(f, epd, t.shift[k], lambda_mm, 1.0);
            double par[2] = { 2.0 * frac[q], w020 }, lim = 1.0 - par[0] / 2;
            double want = fabs(gl_int(defocus_otf_x, par, -lim, lim, 40)) / PI;
            size_t c = (size_t)q * t.nsteps + k;
            worst = fmax(worst, fabs(t.tan[c] - want));
            worst = fmax(worst, fabs(t.sag[c] - want));
        }
    }
    print_message("# through focus at 0.75, 0.25 and 0.5 of the cutoff in one run: MTF against "
                  "Hopkins' integral: largest difference %.3g\n", worst);
    assert_true(worst < 0.004);
    sg_tf_free(&t);
    /* Too many, and one that is not positive, are refused. */
    o.nfrequency = SG_TF_MAX_FREQS + 1;
    assert_int_equal(sg_tf_compute(sys, cat, &o, &t, &d), SG_ERANGE);
    o.nfrequency = 2;
    o.frequencies[1] = -1.0;
    sg_diag_clear(&d);
    assert_int_equal(sg_tf_compute(sys, cat, &o, &t, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "frequency -1"));
    sg_catalog_free(cat);
    sg_system_free(sys);
}

static void bad_input(void **state)
{
    sg_system *sys = paraboloid(200.0, 20.0, 0.0);
    sg_catalog *cat = tu_catalog();
    sg_mtf_opts o;
    sg_psf_opts po;
    sg_mtf m;
    sg_psf p;
    sg_diag d;
    (void)state;
    sg_mtf_opts_init(&o);
    o.sampling = 16;
    sg_diag_clear(&d);
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "sampling 16"));
    o.sampling = 32;
    o.max_frequency = NAN;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_ERANGE);
    o.max_frequency = 0.0;
    o.field = 3;
    sg_diag_clear(&d);
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "field 4"));
    sg_psf_opts_init(&po);
    po.sampling = 4096;
    assert_int_equal(sg_psf_compute(sys, cat, &po, &p, &d), SG_ERANGE);
    po.sampling = 32;
    po.wave = 2;
    sg_diag_clear(&d);
    assert_int_equal(sg_psf_compute(sys, cat, &po, &p, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "wavelength 3"));
    /* Huygens: the image grid's size and spacing are checked. */
    po.wave = -1;
    po.method = SG_PSF_HUYGENS;
    po.image_size = SG_PSF_IMAGE_MAX + 1;
    sg_diag_clear(&d);
    assert_int_equal(sg_psf_compute(sys, cat, &po, &p, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "image points"));
    po.image_size = 0;
    po.image_delta_um = NAN;
    assert_int_equal(sg_psf_compute(sys, cat, &po, &p, &d), SG_ERANGE);
    /* A grid that would run for hours is refused. */
    po.image_delta_um = 0.0;
    po.image_size = SG_PSF_IMAGE_MAX;
    po.sampling = 2048;
    sg_diag_clear(&d);
    assert_int_equal(sg_psf_compute(sys, cat, &po, &p, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "wavelets"));
    po.image_size = 0;
    po.sampling = 32;
    po.method = 7;
    assert_int_equal(sg_psf_compute(sys, cat, &po, &p, &d), SG_EINVAL);
    o.method = 5;
    o.field = -1;
    assert_int_equal(sg_mtf_compute(sys, cat, &o, &m, &d), SG_EINVAL);
    /* Encircled energy: radius, radii, rays and kind. */
    {
        sg_ee_opts eo;
        sg_ee e;
        sg_ee_opts_init(&eo);
        eo.max_radius_um = -1.0;
        sg_diag_clear(&d);
        assert_int_equal(sg_ee_compute(sys, cat, &eo, &e, &d), SG_ERANGE);
        eo.max_radius_um = 0.0;
        eo.npts = 1;
        assert_int_equal(sg_ee_compute(sys, cat, &eo, &e, &d), SG_ERANGE);
        eo.npts = 0;
        eo.kind = 9;
        assert_int_equal(sg_ee_compute(sys, cat, &eo, &e, &d), SG_EINVAL);
        eo.kind = SG_EE_ENCIRCLED;
        eo.max_radius_um = 1e5;
        sg_diag_clear(&d);
        assert_int_equal(sg_ee_compute(sys, cat, &eo, &e, &d), SG_ERANGE);
        assert_non_null(strstr(d.msg, "beyond half the PSF grid"));
        eo.max_radius_um = 0.0;
        eo.field = 2;
        sg_diag_clear(&d);
        assert_int_equal(sg_ee_compute(sys, cat, &eo, &e, &d), SG_ERANGE);
        assert_non_null(strstr(d.msg, "field 3"));
    }
    sg_catalog_free(cat);
    sg_system_free(sys);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(perfect_mtf),
        cmocka_unit_test(perfect_psf),
        cmocka_unit_test(compressed_pupil),
        cmocka_unit_test(slit_pupil),
        cmocka_unit_test(polychromatic_mtf),
        cmocka_unit_test(polychromatic_psf),
        cmocka_unit_test(defocus_strehl),
        cmocka_unit_test(annular_pupil),
        cmocka_unit_test(huygens_psf),
        cmocka_unit_test(huygens_coma),
        cmocka_unit_test(geometric_mtf_defocus),
        cmocka_unit_test(huygens_mtf),
        cmocka_unit_test(through_focus),
        cmocka_unit_test(through_focus_frequencies),
        cmocka_unit_test(encircled_airy),
        cmocka_unit_test(ensquared_airy),
        cmocka_unit_test(encircled_polychromatic),
        cmocka_unit_test(encircled_geometric_disc),
        cmocka_unit_test(bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
