/* merit.h - what the merit function shares with the design reader and
 * writer: each operand type's parameters as JSON names them. */
#ifndef SG_MERIT_H
#define SG_MERIT_H

#include "sagitta.h"

/* Zemax's columns of an operand: Int1 and Int2 under their JSON names
 * (NULL: unused), and whether it reads Hx, Hy and Px, Py. */
typedef struct sg_op_info {
    const char *name;
    const char *k1, *k2;
    int field, pupil;
} sg_op_info;

const sg_op_info *sg_op_info_of(sg_op_type t);

#endif
