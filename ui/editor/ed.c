/* ed.c - the editor's state: setup, trace options, bundled examples. */
#include "ed.h"

#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "sg_config.h"

int ed_init(ed *e)
{
    sg_diag d;
    memset(e, 0, sizeof *e);
    if (doc_init(&e->doc) != SG_EOK)
        return SG_ENOMEM;
    compute_init(&e->cmp);
    edview_init(&e->view);
    e->cat = sg_catalog_new();
    sg_diag_clear(&d);
    if (!e->cat || sg_catalog_load_default(e->cat, &d) != SG_EOK) {
        snprintf(e->cat_msg, sizeof e->cat_msg, "no glass catalog: %s",
                 d.msg[0] ? d.msg : "out of memory");
        sg_catalog_free(e->cat);
        e->cat = NULL;
    } else if (d.nwarn > 0) {
        /* Loaded, but not what was asked for (a bad SAGITTA_LENSDB). */
        snprintf(e->cat_msg, sizeof e->cat_msg, "glass catalog: %s", d.warn[0]);
    }
    sg_trace_opts_init(&e->opts);
    /* The on-axis upper marginal ray shows the most about a new design. */
    e->ray[3] = 1.0;
    e->wave = e->doc.sys->primary_wave;
    e->method = SG_METHOD_PRECISE;
    e->bits = e->opts.mpfr_bits > 0 ? e->opts.mpfr_bits : 256;
    e->clip = e->opts.clip;
    e->global = -1;
    e->out = stdout;
    e->dirty = 1;
    ed_opts(e);
    return SG_EOK;
}

void ed_free(ed *e)
{
    int i;
    for (i = 0; i < e->nhist; i++)
        free(e->hist[i]);
    e->nhist = 0;
    free(e->gframes);
    e->gframes = NULL;
    compute_free(&e->cmp);
    edview_free(&e->view);
    gp_free(&e->glasses);
    if (e->tol_have)
        sg_tol_result_free(&e->tol_res);
    e->tol_have = 0;
    doc_free(&e->doc);
    sg_catalog_free(e->cat);
    e->cat = NULL;
}

void ed_opts(ed *e)
{
    const sg_system *s = e->doc.sys;
    if (e->wave < 0 || e->wave >= s->nwave)
        e->wave = s->primary_wave >= 0 && s->primary_wave < s->nwave ? s->primary_wave : 0;
    if (e->row >= s->nsurf)
        e->row = s->nsurf - 1;
    if (e->row < 0)
        e->row = 0;
    sg_trace_opts_init(&e->opts);
    e->opts.method = e->method;
    e->opts.mpfr_bits = e->bits;
    e->opts.wave = e->wave;
    e->opts.clip = e->clip;
}

const sg_frame *ed_global_frames(ed *e, int ref, sg_diag *d)
{
    const sg_system *s = e->doc.sys;
    if (e->gframes && e->gframes_id == e->doc.id && e->gframes_ref == ref &&
        e->gframes_n == s->nsurf)
        return e->gframes;
    free(e->gframes);
    e->gframes_id = 0;
    e->gframes = malloc((size_t)s->nsurf * sizeof *e->gframes);
    if (!e->gframes) {
        sg_diag_set(d, SG_ENOMEM, "out of memory");
        return NULL;
    }
    if (sg_global_frames(s, ref, e->gframes, d) != SG_OK) {
        free(e->gframes);
        e->gframes = NULL;
        return NULL;
    }
    e->gframes_id = e->doc.id;
    e->gframes_ref = ref;
    e->gframes_n = s->nsurf;
    return e->gframes;
}

/* :global: the rows of the ray (and of the reference) in the frame of
 * surface e->global, as "sagitta trace --global" gives them.  A design
 * that refuses the reference (now a coordinate break, say) turns it off. */
static void to_global(ed *e)
{
    const sg_system *s = e->doc.sys;
    const sg_frame *gf;
    sg_diag d;
    if (!e->cmp.have || e->cmp.nsurf != s->nsurf)
        return;
    sg_diag_clear(&d);
    if (!(gf = ed_global_frames(e, e->global, &d))) {
        ed_msg(e, 1, "global frame off: %s", d.msg);
        e->global = -1;
        return;
    }
    sg_rows_to_global(gf, e->cmp.res, 1, s->nsurf, 0);
    if (e->cmp.ref_have)
        sg_rows_to_global(gf, e->cmp.ref_res, 1, s->nsurf, 0);
}

void ed_recompute(ed *e)
{
    int ref = 0;
    ed_opts(e);
    /* An MPFR trace compared with itself says nothing, so the reference
     * then gets twice the precision. */
    if (e->digits)
        ref = e->method == SG_METHOD_MPFR ? 2 * e->bits : e->bits;
    if (ref > 100000)
        ref = 100000;
    compute_run(&e->cmp, e->doc.sys, e->doc.id, e->cat, &e->opts, ref, e->ray);
    if (e->global >= 0)
        to_global(e);
    /* The view follows every edit too (it keeps its figure otherwise). */
    edview_update(&e->view, e->doc.sys, e->doc.id, e->cat, &e->opts, ed_view_field(e));
    e->dirty = 0;
}

int ed_view_field(const ed *e)
{
    int k = ed_ray_field(e);
    return k > 0 ? k - 1 : e->doc.sys->nfield - 1;
}

