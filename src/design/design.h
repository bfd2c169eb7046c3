/* design.h - the interface of design/ (the merit function, the optimizer,
 * tolerancing) to the other subsystems, beside sagitta.h: what the merit
 * function shares with the design reader and writer, each operand type's
 * parameters as JSON names them. */
#ifndef SG_DESIGN_H
#define SG_DESIGN_H

#include "sagitta.h"

/* Zemax's columns of an operand: Int1, Int2 and Data1 to Data4 under
 * their JSON names (NULL: unused). */
typedef struct sg_op_info {
    const char *name;
    const char *k1, *k2;
    const char *d[4];
} sg_op_info;

const sg_op_info *sg_op_info_of(sg_op_type t);

#endif
