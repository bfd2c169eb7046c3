/*
 * tolmpi.c - "sagitta tolerance" across processes with MPI (Open MPI;
 * sagitta(1), TOLERANCING, MPI).  The Monte Carlo trials go in blocks to
 * the ranks in turn; rank 0 takes each block in trial order from its
 * rank, so it holds one block at a time, and a rank runs at most one
 * block ahead of rank 0 (its send is synchronous).  Trial t's draws depend
 * only on (seed, t), so the output does not depend on the ranks.
 */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "tolmpi.h"

static int mpi_on, mpi_rank, mpi_size = 1, agreed, aborting;
static FILE *captured; /* a worker's standard output and error */

enum { TAG_BLOCK = 1, TAG_TEXT = 2 };

/* A launcher (Open MPI's mpirun, or a PMI one) started this process. */
static int launched(void)
{
    static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"};
    size_t k;
    for (k = 0; k < sizeof vars / sizeof vars[0]; k++)
        if (getenv(vars[k]) && *getenv(vars[k]))
            return 1;
    return 0;
}

int tolmpi_start(void)
{
    int provided;
    /* Without a launcher MPI is not started: a singleton start would spawn
     * Open MPI's daemon for every plain run. */
    if (!launched())
        return CLI_EXIT_OK;
    /* Only the main thread calls MPI; the engine's threads do not. */
    if (MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
        cli_error("tolerance: MPI could not start");
        return CLI_EXIT_INTERNAL;
    }
    mpi_on = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &mpi_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &mpi_size);
    /* Rank 0 alone prints; the others keep their messages, which rank 0
     * prints if that rank fails. */
    if (mpi_rank != 0 && (captured = tmpfile()) != NULL) {
        fflush(stdout);
        fflush(stderr);
        dup2(fileno(captured), STDOUT_FILENO);
        dup2(fileno(captured), STDERR_FILENO);
    }
    return CLI_EXIT_OK;
}

int tolmpi_rank(void)
{
    return mpi_rank;
}

int tolmpi_size(void)
{
    return mpi_size;
}

/* What a worker printed, its last 1 KiB, as a string. */
static void captured_text(char *buf, int n)
{
    long len;
    size_t got;
    buf[0] = '\0';
    fflush(stdout);
    fflush(stderr);
    if (!captured || fseek(captured, 0, SEEK_END) != 0 || (len = ftell(captured)) < 0)
        return;
    fseek(captured, len > n - 1 ? len - (n - 1) : 0, SEEK_SET);
    got = fread(buf, 1, (size_t)n - 1, captured);
    buf[got] = '\0';
}

