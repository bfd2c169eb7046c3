/*
 * sagitta.h - the one public header of the sagitta ray-trace engine.
 *
 * The engine is a plain C11 library.  It never prints and never touches a
 * terminal: every function that can fail returns an sg_err code, and where a
 * message helps the user it also fills an sg_diag with text that names the
 * file, line, column, surface or field at fault.
 *
 * Conventions follow Zemax sequential mode.  Surfaces are numbered 0 (object)
 * to N (image).  Each surface has a local frame whose origin is its vertex and
 * whose axes are parallel to the global frame; light enters travelling +z and
 * thicknesses after a mirror are negative.  Lengths are in lens units (mm by
 * default), wavelengths in micrometres.
 */
#ifndef SAGITTA_H
#define SAGITTA_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Every public function is marked SG_API: the library is built with hidden
 * visibility, so what no installed header declares is not exported. */
#if defined(__GNUC__) && __GNUC__ >= 4
#define SG_API __attribute__((visibility("default")))
#else
#define SG_API
#endif

#define SG_VERSION_MAJOR 0
#define SG_VERSION_MINOR 1
#define SG_VERSION_PATCH 0
#define SG_VERSION_STRING "0.1.0"

/* The JSON design format version this library reads and writes. */
/* Version 2 adds coordinate breaks and surface tilts and decenters; a
 * design without them is still written as version 1. */
#define SG_DESIGN_FORMAT_VERSION 7

/* ------------------------------------------------------------------------
 * Errors.  One table yields the enum, the names and the messages, so the
 * three can never drift apart.  Ray failures (a miss, TIR, vignetting) use
 * the same codes because they are reported per surface as a status.
 * ------------------------------------------------------------------------ */
#define SG_ERRNO_MAP(X)                                                      \
    X(OK, "success")                                                         \
    X(NOMEM, "out of memory")                                                \
    X(INVAL, "invalid argument")                                             \
    X(IO, "input/output error")                                              \
    X(PARSE, "malformed input")                                              \
    X(RANGE, "value out of range")                                           \
    X(NOGLASS, "unknown material")                                           \
    X(NOSTOP, "no aperture stop")                                            \
    X(TWOSTOPS, "more than one aperture stop")                               \
    X(NOSYS, "system has too few surfaces")                                  \
    X(NONPHYS, "nonphysical surface or system")                              \
    X(MISS, "ray misses surface")                                            \
    X(TIR, "total internal reflection")                                      \
    X(VIGNETTED, "ray outside clear semi-diameter")                          \
    X(NOCONV, "intersection did not converge")                               \
    X(AIM, "ray aiming did not converge")                                    \
    X(NOTREACHED, "surface not reached")                                     \
    X(UNSUPPORTED, "unsupported feature")                                    \
    X(WAVERANGE, "wavelength outside material range")                       \
    X(UNCERT, "intersection cannot be certified in double-double")            \
    X(APERTURE, "ray outside the surface aperture")                           \
    X(OBSCURED, "ray stopped by an obscuration")                              \
    X(LOSSY, "the file cannot hold the design faithfully")                   \
    X(STOPPED, "stopped before the end")                                     \
    X(EVANESCENT, "the diffraction order is evanescent")

typedef enum sg_err {
#define SG_ERR_ENUM_(name, msg) SG_E##name,
    SG_ERRNO_MAP(SG_ERR_ENUM_)
#undef SG_ERR_ENUM_
    SG_ERRNO_COUNT
} sg_err;

/* Success is not an error, so it reads without the E. */
#define SG_OK SG_EOK

/* Short message for a code; never NULL. */
SG_API const char *sg_strerror(int err);
/* Symbolic name for a code, e.g. "SG_EMISS"; never NULL. */
SG_API const char *sg_err_name(int err);
/* Nonzero when a trace's return code tells the ray's fate (reached the
 * image, missed, TIR, vignetted, not certified, not aimed ...) rather than
 * a failure of the program or its input. */
SG_API int sg_err_is_ray_status(int err);
/* Nonzero for the codes of a ray something stopped: SG_EVIGNETTED (a fixed
 * semi-diameter), SG_EAPERTURE and SG_EOBSCURED. */
SG_API int sg_err_is_stopped(int err);

#define SG_DIAG_MSG 512
#define SG_DIAG_MAXWARN 16

/* Context for a failure: the first error, plus warnings that did not stop
 * the operation (unknown keys, a wavelength outside a glass's range). */
typedef struct sg_diag {
    int code;                                 /* SG_OK or the error */
    char msg[SG_DIAG_MSG];                    /* names file:line:col, surface or field */
    int nwarn;                                /* warnings recorded (may exceed stored) */
    char warn[SG_DIAG_MAXWARN][SG_DIAG_MSG];
} sg_diag;

