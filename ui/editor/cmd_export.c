/*
 * cmd_export.c - export (ray tables and the view's picture) and print.
 */
#include "cmd_int.h"

/* ------------------------------------------------------------------------
 * Export and print
 * ------------------------------------------------------------------------ */

static int fmt_from_name(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (dot && strcasecmp(dot, ".csv") == 0)
        return REPORT_CSV;
    if (dot && strcasecmp(dot, ".json") == 0)
        return REPORT_JSON;
    return REPORT_TEXT;
}

static void meta_of(ed *e, report_meta *m)
{
    const char *p = doc_path(&e->doc);
    m->design = p ? p : (e->doc.sys->title[0] ? e->doc.sys->title : "(new design)");
    m->method = sg_method_name(e->method);
    m->bits = e->method == SG_METHOD_MPFR ? e->bits : 0;
    m->wave_um = e->doc.sys->wave[e->wave].um;
    m->wave_index = e->wave + 1;
    m->opd = 0;
    m->global = e->global >= 0;
    m->global_ref = e->global;
    /* Every surface's rows (trace --surface chooses some). */
    m->surfaces = NULL;
    m->nsurfaces = 0;
}

/* The rays of a set, made a block at a time so that a grid of a million
 * rays takes no more memory than one of a hundred: the current ray; a y or
 * x fan of n rays from -1 to 1 across the pupil at the current field; or
 * an n by n grid.  The grid divides the square around the pupil into n by
 * n equal cells and takes the centre of each, (2j + 1 - n) / n, keeping
 * those inside the pupil: every ray then stands for the same area (as a
 * spot diagram wants), grid 1 is the chief ray and grid 2 the four rays at
 * (+-0.5, +-0.5).  A grid of odd n holds the chief ray; the rim is the
 * fans' to sample. */
enum { SET_RAY, SET_FAN, SET_XFAN, SET_GRID };

typedef struct rayset {
    int kind, n;
    double hx, hy, px, py; /* the current ray */
    long next;             /* fan index, or grid cell i * n + j */
} rayset;

static int grid_point(const rayset *s, long cell, double *px, double *py)
{
    long i = cell / s->n, j = cell % s->n;
    *px = (2.0 * (double)j + 1.0 - s->n) / s->n;
    *py = (2.0 * (double)i + 1.0 - s->n) / s->n;
    return *px * *px + *py * *py <= 1.0;
}

static size_t rayset_next(rayset *s, sg_ray_in *r, size_t max)
{
    size_t k = 0;
    long end = s->kind == SET_RAY ? 1 : s->kind == SET_GRID ? (long)s->n * s->n : s->n;
    while (k < max && s->next < end) {
        double px, py;
        long i = s->next++;
        memset(&r[k], 0, sizeof r[k]);
        r[k].v[0] = s->hx;
        r[k].v[1] = s->hy;
        if (s->kind == SET_RAY) {
            px = s->px;
            py = s->py;
        } else if (s->kind == SET_GRID) {
            if (!grid_point(s, i, &px, &py))
                continue;
        } else {
            double t = s->n == 1 ? 0.0 : -1.0 + 2.0 * (double)i / (s->n - 1);
            px = s->kind == SET_XFAN ? t : 0.0;
            py = s->kind == SET_XFAN ? 0.0 : t;
        }
        r[k].v[2] = px;
        r[k].v[3] = py;
        k++;
    }
    return k;
}

static size_t rayset_count(const rayset *s)
{
    long c;
    size_t n = 0;
    double px, py;
    if (s->kind == SET_RAY)
        return 1;
    if (s->kind != SET_GRID)
        return (size_t)s->n;
    for (c = 0; c < (long)s->n * s->n; c++)
        n += (size_t)grid_point(s, c, &px, &py);
    return n;
}

/* Exports larger than this ask first (batch mode: need export!). */
#define EXPORT_ASK_BYTES 100e6

