/*
 * analysis.c - "sagitta spot", "sagitta fan" and "sagitta layout": an
 * analysis of the engine (src/analysis/spot.c, fan.c, layout.c) written as text
 * (with a picture on a terminal), CSV, JSON, or a PNG, SVG or PDF picture.
 * Every output goes through outfile, so a file appears whole or not at all.
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ancmd.h"
#include "numfmt.h"
#include "plot.h"
#include "progress.h"
#include "safetext.h"
#include "views.h"

enum { AN_SPOT, AN_FAN, AN_LAYOUT, AN_WAVEFRONT };

enum { O_PATTERN = 1 };

static const int zernike_kinds[] = {SG_ZERNIKE_FRINGE, SG_ZERNIKE_STANDARD};
static const int spot_refs[] = {SG_SPOT_REF_CHIEF, SG_SPOT_REF_CENTROID};

static const char *const an_name[] = {"spot", "fan", "layout", "wavefront"};

static void an_help(int kind, FILE *f)
{
    static const char *const what[] = {
        "Spot diagrams: where a pupil pattern of rays meets the image, per field\n"
        "and wavelength, with RMS and GEO radii, the centroid and the Airy radius.\n",
        "Transverse ray fans: ey against Py and ex against Px on the image, per\n"
        "field and wavelength, relative to the primary wavelength's chief ray;\n"
        "with --opd, OPD fans: the OPD in waves against Py and Px.\n",
        "Layout: a y-z cross-section of the surfaces over their semi-diameters\n"
        "and fans of rays in y from each field.\n",
        "Wavefront: the OPD map over the pupil of one field at one wavelength\n"
        "against the reference sphere, its RMS and P-V (to the chief ray, and\n"
        "with piston and tilt removed) and its Zernike coefficients.\n"};
    fprintf(f, "Usage: sagitta %s DESIGN.json [OPTIONS]\n%s\n", an_name[kind], what[kind]);
    fputs(AN_COMMON_HELP "  --field N          one field (default: every field)\n", f);
    if (kind == AN_WAVEFRONT)
        fputs("  --wave N           the wavelength (default: the primary); --field\n"
              "                     defaults to field 1\n"
              "  --grid N           points across the pupil (default 64)\n"
              "  --zernike Z        fringe (default) or standard\n"
              "  --terms N          Zernike terms, 1 to 37 (default 37)\n", f);
    else if (kind != AN_LAYOUT)
        fputs("  --wave N           one wavelength (default: every wavelength)\n", f);
    else
        fputs("  --wave N           the wavelength traced (default: the primary)\n", f);
    if (kind == AN_SPOT)
        fputs("  --pattern P        hexapolar (default), square or vogel\n"
              "  --density N        rings (hexapolar, default 6), grid size (square),\n"
              "                     or rays (vogel)\n"
              "  --reference R      chief (default) or centroid\n", f);
    if (kind == AN_FAN)
        fputs("  --points N         rays on each fan from -1 to 1 (default 21)\n"
              "  --opd              OPD fans (waves) instead of transverse ray fans\n", f);
    if (kind == AN_LAYOUT)
        fputs("  --rays N           rays per field from Py = -1 to 1 (default 7)\n", f);
    fputs("  --method M         precise (default), classic or mpfr\n"
          "  --threads N        0 (default) uses every core\n"
          "  --no-clip          do not vignette rays outside fixed semi-diameters\n"
          "  -h, --help         show this help\n"
          "\nText on a terminal includes a picture (braille dots, a colour per\n"
          "wavelength unless NO_COLOR is set).  See sagitta(1).\n", f);
}

/* A number for CSV: the shortest decimal that reads back to the same
 * double (0.4861327, not %.17g's 0.48613269999999997), so nothing is lost;
 * -0 is written 0. */
static void num(FILE *f, double v)
{
    char b[NUMFMT_SHORTEST_MAX];
    if (!isfinite(v)) {
        fprintf(f, "%.17g", v);
        return;
    }
    fwrite(b, 1, numfmt_shortest_g(v == 0.0 ? 0.0 : v, b), f);
}

/* ---- spot ---- */

/* A centroid smaller than its own error bound (the mean of its rays'
 * bounds and the sums' rounding, sg_spot_cell), or a Zernike coefficient
 * within its bound (sg_wavefront), is noise, not an offset:
 * it is printed as 0, never as -0 (sagitta(1), spot). */
static double denoise(double v, double bound)
{
    return fabs(v) <= bound ? 0.0 : v;
}

