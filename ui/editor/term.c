/*
 * term.c - curses, and nothing but curses: the one file that knows the
 * editor runs in a terminal.
 */
#ifndef NCURSES_WIDECHAR
#define NCURSES_WIDECHAR 1
#endif

#include "term.h"

#include <curses.h>
#include <langinfo.h>
#include <locale.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>
#include <wchar.h>

static int active;
static int utf8;
static int colors;
static int style_attr[T_NSTYLES];
static volatile sig_atomic_t pending_signal;
static int mouse_y, mouse_x, mouse_kind;

/* What a crash needs to give the terminal back, prepared in advance so the
 * handler only calls write() and tcsetattr(), which are async-signal-safe. */
static struct termios saved_modes;
static int have_modes;
static char restore_seq[256];
static size_t restore_len;

/* SIGTERM, SIGHUP and friends only raise a flag: the event loop notices it
 * within one key timeout, ends curses and exits in ordinary code.  The
 * recovery file needs nothing then, being written after every change. */
static void on_signal(int sig)
{
    pending_signal = sig;
}

/* A crash must not leave the user's terminal in raw mode on the alternate
 * screen. */
static void on_fatal(int sig)
{
    if (active) {
        active = 0;
        if (restore_len) {
            ssize_t k = write(STDOUT_FILENO, restore_seq, restore_len);
            (void)k;
        }
        if (have_modes)
            tcsetattr(STDOUT_FILENO, TCSANOW, &saved_modes);
    }
    signal(sig, SIG_DFL);
    raise(sig);
}

static void add_restore(const char *cap)
{
    size_t n;
    if (!cap || cap == (char *)-1)
        return;
    n = strlen(cap);
    if (restore_len + n < sizeof restore_seq) {
        memcpy(restore_seq + restore_len, cap, n);
        restore_len += n;
    }
}

/* The sequences endwin() would send: normal attributes and cursor, keypad
 * and mouse reporting off, the main screen back. */
static void prepare_restore(void)
{
    const char *xm = tigetstr("XM"), *km = tigetstr("kmous");
    restore_len = 0;
    add_restore(tigetstr("sgr0"));
    add_restore(tigetstr("cnorm"));
    add_restore(tigetstr("rmkx"));
    if (xm && xm != (char *)-1)
        add_restore(tiparm(xm, 0));
    else if (km && km != (char *)-1)
        add_restore("\033[?1000l");
    add_restore(tigetstr("rmcup"));
}

static void install(int sig, void (*fn)(int))
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = fn;
    sigemptyset(&sa.sa_mask);
    /* No SA_RESTART: a signal should wake the key read so the loop sees it. */
    sa.sa_flags = 0;
    sigaction(sig, &sa, NULL);
}

static void setup_styles(void)
{
    static const struct {
        short fg, bg;
        int attr;     /* with colours */
        int mono;     /* without */
    } s[T_NSTYLES] = {
        [T_NORMAL] = {-1, -1, A_NORMAL, A_NORMAL},
        [T_TITLE] = {COLOR_BLACK, COLOR_CYAN, A_NORMAL, A_REVERSE},
        [T_HEADER] = {COLOR_CYAN, -1, A_BOLD, A_BOLD | A_UNDERLINE},
        [T_CURSOR] = {COLOR_BLACK, COLOR_WHITE, A_NORMAL, A_REVERSE},
        [T_ROWSEL] = {-1, COLOR_BLUE, A_NORMAL, A_BOLD},
        [T_STOP] = {COLOR_YELLOW, -1, A_BOLD, A_BOLD},
        [T_ERROR] = {COLOR_RED, -1, A_BOLD, A_BOLD},
        [T_GOOD] = {COLOR_GREEN, -1, A_NORMAL, A_NORMAL},
        [T_DIM] = {-1, -1, A_DIM, A_DIM},
        [T_EDIT] = {COLOR_BLACK, COLOR_YELLOW, A_NORMAL, A_UNDERLINE | A_BOLD},
        [T_FRAME] = {COLOR_MAGENTA, -1, A_BOLD, A_BOLD},
        [T_PLOT0] = {COLOR_BLUE, -1, A_BOLD, A_NORMAL},
        [T_PLOT1] = {COLOR_GREEN, -1, A_NORMAL, A_NORMAL},
        [T_PLOT2] = {COLOR_RED, -1, A_NORMAL, A_NORMAL},
        [T_PLOT3] = {COLOR_YELLOW, -1, A_NORMAL, A_NORMAL},
        [T_PLOT4] = {COLOR_MAGENTA, -1, A_NORMAL, A_NORMAL},
        [T_PLOT5] = {COLOR_CYAN, -1, A_NORMAL, A_NORMAL},
    };
    int i;
    for (i = 0; i < T_NSTYLES; i++) {
        if (colors && (s[i].fg != -1 || s[i].bg != -1)) {
            init_pair((short)(i + 1), s[i].fg, s[i].bg);
            style_attr[i] = (int)COLOR_PAIR(i + 1) | s[i].attr;
        } else {
            style_attr[i] = colors ? s[i].attr : s[i].mono;
        }
    }
}

