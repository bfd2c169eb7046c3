/*
 * param.c - the one table of the parameters of a system, its wavelengths,
 * fields and surfaces (sagitta-design(5)), and the generic access to them.
 *
 * The JSON reader and writer, sg_system_validate, sg_system_equal and the
 * editor's cells walk these rows; a parameter added here is read, written,
 * checked, compared and shown without another list to update.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "model_int.h"
#include "shape.h"

static const char *const units_names[] = {"mm", "cm", "in", "m"};
/* The surface types' JSON names, and their .zmx keywords, which the editor
 * shows: from the one list of types, SG_SURF_TYPES. */
#define JSON_NAME_(name, json, zmx, rec) json,
#define ZMX_NAME_(name, json, zmx, rec) zmx,
static const char *const surf_type_names[] = {SG_SURF_TYPES(JSON_NAME_)};
static const char *const surf_type_shown[] = {SG_SURF_TYPES(ZMX_NAME_)};
#undef JSON_NAME_
#undef ZMX_NAME_
static const char *const aperture_names[] = {
    "none", "circular_aperture", "circular_obscuration", "rectangular_aperture",
    "rectangular_obscuration", "elliptical_aperture", "elliptical_obscuration"};
/* The editor shows the .zmx keyword of each. */
static const char *const aperture_shown[] = {"none", "CLAP", "OBSC", "SQAP", "SQOB", "ELAP", "ELOB"};
static const char *const field_type_names[] = {
    "angle", "object_height", "paraxial_image_height", "real_image_height"};
static const char *const field_norm_names[] = {"radial", "rectangular"};
static const char *const aper_type_names[] = {
    "epd", "image_fnum", "object_na", "float_by_stop", "paraxial_working_fnum",
    "object_cone_angle"};
static const char *const aim_names[] = {"off", "paraxial", "real"};
/* A frame change's order as JSON writes it, and as Zemax shows it. */
static const char *const order_names[] = {"decenter_then_tilt", "tilt_then_decenter"};
static const char *const order_shown[] = {"0", "1"};
static const char *const after_names[] = {"explicit", "reverse"};

#define NAMES(a) (a), NULL, (int)(sizeof(a) / sizeof((a)[0]))
#define NONAMES NULL, NULL, 0

/* Rows: key, label, heading, cell, zmx, kind, flags, offset, size, count,
 * elem_mul, elem_add, min, max, default, names, shown, nnames, version. */
#define REAL1(st, key, label, head, cell, zmx, flags, member, lo, hi, def)                   \
    {key, label, head, cell, zmx, SG_PARAM_REAL, flags, offsetof(st, member), 0, 1, 0, 0,  \
     lo, hi, def, NONAMES, 1}

/* The six values of a frame change: keys "before.dx" ..., labels
 * "decenter x" ..., cells "dx" ... (after: "adx" ...). */
#define FRAME_REAL(m, key, label, head, cell, lo, hi)                                         \
    {key, label, head, cell, NULL, SG_PARAM_REAL, SG_PARAM_NESTED, offsetof(sg_surface, m), 0, \
     1, 0, 0, lo, hi, 0.0, NONAMES, 2}
#define FRAME(m, key, lab, hdx, hdy, htx, hty, htz, hor, pre)                                 \
    FRAME_REAL(m.dx, key ".dx", lab "decenter x", hdx, pre "dx", -SG_MAX_LEN, SG_MAX_LEN),      \
    FRAME_REAL(m.dy, key ".dy", lab "decenter y", hdy, pre "dy", -SG_MAX_LEN, SG_MAX_LEN),      \
    FRAME_REAL(m.tx, key ".tx", lab "tilt about x", htx, pre "tx", -360.0, 360.0),              \
    FRAME_REAL(m.ty, key ".ty", lab "tilt about y", hty, pre "ty", -360.0, 360.0),              \
    FRAME_REAL(m.tz, key ".tz", lab "tilt about z", htz, pre "tz", -360.0, 360.0),              \
    {key ".order", lab "order", hor, pre "order", NULL, SG_PARAM_ENUM, SG_PARAM_NESTED,           \
     offsetof(sg_surface, m.order), 0, 1, 0, 0, 0, 0, 0, order_names, order_shown, 2, 2}