static void spot_text(FILE *f, const sg_system *sys, const sg_spot *s, const sg_spot_opts *o)
{
    double ext = s->airy_radius, sc;
    const char *u;
    char t[200];
    int fi, w;
    for (fi = 0; fi < s->nfield; fi++)
        ext = fmax(ext, s->field[fi].geo);
    u = view_length_unit(sys, ext, &sc);
    fprintf(f, "Spot diagram: %s\n", safe_text(sys->title, t, sizeof t));
    fprintf(f, "Pattern %s, density %d, %zu rays per field and wavelength; reference: %s\n",
            sg_pupil_pattern_name(o->pattern), o->density, s->nray_per_cell,
            o->reference == SG_SPOT_REF_CHIEF ? "chief ray" : "centroid");
    if (sys->afocal)
        fputs("Afocal image space: no Airy radius\n\n", f);
    else
        fprintf(f, "Airy radius %.6g %s (1.22 x %.6g µm x working F/#)\n\n",
                s->airy_radius * sc, u, sys->wave[o->wave >= 0 ? o->wave : sys->primary_wave].um);
    fprintf(f, "%-26s %-12s %8s %14s %14s %14s %14s\n", "Field", "Wavelength", "Rays",
            "RMS", "GEO", "Centroid x", "Centroid y");
    for (fi = 0; fi < s->nfield; fi++) {
        char fl[64];
        const sg_spot_field *fd = &s->field[fi];
        view_field_label(sys, s->field_index[fi], fl, sizeof fl);
        if (fd->status != SG_OK) {
            char why[200];
            fprintf(f, "%-26s chief ray: %s\n", fl,
                    fd->fail_surface >= 0
                        ? sg_ray_stop_text(sys, fd->fail_surface, fd->status, why, sizeof why)
                        : sg_strerror(fd->status));
            continue;
        }
        for (w = 0; w < s->nwave; w++) {
            const sg_spot_cell *c = &s->cell[fi * s->nwave + w];
            char wl[32], rays[32];
            view_wave_label(s->wave_um[w], wl, sizeof wl);
            snprintf(rays, sizeof rays, "%zu", c->nok);
            fprintf(f, "%-26s %-12s %8s %11.6g %s %11.6g %s %14.8g %14.8g\n", w ? "" : fl, wl,
                    rays, c->rms * sc, u, c->geo * sc, u,
                    denoise(c->centroid_x, c->centroid_bound_x),
                    denoise(c->centroid_y, c->centroid_bound_y));
        }
        if (s->nwave > 1)
            fprintf(f, "%-26s %-12s %8s %11.6g %s %11.6g %s %14.8g %14.8g\n", "", "all", "",
                    fd->rms * sc, u, fd->geo * sc, u,
                    denoise(fd->centroid_x, fd->centroid_bound_x),
                    denoise(fd->centroid_y, fd->centroid_bound_y));
    }
    if (sys->afocal)
        fputs("(afocal image space: angles are differences of direction cosines from the "
              "chief ray's; centroids as direction cosines)\n", f);
    else
        fprintf(f, "(centroids in %s on the image surface)\n", sys->units);
}

static void spot_csv(FILE *f, const sg_spot *s)
{
    int fi, w;
    fputs("field,hx,hy,wave,um,rays,reached,chief_x,chief_y,centroid_x,centroid_y,"
          "ref_x,ref_y,rms,geo,status\n", f);
    for (fi = 0; fi < s->nfield; fi++) {
        const sg_spot_field *fd = &s->field[fi];
        for (w = 0; w <= s->nwave; w++) {
            int all = w == s->nwave;
            const sg_spot_cell *c = all ? NULL : &s->cell[fi * s->nwave + w];
            if (all && s->nwave == 1)
                break;
            fprintf(f, "%d,", s->field_index[fi] + 1);
            num(f, fd->hx);
            fputc(',', f);
            num(f, fd->hy);
            if (all)
                fputs(",all,,", f);
            else {
                fprintf(f, ",%d,", s->wave_index[w] + 1);
                num(f, s->wave_um[w]);
                fputc(',', f);
            }
            if (all)
                fputs(",,,,", f);
            else {
                fprintf(f, "%zu,%zu,", c->nray, c->nok);
                num(f, c->chief_x);
                fputc(',', f);
                num(f, c->chief_y);
                fputc(',', f);
            }
            num(f, all ? denoise(fd->centroid_x, fd->centroid_bound_x)
                       : denoise(c->centroid_x, c->centroid_bound_x));
            fputc(',', f);
            num(f, all ? denoise(fd->centroid_y, fd->centroid_bound_y)
                       : denoise(c->centroid_y, c->centroid_bound_y));
            fputc(',', f);
            num(f, fd->ref_x);
            fputc(',', f);
            num(f, fd->ref_y);
            fputc(',', f);
            num(f, all ? fd->rms : c->rms);
            fputc(',', f);
            num(f, all ? fd->geo : c->geo);
            fprintf(f, ",%s\n", sg_err_name(all ? fd->status : c->status));
        }
    }
}

