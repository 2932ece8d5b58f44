/* Scripted input for prt view: one event per line, "SECONDS COMMAND ARGS", run in order once
 * their time has come. Scripts make the viewer testable and record fly-throughs. */
#include "view.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum { EV_ORBIT, EV_PAN, EV_ZOOM, EV_ENV, EV_KEY, EV_DRAG, EV_SCREENSHOT, EV_QUIT } ev_kind;

typedef struct ev {
    double time;
    ev_kind kind;
    float a, b;
    int button, mods;
    char text[512];    /* key name or screenshot path */
} ev;

struct view_script {
    ev *events;
    int count, next;
};

static const struct { const char *name; ev_kind kind; int nargs; } verbs[] = {
    {"orbit", EV_ORBIT, 2}, {"pan", EV_PAN, 2}, {"zoom", EV_ZOOM, 1}, {"env-rotate", EV_ENV, 2}, {"key", EV_KEY, -1},
    {"drag", EV_DRAG, 3}, {"screenshot", EV_SCREENSHOT, -1}, {"quit", EV_QUIT, 0},
};

int view_script_load(const cli *c, const char *path, view_script **out)
{
    *out = NULL;
    FILE *f = fopen(path, "r");
    if (!f) { cli_error(c, "cannot open script '%s'", path); return EXIT_FAILURE_INPUT; }
    view_script *s = calloc(1, sizeof *s);
    int cap = 0, lineno = 0;
    char line[1024];
    double last = 0;
    while (s && fgets(line, sizeof line, f)) {
        lineno++;
        char *hash = strchr(line, '#');
        if (hash) *hash = 0;
        char verb[32] = "", arg[3][512] = {"", "", ""};
        double t;
        int n = sscanf(line, "%lf %31s %511s %511s %511s", &t, verb, arg[0], arg[1], arg[2]);
        if (n <= 0) continue;   /* blank or comment */
        int k = -1;
        for (int i = 0; i < (int)(sizeof verbs / sizeof verbs[0]); ++i)
            if (n >= 2 && !strcmp(verb, verbs[i].name)) k = i;
        bool ok = k >= 0 && t >= last && (verbs[k].nargs < 0 ? n == 3 : n - 2 >= verbs[k].nargs);
        if (!ok) {
            cli_error(c, "%s:%d: expected 'SECONDS VERB ARGS' with times in order; verbs: orbit DYAW DPITCH, pan DX DY, zoom F, "
                         "env-rotate YAW PITCH, key NAME, drag left|right DX DY [ctrl|shift], screenshot FILE, quit", path, lineno);
            fclose(f);
            view_script_free(s);
            return EXIT_USAGE;
        }
        if (s->count == cap) {
            cap = cap ? cap * 2 : 16;
            ev *e = realloc(s->events, (size_t)cap * sizeof *e);
            if (!e) break;
            s->events = e;
        }
        ev *e = &s->events[s->count++];
        memset(e, 0, sizeof *e);
        e->time = last = t;
        e->kind = verbs[k].kind;
        if (e->kind == EV_KEY || e->kind == EV_SCREENSHOT) snprintf(e->text, sizeof e->text, "%s", arg[0]);
        else if (e->kind == EV_DRAG) {
            e->button = !strcmp(arg[0], "right") ? 1 : 0;
            e->a = strtof(arg[1], NULL);
            e->b = strtof(arg[2], NULL);
            char mod[32] = "";   /* an optional modifier after the deltas */
            if (sscanf(line, "%*f %*s %*s %*s %*s %31s", mod) == 1) e->mods = !strcmp(mod, "ctrl") ? PRT_MOD_CTRL : !strcmp(mod, "shift") ? PRT_MOD_SHIFT : 0;
        } else if (verbs[k].nargs >= 1) {
            e->a = strtof(arg[0], NULL);
            if (verbs[k].nargs == 2) e->b = strtof(arg[1], NULL);
        }
    }
    fclose(f);
    if (!s) { cli_error(c, "out of memory reading '%s'", path); return EXIT_NO_MEMORY; }
    *out = s;
    return EXIT_OK;
}

int view_script_step(view_script *s, viewer *v, double elapsed)
{
    while (s->next < s->count && s->events[s->next].time <= elapsed && !v->quit) {
        const ev *e = &s->events[s->next++];
        switch (e->kind) {
        case EV_ORBIT: view_orbit(v, e->a, e->b); break;
        case EV_PAN: view_pan(v, e->a, e->b); break;
        case EV_ZOOM: view_zoom(v, e->a); break;
        case EV_ENV: view_rotate_env(v, e->a - v->want.env_yaw, e->b - v->want.env_pitch); break;
        case EV_DRAG:
            /* The same path as a mouse drag: ctrl rotates the lighting, right pans, left orbits. */
            if (e->mods & PRT_MOD_CTRL) view_rotate_env(v, e->a * 0.25f, e->b * 0.25f);
            else if (e->button == 1 || (e->mods & PRT_MOD_SHIFT)) view_pan(v, e->a / 400.0f, e->b / 400.0f);
            else view_orbit(v, -e->a * 0.3f, e->b * 0.3f);
            break;
        case EV_KEY: {
            int key = view_key_code(v, e->text);
            if (!key) { cli_error(v->c, "script: no control is bound to key '%s' (press h in the viewer for the list)", e->text); return EXIT_USAGE; }
            view_press(v, key);
            break;
        }
        case EV_SCREENSHOT:
            if (view_screenshot(v, e->text)) { cli_error(v->c, "screenshot '%s' failed: %s", e->text, prt_last_error()); return EXIT_FAILURE_INPUT; }
            if (!v->c->quiet) fprintf(stderr, "prt view: wrote %s\n", e->text);
            break;
        case EV_QUIT: v->quit = true; break;
        }
        v->dirty = true;
    }
    if (s->next == s->count) v->quit = true;
    return EXIT_OK;
}

void view_script_free(view_script *s)
{
    if (!s) return;
    free(s->events);
    free(s);
}