static const sg_param system_params[] = {
    {"title", "title", NULL, NULL, NULL, SG_PARAM_TEXT, 0, offsetof(sg_system, title),
     sizeof(((sg_system *)0)->title), 1, 0, 0, 0, 0, 0, NONAMES, 1},
    {"units", "units", NULL, NULL, "UNIT", SG_PARAM_TEXT, 0, offsetof(sg_system, units),
     sizeof(((sg_system *)0)->units), 1, 0, 0, 0, 0, 0, NAMES(units_names), 1},
    {"fields.type", "field type", NULL, NULL, "FTYP", SG_PARAM_ENUM, 0,
     offsetof(sg_system, field_type), 0, 1, 0, 0, 0, 0, SG_FIELD_ANGLE, NAMES(field_type_names), 1},
    {"fields.normalization", "field normalization", NULL, NULL, "FTYP", SG_PARAM_ENUM, 0,
     offsetof(sg_system, field_norm), 0, 1, 0, 0, 0, 0, SG_NORM_RADIAL, NAMES(field_norm_names), 1},
    {"aperture.type", "aperture type", NULL, NULL, "ENPD", SG_PARAM_ENUM, 0,
     offsetof(sg_system, aper_type), 0, 1, 0, 0, 0, 0, SG_APER_EPD, NAMES(aper_type_names), 1},
    REAL1(sg_system, "aperture.value", "aperture value", NULL, NULL, "ENPD", SG_PARAM_NONNEG,
          aper_value, 0.0, SG_MAX_LEN, 10.0),
    {"ray_aiming", "ray aiming", NULL, NULL, "RAIM", SG_PARAM_ENUM, 0, offsetof(sg_system, aim),
     0, 1, 0, 0, 0, 0, SG_AIM_OFF, NAMES(aim_names), 1},
    /* Format version 3: object-space telecentric (in "aperture"). */
    {"aperture.telecentric", "object-space telecentric", NULL, NULL, "FTYP", SG_PARAM_BOOL,
     SG_PARAM_OPTIONAL, offsetof(sg_system, telecentric), 0, 1, 0, 0, 0, 0, 0, NONAMES, 3},
    /* Format version 7: afocal image space. */
    {"afocal", "afocal image space", NULL, NULL, "FTYP", SG_PARAM_BOOL, SG_PARAM_OPTIONAL,
     offsetof(sg_system, afocal), 0, 1, 0, 0, 0, 0, 0, NONAMES, 7},
};

static const sg_param wave_params[] = {
    REAL1(sg_wave, "um", "wavelength", NULL, NULL, "WAVM",
          SG_PARAM_POSITIVE | SG_PARAM_REQUIRED, um, 0.0, INFINITY, 0.5875618),
    REAL1(sg_wave, "weight", "weight", NULL, NULL, "WAVM", SG_PARAM_NONNEG, weight, 0.0,
          INFINITY, 1.0),
};

static const sg_param field_params[] = {
    REAL1(sg_field, "x", "x", NULL, NULL, "XFLN", 0, x, -INFINITY, INFINITY, 0.0),
    REAL1(sg_field, "y", "y", NULL, NULL, "YFLN", 0, y, -INFINITY, INFINITY, 0.0),
    REAL1(sg_field, "weight", "weight", NULL, NULL, "FWGN", SG_PARAM_NONNEG, weight, 0.0,
          INFINITY, 1.0),
    /* Format version 2: Zemax's vignetting factors. */
    {"vdx", "vignetting decenter x", NULL, NULL, "VDXN", SG_PARAM_REAL, SG_PARAM_OPTIONAL,
     offsetof(sg_field, vdx), 0, 1, 0, 0, -1e6, 1e6, 0.0, NONAMES, 2},
    {"vdy", "vignetting decenter y", NULL, NULL, "VDYN", SG_PARAM_REAL, SG_PARAM_OPTIONAL,
     offsetof(sg_field, vdy), 0, 1, 0, 0, -1e6, 1e6, 0.0, NONAMES, 2},
    {"vcx", "vignetting compression x", NULL, NULL, "VCXN", SG_PARAM_REAL, SG_PARAM_OPTIONAL,
     offsetof(sg_field, vcx), 0, 1, 0, 0, -1e6, 1e6, 0.0, NONAMES, 2},
    {"vcy", "vignetting compression y", NULL, NULL, "VCYN", SG_PARAM_REAL, SG_PARAM_OPTIONAL,
     offsetof(sg_field, vcy), 0, 1, 0, 0, -1e6, 1e6, 0.0, NONAMES, 2},
    {"van", "vignetting angle", NULL, NULL, "VANN", SG_PARAM_REAL, SG_PARAM_OPTIONAL,
     offsetof(sg_field, van), 0, 1, 0, 0, -1e6, 1e6, 0.0, NONAMES, 2},
};