int tolmpi_agree(int rc, int *start)
{
    int *all, k, first = -1, out = CLI_EXIT_OK;
    char text[1024];
    if (!mpi_on)
        return rc;
    agreed = 1;
    all = malloc((size_t)mpi_size * sizeof *all);
    if (!all) {
        cli_error("out of memory");
        MPI_Abort(MPI_COMM_WORLD, CLI_EXIT_INTERNAL);
    }
    MPI_Allgather(&rc, 1, MPI_INT, all, 1, MPI_INT, MPI_COMM_WORLD);
    for (k = 0; k < mpi_size && first < 0; k++)
        if (all[k] != CLI_EXIT_OK)
            first = k;
    if (first >= 0) {
        out = all[first];
        /* Rank 0's own message is printed already; another rank's comes. */
        if (first > 0 && mpi_rank == first) {
            captured_text(text, sizeof text);
            MPI_Send(text, (int)strlen(text) + 1, MPI_CHAR, 0, TAG_TEXT, MPI_COMM_WORLD);
        } else if (first > 0 && mpi_rank == 0) {
            MPI_Recv(text, sizeof text, MPI_CHAR, first, TAG_TEXT, MPI_COMM_WORLD,
                     MPI_STATUS_IGNORE);
            text[sizeof text - 1] = '\0';
            fprintf(stderr, "sagitta: tolerance: rank %d of %d failed:\n%s", first, mpi_size,
                    text);
        }
    }
    free(all);
    if (start)
        MPI_Bcast(start, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return out;
}

/* Waits for req, sleeping between tests: MPI's own wait spins a core,
 * which on a machine with more ranks than cores (or a rank's threads on
 * them) takes it from the trials; a trial lasts milliseconds. */
static void wait_req(MPI_Request *req)
{
    struct timespec ts = {0, 200000};
    int flag = 0;
    for (;;) {
        MPI_Test(req, &flag, MPI_STATUS_IGNORE);
        if (flag)
            return;
        nanosleep(&ts, NULL);
        if (ts.tv_nsec < 5000000)
            ts.tv_nsec *= 2;
    }
}

/* A block's message: [0] the rank's code (0, or a CLI exit code, the
 * rank's text following as TAG_TEXT), [1] the trials in it, then each
 * trial's status and criterion. */
static void pack(double *msg, int rc, int n, const sg_tol_value *v)
{
    int k;
    msg[0] = rc;
    msg[1] = n;
    for (k = 0; k < n; k++) {
        msg[2 + 2 * k] = v[k].status;
        msg[3 + 2 * k] = v[k].criterion;
    }
}

static int worker(sg_tol_mc *m, int start, int trials, int block, int nblock)
{
    size_t len = 2 + 2 * (size_t)block;
    double *msg[2];
    sg_tol_value *v = malloc((size_t)block * sizeof *v);
    MPI_Request req = MPI_REQUEST_NULL;
    int b, which = 0, rc = 0;
    char text[1024];
    msg[0] = malloc(len * sizeof(double));
    msg[1] = malloc(len * sizeof(double));
    for (b = mpi_rank; b < nblock; b += mpi_size) {
        int first = start + b * block, done = 0;
        int n = trials - first < block ? trials - first : block;
        if (!v || !msg[0] || !msg[1]) {
            cli_error("rank %d: out of memory", mpi_rank);
            rc = CLI_EXIT_INTERNAL;
        } else if (sg_tol_mc_run(m, first, n, v, &done) != SG_OK) {
            cli_error("rank %d: out of memory", mpi_rank);
            rc = CLI_EXIT_INTERNAL;
        } else if (done < n) {
            cli_error("rank %d: stopped at trial %d", mpi_rank, first + done + 1);
            rc = CLI_EXIT_INTERNAL;
        }
        /* The previous block must be taken before its buffer is reused
         * two blocks on; the synchronous send keeps this rank one block
         * ahead of rank 0 at most. */
        wait_req(&req);
        if (rc) {
            double head[2] = {rc, 0};
            MPI_Send(head, 2, MPI_DOUBLE, 0, TAG_BLOCK, MPI_COMM_WORLD);
            captured_text(text, sizeof text);
            MPI_Send(text, (int)strlen(text) + 1, MPI_CHAR, 0, TAG_TEXT, MPI_COMM_WORLD);
            break;
        }
        pack(msg[which], 0, n, v);
        MPI_Issend(msg[which], 2 + 2 * n, MPI_DOUBLE, 0, TAG_BLOCK, MPI_COMM_WORLD, &req);
        which ^= 1;
    }
    wait_req(&req);
    free(v);
    free(msg[0]);
    free(msg[1]);
    /* A failed rank waits here to be ended with the rest. */
    if (rc)
        for (;;)
            pause();
    return 0;
}

int tolmpi_trials(sg_tol_mc *m, int start, int trials, int block, tolmpi_sink sink, void *ctx,
                  int *done)
{
    int nblock = (trials - start + block - 1) / block, b, rc = 0;
    size_t len = 2 + 2 * (size_t)block;
    double *msg;
    sg_tol_value *v;
    char text[1024];
    *done = start;
    if (mpi_rank != 0)
        return worker(m, start, trials, block, nblock);
    /* Said on standard error, so a cluster's log shows the split. */
    fprintf(stderr, "sagitta: tolerance: %d trials on %d processes (MPI), in blocks of %d\n",
            trials - start, mpi_size, block);
    msg = malloc(len * sizeof *msg);
    v = calloc((size_t)block, sizeof *v);
    if (!msg || !v) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
    }
    for (b = 0; b < nblock && !rc; b++) {
        int src = b % mpi_size, first = start + b * block;
        int n = trials - first < block ? trials - first : block;
        int got = n, k;
        if (src == 0) {
            if (sg_tol_mc_run(m, first, n, v, &got) != SG_OK) {
                cli_error("out of memory");
                rc = CLI_EXIT_INTERNAL;
                break;
            }
        } else {
            MPI_Status st;
            MPI_Request req;
            int count, flag = 0;
            struct timespec ts = {0, 200000};
            MPI_Irecv(msg, (int)len, MPI_DOUBLE, src, TAG_BLOCK, MPI_COMM_WORLD, &req);
            /* As wait_req, keeping the status. */
            for (;;) {
                MPI_Test(&req, &flag, &st);
                if (flag)
                    break;
                nanosleep(&ts, NULL);
                if (ts.tv_nsec < 5000000)
                    ts.tv_nsec *= 2;
            }
            MPI_Get_count(&st, MPI_DOUBLE, &count);
            if (msg[0] != 0) {
                MPI_Recv(text, sizeof text, MPI_CHAR, src, TAG_TEXT, MPI_COMM_WORLD,
                         MPI_STATUS_IGNORE);
                text[sizeof text - 1] = '\0';
                fprintf(stderr, "sagitta: tolerance: rank %d of %d failed:\n%s", src, mpi_size,
                        text);
                rc = (int)msg[0];
                break;
            }
            if (count != 2 + 2 * n || (int)msg[1] != n) {
                cli_error("tolerance: rank %d sent %d values for trials %d to %d", src, count,
                          first + 1, first + n);
                rc = CLI_EXIT_INTERNAL;
                break;
            }
            for (k = 0; k < n; k++) {
                v[k].status = (int)msg[2 + 2 * k];
                v[k].criterion = msg[3 + 2 * k];
            }
        }
        if ((rc = sink(ctx, first, got, v)) != 0)
            break;
        *done = first + got;
        /* Rank 0's own block cut short by a stop: what is done is kept. */
        if (got < n)
            rc = 1;
    }
    free(msg);
    free(v);
    /* The other ranks are still sending: they are ended with the run. */
    if (rc)
        aborting = 1;
    return rc;
}

int tolmpi_end(int rc)
{
    int start = -1;
    if (!mpi_on)
        return rc;
    /* This rank ended before the others learnt whether to run the trials. */
    if (!agreed) {
        int all = tolmpi_agree(rc, &start);
        if (rc == CLI_EXIT_OK)
            rc = all;
    }
    fflush(stdout);
    fflush(stderr);
    if (aborting)
        MPI_Abort(MPI_COMM_WORLD, rc);
    MPI_Finalize();
    if (captured)
        fclose(captured);
    return rc;
}
