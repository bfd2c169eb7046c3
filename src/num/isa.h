/*
 * isa.h - the names of the vector trace's functions in one instruction-set
 * variant.
 *
 * A build without -march=native (a distribution's) compiles trace_vec.c,
 * trace_classic_vec.c, launch.c, batch.c and opd_vec.c once per
 * instruction set, with SG_ISA naming the set, and dispatch.c picks a
 * variant at run time: the double-double kernels run several times faster
 * with eight lanes and FMA than with SSE2's two.  Every operation is correctly rounded in every variant, so
 * results do not depend on which one runs.  Without SG_ISA the names are
 * the plain ones.
 */
#ifndef SG_ISA_H
#define SG_ISA_H

#ifdef SG_ISA
#define SG_ISA_CAT2(name, isa) name##_##isa
#define SG_ISA_CAT(name, isa) SG_ISA_CAT2(name, isa)
#define sg_precise_block SG_ISA_CAT(sg_precise_block, SG_ISA)
#define sg_precise_finish SG_ISA_CAT(sg_precise_finish, SG_ISA)
#define sg_precise_run_from SG_ISA_CAT(sg_precise_run_from, SG_ISA)
#define sg_precise_run_to SG_ISA_CAT(sg_precise_run_to, SG_ISA)
#define sg_sag_v SG_ISA_CAT(sg_sag_v, SG_ISA)
#define sg_sag_xy_v SG_ISA_CAT(sg_sag_xy_v, SG_ISA)
#define sg_classic_block SG_ISA_CAT(sg_classic_block, SG_ISA)
#define sg_classic_run_to SG_ISA_CAT(sg_classic_run_to, SG_ISA)
#define sg_launch_classic_prep SG_ISA_CAT(sg_launch_classic_prep, SG_ISA)
#define sg_launch_classic_path SG_ISA_CAT(sg_launch_classic_path, SG_ISA)
#define sg_launch_classic SG_ISA_CAT(sg_launch_classic, SG_ISA)
#define sg_launch_precise SG_ISA_CAT(sg_launch_precise, SG_ISA)
#define sg_launch_precise_block SG_ISA_CAT(sg_launch_precise_block, SG_ISA)
#define sg_launch_precise_prep SG_ISA_CAT(sg_launch_precise_prep, SG_ISA)
#define sg_launch_prepare SG_ISA_CAT(sg_launch_prepare, SG_ISA)
#define sg_batch_run SG_ISA_CAT(sg_batch_run, SG_ISA)
#define sg_opd_of_rays SG_ISA_CAT(sg_opd_of_rays, SG_ISA)
#endif

#endif