static void human_size(double b, char *buf, size_t n)
{
    if (b >= 1e9)
        snprintf(buf, n, "%.1f GB", b / 1e9);
    else if (b >= 1e6)
        snprintf(buf, n, "%.1f MB", b / 1e6);
    else if (b >= 1e3)
        snprintf(buf, n, "%.0f kB", b / 1e3);
    else
        snprintf(buf, n, "%.0f bytes", b);
}

/* Bytes of the report of the first ray, written to memory: the size of an
 * export is about that times the number of rays. */
static double bytes_per_ray(const report_meta *m, report_fmt fmt, int nsurf,
                            const sg_ray_surface *out, const int *status, const sg_ray_in *ray,
                            int multi)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    report_stream rs;
    double b = 0.0;
    if (!f)
        return 0.0;
    if (report_begin(&rs, f, fmt, m, nsurf, SG_RAYS_NORMALIZED, multi, 1) == 0) {
        size_t head;
        fflush(f);
        head = len;
        report_rays(&rs, out, status, 1, ray);
        fflush(f);
        b = (double)(len - head);
    }
    fclose(f);
    free(buf);
    return b;
}

static int export_picture(ed *e, args *a, const char *path, int format, int bang);

/* What an export would replace at path. */
enum { EXPORT_NEW = 0, EXPORT_REPLACES, EXPORT_OWN };

/* The open design's file, whatever the name (device and inode), is never
 * an export's target; another regular file is replaced only when asked.  A
 * device or pipe (/dev/null) holds nothing to lose. */
static int export_target(ed *e, const char *path)
{
    struct stat t, own;
    const char *dp = doc_path(&e->doc);
    if (strcmp(path, "-") == 0 || stat(path, &t) != 0)
        return EXPORT_NEW;
    if (dp && stat(dp, &own) == 0 && own.st_dev == t.st_dev && own.st_ino == t.st_ino)
        return EXPORT_OWN;
    /* The file as the design was read, should its name now lead elsewhere. */
    if (e->doc.disk.have && e->doc.disk.dev == (unsigned long long)t.st_dev &&
        e->doc.disk.ino == (unsigned long long)t.st_ino)
        return EXPORT_OWN;
    return S_ISREG(t.st_mode) ? EXPORT_REPLACES : EXPORT_NEW;
}

static int export_own_file(ed *e, const char *path)
{
    return ec_fail(e, "export: %s is the open design's file; not written (export to another "
                   "name)", path);
}

/* Asks the question (yes runs the same export with "!"); in batch mode,
 * where nobody can answer, fails naming export!. */
static int export_ask(ed *e, args *a, const char *path, const char *what)
{
    char q[ED_LINE / 2];
    size_t len;
    int i;
    if (e->batch)
        return ec_fail(e, "export: %s; not written (export! %s replaces it)", what, path);
    snprintf(e->pending, sizeof e->pending, "export!");
    for (i = 1; i < a->n; i++) {
        cmd_quote(a->v[i], q, sizeof q);
        len = strlen(e->pending);
        snprintf(e->pending + len, sizeof e->pending - len, " %s", q);
    }
    snprintf(e->question, sizeof e->question, "export: %.900s. Replace it? (y)es (n)o", what);
    e->confirm = CONFIRM_WRITE;
    ed_msg(e, 0, "export: %s", what);
    return ED_HANDLED | ED_CONFIRM | ED_REDRAW;
}