static const sg_param surface_params[] = {
    {"type", "type", "Type", "type", "TYPE", SG_PARAM_ENUM, 0, offsetof(sg_surface, type), 0, 1,
     0, 0, 0, 0, SG_SURF_STANDARD, surf_type_names, surf_type_shown, SG_SURF_NTYPES, 1},
    {"comment", "comment", "Comment", "comment", "COMM", SG_PARAM_TEXT, 0,
     offsetof(sg_surface, comment), SG_COMMENT, 1, 0, 0, 0, 0, 0, NONAMES, 1},
    REAL1(sg_surface, "radius", "radius", "Radius", "radius", "CURV", SG_PARAM_INF, radius,
          -SG_MAX_LEN, SG_MAX_LEN, INFINITY),
    REAL1(sg_surface, "thickness", "thickness", "Thickness", "thickness", "DISZ",
          SG_PARAM_OBJ_INF, thickness, -SG_MAX_LEN, SG_MAX_LEN, 0.0),
    {"material", "material", "Material", "material", "GLAS", SG_PARAM_MATERIAL, 0,
     offsetof(sg_surface, mat), 0, 1, 0, 0, 0, 0, 0, NONAMES, 1},
    REAL1(sg_surface, "semi_diameter", "semi-diameter", "Semi-Dia", "semi", "DIAM",
          SG_PARAM_NONNEG, semi_diameter, 0.0, SG_MAX_LEN, 0.0),
    {"sd_fixed", "fixed semi-diameter", NULL, NULL, "FLAP", SG_PARAM_BOOL, 0,
     offsetof(sg_surface, sd_fixed), 0, 1, 0, 0, 0, 0, 0, NONAMES, 1},
    REAL1(sg_surface, "conic", "conic", "Conic", "conic", "CONI", 0, conic, -INFINITY, INFINITY,
          0.0),
    {"asphere", "asphere term r^%d", "r^%d", "a%d", "PARM", SG_PARAM_REAL, SG_PARAM_SHAPE,
     offsetof(sg_surface, asph), 0, SG_NASPH, 2, 2, -INFINITY, INFINITY, 0.0, NONAMES, 1},
    /* Format version 3: the shapes beyond the even asphere; each type
     * reads only its own (sagitta-design(5), SURFACE TYPES). */
    {"odd", "odd asphere term r^%d", "b%d", "b%d", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_OPTIONAL,
     offsetof(sg_surface, odd), 0, SG_NODD, 1, 1, -INFINITY, INFINITY, 0.0, NONAMES, 3},
    {"radius_x", "x radius", "Radius X", "rx", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_INF | SG_PARAM_OPTIONAL, offsetof(sg_surface, radius_x), 0, 1, 0, 0, -SG_MAX_LEN,
     SG_MAX_LEN, INFINITY, NONAMES, 3},
    {"conic_x", "x conic", "Conic X", "kx", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_OPTIONAL,
     offsetof(sg_surface, conic_x), 0, 1, 0, 0, -INFINITY, INFINITY, 0.0, NONAMES, 3},
    {"norm_radius", "normalization radius", "Norm R", "norm", "XDAT", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_POSITIVE | SG_PARAM_OPTIONAL, offsetof(sg_surface, norm_radius), 0, 1, 0, 0, 0.0,
     SG_MAX_LEN, 1.0, NONAMES, 3},
    /* Zemax's Decenter X and Y of a Zernike sag: where its terms are
     * centred (the conic and r^n terms stay on the vertex). */
    {"zernike_decenter_x", "Zernike decenter x", "Zern dX", "zdx", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_OPTIONAL, offsetof(sg_surface, zern_dx), 0, 1, 0, 0, -SG_MAX_LEN, SG_MAX_LEN, 0.0,
     NONAMES, 3},
    {"zernike_decenter_y", "Zernike decenter y", "Zern dY", "zdy", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_OPTIONAL, offsetof(sg_surface, zern_dy), 0, 1, 0, 0, -SG_MAX_LEN, SG_MAX_LEN, 0.0,
     NONAMES, 3},
    {"terms", "term %d", "T%d", "t%d", "XDAT", SG_PARAM_REAL, SG_PARAM_SHAPE | SG_PARAM_OPTIONAL,
     offsetof(sg_surface, terms), 0, SG_NTERMS, 1, 1, -INFINITY, INFINITY, 0.0, NONAMES, 3},
    /* The paraxial surface (Zemax's ideal lens): its focal length, 0 until
     * set (a paraxial surface needs one), and Zemax's OPD mode. */
    {"focal_length", "focal length", "Focal", "focal", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_OPTIONAL, offsetof(sg_surface, focal_length), 0, 1, 0, 0,
     -SG_MAX_LEN, SG_MAX_LEN, 0.0, NONAMES, 3},
    {"opd_mode", "OPD mode", "OPD Mode", "opdm", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_OPTIONAL, offsetof(sg_surface, opd_mode), 0, 1, 0, 0, 0.0, 3.0,
     1.0, NONAMES, 3},
    /* The diffraction grating: lines per micrometre and the order. */
    {"grating_lines", "grating lines per um", "Lines/um", "lpum", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_OPTIONAL, offsetof(sg_surface, grating_lines), 0, 1, 0, 0,
     -1e6, 1e6, 0.0, NONAMES, 3},
    {"grating_order", "diffraction order", "Diff Ord", "dorder", "PARM", SG_PARAM_REAL,
     SG_PARAM_SHAPE | SG_PARAM_OPTIONAL, offsetof(sg_surface, grating_order), 0, 1, 0, 0,
     -1e6, 1e6, 0.0, NONAMES, 3},
    /* Format version 2: surface apertures and obscurations. */
    {"aperture", "aperture", "Aperture", "aperture", "CLAP|OBSC|SQAP|SQOB|ELAP|ELOB",
     SG_PARAM_ENUM, SG_PARAM_OPTIONAL,
     offsetof(sg_surface, aperture), 0, 1, 0, 0, 0, 0, SG_APERTURE_NONE, aperture_names,
     aperture_shown, 7, 2},
    {"aperture_min_radius", "aperture minimum radius", "Ap r-min", "ap_rmin", "CLAP",
     SG_PARAM_REAL, SG_PARAM_NONNEG | SG_PARAM_OPTIONAL, offsetof(sg_surface, ap_rmin), 0, 1, 0,
     0, 0.0, SG_MAX_LEN, 0.0, NONAMES, 2},
    {"aperture_max_radius", "aperture maximum radius", "Ap r-max", "ap_rmax", "CLAP",
     SG_PARAM_REAL, SG_PARAM_NONNEG | SG_PARAM_OPTIONAL, offsetof(sg_surface, ap_rmax), 0, 1, 0,
     0, 0.0, SG_MAX_LEN, 0.0, NONAMES, 2},
    {"aperture_x_half_width", "aperture x half width", "Ap x-half", "ap_xhalf", "SQAP",
     SG_PARAM_REAL, SG_PARAM_NONNEG | SG_PARAM_OPTIONAL, offsetof(sg_surface, ap_xhalf), 0, 1, 0,
     0, 0.0, SG_MAX_LEN, 0.0, NONAMES, 2},
    {"aperture_y_half_width", "aperture y half width", "Ap y-half", "ap_yhalf", "SQAP",
     SG_PARAM_REAL, SG_PARAM_NONNEG | SG_PARAM_OPTIONAL, offsetof(sg_surface, ap_yhalf), 0, 1, 0,
     0, 0.0, SG_MAX_LEN, 0.0, NONAMES, 2},
    {"aperture_x_decenter", "aperture x decenter", "Ap x-dec", "ap_xdec", "OBDC", SG_PARAM_REAL,
     SG_PARAM_OPTIONAL, offsetof(sg_surface, ap_xdec), 0, 1, 0, 0, -SG_MAX_LEN, SG_MAX_LEN, 0.0,
     NONAMES, 2},
    {"aperture_y_decenter", "aperture y decenter", "Ap y-dec", "ap_ydec", "OBDC", SG_PARAM_REAL,
     SG_PARAM_OPTIONAL, offsetof(sg_surface, ap_ydec), 0, 1, 0, 0, -SG_MAX_LEN, SG_MAX_LEN, 0.0,
     NONAMES, 2},
    /* Format version 2: the frame changes, Zemax's coordinate break
     * (Decenter X ... Order, the break itself, in "before") and a surface's
     * tilt and decenter before and after it.  design_json.c reads and
     * writes them as the nested objects "break", "before" and "after";
     * here for the editor's columns, validation and equality. */
    FRAME(before, "before", "", "Dec X", "Dec Y", "Tilt X", "Tilt Y", "Tilt Z", "Order", ""),
    {"after.mode", "after mode", "After", "after", NULL, SG_PARAM_ENUM, SG_PARAM_NESTED,
     offsetof(sg_surface, after_mode), 0, 1, 0, 0, 0, 0, SG_AFTER_EXPLICIT, after_names,
     after_names, 2, 2},
    FRAME(after, "after", "after ", "Aft dX", "Aft dY", "Aft tX", "Aft tY", "Aft tZ", "Aft Ord",
          "a"),
    /* Format version 3: Zemax's TCE column, 1e-6/K, read by sg_thermal
     * alone (sagitta-design(5), THERMAL EXPANSION); the .zmx line TCED. */
    {"tce", "TCE", "TCE", "tce", "TCED", SG_PARAM_REAL, SG_PARAM_OPTIONAL,
     offsetof(sg_surface, tce), 0, 1, 0, 0, -SG_TCE_MAX, SG_TCE_MAX, 0.0, NONAMES, 3},
    /* A model glass's nd and vd, inside the material's own object in
     * JSON (hence nested, with no column): rows so that a variable or a
     * tolerance can address them, on a model glass alone
     * (sg_param_material_part). */
    {"material.nd", "model glass nd", NULL, NULL, NULL, SG_PARAM_REAL, SG_PARAM_NESTED,
     offsetof(sg_surface, mat.index), 0, 1, 0, 0, SG_MODEL_ND_MIN, SG_MODEL_ND_MAX, 0.0,
     NONAMES, 2},
    {"material.vd", "model glass vd", NULL, NULL, NULL, SG_PARAM_REAL, SG_PARAM_NESTED,
     offsetof(sg_surface, mat.vd), 0, 1, 0, 0, SG_MODEL_VD_MIN, SG_MODEL_VD_MAX, 0.0, NONAMES,
     2},
};

