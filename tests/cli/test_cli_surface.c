/* test_cli_surface.c - "trace --surface LIST": the rows of the chosen
 * surfaces are the rows of the full table for those surfaces, byte for
 * byte, in CSV, JSON and text (HDF5: test_cli_hdf5 against this CSV); a
 * bad list is refused with a message naming the item, and no output. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "clitest.h"

static char examples[1024];

static const char *example(const char *file)
{
    static char buf[4][1100];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", examples, file);
    return buf[k];
}

/* Rays of three fields in mixed order, some outside the pupil, so some
 * surfaces fail. */
static const char *ray_list(void)
{
    char text[64 * 200], *p = text;
    int k;
    p += sprintf(p, "hx,hy,px,py\n");
    for (k = 0; k < 150; k++)
        p += sprintf(p, "0,%.17g,%.17g,%.17g\n", (k * 7 % 3) / 2.0, 1.2 * sin(k * 0.37),
                     1.2 * cos(k * 0.53));
    return ct_file("rays.csv", text);
}

/* Whether surface s is in the list (given as the surfaces it names). */
static int chosen(const int *want, int nwant, int s)
{
    int k;
    for (k = 0; k < nwant; k++)
        if (want[k] == s)
            return 1;
    return 0;
}

/* The full CSV's lines whose surface column names a chosen surface. */
static char *csv_filter(const char *full, const int *want, int nwant)
{
    char *out = malloc(strlen(full) + 1), *o = out;
    const char *line = full, *end;
    int col = -1, first = 1;
    assert_non_null(out);
    for (; *line; line = end + 1) {
        const char *f = line;
        int c, keep;
        end = strchr(line, '\n');
        assert_non_null(end);
        if (first) {
            /* The header's "surface" column. */
            for (c = 0; f < end; c++) {
                if (strncmp(f, "surface,", 8) == 0)
                    col = c;
                f = memchr(f, ',', (size_t)(end - f));
                if (!f)
                    break;
                f++;
            }
            assert_true(col >= 0);
            keep = 1;
            first = 0;
        } else {
            for (c = 0; c < col; c++)
                f = strchr(f, ',') + 1;
            keep = chosen(want, nwant, atoi(f));
        }
        if (keep) {
            memcpy(o, line, (size_t)(end - line + 1));
            o += end - line + 1;
        }
    }
    *o = '\0';
    return out;
}

/* The full text report without the table rows of other surfaces: a row
 * starts with its label (OBJ, IMA or the number) right-aligned in four
 * columns and a blank. */
static char *text_filter(const char *full, const int *want, int nwant, int nsurf)
{
    char *out = malloc(strlen(full) + 1), *o = out;
    const char *line = full, *end;
    assert_non_null(out);
    for (; *line; line = end + 1) {
        int s = -1, keep = 1;
        end = strchr(line, '\n');
        assert_non_null(end);
        if (end - line > 5 && line[4] == ' ') {
            char lab[5];
            memcpy(lab, line, 4);
            lab[4] = '\0';
            if (strcmp(lab, " OBJ") == 0)
                s = 0;
            else if (strcmp(lab, " IMA") == 0)
                s = nsurf - 1;
            else if (strspn(lab, " 0123456789") == 4 && lab[3] != ' ')
                s = atoi(lab);
            if (s >= 0)
                keep = chosen(want, nwant, s);
        }
        if (keep) {
            memcpy(o, line, (size_t)(end - line + 1));
            o += end - line + 1;
        }
    }
    *o = '\0';
    return out;
}

/* Each ray's JSON with its "surfaces" cut to the chosen ones. */
static void json_filter(cJSON *rays, const int *want, int nwant)
{
    cJSON *ray;
    cJSON_ArrayForEach(ray, rays) {
        cJSON *surf = cJSON_GetObjectItem(ray, "surfaces");
        int k;
        assert_non_null(surf);
        for (k = cJSON_GetArraySize(surf) - 1; k >= 0; k--) {
            cJSON *s = cJSON_GetArrayItem(surf, k);
            if (!chosen(want, nwant, cJSON_GetObjectItem(s, "surface")->valueint))
                cJSON_DeleteItemFromArray(surf, k);
        }
    }
}

static void check_list(const char *design, const char *method, int nsurf, const char *list,
                       const int *want, int nwant)
{
    const char *rays = ray_list();
    const char *fmts[3] = {"csv", "json", "text"};
    int f;
    for (f = 0; f < 3; f++) {
        ct_result full, sel;
        ct_run(&full, "trace", design, "--method", method, "--rays", rays, "--format", fmts[f],
               (char *)NULL);
        ct_run(&sel, "trace", design, "--method", method, "--rays", rays, "--format", fmts[f],
               "--surface", list, (char *)NULL);
        if (full.code != 0 || sel.code != 0)
            fail_msg("trace: %s%s", full.err, sel.err);
        if (f == 0) {
            char *want_text = csv_filter(full.out, want, nwant);
            assert_string_equal(sel.out, want_text);
            free(want_text);
        } else if (f == 1) {
            cJSON *a = cJSON_Parse(full.out), *b = cJSON_Parse(sel.out);
            assert_non_null(a);
            assert_non_null(b);
            json_filter(cJSON_GetObjectItem(a, "rays"), want, nwant);
            assert_true(cJSON_Compare(a, b, 1));
            cJSON_Delete(a);
            cJSON_Delete(b);
        } else {
            char *want_text = text_filter(full.out, want, nwant, nsurf);
            assert_string_equal(sel.out, want_text);
            free(want_text);
        }
        ct_free(&full);
        ct_free(&sel);
    }
    print_message("# %s %s --surface %s: CSV, JSON and text rows as the full table's\n",
                  design, method, list);
}