int c_export_any(ed *e, args *a, int bang)
{
    const char *usage = "export FILE [csv|json|text|hdf5] [ray | fan [N] | xfan [N] | grid N] | "
                        "export FILE png|svg|pdf";
    const char *path, *set = "ray";
    int fmt = -1, n = 0, i, rc, tostd, nsurf, multi, err;
    size_t nray, block, got, done = 0;
    sg_ray_in *rays = NULL;
    sg_ray_surface *out = NULL;
    int *status = NULL;
    sg_batch *b = NULL;
    sg_tracer *rt = NULL;
    int trc;
    sg_opd *opd = NULL;
    sg_opd_ref ref;
    sg_diag d;
    report_meta m;
    report_stream rs;
    rayset rset;
    const sg_frame *gf = NULL; /* ed_global_frames', not freed here */
    outfile of;
    int flags, hdf5 = 0, target;
    h5rays *h5 = NULL;
    char size[32], h5err[256];

    if (a->n < 2) {
        if (e->batch)
            return ec_fail(e, "usage: %s", usage);
        snprintf(e->prompt_init, sizeof e->prompt_init, "export ");
        return ED_HANDLED | ED_PROMPT;
    }
    path = a->v[1];
    /* A picture format (named, or the file's extension) writes the view. */
    {
        int pf = a->n > 2 ? plot_file_format(a->v[2]) : -1;
        const char *dot = strrchr(path, '.');
        if (pf < 0 && a->n == 2 && dot)
            pf = plot_file_format(dot + 1);
        if (pf >= 0) {
            if (a->n > 3)
                return ec_fail(e, "export: a picture takes no ray set; usage: export FILE "
                               "[png|svg|pdf]");
            return export_picture(e, a, path, pf, bang);
        }
    }
    target = export_target(e, path);
    if (target == EXPORT_OWN)
        return export_own_file(e, path);
    for (i = 2; i < a->n; i++) {
        int f2 = report_parse_fmt(a->v[i]);
        if (f2 < 0 && strcasecmp(a->v[i], "txt") == 0)
            f2 = REPORT_TEXT;
        if (strcasecmp(a->v[i], "hdf5") == 0) {
            hdf5 = 1;
        } else if (f2 >= 0) {
            fmt = f2;
        } else if (strcmp(a->v[i], "ray") == 0 || strcmp(a->v[i], "fan") == 0 ||
                   strcmp(a->v[i], "xfan") == 0 || strcmp(a->v[i], "grid") == 0) {
            set = a->v[i];
            if (i + 1 < a->n && isdigit((unsigned char)a->v[i + 1][0])) {
                if (!ec_parse_int(e, a->v[++i], set, 1, 1001, &n))
                    return ED_HANDLED | ED_ERROR;
            }
        } else {
            return ec_fail(e, "export: \"%s\" is not a format or a ray set; usage: %s",
                        a->v[i], usage);
        }
    }
    if (strcmp(set, "grid") == 0 && n == 0)
        return ec_fail(e, "export: grid needs a size, e.g. grid 11");
    if (n == 0)
        n = 11;
    {
        const char *dot = strrchr(path, '.');
        if (fmt < 0 && dot && (strcasecmp(dot, ".h5") == 0 || strcasecmp(dot, ".hdf5") == 0))
            hdf5 = 1;
    }
    if (fmt < 0)
        fmt = fmt_from_name(path);
    tostd = strcmp(path, "-") == 0;
    if (tostd && !e->batch)
        return ec_fail(e, "export: \"-\" (standard output) works only in batch mode");
    /* HDF5 seeks about its file, as in sagitta trace. */
    if (tostd && hdf5)
        return ec_fail(e, "export: an HDF5 table needs a file, not \"-\"");
    if (hdf5)
        fmt = REPORT_CSV; /* for the size estimate: about the same bytes */

    ed_opts(e);
    if (e->global >= 0) {
        sg_diag gd;
        sg_diag_clear(&gd);
        if (!(gf = ed_global_frames(e, e->global, &gd)))
            return ec_fail(e, "export: global frame: %s", gd.msg);
    }
    memset(&rset, 0, sizeof rset);
    rset.kind = strcmp(set, "ray") == 0    ? SET_RAY
                : strcmp(set, "fan") == 0  ? SET_FAN
                : strcmp(set, "xfan") == 0 ? SET_XFAN
                                           : SET_GRID;
    rset.n = n;
    rset.hx = e->ray[0];
    rset.hy = e->ray[1];
    rset.px = e->ray[2];
    rset.py = e->ray[3];
    nray = rayset_count(&rset);
    if (nray == 0)
        return ec_fail(e, "export: the ray set is empty");
    multi = nray != 1;
    nsurf = e->doc.sys->nsurf;
    /* About 16 MiB of rows a block, and blocks small enough that progress
     * and Esc are seen often. */
    block = ((size_t)16 << 20) / ((size_t)nsurf * sizeof *out);
    block = block < 16 ? 16 : block > 4096 ? 4096 : block;
    rays = malloc(block * sizeof *rays);
    out = malloc(block * (size_t)nsurf * sizeof *out);
    status = malloc(block * sizeof *status);
    if (!rays || !out || !status) {
        flags = ec_fail(e, "out of memory: %zu rays of %d surfaces", block, nsurf);
        goto done;
    }
    sg_diag_clear(&d);
    b = sg_batch_new(e->doc.sys, e->cat, &e->opts, 0, &d);
    if (!b) {
        flags = ec_fail(e, "export: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
        goto done;
    }
    meta_of(e, &m);
    /* Each row says which ray it is, the single ray's as a fan's. */
    m.csv_inputs = 1;
    /* Every ray's OPD, as sagitta trace writes it, from a tracer of the
     * batch's options for the reference spheres. */
    opd = malloc(block * sizeof *opd);
    trc = opd ? sg_tracer_open(e->doc.sys, e->cat, &e->opts, &rt, &d) : SG_ENOMEM;
    if (trc != SG_OK) {
        flags = ec_fail(e, "export: %s", d.msg[0] ? d.msg : sg_strerror(trc));
        goto done;
    }
    m.opd = 1;
    memset(&ref, 0, sizeof ref);
    ref.status = SG_EINVAL;

    got = rayset_next(&rset, rays, block);
    rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, got, NULL, 0, out, status, &d);
    if (rc != SG_EOK) {
        flags = ec_fail(e, "export: %s", d.msg[0] ? d.msg : sg_strerror(rc));
        goto done;
    }
    {
        double est = bytes_per_ray(&m, (report_fmt)fmt, nsurf, out, status, rays, multi) *
                     (double)nray;
        human_size(est, size, sizeof size);
        if (target == EXPORT_REPLACES && !bang && est <= EXPORT_ASK_BYTES) {
            char what[ED_LINE];
            snprintf(what, sizeof what, "%.900s already exists", path);
            flags = export_ask(e, a, path, what);
            goto done;
        }
        if (est > EXPORT_ASK_BYTES && !bang && !tostd) {
            char q[ED_LINE / 2];
            size_t len;
            if (e->batch) {
                flags = ec_fail(e, "export: %s would take about %s (%zu rays); use export! "
                                "to write it",
                             path, size, nray);
                goto done;
            }
            snprintf(e->pending, sizeof e->pending, "export!");
            for (i = 1; i < a->n; i++) {
                cmd_quote(a->v[i], q, sizeof q);
                len = strlen(e->pending);
                snprintf(e->pending + len, sizeof e->pending - len, " %s", q);
            }
            snprintf(e->question, sizeof e->question,
                     target == EXPORT_REPLACES
                         ? "export: %zu rays, about %s, to %s, which exists. Replace it? (y)es "
                           "(n)o"
                         : "export: %zu rays, about %s, to %s. Write it? (y)es (n)o",
                     nray, size, path);
            e->confirm = CONFIRM_WRITE;
            flags = ED_HANDLED | ED_CONFIRM | ED_REDRAW;
            goto done;
        }
    }
    if (hdf5) {
        /* The same table as sagitta trace --format hdf5, OPD included. */
        h5 = h5rays_open(path, &m, e->doc.sys->units, nsurf, SG_RAYS_NORMALIZED,
                         got * (size_t)nsurf, h5err, sizeof h5err);
        if (!h5) {
            flags = ec_fail(e, "export: %s: %s", path, h5err);
            goto done;
        }
    } else {
        err = outfile_open(&of, tostd ? NULL : path, e->out);
        if (err != 0) {
            flags = ec_fail(e, "export: %s: %s", path, strerror(err));
            goto done;
        }
        if (report_begin(&rs, of.f, (report_fmt)fmt, &m, nsurf, SG_RAYS_NORMALIZED, multi,
                         nray) != 0)
            goto write_error;
    }
    if (e->progress)
        e->progress(e->progress_ctx, path, 0, nray);
    for (;;) {
        report_opd_block(rt, &ref, rays, got, out, nsurf, opd);
        /* :global: after the OPD, which is taken in the image's own frame. */
        if (gf)
            sg_rows_to_global(gf, out, got, nsurf, 0);

        if (h5) {
            if (h5rays_write(h5, out, status, got, rays, opd, h5err, sizeof h5err) != 0) {
                flags = ec_fail(e, "export: %s: %s", path, h5err);
                goto done;
            }
        } else if (report_rays_opd(&rs, out, status, got, rays, opd) != 0)
            goto write_error;
        done += got;
        if (e->progress && e->progress(e->progress_ctx, path, done, nray)) {
            if (h5) {
                h5rays_abort(h5);
                h5 = NULL;
            } else
                outfile_abort(&of);
            ed_msg(e, 0, "export cancelled after %zu of %zu rays; %s not written", done,
                   nray, path);
            flags = ED_HANDLED | ED_REDRAW;
            goto done;
        }
        got = rayset_next(&rset, rays, block);
        if (got == 0)
            break;
        rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, got, NULL, 0, out, status, &d);
        if (rc != SG_EOK) {
            if (!h5)
                outfile_abort(&of);
            flags = ec_fail(e, "export: %s", d.msg[0] ? d.msg : sg_strerror(rc));
            goto done;
        }
    }
    if (h5) {
        rc = h5rays_close(h5, h5err, sizeof h5err);
        h5 = NULL;
        if (rc != 0) {
            flags = ec_fail(e, "export: %s: %s", path, h5err);
            goto done;
        }
    } else {
        if (report_end(&rs) != 0)
            goto write_error;
        err = outfile_commit(&of);
        if (err != 0) {
            flags = ec_fail(e, "export: %s: %s", path, strerror(err));
            goto done;
        }
    }
    ed_msg(e, 0, "exported %zu ray%s (%s) to %s", nray, nray == 1 ? "" : "s", size,
           tostd ? "standard output" : path);
    flags = ED_HANDLED | ED_REDRAW;
    goto done;
