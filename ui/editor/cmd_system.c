/*
 * cmd_system.c - the system's commands: title, units, wavelengths, fields,
 * aperture, aiming, environment, semi-diameters and glasses.
 */
#include "cmd_int.h"

int c_title(ed *e, args *a)
{
    char t[ED_LINE];
    if (a->n > 1)
        ec_rest_of(a, 1, t, sizeof t);
    else
        t[0] = '\0';
    if (strlen(t) >= sizeof e->doc.sys->title)
        return ec_fail(e, "title: longer than %zu bytes", sizeof e->doc.sys->title - 1);
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    memset(e->doc.sys->title, 0, sizeof e->doc.sys->title);
    memcpy(e->doc.sys->title, t, strlen(t));
    return ec_end(e, "title \"%s\"", t);
}

int c_units(ed *e, args *a)
{
    static const char *const u[] = {"mm", "cm", "in", "m"};
    size_t i;
    if (!ec_need(e, a, 1, 1, "units mm|cm|in|m"))
        return ED_HANDLED | ED_ERROR;
    for (i = 0; i < 4; i++)
        if (strcasecmp(a->v[1], u[i]) == 0)
            break;
    if (i == 4)
        return ec_fail(e, "units: \"%s\" is not mm, cm, in or m", a->v[1]);
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    memset(e->doc.sys->units, 0, sizeof e->doc.sys->units);
    memcpy(e->doc.sys->units, u[i], strlen(u[i]));
    return ec_end(e, "units %s", u[i]);
}

static int wl_check(ed *e, double um, double w)
{
    if (!(um > 0.0) || !isfinite(um))
        return ec_fail(e, "wavelength: %g um is not positive", um), 0;
    if (!(um >= 0.1 && um <= 100.0))
        return ec_fail(e, "wavelength: %g um is outside 0.1 to 100 um; it is in micrometres",
                    um), 0;
    if (!(w >= 0.0))
        return ec_fail(e, "wavelength: weight %g is negative", w), 0;
    return 1;
}

/* Spectral lines by their Fraunhofer letters, in micrometres, as Schott's
 * catalog lists them (TIE-29; the d, F and C of Abbe numbers). */
static const struct line_name {
    const char *name;
    double um;
} spectral_lines[] = {
    {"i", 0.3650146}, {"h", 0.4046561}, {"g", 0.4358343}, {"F'", 0.4799914},
    {"F", 0.4861327}, {"e", 0.5460740}, {"d", 0.5875618}, {"D", 0.5892938},
    {"C'", 0.6438469}, {"C", 0.6562725}, {"r", 0.7065188}, {"s", 0.85211},
    {"t", 1.01398},
};
#define NLINES (sizeof spectral_lines / sizeof spectral_lines[0])

/* A wavelength in um, or a line's letter (case matters: d is not D). */
int ec_parse_um(ed *e, const char *s, double *um)
{
    size_t i;
    for (i = 0; i < NLINES; i++)
        if (strcmp(s, spectral_lines[i].name) == 0) {
            *um = spectral_lines[i].um;
            return 1;
        }
    return ec_parse_num(e, s, "wavelength", um);
}

/* Presets as Zemax's wavelength dialog offers them; the primary is the
 * line in the middle, as there. */
static const struct preset {
    const char *name;
    const char *lines[3];
    int primary;
} presets[] = {
    {"FdC", {"F", "d", "C"}, 1},
    {"F'eC'", {"F'", "e", "C'"}, 1},
    {"d", {"d", NULL, NULL}, 0},
    {"e", {"e", NULL, NULL}, 0},
};

