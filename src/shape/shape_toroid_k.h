/*
 * shape_toroid_k.h - the toroid's sag, gradient and bounds, written once
 * for the four arithmetics of shape_tmpl_on.h: shape_toroid.c makes the
 * scalar kernels from it (tor_d, tor_dd), shape_vd.h and shape_vdd.h the
 * lane ones (sv_tor_d, svd_tor).  No include guard: it is included once
 * per mode.  The forms are shape_toroid.c's.
 */
#if SG_TMPL == SG_TMPL_D || SG_TMPL == SG_TMPL_VD

T_FN(tor_d, sv_tor_d)(const sg_shape *s, T_D x, T_D y, T_D *z, T_D g[2], T_D *h T_BADARG)
{
    T_D zy, w, dw, zp, zpp, u, disc, q, zt, aq, hxx, hxy, hyy;
    T_ROT_D(s, y * y, &zy, &w, &dw);
    zp = w * y;
    /* |zy''| at most, from |w| and the magnitude dw. */
    zpp = T_ABS(w) + 2.0 * dw * y * y;
    if (!isfinite(s->Rx)) {
        *z = zy;
        g[0] = T_C(0.0);
        g[1] = zp;
        *h = 1.5 * T_ABS(zpp);
        T_END;
    }
    u = s->Rx - zy;
    disc = u * u - x * x;
    T_OUT(disc < 0.0);
    q = T_COPYSIGN(T_SQRT(disc), u);
    zt = x * x / (u + q);
    *z = zy + zt;
    g[0] = x / q;
    g[1] = u * zp / q;
    aq = T_ABS(q);
    hxx = u * u / (disc * aq);
    hxy = T_ABS(x * u * zp) / (disc * aq);
    hyy = (zp * zp + T_ABS(u * zpp)) / aq + u * u * zp * zp / (disc * aq);
    *h = 1.5 * (hxx + 2.0 * hxy + hyy);
    T_END;
}

#else

T_FN(tor_dd, svd_tor)(const sg_shape *s, T_DD x, T_DD y, T_DD *z, T_DD g[2], T_D *ez, T_D *eg
                      T_BADARG)
{
    T_DD y2 = T_DDOP(sqr)(y), zy, w, zp, u, disc, q, zt;
    T_D ezy, ew, ezp, eu, cond, aq;
    T_ROT_DD(s, y2, &zy, &w, &ezy, &ew);
    ezy += 4.0 * DD_U * T_ABS(w.hi) * y2.hi;
    zp = T_DDOP(mul)(w, y);
    ezp = (ew + 4.0 * DD_U * T_ABS(w.hi)) * T_ABS(y.hi);
    if (!isfinite(s->Rx)) {
        *z = zy;
        g[0] = T_DDC(0.0);
        g[1] = zp;
        *ez = ezy;
        *eg = ezp;
        T_END;
    }
    u = T_DDOP(sub)(T_DDC(s->Rx), zy);
    disc = T_DDOP(sub)(T_DDOP(sqr)(u), T_DDOP(sqr)(x));
    T_OUT(disc.hi <= 0.0);
    q = T_DDOP(sqrt)(disc);
    q = T_DDSEL(T_MASK(u.hi < 0.0), T_DDOP(neg)(q), q);
    zt = T_DDOP(div)(T_DDOP(sqr)(x), T_DDOP(add)(u, q));
    *z = T_DDOP(add)(zy, zt);
    g[0] = T_DDOP(div)(x, q);
    g[1] = T_DDOP(div)(T_DDOP(mul)(u, zp), q);
    /* u carries zy's error and its own rounding; u^2 - x^2 may cancel. */
    eu = ezy + 2.0 * DD_U * (fabs(s->Rx) + T_ABS(zy.hi));
    cond = (u.hi * u.hi + x.hi * x.hi) / disc.hi;
    aq = T_ABS(q.hi);
    *ez = ezy + eu * T_ABS(u.hi) / aq +
          16.0 * DD_U * (T_ABS(zy.hi) + T_ABS(zt.hi) * (1.0 + cond));
    *eg = 16.0 * DD_U * (T_ABS(g[0].hi) + T_ABS(g[1].hi)) * (1.0 + cond) +
          eu * (T_ABS(x.hi * u.hi) + T_ABS(zp.hi) * (u.hi * u.hi + disc.hi)) / (disc.hi * aq) +
          ezp * T_ABS(u.hi) / aq;
    T_END;
}

#endif