write_error:
    err = errno;
    outfile_abort(&of);
    flags = ec_fail(e, "export: %s: %s", path, strerror(err));
done:
    h5rays_abort(h5);
    sg_batch_free(b);
    sg_tracer_free(rt);
    free(opd);
    free(rays);
    free(out);
    free(status);
    return flags;
}

int c_export(ed *e, args *a)
{
    return c_export_any(e, a, 0);
}

int c_export1(ed *e, args *a)
{
    return c_export_any(e, a, 1);
}

int c_print(ed *e, args *a)
{
    char buf[ED_LINE];
    const char *what = a->n > 1 ? a->v[1] : "ray";
    report_meta m;
    if (strcmp(what, "cell") == 0) {
        int row, col;
        if (!ec_need(e, a, 3, 3, "print cell SURFACE COLUMN") ||
            !ec_parse_row(e, a->v[2], 0, e->doc.sys->nsurf - 1, &row))
            return ED_HANDLED | ED_ERROR;
        col = cell_parse_name(a->v[3]);
        if (col < 0)
            return ec_fail(e, "no column \"%s\"", a->v[3]);
        cell_text(e->doc.sys, row, col, buf, sizeof buf);
        if (e->batch)
            fprintf(e->out, "%s\n", buf);
        ed_msg(e, 0, "surface %d %s: %s", row, cell_name(col), buf);
        return ED_HANDLED | ED_REDRAW;
    }
    if (strcmp(what, "ray") != 0 && strcmp(what, "paraxial") != 0)
        return ec_fail(e, "usage: print ray | paraxial | cell SURFACE COLUMN");
    ed_recompute(e);
    if (strcmp(what, "paraxial") == 0 && !e->batch)
        return ED_HANDLED | ED_SHOW_SYSDATA;
    if (strcmp(what, "paraxial") == 0 && !e->cmp.par_ok)
        return ec_fail(e, "no paraxial data: %s", e->cmp.build_msg);
    if (strcmp(what, "paraxial") != 0 && !e->cmp.have)
        return ec_fail(e, "no trace: %s", e->cmp.build_msg);
    if (!e->batch) {
        const sg_ray_surface *r = &e->cmp.res[e->row];
        char x[NUMFMT_MAX], y[NUMFMT_MAX], z[NUMFMT_MAX];
        numfmt_shortest(r->x, x, sizeof x);
        numfmt_shortest(r->y, y, sizeof y);
        numfmt_shortest(r->z, z, sizeof z);
        ed_msg(e, 0, "surface %d: x %s  y %s  z %s", e->row, x, y, z);
        return ED_HANDLED | ED_REDRAW;
    }
    meta_of(e, &m);
    if (strcmp(what, "paraxial") == 0) {
        /* At the primary wavelength, as "sagitta paraxial" computes it. */
        m.wave_um = e->doc.sys->wave[e->doc.sys->primary_wave].um;
        m.wave_index = e->doc.sys->primary_wave + 1;
        report_write_paraxial(e->out, REPORT_TEXT, &m, &e->cmp.par);
    }
    else
        report_write(e->out, REPORT_TEXT, &m, e->cmp.nsurf, e->cmp.res, &e->cmp.rc, 1,
                     SG_RAYS_NORMALIZED, NULL);
    fflush(e->out);
    return ED_HANDLED;
}