static cJSON *spot_json(const sg_system *sys, const sg_spot *s, const sg_spot_opts *o)
{
    cJSON *root = cJSON_CreateObject(), *fields = cJSON_AddArrayToObject(root, "fields");
    int fi, w;
    cJSON_AddStringToObject(root, "analysis", "spot");
    cJSON_AddStringToObject(root, "units", sys->units);
    cJSON_AddStringToObject(root, "pattern", sg_pupil_pattern_name(o->pattern));
    cJSON_AddNumberToObject(root, "density", o->density);
    cJSON_AddNumberToObject(root, "rays_per_cell", (double)s->nray_per_cell);
    cJSON_AddStringToObject(root, "reference",
                            o->reference == SG_SPOT_REF_CHIEF ? "chief" : "centroid");
    cJSON_AddNumberToObject(root, "airy_radius", s->airy_radius);
    for (fi = 0; fi < s->nfield; fi++) {
        const sg_spot_field *fd = &s->field[fi];
        cJSON *jf = cJSON_CreateObject(), *ws;
        cJSON_AddNumberToObject(jf, "field", s->field_index[fi] + 1);
        cJSON_AddNumberToObject(jf, "hx", fd->hx);
        cJSON_AddNumberToObject(jf, "hy", fd->hy);
        cJSON_AddStringToObject(jf, "status", sg_err_name(fd->status));
        cJSON_AddNumberToObject(jf, "ref_x", fd->ref_x);
        cJSON_AddNumberToObject(jf, "ref_y", fd->ref_y);
        cJSON_AddNumberToObject(jf, "rms", fd->rms);
        cJSON_AddNumberToObject(jf, "geo", fd->geo);
        cJSON_AddNumberToObject(jf, "centroid_x",
                                denoise(fd->centroid_x, fd->centroid_bound_x));
        cJSON_AddNumberToObject(jf, "centroid_y",
                                denoise(fd->centroid_y, fd->centroid_bound_y));
        ws = cJSON_AddArrayToObject(jf, "waves");
        for (w = 0; w < s->nwave; w++) {
            const sg_spot_cell *c = &s->cell[fi * s->nwave + w];
            cJSON *jw = cJSON_CreateObject();
            cJSON_AddNumberToObject(jw, "wave", s->wave_index[w] + 1);
            cJSON_AddNumberToObject(jw, "um", s->wave_um[w]);
            cJSON_AddNumberToObject(jw, "rays", (double)c->nray);
            cJSON_AddNumberToObject(jw, "reached", (double)c->nok);
            cJSON_AddNumberToObject(jw, "chief_x", c->chief_x);
            cJSON_AddNumberToObject(jw, "chief_y", c->chief_y);
            cJSON_AddNumberToObject(jw, "centroid_x",
                                    denoise(c->centroid_x, c->centroid_bound_x));
            cJSON_AddNumberToObject(jw, "centroid_y",
                                    denoise(c->centroid_y, c->centroid_bound_y));
            cJSON_AddNumberToObject(jw, "rms", c->rms);
            cJSON_AddNumberToObject(jw, "geo", c->geo);
            cJSON_AddItemToArray(ws, jw);
        }
        cJSON_AddItemToArray(fields, jf);
    }
    return root;
}

/* ---- fan ---- */

