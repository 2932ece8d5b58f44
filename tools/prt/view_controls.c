/* The viewer's key bindings, one table per concern: core (camera, display, files) here, and a
 * table per method. Adding a method adds a table and a view_register call, not a case. */
#include "view.h"

#include <stdio.h>
#include <string.h>
#include <strings.h>

void view_register(viewer *v, const view_control *table, int count)
{
    for (int i = 0; i < count && v->ncontrols < VIEW_MAX_CONTROLS; ++i) v->controls[v->ncontrols++] = table[i];
}

int view_key_code(const viewer *v, const char *name)
{
    for (int i = 0; i < v->ncontrols; ++i)
        if (!strcasecmp(v->controls[i].name, name)) return v->controls[i].key;
    return 0;
}

void view_press(viewer *v, int key)
{
    for (int i = 0; i < v->ncontrols; ++i)
        if (v->controls[i].key == key) {
            v->controls[i].fn(v);
            v->dirty = true;
            return;
        }
}

/* ---- core ---- */
static void quit(viewer *v) { v->quit = true; }
static void toggle_help(viewer *v) { v->help = !v->help; }
static void toggle_hud(viewer *v) { v->hud = !v->hud; }
static void brighter(viewer *v) { v->exposure += 0.5f; }
static void darker(viewer *v) { v->exposure -= 0.5f; }
static void cycle_tonemap(viewer *v) { v->tonemap = v->tonemap == 2 ? 1 : 2; }
static void reset_view(viewer *v)
{
    v->moved = false;
    v->want.env_yaw = v->want.env_pitch = 0;
    view_request_relight(v);
}
static void reload_probe(viewer *v)
{
    prt_transfer_info info;
    prt_transfer_get_info(v->t, &info);
    prt_sh_light sh;
    prt_envmap *env = NULL;
    if (cli_light_project(v->c, &v->light, info.order, &sh, v->env ? &env : NULL)) {
        cli_error(v->c, "reload failed: %s", prt_last_error());
        return;
    }
    if (env) {   /* the worker reads the map: swap it while the worker is idle */
        view_sync(v);
        prt_envmap_release(v->env);
        v->env = env;
    }
    /* cli_light_project applies the file's rotation and intensity; the viewer's own rotation
     * is applied by the worker on top. */
    v->sh = sh;
    view_request_relight(v);
}
static void screenshot(viewer *v)
{
    char path[64];
    snprintf(path, sizeof path, "prt-screenshot-%d.png", ++v->screenshots);
    if (view_screenshot(v, path)) cli_error(v->c, "screenshot failed: %s", prt_last_error());
    else if (!v->c->quiet) fprintf(stderr, "prt view: wrote %s\n", path);
}

static const view_control core[] = {
    {PRT_KEY_ESCAPE, "escape", "quit", quit},
    {'Q', "q", "quit", quit},
    {'H', "h", "show or hide this help", toggle_help},
    {'I', "i", "show or hide the status line", toggle_hud},
    {'=', "+", "exposure +1/2 stop", brighter},
    {'-', "-", "exposure -1/2 stop", darker},
    {'T', "t", "tone mapping: Reinhard / clamp", cycle_tonemap},
    {'0', "0", "reset camera and lighting rotation", reset_view},
    {'L', "l", "reload the environment probe", reload_probe},
    {'P', "p", "screenshot (prt-screenshot-N.png)", screenshot},
};

void view_register_core(viewer *v) { view_register(v, core, (int)(sizeof core / sizeof core[0])); }

/* ---- spherical-harmonic PRT ---- */
static void next_kind(viewer *v)
{
    for (int step = 1; step <= 5; ++step) {
        int i = 0;
        while ((1u << i) != (unsigned)v->want.kind) ++i;
        prt_transfer_kind k = (prt_transfer_kind)(1u << ((i + step) % 5));
        if (prt_transfer_channels(v->t, k)) {
            v->want.kind = k;
            break;
        }
    }
    view_request_relight(v);
}
static void order_down(viewer *v)
{
    if (v->want.order > 1) v->want.order--;
    view_request_relight(v);
}
static void order_up(viewer *v)
{
    prt_transfer_info info;
    prt_transfer_get_info(v->t, &info);
    if (v->want.order < info.order) v->want.order++;
    view_request_relight(v);
}
static void next_component(viewer *v)
{
    /* Direct and indirect are separable when the file holds shadowed and inter-reflected sets. */
    bool split = prt_transfer_channels(v->t, PRT_TRANSFER_SHADOWED) && prt_transfer_channels(v->t, PRT_TRANSFER_INTERREFLECTED);
    v->want.component = split ? (v->want.component + 1) % 3 : 0;
    view_request_relight(v);
}

static const view_control sh[] = {
    {'K', "k", "next transfer kind (unshadowed, shadowed, inter-reflected, glossy ones)", next_kind},
    {'[', "[", "SH order -1", order_down},
    {']', "]", "SH order +1", order_up},
    {'D', "d", "full / direct only / indirect only", next_component},
};

void view_register_sh(viewer *v) { view_register(v, sh, (int)(sizeof sh / sizeof sh[0])); }

/* ---- wavelet PRT ---- */
static void fewer_light_coefficients(viewer *v)
{
    if (v->want.light_coefficients > 64) v->want.light_coefficients /= 2;
    view_request_relight(v);
}
static void more_light_coefficients(viewer *v)
{
    if (v->want.light_coefficients < PRT_WAVELET_DIM) v->want.light_coefficients = v->want.light_coefficients * 2 > PRT_WAVELET_DIM ? PRT_WAVELET_DIM : v->want.light_coefficients * 2;
    view_request_relight(v);
}

static const view_control wavelet[] = {
    {'[', "[", "keep half the lighting's Haar coefficients", fewer_light_coefficients},
    {']', "]", "keep twice the lighting's Haar coefficients", more_light_coefficients},
};

void view_register_wavelet(viewer *v) { view_register(v, wavelet, (int)(sizeof wavelet / sizeof wavelet[0])); }