int c_wavelength(ed *e, args *a)
{
    sg_system *s = e->doc.sys;
    const char *usage = "wavelength add UM|LINE [WEIGHT] | set N UM|LINE [WEIGHT] | delete N | "
                        "primary N | move N TO | preset FdC|F'eC'|d|e";
    const char *sub = a->n > 1 ? a->v[1] : "";
    double um, w = 1.0;
    int k;
    if (strcasecmp(sub, "preset") == 0) {
        size_t p, j;
        if (!ec_need(e, a, 2, 2, usage))
            return ED_HANDLED | ED_ERROR;
        for (p = 0; p < sizeof presets / sizeof presets[0]; p++)
            if (strcasecmp(a->v[2], presets[p].name) == 0)
                break;
        if (p == sizeof presets / sizeof presets[0])
            return ec_fail(e, "wavelength preset: \"%s\" is not FdC, F'eC', d or e", a->v[2]);
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        memset(s->wave, 0, sizeof s->wave);
        for (j = 0; j < 3 && presets[p].lines[j]; j++) {
            ec_parse_um(e, presets[p].lines[j], &s->wave[j].um);
            s->wave[j].weight = 1.0;
        }
        s->nwave = (int)j;
        s->primary_wave = presets[p].primary;
        e->wave = s->primary_wave;
        return ec_end(e, "wavelengths %s (primary %s)", presets[p].name,
                   presets[p].lines[presets[p].primary]);
    }
    if (strcasecmp(sub, "move") == 0) {
        int to, i;
        sg_wave moved;
        if (!ec_need(e, a, 3, 3, usage) ||
            !ec_parse_int(e, a->v[2], "wavelength", 1, s->nwave, &k) ||
            !ec_parse_int(e, a->v[3], "to", 1, s->nwave, &to))
            return ED_HANDLED | ED_ERROR;
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        k--;
        to--;
        moved = s->wave[k];
        /* The primary and the traced wavelength stay the same light. */
        {
            int prim = s->primary_wave, cur = e->wave;
            if (k < to) {
                for (i = k; i < to; i++)
                    s->wave[i] = s->wave[i + 1];
            } else {
                for (i = k; i > to; i--)
                    s->wave[i] = s->wave[i - 1];
            }
            s->wave[to] = moved;
#define FOLLOW(x) ((x) == k ? to : k < to && (x) > k && (x) <= to ? (x) - 1 \
                   : to < k && (x) >= to && (x) < k ? (x) + 1 : (x))
            s->primary_wave = FOLLOW(prim);
            e->wave = FOLLOW(cur);
#undef FOLLOW
        }
        return ec_end(e, "wavelength %d is now %d", k + 1, to + 1);
    }
    if (strcasecmp(sub, "add") == 0) {
        if (!ec_need(e, a, 2, 3, usage) || !ec_parse_um(e, a->v[2], &um) ||
            (a->n > 3 && !ec_parse_num(e, a->v[3], "weight", &w)) || !wl_check(e, um, w))
            return ED_HANDLED | ED_ERROR;
        if (s->nwave >= SG_MAX_WAVES)
            return ec_fail(e, "a design holds at most %d wavelengths", SG_MAX_WAVES);
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        s->wave[s->nwave].um = um;
        s->wave[s->nwave].weight = w;
        s->nwave++;
        return ec_end(e, "wavelength %d: %.10g um", s->nwave, um);
    }
    if (strcasecmp(sub, "set") == 0) {
        if (!ec_need(e, a, 3, 4, usage) ||
            !ec_parse_int(e, a->v[2], "wavelength", 1, s->nwave, &k) ||
            !ec_parse_um(e, a->v[3], &um))
            return ED_HANDLED | ED_ERROR;
        w = s->wave[k - 1].weight;
        if ((a->n > 4 && !ec_parse_num(e, a->v[4], "weight", &w)) || !wl_check(e, um, w))
            return ED_HANDLED | ED_ERROR;
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->wave[k - 1].um = um;
        e->doc.sys->wave[k - 1].weight = w;
        return ec_end(e, "wavelength %d: %.10g um", k, um);
    }
    if (strcasecmp(sub, "delete") == 0 || strcasecmp(sub, "del") == 0) {
        int i;
        if (!ec_need(e, a, 2, 2, usage) ||
            !ec_parse_int(e, a->v[2], "wavelength", 1, s->nwave, &k))
            return ED_HANDLED | ED_ERROR;
        if (s->nwave == 1)
            return ec_fail(e, "the only wavelength cannot be deleted");
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        for (i = k - 1; i + 1 < s->nwave; i++)
            s->wave[i] = s->wave[i + 1];
        s->nwave--;
        memset(&s->wave[s->nwave], 0, sizeof s->wave[0]);
        /* The primary stays the same wavelength when it survives. */
        if (s->primary_wave > k - 1)
            s->primary_wave--;
        if (s->primary_wave >= s->nwave)
            s->primary_wave = s->nwave - 1;
        if (e->wave > k - 1)
            e->wave--;
        return ec_end(e, "deleted wavelength %d", k);
    }
    if (strcasecmp(sub, "primary") == 0) {
        if (!ec_need(e, a, 2, 2, usage) ||
            !ec_parse_int(e, a->v[2], "wavelength", 1, s->nwave, &k))
            return ED_HANDLED | ED_ERROR;
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->primary_wave = k - 1;
        return ec_end(e, "primary wavelength %d", k);
    }
    return ec_fail(e, "usage: %s", usage);
}

