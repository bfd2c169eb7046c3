/* test_cli_frames.c - "sagitta trace --global" and designs with coordinate
 * breaks and tilts, run through the program.
 *
 * The fold: a plano-convex lens, 40 mm of air, a flat mirror between two
 * 45-degree breaks about x, and 57.25 mm back to the image.  Turning the
 * axes twice by 45 degrees right-handed about x makes the image frame's
 * y axis the old +z and its z axis the old -y, and its origin lies at
 * (0, 57.25, 43.6) in surface 1's frame.  So a ray's global image point
 * is (x, 57.25, 43.6 + y) where (x, y) is its point on the image of the
 * same lens unfolded (97.25 mm of air): a closed form of the geometry,
 * checked against the unfolded design's own trace. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"

static const char *const FOLD =
    "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
    "    {\"radius\": 51.5, \"thickness\": 3.6, \"material\": 1.5168, \"stop\": true},\n"
    "    {\"radius\": \"inf\", \"thickness\": 40},\n"
    "    {\"type\": \"coordinate_break\", \"thickness\": 0, \"break\": {\"tilt\": [45, 0, 0]}},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0, \"material\": \"MIRROR\"},\n"
    "    {\"type\": \"coordinate_break\", \"thickness\": -57.25, \"break\": {\"tilt\": [45, 0, 0]}},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0}";

static const char *const UNFOLDED =
    "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
    "    {\"radius\": 51.5, \"thickness\": 3.6, \"material\": 1.5168, \"stop\": true},\n"
    "    {\"radius\": \"inf\", \"thickness\": 97.25},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0}";

static void global_fold(void **state)
{
    const char *fold = ct_design("fold.json", FOLD), *unf = ct_design("unf.json", UNFOLDED);
    static const char *const rays[3] = {"0,1,0,1", "0,0.5,0.7,-0.3", "0,0,-1,0"};
    static const char *const methods[3] = {"precise", "mpfr", "classic"};
    int k, m;
    (void)state;
    for (m = 0; m < 3; m++)
        for (k = 0; k < 3; k++) {
            ct_result g, u, l;
            double want[3], got[3], bound;
            int j;
            static const char *const col[3] = {"x", "y", "z"};
            ct_run(&g, "trace", fold, "--ray", rays[k], "--method", methods[m], "--global",
                   "--format", "csv", NULL);
            ct_run(&u, "trace", unf, "--ray", rays[k], "--method", methods[m], "--format",
                   "csv", NULL);
            ct_run(&l, "trace", fold, "--ray", rays[k], "--method", methods[m], "--format",
                   "csv", NULL);
            if (g.code != 0 || u.code != 0 || l.code != 0)
                fail_msg("exit %d %d %d: %s%s", g.code, u.code, l.code, g.err, u.err);
            want[0] = ct_csv_num(u.out, 3, "x");
            want[1] = 57.25;
            want[2] = 43.6 + ct_csv_num(u.out, 3, "y");
            bound = ct_csv_num(g.out, 6, m == 2 ? "error_estimate" : "error_bound");
            for (j = 0; j < 3; j++) {
                got[j] = ct_csv_num(g.out, 6, col[j]);
                /* The unfolded trace's own rounding, the global bound, and
                 * the rounding of 43.6 + y. */
                if (fabs(got[j] - want[j]) > bound + 2e-16 * 60.0 + (m == 2 ? 1e-12 : 0.0))
                    fail_msg("%s ray %s: global %s %.17g, the unfolded lens gives %.17g "
                             "(bound %.3g)",
                             methods[m], rays[k], col[j], got[j], want[j], bound);
            }
            /* Locally the image point is the unfolded one. */
            assert_true(fabs(ct_csv_num(l.out, 6, "x") - ct_csv_num(u.out, 3, "x")) <=
                        (m == 2 ? 1e-12 : 1e-15));
            /* Surface 1 is the reference: its row does not move. */
            assert_true(ct_csv_num(g.out, 1, "y") == ct_csv_num(l.out, 1, "y"));
            ct_free(&g);
            ct_free(&u);
            ct_free(&l);
        }
}