#define NROWS(a) ((int)(sizeof(a) / sizeof((a)[0])))

static const sg_param *table(sg_param_scope scope, int *n)
{
    switch (scope) {
    case SG_SCOPE_SYSTEM: *n = NROWS(system_params); return system_params;
    case SG_SCOPE_WAVE: *n = NROWS(wave_params); return wave_params;
    case SG_SCOPE_FIELD: *n = NROWS(field_params); return field_params;
    case SG_SCOPE_SURFACE: *n = NROWS(surface_params); return surface_params;
    default: *n = 0; return NULL;
    }
}

int sg_param_count(sg_param_scope scope)
{
    int n;
    (void)table(scope, &n);
    return n;
}

const sg_param *sg_param_at(sg_param_scope scope, int i)
{
    int n;
    const sg_param *t = table(scope, &n);
    return i >= 0 && i < n ? &t[i] : NULL;
}

const sg_param *sg_param_find(sg_param_scope scope, const char *key)
{
    int n, i;
    const sg_param *t = table(scope, &n);
    for (i = 0; i < n; i++)
        if (strcmp(t[i].key, key) == 0)
            return &t[i];
    return NULL;
}

void *sg_param_ptr(const sg_param *p, void *obj)
{
    return (char *)obj + p->offset;
}

const void *sg_param_cptr(const sg_param *p, const void *obj)
{
    return (const char *)obj + p->offset;
}

