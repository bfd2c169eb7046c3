/* error.c - the error table and diagnostics. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "core.h"

static const char *const err_msgs[] = {
#define SG_ERR_MSG_(name, msg) msg,
    SG_ERRNO_MAP(SG_ERR_MSG_)
#undef SG_ERR_MSG_
};

static const char *const err_names[] = {
#define SG_ERR_NAME_(name, msg) "SG_E" #name,
    SG_ERRNO_MAP(SG_ERR_NAME_)
#undef SG_ERR_NAME_
};

const char *sg_strerror(int err)
{
    if (err < 0 || err >= SG_ERRNO_COUNT)
        return "unknown error";
    return err_msgs[err];
}

const char *sg_err_name(int err)
{
    if (err < 0 || err >= SG_ERRNO_COUNT)
        return "SG_EUNKNOWN";
    return err_names[err];
}

int sg_err_is_ray_status(int err)
{
    return err == SG_OK || err == SG_EMISS || err == SG_ETIR || err == SG_EVIGNETTED ||
           err == SG_EAPERTURE || err == SG_EOBSCURED ||
           err == SG_ENOCONV || err == SG_EAIM || err == SG_ENOTREACHED || err == SG_EUNCERT ||
           err == SG_ERANGE || err == SG_EEVANESCENT;
}

int sg_err_is_stopped(int err)
{
    return err == SG_EVIGNETTED || err == SG_EAPERTURE || err == SG_EOBSCURED;
}

void sg_diag_clear(sg_diag *d)
{
    if (d)
        memset(d, 0, sizeof *d);
}

int sg_diag_set(sg_diag *d, int code, const char *fmt, ...)
{
    /* The first error is the one the user needs; later ones are echoes. */
    if (d && d->code == SG_OK) {
        va_list ap;
        d->code = code;
        va_start(ap, fmt);
        vsnprintf(d->msg, sizeof d->msg, fmt, ap);
        va_end(ap);
    }
    return code;
}

void sg_diag_warn(sg_diag *d, const char *fmt, ...)
{
    if (!d)
        return;
    if (d->nwarn < SG_DIAG_MAXWARN) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(d->warn[d->nwarn], sizeof d->warn[0], fmt, ap);
        va_end(ap);
    }
    d->nwarn++;
}

void sg_strlcpy(char *dst, const char *src, size_t n)
{
    size_t k;
    if (n == 0)
        return;
    for (k = 0; k + 1 < n && src[k]; k++)
        dst[k] = src[k];
    dst[k] = '\0';
}