SG_API void sg_diag_clear(sg_diag *d);
/* Records an error (the first one wins) and returns code.  d may be NULL. */
SG_API int sg_diag_set(sg_diag *d, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* Records a warning.  d may be NULL. */
SG_API void sg_diag_warn(sg_diag *d, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* ------------------------------------------------------------------------
 * Materials and catalogs
 * ------------------------------------------------------------------------ */

/* Dispersion formulas, numbered as Zemax AGF files number them. */
typedef enum sg_formula {
    SG_FORMULA_SCHOTT = 1,
    SG_FORMULA_SELLMEIER1 = 2,
    SG_FORMULA_HERZBERGER = 3,
    SG_FORMULA_SELLMEIER2 = 4,
    SG_FORMULA_CONRADY = 5,
    SG_FORMULA_SELLMEIER3 = 6,
    SG_FORMULA_HANDBOOK1 = 7,
    SG_FORMULA_HANDBOOK2 = 8,
    SG_FORMULA_SELLMEIER4 = 9,
    SG_FORMULA_EXTENDED1 = 10,
    SG_FORMULA_SELLMEIER5 = 11,
    SG_FORMULA_EXTENDED2 = 12,
    SG_FORMULA_EXTENDED3 = 13
} sg_formula;

#define SG_GLASS_NAME 32
#define SG_GLASS_NCOEF 12

typedef struct sg_glass {
    char name[SG_GLASS_NAME];    /* upper case, e.g. "N-BK7" */
    char catalog[SG_GLASS_NAME]; /* catalog file stem, e.g. "SCHOTT" */
    int formula;                 /* sg_formula */
    double c[SG_GLASS_NCOEF];    /* CD line coefficients, in file order */
    double lmin, lmax;           /* valid range in um (LD line) */
    double nd, vd;               /* catalog nd and Abbe number (NM line) */
    /* TD line: dn/dT coefficients D0, D1, D2, E0, E1 and lambda_tk (um),
     * and the temperature (C) the catalog's data were measured at.  A
     * glass without a TD line has zeros and 20 C. */
    double td[6];
    double tref;
    /* ED line: expansion coefficients -30..+70 C and +100..+300 C (1e-6/K),
     * density (g/cm^3) and relative partial dispersion deviation dPgF. */
    double ed[4];
    int has_td, has_ed;
    /* The ED line's fifth field, Zemax's "ignore thermal expansion" (a
     * liquid or gas): its surfaces expand with their mounts' TCE. */
    int ignore_expansion;
} sg_glass;

typedef struct sg_catalog sg_catalog;

SG_API sg_catalog *sg_catalog_new(void);
SG_API void sg_catalog_free(sg_catalog *cat);
/* Appends the glasses of one AGF file; the file's stem (upper case) is
 * the glasses' catalog.  A later glass of the same name in the same
 * catalog replaces an earlier one; glasses of one name in different
 * catalogs are all kept. */
SG_API int sg_catalog_load_agf(sg_catalog *cat, const char *path, sg_diag *d);
/* Loads every *.agf in a directory. */
SG_API int sg_catalog_load_dir(sg_catalog *cat, const char *dir, sg_diag *d);
/* Loads the bundled catalog: $SAGITTA_LENSDB, then the source tree's
 * lensdb/ (so the program runs unbuilt and uninstalled), then the installed
 * data directory.  The first directory that exists is used. */
SG_API int sg_catalog_load_default(sg_catalog *cat, sg_diag *d);
/* The directory of the data installed with sagitta, NAME "lensdb" or
 * "examples", written into buf: the source tree's while the program runs
 * from the build tree, else the one installed beside the program or the
 * library, else the configured one.  NULL when none exists. */
SG_API const char *sg_data_dir(const char *name, char *buf, size_t n);
/* The directory sg_catalog_load_default() used, or NULL. */
SG_API const char *sg_catalog_dir(const sg_catalog *cat);
/* The glass an unqualified name means: of the catalogs holding it, the
 * first in the search order SCHOTT, OHARA, MISC, INFRARED, HOYA, SUMITA,
 * CDGM, HIKARI, then other catalogs in load order.  Case-insensitive. */
SG_API const sg_glass *sg_catalog_find(const sg_catalog *cat, const char *name);
/* The glass name of one catalog (NULL or "" means sg_catalog_find). */
SG_API const sg_glass *sg_catalog_find_in(const sg_catalog *cat, const char *catalog,
                                   const char *name);
/* The catalogs loaded, in load order. */
SG_API size_t sg_catalog_ncatalogs(const sg_catalog *cat);
SG_API const char *sg_catalog_catalog_at(const sg_catalog *cat, size_t i);
SG_API size_t sg_catalog_count(const sg_catalog *cat);
SG_API const sg_glass *sg_catalog_at(const sg_catalog *cat, size_t i);

/* Refractive index relative to air at wavelength um.  Returns NaN for an
 * unknown formula or a non-positive n^2. */
SG_API double sg_glass_index(const sg_glass *g, double um);
SG_API int sg_glass_in_range(const sg_glass *g, double um);

/* Zemax's index of air at wavelength um, temperature temp (C) and relative
 * pressure pres (atm): n = 1 + (n_ref - 1) P / (1 + 3.4785e-3 (T - 15)),
 * n_ref = 1 + 1e-8 (6432.8 + 2949810 L^2 / (146 L^2 - 1)
 *                   + 25540 L^2 / (41 L^2 - 1)). */
SG_API double sg_air_index(double um, double temp, double pres);
/* The glass's index relative to air at temp (C) and pres (atm), for a
 * wavelength um measured in that air, by Zemax's thermal model: the
 * wavelength is taken into the catalog's reference air (tref, 1 atm), the
 * catalog index made absolute there, changed by the TD line's
 *   dn_abs = (n^2 - 1) / (2 n) (D0 dT + D1 dT^2 + D2 dT^3
 *            + (E0 dT + E1 dT^2) / (L^2 - Ltk^2)),  dT = temp - tref,
 * and divided by the index of the air at temp and pres.  At the reference
 * conditions (temp == tref, pres == 1) it is sg_glass_index() exactly. */
SG_API double sg_glass_index_env(const sg_glass *g, double um, double temp, double pres);

/* A model glass from nd, vd and dPgF, as a catalog glass (named "MODEL") of
 * the Conrady formula (5), n = n0 + A / L + B / L^3.5, whose three
 * coefficients give exactly
 *   n(d) = nd,  n(F) - n(C) = (nd - 1) / vd,
 *   (n(g) - n(F)) / (n(F) - n(C)) = 0.6438 - 0.001682 vd + dPgF,
 * the last SCHOTT's normal line of the partial dispersion P_g,F (TIE-29),
 * from which catalogs' dPgF is measured.  Zemax's own model glass formula
 * is not published; in the visible this one follows real glasses to about
 * 1e-4.  Returns SG_ERANGE for values outside the SG_MODEL_* limits. */
SG_API int sg_model_glass(double nd, double vd, double dpgf, sg_glass *out);

/* ------------------------------------------------------------------------
 * The optical system
 * ------------------------------------------------------------------------ */

#define SG_NASPH 8        /* even asphere terms on r^2, r^4, ... r^16 */
#define SG_NODD 8         /* odd asphere terms on r^1, r^2, ... r^8 */
#define SG_NTERMS 66      /* Zernike (to radial order 10) or x^i y^j (orders 1 to 10) terms */
#define SG_MAX_WAVES 24
#define SG_MAX_FIELDS 64
#define SG_COMMENT 64
#define SG_MAX_SURFACES 100000

/* The surface types, one row each: the enum's name (SG_SURF_...), the JSON
 * name (sagitta-design(5)), Zemax's .zmx TYPE keyword and the shape's
 * record (sg_shape_<record>_type in src/shape*.c, which holds its
 * parameters, .zmx map, thermal rule and kernels).  The enum, the names
 * and the engine's registry are made from this list, in this order; a new
 * type is a row at the end. */
#define SG_SURF_TYPES(X)                                                         \
    X(STANDARD, "standard", "STANDARD", standard)       /* sphere, plane, conic */ \
    X(EVENASPH, "even_asphere", "EVENASPH", even)       /* conic + r^2 ... r^16 */ \
    X(COORDBRK, "coordinate_break", "COORDBRK", coordbrk) /* a frame, no optics */ \
    X(ODDASPH, "odd_asphere", "ODDASPHE", odd)          /* conic + r^1 ... r^8 */  \
    X(TOROIDAL, "toroidal", "TOROIDAL", toroid)         /* y-z curve, turned */    \
    X(BICONIC, "biconic", "BICONICX", biconic)          /* conics in x and y */    \
    X(ZERNIKE_FRINGE, "zernike_fringe", "FZERNSAG", zernike_fringe)                \
    X(ZERNIKE_STANDARD, "zernike_standard", "SZERNSAG", zernike_standard)          \
    X(XYPOLY, "xy_polynomial", "XPOLYNOM", xypoly)      /* conic + x^i y^j */ \
    X(QCON, "q_type_asphere", "QTYPEASP", qcon)         /* conic + Forbes Qcon */  \
    X(PARAXIAL, "paraxial", "PARAXIAL", paraxial)       /* ideal thin lens, flat */ \
    X(DGRATING, "diffraction_grating", "DGRATING", dgrating) /* ruled conic */ \
    X(BINARY_2, "binary_2", "BINARY_2", binary2)  /* conic + phase in r^2i */      \
    X(ZERNIKE_PHASE, "zernike_fringe_phase", "FZERNPHA", fzernpha) /* + Zernike phase */

/* The values are those of earlier versions: 0 standard ... 8 XY. */
#define SG_SURF_ENUM_(name, json, zmx, rec) SG_SURF_##name,
typedef enum sg_surf_type { SG_SURF_TYPES(SG_SURF_ENUM_) SG_SURF_NTYPES } sg_surf_type;
#undef SG_SURF_ENUM_

/* Surface apertures and obscurations, as Zemax defines them: one a surface
 * (a dummy surface of zero thickness adds another), each about its own
 * decenter.  A ray that meets the surface where its aperture stops it
 * fails there with SG_EAPERTURE, where its obscuration stops it with
 * SG_EOBSCURED; beyond a fixed semi-diameter it is SG_EVIGNETTED.
 * sg_ray_stop_text names the kind and the surface. */
typedef enum sg_aperture_type {
    SG_APERTURE_NONE = 0,
    SG_APERTURE_CIRCULAR = 1,     /* passes min_radius <= r <= max_radius */
    SG_OBSCURATION_CIRCULAR = 2,  /* stops min_radius <= r <= max_radius */
    SG_APERTURE_RECTANGULAR = 3,  /* passes |x| <= x_half, |y| <= y_half */
    SG_OBSCURATION_RECTANGULAR = 4,
    SG_APERTURE_ELLIPTICAL = 5,   /* passes (x/x_half)^2 + (y/y_half)^2 <= 1 */
    SG_OBSCURATION_ELLIPTICAL = 6
} sg_aperture_type;

typedef enum sg_mat_kind {
    SG_MAT_AIR = 0,    /* index 1 (indices are relative to air) */
    SG_MAT_MIRROR = 1, /* reflect; the medium after keeps the index before */
    SG_MAT_GLASS = 2,  /* a catalog glass, by name */
    SG_MAT_INDEX = 3,  /* a fixed, non-dispersive index */
    SG_MAT_MODEL = 4   /* a model glass: nd (in index), vd and dpgf */
} sg_mat_kind;

typedef struct sg_material {
    sg_mat_kind kind;
    char name[SG_GLASS_NAME]; /* glass name for SG_MAT_GLASS */
    /* The glass's catalog, or "" for the glass the name alone means
     * (sg_catalog_find); upper case. */
    char catalog[SG_GLASS_NAME];
    double index;             /* for SG_MAT_INDEX; nd for SG_MAT_MODEL */
    double vd, dpgf;          /* for SG_MAT_MODEL */
    /* A catalog glass as tolerancing changes it (TIND, TABB; sg_tol_apply;
     * no file holds them): dn is added to the index at every wavelength,
     * and n - n(d) is scaled by disp (0: not scaled). */
    double dn, disp;
} sg_material;

/* The catalog glass of a glass material (its catalog's if it names one),
 * or NULL: not a glass, or not in cat. */
SG_API const sg_glass *sg_material_glass(const sg_catalog *cat, const sg_material *m);

/* A change of coordinate frame, as Zemax defines it (its coordinate break
 * and surface tilt/decenter).  Order 0: decenter the frame in x and y,
 * then tilt it about x, then about the new y, then about the new z.
 * Order 1: tilt about z, new y, new x, then decenter along the new axes.
 * Tilts are in degrees, right-handed; decenters in lens units.  A change
 * with order toggled and every value negated undoes it. */
typedef struct sg_frame_change {
    double dx, dy;
    double tx, ty, tz;
    int order; /* 0 or 1 */
} sg_frame_change;

typedef enum sg_after_mode {
    SG_AFTER_EXPLICIT = 0, /* the after change is as given */
    SG_AFTER_REVERSE = 1   /* the after change undoes the before change */
} sg_after_mode;
/* Limits of a model glass's nd, vd and |dPgF|. */
#define SG_MODEL_ND_MIN 1.0
#define SG_MODEL_ND_MAX 4.0
#define SG_MODEL_VD_MIN 5.0
#define SG_MODEL_VD_MAX 200.0
#define SG_MODEL_DPGF_MAX 0.2

/* Solves and pickups (Zemax's): a parameter of a surface computed from the
 * rest of the design by sg_system_apply_solves, in surface order.  The
 * kinds each parameter may hold are in sg_solve_allowed. */
typedef enum sg_solve_target {
    SG_SOLVE_RADIUS = 0,
    SG_SOLVE_THICKNESS = 1,
    SG_SOLVE_CONIC = 2,
    SG_SOLVE_NTARGETS
} sg_solve_target;

typedef enum sg_solve_kind {
    SG_SOLVE_NONE = 0,
    /* scale * (the same parameter of surface `from`) + offset; from is an
     * earlier surface */
    SG_SOLVE_PICKUP = 1,
    /* thickness: the paraxial marginal ray meets the next surface at
     * height `value` (0: the paraxial focus); Zemax's marginal ray height */
    SG_SOLVE_MARGINAL_HEIGHT = 2,
    /* radius: the paraxial marginal ray leaves the surface with slope
     * `value` (u'); Zemax's marginal ray angle */
    SG_SOLVE_MARGINAL_ANGLE = 3,
    /* radius: the marginal ray leaves with slope -1 / (2 value), value
     * the F/#; Zemax's F number solve */
    SG_SOLVE_FNUM = 4,
    /* thickness: the paraxial chief ray of the largest field meets the next
     * surface at height `value`; Zemax's chief ray height */
    SG_SOLVE_CHIEF_HEIGHT = 5,
    /* radius: the curvature is scale * (surface `from`'s curvature) +
     * offset, offset in 1 / lens units; Zemax's curvature pickup, whose
     * scale and offset act on the curvature (a flat source has 0) */
    SG_SOLVE_CURV_PICKUP = 6,
    /* thickness: the distance along the axis from the vertex of surface
     * `from` (this surface or an earlier one) to the next surface is
     * `value`; Zemax's position solve */
    SG_SOLVE_POSITION = 7,
    /* the optimizer varies the value, within [lo, hi] (each may be
     * infinite); sg_system_apply_solves leaves it as it is.  Format
     * version 6 */
    SG_SOLVE_VARIABLE = 8,
    SG_SOLVE_NKINDS
} sg_solve_kind;

typedef struct sg_solve {
    sg_solve_kind kind;
    int from;            /* pickups: the source surface; position: the reference */
    double scale, offset; /* pickups */
    double value;        /* height, angle or F/# */
    double lo, hi;       /* variable: the bounds, -inf and +inf when not given */
} sg_solve;

/* A variable on a surface parameter other than radius, thickness and
 * conic (those are solves of kind variable): a REAL row of the surface
 * table (an asphere term, a tilt, a toroid's x radius ...) and its element,
 * with bounds, -inf and inf when free (sagitta-design(5), SOLVES). */
#define SG_SURF_MAXVARS 16
struct sg_param;
typedef struct sg_pvar {
    const struct sg_param *param;
    int elem;
    double lo, hi;
} sg_pvar;

typedef struct sg_surface {
    sg_surf_type type;
    char comment[SG_COMMENT];
    double radius;         /* +-inf (or 0 on input) means flat */
    double thickness;      /* to the next vertex; +inf allowed on the object */
    sg_material mat;       /* the medium after this surface */
    double semi_diameter;  /* clear semi-diameter; 0 means not set */
    int sd_fixed;          /* nonzero: rays beyond semi_diameter are vignetted */
    double conic;
    double asph[SG_NASPH]; /* coefficients of r^2, r^4, ..., r^16 (toroid: y^2 ... y^14) */
    /* The shapes beyond the even asphere (sagitta-design(5), SURFACE
     * TYPES); each type reads only its own. */
    double odd[SG_NODD];   /* odd asphere: coefficients of r^1 ... r^8 */
    double radius_x;       /* biconic: x radius; toroid: radius of rotation; inf: flat */
    double conic_x;        /* biconic: x conic */
    double norm_radius;    /* Zernike and XY: x and y are divided by it */
    double terms[SG_NTERMS]; /* Zernike Z1 ...; XY: x, y, x^2, xy, y^2, x^3, ... */
    double zern_dx, zern_dy; /* Zernike: the terms' centre (Zemax's Decenter X, Y);
                              * the conic and r^n terms stay on the vertex */
    double focal_length;   /* paraxial: the ideal lens's focal length (Zemax's PARM 1) */
    double opd_mode;       /* paraxial: Zemax's OPD mode 0 to 3 (PARM 2) */
    double grating_lines;  /* grating: lines per micrometre (Zemax's PARM 1) */
    double grating_order;  /* grating: the diffraction order (PARM 2); binary 2 and
                            * Zernike phase: their diffraction order (PARM 0) */
    sg_aperture_type aperture; /* the surface aperture or obscuration */
    double ap_rmin, ap_rmax;   /* circular: the annulus's radii */
    double ap_xhalf, ap_yhalf; /* rectangular and elliptical: half widths */
    double ap_xdec, ap_ydec;   /* the aperture's centre in the local frame */
    /* The frame changes around the surface: before it (for a coordinate
     * break, the break itself) and after it, ahead of the thickness.  A
     * coordinate break is a plane in its new frame, with the medium
     * before it; its radius, material and semi-diameter are not used. */
    sg_frame_change before;
    sg_frame_change after;
    sg_after_mode after_mode;
    sg_solve solve[SG_SOLVE_NTARGETS]; /* by sg_solve_target; kind 0: none */
    int nvar;                          /* variables on other parameters */
    sg_pvar var[SG_SURF_MAXVARS];
    /* Zemax's TCE column, 1e-6/K: the expansion of the mount that holds
     * the surface (the air space after it, a mirror's substrate, a
     * dummy's or coordinate break's placement).  Only sg_thermal reads
     * it; traces do not.  Default 0. */
    double tce;
    /* The surface of the .zmx file it was read from, from 1 (0: none),
     * whose lines sagitta keeps for a lossless save; no trace reads it. */
    int zmx_src;
} sg_surface;

typedef enum sg_field_type {
    SG_FIELD_ANGLE = 0,           /* degrees; direction ~ (tan x, tan y, 1) */
    SG_FIELD_OBJECT_HEIGHT = 1,   /* lens units on the object surface */
    SG_FIELD_PARAX_IMAGE_HEIGHT = 2,
    SG_FIELD_REAL_IMAGE_HEIGHT = 3
} sg_field_type;

typedef enum sg_field_norm {
    SG_NORM_RADIAL = 0,
    SG_NORM_RECT = 1
} sg_field_norm;

typedef enum sg_aper_type {
    SG_APER_EPD = 0,
    SG_APER_IMAGE_FNUM = 1,
    SG_APER_OBJECT_NA = 2,
    SG_APER_FLOAT_STOP = 3,
    SG_APER_PARAX_WORKING_FNUM = 4,
    /* Zemax's object cone angle: the half angle, in degrees, of the cone
     * of light from the axial object point (below 90); n sin of it is the
     * object NA.  Format version 3. */
    SG_APER_OBJECT_CONE = 5
} sg_aper_type;

typedef enum sg_aim {
    SG_AIM_OFF = 0,      /* aim at the paraxial entrance pupil */
    SG_AIM_PARAXIAL = 1, /* iterate onto the stop, paraxial stop size */
    SG_AIM_REAL = 2      /* iterate onto the stop, real stop size */
} sg_aim;

typedef struct sg_wave {
    double um;
    double weight;
} sg_wave;

typedef struct sg_field {
    double x, y;
    double weight;
    /* Zemax's vignetting factors: the pupil of this field is compressed
     * (vcx, vcy), turned by van degrees and decentred (vdx, vdy) before
     * its rays are aimed; see sg_field_vignette. */
    double vdx, vdy, vcx, vcy, van;
} sg_field;

/* Limits of the environment: temperature in C, pressure in atm. */
#define SG_TEMP_MIN (-250.0)
#define SG_TEMP_MAX 1000.0
#define SG_PRES_MAX 100.0
/* Limit of a surface's |tce|, in 1e-6/K. */
#define SG_TCE_MAX 1000.0

/* The merit function (sagitta-design(5), MERIT FUNCTION): Zemax's
 * operands and its default merit function.  Values are Zemax's: MF^2 =
 * sum w (v - t)^2 / sum w over the rows with nonzero weight. */
#define SG_MAX_OPERANDS 200
typedef enum sg_op_type {
    SG_OP_BLNK = 0, SG_OP_EFFL, SG_OP_TOTR, SG_OP_TTHI, SG_OP_CTGT, SG_OP_CTLT, SG_OP_CTVA,
    SG_OP_ETGT, SG_OP_ETLT, SG_OP_ETVA, SG_OP_MNCT, SG_OP_MXCT, SG_OP_MNET, SG_OP_MNCA,
    SG_OP_MXCA, SG_OP_MNCG, SG_OP_MXCG, SG_OP_REAX, SG_OP_REAY, SG_OP_REAZ, SG_OP_TRAX,
    SG_OP_TRAY, SG_OP_TRAR, SG_OP_RSCE, SG_OP_RSCH, SG_OP_SUMM, SG_OP_DIFF, SG_OP_PROD,
    SG_OP_DIVI, SG_OP_CONS, SG_OP_OPGT, SG_OP_OPLT, SG_OP_ABSO,
    /* first order */
    SG_OP_PMAG, SG_OP_WFNO, SG_OP_ISFN, SG_OP_EPDI, SG_OP_EXPP, SG_OP_PARX, SG_OP_PARY,
    SG_OP_PANA,
    /* edge thickness boundaries */
    SG_OP_MXET, SG_OP_MNEA, SG_OP_MXEA, SG_OP_MNEG, SG_OP_MXEG,
    /* real rays */
    SG_OP_REAR, SG_OP_RANG, SG_OP_TRAC, SG_OP_OPDC, SG_OP_OPDX,
    /* image quality */
    SG_OP_RSRE, SG_OP_RSRH, SG_OP_RWCE, SG_OP_RWRE, SG_OP_DIST, SG_OP_DIMX, SG_OP_FCGS,
    SG_OP_FCGT, SG_OP_ZERN,
    /* Seidel */
    SG_OP_SPHA, SG_OP_COMA, SG_OP_ASTI, SG_OP_FCUR, SG_OP_AXCL, SG_OP_LACL,
    /* arithmetic */
    SG_OP_SQRT,
    /* physical optics */
    SG_OP_MTFT, SG_OP_MTFS, SG_OP_MTFA, SG_OP_GMTT, SG_OP_GMTS, SG_OP_GMTA, SG_OP_STRH,
    /* multi-configuration: the rows below are configuration i1's */
    SG_OP_CONF,
    SG_OP_NTYPES
} sg_op_type;

typedef struct sg_operand {
    sg_op_type type;
    int i1, i2;             /* Zemax's Int1 and Int2 (surface, wave, rings, operand) */
    double hx, hy, px, py;  /* Zemax's Data1 to Data4: the normalized field and pupil,
                             * or the type's own (sg_op_keys) */
    double target, weight;
} sg_operand;

typedef enum sg_merit_ref {
    SG_MERIT_CENTROID = 0,
    SG_MERIT_CHIEF = 1
} sg_merit_ref;

typedef struct sg_merit {
    int present;            /* the design has a "merit" object */
    int has_default;        /* the generated default part */
    int reference;          /* sg_merit_ref */
    int rings, arms;        /* pupil sampling of the default part */
    int nop;
    sg_operand op[SG_MAX_OPERANDS];
} sg_merit;

/* Configurations (Zemax's Multi-Configuration Editor; sagitta-design(5),
 * CONFIGURATIONS): operands, each a parameter of the design with one value
 * per configuration.  type is Zemax's name: THIC, CRVT, CONI, SDIA, GLSS
 * (surface num), PRAM (surface num, parameter num2), APER, STPS, TEMP,
 * PRES (num 0), XFIE, YFIE, FLWT (field num), WAVE, WLWT (wavelength num).
 * Shared between copies of a design and not changed once made. */
#define SG_MAX_CONFIGS 256
#define SG_MAX_CONFIG_OPS 512
typedef struct sg_config_op {
    char type[8];
    int num, num2;
    double *value;     /* n values; CRVT a curvature, STPS a surface */
    sg_material *mat;  /* GLSS: n materials; NULL for the others */
} sg_config_op;
typedef struct sg_configs {
    int refs;
    int n;             /* configurations, 2 or more */
    int current;       /* the one the design's own values are: 1 to n */
    int nop;
    sg_config_op op[SG_MAX_CONFIG_OPS];
} sg_configs;
/* Tolerances (sagitta-design(5), TOLERANCES; sagitta(1), TOLERANCING):
 * Zemax's tolerance operands, compensators, a criterion and Monte Carlo
 * settings.  Min and max are changes from the nominal value. */
#define SG_MAX_TOL_OPERANDS 200
#define SG_MAX_COMPENSATORS 16
typedef enum sg_tol_type {
    SG_TOL_TRAD = 0, SG_TOL_TCUR, SG_TOL_TFRN, SG_TOL_TTHI, SG_TOL_TCON, SG_TOL_TPAR,
    SG_TOL_TSDX, SG_TOL_TSDY, SG_TOL_TSTX, SG_TOL_TSTY,
    SG_TOL_TEDX, SG_TOL_TEDY, SG_TOL_TETX, SG_TOL_TETY, SG_TOL_TETZ,
    SG_TOL_TIND, SG_TOL_TABB, SG_TOL_TIRR, SG_TOL_TEZI,
    SG_TOL_NTYPES
} sg_tol_type;
typedef struct sg_tol_operand {
    sg_tol_type type;
    int surface;            /* the surface; an element's first */
    int last;               /* an element's last surface */
    int adjust;             /* TTHI: the surface whose thickness takes the opposite change, or -1 */
    char param[32];         /* TPAR: the parameter table's key */
    int elem;               /* TPAR: its element */
    int zmin, zmax;         /* TEZI: the Standard Zernike terms (Noll's j) it spans */
    double min, max;
} sg_tol_operand;
typedef struct sg_tol_comp {
    int surface;
    char param[32];         /* the parameter table's key ("thickness") */
    int elem;
    double min, max;        /* changes from the nominal */
} sg_tol_comp;
typedef enum sg_tol_crit {
    SG_TOLC_RMS_SPOT = 0, SG_TOLC_MERIT = 1, SG_TOLC_RMS_WAVEFRONT = 2
} sg_tol_crit;
typedef enum sg_tol_dist {
    SG_TOLD_NORMAL = 0, SG_TOLD_UNIFORM = 1, SG_TOLD_PARABOLIC = 2
} sg_tol_dist;
typedef struct sg_tolerances {
    int present;            /* the design has a "tolerances" object */
    int nop, ncomp;
    sg_tol_operand op[SG_MAX_TOL_OPERANDS];
    sg_tol_comp comp[SG_MAX_COMPENSATORS];
    int criterion;          /* sg_tol_crit */
    int reference;          /* sg_spot_ref: 0 chief, 1 centroid */
    int pattern, density;   /* the criterion's pupil sampling (sg_pupil_pattern) */
    int grid;               /* the wavefront criterion's grid (64) */
    int trials;             /* Monte Carlo trials (0: none given) */
    double seed;            /* an integer from 0 to 2^53 */
    int distribution;       /* sg_tol_dist */
    double test_wave;       /* TFRN's and TIRR's test wavelength, um (0: Zemax's 0.6328) */
} sg_tolerances;

typedef struct sg_system {
    char title[128];
    char units[8]; /* "mm", "cm", "in" or "m" */

    int nwave;
    int primary_wave; /* 0-based */
    sg_wave wave[SG_MAX_WAVES];

    sg_field_type field_type;
    sg_field_norm field_norm;
    int nfield;
    sg_field field[SG_MAX_FIELDS];

    sg_aper_type aper_type;
    double aper_value;
    sg_aim aim;
    /* Object-space telecentric (Zemax's "Telecentric Object Space"): the
     * entrance pupil is at infinity whatever the stop, every chief ray
     * leaves the object parallel to the axis, the aperture is an object
     * NA, the object is at a finite distance, fields are heights, and ray
     * aiming does not apply (the rays are fixed in object space). */
    int telecentric;
    /* Afocal image space (Zemax's "Afocal Image Space"): image-space
     * aberrations are angles, the differences of the rays' direction
     * cosines l and m from the chief ray's on the image surface (Zemax's
     * ANAX and ANAY), so the spot diagram and ray fans are angular. */
    int afocal;

    /* The environment (Zemax's ENVD): temperature in C (20) and pressure
     * in atm (1) of the air the wavelengths are measured in.  With
     * adjust_index nonzero each glass's index follows them by Zemax's
     * thermal model (sg_glass_index_env); with 0 (the default, Zemax's
     * "Adjust Index Data To Environment" unchecked) catalog indices are
     * used as they are. */
    double temperature, pressure;
    int adjust_index;

    /* The merit function; merit.present 0 when the design has none. */
    sg_merit merit;
    /* Tolerances; tol.present 0 when the design has none. */
    sg_tolerances tol;

    int stop; /* surface index of the aperture stop */
    int nsurf;   /* surfaces 0..nsurf-1; object is 0, image is nsurf-1 */
    int capsurf; /* allocated */
    sg_surface *surf;
    /* The .zmx file the design was read from (its lines, encoding and the
     * design as read), shared between copies; NULL for any other design.
     * sg_system_assign, _clone and _free keep its count. */
    struct sg_zmx_origin *zmx;
    /* Its configurations, shared between copies like zmx; NULL: one. */
    sg_configs *configs;
} sg_system;

/* Configurations.  sg_configs_new makes n configurations without
 * operands (refs 1); sg_configs_add appends one operand, its values 0
 * (SG_ERANGE naming the type when it is not one of the list above or
 * the table is full); retain and release keep the count.  sg_config_count
 * is 1 for a design without configurations.  sg_config_apply sets every
 * operand of configuration k (1 to the count) in sys, so that every
 * analysis of the result is configuration k's; the message names the
 * operand whose target (surface, field, wavelength) is not in the design.
 * sg_configs_check applies each configuration to a copy and validates
 * it. */
SG_API sg_configs *sg_configs_new(int n);
SG_API int sg_configs_add(sg_configs *c, const char *type, int num, int num2, sg_diag *d);
SG_API void sg_configs_retain(sg_configs *c);
SG_API void sg_configs_release(sg_configs *c);
SG_API int sg_configs_equal(const sg_configs *a, const sg_configs *b);
SG_API int sg_config_count(const sg_system *sys);
SG_API int sg_config_apply(sg_system *sys, int k, sg_diag *d);
SG_API int sg_configs_check(const sg_system *sys, const sg_catalog *cat, sg_diag *d);
/* The editor's switch to configuration k (Zemax's current configuration):
 * a new table (refs 1) that holds sys's own values of every operand as
 * configuration current's, so an edit made there is kept, with current
 * set to k; sys's configs are not changed.  Then sg_config_apply(sys, k)
 * with the new table shows k.  NULL when out of memory or sys has no
 * configurations. */
SG_API sg_configs *sg_configs_switch(const sg_system *sys, int k);

/* What stopped a ray that failed at surface surf with status: for the
 * stopped codes the kind and the surface ("ray stopped by the circular
 * obscuration of surface 2", "ray outside the clear semi-diameter 5 of
 * surface 1"), for others the code's message and the surface.  Writes
 * at most len bytes (always terminated); returns buf. */
SG_API char *sg_ray_stop_text(const sg_system *sys, int surf, int status, char *buf, size_t len);

/* ------------------------------------------------------------------------
 * Parameters.  One table (src/model/param.c) describes every parameter of the
 * system, its wavelengths, fields and surfaces: its JSON key, the editor's
 * column, its kind, limits, default and .zmx keyword, and where it lives in
 * the struct.  JSON reading and writing, validation, equality and the
 * editor's cells are driven by it, so a new parameter is one row.
 * ------------------------------------------------------------------------ */

typedef enum sg_param_scope {
    SG_SCOPE_SYSTEM = 0,  /* an sg_system */
    SG_SCOPE_WAVE = 1,    /* an sg_wave */
    SG_SCOPE_FIELD = 2,   /* an sg_field */
    SG_SCOPE_SURFACE = 3, /* an sg_surface */
    SG_SCOPE_COUNT
} sg_param_scope;

typedef enum sg_param_kind {
    SG_PARAM_REAL = 0,    /* count doubles */
    SG_PARAM_BOOL = 1,    /* an int, 0 or 1 */
    SG_PARAM_ENUM = 2,    /* an int (an enum), one of names[] */
    SG_PARAM_TEXT = 3,    /* char[size]; one of names[] when names is set */
    SG_PARAM_MATERIAL = 4 /* an sg_material */
} sg_param_kind;

#define SG_PARAM_NONNEG 0x01u    /* not negative */
#define SG_PARAM_POSITIVE 0x02u  /* above zero */
#define SG_PARAM_INF 0x04u       /* +-inf allowed, written "inf"; 0 reads as inf (a radius) */
#define SG_PARAM_OBJ_INF 0x08u   /* +inf allowed on the object surface alone */
#define SG_PARAM_OPTIONAL 0x10u  /* written only when not at its default */
#define SG_PARAM_REQUIRED 0x20u  /* a JSON object must give it */
#define SG_PARAM_NESTED 0x40u    /* not a JSON key of its own: design_json.c reads and
                                  * writes it inside a nested object (a frame change) */
#define SG_PARAM_SHAPE 0x80u     /* a shape's own: read only by the types whose record
                                  * lists it (src/shape/shape.h, sg_param_used) */

typedef struct sg_param {
    const char *key;       /* JSON key, e.g. "semi_diameter" */
    const char *label;     /* in messages, e.g. "semi-diameter"; arrays: a
                            * format of the element's number ("asphere term r^%d") */
    const char *heading;   /* editor column heading ("r^%d" per element); NULL: none */
    const char *cell;      /* editor command name ("a%d" per element) */
    const char *zmx;       /* the .zmx keyword that holds it, or NULL */
    sg_param_kind kind;
    unsigned flags;        /* SG_PARAM_* */
    size_t offset;         /* offsetof in the scope's struct */
    size_t size;           /* bytes of a TEXT buffer */
    int count;             /* REAL elements (1: a scalar) */
    int elem_mul, elem_add; /* element k is numbered elem_mul * k + elem_add */
    double min, max;       /* REAL limits, inclusive, after the finite check */
    double def;            /* default of a REAL, BOOL or ENUM */
    const char *const *names; /* ENUM and TEXT: the values as JSON writes them */
    const char *const *shown; /* ENUM: as the editor and .zmx files show them */
    int nnames;
    int version;           /* the first design format version with the key */
} sg_param;

/* The scope's parameters in JSON order; NULL beyond the end. */
SG_API int sg_param_count(sg_param_scope scope);
SG_API const sg_param *sg_param_at(sg_param_scope scope, int i);
/* By JSON key; NULL when none. */
SG_API const sg_param *sg_param_find(sg_param_scope scope, const char *key);
/* Element k of a REAL, or a BOOL or ENUM as a double, from the scope's
 * struct obj. */
SG_API double sg_param_get(const sg_param *p, const void *obj, int k);
/* Sets element k of a REAL, BOOL or ENUM (no checks: see sg_param_check). */
SG_API void sg_param_set(const sg_param *p, void *obj, int k, double v);
/* The address of the parameter in obj. */
SG_API void *sg_param_ptr(const sg_param *p, void *obj);
SG_API const void *sg_param_cptr(const sg_param *p, const void *obj);
/* SG_OK when v may be element k's value (the object surface when object
 * is nonzero); else SG_ERANGE, with "LABEL: ..." in msg (may be NULL). */
SG_API int sg_param_check(const sg_param *p, int k, double v, int object, char *msg, size_t n);
/* The label of element k ("asphere term r^4"), the heading ("r^4") and
 * the cell name ("a4"). */
SG_API void sg_param_label(const sg_param *p, int k, char *buf, size_t n);
SG_API void sg_param_heading(const sg_param *p, int k, char *buf, size_t n);
SG_API void sg_param_cell(const sg_param *p, int k, char *buf, size_t n);
/* Whether a surface of type reads element k of surface parameter p (each
 * shape reads only its own; the editor shows the rest dim). */
SG_API int sg_param_used(const sg_param *p, int k, int type);
/* Whether p is a part of the material (a model glass's nd or vd,
 * "material.nd" and "material.vd"), which only a model glass has. */
SG_API int sg_param_material_part(const sg_param *p);
/* Every parameter of obj at its default. */
SG_API void sg_param_defaults(sg_param_scope scope, void *obj);
/* Nonzero when every parameter of a and b is the same, bit for bit. */
SG_API int sg_param_equal(sg_param_scope scope, const void *a, const void *b);
/* Nonzero when the whole systems are the same, bit for bit: every
 * parameter, wavelength, field and surface, and the stop. */
SG_API int sg_system_equal(const sg_system *a, const sg_system *b);

/* A new system: object at infinity, stop on surface 1, image; one
 * wavelength (0.5875618 um), one on-axis field, EPD 10. */
SG_API sg_system *sg_system_new(void);
SG_API void sg_system_free(sg_system *sys);
/* A deep copy, or NULL when out of memory. */
SG_API sg_system *sg_system_clone(const sg_system *sys);
/* Copies src into dst, reusing dst's storage where it can. */
SG_API int sg_system_assign(sg_system *dst, const sg_system *src);
/* Sets every field to an empty system with n default surfaces (flat, air). */
SG_API int sg_system_reset(sg_system *sys, int nsurf);
/* Inserts a flat air surface before index at (1 <= at <= nsurf-1). */
SG_API int sg_system_insert(sg_system *sys, int at);
/* Deletes surface at (1 <= at <= nsurf-2); the stop moves with its rows. */
SG_API int sg_system_delete(sg_system *sys, int at);
SG_API void sg_surface_init(sg_surface *s);
/* Checks what a trace needs: enough surfaces, one stop, finite values,
 * known glasses (when cat is not NULL), wavelengths and fields.  The
 * message names the surface and field at fault. */
SG_API int sg_system_validate(const sg_system *sys, const sg_catalog *cat, sg_diag *d);
/* Whether normalized field coordinates (hx, hy) give a field a trace can
 * launch: Zemax's scaling of the largest field (of the angle itself for
 * angle fields), below 90 degrees.  The message names the field. */
SG_API int sg_field_check(const sg_system *sys, double hx, double hy, sg_diag *d);
/* Curvature 1/R, 0 for a flat. */
SG_API double sg_surface_curvature(const sg_surface *s);
/* Sag z(x, y) in the surface's local frame; NaN outside the conic's domain. */
SG_API double sg_surface_sag(const sg_surface *s, double x, double y);
/* Whether a frame change moves or turns anything. */
SG_API int sg_frame_change_is_zero(const sg_frame_change *c);
/* Solves.  Names are the JSON and editor words ("pickup", "marginal_height",
 * "marginal_angle", "fnum", "chief_height", "curvature_pickup",
 * "position"; "radius", "thickness", "conic"); NULL when out of range. */
SG_API const char *sg_solve_kind_name(sg_solve_kind k);
/* Whether kind is a pickup, whose from, scale and offset are used. */
SG_API int sg_solve_is_pickup(sg_solve_kind k);
/* Whether kind names another surface in from (pickups, position), so that
 * inserting and deleting surfaces renumbers it. */
SG_API int sg_solve_has_from(sg_solve_kind k);
SG_API const char *sg_solve_target_name(sg_solve_target t);
/* Whether kind may sit on target. */
SG_API int sg_solve_allowed(sg_solve_target t, sg_solve_kind k);
/* Checks the solve on target of surface i (kind, source surface, value):
 * SG_ERANGE with a message naming the surface. */
SG_API int sg_solve_check(const sg_system *sys, int i, sg_solve_target t, sg_diag *d);
/* Whether any surface holds a solve. */
SG_API int sg_system_has_solves(const sg_system *sys);
/* Evaluates every solve and pickup in surface order, at the primary
 * wavelength, in 128-bit MPFR, and stores the values (rounded once) in the
 * surfaces.  Solves that depend on the entrance pupil are repeated until
 * no value changes.  A solve without a solution (the marginal ray on the
 * axis, parallel to it, or a surface without power) is SG_ENONPHYS naming
 * the surface; the system is then left with the values of the last pass. */
SG_API int sg_system_apply_solves(sg_system *sys, const sg_catalog *cat, sg_diag *d);

/* ------------------------------------------------------------------------
 * Parameter addresses: one numeric parameter of a design, named through
 * the parameter table (scope, index of the wavelength, field or surface,
 * the table's key, the element of an array), so optimization variables
 * address every parameter without a list of their own.
 * ------------------------------------------------------------------------ */
typedef struct sg_paddr {
    sg_param_scope scope;
    int index;              /* wavelength, field or surface; 0 for the system */
    const sg_param *param;  /* a REAL row of the scope's table */
    int elem;               /* element of an array parameter; 0 for a scalar */
} sg_paddr;
/* Fills a from scope, index, key and element; SG_ERANGE with a message
 * naming what is wrong (no such key, not a real number, element or index
 * out of range). */
SG_API int sg_paddr_make(const sg_system *sys, sg_param_scope scope, int index, const char *key,
                  int elem, sg_paddr *a, sg_diag *d);
/* The value at a, and setting it (no checks: see sg_paddr_check). */
SG_API double sg_paddr_get(const sg_system *sys, const sg_paddr *a);
SG_API void sg_paddr_set(sg_system *sys, const sg_paddr *a, double v);
/* SG_OK when v may be the value at a; else SG_ERANGE with a message. */
SG_API int sg_paddr_check(const sg_system *sys, const sg_paddr *a, double v, sg_diag *d);
/* "surface 3 radius", "surface 5 asphere term r^4" ... */
SG_API void sg_paddr_name(const sg_paddr *a, char *buf, size_t n);
/* The solve target (radius, thickness, conic) a names, or -1. */
SG_API int sg_paddr_solve_target(const sg_paddr *a);

/* ------------------------------------------------------------------------
 * The merit function and optimization (src/design/merit.c, src/design/optimize.c;
 * sagitta(1), OPTIMIZATION)
 * ------------------------------------------------------------------------ */
/* Zemax's name of an operand type ("EFFL"), and the type of a name; -1
 * when unknown. */
SG_API const char *sg_op_name(sg_op_type t);
SG_API int sg_op_parse(const char *name);
/* The JSON names of an operand type's Int1, Int2 and Data1 to Data4
 * (stored in i1, i2, hx, hy, px, py); NULL where the type has none. */
SG_API void sg_op_keys(sg_op_type t, const char *keys[6]);
/* After inserting (dir 1) or deleting (dir -1) surface at: the operands'
 * surface numbers (sg_op_keys "surf", "surf1", "surf2") naming later
 * surfaces follow them, as Zemax renumbers its Merit Function Editor; one
 * naming the deleted surface keeps its number (sg_system_insert and
 * sg_system_delete call it). */
SG_API void sg_merit_renumber(sg_merit *m, int at, int dir);
/* Checks the merit function's rows against sys (surfaces, wavelengths,
 * operand numbers in range): SG_ERANGE naming the row. */
SG_API int sg_merit_check(const sg_system *sys, sg_diag *d);

/* One row's result. */
typedef struct sg_merit_row {
    int row;                /* 1-based: the operands, then the default rows */
    sg_op_type type;        /* the default's rows are TRAX and TRAY */
    double value, target, weight;
    double contribution;    /* percent of the sum */
} sg_merit_row;

typedef struct sg_merit_result {
    double merit;           /* MF */
    double wsum;            /* sum of the weights */
    int nrow;               /* operands, then default rows */
    sg_merit_row *row;      /* malloc'd; sg_merit_result_free */
    double bound;           /* a bound on the rounding of the traced values */
} sg_merit_result;
/* Evaluates every row at sys.  A row that cannot be computed (a ray that
 * misses, a surface out of range) is an error naming the row and why;
 * the merit is never NaN. */
SG_API int sg_merit_eval(const sg_system *sys, const sg_catalog *cat, sg_merit_result *out,
                  sg_diag *d);
SG_API void sg_merit_result_free(sg_merit_result *r);
/* Nonzero when two merit functions are the same, bit for bit. */
SG_API int sg_merit_equal(const sg_merit *a, const sg_merit *b);
/* Gauss-Legendre nodes and weights of the default's rings: n points on
 * [0, 1] in u = rho^2 (Forbes, JOSA A 5, 1943 (1988)); rho[k] = sqrt(u),
 * w[k] sums to 1.  n at most 32. */
SG_API int sg_merit_rings(int n, double *rho, double *w);

/* The variables of a design: every solve of kind variable, in surface
 * order (radius, thickness, conic).  Returns the count (at most cap). */
SG_API int sg_variables(const sg_system *sys, sg_paddr *out, int cap);
/* Whether a is a variable (a solve of kind variable or a surface's var
 * entry), with its bounds in lo and hi when it is. */
SG_API int sg_variable_bounds(const sg_system *sys, const sg_paddr *a, double *lo, double *hi);
/* Makes parameter key (element elem) of surface surf a variable within
 * [lo, hi] (on), or not (off): radius, thickness and conic through their
 * solves, any other REAL row of the surface table through the surface's
 * var list.  SG_ERANGE naming what is wrong: no such key or element, a
 * parameter the surface's type does not read, lo above hi, a full list,
 * or (off) one that is not a variable. */
SG_API int sg_variable_set(sg_system *sys, int surf, const char *key, int elem, int on,
                           double lo, double hi, sg_diag *d);

typedef struct sg_opt_opts {
    int cycles;             /* at most this many; 0: until converged (500) */
    int nthreads;           /* for the Jacobian's columns; 0: one */
    /* Called after each cycle (may be NULL); a nonzero return stops. */
    int (*progress)(void *ctx, int cycle, double merit, double step, double seconds);
    void *ctx;
    volatile int *stop;     /* when set nonzero (a signal), the run stops */
    /* Global search (sagitta(1), OPTIMIZATION): when global_seconds > 0,
     * multi-start damped least squares from the points of a Halton set
     * inside the variables' bounds (every variable needs min and max),
     * from index seed + 1 on, for global_seconds or global_starts starts
     * (0: no limit), whichever ends first; the best design is kept.  The
     * progress callback is then called once a start, with the start's
     * number and the best merit so far. */
    double global_seconds;
    int global_starts;
    unsigned seed;
} sg_opt_opts;
SG_API void sg_opt_opts_init(sg_opt_opts *o);

typedef struct sg_opt_result {
    int cycles;
    double merit0, merit;   /* before and after */
    int converged;
    int stopped;            /* stopped by *stop or progress */
} sg_opt_result;
/* Damped least squares (GSL's trust-region Levenberg-Marquardt with
 * scaling) on the variables of sys against its merit function; sys gets
 * the best design found (variables and what their solves derive), also
 * when stopped.  SG_ENOSYS when the design has no variables or no merit
 * function. */
SG_API int sg_optimize(sg_system *sys, const sg_catalog *cat, const sg_opt_opts *o,
                sg_opt_result *res, sg_diag *d);

/* Whether a surface changes the frame: a coordinate break, or a tilt or
 * decenter before or after it. */
SG_API int sg_surface_moves_frame(const sg_surface *s);

/* ------------------------------------------------------------------------
 * JSON designs
 * ------------------------------------------------------------------------ */

/* Loads a design.  On failure the message reads "FILE:LINE:COL: ..." for
 * syntax errors and "FILE: surface N: field: ..." for content errors. */
SG_API int sg_design_load(sg_system *sys, const char *path, sg_diag *d);
/* Parses a design held in memory; name is used in messages. */
SG_API int sg_design_parse(sg_system *sys, const char *text, size_t len,
                    const char *name, sg_diag *d);
/* Writes a design atomically: a temporary file in the same directory,
 * fsync, then rename.  A failure leaves any existing file intact.  The file
 * keeps its owner, group and mode; a symbolic link, even a dangling one,
 * is written through; a file whose owner a new file could not keep, or in
 * a directory where no temporary can be made, or one with other hard
 * links (which a rename would leave on the old bytes), is rewritten in
 * place after a backup of its bytes (beside it, in $TMPDIR or /tmp),
 * removed once the write is synced. */
SG_API int sg_design_save(const sg_system *sys, const char *path, sg_diag *d);
/* The design as a NUL-terminated JSON text; free() it. */
SG_API char *sg_design_to_json(const sg_system *sys);
/* A program may list the temporary files the atomic saves make beside
 * their targets: hook(path, 1) once one exists, hook(path, 0) once it is
 * renamed into place or removed, so that a signal ending the program
 * meanwhile can remove it.  NULL (the default): none.  Set it once, before
 * any save. */
typedef void (*sg_temp_hook)(const char *path, int add);
SG_API void sg_set_temp_hook(sg_temp_hook hook);

/* sg_design_load reads a Zemax .zmx lens file too (by its name, or by a
 * byte-order mark or a first VERS or MODE line), and sg_design_save writes
 * one when the name ends in .zmx.  The functions below do the same with a
 * catalog of the caller's: the reader checks each glass in it (NULL: the
 * default catalog) and names the nearest by nd and vd for one it lacks.
 * What the model cannot hold (a tilt after a surface, surface types
 * beyond sagitta-design(5)'s, several configurations...) is refused with
 * SG_EUNSUPPORTED and a message "FILE:LINE: surface N: KEYWORD: ...";
 * values are read as the file stores them; the solves sagitta evaluates
 * (MAZH at zone 0, CHZH, PZUP of a thickness, a CURV pickup of offset 0,
 * the CURV marginal ray angle and F number, types 2 and 11) are kept in the
 * surfaces' solve[] with a note, the others frozen with a warning.  See sagitta-design(5), ZEMAX FILES. */
SG_API int sg_zmx_parse(sg_system *sys, const void *bytes, size_t len, const char *name,
                 const sg_catalog *cat, sg_diag *d);
SG_API int sg_zmx_load(sg_system *sys, const char *path, const sg_catalog *cat, sg_diag *d);
/* Glasses substituted on reading a .zmx file, for a glass the catalog
 * lacks: pairs[i] is "NAME=GLASS" (GLASS by the catalog's search order);
 * with nearest set, any other missing glass whose nd and vd the file
 * stores takes the catalog's nearest by nd and vd.  Each substitution is
 * reported as a warning; the design keeps the substitute, and a lossless
 * save writes the file's own glass back. */
typedef struct sg_zmx_subst {
    int n;
    const char *const *pairs;
    int nearest;
} sg_zmx_subst;
SG_API int sg_zmx_parse_subst(sg_system *sys, const void *bytes, size_t len, const char *name,
                       const sg_catalog *cat, const sg_zmx_subst *sub, sg_diag *d);
SG_API int sg_zmx_load_subst(sg_system *sys, const char *path, const sg_catalog *cat,
                      const sg_zmx_subst *sub, sg_diag *d);
/* The design as .zmx text (UTF-8, Zemax keywords); NULL on failure. */
SG_API char *sg_zmx_to_text(const sg_system *sys, const sg_catalog *cat, sg_diag *d);
/* Writes a .zmx file atomically, as sg_design_save does.  A design read
 * from a .zmx file is written losslessly: every line of that file comes
 * back unchanged, in its encoding, except the lines an edit concerns
 * (sagitta-design(5), ZEMAX FILES).  Where that cannot be done faithfully
 * (the file would read back as another design, surfaces were inserted or
 * deleted while kept lines name surfaces by number, a character the
 * encoding lacks) nothing is written and the result is SG_ELOSSY, its
 * message saying what; with SG_ZMX_ALLOW_LOSS the file is written all the
 * same (as sagitta's own .zmx text where the lossless one would read back
 * wrong) with a warning. */
SG_API int sg_zmx_save(const sg_system *sys, const char *path, const sg_catalog *cat, sg_diag *d);
#define SG_ZMX_ALLOW_LOSS 1u
SG_API int sg_zmx_save_flags(const sg_system *sys, const char *path, const sg_catalog *cat,
                      unsigned flags, sg_diag *d);
/* sg_design_save with flags for a .zmx name (SG_ZMX_ALLOW_LOSS). */
SG_API int sg_design_save_flags(const sg_system *sys, const char *path, unsigned flags, sg_diag *d);
/* How many lines of the .zmx file sys was read from hold what sagitta does
 * not interpret (and a JSON design does not keep); 0 for other designs. */
SG_API int sg_zmx_kept_lines(const sg_system *sys);
/* Nonzero when path ends in .zmx (any case) or the first n bytes of head
 * (may be NULL) look like a lens file rather than JSON. */
SG_API int sg_zmx_detect(const char *path, const void *head, size_t n);

/* Zemax archives (.zar): the one lens file inside is read by sg_zmx_parse,
 * its messages naming "ARCHIVE:LENS.ZMX:LINE".  Glasses still come from
 * cat (NULL: the default catalog); a glass missing there is reported with
 * the archive's own catalogs named.  Damaged or hostile archives get
 * SG_EPARSE naming the member and byte; at most 64 MiB is unpacked.  See
 * sagitta-design(5), ZEMAX ARCHIVES. */
SG_API int sg_zar_parse(sg_system *sys, const void *bytes, size_t len, const char *path,
                 const sg_catalog *cat, sg_diag *d);
SG_API int sg_zar_load(sg_system *sys, const char *path, const sg_catalog *cat, sg_diag *d);
/* One member unpacked into *out (malloc'd, NUL after its *outlen bytes):
 * the one named want (any case, without ".LZW"), or with want NULL the
 * lens file; name (may be NULL) gets its name. */
SG_API int sg_zar_member(const void *bytes, size_t len, const char *path, const char *want,
                  void **out, size_t *outlen, char name[256], sg_diag *d);
/* Nonzero when path ends in .zar (any case) or head starts as an archive. */
SG_API int sg_zar_detect(const char *path, const void *head, size_t n);

/* ------------------------------------------------------------------------
 * Paraxial data (y-nu trace)
 * ------------------------------------------------------------------------ */

typedef struct sg_paraxial {
    double efl;          /* effective focal length (image space) */
    double bfl;          /* last surface to paraxial focus, for an infinite object */
    double image_dist;   /* last surface to paraxial image of the object */
    double epd;          /* entrance pupil diameter */
    double enp_pos;      /* entrance pupil, measured from surface 1 */
    double exp_diam;     /* exit pupil diameter */
    double exp_pos;      /* exit pupil, measured from the image surface */
    double image_fnum;   /* EFL / EPD */
    double working_fnum; /* 1 / (2 n' |u'|) of the paraxial marginal ray */
    double object_na;    /* n sin(U) of the paraxial marginal ray, finite object */
    double parax_image_height; /* of the largest field */
    double magnification;      /* paraxial lateral magnification; 0 at infinity */
    double total_track;        /* surface 1 to image */
    double stop_radius;        /* paraxial marginal height on the stop */
} sg_paraxial;

/* Paraxial data at wavelength index wave (0-based).  Mirrors follow the
 * sign convention n' = -n. */
SG_API int sg_paraxial_compute(const sg_system *sys, const sg_catalog *cat, int wave,
                        sg_paraxial *out, sg_diag *d);

/* ------------------------------------------------------------------------
 * Ray tracing
 * ------------------------------------------------------------------------ */

typedef enum sg_method {
    SG_METHOD_PRECISE = 0, /* the paper's four measures, carried in double-double */
    SG_METHOD_CLASSIC = 1, /* textbook: global frame, direct quadratic formula */
    SG_METHOD_MPFR = 2     /* every operation in MPFR; the reference */
} sg_method;

SG_API const char *sg_method_name(sg_method m);
/* Parses "precise", "classic" or "mpfr"; returns -1 when unknown. */
SG_API int sg_method_parse(const char *s);

typedef struct sg_trace_opts {
    sg_method method;
    int mpfr_bits;      /* precision of the mpfr method; default 256 */
    int wave;           /* 0-based wavelength index; -1 means primary */
    int clip;           /* nonzero: flag rays beyond fixed semi-diameters */
    double clip_rtol;   /* relative tolerance of that test; default 1e-9 */
    int max_iter;       /* Newton iterations for aspheres; default 50 */
    int aim_max_iter;   /* ray-aiming Newton iterations; default 50 */
    double aim_rtol;    /* aiming tolerance relative to the stop radius; default 1e-13 */
} sg_trace_opts;

SG_API void sg_trace_opts_init(sg_trace_opts *o);

/* The result at one surface, in that surface's local frame. */
typedef struct sg_ray_surface {
    double x, y, z;     /* intersection point */
    double l, m, n;     /* direction cosines after the surface */
    double residual;    /* |z - sag(x, y)| of the reported point */
    double error_bound; /* bound on max |coordinate error| against exact arithmetic */
    double dir_error_bound; /* the same for l, m, n */
    double path;        /* geometric distance from the previous surface */
    /* Optical path from the ray's start to this point: the sum of |index|
     * times each signed step, in lens units.  A finite object's rays start
     * at the object point; an object at infinity's on the plane through
     * the primary wavelength's chief ray's point on surface 1, normal to
     * the field's direction; rays given by start and direction at their
     * start.  opl + opl_lo is the path in double-double (opl_lo is 0 in
     * the classic method), and opl_error_bound bounds its error. */
    double opl, opl_lo, opl_error_bound;
    int status;         /* SG_OK or a ray failure: SG_EMISS, SG_ETIR, ... */
} sg_ray_surface;

/* A surface's frame in a global one: a point p given in the surface's
 * local frame is R p + o globally, and a direction u is R u.  R's columns
 * are the local axes. */
typedef struct sg_frame {
    double R[3][3];
    double o[3];
} sg_frame;
/* Every surface's frame (out[0..nsurf-1]) relative to the frame of
 * surface ref, Zemax's global coordinate reference surface (1 by
 * default; 0 is refused for an object at infinity, whose frame has no
 * place).  Computed in 256-bit MPFR and rounded. */
SG_API int sg_global_frames(const sg_system *sys, int ref, sg_frame *out, sg_diag *d);
/* A trace row in surface i's local frame to the global frame f: point,
 * direction and their bounds (a rotation can grow a coordinate's error by
 * the rows of R; the conversion's rounding is added). */
SG_API void sg_row_to_global(const sg_frame *f, sg_ray_surface *row);
/* The rows of nray rays (nsurf each, as the batch writes them) to the
 * frames gf of sg_global_frames.  Rows a ray did not reach keep their NaN,
 * and an object at infinity its infinities.  Row 0 of a ray given by start
 * and direction (start_dir nonzero) is in surface 1's frame, of a
 * normalized ray in the object's. */
SG_API void sg_rows_to_global(const sg_frame *gf, sg_ray_surface *rows, size_t nray, int nsurf,
                       int start_dir);

/* Zemax's automatic semi-diameters. */
typedef struct sg_semidiam_opts {
    sg_trace_opts trace; /* the method; every wavelength is traced (trace.wave
                            is not used); clip off, so no fixed aperture
                            hides a ray */
    int ring;            /* rays on the pupil's edge a field and wavelength (64) */
    int refine;          /* golden-section steps refining each surface's
                            highest ray along the edge (40) */
    int zemax;           /* 1: Zemax's figure, the highest of the rays
                            (Px, Py) = (0, +-1) alone, and (+-1, 0) where a
                            field is off the y axis or the system is not
                            rotationally symmetric; 0 (default): the whole
                            edge, which every ray passes */
} sg_semidiam_opts;
SG_API void sg_semidiam_opts_init(sg_semidiam_opts *o);
/* sd[i] for every surface i: the largest radial height, hypot(x, y) in the
 * surface's frame, of the real rays through the edge of the pupil over
 * every field and wavelength (0 where none reaches, and on the object).
 * The ring finds each surface's highest ray; a golden-section search along
 * the edge refines it.  o NULL takes the defaults. */
SG_API int sg_semi_diameters(const sg_system *sys, const sg_catalog *cat, const sg_semidiam_opts *o,
                      double *sd, sg_diag *d);

/* Zemax's "Set Vignetting": each field's vignetting factors, found at the
 * primary wavelength with the field's own factors cleared.  A grid of
 * grid x grid rays over the unit pupil finds the rays that pass every
 * aperture (and fixed semi-diameter, with trace.clip on, the default);
 * through their centroid, the pupil's top, bottom, left and right edges
 * are bracketed by line samples and bisected to tol.  Then
 *   vdy = (top + bottom) / 2, vcy = 1 - (top - bottom) / 2,
 * likewise in x, and van = 0.  SG_EVIGNETTED names a field no grid ray
 * passes. */
typedef struct sg_setvig_opts {
    sg_trace_opts trace; /* method, clip, aiming tolerances; wave is the primary */
    int grid;            /* rays across the pupil for the centroid (64) */
    int line;            /* samples along an edge's line before bisecting (256) */
    double tol;          /* bisection tolerance in pupil units (1e-12) */
} sg_setvig_opts;
typedef struct sg_vigfactors {
    double vdx, vdy, vcx, vcy, van;
    double cx, cy; /* the centroid of the grid rays that pass */
    long pass;     /* how many grid rays pass */
} sg_vigfactors;
SG_API void sg_setvig_opts_init(sg_setvig_opts *o);
/* out[k] for every field k.  o NULL takes the defaults. */
SG_API int sg_set_vignetting(const sg_system *sys, const sg_catalog *cat, const sg_setvig_opts *o,
                      sg_vigfactors *out, sg_diag *d);
/* Sets every field's factors to vf[field]. */
SG_API void sg_set_vignetting_apply(sg_system *sys, const sg_vigfactors *vf);

/* Thermal expansion, as Zemax's thermal analysis applies it (its Make
 * Thermal tool and thermal pickups; sagitta-design(5), THERMAL
 * EXPANSION).  Every length of a part grows by s = 1 + TCE 1e-6 dT, dT =
 * temp - sys->temperature (the design's own temperature is the reference),
 * and every parameter in lens units to the power k by s^k, so a surface's
 * sag becomes z'(x, y) = s z(x / s, y / s).  Which TCE a value takes:
 *   shape (radius, shape terms, semi-diameter, aperture): the glass after
 *     the surface; else the glass before it (a lens's rear surface, a
 *     back-surface mirror); else the surface's own tce (a mirror's
 *     substrate, a dummy);
 *   thickness: inside a glass, the glass's (the centre thickness scales);
 *     an air space, the tce of the surface where it starts (the mount),
 *     whose spacer touches the surfaces at their semi-diameters: the
 *     spacer's length between those points scales, the points move to
 *     the scaled surfaces at the spacer's scaled radius, and the centre
 *     thickness follows;
 *   decenters of a coordinate break or a surface: its own tce.
 * A catalog glass's TCE is its ED line's -30..+70 C figure (0 without
 * one, with a warning); a model glass or fixed index, which carry none,
 * and a glass flagged to ignore expansion take the tce of their surface. */
typedef struct sg_thermal_tce {
    double shape; /* 1e-6/K: radius, shape terms, semi-diameter, aperture */
    double space; /* the thickness after the surface */
    double place; /* decenters (the surface's own tce) */
    int solid;    /* nonzero: the thickness after lies inside a glass */
} sg_thermal_tce;
/* out[i] for every surface i.  SG_ENOGLASS names a surface whose glass
 * is not in cat (NULL refuses every catalog glass). */
SG_API int sg_thermal_tces(const sg_system *sys, const sg_catalog *cat, sg_thermal_tce *out,
                    sg_diag *d);
/* The design sys as built at temp (C) and pres (atm), into out (an
 * sg_system_new; may be sys): every surface scaled as above, temperature
 * and pressure set, adjust_index on.  Solves and pickups are frozen at
 * their values (the built lens does not refocus), with a warning.
 * SG_ERANGE names the temperature or pressure outside their limits, or
 * the surface whose expansion factor is not positive or whose sag at a
 * spacer's contact height does not exist; on any error out is unchanged. */
SG_API int sg_thermal(const sg_system *sys, const sg_catalog *cat, double temp, double pres,
               sg_system *out, sg_diag *d);

/* Tolerancing (src/design/tolerance.c; sagitta(1), TOLERANCING).  Zemax's names
 * of the operand types ("TRAD"), and the type of a name (-1: unknown). */
SG_API const char *sg_tol_name(sg_tol_type t);
SG_API int sg_tol_parse(const char *name);
/* Checks sys->tol against sys: surfaces, elements, parameters, limits;
 * SG_ERANGE naming the row ("tolerances: operand 3 (TEDX): ..."). */
SG_API int sg_tol_check(const sg_system *sys, sg_diag *d);
/* The nominal prepared for tolerancing: solves applied, then every solve
 * but the pickups frozen at its value (the built lens does not refocus
 * itself; compensators do). */
SG_API int sg_tol_nominal(const sg_system *sys, const sg_catalog *cat, sg_system *out,
                          sg_diag *d);
/* out = nominal with operand k changed by delta[k] (nop values; 0 leaves
 * a row alone), as Zemax applies each operand: element operands insert a
 * coordinate break before the element and one after it that returns to
 * the first vertex's frame.  map (nominal->nsurf entries, may be NULL)
 * gets each nominal surface's index in out.  The nominal is not
 * touched. */
SG_API int sg_tol_apply(const sg_system *nominal, const sg_catalog *cat, const double *delta,
                        sg_system *out, int *map, sg_diag *d);

typedef struct sg_tol_opts {
    int method;             /* sg_method of the criterion's traces (precise) */
    int mpfr_bits;          /* for the mpfr method; 0: 256 */
    int nthreads;           /* systems evaluated at once; 0: every core */
    int compensate;         /* nonzero (default): re-optimize the compensators */
    int cycles;             /* compensator cycles at most; 0: 50 */
    /* Called after each system (may be NULL); nonzero stops the run. */
    int (*progress)(void *ctx, int done, int total);
    void *ctx;
    volatile int *stop;     /* set nonzero (a signal) to stop; what is done is kept */
} sg_tol_opts;
SG_API void sg_tol_opts_init(sg_tol_opts *o);

/* One evaluated system: the criterion over the fields and each field's. */
typedef struct sg_tol_value {
    int status;             /* SG_OK, or why the system could not be evaluated */
    double criterion;
    int nfield;
    double field[SG_MAX_FIELDS];
    double comp[SG_MAX_COMPENSATORS]; /* the compensators' changes */
} sg_tol_value;
/* The criterion of sys (compensators not moved): sqrt(sum w c^2 / sum w)
 * over the fields, c a field's polychromatic RMS spot radius as
 * sg_spot_compute gives it with the tolerances' sampling (or the merit
 * function's value). */
SG_API int sg_tol_criterion(const sg_system *sys, const sg_catalog *cat, const sg_tol_opts *o,
                            sg_tol_value *out, sg_diag *d);
/* sys's compensators (addressed through map, as sg_tol_apply fills it)
 * re-optimized by damped least squares on the criterion; sys gets them,
 * out the criterion there. */
SG_API int sg_tol_compensate(sg_system *sys, const sg_system *nominal, const int *map,
                             const sg_catalog *cat, const sg_tol_opts *o, sg_tol_value *out,
                             sg_diag *d);

/* Trial t's draw for operand k: a counter-based SplitMix64 keyed by
 * (seed, t, k), so it depends on nothing else.  Normal: within +-2 sigma
 * at min and max; uniform; parabolic (density growing as the square of
 * the distance from the centre, Zemax's). */
SG_API double sg_tol_draw(uint64_t seed, uint64_t trial, int k, int dist, double min,
                          double max);

typedef struct sg_tol_stats {
    int n;                  /* values counted (failed systems left out) */
    double best, worst, mean, std;
    double pct[5];          /* at 90, 80, 50, 20 and 10 % cumulative probability */
} sg_tol_stats;
/* Statistics of v[0..n-1], NaNs left out: std with n - 1; the p % value
 * is the smallest value that at least p % of the values do not exceed
 * (Zemax's "90% <= X"). */
SG_API void sg_tol_statistics(const double *v, int n, sg_tol_stats *out);

typedef struct sg_tol_sens {
    int row;                /* 1-based operand row */
    sg_tol_value at_min, at_max;
} sg_tol_sens;
typedef struct sg_tol_result {
    sg_tol_value nominal;
    int nsens;              /* rows done (all, unless stopped) */
    sg_tol_sens *sens;      /* malloc'd, nop rows */
    double rss;             /* sqrt of the sum over rows of the larger |change| squared */
    int trials, done;       /* Monte Carlo: asked, and done in order from 0 */
    uint64_t seed;
    sg_tol_value *mc;       /* malloc'd, trials rows */
    sg_tol_stats stats;
    int stopped;
} sg_tol_result;
/* Sensitivity (when sens) and Monte Carlo (trials > 0) of sys's
 * tolerances.  Every system is a copy; sys is not touched.  The systems
 * run on threads and the results do not depend on their number. */
SG_API int sg_tolerance_run(const sg_system *sys, const sg_catalog *cat, const sg_tol_opts *o,
                            int sens, int trials, uint64_t seed, sg_tol_result *out,
                            sg_diag *d);
SG_API void sg_tol_result_free(sg_tol_result *r);
/* Monte Carlo in blocks, for a caller that streams the trials (sagitta
 * tolerance's table, MPI ranks): open compensates the nominal once (its
 * value in *nominal when not NULL); run evaluates trials first ..
 * first + n - 1 on o's threads into out[0 .. n-1], each as
 * sg_tolerance_run gives it, and *done counts those finished in order
 * from first (fewer than n after o's stop). */
typedef struct sg_tol_mc sg_tol_mc;
SG_API int sg_tol_mc_open(const sg_system *sys, const sg_catalog *cat, const sg_tol_opts *o,
                          uint64_t seed, sg_tol_mc **out, sg_tol_value *nominal, sg_diag *d);
SG_API int sg_tol_mc_run(sg_tol_mc *m, int first, int n, sg_tol_value *out, int *done);
/* Trial trial's system, perturbed and compensated, into out (its
 * criterion in v), as sg_tol_mc_run evaluates it. */
SG_API int sg_tol_mc_system(sg_tol_mc *m, int trial, sg_system *out, sg_tol_value *v,
                            sg_diag *d);
/* Inverse sensitivity: for each operand alone, on each side of the
 * nominal, the change at which the compensated criterion exceeds the
 * nominal's by limit (found by bracketing from the operand's min or max
 * and the Illinois method to 1e-12 of it); status SG_ERANGE where no
 * change up to 2^40 times the operand's range reaches it.  out has nop
 * rows, *done of them filled (fewer when o's stop ended it). */
typedef struct sg_tol_inv_side {
    int status;
    double limit;           /* the operand's change, signed */
    double criterion;       /* the compensated criterion there */
} sg_tol_inv_side;
typedef struct sg_tol_inv {
    sg_tol_inv_side at_min, at_max;
} sg_tol_inv;
SG_API int sg_tol_inverse(sg_tol_mc *m, double limit, sg_tol_inv *out, int *done,
                          sg_diag *d);
SG_API void sg_tol_mc_close(sg_tol_mc *m);
/* A default tolerance set, as Zemax's Tolerance Wizard makes one
 * (sagitta(1), TOLERANCING, Default tolerances); a value of 0 leaves its
 * rows out. */
typedef struct sg_tol_defaults {
    double fringes;         /* TFRN on each surface with power (1 fringe) */
    double radius;          /* > 0: TRAD in lens units on curved ones instead */
    double thickness;       /* TTHI on each thickness, the next air space adjusting (0.2) */
    double sdecenter;       /* TSDX, TSDY on each surface with power (0.2) */
    double stilt_tir;       /* TSTX, TSTY: a runout of this across the diameter (0.2) */
    double irregularity;    /* TIRR on each standard surface with power, fringes (0.2) */
    double edecenter;       /* TEDX, TEDY on each element (0.2) */
    double etilt;           /* TETX, TETY on each element, degrees (0.2) */
    double index;           /* TIND on each glass (0.001) */
    double abbe_pct;        /* TABB on each glass, percent of its Abbe number (1) */
    int focus;              /* the thickness before the image as compensator (1) */
} sg_tol_defaults;
SG_API void sg_tol_defaults_init(sg_tol_defaults *o);
/* sys->tol's operands replaced by the default set built from the surfaces
 * (and its compensators, when it has none, by the back focus); the
 * criterion and Monte Carlo settings kept (or JSON's defaults when the
 * design had no tolerances).  SG_ERANGE when the set would exceed
 * SG_MAX_TOL_OPERANDS; the semi-diameters the tilts need from
 * sg_semi_diameters where not set. */
SG_API int sg_tol_default_set(sg_system *sys, const sg_catalog *cat, const sg_tol_defaults *o,
                              sg_diag *d);

/* A prepared system: indices, paraxial data and work buffers, computed
 * once so the per-ray path allocates nothing.  A tracer is used by one
 * thread at a time; make one per thread. */
typedef struct sg_tracer sg_tracer;

/* Makes a tracer for sys: *out, and SG_OK; or NULL in *out and the error
 * (also in d when given): the system's validation code, SG_ENOGLASS for a
 * glass the catalog lacks, SG_ERANGE for options out of range, SG_EAIM
 * when aiming cannot land the marginal ray, SG_ENOMEM.  The tracer copies
 * sys and opts; cat must outlive it. */
SG_API int sg_tracer_open(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                   sg_tracer **out, sg_diag *d);
/* sg_tracer_open returning the tracer, or NULL (the code in d, when
 * given): kept for the library's ABI; new code calls sg_tracer_open,
 * which returns the code even without a diagnostic. */
SG_API sg_tracer *sg_tracer_new(const sg_system *sys, const sg_catalog *cat,
                         const sg_trace_opts *opts, sg_diag *d);

/* Glass indices kept between the tracers and paraxial data of one design
 * (the editor makes new ones after every edit): a tracer or paraxial
 * computation given a cache takes each glass index it already holds for
 * the same inputs (every number of the glass, the wavelength, the
 * system's temperature, pressure and adjust setting, the precision), and
 * gets the same bits as without it.  The caller owns the cache; it is used
 * only during the call, by one thread at a time. */
typedef struct sg_index_cache sg_index_cache;
SG_API sg_index_cache *sg_index_cache_new(void);
SG_API void sg_index_cache_free(sg_index_cache *c);
SG_API void sg_index_cache_clear(sg_index_cache *c);
/* Lookups answered from the cache and computed, since it was made. */
SG_API void sg_index_cache_stats(const sg_index_cache *c, unsigned long *hits,
                          unsigned long *misses);
/* The cache also keeps the paraxial y-nu traces' state after each surface
 * (the launch's, the mpfr method's, sg_paraxial_compute_cached's): a trace
 * whose start and surfaces up to the first changed one are as before
 * resumes there, with the same bits.  How many have resumed: */
SG_API unsigned long sg_index_cache_resumes(const sg_index_cache *c);
/* sg_tracer_new and sg_paraxial_compute with a cache (NULL: none); NULL
 * on failure with the code in d, when given (the engine's own callers use
 * a form that returns the code).  With
 * a cache, sg_tracer_new_cached also leaves the validation's warnings (a
 * glass used beyond its range) in d, so its caller need not validate
 * the system a second time for them. */
SG_API sg_tracer *sg_tracer_new_cached(const sg_system *sys, const sg_catalog *cat,
                                const sg_trace_opts *opts, sg_index_cache *cache,
                                sg_diag *d);
SG_API int sg_paraxial_compute_cached(const sg_system *sys, const sg_catalog *cat, int wave,
                               sg_index_cache *cache, sg_paraxial *out, sg_diag *d);
SG_API void sg_tracer_free(sg_tracer *t);
/* The mpfr method's ray kept between the tracers of one design (the
 * editor's digits check, after every edit): an mpfr tracer given a memo
 * keeps in it the state of its last normalized or started ray after each
 * surface, with what that state was computed from (the ray's launch bit
 * for bit, the precision, each surface and the one before it, the indices
 * on both sides, the trace options).  The next tracer's ray that launches
 * the same resumes after the last surface before the first that differs,
 * with the same bits as a full trace.  Memory: about 600 bytes a surface
 * at 256 bits, plus a copy of the surfaces.  The caller owns the memo; a
 * tracer uses it only from sg_tracer_use_memo until it is freed or given
 * another, from one thread; other methods ignore it. */
/* A tracer of t's system, wavelength and options but with method
 * `method` (mpfr at mpfr_bits bits): it shares t's prepared surfaces,
 * paraxial data and launch, which a tracer of the precise or mpfr method
 * computes the same way, so it gives the bits sg_tracer_new would, and
 * prepares only what the new method adds (glass indices from cache when
 * given).  t must outlive it.  A classic tracer on either side makes a
 * new tracer from t's system instead.  NULL on failure, with the code in
 * d when given (the engine's own callers use a form that returns it). */
SG_API sg_tracer *sg_tracer_new_method(const sg_tracer *t, sg_method method, int mpfr_bits,
                                sg_index_cache *cache, sg_diag *d);
typedef struct sg_mpfr_memo sg_mpfr_memo;
SG_API sg_mpfr_memo *sg_mpfr_memo_new(void);
SG_API void sg_mpfr_memo_free(sg_mpfr_memo *memo);
SG_API void sg_tracer_use_memo(sg_tracer *t, sg_mpfr_memo *memo);
/* The surface the last ray resumed at (1 when it was traced in full), and
 * how many rays resumed later than surface 1, since the memo was made. */
SG_API int sg_mpfr_memo_last_resume(const sg_mpfr_memo *memo);
SG_API unsigned long sg_mpfr_memo_resumes(const sg_mpfr_memo *memo);
SG_API int sg_tracer_nsurf(const sg_tracer *t);
SG_API const sg_paraxial *sg_tracer_paraxial(const sg_tracer *t);
/* Index of the medium after surface i at the tracer's wavelength
 * (negative after an odd number of mirrors, as in the paraxial trace). */
SG_API double sg_tracer_index(const sg_tracer *t, int i);
/* How many roots the precise method has had to find in MPFR since t was
 * made: rays it could not certify in double-double (grazing, tangent, or
 * an asphere's ill-conditioned root).  Ordinary rays need none; a count
 * that grows on them means a slow trace. */
SG_API unsigned long sg_tracer_rescues(const sg_tracer *t);

/* Traces a ray given in surface 1's local frame: start point and direction
 * (any nonzero length).  out has nsurf entries; out[0] holds the start.
 * Returns SG_OK when the ray reaches the image, else the failure, which is
 * also the status of the surface where it happened; later surfaces get
 * SG_ENOTREACHED. */
SG_API int sg_trace_start(sg_tracer *t, const double start[3], const double dir[3],
                   sg_ray_surface *out);

/* Traces the ray with normalized field (hx, hy) and pupil (px, py)
 * coordinates, using the system's fields, aperture and ray aiming, all
 * defined at the primary wavelength whatever the tracer's (as in Zemax).
 * Returns SG_EAIM (with every surface SG_ENOTREACHED) when aiming fails,
 * and SG_ERANGE on every surface for a field sg_field_check refuses.  In
 * every method and entry point, a ray whose numbers leave the doubles
 * gets SG_ERANGE where they do: no surface marked SG_OK has a NaN or an
 * infinity (but the object row's point of an object at infinity). */
SG_API int sg_trace_normalized(sg_tracer *t, double hx, double hy, double px,
                        double py, sg_ray_surface *out);

/* Rays of a batch: either normalized, or start and direction. */
typedef struct sg_ray_in {
    double v[6]; /* hx, hy, px, py (normalized) or x, y, z, l, m, n */
} sg_ray_in;

typedef enum sg_ray_kind {
    SG_RAYS_NORMALIZED = 0,
    SG_RAYS_START_DIR = 1
} sg_ray_kind;

/* Traces nray rays into out (nray * nsurf entries) and status (nray
 * entries), on nthreads threads (0 means every core).  Results equal the
 * single-ray calls bit for bit. */
SG_API int sg_trace_batch(const sg_system *sys, const sg_catalog *cat,
                   const sg_trace_opts *opts, sg_ray_kind kind,
                   const sg_ray_in *rays, size_t nray, int nthreads,
                   sg_ray_surface *out, int *status, sg_diag *d);

/* A batch kept ready for many calls: one prepared tracer per thread, so a
 * long ray list can be traced block after block (read, trace, write) in
 * bounded memory without preparing the system again. */
typedef struct sg_batch sg_batch;

/* nthreads as in sg_trace_batch.  NULL on failure, with the code in d when
 * given (the engine's own callers use a form that returns it). */
SG_API sg_batch *sg_batch_new(const sg_system *sys, const sg_catalog *cat,
                       const sg_trace_opts *opts, int nthreads, sg_diag *d);
SG_API void sg_batch_free(sg_batch *b);
SG_API int sg_batch_nsurf(const sg_batch *b);
/* Traces nray rays and keeps, for each, only surfaces surf[0..nsel-1]
 * (each in 0..nsurf-1, in the order given, repeats allowed) at out[r *
 * nsel + k]; surf NULL keeps every surface (nsel is then ignored and
 * out has nray * nsurf entries).  Rows and status equal sg_trace_batch's
 * bit for bit, so an analysis of the image alone stores one row a ray. */
SG_API int sg_batch_trace(sg_batch *b, sg_ray_kind kind, const sg_ray_in *rays,
                   size_t nray, const int *surf, int nsel,
                   sg_ray_surface *out, int *status, sg_diag *d);
/* Reference mode (on nonzero): the batch's later calls trace their rays
 * past every semi-diameter, aperture and obscuration, as Zemax traces the
 * chief ray an analysis measures from; the arithmetic is the same, so a
 * ray that passes gets the same bits either way.  Off again with 0. */
SG_API void sg_batch_set_reference(sg_batch *b, int on);
/* The same for one tracer (sg_trace_normalized and sg_trace_start). */
SG_API void sg_tracer_set_reference(sg_tracer *t, int on);

/* ------------------------------------------------------------------------
 * Image analyses: spot diagrams, transverse ray fans and the layout.  Each
 * returns data (no printing); the rays go through a kept sg_batch that
 * keeps only the surfaces an analysis needs, in blocks of bounded size.
 * ------------------------------------------------------------------------ */

/* Normalized field coordinates (Hx, Hy) of field k (0-based): the field
 * divided by Zemax's field scale (the largest radius, or the largest |x|
 * and |y| for rectangular normalization). */
SG_API int sg_field_normalized(const sg_system *sys, int k, double *hx, double *hy);

/* The pupil point a normalized ray is traced at: (px, py) itself, unless
 * (hx, hy) is a field's own normalized point (sg_field_normalized, bit for
 * bit; the first such field) with vignetting factors, when it is
 *   a = px (1 - vcx), b = py (1 - vcy),
 *   px' = vdx + a cos(van) - b sin(van), py' = vdy + a sin(van) + b cos(van),
 * the compressed pupil turned by van (degrees, counterclockwise) about its
 * centre, then decentred.  Every method traces (px', py'). */
SG_API void sg_field_vignette(const sg_system *sys, double hx, double hy, double px, double py,
                       double *vpx, double *vpy);

/* Pupil sampling patterns, as Zemax defines them.  Hexapolar: density N
 * rings; ring i (1..N) holds 6i rays at radius i/N, the first at angle 0
 * (the +x axis), so 1 + 3N(N+1) rays.  Square: an N x N grid of cell
 * centres, Px = -1 + (2j+1)/N, keeping those with Px^2 + Py^2 <= 1.
 * Vogel: N rays on the sunflower spiral, r = sqrt((k+1/2)/N), angle k
 * times the golden angle pi (3 - sqrt 5), each ray an equal area. */
typedef enum sg_pupil_pattern {
    SG_PUPIL_HEXAPOLAR = 0,
    SG_PUPIL_SQUARE = 1,
    SG_PUPIL_VOGEL = 2
} sg_pupil_pattern;

#define SG_PUPIL_MAX_DENSITY 100000000 /* N for square and Vogel; rings are fewer */

SG_API const char *sg_pupil_pattern_name(int pattern);
/* Parses "hexapolar", "square" or "vogel"; -1 when unknown. */
SG_API int sg_pupil_pattern_parse(const char *s);
/* Checks density for a pattern (message names the limit). */
SG_API int sg_pupil_check(int pattern, int density, sg_diag *d);
/* Number of pupil points of a pattern; 0 for a bad pattern or density. */
SG_API size_t sg_pupil_count(int pattern, int density);
/* Fills up to cap points (px, py) of the pattern in its order, from
 * *cursor (0 at the start; an opaque position advanced by the call), so
 * a long pattern can be made block by block.  Returns the number filled;
 * 0 at the end. */
SG_API size_t sg_pupil_fill(int pattern, int density, size_t *cursor, double (*p)[2], size_t cap);

typedef enum sg_spot_ref {
    SG_SPOT_REF_CHIEF = 0,   /* the real chief ray (Zemax's default) */
    SG_SPOT_REF_CENTROID = 1 /* the mean of the rays' image points */
} sg_spot_ref;

typedef struct sg_spot_opts {
    sg_trace_opts trace; /* method, clipping ...; trace.wave is ignored */
    int pattern;         /* sg_pupil_pattern */
    int density;         /* rings (hexapolar), grid size (square), rays (Vogel) */
    int reference;       /* sg_spot_ref */
    int wave;            /* 0-based, or -1: every wavelength (polychromatic) */
    int field;           /* 0-based, or -1: every field */
    int nthreads;        /* 0: every core */
    size_t block;        /* rays per batch call; 0: 65536 */
    size_t max_points;   /* image points kept per field and wavelength, for
                            pictures (every k-th ray); 0 keeps none */
    /* Called after each block with rays traced and in all (may be NULL);
     * a nonzero return stops the run with SG_ESTOPPED. */
    int (*progress)(void *ctx, size_t done, size_t total);
    void *progress_ctx;
} sg_spot_opts;

SG_API void sg_spot_opts_init(sg_spot_opts *o);

/* One field at one wavelength.  Points and radii are in lens units on the
 * image surface, relative to the reference point (ref_x, ref_y). */
typedef struct sg_spot_cell {
    int status;            /* SG_OK, or the chief ray's failure */
    size_t nray, nok;      /* rays launched; rays that reached the image */
    double chief_x, chief_y;       /* this wavelength's chief ray on the image */
    double centroid_x, centroid_y; /* mean image point of the rays that reached it */
    double rms, geo;       /* about the analysis's reference point */
    size_t npts;           /* points kept */
    double (*pts)[2];      /* kept points, relative to the reference */
    double centroid_bound_x, centroid_bound_y; /* bounds on the centroid's errors: the
                              mean of its rays' error bounds and the sums' rounding
                              (classic: from its estimates) */
} sg_spot_cell;

typedef struct sg_spot_field {
    double hx, hy;         /* normalized field */
    int status;            /* SG_OK, or the reference chief ray's failure */
    int fail_surface;      /* the surface where that chief ray failed, or -1 */
    double ref_x, ref_y;   /* reference point: the primary (or only) wavelength's
                              chief ray, or the weighted centroid */
    double rms, geo;       /* over every wavelength, weighted by wavelength weight */
    double centroid_x, centroid_y;
    double centroid_bound_x, centroid_bound_y; /* as sg_spot_cell's */
} sg_spot_field;

typedef struct sg_spot {
    int nfield, nwave;
    int field_index[SG_MAX_FIELDS]; /* design field of each row */
    int wave_index[SG_MAX_WAVES];   /* design wavelength of each column */
    double wave_um[SG_MAX_WAVES];
    double airy_radius;    /* 1.22 lambda F/#: the primary (or only) wavelength and
                              the paraxial working F/# (Zemax's Airy radius) */
    size_t nray_per_cell;  /* pupil points of the pattern */
    sg_spot_field field[SG_MAX_FIELDS];
    sg_spot_cell *cell;    /* nfield * nwave, row by field */
} sg_spot;

/* Spot diagrams of the chosen fields and wavelengths.  Fills *out (free it
 * with sg_spot_free).  Rays that fail (vignetting, TIR ...) are left out of
 * the figures and counted.  Returns SG_OK, or an error with d filled. */
SG_API int sg_spot_compute(const sg_system *sys, const sg_catalog *cat, const sg_spot_opts *o,
                    sg_spot *out, sg_diag *d);
SG_API void sg_spot_free(sg_spot *s);

typedef struct sg_fan_opts {
    sg_trace_opts trace;
    int npts;    /* pupil samples from -1 to 1 on each fan; at least 2 */
    int wave;    /* 0-based, or -1 for every wavelength */
    int field;   /* 0-based, or -1 for every field */
    int nthreads;
    int opd;     /* nonzero: OPD fans (waves) instead of transverse ray fans */
    /* Nonzero: samples added where a curve bends, for pictures: an
     * interval's midpoint is traced, and kept (its halves tested in turn,
     * down to a 128th of the first step) while it lies farther than
     * refine_tol times the largest |e| so far from the chord. */
    int refine;
    double refine_tol; /* 0: 1e-3 */
} sg_fan_opts;

SG_API void sg_fan_opts_init(sg_fan_opts *o);

/* One fan: the pupil coordinate of each sample and the aberration. */
typedef struct sg_fan_curve {
    int n;          /* samples: npts, or more with refine */
    double *p;      /* n pupil coordinates, increasing (Py tangential, Px sagittal) */
    double *e;      /* ey (tangential) or ex (sagittal), lens units; or, in an
                       OPD fan, the OPD in waves of the curve's wavelength */
    int *status;    /* each ray's status; e is 0 where it is not SG_OK */
} sg_fan_curve;

typedef struct sg_fan {
    int nfield, nwave, npts;
    int field_index[SG_MAX_FIELDS];
    int wave_index[SG_MAX_WAVES];
    double wave_um[SG_MAX_WAVES];
    double hx[SG_MAX_FIELDS], hy[SG_MAX_FIELDS];
    int status[SG_MAX_FIELDS];       /* the reference chief ray's status */
    double ref_x[SG_MAX_FIELDS], ref_y[SG_MAX_FIELDS];
    sg_fan_curve *tan, *sag;         /* nfield * nwave each, row by field */
    int opd;                         /* OPD fans: e in waves */
} sg_fan;

/* Transverse ray fans: ey against Py (Px = 0) and ex against Px (Py = 0),
 * on the image surface, each relative to the chief ray of the primary
 * wavelength (of the only wavelength when one is chosen), as Zemax draws
 * them.  With o->opd, OPD fans instead: the OPD (sg_opd_of_ray) against
 * each field's reference sphere (the primary wavelength's, whatever is
 * chosen, as in Zemax), in waves of each curve's wavelength, less that
 * wavelength's chief ray's OPD so every curve passes through zero at the
 * pupil's centre (the chromatic piston left out, as Zemax draws OPD fans);
 * a ray whose OPD is not defined gets that status. */
SG_API int sg_fan_compute(const sg_system *sys, const sg_catalog *cat, const sg_fan_opts *o,
                   sg_fan *out, sg_diag *d);
SG_API void sg_fan_free(sg_fan *f);

typedef struct sg_layout_opts {
    sg_trace_opts trace;  /* trace.wave: -1 primary */
    int nrays;            /* rays per field from Py = -1 to 1; at least 1 */
    int field;            /* 0-based, or -1 for every field */
    int profile_pts;      /* points per surface profile; at least 2 */
    int nthreads;
} sg_layout_opts;

SG_API void sg_layout_opts_init(sg_layout_opts *o);

typedef struct sg_layout_surface {
    double z0;           /* the vertex's global z (surface 1 at 0) */
    double sd;           /* the semi-diameter drawn: a fixed one as stored,
                            else the automatic one (sg_semi_diameters), else
                            the stored one or the rays drawn's highest */
    int mirror, glass_after; /* a mirror; glass (index != 1) after it */
    int npts;
    double *y, *z;       /* the profile, global y and z */
} sg_layout_surface;

typedef struct sg_layout_ray {
    int field;           /* row of field_index */
    double py;
    int status;          /* the trace's result */
    int npts;            /* points from surface 1 to where the ray stopped */
    double *y, *z;       /* global y and z of each point */
} sg_layout_ray;

typedef struct sg_layout {
    int nsurf;           /* surfaces 1 .. N drawn: nsurf - 1 entries */
    sg_layout_surface *surf; /* surf[i - 1] for surface i */
    int nfield;
    int field_index[SG_MAX_FIELDS];
    int nray;
    sg_layout_ray *ray;
    double zmin, zmax, ymin, ymax; /* extent of everything drawn */
} sg_layout;

/* A y-z cross-section: each surface's profile over its semi-diameter at
 * its global position (surfaces 1 to the image; the object is left out,
 * as in Zemax's default layout), and a fan of rays in y per field. */
SG_API int sg_layout_compute(const sg_system *sys, const sg_catalog *cat, const sg_layout_opts *o,
                      sg_layout *out, sg_diag *d);
SG_API void sg_layout_free(sg_layout *l);

/* ------------------------------------------------------------------------
 * Optical path difference (Zemax's convention, sagitta(1)).
 * ------------------------------------------------------------------------ */

/* The reference sphere of one field: centred on the primary wavelength's
 * chief ray's point on the image surface, through the axial point of the
 * paraxial exit pupil (the stop's paraxial image in image space).  All
 * coordinates are in the image surface's frame. */
typedef struct sg_opd_ref {
    double hx, hy;          /* the field */
    int status;             /* SG_OK, or the chief ray's failure */
    double um;              /* the primary wavelength */
    double n_image;         /* |index| of image space at the primary wavelength */
    double cx, cy, cz;      /* the centre: the chief ray's image point */
    double chief_l, chief_m, chief_n; /* the chief ray's direction in image space */
    double centre_error_bound;        /* the chief row's error_bound */
    double ez;              /* the exit pupil's axial point (0, 0, ez) */
    double radius, radius_lo; /* |E - C|, in double-double */
    double side;            /* -1 when the sphere lies behind the image point
                             * along the chief ray (a pupil before the image) */
    double chief_opl, chief_opl_lo;  /* the chief ray's optical path to the sphere */
    double chief_opl_error_bound;
} sg_opd_ref;

/* One ray against a reference sphere. */
typedef struct sg_opd {
    int status;            /* SG_OK, the ray's failure, or the reference's */
    double opd_waves;      /* (chief's path - ray's path to the sphere) / lambda */
    double error_bound;    /* bound on |opd_waves - exact|, in waves */
    double ex, ey;         /* transverse aberration: image point minus the chief's */
    double sphere_x, sphere_y, sphere_z; /* the ray's point on the sphere */
    double opl, opl_lo;    /* the ray's optical path to the sphere */
} sg_opd;

/* The reference sphere of field (hx, hy).  The chief ray is traced at the
 * primary wavelength (by t's primary-wavelength tracer when t is at
 * another).  A chief ray that fails is a result: SG_OK is returned with
 * ref->status set.  SG_EUNSUPPORTED when the exit pupil is at infinity. */
SG_API int sg_opd_reference(sg_tracer *t, double hx, double hy, sg_opd_ref *ref, sg_diag *d);
/* The OPD of a ray traced by t (in t's wavelength, for ref's field) from
 * its image row alone, so the rows of sg_batch_trace with only the image
 * surface selected serve.  A failed ray or reference sets out->status and
 * NaNs; returns SG_EINVAL only for NULL arguments. */
SG_API int sg_opd_of_ray(const sg_tracer *t, const sg_opd_ref *ref, const sg_ray_surface *image_row,
                  sg_opd *out);
/* sg_opd_of_ray for n rays of ref's field at once, their image rows at
 * rows[r * stride] and their results in out[r], each with the bits
 * sg_opd_of_ray gives (on vector lanes where the build has them). */
SG_API int sg_opd_of_rays(const sg_tracer *t, const sg_opd_ref *ref, const sg_ray_surface *rows,
                   size_t stride, size_t n, sg_opd *out);
/* Traces pupil point (px, py) of ref's field with t (out: nsurf rows) and
 * fills res; returns the trace's status. */
SG_API int sg_trace_opd(sg_tracer *t, const sg_opd_ref *ref, double px, double py,
                 sg_ray_surface *out, sg_opd *res);
/* The tracer's wavelength in micrometres. */
SG_API double sg_tracer_wavelength(const sg_tracer *t);

/* ------------------------------------------------------------------------
 * Seidel sums (third-order aberrations and first-order colour)
 * ------------------------------------------------------------------------ */

/* The seven sums, Welford's S_I to S_V, C_I and C_II, in lens units. */
enum {
    SG_SEIDEL_SI = 0,   /* spherical aberration */
    SG_SEIDEL_SII = 1,  /* coma */
    SG_SEIDEL_SIII = 2, /* astigmatism */
    SG_SEIDEL_SIV = 3,  /* Petzval field curvature */
    SG_SEIDEL_SV = 4,   /* distortion */
    SG_SEIDEL_CI = 5,   /* axial colour */
    SG_SEIDEL_CII = 6,  /* lateral colour */
    SG_SEIDEL_N = 7
};

typedef struct sg_seidel {
    int nsurf;        /* surfaces 0..nsurf-1; row 0 (the object) is zero */
    double *surf;     /* nsurf * SG_SEIDEL_N: surface j's sums at surf[j * SG_SEIDEL_N] */
    double total[SG_SEIDEL_N];
    /* Bounds on the errors of surf and total, to first order in the
     * roundings: a sum within its bound is indistinguishable from 0. */
    double *surf_bound;
    double total_bound[SG_SEIDEL_N];
    double lagrange;  /* Welford's H = n (u ybar - ubar y), full field and aperture */
    double nu_image;  /* n'u' of the paraxial marginal ray in image space */
    double wave_um;   /* the primary wavelength, at which the sums are taken */
    double wave_lens; /* the same in lens units */
    double short_um, long_um; /* colour: index differences between these two */
    int decentred;    /* the first surface (0-based) whose frame is tilted or
                         decentred (a coordinate break or a surface's own
                         tilt or decenter), or -1: third-order theory assumes
                         a centred system, so the sums of a system with one
                         describe the centred system the tilts leave out;
                         sg_seidel_compute also warns (sg_diag_warn) */
} sg_seidel;

/* Seidel sums of every surface at the primary wavelength, from the
 * paraxial marginal ray (full entrance pupil) and the chief ray of the
 * largest field (scaled to the paraxial image height).  The conic and the
 * r^4 term of an even asphere contribute; the r^2 term is left out, as in
 * the paraxial data.  Free with sg_seidel_free. */
SG_API int sg_seidel_compute(const sg_system *sys, const sg_catalog *cat, sg_seidel *out,
                      sg_diag *d);
SG_API void sg_seidel_free(sg_seidel *s);

/* Zemax's wavefront coefficients, in waves of lambda (lens units):
 * W040 = SI/8, W131 = SII/2, W222 = SIII/2, W220P = SIV/4, W311 = SV/2,
 * W020 = CI/2, W111 = CII, W220S = (SIII+SIV)/4, W220M = (2SIII+SIV)/4,
 * W220T = (3SIII+SIV)/4. */
enum {
    SG_W040 = 0, SG_W131, SG_W222, SG_W220P, SG_W311, SG_W020, SG_W111,
    SG_W220S, SG_W220M, SG_W220T, SG_NWCOEF
};
SG_API void sg_seidel_waves(const double *s, double lambda, double *w);

/* Zemax's transverse aberrations in lens units, with nu = n'u' of the
 * marginal ray: TSPH = SI/(2n'u'), TSCO = SII/(2n'u'), TTCO = 3 TSCO,
 * TAST = SIII/(n'u'), TPFC = SIV/(2n'u'), TSFC = (SIII+SIV)/(2n'u'),
 * TTFC = (3SIII+SIV)/(2n'u'), TDIS = SV/(2n'u'), TAXC = CI/(n'u'),
 * TLAC = CII/(n'u'). */
enum {
    SG_TSPH = 0, SG_TSCO, SG_TTCO, SG_TAST, SG_TPFC, SG_TSFC, SG_TTFC, SG_TDIS,
    SG_TAXC, SG_TLAC, SG_NTCOEF
};
SG_API void sg_seidel_transverse(const double *s, double nu, double *t);

/* Millimetres in one lens unit of the system (mm, cm, in or m). */
SG_API double sg_lens_unit_mm(const sg_system *sys);

/* ------------------------------------------------------------------------
 * Field curvature and distortion
 * ------------------------------------------------------------------------ */

typedef struct sg_fieldcurve_pt {
    double hy;         /* normalized field, 0 to 1 */
    double field;      /* the same in the system's field units (degrees or lens units) */
    double tan_focus;  /* tangential focus: z from the chief ray's image-surface point */
    double sag_focus;  /* sagittal focus, the same way */
    double real_y;     /* real chief ray height on the image surface */
    double parax_y;    /* paraxial image height of this field (f tan(theta) at infinity) */
    double distortion; /* 100 (real_y - parax_y) / parax_y, percent; 0 on axis */
    int status;        /* SG_OK, or the failure of one of the field's rays */
} sg_fieldcurve_pt;

/* Field curvature and distortion at npts fields evenly from 0 to the
 * largest (in the field's own measure: the angle for angle fields), along
 * +y, at opts' wavelength, by differential real rays a pupil step delta
 * (normalized, e.g. 0.01) either side of the chief ray, with Richardson's
 * step to delta / 2.  A field whose rays fail gets that status; the call
 * fails only for bad arguments or a system that cannot be traced.  Fields
 * given as real image height are refused (SG_EUNSUPPORTED). */
SG_API int sg_fieldcurve(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                  int npts, double delta, sg_fieldcurve_pt *out, sg_diag *d);

/* How sg_fieldcurve_recipe finds a fan's focus: the exact limit above
 * (sg_fieldcurve's), or Zemax's recipe: the chief ray and one ray at
 * pupil step delta (Zemax's is 0.001), both lines taken from the chief
 * ray's z on the image surface, which on a curved image moves the
 * tangential focus by the difference of the two rays' z. */
enum { SG_FIELDCURVE_EXACT = 0, SG_FIELDCURVE_ZEMAX = 1 };
SG_API int sg_fieldcurve_recipe(const sg_system *sys, const sg_catalog *cat,
                         const sg_trace_opts *opts, int npts, double delta, int recipe,
                         sg_fieldcurve_pt *out, sg_diag *d);

/* ------------------------------------------------------------------------
 * Zernike polynomials and wavefront statistics
 * ------------------------------------------------------------------------ */

typedef enum sg_zernike_kind {
    SG_ZERNIKE_FRINGE = 0,  /* University of Arizona order, 37 terms, not normalized */
    SG_ZERNIKE_STANDARD = 1 /* Noll's order and normalization (unit RMS) */
} sg_zernike_kind;

#define SG_ZERNIKE_FRINGE_MAX 37
#define SG_ZERNIKE_STANDARD_MAX 231 /* radial orders 0 to 20 */

/* Radial order n and azimuthal order m of term j (from 1); m < 0 is a
 * sine term, m > 0 a cosine term.  SG_ERANGE outside the set. */
SG_API int sg_zernike_nm(sg_zernike_kind kind, int j, int *n, int *m);
/* Term j at pupil point (x, y), |(x, y)| <= 1, angle from the x axis; NaN
 * for a j outside the set. */
SG_API double sg_zernike_eval(sg_zernike_kind kind, int j, double x, double y);
/* Least-squares coefficients of terms 1..nterms for the values w at the
 * npts points (x, y) of the unit pupil, into coef[0..nterms-1], and the
 * RMS of what the fit leaves (rms_resid may be NULL).  Memory does not
 * depend on npts. */
SG_API int sg_zernike_fit(sg_zernike_kind kind, int nterms, size_t npts, const double *x,
                   const double *y, const double *w, double *coef, double *rms_resid,
                   sg_diag *d);
/* RMS and peak-to-valley of the values w at (x, y) after removing their
 * least-squares piston, and tilt too when remove_tilt (Zemax's figures
 * "to centroid"; piston alone gives its "to chief"). */
SG_API int sg_wavefront_stats(size_t npts, const double *x, const double *y, const double *w,
                       int remove_tilt, double *rms, double *pv, sg_diag *d);

/* A source of optical path difference: OPD in waves at normalized pupil
 * point (px, py), returning SG_OK or the ray's failure. */
typedef int (*sg_opd_fn)(void *ctx, double px, double py, double *opd_waves);

#define SG_WAVEFRONT_MAXTERMS 37

typedef struct sg_wavefront {
    int grid;           /* points across the pupil */
    double *map;        /* grid * grid, row py, column px, from -1 to 1 */
    unsigned char *valid; /* 1 where map holds an OPD (inside the pupil, ray OK) */
    size_t nvalid;
    double rms_chief, pv_chief;       /* piston removed */
    double rms_centroid, pv_centroid; /* piston and tilt removed */
    sg_zernike_kind kind;
    int nterms;
    double coef[SG_WAVEFRONT_MAXTERMS]; /* Zernike coefficients, waves */
    double fit_rms;                     /* RMS of what the fit leaves */
    /* Bounds on each coefficient's error, waves: from the OPDs' error
     * bounds (sg_wavefront_trace) and the fit's rounding.  A coefficient
     * within its bound is indistinguishable from zero. */
    double coef_bound[SG_WAVEFRONT_MAXTERMS];
} sg_wavefront;

/* The wavefront map of opd on a grid x grid square of pupil points (those
 * inside the unit circle), its RMS and P-V, and nterms Zernike terms of
 * kind.  Free with sg_wavefront_free. */
SG_API int sg_wavefront_compute(sg_opd_fn opd, void *ctx, int grid, sg_zernike_kind kind,
                         int nterms, sg_wavefront *out, sg_diag *d);
SG_API void sg_wavefront_free(sg_wavefront *w);

typedef struct sg_wavefront_opts {
    sg_trace_opts trace; /* trace.wave: the wavelength, -1 the primary */
    int field;           /* 0-based design field, or -1 to use hx, hy */
    double hx, hy;       /* normalized field when field < 0 */
    int grid;            /* points across the pupil (Zemax's sampling) */
    int kind;            /* sg_zernike_kind */
    int nterms;          /* Zernike terms fitted, 1 to 37 */
    int nthreads;        /* 0: every core */
    size_t block;        /* rays per batch call; 0: 65536 */
    /* Called after each block with grid points done and in all (may be
     * NULL); a nonzero return stops the run with SG_ESTOPPED. */
    int (*progress)(void *ctx, size_t done, size_t total);
    void *progress_ctx;
} sg_wavefront_opts;

SG_API void sg_wavefront_opts_init(sg_wavefront_opts *o);

/* The traced wavefront of one field at one wavelength: the OPD of the
 * grid's pupil points against the field's reference sphere (sg_opd_ref,
 * copied to *ref when ref is not NULL), through the batch in blocks with
 * only the image surface kept.  At a wavelength other than the primary,
 * less that wavelength's chief ray's OPD, so the map is zero at its chief
 * ray, as Zemax's.  Rays that fail are left out, as in Zemax.
 * A chief ray that fails is an error naming the field. */
SG_API int sg_wavefront_trace(const sg_system *sys, const sg_catalog *cat,
                       const sg_wavefront_opts *o, sg_wavefront *out, sg_opd_ref *ref,
                       sg_diag *d);

/* ------------------------------------------------------------------------
 * Diffraction: FFT PSF, Strehl ratio and FFT MTF (sagitta(1), psf, mtf)
 * ------------------------------------------------------------------------ */

#define SG_PSF_SAMPLING_MIN 32
#define SG_PSF_SAMPLING_MAX 2048

typedef enum sg_psf_method {
    SG_PSF_FFT = 0,     /* the pupil's Fourier transform */
    SG_PSF_HUYGENS = 1  /* wavelets from the reference sphere, summed */
} sg_psf_method;

#define SG_PSF_IMAGE_MAX 1024

typedef struct sg_psf_opts {
    sg_trace_opts trace; /* trace.wave is ignored: see wave */
    int field;           /* 0-based design field */
    int wave;            /* 0-based wavelength, or -1: every one, by weight */
    int sampling;        /* N, pupil grid points across, 32 to 2048 */
    int nthreads;        /* 0: every core */
    int method;          /* sg_psf_method */
    int image_size;      /* Huygens: image points across, 0: N; at most
                          * SG_PSF_IMAGE_MAX */
    double image_delta_um; /* Huygens: their spacing; 0: the FFT's */
} sg_psf_opts;

typedef struct sg_psf {
    int field;            /* 0-based */
    int sampling;         /* N */
    int method;           /* sg_psf_method */
    int size;             /* M = 2N, PSF grid points across (Huygens: the
                           * image points) */
    double wave_um;       /* the wavelength whose grid the PSF is on: the
                           * shortest of those summed */
    double spacing_x_um, spacing_y_um; /* grid spacing: lambda F# (N-1) / M
                                        * / (1 - vc) on each axis */
    double fnum;          /* the primary wavelength's paraxial working F/# */
    double strehl;        /* the PSF at the chief ray's point */
    double strehl_exact;  /* |mean of exp(i 2 pi W)|^2, weighted alike */
    double peak;          /* the PSF's largest value */
    double *psf;          /* M * M, row y, column x; (M/2, M/2) is the
                           * chief ray's point; the unaberrated pupil of
                           * the same shape has peak 1 */
} sg_psf;

SG_API void sg_psf_opts_init(sg_psf_opts *o);
/* The FFT PSF of one field: the traced pupil (amplitude 1 where the ray
 * reaches the image, phase 2 pi OPD) on an N x N grid, zero-padded to
 * 2N x 2N.  Several wavelengths are summed, each with unit energy times
 * its weight, on the shortest one's grid: a longer one is padded to
 * 2N lambda / lambda_min points, rounded, and its centre taken.  With
 * method SG_PSF_HUYGENS, the Huygens PSF of the same rays on an
 * image_size square grid (huygens.c), normalized alike. */
SG_API int sg_psf_compute(const sg_system *sys, const sg_catalog *cat, const sg_psf_opts *o,
                          sg_psf *out, sg_diag *d);
SG_API void sg_psf_free(sg_psf *p);

typedef enum sg_mtf_method {
    SG_MTF_FFT = 0,       /* the FFT PSF's transform */
    SG_MTF_GEOMETRIC = 1, /* the transform of the rays' line spread */
    SG_MTF_HUYGENS = 2    /* the transform of the Huygens PSF */
} sg_mtf_method;

typedef struct sg_mtf_opts {
    sg_trace_opts trace;  /* trace.wave is ignored: see wave */
    int field;            /* 0-based design field, or -1: every one */
    int wave;             /* 0-based wavelength, or -1: every one, by weight */
    int sampling;         /* N, 32 to 2048: the pupil grid (geometric: N x N
                           * rays, a square grid) */
    double max_frequency; /* cycles/mm; 0: the cutoff 1 / (lambda F#) */
    int nthreads;
    int method;           /* sg_mtf_method */
    int image_size;       /* Huygens: the PSF's image points across, 0: N */
    double image_delta_um; /* Huygens: their spacing; 0: the FFT PSF's */
} sg_mtf_opts;

typedef struct sg_mtf {
    int nfield, npts;
    int sampling;
    int method;           /* sg_mtf_method */
    int image_size;       /* Huygens: the PSF's image points across */
    double image_delta_um; /* Huygens: their spacing */
    int *field;           /* nfield 0-based design fields */
    double fnum;          /* the working F/# the frequencies are scaled by */
    double cutoff;        /* 1 / (lambda F#) of the shortest wavelength, cycles/mm */
    double *freq;         /* npts, cycles/mm, from 0 to the maximum */
    double *tan, *sag;    /* nfield * npts: along y and along x */
    double *dl;           /* npts: the first field's pupil, unaberrated */
} sg_mtf;

SG_API void sg_mtf_opts_init(sg_mtf_opts *o);
/* The FFT MTF: |FFT of the FFT PSF|, cut along y (tangential) and x
 * (sagittal), at N frequencies from 0 to the maximum.  With method
 * SG_MTF_GEOMETRIC, |mean of exp(i 2 pi nu y)| over the rays of an N x N
 * square pupil grid (x for sagittal), each wavelength's rays sharing its
 * weight, about the spot's reference; the diffraction limit is the FFT's.
 * With SG_MTF_HUYGENS, the modulus of the Huygens PSF's (sg_psf_compute)
 * transform, cut alike, at frequencies up to the image grid's Nyquist
 * frequency 1 / (2 image_delta), beyond which it refuses. */
SG_API int sg_mtf_compute(const sg_system *sys, const sg_catalog *cat, const sg_mtf_opts *o,
                          sg_mtf *out, sg_diag *d);
SG_API void sg_mtf_free(sg_mtf *m);

/* Encircled and ensquared energy (sagitta(1), encircled). */
typedef enum sg_ee_kind {
    SG_EE_ENCIRCLED = 0, /* within a circle of radius r about the chief ray */
    SG_EE_ENSQUARED = 1  /* within a square of half-width r */
} sg_ee_kind;

#define SG_EE_MAX_NPTS 10000

typedef struct sg_ee_opts {
    sg_trace_opts trace;  /* trace.wave is ignored: see wave */
    int field;            /* 0-based design field, or -1: every one */
    int wave;             /* 0-based wavelength, or -1: every one, by weight */
    int sampling;         /* N, the FFT PSF's pupil grid, 32 to 2048 */
    int rays;             /* geometric: a square grid of rays across; 0: 2N */
    int kind;             /* sg_ee_kind */
    double max_radius_um; /* 0: the farthest ray or 5 lambda F#, whichever is wider */
    int npts;             /* radii from 0 to the maximum; 0: 101 */
    int nthreads;
} sg_ee_opts;

typedef struct sg_ee {
    int nfield, npts, sampling, rays, kind;
    int *field;           /* nfield 0-based design fields */
    double fnum;          /* the working F/# */
    double wave_um;       /* the shortest wavelength summed */
    double *radius_um;    /* npts: radius or half-width, from 0 */
    double *diffraction;  /* nfield * npts: the FFT PSF's fraction */
    double *geometric;    /* nfield * npts: the rays' fraction */
    double *limit;        /* nfield * npts: each field's pupil, unaberrated */
} sg_ee;

SG_API void sg_ee_opts_init(sg_ee_opts *o);
/* Energy within r of each field's chief ray point: the FFT PSF (psf.c)
 * integrated exactly over the circle or square through its OTF, the same
 * for the pupil unaberrated, and the fraction of a square grid of rays
 * (each wavelength's rays that reach the image sharing its weight). */
SG_API int sg_ee_compute(const sg_system *sys, const sg_catalog *cat, const sg_ee_opts *o,
                         sg_ee *out, sg_diag *d);
SG_API void sg_ee_free(sg_ee *e);

/* Through-focus MTF and Strehl ratio (sagitta(1), mtf --through-focus). */
#define SG_TF_MAX_STEPS 1001

#define SG_TF_MAX_FREQS 8

typedef struct sg_tf_opts {
    sg_mtf_opts mtf;   /* field, wave, sampling, method, trace; its
                        * max_frequency is set to each frequency */
    double frequency;  /* cycles/mm, when nfrequency is 0 */
    double range;      /* lens units: the image plane from -range to +range */
    int steps;         /* shifts, 2 to SG_TF_MAX_STEPS; default 11 */
    /* Several frequencies in one run (after the fields above, so that a
     * caller built against the one-frequency layout keeps its offsets):
     * 0 takes frequency alone. */
    int nfrequency;                       /* 0 to SG_TF_MAX_FREQS */
    double frequencies[SG_TF_MAX_FREQS];  /* cycles/mm */
} sg_tf_opts;

typedef struct sg_tf {
    int nfield, nsteps;
    int *field;          /* nfield 0-based design fields */
    double frequency;    /* cycles/mm: the first frequency */
    double *shift;       /* nsteps, lens units, from -range to +range */
    double *tan, *sag;   /* nfield * nfreq * nsteps: the MTF of field f at
                          * frequency q is at [(f * nfreq + q) * nsteps] */
    double *strehl;      /* nfield * nsteps: the FFT PSF's Strehl ratio */
    int nfreq;           /* 1 to SG_TF_MAX_FREQS */
    double *freq;        /* nfreq cycles/mm, in the order asked */
} sg_tf;

SG_API void sg_tf_opts_init(sg_tf_opts *o);
/* The MTF at each frequency and the Strehl ratio of each field with the
 * image plane shifted along the axis (the gap before it lengthened),
 * at steps shifts from -range to +range.  Each frequency's values are
 * those of a run at that frequency alone. */
SG_API int sg_tf_compute(const sg_system *sys, const sg_catalog *cat, const sg_tf_opts *o,
                         sg_tf *out, sg_diag *d);
SG_API void sg_tf_free(sg_tf *t);

/* Significant decimal digits by which a agrees with the reference b:
 * -log10(|a - b| / |b|), capped at 17 (equal) and floored at 0. */
SG_API double sg_digits(double a, double b);

#ifdef __cplusplus
}
#endif

#endif /* SAGITTA_H */