/* Enums are stored as int-sized enums; the build checks that below. */
typedef char enum_is_int[sizeof(sg_surf_type) == sizeof(int) ? 1 : -1];

double sg_param_get(const sg_param *p, const void *obj, int k)
{
    const void *q = sg_param_cptr(p, obj);
    switch (p->kind) {
    case SG_PARAM_REAL: return ((const double *)q)[k];
    case SG_PARAM_BOOL:
    case SG_PARAM_ENUM: return (double)*(const int *)q;
    default: return NAN;
    }
}

void sg_param_set(const sg_param *p, void *obj, int k, double v)
{
    void *q = sg_param_ptr(p, obj);
    switch (p->kind) {
    case SG_PARAM_REAL: ((double *)q)[k] = v; break;
    case SG_PARAM_BOOL: *(int *)q = v != 0.0; break;
    case SG_PARAM_ENUM: *(int *)q = (int)v; break;
    default: break;
    }
}

void sg_param_label(const sg_param *p, int k, char *buf, size_t n)
{
    if (p->count > 1)
        snprintf(buf, n, p->label, p->elem_mul * k + p->elem_add);
    else
        snprintf(buf, n, "%s", p->label);
}

void sg_param_heading(const sg_param *p, int k, char *buf, size_t n)
{
    const char *h = p->heading ? p->heading : p->key;
    if (p->count > 1)
        snprintf(buf, n, h, p->elem_mul * k + p->elem_add);
    else
        snprintf(buf, n, "%s", h);
}

