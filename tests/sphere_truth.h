/* sphere_truth.h - the exact crossing of a line with the paper's sphere,
 * shared by the engine's Table 1 test and the verify experiment test. */
#ifndef SG_SPHERE_TRUTH_H
#define SG_SPHERE_TRUTH_H

/* The near-side crossing of S + t D with x^2 + y^2 + z^2 = 64, from the
 * double inputs exactly (MPFR, 400 bits): out = S + t D + (0, 0, dz),
 * each coordinate rounded once. */
void sphere64_hit(const double S[3], const double D[3], double dz, double out[3]);
/* The same, with lo = the exact value minus out (rounded), so that an
 * error can be measured against the unrounded crossing. */
void sphere64_hit_lo(const double S[3], const double D[3], double dz, double out[3],
                     double lo[3]);

#endif