int term_init(void)
{
    const char *nc = getenv("NO_COLOR");
    /* Only the character type follows the user's locale: numbers are read
     * and written with a '.' whatever LC_NUMERIC says. */
    setlocale(LC_CTYPE, "");
    utf8 = strcmp(nl_langinfo(CODESET), "UTF-8") == 0;
    have_modes = tcgetattr(STDOUT_FILENO, &saved_modes) == 0;
    if (!newterm(NULL, stdout, stdin)) {
        fprintf(stderr, "sagitta: cannot start the terminal (TERM=%s)\n",
                getenv("TERM") ? getenv("TERM") : "unset");
        return -1;
    }
    {
        /* A screen editor cannot work without cursor addressing. */
        const char *cup = tigetstr("cup");
        if (cup == NULL || cup == (char *)-1) {
            endwin();
            fprintf(stderr, "sagitta: the terminal (TERM=%s) cannot move the cursor; "
                            "use --batch SCRIPT or a real terminal\n",
                    getenv("TERM") ? getenv("TERM") : "unset");
            return -1;
        }
    }
    active = 1;
    atexit(term_end);
    raw();
    noecho();
    nonl();
    keypad(stdscr, TRUE);
    set_escdelay(25);
    curs_set(0);
    colors = has_colors() && !(nc && nc[0]);
    if (colors) {
        start_color();
        use_default_colors();
    }
    setup_styles();
    mousemask(BUTTON1_PRESSED | BUTTON1_DOUBLE_CLICKED | BUTTON4_PRESSED | BUTTON5_PRESSED,
              NULL);
    mouseinterval(250);
    prepare_restore();
    install(SIGINT, on_signal);
    install(SIGTERM, on_signal);
    install(SIGHUP, on_signal);
    install(SIGQUIT, on_signal);
    signal(SIGSEGV, on_fatal);
    signal(SIGBUS, on_fatal);
    signal(SIGFPE, on_fatal);
    signal(SIGABRT, on_fatal);
    return 0;
}

void term_end(void)
{
    if (!active)
        return;
    active = 0;
    curs_set(1);
    endwin();
    fflush(stdout);
}

int term_active(void)
{
    return active;
}

void term_size(int *rows, int *cols)
{
    getmaxyx(stdscr, *rows, *cols);
}

int term_utf8(void)
{
    return utf8;
}

void term_erase(void)
{
    erase();
}

int term_text(int y, int x, int w, int style, int pad, const char *s)
{
    mbstate_t st;
    int used = 0;
    size_t len = strlen(s);
    if (w <= 0)
        return 0;
    memset(&st, 0, sizeof st);
    attrset(style_attr[style]);
    move(y, x);
    while (len > 0) {
        wchar_t wc;
        size_t k = mbrtowc(&wc, s, len, &st);
        int cw;
        if (k == (size_t)-1 || k == (size_t)-2 || k == 0) {
            /* Bytes the locale cannot read show as '?', one per byte. */
            memset(&st, 0, sizeof st);
            wc = L'?';
            k = 1;
        }
        cw = wcwidth(wc);
        if (cw < 0) {
            wc = L'?';
            cw = 1;
        }
        if (used + cw > w)
            break;
        addnwstr(&wc, 1);
        used += cw;
        s += k;
        len -= k;
    }
    if (pad)
        for (; used < w; used++)
            addch(' ');
    attrset(A_NORMAL);
    return used;
}