int ed_ray_field(const ed *e)
{
    const sg_system *s = e->doc.sys;
    double fx, fy;
    int k;
    ed_field_scale(s, &fx, &fy);
    for (k = 0; k < s->nfield; k++)
        if (e->ray[0] == (fx > 0.0 ? s->field[k].x / fx : 0.0) &&
            e->ray[1] == (fy > 0.0 ? s->field[k].y / fy : 0.0))
            return k + 1;
    return 0;
}

void ed_msg(ed *e, int err, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
    e->msg_err = err;
}

void ed_hist_add(ed *e, int err, const char *text)
{
    size_t len = strlen(text);
    char *s;
    if (!text[0] || (e->nhist > 0 && strcmp(e->hist[e->nhist - 1] + 1, text) == 0))
        return;
    if (!(s = malloc(len + 2)))
        return;
    s[0] = err ? '!' : ' ';
    memcpy(s + 1, text, len + 1);
    if (e->nhist == ED_HIST_MAX) {
        free(e->hist[0]);
        memmove(e->hist, e->hist + 1, (ED_HIST_MAX - 1) * sizeof e->hist[0]);
        e->nhist--;
    }
    e->hist[e->nhist++] = s;
}

void ed_msg_log(ed *e)
{
    ed_hist_add(e, e->msg_err, e->msg);
}

void ed_load_warnings(ed *e, const char *path, const sg_diag *d)
{
    int i, n = d->nwarn < SG_DIAG_MAXWARN ? d->nwarn : SG_DIAG_MAXWARN;
    char line[ED_MSG + 64];
    size_t len;
    if (d->nwarn <= 0)
        return;
    for (i = 0; i < n; i++) {
        /* Each warning names the file, line and surface already. */
        snprintf(line, sizeof line, "warning: %s", d->warn[i]);
        ed_hist_add(e, 1, line);
        if (e->batch)
            fprintf(stderr, "sagitta edit: %s\n", line);
    }
    if (d->nwarn > n) {
        snprintf(line, sizeof line, "%s: %d more warnings (sagitta import lists them all)", path,
                 d->nwarn - n);
        ed_hist_add(e, 1, line);
        if (e->batch)
            fprintf(stderr, "sagitta edit: %s\n", line);
    }
    /* The count and the way to read them come first, so a narrow status
     * line still shows them. */
    len = strlen(e->msg);
    snprintf(line, sizeof line, "%d warning%s reading the file (:messages shows %s): %s",
             d->nwarn, d->nwarn == 1 ? "" : "s", d->nwarn == 1 ? "it" : "them all", d->warn[0]);
    if (len > 0)
        snprintf(line + strlen(line), sizeof line - strlen(line), "; %s", e->msg);
    snprintf(e->msg, sizeof e->msg, "%s", line);
    e->msg_err = 1;
}

static int is_dir(const char *p)
{
    struct stat st;
    return p && *p && stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

const char *ed_examples_dir(void)
{
    static char found[4096];
    const char *env = getenv("SAGITTA_EXAMPLES");

    if (is_dir(env))
        return env;
    return sg_data_dir("examples", found, sizeof found);
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int ed_examples_list(char ***names)
{
    const char *dir = ed_examples_dir();
    DIR *dp;
    struct dirent *de;
    char **v = NULL;
    int n = 0, cap = 0;
    *names = NULL;
    if (!dir || !(dp = opendir(dir)))
        return -1;
    while ((de = readdir(dp)) != NULL) {
        size_t len = strlen(de->d_name);
        char *s;
        if (len <= 5 || de->d_name[0] == '.' || strcmp(de->d_name + len - 5, ".json") != 0)
            continue;
        if (n == cap) {
            char **nv = realloc(v, (size_t)(cap ? cap * 2 : 16) * sizeof *nv);
            if (!nv)
                break;
            v = nv;
            cap = cap ? cap * 2 : 16;
        }
        s = malloc(len - 4);
        if (!s)
            break;
        memcpy(s, de->d_name, len - 5);
        s[len - 5] = '\0';
        v[n++] = s;
    }
    closedir(dp);
    if (n > 1)
        qsort(v, (size_t)n, sizeof *v, cmp_str);
    *names = v;
    return n;
}

void ed_examples_free(char **names, int n)
{
    int i;
    for (i = 0; i < n; i++)
        free(names[i]);
    free(names);
}

const char *ed_aper_name(int t)
{
    static const char *const n[] = {"epd", "fnum", "na", "float", "pwfnum", "cone"};
    return t >= 0 && t < 6 ? n[t] : "?";
}

const char *ed_field_type_name(int t)
{
    static const char *const n[] = {"angle", "object", "paraximage", "realimage"};
    return t >= 0 && t < 4 ? n[t] : "?";
}

const char *ed_field_norm_name(int t)
{
    return t == SG_NORM_RECT ? "rect" : "radial";
}

const char *ed_aim_name(int a)
{
    static const char *const n[] = {"off", "paraxial", "real"};
    return a >= 0 && a < 3 ? n[a] : "?";
}

void ed_field_scale(const sg_system *s, double *fx, double *fy)
{
    int k;
    *fx = *fy = 0.0;
    for (k = 0; k < s->nfield; k++) {
        if (s->field_norm == SG_NORM_RADIAL) {
            double r = hypot(s->field[k].x, s->field[k].y);
            if (r > *fx)
                *fx = *fy = r;
        } else {
            if (fabs(s->field[k].x) > *fx)
                *fx = fabs(s->field[k].x);
            if (fabs(s->field[k].y) > *fy)
                *fy = fabs(s->field[k].y);
        }
    }
}

const char *ed_field_unit(const sg_system *s)
{
    return s->field_type == SG_FIELD_ANGLE ? "deg" : s->units;
}
