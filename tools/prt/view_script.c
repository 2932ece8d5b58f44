/* Scripted input for prt view: one event per line, "SECONDS COMMAND ARGS", run in order once
 * their time has come. Scripts make the viewer testable and record fly-throughs. */
#include "view.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum { EV_ORBIT, EV_PAN, EV_ZOOM, EV_ENV, EV_KEY, EV_DRAG, EV_SCREENSHOT, EV_QUIT, EV_LIGHT_ADD, EV_LIGHT_SELECT, EV_LIGHT_MOVE,
               EV_LIGHT_SCALE, EV_LIGHT_COLOUR, EV_LIGHT_REMOVE, EV_PAINT, EV_PAINT_CLEAR, EV_PAINT_SAVE } ev_kind;

typedef struct ev {
    double time;
    ev_kind kind;
    float a, b, c;
    float rgb[3];      /* paint: the light */
    int button, mods;
    bool has_position;
    char text[512];    /* key name or screenshot path */
} ev;

struct view_script {
    ev *events;
    int count, next;
};

static const struct { const char *name; ev_kind kind; int nargs; } verbs[] = {
    {"orbit", EV_ORBIT, 2}, {"pan", EV_PAN, 2}, {"zoom", EV_ZOOM, 1}, {"env-rotate", EV_ENV, 2}, {"key", EV_KEY, -1},
    {"drag", EV_DRAG, 3}, {"screenshot", EV_SCREENSHOT, -1}, {"quit", EV_QUIT, 0}, {"light-add", EV_LIGHT_ADD, 1},
    {"light-select", EV_LIGHT_SELECT, 1}, {"light-move", EV_LIGHT_MOVE, 3}, {"light-scale", EV_LIGHT_SCALE, 1},
    {"light-colour", EV_LIGHT_COLOUR, 3}, {"light-color", EV_LIGHT_COLOUR, 3}, {"light-remove", EV_LIGHT_REMOVE, 0},
    {"paint", EV_PAINT, 4}, {"paint-clear", EV_PAINT_CLEAR, 0}, {"paint-save", EV_PAINT_SAVE, -1},
};

static const char *VERBS = "verbs: orbit DYAW DPITCH, pan DX DY, zoom F, env-rotate YAW PITCH, key NAME, drag left|right DX DY [ctrl|shift|alt], "
                           "light-add point|spot|directional|sphere [X Y Z], light-select N, light-move DX DY DZ, light-scale F, "
                           "light-colour R G B, light-remove, paint X Y RADIUS R,G,B, paint-clear, paint-save FILE, screenshot FILE, quit";

static bool number(const char *text, float *out)
{
    char *end;
    *out = strtof(text, &end);
    return end != text && !*end && isfinite(*out);
}

