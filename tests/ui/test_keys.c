/*
 * test_keys.c - the keys that work anywhere are one table: every key is
 * bound once, every row names its keys, and sagitta(1)'s "Keys anywhere"
 * lists exactly the table's rows in its order, so the manual cannot drift
 * from what the editor does.
 *
 * Independent reference: the man page, read as groff source.
 */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "term.h"
#include "ui.h"

/* A label without commas and with single blanks: "q, F10, Ctrl-C" and
 * "q F10 Ctrl-C" are the same keys. */
static void norm(const char *s, char *out, size_t n)
{
    size_t k = 0;
    for (; *s && k + 1 < n; s++) {
        char c = *s == ',' ? ' ' : *s;
        if (c == ' ' && (k == 0 || out[k - 1] == ' '))
            continue;
        out[k++] = c;
    }
    while (k && out[k - 1] == ' ')
        k--;
    out[k] = '\0';
}

/* The tag line of a .TP entry as text: macros' arguments joined, quotes
 * dropped, groff's \- as -. */
static void tag_text(const char *line, char *out, size_t n)
{
    char buf[256];
    size_t k = 0;
    const char *p = line;
    if (p[0] == '.') {
        while (*p && *p != ' ')
            p++;
    }
    for (; *p && *p != '\n' && k + 1 < sizeof buf; p++) {
        if (*p == '"')
            continue;
        if (p[0] == '\\' && p[1] == '-') {
            buf[k++] = '-';
            p++;
            continue;
        }
        buf[k++] = *p;
    }
    buf[k] = '\0';
    norm(buf, out, n);
}

/* The labels of sagitta(1)'s "Keys anywhere", in order. */
static int man_labels(char labels[][64], int max)
{
    char path[4096], line[512];
    FILE *f = fopen(tu_path("man/sagitta.1", path, sizeof path), "r");
    int in = 0, tag = 0, n = 0;
    assert_non_null(f);
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, ".SS ", 4) == 0) {
            if (in)
                break;
            in = strcmp(line, ".SS Keys anywhere\n") == 0;
            continue;
        }
        if (!in)
            continue;
        if (strncmp(line, ".TP", 3) == 0) {
            tag = 1;
            continue;
        }
        if (tag) {
            assert_true(n < max);
            tag_text(line, labels[n++], 64);
            tag = 0;
        }
    }
    fclose(f);
    assert_true(in);
    return n;
}

static void man_lists_the_table(void **state)
{
    char man[64][64], want[64];
    int n = man_labels(man, 64), i = 0;
    const ui_key *k;
    (void)state;
    for (k = ui_keys; k->label; k++, i++) {
        norm(k->label, want, sizeof want);
        if (i >= n)
            fail_msg("sagitta(1) Keys anywhere ends before \"%s\"", want);
        if (strcmp(man[i], want) != 0)
            fail_msg("sagitta(1) Keys anywhere entry %d is \"%s\"; the editor's table has \"%s\"",
                     i + 1, man[i], want);
    }
    if (i != n)
        fail_msg("sagitta(1) Keys anywhere has %d entries; the editor's table %d", n, i);
}

static void each_key_bound_once(void **state)
{
    const ui_key *k;
    int i;
    (void)state;
    for (k = ui_keys; k->label; k++) {
        assert_non_null(k->help);
        assert_true(k->help[0] != '\0');
        if (k->kind == UI_KEY_DOC) {
            /* Keys the loop reads before the table bind nothing here. */
            assert_int_equal(k->keys[0], 0);
            continue;
        }
        assert_true(k->keys[0] != 0);
        assert_true(k->kind == UI_KEY_ACT ? k->act != NULL : k->text != NULL);
        for (i = 0; i < UI_KEY_MAX && k->keys[i]; i++)
            if (ui_key_find(k->keys[i]) != k)
                fail_msg("key %d of \"%s\" is bound by \"%s\" first", k->keys[i], k->label,
                         ui_key_find(k->keys[i])->label);
    }
    /* The keys the help and the man page promise everywhere. */
    assert_non_null(ui_key_find('?'));
    assert_non_null(ui_key_find(K_F(1)));
    assert_non_null(ui_key_find(K_CTRL('e')));
    assert_null(ui_key_find('Z'));
}

/* Every key a row's label names is bound by that row: "Ctrl-R" is
 * K_CTRL('r'), "F5" is K_F(5), one character is itself. */
static int key_of(const char *name)
{
    if (strncmp(name, "Ctrl-", 5) == 0 && name[5] && !name[6])
        return K_CTRL(tolower((unsigned char)name[5]));
    if (name[0] == 'F' && isdigit((unsigned char)name[1]))
        return K_F(atoi(name + 1));
    if (name[0] && !name[1])
        return (unsigned char)name[0];
    return 0;
}

static void labels_name_the_keys(void **state)
{
    const ui_key *k;
    (void)state;
    for (k = ui_keys; k->label; k++) {
        char buf[64], *tok, *save;
        if (k->kind == UI_KEY_DOC)
            continue;
        snprintf(buf, sizeof buf, "%s", k->label);
        for (tok = strtok_r(buf, " ", &save); tok; tok = strtok_r(NULL, " ", &save)) {
            int key = key_of(tok);
            if (!key)
                fail_msg("\"%s\": cannot read key \"%s\"", k->label, tok);
            if (ui_key_find(key) != k)
                fail_msg("\"%s\" names %s, which that row does not bind", k->label, tok);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(each_key_bound_once),
        cmocka_unit_test(labels_name_the_keys),
        cmocka_unit_test(man_lists_the_table),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
