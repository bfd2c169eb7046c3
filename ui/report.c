/* report.c - ray-trace and paraxial results as text, CSV or JSON. */
#include "report.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

int report_parse_fmt(const char *s)
{
    if (!s)
        return -1;
    if (strcmp(s, "text") == 0)
        return REPORT_TEXT;
    if (strcmp(s, "csv") == 0)
        return REPORT_CSV;
    if (strcmp(s, "json") == 0)
        return REPORT_JSON;
    return -1;
}

const char *report_status_name(int status)
{
    const char *name;
    switch (status) {
    case SG_OK: return "OK";
    case SG_EMISS: return "MISS";
    case SG_ETIR: return "TIR";
    case SG_EVIGNETTED: return "VIGNETTED";
    case SG_ENOCONV: return "NOCONV";
    case SG_ENOTREACHED: return "NOT REACHED";
    case SG_EAIM: return "AIM FAILED";
    case SG_ERANGE: return "OUT OF RANGE";
    default:
        name = sg_err_name(status);
        return strncmp(name, "SG_E", 4) == 0 ? name + 4 : name;
    }
}

/* The status of a whole ray when the caller has no return code: the first
 * surface that failed, as the trace functions themselves report it. */
static int ray_status(const sg_ray_surface *s, int nsurf, const int *status,
                      size_t r)
{
    int i;
    if (status)
        return status[r];
    for (i = 0; i < nsurf; i++)
        if (s[i].status != SG_OK)
            return s[i].status;
    return SG_OK;
}

static int first_failure(const sg_ray_surface *s, int nsurf)
{
    int i;
    for (i = 0; i < nsurf; i++)
        if (s[i].status != SG_OK && s[i].status != SG_ENOTREACHED)
            return i;
    return -1;
}

/* Shortest %g text that reads back as the same double, for header lines
 * meant for people (0.55, not 0.55000000000000004). */
static const char *shortest(double v, char *buf, size_t n)
{
    int prec;
    if (isinf(v))
        return v > 0 ? "Infinity" : "-Infinity";
    if (isnan(v))
        return "undefined";
    for (prec = 1; prec <= 17; prec++) {
        snprintf(buf, n, "%.*g", prec, v);
        if (strtod(buf, NULL) == v)
            break;
    }
    return buf;
}

/* Scientific text of fixed width for the tables.  A NaN should not reach
 * a report; if one does, it reads as a word rather than "nan". */
static const char *sci(double v, int prec, char *buf, size_t n)
{
    if (isinf(v))
        return v > 0 ? "Infinity" : "-Infinity";
    if (isnan(v))
        return "undefined";
    snprintf(buf, n, "%.*e", prec, v);
    return buf;
}

static const char *const norm_label[4] = { "Hx", "Hy", "Px", "Py" };
static const char *const sd_json[6] = { "x", "y", "z", "l", "m", "n" };
static const char *const norm_json[4] = { "hx", "hy", "px", "py" };

/* ---------------------------------------------------------------- text */

static void text_ray_line(FILE *f, sg_ray_kind kind, const sg_ray_in *ray)
{
    char b[6][40];
    int k;
    if (kind == SG_RAYS_NORMALIZED) {
        fputs("Ray         :", f);
        for (k = 0; k < 4; k++)
            fprintf(f, " %s = %s%s", norm_label[k], shortest(ray->v[k], b[k], sizeof b[k]),
                    k < 3 ? "," : "\n");
    } else {
        fprintf(f, "Start       : x = %s, y = %s, z = %s (surface 1 frame)\n",
                shortest(ray->v[0], b[0], sizeof b[0]),
                shortest(ray->v[1], b[1], sizeof b[1]),
                shortest(ray->v[2], b[2], sizeof b[2]));
        fprintf(f, "Direction   : l = %s, m = %s, n = %s\n",
                shortest(ray->v[3], b[3], sizeof b[3]),
                shortest(ray->v[4], b[4], sizeof b[4]),
                shortest(ray->v[5], b[5], sizeof b[5]));
    }
}

static void text_status_line(FILE *f, const sg_ray_surface *s, int nsurf, int st)
{
    int at = first_failure(s, nsurf);
    if (st == SG_OK)
        fputs("Status      : OK\n", f);
    else if (at >= 0)
        fprintf(f, "Status      : %s at surface %d (%s)\n", report_status_name(st),
                at, sg_strerror(st));
    else
        fprintf(f, "Status      : %s (%s)\n", report_status_name(st), sg_strerror(st));
}

