/*
 * tolmpi.h - "sagitta tolerance" across processes with MPI (sagitta(1),
 * TOLERANCING, MPI).  ui/tolmpi.c is built with Open MPI (meson -Dmpi);
 * ui/tolmpi_none.c, without it, runs one process and refuses a launch by
 * mpirun of several, each of which would run every trial.  The engine
 * knows nothing of MPI: ranks run blocks of trials through sg_tol_mc_run.
 */
#ifndef SG_UI_TOLMPI_H
#define SG_UI_TOLMPI_H

#include <sagitta.h>

/* At the command's start: MPI is started when a launcher (mpirun) started
 * this process; a rank other than 0 keeps its standard output and error
 * to itself (rank 0 prints them when that rank fails).  0, or a CLI exit
 * code after printing why. */
int tolmpi_start(void);
int tolmpi_rank(void);
int tolmpi_size(void);
/* Collective, once per run before the trials: every rank's code (0: ready)
 * in; the first rank's nonzero code out, on every rank, rank 0 printing
 * that rank's messages.  *start (rank 0's: the first trial to run, -1 for
 * none) becomes rank 0's on every rank.  A rank that ends before calling
 * it calls it in tolmpi_end, so the others do not wait for it. */
int tolmpi_agree(int rc, int *start);

/* Rank 0's receiver of trials first .. first + n - 1, in trial order; a
 * nonzero return (a CLI exit code) ends the run. */
typedef int (*tolmpi_sink)(void *ctx, int first, int n, const sg_tol_value *v);
/* Trials start .. trials - 1 in blocks of block from start, block b on
 * rank b mod size
 * (rank 0 among them); rank 0 hands each block to sink in order.  A value
 * sent carries the status and the criterion only.  0, 1 when rank 0's own
 * block was stopped (*done: the trials handed over), or a CLI exit code
 * after printing why; after a nonzero one, tolmpi_end ends every rank. */
int tolmpi_trials(sg_tol_mc *m, int start, int trials, int block, tolmpi_sink sink, void *ctx,
                  int *done);
/* At the command's end: rc out; MPI is finished (aborted on every rank
 * when tolmpi_trials did not finish). */
int tolmpi_end(int rc);

#endif