static void fan_rows(FILE *f, const sg_system *sys, const sg_fan *fan, int csv)
{
    int fi, w, j, side;
    double sc = 1.0;
    const char *u = sys->units;
    if (csv)
        fputs(fan->opd ? "field,wave,um,fan,p,opd_waves,status\n"
                       : "field,wave,um,fan,p,e,status\n", f);
    else {
        double ext = 0.0;
        for (j = 0; j < fan->nfield * fan->nwave; j++)
            for (side = 0; side < 2; side++) {
                const sg_fan_curve *c = side ? &fan->sag[j] : &fan->tan[j];
                int i;
                for (i = 0; i < fan->npts; i++)
                    if (c->status[i] == SG_OK)
                        ext = fmax(ext, fabs(c->e[i]));
            }
        u = view_length_unit(sys, ext, &sc);
        if (fan->opd) {
            /* OPD in waves of each curve's wavelength. */
            u = "waves";
            sc = 1.0;
        }
        fprintf(f, "%-26s %-12s %-11s %8s %16s  %s\n", "Field", "Wavelength", "Fan", "P",
                fan->opd ? "OPD" : "e", "Status");
    }
    for (fi = 0; fi < fan->nfield; fi++)
        for (w = 0; w < fan->nwave; w++)
            for (side = 0; side < 2; side++) {
                const sg_fan_curve *c = side ? &fan->sag[fi * fan->nwave + w]
                                             : &fan->tan[fi * fan->nwave + w];
                char fl[64], wl[32];
                view_field_label(sys, fan->field_index[fi], fl, sizeof fl);
                view_wave_label(fan->wave_um[w], wl, sizeof wl);
                for (j = 0; j < fan->npts; j++) {
                    if (csv) {
                        fprintf(f, "%d,%d,", fan->field_index[fi] + 1, fan->wave_index[w] + 1);
                        num(f, fan->wave_um[w]);
                        fprintf(f, ",%s,", side ? "sagittal" : "tangential");
                        num(f, c->p[j]);
                        fputc(',', f);
                        if (c->status[j] == SG_OK)
                            num(f, c->e[j]);
                        fprintf(f, ",%s\n", sg_err_name(c->status[j]));
                    } else if (c->status[j] == SG_OK) {
                        fprintf(f, "%-26s %-12s %-11s %8.4f %13.6g %s  OK\n", fl, wl,
                                side ? "sagittal" : "tangential", c->p[j], c->e[j] * sc, u);
                    } else {
                        fprintf(f, "%-26s %-12s %-11s %8.4f %16s  %s\n", fl, wl,
                                side ? "sagittal" : "tangential", c->p[j], "-",
                                sg_strerror(c->status[j]));
                    }
                }
            }
}

static cJSON *fan_json(const sg_system *sys, const sg_fan *fan)
{
    cJSON *root = cJSON_CreateObject(), *fans = cJSON_AddArrayToObject(root, "fans");
    int fi, w, side;
    cJSON_AddStringToObject(root, "analysis", "fan");
    cJSON_AddStringToObject(root, "kind", fan->opd ? "opd" : "ray");
    cJSON_AddStringToObject(root, "units", fan->opd ? "waves" : sys->units);
    for (fi = 0; fi < fan->nfield; fi++)
        for (w = 0; w < fan->nwave; w++)
            for (side = 0; side < 2; side++) {
                const sg_fan_curve *c = side ? &fan->sag[fi * fan->nwave + w]
                                             : &fan->tan[fi * fan->nwave + w];
                cJSON *o = cJSON_CreateObject(), *p, *e, *st;
                int j;
                cJSON_AddNumberToObject(o, "field", fan->field_index[fi] + 1);
                cJSON_AddNumberToObject(o, "wave", fan->wave_index[w] + 1);
                cJSON_AddNumberToObject(o, "um", fan->wave_um[w]);
                cJSON_AddStringToObject(o, "fan", side ? "sagittal" : "tangential");
                cJSON_AddNumberToObject(o, "ref_x", fan->ref_x[fi]);
                cJSON_AddNumberToObject(o, "ref_y", fan->ref_y[fi]);
                p = cJSON_AddArrayToObject(o, side ? "px" : "py");
                e = cJSON_AddArrayToObject(o, fan->opd ? "opd" : side ? "ex" : "ey");
                st = cJSON_AddArrayToObject(o, "status");
                for (j = 0; j < fan->npts; j++) {
                    cJSON_AddItemToArray(p, cJSON_CreateNumber(c->p[j]));
                    cJSON_AddItemToArray(e, c->status[j] == SG_OK ? cJSON_CreateNumber(c->e[j])
                                                                  : cJSON_CreateNull());
                    cJSON_AddItemToArray(st, cJSON_CreateString(sg_err_name(c->status[j])));
                }
                cJSON_AddItemToArray(fans, o);
            }
    return root;
}

/* ---- layout ---- */