static void text_table(FILE *f, const sg_ray_surface *s, int nsurf)
{
    int i;
    fprintf(f, "%4s %23s %23s %23s %23s %23s %23s %10s %10s %23s  %s\n", "Surf",
            "X", "Y", "Z", "L", "M", "N", "Residual", "ErrBound", "Path", "Status");
    for (i = 0; i < nsurf; i++) {
        const sg_ray_surface *e = &s[i];
        char label[16], b[9][40];
        if (i == 0)
            strcpy(label, "OBJ");
        else if (i == nsurf - 1)
            strcpy(label, "IMA");
        else
            snprintf(label, sizeof label, "%d", i);
        if (e->status != SG_OK) {
            /* The numbers of a failed surface mean nothing; the name of
             * the failure stands in their place. */
            fprintf(f, "%4s %23s\n", label, report_status_name(e->status));
            continue;
        }
        fprintf(f, "%4s %23s %23s %23s %23s %23s %23s %10s %10s %23s  %s\n", label,
                sci(e->x, 15, b[0], sizeof b[0]), sci(e->y, 15, b[1], sizeof b[1]),
                sci(e->z, 15, b[2], sizeof b[2]), sci(e->l, 15, b[3], sizeof b[3]),
                sci(e->m, 15, b[4], sizeof b[4]), sci(e->n, 15, b[5], sizeof b[5]),
                sci(e->residual, 3, b[6], sizeof b[6]),
                sci(e->error_bound, 3, b[7], sizeof b[7]),
                sci(e->path, 15, b[8], sizeof b[8]), "OK");
    }
}

static void text_write(FILE *f, const report_meta *m, int nsurf,
                       const sg_ray_surface *out, const int *status, size_t nray,
                       sg_ray_kind kind, const sg_ray_in *rays)
{
    char b[40];
    size_t r;

    fputs(nray == 1 ? "Single ray trace\n" : "Ray trace\n", f);
    fprintf(f, "Design      : %s\n", m && m->design ? m->design : "(untitled)");
    if (m && m->method) {
        if (m->bits > 0)
            fprintf(f, "Method      : %s, %d bits\n", m->method, m->bits);
        else
            fprintf(f, "Method      : %s\n", m->method);
    }
    if (m)
        fprintf(f, "Wavelength  : %s um (wave %d)\n",
                shortest(m->wave_um, b, sizeof b), m->wave_index);
    fputs("Coordinates are in each surface's local frame; L, M, N are the "
          "direction cosines after the surface.\n", f);
    if (nray > 1)
        fprintf(f, "Rays        : %zu\n", nray);
    for (r = 0; r < nray; r++) {
        const sg_ray_surface *s = out + r * (size_t)nsurf;
        fputc('\n', f);
        if (nray > 1)
            fprintf(f, "Ray %zu\n", r);
        if (rays)
            text_ray_line(f, kind, &rays[r]);
        text_status_line(f, s, nsurf, ray_status(s, nsurf, status, r));
        fputc('\n', f);
        text_table(f, s, nsurf);
    }
}

/* ----------------------------------------------------------- CSV, JSON */

/* A number as CSV and JSON carry it: %.17g, so it reads back exactly.
 * JSON has no infinity, so both formats spell it as the string strtod and
 * most readers accept; JSON gets it quoted. */
static void put_num(FILE *f, double v, int json)
{
    if (isnan(v))
        fputs(json ? "null" : "", f);
    else if (isinf(v))
        fputs(json ? (v > 0 ? "\"inf\"" : "\"-inf\"") : (v > 0 ? "inf" : "-inf"), f);
    else
        fprintf(f, "%.17g", v);
}

static void csv_write(FILE *f, int nsurf, const sg_ray_surface *out, size_t nray)
{
    size_t r;
    int i;
    fputs(nray > 1 ? "ray,surface,x,y,z,l,m,n,residual,error_bound,path,status\n"
                   : "surface,x,y,z,l,m,n,residual,error_bound,path,status\n",
          f);
    for (r = 0; r < nray; r++)
        for (i = 0; i < nsurf; i++) {
            const sg_ray_surface *e = &out[r * (size_t)nsurf + (size_t)i];
            if (nray > 1)
                fprintf(f, "%zu,", r);
            fprintf(f, "%d,", i);
            if (e->status == SG_OK) {
                const double v[9] = { e->x, e->y, e->z, e->l, e->m, e->n,
                                      e->residual, e->error_bound, e->path };
                int k;
                for (k = 0; k < 9; k++) {
                    put_num(f, v[k], 0);
                    fputc(',', f);
                }
            } else {
                fputs(",,,,,,,,,", f);
            }
            fprintf(f, "%s\n", report_status_name(e->status));
        }
}

