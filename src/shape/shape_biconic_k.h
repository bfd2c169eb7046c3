/*
 * shape_biconic_k.h - the biconic's sag, gradient and bounds, written once
 * for the four arithmetics of shape_tmpl_on.h: shape_biconic.c makes the
 * scalar kernels from it (bic_d, bic_dd), shape_vd.h and shape_vdd.h the
 * lane ones (sv_bic_d, svd_bic).  No include guard: it is included once
 * per mode.
 *
 *   z = N / (1 + S),  N = cx x^2 + cy y^2,
 *   S = sqrt(1 - (1 + kx) cx^2 x^2 - (1 + ky) cy^2 y^2).
 */
#if SG_TMPL == SG_TMPL_D || SG_TMPL == SG_TMPL_VD

/* The curvatures and the conics' bound are the same at every point: they
 * are formed in scalar, and a product that starts with them (kx1 cx cx x
 * x) rounds them first, in either mode. */
T_FN(bic_d, sv_bic_d)(const sg_shape *s, T_D x, T_D y, T_D *z, T_D g[2], T_D *h T_BADARG)
{
    double cx = isfinite(s->Rx) ? 1.0 / s->Rx : 0.0, cy = isfinite(s->R) ? 1.0 / s->R : 0.0;
    double km = fmax(1.0, fmax(fabs(s->kx1), fabs(s->k1)));
    T_D N = cx * x * x + cy * y * y;
    T_D Q = 1.0 - s->kx1 * cx * cx * x * x - s->k1 * cy * cy * y * y, S, D;
    T_M pos;
    T_START;
    T_OUT(Q < 0.0);
    S = T_SQRT(Q);
    D = 1.0 + S;
    *z = N / D;
    /* The slopes where S > 0, infinite at the rim. */
    pos = T_MASK(S > 0.0);
    g[0] = T_SEL(pos, (2.0 * cx * x * D + N * s->kx1 * cx * cx * x / S) / (D * D), T_C(INFINITY));
    g[1] = T_SEL(pos, (2.0 * cy * y * D + N * s->k1 * cy * cy * y / S) / (D * D), T_C(INFINITY));
    /* A conic section's second derivative is c / S^3; the cross terms of
     * two sections are of the same order. */
    *h = 3.0 * (fabs(cx) + fabs(cy)) * km / (Q * S);
    T_END;
}

#else

T_FN(bic_dd, svd_bic)(const sg_shape *s, T_DD x, T_DD y, T_DD *z, T_DD g[2], T_D *ez, T_D *eg
                      T_BADARG)
{
    /* The curvatures, in scalar double-double as at every point. */
    dd cxs = isfinite(s->Rx) ? dd_div(dd_from(1.0), dd_from(s->Rx)) : dd_from(0.0);
    dd cys = isfinite(s->R) ? dd_div(dd_from(1.0), dd_from(s->R)) : dd_from(0.0);
    T_DD one = T_DDC(1.0), cx = T_DDK(cxs), cy = T_DDK(cys);
    T_DD ax = T_DDOP(mul)(cx, T_DDOP(sqr)(x)), ay = T_DDOP(mul)(cy, T_DDOP(sqr)(y));
    T_DD N = T_DDOP(add)(ax, ay);
    T_DD px = T_MULD(T_DDOP(mul)(ax, cx), s->kx1), py = T_MULD(T_DDOP(mul)(ay, cy), s->k1);
    T_DD Q = T_DDOP(sub)(T_DDOP(sub)(one, px), py), S, D, D2, tx, ty;
    T_D cond, gm;
    T_START;
    T_OUT(Q.hi < 0.0);
    S = T_DDOP(sqrt)(Q);
    D = T_DDOP(add)(one, S);
    *z = T_DDOP(div)(N, D);
    T_OUT(S.hi <= 0.0);
    D2 = T_DDOP(sqr)(D);
    /* dz/dx = (2 cx x D + N kx1 cx^2 x / S) / D^2. */
    tx = T_DDOP(add)(T_DDOP(mul)(T_MULD(T_DDOP(mul)(cx, x), 2.0), D),
                     T_DDOP(div)(T_DDOP(mul)(N, T_MULD(T_DDOP(mul)(T_DDOP(mul)(cx, cx), x), s->kx1)),
                                 S));
    ty = T_DDOP(add)(T_DDOP(mul)(T_MULD(T_DDOP(mul)(cy, y), 2.0), D),
                     T_DDOP(div)(T_DDOP(mul)(N, T_MULD(T_DDOP(mul)(T_DDOP(mul)(cy, cy), y), s->k1)),
                                 S));
    g[0] = T_DDOP(div)(tx, D2);
    g[1] = T_DDOP(div)(ty, D2);
    /* Q = 1 - kx1 cx^2 x^2 - ky1 cy^2 y^2 may cancel near the rim. */
    cond = (1.0 + T_ABS(px.hi) + T_ABS(py.hi)) / Q.hi;
    *ez = 24.0 * DD_U * T_ABS(z->hi) * (1.0 + cond) + 8.0 * DD_U * (T_ABS(ax.hi) + T_ABS(ay.hi));
    gm = (T_ABS(tx.hi) + T_ABS(ty.hi) +
          2.0 * T_ABS(N.hi) *
              (T_ABS(s->kx1 * cxs.hi * cxs.hi * x.hi) + T_ABS(s->k1 * cys.hi * cys.hi * y.hi)) /
              (S.hi * Q.hi)) /
         (D.hi * D.hi);
    *eg = 48.0 * DD_U * gm * (1.0 + cond);
    T_END;
}

#endif