static void layout_rows(FILE *f, const sg_system *sys, const sg_layout *l, int csv)
{
    int i, j;
    if (csv)
        fputs("kind,index,field,py,point,y,z\n", f);
    else
        fprintf(f, "Layout: surfaces 1 to %d, %d rays; lengths in %s\n%-8s %16s %14s %s\n",
                l->nsurf - 1, l->nray, sys->units, "Surface", "Vertex z", "Semi-diam",
                "Kind");
    for (i = 0; i < l->nsurf - 1; i++) {
        const sg_layout_surface *s = &l->surf[i];
        if (!csv) {
            fprintf(f, "%-8d %16.10g %14.8g %s\n", i + 1, s->z0, s->sd,
                    s->mirror ? "mirror" : s->glass_after ? "into glass" : "");
            continue;
        }
        for (j = 0; j < s->npts; j++) {
            fprintf(f, "surface,%d,,,%d,", i + 1, j);
            num(f, s->y[j]);
            fputc(',', f);
            num(f, s->z[j]);
            fputc('\n', f);
        }
    }
    if (!csv)
        return;
    for (i = 0; i < l->nray; i++)
        for (j = 0; j < l->ray[i].npts; j++) {
            fprintf(f, "ray,%d,%d,", i + 1, l->field_index[l->ray[i].field] + 1);
            num(f, l->ray[i].py);
            fprintf(f, ",%d,", j + 1);
            num(f, l->ray[i].y[j]);
            fputc(',', f);
            num(f, l->ray[i].z[j]);
            fputc('\n', f);
        }
}

static cJSON *layout_json(const sg_system *sys, const sg_layout *l)
{
    cJSON *root = cJSON_CreateObject(), *ss = cJSON_AddArrayToObject(root, "surfaces"),
          *rs = cJSON_AddArrayToObject(root, "rays");
    int i;
    cJSON_AddStringToObject(root, "analysis", "layout");
    cJSON_AddStringToObject(root, "units", sys->units);
    for (i = 0; i < l->nsurf - 1; i++) {
        const sg_layout_surface *s = &l->surf[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "surface", i + 1);
        cJSON_AddNumberToObject(o, "z0", s->z0);
        cJSON_AddNumberToObject(o, "semi_diameter", s->sd);
        cJSON_AddBoolToObject(o, "mirror", s->mirror);
        cJSON_AddItemToObject(o, "y", cJSON_CreateDoubleArray(s->y, s->npts));
        cJSON_AddItemToObject(o, "z", cJSON_CreateDoubleArray(s->z, s->npts));
        cJSON_AddItemToArray(ss, o);
    }
    for (i = 0; i < l->nray; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "field", l->field_index[l->ray[i].field] + 1);
        cJSON_AddNumberToObject(o, "py", l->ray[i].py);
        cJSON_AddStringToObject(o, "status", sg_err_name(l->ray[i].status));
        cJSON_AddItemToObject(o, "y", cJSON_CreateDoubleArray(l->ray[i].y, l->ray[i].npts));
        cJSON_AddItemToObject(o, "z", cJSON_CreateDoubleArray(l->ray[i].z, l->ray[i].npts));
        cJSON_AddItemToArray(rs, o);
    }
    return root;
}

/* ---- wavefront ---- */

static void wave_label_of(const sg_system *sys, int wave1, char *wl, size_t n)
{
    view_wave_label(sys->wave[wave1 > 0 ? wave1 - 1 : sys->primary_wave].um, wl, n);
}

static void wavefront_text(FILE *f, const sg_system *sys, const sg_wavefront *w,
                           const sg_opd_ref *ref, int field1, int wave1)
{
    char t[200], fl[64], wl[32];
    int j;
    view_field_label(sys, field1 - 1, fl, sizeof fl);
    wave_label_of(sys, wave1, wl, sizeof wl);
    fprintf(f, "Wavefront: %s\n", safe_text(sys->title, t, sizeof t));
    fprintf(f, "%s, %s; grid %d x %d, %zu rays in the pupil\n", fl, wl, w->grid, w->grid,
            w->nvalid);
    fprintf(f, "Reference sphere: centre (%.10g, %.10g) on the image, radius %.10g %s\n",
            ref->cx, ref->cy, ref->radius, sys->units);
    fprintf(f, "OPD in waves of %s\n\n", wl);
    fprintf(f, "%-44s %14s %14s\n", "", "RMS", "P-V");
    fprintf(f, "%-44s %14.8g %14.8g\n", "to chief (piston removed)", w->rms_chief,
            w->pv_chief);
    fprintf(f, "%-44s %14.8g %14.8g\n", "to centroid (piston and tilt removed)",
            w->rms_centroid, w->pv_centroid);
    fprintf(f, "\n%s Zernike coefficients (waves):\n",
            w->kind == SG_ZERNIKE_FRINGE ? "Fringe" : "Standard");
    for (j = 1; j <= w->nterms; j++) {
        int n = 0, m = 0;
        sg_zernike_nm(w->kind, j, &n, &m);
        fprintf(f, "  Z%-3d n %2d m %3d %16.8g\n", j, n, m,
                denoise(w->coef[j - 1], w->coef_bound[j - 1]));
    }
    fprintf(f, "Fit residual RMS: %.8g waves\n", w->fit_rms);
}