/* Writes s as a JSON string; cJSON does the escaping. */
static int put_str(FILE *f, const char *s)
{
    cJSON *j = cJSON_CreateString(s ? s : "");
    char *t = j ? cJSON_PrintUnformatted(j) : NULL;
    cJSON_Delete(j);
    if (!t) {
        errno = ENOMEM;
        return -1;
    }
    fputs(t, f);
    cJSON_free(t);
    return 0;
}

static int json_meta(FILE *f, const report_meta *m)
{
    fputs("  \"design\": ", f);
    if (m && m->design) {
        if (put_str(f, m->design) < 0)
            return -1;
    } else {
        fputs("null", f);
    }
    if (m && m->method) {
        fputs(",\n  \"method\": ", f);
        if (put_str(f, m->method) < 0)
            return -1;
    }
    if (m && m->bits > 0)
        fprintf(f, ",\n  \"bits\": %d", m->bits);
    if (m) {
        fputs(",\n  \"wavelength_um\": ", f);
        put_num(f, m->wave_um, 1);
        fprintf(f, ",\n  \"wave\": %d", m->wave_index);
    }
    return 0;
}

static void json_input(FILE *f, sg_ray_kind kind, const sg_ray_in *ray)
{
    int k, n = kind == SG_RAYS_NORMALIZED ? 4 : 6;
    const char *const *names = kind == SG_RAYS_NORMALIZED ? norm_json : sd_json;
    fputc('{', f);
    for (k = 0; k < n; k++) {
        fprintf(f, "%s\"%s\": ", k ? ", " : "", names[k]);
        put_num(f, ray->v[k], 1);
    }
    fputc('}', f);
}

static void json_surfaces(FILE *f, const sg_ray_surface *s, int nsurf,
                          const char *indent)
{
    int i;
    fputs("[\n", f);
    for (i = 0; i < nsurf; i++) {
        const sg_ray_surface *e = &s[i];
        static const char *const key[9] = { "x", "y", "z", "l", "m", "n",
                                            "residual", "error_bound", "path" };
        const double v[9] = { e->x, e->y, e->z, e->l, e->m, e->n,
                              e->residual, e->error_bound, e->path };
        int k;
        fprintf(f, "%s  {\"surface\": %d", indent, i);
        for (k = 0; k < 9; k++) {
            fprintf(f, ", \"%s\": ", key[k]);
            if (e->status == SG_OK)
                put_num(f, v[k], 1);
            else
                fputs("null", f);
        }
        fprintf(f, ", \"status\": \"%s\"}%s\n", report_status_name(e->status),
                i + 1 < nsurf ? "," : "");
    }
    fprintf(f, "%s]", indent);
}

static int json_write(FILE *f, const report_meta *m, int nsurf,
                      const sg_ray_surface *out, const int *status, size_t nray,
                      sg_ray_kind kind, const sg_ray_in *rays)
{
    size_t r;
    fputs("{\n", f);
    if (json_meta(f, m) < 0)
        return -1;
    if (nray == 1) {
        if (rays) {
            fputs(",\n  \"input\": ", f);
            json_input(f, kind, &rays[0]);
        }
        fprintf(f, ",\n  \"status\": \"%s\",\n  \"surfaces\": ",
                report_status_name(ray_status(out, nsurf, status, 0)));
        json_surfaces(f, out, nsurf, "  ");
        fputs("\n}\n", f);
        return 0;
    }
    fputs(",\n  \"rays\": [\n", f);
    for (r = 0; r < nray; r++) {
        const sg_ray_surface *s = out + r * (size_t)nsurf;
        fprintf(f, "    {\"ray\": %zu", r);
        if (rays) {
            fputs(", \"input\": ", f);
            json_input(f, kind, &rays[r]);
        }
        fprintf(f, ", \"status\": \"%s\", \"surfaces\": ",
                report_status_name(ray_status(s, nsurf, status, r)));
        json_surfaces(f, s, nsurf, "    ");
        fprintf(f, "}%s\n", r + 1 < nray ? "," : "");
    }
    fputs("  ]\n}\n", f);
    return 0;
}

