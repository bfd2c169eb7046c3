/*
 * cmd.h - the command table, for the help panel and completion.
 * cmd_exec() itself is declared in ed.h with the state it works on.
 */
#ifndef SG_ED_CMD_H
#define SG_ED_CMD_H

int cmd_count(void);
const char *cmd_name(int i);
const char *cmd_usage(int i);
const char *cmd_help(int i);

/* The Merit Function Editor's columns of an operand row (cmd_merit.c), as
 * "merit set" names them: type, int1, int2, hx, hy, px, py, target, weight. */
#include "sagitta.h"
#define MERIT_NCOLS 9
extern const char *const merit_cols[MERIT_NCOLS];
int merit_col_parse(const char *s);
/* The number in column col (1 to 8) of an operand. */
double merit_col_value(const sg_operand *o, int col);
/* The Tolerance Data Editor's columns (cmd_tol.c), as "tol set" names
 * them: type, int1, int2, int3, min, max. */
#define TOL_NCOLS 6
extern const char *const tol_cols[TOL_NCOLS];
int tol_col_parse(const char *s);
int tol_col_used(const sg_tol_operand *o, int col);
double tol_col_value(const sg_tol_operand *o, int col);

#endif
