/* sphere_truth.c - see sphere_truth.h. */
#include <mpfr.h>

#include "sphere_truth.h"

void sphere64_hit(const double S[3], const double D[3], double dz, double out[3])
{
    double lo[3];
    sphere64_hit_lo(S, D, dz, out, lo);
}

void sphere64_hit_lo(const double S[3], const double D[3], double dz, double out[3],
                     double lo[3])
{
    mpfr_t a, b, c, t, u, disc;
    int k;
    mpfr_inits2(400, a, b, c, t, u, disc, (mpfr_ptr)0);
    /* |S + t D|^2 = 64: a t^2 + 2 b t + c = 0 */
    mpfr_set_zero(a, 1);
    mpfr_set_zero(b, 1);
    mpfr_set_si(c, -64, MPFR_RNDN);
    for (k = 0; k < 3; k++) {
        mpfr_set_d(t, D[k], MPFR_RNDN);
        mpfr_sqr(u, t, MPFR_RNDN);
        mpfr_add(a, a, u, MPFR_RNDN);
        mpfr_mul_d(u, t, S[k], MPFR_RNDN);
        mpfr_add(b, b, u, MPFR_RNDN);
        mpfr_set_d(t, S[k], MPFR_RNDN);
        mpfr_sqr(u, t, MPFR_RNDN);
        mpfr_add(c, c, u, MPFR_RNDN);
    }
    /* t = (-b - sqrt(b^2 - a c)) / a : the first crossing */
    mpfr_sqr(disc, b, MPFR_RNDN);
    mpfr_mul(u, a, c, MPFR_RNDN);
    mpfr_sub(disc, disc, u, MPFR_RNDN);
    mpfr_sqrt(disc, disc, MPFR_RNDN);
    mpfr_add(t, b, disc, MPFR_RNDN);
    mpfr_neg(t, t, MPFR_RNDN);
    mpfr_div(t, t, a, MPFR_RNDN);
    for (k = 0; k < 3; k++) {
        mpfr_mul_d(u, t, D[k], MPFR_RNDN);
        mpfr_add_d(u, u, S[k], MPFR_RNDN);
        if (k == 2)
            mpfr_add_d(u, u, dz, MPFR_RNDN);
        out[k] = mpfr_get_d(u, MPFR_RNDN);
        mpfr_sub_d(u, u, out[k], MPFR_RNDN);
        lo[k] = mpfr_get_d(u, MPFR_RNDN);
    }
    mpfr_clears(a, b, c, t, u, disc, (mpfr_ptr)0);
}
