/*
 * shape_tmpl_on.h - the arithmetic a shape's kernel is written in once
 * (as GSL's templates_on.h), for the mode SG_TMPL names:
 *
 *   SG_TMPL_D    double, one point: the shape's sag_d
 *   SG_TMPL_VD   double on SG_VL lanes (vdd.h's vd): shape_vd.h
 *   SG_TMPL_DD   double-double, one point: the shape's sag_dd
 *   SG_TMPL_VDD  double-double on SG_VL lanes: shape_vdd.h
 *
 * A kernel (e.g. shape_biconic_k.h) is included after this header and
 * before shape_tmpl_off.h.  The lane forms do the scalar operations in the
 * same order, so each lane gets the scalar bits (the build uses
 * -ffp-contract=off and only correctly rounded operations;
 * tests/test_shapes.c compares them bit for bit).  A point outside the
 * shape: T_OUT(cond) returns 0 from the scalar kernel, and marks the lanes
 * in *bad, which go on with numbers not to be read.  A branch on the
 * point is a selection, T_SEL, which in scalar evaluates only the side it
 * takes.
 */
#define SG_TMPL_D 1
#define SG_TMPL_VD 2
#define SG_TMPL_DD 3
#define SG_TMPL_VDD 4

#if SG_TMPL == SG_TMPL_D || SG_TMPL == SG_TMPL_DD
/* One point: the kernel returns 1, or 0 outside the shape. */
#define T_VEC 0
#define T_FN(scalar, vector) static int scalar
#define T_FNX(scalar, vector) int scalar /* the scalar form is shape.h's */
#define T_BADARG
#define T_START
#define T_OUT(cond)                                                                              \
    do {                                                                                         \
        if (cond)                                                                                \
            return 0;                                                                            \
    } while (0)
#define T_END return 1
#define T_M int
#define T_MASK(cond) (cond)
#define T_SEL(m, a, b) ((m) ? (a) : (b))
#define T_C(c) (c)
#define T_ABS fabs
#define T_SQRT sqrt
#define T_COPYSIGN copysign
#define T_FMAX fmax
#define T_DDSEL(m, a, b) ((m) ? (a) : (b))
/* shape.c's rotational part, leaving the kernel outside its domain. */
#define T_ROT_D(s, r2, z, w, dw) T_OUT(!sg_rot_d(s, r2, z, w, dw))
#define T_ROT_DD(s, r2, z, w, ez, ew) T_OUT(!sg_rot_dd(s, r2, z, w, ez, ew))
#else
/* SG_VL lanes: the kernel marks the lanes outside the shape in *bad. */
#define T_VEC 1
#define T_FN(scalar, vector) static inline void vector
#define T_FNX(scalar, vector) static inline void vector
#define T_BADARG , vm *bad
#define T_START (*bad = vm_set(0))
#define T_OUT(cond) (*bad |= (vm)(cond))
#define T_END return
#define T_M vm
#define T_MASK(cond) ((vm)(cond))
#define T_SEL(m, a, b) vsel(m, a, b)
#define T_C(c) vd_set(c)
#define T_ABS vd_abs
#define T_SQRT vd_sqrt
#define T_COPYSIGN vd_copysign
#define T_FMAX vd_fmax
#define T_DDSEL(m, a, b) vdd_sel(m, a, b)
/* The lane twins of shape.c's rotational part (shape_vd.h, shape_vdd.h);
 * they set *bad afresh, so a kernel calls them before any T_OUT. */
#define T_ROT_D(s, r2, z, w, dw) sv_rot_d(s, r2, z, w, dw, bad)
#define T_ROT_DD(s, r2, z, w, ez, ew) svd_rot(s, r2, z, w, ez, ew, bad)
#endif

#if SG_TMPL == SG_TMPL_D
#define T_D double
#elif SG_TMPL == SG_TMPL_VD
#define T_D vd
#elif SG_TMPL == SG_TMPL_DD
/* A double-double (T_DD) and its operations; T_D is its double part. */
#define T_D double
#define T_DD dd
#define T_DDC(c) dd_from(c)      /* a constant double */
#define T_DDK(k) (k)             /* a constant double-double */
#define T_DDOP(op) dd_##op
#define T_MULD(a, c) dd_mul_d(a, c) /* by a constant double */
#else
#define T_D vd
#define T_DD vdd
#define T_DDC(c) vdd_from(vd_set(c))
#define T_DDK(k) vdd_set(k)
#define T_DDOP(op) vdd_##op
#define T_MULD(a, c) vdd_mul_d(a, vd_set(c))
#endif