/* stdio keeps the first write error sticky, so checking once at the end
 * (after a flush) catches a full disk anywhere in the report. */
static int finish(FILE *f)
{
    if (fflush(f) != 0)
        return -1;
    if (ferror(f)) {
        if (errno == 0)
            errno = EIO;
        return -1;
    }
    return 0;
}

int report_write(FILE *f, report_fmt fmt, const report_meta *m, int nsurf,
                 const sg_ray_surface *out, const int *status, size_t nray,
                 sg_ray_kind kind, const sg_ray_in *rays)
{
    if (!f || nsurf < 0 || (nray > 0 && !out)) {
        errno = EINVAL;
        return -1;
    }
    switch (fmt) {
    case REPORT_TEXT:
        text_write(f, m, nsurf, out, status, nray, kind, rays);
        break;
    case REPORT_CSV:
        csv_write(f, nsurf, out, nray);
        break;
    case REPORT_JSON:
        if (json_write(f, m, nsurf, out, status, nray, kind, rays) < 0)
            return -1;
        break;
    default:
        errno = EINVAL;
        return -1;
    }
    return finish(f);
}

/* ------------------------------------------------------------ paraxial */

struct pfield {
    const char *label; /* text */
    const char *key;   /* JSON and CSV */
    size_t off;
};

#define PF_(label, key, member) { label, key, offsetof(sg_paraxial, member) }
static const struct pfield pfields[] = {
    PF_("Effective focal length", "efl", efl),
    PF_("Back focal length", "bfl", bfl),
    PF_("Paraxial image distance", "image_distance", image_dist),
    PF_("Entrance pupil diameter", "entrance_pupil_diameter", epd),
    PF_("Entrance pupil position", "entrance_pupil_position", enp_pos),
    PF_("Exit pupil diameter", "exit_pupil_diameter", exp_diam),
    PF_("Exit pupil position", "exit_pupil_position", exp_pos),
    PF_("Image space F/#", "image_fnum", image_fnum),
    PF_("Paraxial working F/#", "working_fnum", working_fnum),
    PF_("Object space NA", "object_na", object_na),
    PF_("Paraxial image height", "paraxial_image_height", parax_image_height),
    PF_("Paraxial magnification", "magnification", magnification),
    PF_("Total track", "total_track", total_track),
    PF_("Paraxial stop radius", "stop_radius", stop_radius),
};
#undef PF_
#define NPFIELDS (sizeof pfields / sizeof pfields[0])

static double pget(const sg_paraxial *p, size_t k)
{
    double v;
    memcpy(&v, (const char *)p + pfields[k].off, sizeof v);
    return v;
}

int report_write_paraxial(FILE *f, report_fmt fmt, const report_meta *m,
                          const sg_paraxial *p)
{
    size_t k;
    char b[40];
    if (!f || !p) {
        errno = EINVAL;
        return -1;
    }
    switch (fmt) {
    case REPORT_TEXT:
        fprintf(f, "%-24s:  %s\n", "Design", m && m->design ? m->design : "(untitled)");
        if (m)
            fprintf(f, "%-24s:  %s um (wave %d)\n", "Wavelength",
                    shortest(m->wave_um, b, sizeof b), m->wave_index);
        for (k = 0; k < NPFIELDS; k++) {
            double v = pget(p, k);
            fprintf(f, "%-24s:  ", pfields[k].label);
            if (isinf(v) || isnan(v))
                fputs(isnan(v) ? "undefined" : v > 0 ? "Infinity" : "-Infinity", f);
            else
                fprintf(f, "%.17g", v);
            fputc('\n', f);
        }
        break;
    case REPORT_CSV:
        fputs("quantity,value\n", f);
        for (k = 0; k < NPFIELDS; k++) {
            fprintf(f, "%s,", pfields[k].key);
            put_num(f, pget(p, k), 0);
            fputc('\n', f);
        }
        break;
    case REPORT_JSON:
        fputs("{\n", f);
        if (json_meta(f, m) < 0)
            return -1;
        for (k = 0; k < NPFIELDS; k++) {
            fprintf(f, ",\n  \"%s\": ", pfields[k].key);
            put_num(f, pget(p, k), 1);
        }
        fputs("\n}\n", f);
        break;
    default:
        errno = EINVAL;
        return -1;
    }
    return finish(f);
}
