/* tolmpi_none.c - tolmpi.h in a build without MPI: one process.  Started
 * by mpirun as several, each would run every trial and write the same
 * file, so that is refused. */
#include <stdlib.h>

#include "cli.h"
#include "tolmpi.h"

/* The world's size a launcher gave this process: Open MPI's mpirun, or a
 * PMI launcher (MPICH's, Slurm's srun); 1 when there is none. */
static long launched_size(void)
{
    static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"};
    size_t k;
    for (k = 0; k < sizeof vars / sizeof vars[0]; k++) {
        const char *v = getenv(vars[k]);
        if (v && *v)
            return strtol(v, NULL, 10);
    }
    return 1;
}

int tolmpi_start(void)
{
    long n = launched_size();
    if (n > 1) {
        /* Each of the processes says it; the launcher shows them all. */
        cli_error("tolerance: this sagitta was built without MPI, so the %ld processes "
                  "mpirun started would each run every trial; build with meson -Dmpi=enabled "
                  "(Debian libopenmpi-dev), or run one process with --threads",
                  n);
        return CLI_EXIT_USAGE;
    }
    return CLI_EXIT_OK;
}

int tolmpi_rank(void)
{
    return 0;
}

int tolmpi_size(void)
{
    return 1;
}

int tolmpi_agree(int rc, int *start)
{
    (void)start;
    return rc;
}

int tolmpi_trials(sg_tol_mc *m, int start, int trials, int block, tolmpi_sink sink, void *ctx,
                  int *done)
{
    /* tolmpi_size is 1: the caller runs the trials itself. */
    (void)m, (void)start, (void)trials, (void)block, (void)sink, (void)ctx;
    *done = 0;
    return CLI_EXIT_INTERNAL;
}

int tolmpi_end(int rc)
{
    return rc;
}