void sg_param_cell(const sg_param *p, int k, char *buf, size_t n)
{
    const char *c = p->cell ? p->cell : p->key;
    if (p->count > 1)
        snprintf(buf, n, c, p->elem_mul * k + p->elem_add);
    else
        snprintf(buf, n, "%s", c);
}

int sg_param_check(const sg_param *p, int k, double v, int object, char *msg, size_t n)
{
    char lab[64];
    int inf_ok = (p->flags & SG_PARAM_INF) || ((p->flags & SG_PARAM_OBJ_INF) && object && v > 0);
    /* The label is made only for a message: a valid design has every
     * value of every surface checked each time a tracer is made. */
    if (p->kind == SG_PARAM_BOOL) {
        if (v == 0.0 || v == 1.0)
            return SG_OK;
        if (msg) {
            sg_param_label(p, k, lab, sizeof lab);
            snprintf(msg, n, "%s: %g is not 0 or 1", lab, v);
        }
        return SG_ERANGE;
    }
    if (p->kind == SG_PARAM_ENUM) {
        if (v >= 0 && v < p->nnames && v == floor(v))
            return SG_OK;
        if (msg) {
            sg_param_label(p, k, lab, sizeof lab);
            snprintf(msg, n, "%s: %g is not one of 0 to %d", lab, v, p->nnames - 1);
        }
        return SG_ERANGE;
    }
    if (p->kind != SG_PARAM_REAL)
        return SG_OK;
    if (isnan(v) || (isinf(v) && !inf_ok)) {
        if (msg) {
            sg_param_label(p, k, lab, sizeof lab);
            if (p->flags & (SG_PARAM_NONNEG | SG_PARAM_POSITIVE))
                snprintf(msg, n, "%s %g must be finite and %s", lab, v,
                         p->flags & SG_PARAM_POSITIVE ? "positive" : "not negative");
            else
                snprintf(msg, n, "%s must be finite", lab);
        }
        return SG_ERANGE;
    }
    if (((p->flags & SG_PARAM_NONNEG) && v < 0.0) ||
        ((p->flags & SG_PARAM_POSITIVE) && !(v > 0.0))) {
        if (msg) {
            sg_param_label(p, k, lab, sizeof lab);
            snprintf(msg, n, "%s %g must be finite and %s", lab, v,
                     p->flags & SG_PARAM_POSITIVE ? "positive" : "not negative");
        }
        return SG_ERANGE;
    }
    /* A radius whose curvature 1/R overflows (|R| below 1/DBL_MAX, 5e-324
     * say): no trace or .zmx file can hold it. */
    if ((p->flags & SG_PARAM_INF) && v != 0.0 && !isfinite(1.0 / v)) {
        if (msg) {
            sg_param_label(p, k, lab, sizeof lab);
            snprintf(msg, n, "%s %g is so small that its curvature 1/R is beyond the doubles",
                     lab, v);
        }
        return SG_ERANGE;
    }
    if (isfinite(v) && (v < p->min || v > p->max)) {
        if (msg) {
            sg_param_label(p, k, lab, sizeof lab);
            if (p->max == SG_MAX_LEN && v > p->max)
                snprintf(msg, n, "%s %g is beyond %g lens units", lab, v, p->max);
            else if (v > p->max)
                snprintf(msg, n, "%s %g is beyond %g", lab, v, p->max);
            else
                snprintf(msg, n, "%s %g is below %g", lab, v, p->min);
        }
        return SG_ERANGE;
    }
    return SG_OK;
}