static void global_reports_and_refusals(void **state)
{
    const char *fold = ct_design("fold2.json", FOLD);
    const char *rays = ct_file("rays.csv", "hx,hy,px,py\n0,1,0,1\n0,0,0.5,0.5\n");
    ct_result r, a, b;
    (void)state;
    ct_run(&r, "trace", fold, "--ray", "0,1,0,1", "--global", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "Coordinates are global, in the frame of surface 1"));
    ct_free(&r);
    ct_run(&r, "trace", "--global=4", fold, "--ray", "0,1,0,1", "--format", "json", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "\"frame\": \"global\""));
    assert_non_null(strstr(r.out, "\"global_reference\": 4"));
    ct_free(&r);
    /* "--global 2" takes the number; the design may come after it. */
    ct_run(&a, "trace", "--global", "2", fold, "--ray", "0,1,0,1", "--format", "csv", NULL);
    ct_run(&b, "trace", fold, "--global=2", "--ray", "0,1,0,1", "--format", "csv", NULL);
    assert_int_equal(a.code, 0);
    assert_string_equal(a.out, b.out);
    /* Surface 2 is its own reference: its row is its local one. */
    ct_free(&b);
    ct_run(&b, "trace", fold, "--ray", "0,1,0,1", "--format", "csv", NULL);
    assert_true(ct_csv_num(a.out, 2, "y") == ct_csv_num(b.out, 2, "y"));
    ct_free(&a);
    ct_free(&b);
    /* A list of rays gives the rows single rays give. */
    ct_run(&a, "trace", fold, "--rays", rays, "--global", "--format", "csv", NULL);
    ct_run(&b, "trace", fold, "--ray", "0,1,0,1", "--global", "--format", "csv", NULL);
    assert_int_equal(a.code, 0);
    assert_true(ct_csv_num(a.out, 6, "y") == ct_csv_num(b.out, 6, "y"));
    assert_true(ct_csv_num(a.out, 6, "z") == ct_csv_num(b.out, 6, "z"));
    ct_free(&a);
    ct_free(&b);
    /* Refused, with the reason. */
    ct_run(&r, "trace", fold, "--ray", "0,1,0,1", "--global", "3", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "global reference surface 3 is a coordinate break"));
    ct_free(&r);
    ct_run(&r, "trace", fold, "--ray", "0,1,0,1", "--global=0", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "the object is at infinity"));
    ct_free(&r);
    ct_run(&r, "trace", fold, "--ray", "0,1,0,1", "--global=99", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "global reference surface 99 is not one of 0 to 6"));
    ct_free(&r);
    ct_run(&r, "trace", fold, "--ray", "0,1,0,1", "--global=x", NULL);
    assert_int_equal(r.code, 2);
    ct_free(&r);
}

/* A design whose frame change cannot stand is refused before any output,
 * naming the file and surface (exit status 3 or 4, as for other bad
 * designs). */
static void bad_frames(void **state)
{
    static const char *const bad[][2] = {
        {"    {\"thickness\": \"inf\"},\n    {\"type\": \"coordinate_break\", \"stop\": true},\n"
         "    {}",
         "surface 1: a coordinate break cannot be the stop"},
        {"    {\"thickness\": \"inf\"},\n    {\"stop\": true, \"thickness\": 5},\n"
         "    {\"type\": \"coordinate_break\", \"break\": {\"tilt\": [0, 400, 0]}},\n    {}",
         "surface 2: break tilt about y 400 is beyond 360 degrees"},
        {"    {\"thickness\": \"inf\"},\n    {\"stop\": true, \"thickness\": 5},\n"
         "    {\"type\": \"coordinate_break\", \"break\": {\"order\": 1}},\n    {}",
         "surface 2: break: order: expected"},
    };
    size_t c;
    (void)state;
    for (c = 0; c < sizeof bad / sizeof bad[0]; c++) {
        const char *d = ct_design("bad.json", bad[c][0]);
        const char *out = ct_path("out.csv");
        ct_result r;
        ct_run(&r, "trace", d, "--ray", "0,0,0,1", "-o", out, NULL);
        if ((r.code != 3 && r.code != 4) || !strstr(r.err, bad[c][1]) || !strstr(r.err, "bad.json"))
            fail_msg("case %zu: exit %d, \"%s\"", c, r.code, r.err);
        {
            FILE *f = fopen(out, "r");
            assert_null(f); /* nothing written */
        }
        ct_free(&r);
    }
}

/* "sagitta semidiam": the fold's surfaces 1 and 2 carry the whole beam
 * (EPD 10, field 5 degrees), so the lens's front is the pupil: 5 mm. */
static void semidiam_command(void **state)
{
    const char *fold = ct_design("fold3.json", FOLD);
    ct_result r;
    (void)state;
    ct_run(&r, "semidiam", fold, NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "coordinate break"));
    ct_free(&r);
    ct_run(&r, "semidiam", fold, "--format", "json", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "{\"surface\": 1, \"auto\": 5"));
    ct_free(&r);
    ct_run(&r, "semidiam", NULL);
    assert_int_equal(r.code, 2);
    ct_free(&r);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(semidiam_command),
        cmocka_unit_test(global_fold),
        cmocka_unit_test(global_reports_and_refusals),
        cmocka_unit_test(bad_frames),
    };
    int rc;
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