static void wavefront_csv(FILE *f, const sg_wavefront *w)
{
    int i, j;
    fputs("i,j,px,py,opd_waves\n", f);
    for (j = 0; j < w->grid; j++)
        for (i = 0; i < w->grid; i++) {
            size_t k = (size_t)j * (size_t)w->grid + (size_t)i;
            fprintf(f, "%d,%d,", i, j);
            num(f, -1.0 + 2.0 * i / (w->grid - 1));
            fputc(',', f);
            num(f, -1.0 + 2.0 * j / (w->grid - 1));
            fputc(',', f);
            if (w->valid[k])
                num(f, w->map[k]);
            fputc('\n', f);
        }
}

static cJSON *wavefront_json(const sg_system *sys, const sg_wavefront *w,
                             const sg_opd_ref *ref, int field1, int wave1)
{
    cJSON *root = cJSON_CreateObject(), *z, *map;
    int i, j;
    cJSON_AddStringToObject(root, "analysis", "wavefront");
    cJSON_AddStringToObject(root, "units", sys->units);
    cJSON_AddNumberToObject(root, "field", field1);
    cJSON_AddNumberToObject(root, "hx", ref->hx);
    cJSON_AddNumberToObject(root, "hy", ref->hy);
    cJSON_AddNumberToObject(root, "wave", wave1 > 0 ? wave1 : sys->primary_wave + 1);
    cJSON_AddNumberToObject(root, "um", sys->wave[wave1 > 0 ? wave1 - 1 : sys->primary_wave].um);
    cJSON_AddNumberToObject(root, "grid", w->grid);
    cJSON_AddNumberToObject(root, "rays", (double)w->nvalid);
    cJSON_AddNumberToObject(root, "sphere_radius", ref->radius);
    cJSON_AddNumberToObject(root, "rms_chief", w->rms_chief);
    cJSON_AddNumberToObject(root, "pv_chief", w->pv_chief);
    cJSON_AddNumberToObject(root, "rms_centroid", w->rms_centroid);
    cJSON_AddNumberToObject(root, "pv_centroid", w->pv_centroid);
    z = cJSON_AddObjectToObject(root, "zernike");
    cJSON_AddStringToObject(z, "kind", w->kind == SG_ZERNIKE_FRINGE ? "fringe" : "standard");
    {
        double c[SG_WAVEFRONT_MAXTERMS];
        for (i = 0; i < w->nterms; i++)
            c[i] = denoise(w->coef[i], w->coef_bound[i]);
        cJSON_AddItemToObject(z, "coef", cJSON_CreateDoubleArray(c, w->nterms));
        cJSON_AddItemToObject(z, "coef_bound", cJSON_CreateDoubleArray(w->coef_bound, w->nterms));
    }
    cJSON_AddNumberToObject(z, "fit_rms", w->fit_rms);
    /* map[j][i]: py = -1 + 2 j / (grid - 1), px likewise; null outside the
     * pupil or where the ray failed. */
    map = cJSON_AddArrayToObject(root, "map");
    for (j = 0; j < w->grid; j++) {
        cJSON *row = cJSON_CreateArray();
        for (i = 0; i < w->grid; i++) {
            size_t k = (size_t)j * (size_t)w->grid + (size_t)i;
            cJSON_AddItemToArray(row, w->valid[k] ? cJSON_CreateNumber(w->map[k])
                                                  : cJSON_CreateNull());
        }
        cJSON_AddItemToArray(map, row);
    }
    return root;
}

/* ---- the command ---- */

/* One command's results, for its writer. */
typedef struct an_res {
    int kind, field1, wave1;
    const char *design;
    const sg_system *sys;
    sg_spot spot;
    sg_spot_opts so;
    sg_fan fan;
    sg_layout lay;
    sg_wavefront wf;
    sg_opd_ref wref;
} an_res;

static int res_fig(void *ctx, plot_figure *fig)
{
    const an_res *r = ctx;
    const sg_system *sys = r->sys;
    switch (r->kind) {
    case AN_SPOT:
        return view_spot_figure(sys, &r->spot, fig);
    case AN_FAN:
        return view_fan_figure(sys, &r->fan, fig);
    case AN_WAVEFRONT:
        return view_wavefront_figure(
            sys, &r->wf, &r->wref, r->field1 - 1,
            sys->wave[r->wave1 > 0 ? r->wave1 - 1 : sys->primary_wave].um, fig);
    default:
        return view_layout_figure(sys, &r->lay, fig);
    }
}