static void test_chosen_rows(void **state)
{
    /* The Cassegrain: 15 surfaces, the stop on surface 2. */
    static const int ima[] = {14}, mixed[] = {0, 2, 5, 6, 7, 14}, sto[] = {2};
    /* The Cooke triplet: 8 surfaces. */
    static const int cooke[] = {1, 2, 3, 7};
    (void)state;
    check_list(example("cassegrain.json"), "precise", 15, "IMA", ima, 1);
    check_list(example("cassegrain.json"), "precise", 15, "ima, 5-7,STO,0,6,OBJ", mixed, 6);
    check_list(example("cassegrain.json"), "classic", 15, "sto", sto, 1);
    check_list(example("cooke_triplet.json"), "precise", 8, "1-3,7", cooke, 4);
}

static void test_one_ray(void **state)
{
    ct_result full, sel;
    static const int want[] = {2, 14};
    (void)state;
    ct_run(&full, "trace", example("cassegrain.json"), "--ray", "0,1,0,0.5", "--format", "csv",
           (char *)NULL);
    ct_run(&sel, "trace", example("cassegrain.json"), "--ray", "0,1,0,0.5", "--format", "csv",
           "--surface", "STO,IMA", (char *)NULL);
    assert_int_equal(full.code, 0);
    assert_int_equal(sel.code, 0);
    {
        char *w = csv_filter(full.out, want, 2);
        assert_string_equal(sel.out, w);
        free(w);
    }
    ct_free(&full);
    ct_free(&sel);
}

/* The OPD of rays of interleaved fields (taken field by field within a
 * block) against each ray traced alone with --ray (its own sphere, the
 * one-ray OPD): the same digits, at blocks of 1000 and of 7 rays. */
static void test_opd_any_order(void **state)
{
    const char *rays = ray_list();
    static const char *const cols[] = {"opd_waves", "opd_error_bound", "ex", "ey", "x", "y"};
    const char *blocks[2] = {NULL, "7"};
    int b, k, c;
    (void)state;
    for (b = 0; b < 2; b++) {
        ct_result list;
        if (blocks[b])
            setenv("SAGITTA_RAYS_BLOCK", blocks[b], 1);
        else
            unsetenv("SAGITTA_RAYS_BLOCK");
        ct_run(&list, "trace", example("cassegrain.json"), "--rays", rays, "--format", "csv",
               "--surface", "IMA", (char *)NULL);
        assert_int_equal(list.code, 0);
        for (k = 0; k < 150; k += 13) {
            char ray[128], want[64], got[64];
            ct_result one;
            snprintf(ray, sizeof ray, "0,%.17g,%.17g,%.17g", (k * 7 % 3) / 2.0,
                     1.2 * sin(k * 0.37), 1.2 * cos(k * 0.53));
            ct_run(&one, "trace", example("cassegrain.json"), "--ray", ray, "--format", "csv",
                   "--surface", "IMA", (char *)NULL);
            assert_int_equal(one.code, 0);
            for (c = 0; c < 6; c++) {
                assert_non_null(ct_csv(one.out, 0, cols[c], want, sizeof want));
                assert_non_null(ct_csv(list.out, k, cols[c], got, sizeof got));
                if (strcmp(want, got) != 0)
                    fail_msg("ray %d %s: list %s, alone %s", k, cols[c], got, want);
            }
            ct_free(&one);
        }
        ct_free(&list);
    }
    unsetenv("SAGITTA_RAYS_BLOCK");
}

/* A bad list: exit status 2, the item named, no output file. */
static void refused(const char *list, const char *says)
{
    const char *rays = ray_list(), *out = ct_path("never.csv");
    ct_result r;
    ct_run(&r, "trace", example("cassegrain.json"), "--rays", rays, "--format", "csv", "-o",
           out, "--surface", list, (char *)NULL);
    assert_int_equal(r.code, 2);
    if (!strstr(r.err, says) || !strstr(r.err, "--surface"))
        fail_msg("--surface %s: \"%s\" does not say \"%s\"", list, r.err, says);
    assert_int_not_equal(access(out, F_OK), 0);
    ct_free(&r);
}

static void test_bad_lists(void **state)
{
    (void)state;
    refused("15", "\"15\": surface 15 is past the image, surface 14");
    refused("1,x2", "\"x2\" is not a surface");
    refused("-3", "\"-3\" is not a surface");
    refused("7-2", "\"7-2\": the range runs from 7 down to 2");
    refused("1,,2", "an empty item");
    refused("", "an empty item");
    refused("IMA-STO", "the range runs from 14 down to 2");
    refused("2-99999999999", "is not a surface");
}

int main(int argc, char **argv)
{
    const char *e = getenv("SAGITTA_EXAMPLES");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chosen_rows),
        cmocka_unit_test(test_one_ray),
        cmocka_unit_test(test_opd_any_order),
        cmocka_unit_test(test_bad_lists),
    };
    int rc;
    ct_init(argc, argv);
    snprintf(examples, sizeof examples, "%s", e && *e ? e : "examples");
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