static bool light_type(const char *name, prt_light_type *out)
{
    static const struct { const char *name; prt_light_type type; } types[] = {
        {"point", PRT_LIGHT_POINT}, {"spot", PRT_LIGHT_SPOT}, {"directional", PRT_LIGHT_DIRECTIONAL}, {"sphere", PRT_LIGHT_SPHERE}};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; ++i)
        if (!strcmp(name, types[i].name)) { *out = types[i].type; return true; }
    return false;
}

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
        char verb[32] = "", arg[4][512] = {"", "", "", ""};
        double t;
        int n = sscanf(line, "%lf %31s %511s %511s %511s %511s", &t, verb, arg[0], arg[1], arg[2], arg[3]);
        if (n == EOF) continue;   /* blank or comment; a line not starting with a time is an error */
        int k = -1;
        for (int i = 0; i < (int)(sizeof verbs / sizeof verbs[0]); ++i)
            if (n >= 2 && !strcmp(verb, verbs[i].name)) k = i;
        bool ok = k >= 0 && t >= last && (verbs[k].nargs < 0 ? n == 3 : n - 2 >= verbs[k].nargs);
        prt_light_type type = PRT_LIGHT_POINT;
        if (ok && verbs[k].kind == EV_LIGHT_ADD) ok = light_type(arg[0], &type) && (n == 3 || n == 6);
        if (!ok) {
            cli_error(c, "%s:%d: expected 'SECONDS VERB ARGS' with times in order; %s", path, lineno, VERBS);
            fclose(f);
            view_script_free(s);
            return EXIT_USAGE;
        }
        if (s->count == cap) {
            cap = cap ? cap * 2 : 16;
            ev *grown = realloc(s->events, (size_t)cap * sizeof *grown);
            if (!grown) {
                cli_error(c, "out of memory reading '%s'", path);
                fclose(f);
                view_script_free(s);
                return EXIT_NO_MEMORY;
            }
            s->events = grown;
        }
        ev *e = &s->events[s->count++];
        memset(e, 0, sizeof *e);
        e->time = last = t;
        e->kind = verbs[k].kind;
        bool numbers = true;
        if (e->kind == EV_KEY) snprintf(e->text, sizeof e->text, "%s", arg[0]);
        else if (e->kind == EV_SCREENSHOT || e->kind == EV_PAINT_SAVE) {
            /* Relative to the script, as its other paths would be: the script can move with its shots. */
            const char *slash = strrchr(path, '/');
            const size_t dir = arg[0][0] == '/' || !slash ? 0 : (size_t)(slash - path) + 1;
            ok = dir + strlen(arg[0]) < sizeof e->text;
            if (ok) { memcpy(e->text, path, dir); memcpy(e->text + dir, arg[0], strlen(arg[0]) + 1); }
            else { cli_error(c, "%s:%d: the %s path is too long", path, lineno, verb); fclose(f); view_script_free(s); return EXIT_USAGE; }
        }
        else if (e->kind == EV_PAINT) {
            /* X Y in window pixels from the top left, the radius in world units, the light >= 0. */
            numbers = number(arg[0], &e->a) && number(arg[1], &e->b) && number(arg[2], &e->c) && e->c > 0 && cli_parse_vec3(arg[3], true, e->rgb) &&
                      e->rgb[0] >= 0 && e->rgb[1] >= 0 && e->rgb[2] >= 0;
            if (!numbers) {
                cli_error(c, "%s:%d: paint takes X Y RADIUS R,G,B: pixels, a radius > 0 and light >= 0", path, lineno);
                fclose(f);
                view_script_free(s);
                return EXIT_USAGE;
            }
        }
        else if (e->kind == EV_LIGHT_ADD) {
            e->button = (int)type;
            e->has_position = n == 6;
            if (e->has_position) numbers = number(arg[1], &e->a) && number(arg[2], &e->b) && number(arg[3], &e->c);
        } else if (e->kind == EV_DRAG) {
            e->button = !strcmp(arg[0], "right") ? 1 : 0;
            numbers = number(arg[1], &e->a) && number(arg[2], &e->b);
            char mod[32] = "";   /* an optional modifier after the deltas */
            if (sscanf(line, "%*f %*s %*s %*s %*s %31s", mod) == 1)
                e->mods = !strcmp(mod, "ctrl") ? PRT_MOD_CTRL : !strcmp(mod, "shift") ? PRT_MOD_SHIFT : !strcmp(mod, "alt") ? PRT_MOD_ALT : 0;
        } else {
            float *dst[3] = {&e->a, &e->b, &e->c};
            for (int i = 0; i < verbs[k].nargs && numbers; ++i) numbers = number(arg[i], dst[i]);
        }
        if (!numbers) {
            cli_error(c, "%s:%d: '%s' takes finite numbers", path, lineno, verb);
            fclose(f);
            view_script_free(s);
            return EXIT_USAGE;
        }
    }
    fclose(f);
    if (!s) { cli_error(c, "out of memory reading '%s'", path); return EXIT_NO_MEMORY; }
    *out = s;
    return EXIT_OK;
}

/* A scripted action that does not apply is an error: scripts are tests and recordings. */
static int script_refused(viewer *v)
{
    cli_error(v->c, "script: %s", v->message[0] ? v->message : "the light action does not apply");
    return EXIT_USAGE;
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
            /* The same path as a mouse drag: alt moves the selected light, ctrl rotates the
             * lighting, right pans, left orbits. */
            if (e->mods & PRT_MOD_ALT) {
                const float px = v->dist > 0 ? v->dist * 0.0015f : 0.01f;
                if (e->button == 1) view_light_move(v, 0, 0, e->b * px);
                else view_light_move(v, e->a * px, -e->b * px, 0);
            } else if (e->mods & PRT_MOD_CTRL) view_rotate_env(v, e->a * 0.25f, e->b * 0.25f);
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
        case EV_LIGHT_ADD: {
            float p[3] = {e->a, e->b, e->c};
            if (!view_light_add(v, (prt_light_type)e->button, e->has_position ? p : NULL)) return script_refused(v);
            break;
        }
        case EV_LIGHT_SELECT: if (!view_light_select(v, (int)e->a - 1)) return script_refused(v); break;
        case EV_LIGHT_MOVE: if (!view_light_move(v, e->a, e->b, e->c)) return script_refused(v); break;
        case EV_LIGHT_SCALE: if (!view_light_scale(v, e->a)) return script_refused(v); break;
        case EV_LIGHT_COLOUR: {
            float rgb[3] = {e->a, e->b, e->c};
            if (!view_light_colour(v, rgb)) return script_refused(v);
            break;
        }
        case EV_LIGHT_REMOVE: if (!view_light_remove(v)) return script_refused(v); break;
        case EV_PAINT: if (!view_paint_at(v, e->a, e->b, e->c, e->rgb)) return script_refused(v); break;
        case EV_PAINT_CLEAR: if (!view_paint_clear(v)) return script_refused(v); break;
        case EV_PAINT_SAVE:
            if (!view_paint_save(v, e->text)) return script_refused(v);
            if (!v->c->quiet) fprintf(stderr, "prt view: wrote %s\n", e->text);
            break;
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