/* Writes the view on show as a picture (format: plot.h's PLOT_*). */
static int export_picture(ed *e, args *a, const char *path, int format, int bang)
{
    outfile of;
    char msg[256];
    int err, rc, target;
    if (e->view.kind == VIEW_OFF)
        return ec_fail(e, "export: no view on show to draw; choose one with g or "
                       ":view layout|spot|fan|opd|wave|mtf|psf|encircled");
    if (strcmp(path, "-") == 0 && !e->batch)
        return ec_fail(e, "export: \"-\" (standard output) works only in batch mode");
    target = export_target(e, path);
    if (target == EXPORT_OWN)
        return export_own_file(e, path);
    if (target == EXPORT_REPLACES && !bang) {
        snprintf(msg, sizeof msg, "%.200s already exists", path);
        return export_ask(e, a, path, msg);
    }
    ed_opts(e);
    rc = edview_update(&e->view, e->doc.sys, e->doc.id, e->cat, &e->opts, ed_view_field(e));
    if (rc != SG_EOK || !e->view.have_fig)
        return ec_fail(e, "export: %s", e->view.msg[0] ? e->view.msg : sg_strerror(rc));
    if ((err = outfile_open(&of, strcmp(path, "-") == 0 ? NULL : path, e->out ? e->out : stdout)))
        return ec_fail(e, "export: %s: %s", path, strerror(err));
    if (plot_write(&e->view.fig, format, 1000, 750, of.f, msg, sizeof msg)) {
        outfile_abort(&of);
        return ec_fail(e, "export: %s: %s", path, msg);
    }
    if ((err = outfile_commit(&of)))
        return ec_fail(e, "export: %s: %s", path, strerror(err));
    ed_msg(e, 0, "exported the %s view to %s", view_name(e->view.kind), path);
    return ED_HANDLED | ED_REDRAW;
}