static int res_text(void *ctx, FILE *f, int fmt)
{
    const an_res *r = ctx;
    const sg_system *sys = r->sys;
    if (fmt == AN_FMT_JSON) {
        cJSON *j = r->kind == AN_SPOT  ? spot_json(sys, &r->spot, &r->so)
                   : r->kind == AN_FAN ? fan_json(sys, &r->fan)
                   : r->kind == AN_WAVEFRONT
                       ? wavefront_json(sys, &r->wf, &r->wref, r->field1, r->wave1)
                       : layout_json(sys, &r->lay);
        char *s;
        if (j)
            cJSON_AddStringToObject(j, "design", r->design);
        s = j ? cJSON_Print(j) : NULL;
        if (s) {
            fputs(s, f);
            fputc('\n', f);
        }
        free(s);
        cJSON_Delete(j);
        return s ? 0 : -1;
    }
    if (r->kind == AN_SPOT) {
        if (fmt == AN_FMT_CSV)
            spot_csv(f, &r->spot);
        else
            spot_text(f, sys, &r->spot, &r->so);
    } else if (r->kind == AN_FAN) {
        fan_rows(f, sys, &r->fan, fmt == AN_FMT_CSV);
    } else if (r->kind == AN_WAVEFRONT) {
        if (fmt == AN_FMT_CSV)
            wavefront_csv(f, &r->wf);
        else
            wavefront_text(f, sys, &r->wf, &r->wref, r->field1, r->wave1);
    } else {
        layout_rows(f, sys, &r->lay, fmt == AN_FMT_CSV);
    }
    return 0;
}

