/*
 * fuzz_design.c - libFuzzer harness for the JSON design loader.
 *
 * The bytes go to sg_design_parse().  Whatever happens, the diagnostic must
 * be a terminated string that names the input.  When the design parses:
 * it is validated against the bundled catalog; it is written back with
 * sg_design_to_json(), which must succeed (everything the loader accepts
 * is writable); that text must parse again to the same system, every double
 * bit for bit, and write the identical text.
 *
 * With SAGITTA_FUZZ_TRACE=1 in the environment (run.sh --trace, as the
 * smoke test runs it), small designs that validate are also traced
 * (paraxial data, then rays inside and beyond the field and pupil by every
 * method, at the primary and another wavelength), so that the engine meets
 * every odd value the loader lets through; a surface marked OK must then
 * have finite numbers (only the object row of an object at infinity has
 * infinite coordinates), never NaN or an infinite bound or path.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sagitta.h"

#define NAME "fuzz.json"

static sg_catalog *cat;
static int do_trace;

static void die(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_design: %s\n%s\n", what, detail ? detail : "");
    abort();
}

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    sg_diag d;
    const char *env = getenv("SAGITTA_FUZZ_TRACE");
    (void)argc;
    (void)argv;
    do_trace = env && strcmp(env, "1") == 0;
    cat = sg_catalog_new();
    sg_diag_clear(&d);
    if (!cat || sg_catalog_load_default(cat, &d) != SG_OK || sg_catalog_count(cat) == 0) {
        fprintf(stderr, "fuzz_design: no glass catalog (%s); set SAGITTA_LENSDB\n", d.msg);
        exit(1);
    }
    return 0;
}

/* named: the call knows the input's name, so its failures must show it. */
static void check_diag(const sg_diag *d, int rc, int named)
{
    int k, n = d->nwarn < SG_DIAG_MAXWARN ? d->nwarn : SG_DIAG_MAXWARN;
    if (!memchr(d->msg, '\0', sizeof d->msg))
        die("diagnostic message not terminated", NULL);
    for (k = 0; k < n; k++)
        if (!memchr(d->warn[k], '\0', sizeof d->warn[k]))
            die("warning not terminated", NULL);
    if (rc != SG_OK && (d->code != rc || d->msg[0] == '\0'))
        die("failure without a message, or with another code", d->msg);
    if (named && rc != SG_OK && rc != SG_ENOMEM && !strstr(d->msg, NAME))
        die("message does not name the input", d->msg);
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Every value the format carries, compared bit for bit. */
static const char *compare(const sg_system *a, const sg_system *b)
{
    int i, k;
    if (strcmp(a->title, b->title) || strcmp(a->units, b->units))
        return "title or units";
    if (a->nwave != b->nwave || a->primary_wave != b->primary_wave)
        return "wavelength count or primary";
    for (k = 0; k < a->nwave; k++)
        if (!same_bits(a->wave[k].um, b->wave[k].um) ||
            !same_bits(a->wave[k].weight, b->wave[k].weight))
            return "a wavelength";
    if (a->field_type != b->field_type || a->field_norm != b->field_norm ||
        a->nfield != b->nfield)
        return "field type, normalization or count";
    for (k = 0; k < a->nfield; k++)
        if (!same_bits(a->field[k].x, b->field[k].x) || !same_bits(a->field[k].y, b->field[k].y) ||
            !same_bits(a->field[k].weight, b->field[k].weight))
            return "a field";
    if (a->aper_type != b->aper_type || !same_bits(a->aper_value, b->aper_value) ||
        a->aim != b->aim)
        return "aperture or aiming";
    if (a->stop != b->stop || a->nsurf != b->nsurf)
        return "stop or surface count";
    for (i = 0; i < a->nsurf; i++) {
        const sg_surface *s = &a->surf[i], *t = &b->surf[i];
        if (s->type != t->type || strcmp(s->comment, t->comment) ||
            !same_bits(s->radius, t->radius) || !same_bits(s->thickness, t->thickness) ||
            s->mat.kind != t->mat.kind || !same_bits(s->semi_diameter, t->semi_diameter) ||
            s->sd_fixed != t->sd_fixed || !same_bits(s->conic, t->conic))
            return "a surface";
        if (s->mat.kind == SG_MAT_GLASS && strcmp(s->mat.name, t->mat.name))
            return "a glass name";
        if (s->mat.kind == SG_MAT_INDEX && !same_bits(s->mat.index, t->mat.index))
            return "a fixed index";
        for (k = 0; k < SG_NASPH; k++)
            if (!same_bits(s->asph[k], t->asph[k]))
                return "an asphere term";
        /* Every other row of the parameter table (apertures, ...). */
        if (!sg_param_equal(SG_SCOPE_SURFACE, s, t))
            return "a surface parameter";
    }
    for (k = 0; k < a->nfield; k++)
        if (!sg_param_equal(SG_SCOPE_FIELD, &a->field[k], &b->field[k]))
            return "a field parameter";
    return NULL;
}

/* A failed surface has no numbers; a reached one has finite numbers, and
 * only the object row of an object at infinity infinite coordinates
 * (sagitta(1), OUTPUT FORMATS). */
static void check_rays(const sg_system *sys, const sg_ray_surface *out, int n, int rc)
{
    int i;
    for (i = 0; i < n; i++) {
        const sg_ray_surface *o = &out[i];
        int inf_point = i == 0 && isinf(sys->surf[0].thickness);
        if (o->status < 0 || o->status >= SG_ERRNO_COUNT)
            die("a surface status outside the error table", NULL);
        if (o->status != SG_OK)
            continue;
        if (isnan(o->x) || isnan(o->y) || isnan(o->z) || !isfinite(o->l) || !isfinite(o->m) ||
            !isfinite(o->n))
            die("NaN coordinates on a surface reported OK", NULL);
        if (!inf_point && (!isfinite(o->x) || !isfinite(o->y) || !isfinite(o->z)))
            die("infinite coordinates on a surface reported OK", NULL);
        if (!isfinite(o->residual) || !isfinite(o->error_bound) ||
            !isfinite(o->dir_error_bound) || !isfinite(o->path))
            die("a residual, bound or path that is not finite on a surface reported OK", NULL);
    }
    if (rc == SG_OK && out[n - 1].status != SG_OK)
        die("trace succeeded but the image is not OK", NULL);
}

static void trace_some(const sg_system *sys)
{
    static const sg_method methods[] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR};
    /* Inside the field and pupil, and beyond both: a field past 90
     * degrees must be refused, never wrap. */
    static const double rays[][4] = {{0.0, 1.0, 0.0, 1.0}, {0.7, -0.3, -0.5, 0.5},
                                     {0.0, 20.0, 0.0, 0.0}, {3.0, 0.0, 0.0, -4.0}};
    sg_ray_surface out[64];
    sg_trace_opts o;
    sg_paraxial p;
    sg_diag d;
    size_t m;
    int w;

    if (sys->nsurf > 64)
        return;
    for (w = 0; w < sys->nwave && w < 2; w++) {
        sg_diag_clear(&d);
        check_diag(&d, sg_paraxial_compute(sys, cat, w, &p, &d), 0);
    }
    for (m = 0; m < sizeof methods / sizeof methods[0] * 2; m++) {
        static const double start[3] = {0.0, 1.0, -1.0}, dir[3] = {0.0, 0.01, 1.0};
        sg_tracer *t;
        size_t r;
        int rc;
        sg_trace_opts_init(&o);
        o.method = methods[m % 3];
        o.mpfr_bits = 64;
        /* The second round at the last wavelength, whose pupil and fields
         * are the primary's. */
        o.wave = m < 3 ? -1 : sys->nwave - 1;
        sg_diag_clear(&d);
        t = sg_tracer_new(sys, cat, &o, &d);
        if (!t) {
            if (d.code == SG_OK)
                die("sg_tracer_new failed without a code", NULL);
            continue;
        }
        if (sg_tracer_nsurf(t) != sys->nsurf)
            die("tracer surface count differs from the system's", NULL);
        for (r = 0; r < sizeof rays / sizeof rays[0]; r++) {
            rc = sg_trace_normalized(t, rays[r][0], rays[r][1], rays[r][2], rays[r][3], out);
            check_rays(sys, out, sys->nsurf, rc);
            if (r == 2 && sys->field_type == SG_FIELD_ANGLE && rc == SG_OK &&
                !(sg_field_check(sys, rays[r][0], rays[r][1], NULL) == SG_OK))
                die("a field past 90 degrees was traced", NULL);
        }
        rc = sg_trace_start(t, start, dir, out);
        check_rays(sys, out, sys->nsurf, rc);
        sg_tracer_free(t);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    sg_system *a = sg_system_new(), *b = sg_system_new();
    char *j1 = NULL, *j2 = NULL;
    const char *diff;
    sg_diag d;
    int rc;

    if (!a || !b)
        die("out of memory", NULL);
    sg_diag_clear(&d);
    rc = sg_design_parse(a, (const char *)data, size, NAME, &d);
    check_diag(&d, rc, 1);
    if (rc != SG_OK)
        goto done;

    sg_diag_clear(&d);
    rc = sg_system_validate(a, cat, &d);
    check_diag(&d, rc, 0);

    j1 = sg_design_to_json(a);
    if (!j1)
        die("a design that parsed cannot be written", NULL);
    sg_diag_clear(&d);
    if (sg_design_parse(b, j1, strlen(j1), NAME, &d) != SG_OK)
        die("the written design does not parse", d.msg);
    if (d.nwarn != 0)
        die("the written design gives a warning", d.warn[0]);
    diff = compare(a, b);
    if (diff)
        die("the written design reads back differently:", diff);
    j2 = sg_design_to_json(b);
    if (!j2 || strcmp(j1, j2) != 0)
        die("writing the design twice gives different text", j1);

    if (rc == SG_OK) {
        /* The design as built hot: refused with a message, or a design
         * that validates and writes. */
        sg_system *h = sg_system_new();
        char *j3;
        if (!h)
            die("out of memory", NULL);
        sg_diag_clear(&d);
        rc = sg_thermal(a, cat, a->temperature + 55.0 <= SG_TEMP_MAX ? a->temperature + 55.0
                                                                    : SG_TEMP_MIN, 1.0, h, &d);
        check_diag(&d, rc, 0);
        if (rc == SG_OK) {
            sg_diag_clear(&d);
            if (sg_system_validate(h, cat, &d) != SG_OK)
                die("the thermal design does not validate", d.msg);
            if (!(j3 = sg_design_to_json(h)))
                die("the thermal design cannot be written", NULL);
            free(j3);
        }
        sg_system_free(h);
        rc = SG_OK;
    }
    if (rc == SG_OK && do_trace)
        trace_some(a);
done:
    free(j1);
    free(j2);
    sg_system_free(a);
    sg_system_free(b);
    return 0;
}
