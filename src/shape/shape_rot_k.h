/*
 * shape_rot_k.h - the rotational part in double (the conic with even and
 * odd terms: shape.c's sg_rot_d, shape_vd.h's sv_rot_d) and the odd
 * asphere's double kernel on it (shape_odd.c's odd_d, shape_vd.h's
 * sv_odd_d), written once for shape_tmpl_on.h's double modes.  No include
 * guard: it is included once per mode.
 */
#if SG_TMPL == SG_TMPL_D || SG_TMPL == SG_TMPL_VD
#ifndef SG_ROT_K_ODD

/* At r2 = x^2 + y^2: the sag, w = sag'(r) / r and w' = dw / d(r^2)'s
 * bound. */
T_FNX(sg_rot_d, sv_rot_d)(const sg_shape *s, T_D r2, T_D *z, T_D *w, T_D *dw T_BADARG)
{
    /* rk = r^(2k) and rkm = r^(2k-2), each a product of r2: a quotient
     * rk / r2 would be 0 / 0 on the axis. */
    T_D zz = T_C(0.0), ww = T_C(0.0), dd2 = T_C(0.0), rk = T_C(1.0), rkm = T_C(0.0);
    int k;
    T_START;
    if (isfinite(s->R)) {
        T_D q = s->R * s->R - s->k1 * r2, sq;
        T_OUT(q < 0.0);
        sq = T_SQRT(q);
        zz = r2 / (s->R + T_COPYSIGN(sq, T_C(s->R)));
        ww = copysign(1.0, s->R) / sq;
        dd2 = fabs(s->k1) / (2.0 * q * sq);
    }
    for (k = 0; k < s->na; k++) {
        /* a_k r^(2k+2): w gains (2k+2) a_k r^(2k), w' k (2k+2) a_k r^(2k-2). */
        zz += s->a[k] * rk * r2;
        ww += (2.0 * k + 2.0) * s->a[k] * rk;
        if (k > 0)
            dd2 += fabs(k * (2.0 * k + 2.0) * s->a[k]) * rkm;
        rkm = rk;
        rk *= r2;
    }
    if (s->nodd) {
        /* b r^i, i = k + 1: w gains i b r^(i-2), w' i (i-2) b r^(i-4) / 2;
         * on the axis only r^2 has a slope over r, and r^1 an infinite
         * curvature. */
        T_D r = T_SQRT(r2), rp = T_C(1.0);
        T_M pos = T_MASK(r2 > 0.0);
        for (k = 0; k < s->nodd; k++) {
            double i = k + 1.0, b = s->odd[k];
            T_D wz = ww, dz = dd2;
            rp *= r; /* r^i */
            zz += b * rp;
            if (k == 1)
                wz = ww + 2.0 * b;
            else if (k == 0 && b != 0.0)
                dz = T_C(INFINITY);
            ww = T_SEL(pos, ww + i * b * rp / r2, wz);
            dd2 = T_SEL(pos, dd2 + fabs(i * (i - 2.0) * b) * rp / (2.0 * r2 * r2), dz);
        }
    }
    *z = zz;
    *w = ww;
    *dw = dd2;
    T_END;
}

#else

/* The odd asphere: the gradient of a rotational sag is w (x, y); its
 * Hessian w I + 2 w' (x, y)(x, y)^T has row sums at most |w| + 4 |w'|
 * r^2. */
T_FN(odd_d, sv_odd_d)(const sg_shape *s, T_D x, T_D y, T_D *z, T_D g[2], T_D *h T_BADARG)
{
    T_D r2 = x * x + y * y, w, dw;
    T_ROT_D(s, r2, z, &w, &dw);
    g[0] = w * x;
    g[1] = w * y;
    *h = 1.5 * (T_ABS(w) + 4.0 * dw * r2);
    T_END;
}

#endif
#endif