static int parse_field_type(const char *s)
{
    if (strcasecmp(s, "angle") == 0)
        return SG_FIELD_ANGLE;
    if (strcasecmp(s, "object") == 0 || strcasecmp(s, "object_height") == 0 ||
        strcasecmp(s, "height") == 0)
        return SG_FIELD_OBJECT_HEIGHT;
    if (strcasecmp(s, "paraximage") == 0 || strcasecmp(s, "paraxial_image_height") == 0)
        return SG_FIELD_PARAX_IMAGE_HEIGHT;
    if (strcasecmp(s, "realimage") == 0 || strcasecmp(s, "real_image_height") == 0)
        return SG_FIELD_REAL_IMAGE_HEIGHT;
    return -1;
}

static int field_check(ed *e, int type, double x, double y, double w)
{
    if (type == SG_FIELD_ANGLE && (fabs(x) >= 90.0 || fabs(y) >= 90.0))
        return ec_fail(e, "field: angle (%g, %g) must be below 90 degrees", x, y), 0;
    if (!(w >= 0.0))
        return ec_fail(e, "field: weight %g is negative", w), 0;
    return 1;
}

int c_field(ed *e, args *a)
{
    sg_system *s = e->doc.sys;
    const char *usage = "field type angle|object|paraximage|realimage | norm radial|rect | "
                        "add X Y [WEIGHT] | set N X Y [WEIGHT] | delete N | "
                        "vignette N VDX VDY VCX VCY [VAN] | setvig | clearvig";
    const char *sub = a->n > 1 ? a->v[1] : "";
    double x, y, w = 1.0;
    int k, i;
    if (a->n == 2 && isdigit((unsigned char)sub[0])) {
        /* field N: the ray of Zemax's ray trace dialog, at field N. */
        double fx, fy;
        if (!ec_parse_int(e, sub, "field", 1, s->nfield, &k))
            return ED_HANDLED | ED_ERROR;
        ed_field_scale(s, &fx, &fy);
        e->ray[0] = fx > 0.0 ? s->field[k - 1].x / fx : 0.0;
        e->ray[1] = fy > 0.0 ? s->field[k - 1].y / fy : 0.0;
        e->dirty = 1;
        {
            char hx[NUMFMT_MAX], hy[NUMFMT_MAX], fxs[NUMFMT_MAX], fys[NUMFMT_MAX];
            numfmt_shortest(e->ray[0], hx, sizeof hx);
            numfmt_shortest(e->ray[1], hy, sizeof hy);
            numfmt_shortest(s->field[k - 1].x, fxs, sizeof fxs);
            numfmt_shortest(s->field[k - 1].y, fys, sizeof fys);
            ed_msg(e, 0, "field %d (%s, %s %s): Hx %s Hy %s", k, fxs, fys,
                   ed_field_unit(s), hx, hy);
        }
        return OK_VIEW;
    }
    if (strcasecmp(sub, "type") == 0) {
        if (!ec_need(e, a, 2, 2, usage))
            return ED_HANDLED | ED_ERROR;
        k = parse_field_type(a->v[2]);
        if (k < 0)
            return ec_fail(e, "field type: \"%s\" is not angle, object, paraximage or realimage",
                        a->v[2]);
        if (k == SG_FIELD_ANGLE && s->telecentric)
            return ec_fail(e, "field type: a telecentric object space has height fields, not "
                        "angles (telecentric off first)");
        if (k == SG_FIELD_ANGLE)
            for (i = 0; i < s->nfield; i++)
                if (!field_check(e, k, s->field[i].x, s->field[i].y, 1.0))
                    return ED_HANDLED | ED_ERROR;
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->field_type = (sg_field_type)k;
        return ec_end(e, "field type %s", ed_field_type_name(k));
    }
    if (strcasecmp(sub, "norm") == 0 || strcasecmp(sub, "normalization") == 0) {
        if (!ec_need(e, a, 2, 2, usage))
            return ED_HANDLED | ED_ERROR;
        if (strcasecmp(a->v[2], "radial") == 0)
            k = SG_NORM_RADIAL;
        else if (strcasecmp(a->v[2], "rect") == 0 || strcasecmp(a->v[2], "rectangular") == 0)
            k = SG_NORM_RECT;
        else
            return ec_fail(e, "field norm: \"%s\" is not radial or rect", a->v[2]);
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->field_norm = (sg_field_norm)k;
        return ec_end(e, "field normalization %s", ed_field_norm_name(k));
    }
    if (strcasecmp(sub, "add") == 0) {
        if (!ec_need(e, a, 3, 4, usage) || !ec_parse_num(e, a->v[2], "field x", &x) ||
            !ec_parse_num(e, a->v[3], "field y", &y) ||
            (a->n > 4 && !ec_parse_num(e, a->v[4], "weight", &w)) ||
            !field_check(e, s->field_type, x, y, w))
            return ED_HANDLED | ED_ERROR;
        if (s->nfield >= SG_MAX_FIELDS)
            return ec_fail(e, "a design holds at most %d fields", SG_MAX_FIELDS);
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        sg_param_defaults(SG_SCOPE_FIELD, &s->field[s->nfield]);
        s->field[s->nfield].x = x;
        s->field[s->nfield].y = y;
        s->field[s->nfield].weight = w;
        s->nfield++;
        return ec_end(e, "field %d: (%s, %s)", s->nfield, a->v[2], a->v[3]);
    }
    if (strcasecmp(sub, "set") == 0) {
        if (!ec_need(e, a, 4, 5, usage) || !ec_parse_int(e, a->v[2], "field", 1, s->nfield, &k) ||
            !ec_parse_num(e, a->v[3], "field x", &x) || !ec_parse_num(e, a->v[4], "field y", &y))
            return ED_HANDLED | ED_ERROR;
        w = s->field[k - 1].weight;
        if ((a->n > 5 && !ec_parse_num(e, a->v[5], "weight", &w)) ||
            !field_check(e, s->field_type, x, y, w))
            return ED_HANDLED | ED_ERROR;
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        s->field[k - 1].x = x;
        s->field[k - 1].y = y;
        s->field[k - 1].weight = w;
        return ec_end(e, "field %d: (%s, %s)", k, a->v[3], a->v[4]);
    }
    if (strcasecmp(sub, "vignette") == 0 || strcasecmp(sub, "vig") == 0) {
        /* Zemax's VDX VDY VCX VCY VAN, rows of the engine's field table. */
        static const char *const keys[] = {"vdx", "vdy", "vcx", "vcy", "van"};
        double v[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
        char msg[160];
        if (!ec_need(e, a, 6, 7, usage) || !ec_parse_int(e, a->v[2], "field", 1, s->nfield, &k))
            return ED_HANDLED | ED_ERROR;
        for (i = 0; i < 5 && 3 + i < a->n; i++) {
            const sg_param *p = sg_param_find(SG_SCOPE_FIELD, keys[i]);
            if (!ec_parse_num(e, a->v[3 + i], keys[i], &v[i]))
                return ED_HANDLED | ED_ERROR;
            if (sg_param_check(p, 0, v[i], 0, msg, sizeof msg) != SG_OK)
                return ec_fail(e, "field %d: %s", k, msg);
        }
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        for (i = 0; i < 5; i++)
            sg_param_set(sg_param_find(SG_SCOPE_FIELD, keys[i]), &s->field[k - 1], 0, v[i]);
        return ec_end(e, "field %d: vignetting VDX %g VDY %g VCX %g VCY %g VAN %g", k, v[0], v[1],
                   v[2], v[3], v[4]);
    }
    if (strcasecmp(sub, "setvig") == 0) {
        /* Zemax's Set Vignetting: every field's factors from the apertures,
         * as one edit (one undo). */
        sg_vigfactors vf[SG_MAX_FIELDS];
        sg_setvig_opts o;
        sg_diag d;
        if (!ec_need(e, a, 1, 1, usage))
            return ED_HANDLED | ED_ERROR;
        if (!e->cat)
            return ec_fail(e, "no glass catalog: %s", e->cat_msg);
        sg_setvig_opts_init(&o);
        sg_diag_clear(&d);
        if (sg_set_vignetting(s, e->cat, &o, vf, &d) != SG_OK)
            return ec_fail(e, "field setvig: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        sg_set_vignetting_apply(s, vf);
        return ec_end(e, "vignetting factors set for %d field%s from the apertures (field N shows "
                   "them)", s->nfield, s->nfield == 1 ? "" : "s");
    }
    if (strcasecmp(sub, "clearvig") == 0) {
        if (!ec_need(e, a, 1, 1, usage))
            return ED_HANDLED | ED_ERROR;
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        for (i = 0; i < s->nfield; i++)
            s->field[i].vdx = s->field[i].vdy = s->field[i].vcx = s->field[i].vcy =
                s->field[i].van = 0.0;
        return ec_end(e, "vignetting factors cleared");
    }
    if (strcasecmp(sub, "delete") == 0 || strcasecmp(sub, "del") == 0) {
        if (!ec_need(e, a, 2, 2, usage) || !ec_parse_int(e, a->v[2], "field", 1, s->nfield, &k))
            return ED_HANDLED | ED_ERROR;
        if (s->nfield == 1)
            return ec_fail(e, "the only field cannot be deleted");
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        for (i = k - 1; i + 1 < s->nfield; i++)
            s->field[i] = s->field[i + 1];
        s->nfield--;
        memset(&s->field[s->nfield], 0, sizeof s->field[0]);
        return ec_end(e, "deleted field %d", k);
    }
    return ec_fail(e, "usage: %s", usage);
}

static int parse_aper(const char *s)
{
    static const char *const n[][3] = {
        {"epd", "entrance", NULL},
        {"fnum", "image_fnum", "f/#"},
        {"na", "object_na", "objna"},
        {"float", "float_by_stop", "stop"},
        {"pwfnum", "paraxial_working_fnum", "working"},
        {"cone", "object_cone_angle", "coneangle"},
    };
    int i, j;
    for (i = 0; i < 6; i++)
        for (j = 0; j < 3; j++)
            if (n[i][j] && strcasecmp(s, n[i][j]) == 0)
                return i;
    return -1;
}

int c_aperture(ed *e, args *a)
{
    const char *usage = "aperture epd|fnum|na|float|pwfnum|cone [VALUE] | aperture VALUE";
    int type = e->doc.sys->aper_type, vi = 1;
    double v = e->doc.sys->aper_value;
    char shown[NUMFMT_MAX];
    if (!ec_need(e, a, 1, 2, usage))
        return ED_HANDLED | ED_ERROR;
    if (parse_aper(a->v[1]) >= 0) {
        type = parse_aper(a->v[1]);
        vi = 2;
    } else if (a->n > 2) {
        return ec_fail(e, "aperture: \"%s\" is not epd, fnum, na, float, pwfnum or cone", a->v[1]);
    }
    if (vi < a->n && !ec_parse_num(e, a->v[vi], "aperture value", &v))
        return ED_HANDLED | ED_ERROR;
    if (type != SG_APER_FLOAT_STOP && !(v > 0.0))
        return ec_fail(e, "aperture: value %g must be positive", v);
    if (type == SG_APER_OBJECT_NA && !(v < 1.0))
        return ec_fail(e, "aperture: object NA %g must be below 1", v);
    if (type == SG_APER_OBJECT_CONE && !(v < 90.0))
        return ec_fail(e, "aperture: object cone angle %g must be below 90 degrees", v);
    if ((type == SG_APER_OBJECT_NA || type == SG_APER_OBJECT_CONE) &&
        isinf(e->doc.sys->surf[0].thickness))
        return ec_fail(e, "aperture: an object %s needs a finite object distance",
                    type == SG_APER_OBJECT_NA ? "NA" : "cone angle");
    if (type != SG_APER_OBJECT_NA && type != SG_APER_OBJECT_CONE && e->doc.sys->telecentric)
        return ec_fail(e, "aperture: a telecentric object space's aperture is the object NA or "
                    "cone angle (telecentric off first)");
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->aper_type = (sg_aper_type)type;
    e->doc.sys->aper_value = v;
    numfmt_shortest(v, shown, sizeof shown);
    return ec_end(e, "aperture %s %s", ed_aper_name(type), shown);
}

int c_aim(ed *e, args *a)
{
    int k;
    if (!ec_need(e, a, 1, 1, "aim off|paraxial|real"))
        return ED_HANDLED | ED_ERROR;
    for (k = 0; k < 3; k++)
        if (strcasecmp(a->v[1], ed_aim_name(k)) == 0)
            break;
    if (k == 3)
        return ec_fail(e, "aim: \"%s\" is not off, paraxial or real", a->v[1]);
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->aim = (sg_aim)k;
    return ec_end(e, "ray aiming %s", ed_aim_name(k));
}

/* Zemax's "Telecentric Object Space": the entrance pupil at infinity.  It
 * needs an object NA, a finite object and height fields, as in Zemax. */
int c_telecentric(ed *e, args *a)
{
    const sg_system *s = e->doc.sys;
    int on;
    if (!ec_need(e, a, 0, 1, "telecentric on|off|toggle") ||
        !ec_parse_switch(e, a->n > 1 ? a->v[1] : NULL, s->telecentric, &on, "telecentric"))
        return ED_HANDLED | ED_ERROR;
    if (on && s->aper_type != SG_APER_OBJECT_NA && s->aper_type != SG_APER_OBJECT_CONE)
        return ec_fail(e, "telecentric: the aperture must be the object NA or cone angle "
                    "(aperture na VALUE, aperture cone DEGREES)");
    if (on && isinf(s->surf[0].thickness))
        return ec_fail(e, "telecentric: the object must be at a finite distance");
    if (on && s->field_type == SG_FIELD_ANGLE)
        return ec_fail(e, "telecentric: the fields must be heights (field type object, "
                    "paraximage or realimage)");
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->telecentric = on;
    return ec_end(e, "object space %s", on ? "telecentric: the entrance pupil at infinity"
                                        : "not telecentric");
}

/* The environment: Zemax's system temperature and pressure, and whether
 * glass indices follow them (sagitta-design(5), GLASS INDICES). */
int c_temperature(ed *e, args *a)
{
    double t;
    if (!ec_need(e, a, 1, 1, "temperature CELSIUS") ||
        !ec_parse_num(e, a->v[1], "temperature", &t))
        return ED_HANDLED | ED_ERROR;
    if (!(t >= SG_TEMP_MIN && t <= SG_TEMP_MAX))
        return ec_fail(e, "temperature: %g C is outside %g to %g C", t, SG_TEMP_MIN, SG_TEMP_MAX);
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->temperature = t;
    return ec_end(e, "temperature %g C%s", t,
               e->doc.sys->adjust_index ? "" : " (glass indices follow it after \"adjust on\")");
}

/* Zemax's thermal analysis on the design: the lens as built at another
 * temperature (sg_thermal), one edit and one undo. */
int c_thermal(ed *e, args *a)
{
    double t, p;
    sg_system *hot;
    sg_diag d;
    double from;
    if (!ec_need(e, a, 1, 2, "thermal CELSIUS [ATM]") ||
        !ec_parse_num(e, a->v[1], "temperature", &t))
        return ED_HANDLED | ED_ERROR;
    p = e->doc.sys->pressure;
    if (a->n == 3 && !ec_parse_num(e, a->v[2], "pressure", &p))
        return ED_HANDLED | ED_ERROR;
    if (!(t >= SG_TEMP_MIN && t <= SG_TEMP_MAX))
        return ec_fail(e, "thermal: temperature %g C is outside %g to %g C", t, SG_TEMP_MIN,
                    SG_TEMP_MAX);
    if (!(p >= 0.0 && p <= SG_PRES_MAX))
        return ec_fail(e, "thermal: pressure %g atm is outside 0 to %g atm", p, SG_PRES_MAX);
    if (!e->cat)
        return ec_fail(e, "no glass catalog: %s", e->cat_msg);
    if (!(hot = sg_system_new()))
        return ec_fail(e, "out of memory: the change was not made");
    sg_diag_clear(&d);
    if (sg_thermal(e->doc.sys, e->cat, t, p, hot, &d) != SG_OK) {
        sg_system_free(hot);
        return ec_fail(e, "thermal: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
    }
    from = e->doc.sys->temperature;
    if (!ec_begin(e, e->row) || sg_system_assign(e->doc.sys, hot) != SG_OK) {
        if (e->doc.open_change)
            doc_cancel(&e->doc);
        sg_system_free(hot);
        return ec_fail(e, "out of memory: the change was not made");
    }
    sg_system_free(hot);
    return ec_end(e, "thermal: the lens as built at %g C, %g atm (from %g C)%s%s", t, p, from,
               d.nwarn ? "; " : "", d.nwarn ? d.warn[0] : "");
}

/* Zemax's automatic semi-diameters: every surface whose semi-diameter is
 * not fixed gets the highest edge ray's height there, as one edit (one
 * undo).  A surface no ray reaches keeps its value. */
int c_semidiam(ed *e, args *a)
{
    double *sd;
    sg_diag d;
    sg_system *s;
    int i, set = 0, kept = 0;
    if (!ec_need(e, a, 0, 0, "semidiam"))
        return ED_HANDLED | ED_ERROR;
    if (!e->cat)
        return ec_fail(e, "no glass catalog: %s", e->cat_msg);
    if (!(sd = calloc((size_t)e->doc.sys->nsurf, sizeof *sd)))
        return ec_fail(e, "out of memory: the change was not made");
    sg_diag_clear(&d);
    if (sg_semi_diameters(e->doc.sys, e->cat, NULL, sd, &d) != SG_OK) {
        free(sd);
        return ec_fail(e, "semidiam: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
    }
    if (!ec_begin(e, e->row)) {
        free(sd);
        return ED_HANDLED | ED_ERROR;
    }
    s = e->doc.sys;
    for (i = 1; i < s->nsurf; i++) {
        if (s->surf[i].sd_fixed)
            continue;
        if (sd[i] > 0.0) {
            s->surf[i].semi_diameter = sd[i];
            set++;
        } else
            kept++;
    }
    free(sd);
    return ec_end(e, "semidiam: %d automatic semi-diameter%s set from the edge rays%s", set,
               set == 1 ? "" : "s",
               kept ? " (surfaces no ray reaches kept theirs)" : "");
}

int c_pressure(ed *e, args *a)
{
    double p;
    if (!ec_need(e, a, 1, 1, "pressure ATM") || !ec_parse_num(e, a->v[1], "pressure", &p))
        return ED_HANDLED | ED_ERROR;
    if (!(p >= 0.0 && p <= SG_PRES_MAX))
        return ec_fail(e, "pressure: %g atm is outside 0 to %g atm", p, SG_PRES_MAX);
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->pressure = p;
    return ec_end(e, "pressure %g atm", p);
}

int c_adjust(ed *e, args *a)
{
    int on;
    if (!ec_need(e, a, 0, 1, "adjust on|off|toggle") ||
        !ec_parse_switch(e, a->n > 1 ? a->v[1] : NULL, e->doc.sys->adjust_index, &on, "adjust"))
        return ED_HANDLED | ED_ERROR;
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->adjust_index = on;
    return ec_end(e, "glass indices %s", on ? "follow the temperature and pressure"
                                         : "are the catalog's");
}

/* The glass picker: "glasses N-BK" by name, "glasses 1.5168 64.17" by nd
 * and vd; "pick N" makes hit N the material of the cursor's surface. */
int c_glasses(ed *e, args *a)
{
    char q[ED_LINE];
    const sg_system *s = e->doc.sys;
    double um = s->wave[s->primary_wave].um;
    int n, i;
    if (!e->cat)
        return ec_fail(e, "no glass catalog: %s", e->cat_msg);
    if (a->n > 1)
        ec_rest_of(a, 1, q, sizeof q);
    else
        q[0] = '\0';
    n = gp_search(e->cat, s, um, q, &e->glasses);
    if (n < 0)
        return ec_fail(e, "glasses: out of memory");
    e->glass_sel = 0;
    if (e->batch) {
        for (i = 0; i < n; i++) {
            const gp_hit *h = &e->glasses.hit[i];
            fprintf(e->out, "%d %s %s %.17g %.17g %.17g\n", i + 1, h->g->name, h->g->catalog,
                    h->g->nd, h->g->vd, h->n);
        }
        fflush(e->out);
    }
    ed_msg(e, 0, "%d glass%s for \"%s\", n at %g um; \"pick N\" sets surface %d's material", n,
           n == 1 ? "" : "es", q, um, e->row);
    return ED_HANDLED | ED_REDRAW | (e->batch || n == 0 ? 0 : ED_SHOW_GLASSES);
}

int c_pick(ed *e, args *a)
{
    double k;
    char line[ED_LINE];
    const sg_glass *g;
    if (!ec_need(e, a, 1, 1, "pick N") || !ec_parse_num(e, a->v[1], "pick", &k))
        return ED_HANDLED | ED_ERROR;
    if (e->glasses.n == 0)
        return ec_fail(e, "pick: no glasses listed; search with \"glasses NAME\" or "
                       "\"glasses ND VD\" first");
    if (k != floor(k) || k < 1 || k > e->glasses.n)
        return ec_fail(e, "pick: %g is not one of 1 to %d", k, e->glasses.n);
    if (e->row < 1 || e->row >= e->doc.sys->nsurf - 1)
        return ec_fail(e, "pick: the cursor is on surface %d; a glass goes on surfaces 1 to %d",
                     e->row, e->doc.sys->nsurf - 2);
    /* Through "set", so undo, messages and checks are the cell's; the
     * catalog is named when the name alone means another's glass. */
    g = e->glasses.hit[(int)k - 1].g;
    if (g == sg_catalog_find(e->cat, g->name))
        snprintf(line, sizeof line, "set %d material %s", e->row, g->name);
    else
        snprintf(line, sizeof line, "set %d material %s:%s", e->row, g->catalog, g->name);
    return cmd_exec(e, line);
}
