/* measure.c - see measure.h. */
#include "measure.h"

#include <math.h>
#include <mpfr.h>

double meas_coord_digits(double a, double b, double size)
{
    double e, d, den;
    if (a == b)
        return MEAS_DIGITS_CAP;
    e = fabs(a - b);
    den = fmax(fabs(b), MEAS_DIGITS_FLOOR * size);
    if (!(den > 0.0) || !isfinite(e))
        return 0.0;
    d = -log10(e / den);
    return d < 0.0 ? 0.0 : d > MEAS_DIGITS_CAP ? MEAS_DIGITS_CAP : d;
}

double meas_point_digits(const double a[3], const double b[3], double scale)
{
    double size = fmax(fabs(b[0]), fmax(fabs(b[1]), fabs(b[2]))), d = MEAS_DIGITS_CAP;
    int k;
    if (!(size > 0.0))
        size = scale;
    for (k = 0; k < 3; k++)
        d = fmin(d, meas_coord_digits(a[k], b[k], size));
    return d;
}

/* z - sag(x, y) at prec bits into out; 0 when outside the conic's domain.
 * The conic part is r^2 / (R + sgn(R) sqrt(R^2 - (1 + k) r^2)), which
 * needs no 1/R. */
static int resid_at(const sg_surface *s, double x, double y, double z, mpfr_prec_t prec,
                    mpfr_t out)
{
    mpfr_t r2, t, u;
    int ok = 1, k;
    mpfr_inits2(prec, r2, t, u, (mpfr_ptr)0);
    mpfr_set_d(t, x, MPFR_RNDN);
    mpfr_sqr(r2, t, MPFR_RNDN);
    mpfr_set_d(t, y, MPFR_RNDN);
    mpfr_sqr(t, t, MPFR_RNDN);
    mpfr_add(r2, r2, t, MPFR_RNDN);
    mpfr_set_d(out, z, MPFR_RNDN);
    if (isfinite(s->radius) && s->radius != 0.0) {
        mpfr_set_d(t, s->radius, MPFR_RNDN);
        mpfr_sqr(u, t, MPFR_RNDN);
        mpfr_set_d(t, s->conic, MPFR_RNDN);
        mpfr_add_ui(t, t, 1, MPFR_RNDN);
        mpfr_mul(t, t, r2, MPFR_RNDN);
        mpfr_sub(u, u, t, MPFR_RNDN);
        if (mpfr_sgn(u) < 0) {
            ok = 0;
        } else {
            mpfr_sqrt(u, u, MPFR_RNDN);
            if (s->radius < 0.0)
                mpfr_neg(u, u, MPFR_RNDN);
            mpfr_add_d(u, u, s->radius, MPFR_RNDN);
            mpfr_div(t, r2, u, MPFR_RNDN);
            mpfr_sub(out, out, t, MPFR_RNDN);
        }
    }
    if (ok && s->type == SG_SURF_EVENASPH) {
        mpfr_set_zero(t, 1);
        for (k = SG_NASPH - 1; k >= 0; k--) {
            mpfr_mul(t, t, r2, MPFR_RNDN);
            mpfr_add_d(t, t, s->asph[k], MPFR_RNDN);
        }
        mpfr_mul(t, t, r2, MPFR_RNDN);
        mpfr_sub(out, out, t, MPFR_RNDN);
    }
    mpfr_clears(r2, t, u, (mpfr_ptr)0);
    return ok;
}

double meas_residual(const sg_surface *s, double x, double y, double z)
{
    mpfr_prec_t prec = 128;
    double res = NAN;
    if (!isfinite(x) || !isfinite(y) || !isfinite(z))
        return NAN;
    /* A plane's residual is |z| exactly. */
    if ((!isfinite(s->radius) || s->radius == 0.0) && s->type != SG_SURF_EVENASPH)
        return fabs(z);
    /* The terms are at most about max(|x|, |y|, |z|)^2 / |R| and the
     * polynomial's; a result above 2^(60 - prec) of the largest is known
     * to 20 bits or more.  2^-2200 of it is below any double. */
    for (;;) {
        mpfr_t out;
        double big = fmax(fabs(z), fmax(fabs(x), fabs(y)));
        mpfr_init2(out, prec);
        if (!resid_at(s, x, y, z, prec, out)) {
            mpfr_clear(out);
            return NAN;
        }
        res = fabs(mpfr_get_d(out, MPFR_RNDN));
        mpfr_clear(out);
        if (res == 0.0 && prec >= 4400)
            return 0.0;
        if (prec >= 4400 || res > ldexp(fmax(big, 1e-300), 60 - (int)prec) ||
            (big == 0.0 && res == 0.0))
            return res;
        prec *= 2;
    }
}
