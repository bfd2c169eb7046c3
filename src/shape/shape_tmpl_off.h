/*
 * shape_tmpl_off.h - ends a kernel's arithmetic (shape_tmpl_on.h), so the
 * next mode can be set.
 */
#undef SG_TMPL
#undef SG_TMPL_D
#undef SG_TMPL_VD
#undef SG_TMPL_DD
#undef SG_TMPL_VDD
#undef T_VEC
#undef T_FN
#undef T_FNX
#undef T_BADARG
#undef T_START
#undef T_OUT
#undef T_END
#undef T_M
#undef T_MASK
#undef T_SEL
#undef T_C
#undef T_ABS
#undef T_SQRT
#undef T_COPYSIGN
#undef T_FMAX
#undef T_DDSEL
#undef T_ROT_D
#undef T_ROT_DD
#undef T_D
#undef T_DD
#undef T_DDC
#undef T_DDK
#undef T_DDOP
#undef T_MULD
