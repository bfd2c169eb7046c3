/*
 * cells.h - the columns of the lens data spreadsheet: their names, how a
 * cell reads as text and how typed text becomes a value.
 *
 * Parsing never touches the surface until the whole text has been checked,
 * so a refused value changes nothing.
 */
#ifndef SG_ED_CELLS_H
#define SG_ED_CELLS_H

#include <stddef.h>

#include "sagitta.h"

/* The columns are the surface parameters of the engine's table
 * (sg_param_at(SG_SCOPE_SURFACE, ...)) that have a heading, an array's
 * elements one column each, in the table's order.  The first ones are
 * named here because the editor treats them specially. */
typedef enum cell_col {
    COL_TYPE = 0,
    COL_COMMENT,
    COL_RADIUS,
    COL_THICKNESS,
    COL_MATERIAL,
    COL_SEMI,
    COL_CONIC,
    COL_ASPH0, /* r^2; COL_ASPH0 + k is the r^(2k+2) term */
    COL_MAX = 128 /* room for every column the table can give */
} cell_col;

/* How many columns the table gives. */
int cell_count(void);
/* The parameter and element of a column, or NULL. */
const sg_param *cell_param(int col, int *k);
/* Column heading, e.g. "Radius" or "r^4". */
const char *cell_heading(int col);
/* Command name, e.g. "radius" or "a4". */
const char *cell_name(int col);
/* Column of a name or alias ("radius", "r", "thickness", "thick", "t",
 * "material", "glass", "semi", "sd", "a4", "r4", ...); -1 if none. */
int cell_parse_name(const char *s);
/* Whether surface row uses the column's value (else it is shown dim): its
 * type's parameters, and a frame change's values where one may stand and
 * is typed. */
int cell_used(const sg_system *sys, int row, int col);
/* Whether key (a code point) can begin a value of the column: any
 * character but ':' in text, what a number may begin with (0-9 + - . and
 * the i and n of inf, infinity and nan), the first letter of a choice's
 * name.  Such a key types into the cell; it never runs a command there. */
int cell_key_begins(int col, int key);
/* Nonzero for the columns that hold numbers. */
int cell_numeric(int col);

/* The cell as shown, full precision (not cut to a width). */
void cell_text(const sg_system *sys, int row, int col, char *buf, size_t n);
/* The text an edit of the cell starts from: like cell_text(), but it reads
 * back as exactly the stored value (a flat radius stored as 0 shows "0"). */
void cell_edit_text(const sg_system *sys, int row, int col, char *buf, size_t n);

/* Sets the cell from text.  cat checks glass names (NULL: glasses are
 * refused, since nothing can vouch for them).  On error returns an sg_err
 * code, writes a message to err and leaves sys untouched.  info (may be
 * NULL) receives a note about a side effect, e.g. the surface type
 * changing to even asphere. */
int cell_set(sg_system *sys, const sg_catalog *cat, int row, int col,
             const char *text, char *err, size_t errn, char *info, size_t infon);

/* Names of the enumerations, as shown and as typed. */
const char *cell_type_name(int type);
int cell_type_parse(const char *s);

#endif