void term_fill(int y, int x, int w, int style)
{
    term_text(y, x, w, style, 1, "");
}

void term_cursor(int y, int x)
{
    if (y < 0) {
        curs_set(0);
        return;
    }
    move(y, x);
    curs_set(1);
}

void term_flush(void)
{
    refresh();
}

void term_repaint(void)
{
    clearok(curscr, TRUE);
}

void term_beep(void)
{
    beep();
}

void term_flush_input(void)
{
    if (active)
        flushinp();
}

static int map_code(wint_t c)
{
    switch (c) {
    case KEY_UP: return K_UP;
    case KEY_DOWN: return K_DOWN;
    case KEY_LEFT: return K_LEFT;
    case KEY_RIGHT: return K_RIGHT;
    case KEY_HOME: return K_HOME;
    case KEY_END: return K_END;
    case KEY_PPAGE: return K_PGUP;
    case KEY_NPAGE: return K_PGDN;
    case KEY_IC: return K_INS;
    case KEY_DC: return K_DEL;
    case KEY_BACKSPACE: return K_BACKSPACE;
    case KEY_ENTER: return K_ENTER;
    case KEY_BTAB: return K_BTAB;
    case KEY_RESIZE: return K_RESIZE;
    case KEY_MOUSE: {
        MEVENT ev;
        if (getmouse(&ev) != OK)
            return K_NONE;
        mouse_y = ev.y;
        mouse_x = ev.x;
        if (ev.bstate & BUTTON1_DOUBLE_CLICKED)
            mouse_kind = M_DOUBLE;
        else if (ev.bstate & BUTTON4_PRESSED)
            mouse_kind = M_WHEEL_UP;
        else if (ev.bstate & BUTTON5_PRESSED)
            mouse_kind = M_WHEEL_DOWN;
        else if (ev.bstate & BUTTON1_PRESSED)
            mouse_kind = M_CLICK;
        else
            return K_NONE;
        return K_MOUSE;
    }
    default:
        if (c >= KEY_F(1) && c <= KEY_F(12))
            return K_F((int)(c - KEY_F0));
        return K_NONE;
    }
}

static int hung_up(void)
{
    struct pollfd p;
    p.fd = STDIN_FILENO;
    p.events = POLLIN;
    p.revents = 0;
    return poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0;
}

int term_key(int timeout_ms)
{
    wint_t c;
    int r;
    if (pending_signal)
        return K_SIGNAL;
    timeout(timeout_ms);
    r = get_wch(&c);
    if (pending_signal)
        return K_SIGNAL;
    if (r == ERR) {
        /* A terminal that went away without a SIGHUP reaching us would
         * otherwise make every read fail at once, forever. */
        if (hung_up()) {
            pending_signal = SIGHUP;
            return K_SIGNAL;
        }
        return K_NONE;
    }
    if (r == KEY_CODE_YES)
        return map_code(c);
    switch (c) {
    case 27: return K_ESC;
    case '\r':
    case '\n': return K_ENTER;
    case '\t': return K_TAB;
    case 127:
    case 8: return K_BACKSPACE;
    default: return (int)c;
    }
}

void term_mouse(int *y, int *x, int *kind)
{
    *y = mouse_y;
    *x = mouse_x;
    *kind = mouse_kind;
}

int term_signal(void)
{
    int s = pending_signal;
    pending_signal = 0;
    return s;
}

void term_suspend(void)
{
    if (!active)
        return;
    def_prog_mode();
    endwin();
    fflush(stdout);
    raise(SIGSTOP);
    reset_prog_mode();
    clearok(curscr, TRUE);
    refresh();
}