void sg_param_defaults(sg_param_scope scope, void *obj)
{
    int n, i, k;
    const sg_param *t = table(scope, &n);
    for (i = 0; i < n; i++) {
        const sg_param *p = &t[i];
        void *q = sg_param_ptr(p, obj);
        switch (p->kind) {
        case SG_PARAM_REAL:
        case SG_PARAM_BOOL:
        case SG_PARAM_ENUM:
            for (k = 0; k < p->count; k++)
                sg_param_set(p, obj, k, p->def);
            break;
        case SG_PARAM_TEXT:
            memset(q, 0, p->size);
            if (p->names)
                sg_strlcpy(q, p->names[0], p->size);
            break;
        case SG_PARAM_MATERIAL:
            memset(q, 0, sizeof(sg_material));
            ((sg_material *)q)->kind = SG_MAT_AIR;
            break;
        }
    }
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

int sg_param_equal(sg_param_scope scope, const void *a, const void *b)
{
    int n, i, k;
    const sg_param *t = table(scope, &n);
    for (i = 0; i < n; i++) {
        const sg_param *p = &t[i];
        const void *qa = sg_param_cptr(p, a), *qb = sg_param_cptr(p, b);
        switch (p->kind) {
        case SG_PARAM_REAL:
            for (k = 0; k < p->count; k++)
                if (!same_bits(((const double *)qa)[k], ((const double *)qb)[k]))
                    return 0;
            break;
        case SG_PARAM_BOOL:
        case SG_PARAM_ENUM:
            if (*(const int *)qa != *(const int *)qb)
                return 0;
            break;
        case SG_PARAM_TEXT:
            if (strncmp(qa, qb, p->size) != 0)
                return 0;
            break;
        case SG_PARAM_MATERIAL: {
            const sg_material *ma = qa, *mb = qb;
            if (ma->kind != mb->kind || strncmp(ma->name, mb->name, sizeof ma->name) != 0 ||
                strncmp(ma->catalog, mb->catalog, sizeof ma->catalog) != 0 ||
                !same_bits(ma->index, mb->index) || !same_bits(ma->vd, mb->vd) ||
                !same_bits(ma->dpgf, mb->dpgf) || !same_bits(ma->dn, mb->dn) ||
                !same_bits(ma->disp, mb->disp))
                return 0;
            break;
        }
        }
    }
    return 1;
}

/* Frame changes are one nested JSON object each ("break", "before",
 * "after"), read and written by design_json.c outside this table; bits,
 * as the table compares. */
static int same_change(const sg_frame_change *a, const sg_frame_change *b)
{
    return memcmp(&a->dx, &b->dx, sizeof a->dx) == 0 && memcmp(&a->dy, &b->dy, sizeof a->dy) == 0 &&
           memcmp(&a->tx, &b->tx, sizeof a->tx) == 0 && memcmp(&a->ty, &b->ty, sizeof a->ty) == 0 &&
           memcmp(&a->tz, &b->tz, sizeof a->tz) == 0 && a->order == b->order;
}

/* Solves are one nested JSON object ("solves"), read and written by
 * design_json.c outside this table. */
static int same_solves(const sg_solve *a, const sg_solve *b)
{
    int t;
    for (t = 0; t < SG_SOLVE_NTARGETS; t++)
        if (a[t].kind != b[t].kind || a[t].from != b[t].from ||
            !same_bits(a[t].scale, b[t].scale) || !same_bits(a[t].offset, b[t].offset) ||
            !same_bits(a[t].value, b[t].value) || !same_bits(a[t].lo, b[t].lo) ||
            !same_bits(a[t].hi, b[t].hi))
            return 0;
    return 1;
}

static int same_vars(const sg_surface *a, const sg_surface *b)
{
    int k;
    if (a->nvar != b->nvar)
        return 0;
    for (k = 0; k < a->nvar; k++)
        if (a->var[k].param != b->var[k].param || a->var[k].elem != b->var[k].elem ||
            !same_bits(a->var[k].lo, b->var[k].lo) || !same_bits(a->var[k].hi, b->var[k].hi))
            return 0;
    return 1;
}

/* The tolerances are their own object (design_json.c reads them), so a
 * save that would lose an edit of them is noticed. */
static int same_tol(const sg_tolerances *a, const sg_tolerances *b)
{
    int k;
    if (a->present != b->present || a->nop != b->nop || a->ncomp != b->ncomp ||
        a->criterion != b->criterion || a->reference != b->reference ||
        a->pattern != b->pattern || a->density != b->density || a->grid != b->grid ||
        a->trials != b->trials || !same_bits(a->seed, b->seed) ||
        a->distribution != b->distribution || !same_bits(a->test_wave, b->test_wave))
        return 0;
    for (k = 0; k < a->nop; k++) {
        const sg_tol_operand *x = &a->op[k], *y = &b->op[k];
        if (x->type != y->type || x->surface != y->surface || x->last != y->last ||
            x->adjust != y->adjust || strcmp(x->param, y->param) != 0 || x->elem != y->elem ||
            x->zmin != y->zmin || x->zmax != y->zmax ||
            !same_bits(x->min, y->min) || !same_bits(x->max, y->max))
            return 0;
    }
    for (k = 0; k < a->ncomp; k++) {
        const sg_tol_comp *x = &a->comp[k], *y = &b->comp[k];
        if (x->surface != y->surface || strcmp(x->param, y->param) != 0 || x->elem != y->elem ||
            !same_bits(x->min, y->min) || !same_bits(x->max, y->max))
            return 0;
    }
    return 1;
}

int sg_system_equal(const sg_system *a, const sg_system *b)
{
    int i;
    /* The environment is read and written beside the table (design_json.c). */
    if (!same_bits(a->temperature, b->temperature) || !same_bits(a->pressure, b->pressure) ||
        a->adjust_index != b->adjust_index)
        return 0;
    /* The merit function is its own object (sg_merit_equal, below). */
    if (!sg_merit_equal(&a->merit, &b->merit))
        return 0;
    /* So are the configurations (config.c). */
    if (!sg_configs_equal(a->configs, b->configs))
        return 0;
    if (!same_tol(&a->tol, &b->tol))
        return 0;
    if (!sg_param_equal(SG_SCOPE_SYSTEM, a, b) || a->nwave != b->nwave ||
        a->primary_wave != b->primary_wave || a->nfield != b->nfield || a->stop != b->stop ||
        a->nsurf != b->nsurf)
        return 0;
    for (i = 0; i < a->nwave; i++)
        if (!sg_param_equal(SG_SCOPE_WAVE, &a->wave[i], &b->wave[i]))
            return 0;
    for (i = 0; i < a->nfield; i++)
        if (!sg_param_equal(SG_SCOPE_FIELD, &a->field[i], &b->field[i]))
            return 0;
    for (i = 0; i < a->nsurf; i++)
        if (!sg_param_equal(SG_SCOPE_SURFACE, &a->surf[i], &b->surf[i]) ||
            !same_change(&a->surf[i].before, &b->surf[i].before) ||
            !same_change(&a->surf[i].after, &b->surf[i].after) ||
            a->surf[i].after_mode != b->surf[i].after_mode ||
            !same_solves(a->surf[i].solve, b->surf[i].solve) ||
            !same_vars(&a->surf[i], &b->surf[i]))
            return 0;
    return 1;
}

/* The record of the type (src/shape/shape.h) lists the parameters it reads. */
int sg_param_material_part(const sg_param *p)
{
    return p && p->kind == SG_PARAM_REAL && strncmp(p->key, "material.", 9) == 0;
}

int sg_param_used(const sg_param *p, int k, int type)
{
    const sg_shape_type *t = sg_shape_type_of(type);
    const sg_shape_key *e;
    if (!t)
        return !(p->flags & SG_PARAM_SHAPE);
    for (e = t->keys; e->key; e++) {
        size_t n = strlen(e->key);
        if (e->key[n - 1] == '.' ? strncmp(p->key, e->key, n) == 0 : strcmp(p->key, e->key) == 0)
            return e->n == 0 || k < e->n;
    }
    return !t->only && !(p->flags & SG_PARAM_SHAPE);
}

/* The merit function is data of the design: its equality lives with the
 * rest of sg_system_equal, below the optimizer that evaluates it. */
int sg_merit_equal(const sg_merit *a, const sg_merit *b)
{
    int i;
    if (a->present != b->present || a->has_default != b->has_default ||
        a->reference != b->reference || a->rings != b->rings || a->arms != b->arms ||
        a->nop != b->nop)
        return 0;
    for (i = 0; i < a->nop; i++) {
        const sg_operand *x = &a->op[i], *y = &b->op[i];
        if (x->type != y->type || x->i1 != y->i1 || x->i2 != y->i2 || !same_bits(x->hx, y->hx) ||
            !same_bits(x->hy, y->hy) || !same_bits(x->px, y->px) || !same_bits(x->py, y->py) ||
            !same_bits(x->target, y->target) || !same_bits(x->weight, y->weight))
            return 0;
    }
    return 1;
}