static int run(int kind, int argc, char **argv)
{
    cli_iter it;
    const char *val, *cmd = an_name[kind];
    int id, rc, wave1 = 0, field1 = 0, method = SG_METHOD_PRECISE;
    int pattern = SG_PUPIL_HEXAPOLAR, density = 6, ref = SG_SPOT_REF_CHIEF, points = 21;
    int nrays = 7, threads = 0, noclip = 0;
    int grid = 64, zkind = SG_ZERNIKE_FRINGE, terms = 37, opdfan = 0;
    ui_progress pg;
    sg_wavefront_opts wo;
    sg_fan_opts fo;
    sg_layout_opts lo;
    sg_trace_opts to;
    sg_diag d;
    an_cmd a;
    an_res r;
    an_writer w = {res_fig, res_text, &r};

    const cli_opt an_opts[] = {
        AN_COMMON_OPTS,
        CLI_OPT_INT("--wave", 0, wave1, 1, SG_MAX_WAVES),
        CLI_OPT_INT("--field", 0, field1, 1, SG_MAX_FIELDS),
        CLI_OPT_METHOD(method),
        /* The engine owns the pattern names. */
        CLI_ID("--pattern", 0, 1, O_PATTERN),
        CLI_OPT_INT_FOR("--density", density, 1, SG_PUPIL_MAX_DENSITY, "spot"),
        CLI_OPT_WORD_FOR("--reference", ref, "chief|centroid", spot_refs, "spot"),
        CLI_OPT_INT_FOR("--points", points, 2, 1000000, "fan"),
        CLI_OPT_INT_FOR("--rays", nrays, 1, 10000, "layout"),
        CLI_OPT_INT("--threads", 0, threads, 0, 256),
        CLI_OPT_FLAG("--no-clip", 0, noclip),
        CLI_OPT_INT_FOR("--grid", grid, 3, 4096, "wavefront"),
        CLI_OPT_WORD_FOR("--zernike", zkind, "fringe|standard", zernike_kinds, "wavefront"),
        CLI_OPT_INT_FOR("--terms", terms, 1, SG_WAVEFRONT_MAXTERMS, "wavefront"),
        CLI_OPT_FLAG_FOR("--opd", opdfan, "fan"),
        CLI_END
    };

    memset(&r, 0, sizeof r);
    an_cmd_init(&a, cmd);
    cli_iter_init(&it, cmd, argc, argv);
    while ((id = an_cmd_next(&a, &it, an_opts, &val)) >= 0) {
        switch (id) {
        case AN_OPT_HELP:
            an_help(kind, stdout);
            return CLI_EXIT_OK;
        case O_PATTERN:
            pattern = sg_pupil_pattern_parse(val);
            if (pattern < 0 || kind != AN_SPOT)
                return cli_usage_error(cmd, kind != AN_SPOT ? "--pattern is an option of spot only"
                                                            : "--pattern: expected hexapolar, "
                                                              "square or vogel");
            break;
        default:
            return CLI_EXIT_USAGE;
        }
    }
    if (id < -1)
        return -id;
    if (kind == AN_SPOT && a.design) {
        sg_diag_clear(&d);
        if (sg_pupil_check(pattern, density, &d) != SG_OK)
            return cli_usage_error(cmd, "--density: %s", d.msg);
    }
    rc = an_cmd_load(&a);
    if (rc != CLI_EXIT_OK)
        return rc;
    if (wave1 > a.sys->nwave || field1 > a.sys->nfield) {
        rc = cli_usage_error(cmd, "%s: %s %d is not one of 1 to %d", a.design,
                             wave1 > a.sys->nwave ? "--wave" : "--field",
                             wave1 > a.sys->nwave ? wave1 : field1,
                             wave1 > a.sys->nwave ? a.sys->nwave : a.sys->nfield);
        goto done;
    }
    r.kind = kind;
    r.sys = a.sys;
    r.design = a.design;
    r.wave1 = wave1;
    /* The wavefront's text always carries its shaded map. */
    a.text_picture = kind == AN_WAVEFRONT;
    sg_trace_opts_init(&to);
    to.method = (sg_method)method;
    to.clip = !noclip;
    sg_diag_clear(&d);
    if (kind == AN_SPOT) {
        sg_spot_opts_init(&r.so);
        r.so.trace = to;
        r.so.pattern = pattern;
        r.so.density = density;
        r.so.reference = ref;
        r.so.wave = wave1 - 1;
        r.so.field = field1 - 1;
        r.so.nthreads = threads;
        r.so.max_points = 20000;
        ui_progress_init(&pg, "spot", "rays");
        r.so.progress = ui_progress_cb;
        r.so.progress_ctx = &pg;
        rc = sg_spot_compute(a.sys, a.cat, &r.so, &r.spot, &d);
        ui_progress_end(&pg);
    } else if (kind == AN_FAN) {
        sg_fan_opts_init(&fo);
        fo.trace = to;
        fo.npts = points;
        fo.wave = wave1 - 1;
        fo.field = field1 - 1;
        fo.nthreads = threads;
        fo.opd = opdfan;
        /* A picture file's curves get samples where they bend; the
         * tables keep the --points steps. */
        fo.refine = a.fmt >= AN_FMT_PNG;
        rc = sg_fan_compute(a.sys, a.cat, &fo, &r.fan, &d);
    } else if (kind == AN_WAVEFRONT) {
        if (field1 == 0)
            field1 = 1;
        sg_wavefront_opts_init(&wo);
        wo.trace = to;
        wo.trace.wave = wave1 - 1;
        wo.field = field1 - 1;
        wo.grid = grid;
        wo.kind = zkind;
        wo.nterms = terms;
        wo.nthreads = threads;
        ui_progress_init(&pg, "wavefront", "grid points");
        wo.progress = ui_progress_cb;
        wo.progress_ctx = &pg;
        rc = sg_wavefront_trace(a.sys, a.cat, &wo, &r.wf, &r.wref, &d);
        ui_progress_end(&pg);
    } else {
        sg_layout_opts_init(&lo);
        lo.trace = to;
        lo.trace.wave = wave1 - 1;
        lo.nrays = nrays;
        lo.field = field1 - 1;
        lo.nthreads = threads;
        rc = sg_layout_compute(a.sys, a.cat, &lo, &r.lay, &d);
    }
    r.field1 = field1;
    if (rc != SG_OK) {
        rc = an_cmd_engine_error(&a, &d, rc);
        goto done;
    }
    cli_print_warnings(&d, a.design);
    rc = an_cmd_write(&a, &w);
    if (kind == AN_SPOT)
        sg_spot_free(&r.spot);
    else if (kind == AN_FAN)
        sg_fan_free(&r.fan);
    else if (kind == AN_WAVEFRONT)
        sg_wavefront_free(&r.wf);
    else
        sg_layout_free(&r.lay);
done:
    an_cmd_free(&a);
    return rc;
}

int cmd_spot(int argc, char **argv)
{
    return run(AN_SPOT, argc, argv);
}

int cmd_fan(int argc, char **argv)
{
    return run(AN_FAN, argc, argv);
}

int cmd_layout(int argc, char **argv)
{
    return run(AN_LAYOUT, argc, argv);
}

int cmd_wavefront(int argc, char **argv)
{
    return run(AN_WAVEFRONT, argc, argv);
}
