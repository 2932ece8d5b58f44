/* The viewer's key bindings, one table per concern: core (camera, display, files), the
 * method's run-time controls as the method table declares them, and light editing for the
 * light types the method relights. The viewer never switches on the method. */
#include "view.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
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
    /* Fly mode takes W A S D E Z for moving, ahead of their usual bindings. */
    if (v->fly && (key == 'W' || key == 'A' || key == 'S' || key == 'D' || key == 'E' || key == 'Z')) {
        v->message[0] = 0;
        view_fly(v, key == 'W' ? 1.0f : key == 'S' ? -1.0f : 0.0f, key == 'D' ? 1.0f : key == 'A' ? -1.0f : 0.0f,
                 key == 'E' ? 1.0f : key == 'Z' ? -1.0f : 0.0f);
        return;
    }
    if (view_paint_key(v, key)) return;   /* paint mode takes , and . for the brush */
    for (int i = 0; i < v->ncontrols; ++i)
        if (v->controls[i].key == key) {
            v->message[0] = 0;
            v->controls[i].fn(v, v->controls[i].arg);
            v->dirty = true;
            return;
        }
}

/* ---- core ---- */
static void quit(viewer *v, int arg) { (void)arg; v->quit = true; }
static void toggle_help(viewer *v, int arg) { (void)arg; v->help = !v->help; }
static void toggle_hud(viewer *v, int arg) { (void)arg; v->hud = !v->hud; }
static void toggle_fly(viewer *v, int arg)
{
    (void)arg;
    v->fly = !v->fly;
    snprintf(v->message, sizeof v->message, "%s", v->fly ? "fly mode: w a s d move, e z rise and sink, drag looks around (f leaves)" : "orbit mode");
}
/* w s e z outside fly mode (in it, view_press moves before the tables are looked at). */
static void fly_key(viewer *v, int arg)
{
    (void)arg;
    snprintf(v->message, sizeof v->message, "w a s d e z move in fly mode: press f first");
}
static void exposure(viewer *v, int arg) { v->exposure += 0.5f * (float)arg; }
static void cycle_tonemap(viewer *v, int arg) { (void)arg; v->tonemap = v->tonemap == 2 ? 1 : 2; }
static void reset_view(viewer *v, int arg)
{
    (void)arg;
    v->moved = false;
    v->want.env_yaw = v->want.env_pitch = 0;
    view_request_relight(v);
}
static void reload_probe(viewer *v, int arg)
{
    (void)arg;
    prt_lighting *l = NULL;
    if (cli_lighting(v->c, &v->light, v->t, NULL, &l)) {
        snprintf(v->message, sizeof v->message, "reload failed: %s", prt_last_error());
        return;
    }
    /* The worker reads the lighting: swap it while the worker is idle. */
    view_sync(v);
    prt_lighting_release(v->lighting);
    v->lighting = l;
    view_take_lights(v);
    view_request_relight(v);
}
static void screenshot(viewer *v, int arg)
{
    (void)arg;
    char path[64];
    snprintf(path, sizeof path, "prt-screenshot-%d.png", ++v->screenshots);
    if (view_screenshot(v, path)) snprintf(v->message, sizeof v->message, "screenshot failed: %s", prt_last_error());
    else if (!v->c->quiet) fprintf(stderr, "prt view: wrote %s\n", path);
}
static void next_variant(viewer *v, int arg)
{
    (void)arg;
    v->want.variant = (v->want.variant + 1) % prt_transfer_variant_count(v->t);
    view_request_relight(v);
}
static void next_component(viewer *v, int arg)
{
    (void)arg;
    v->want.component = (v->want.component + 1) % 3;   /* a method that cannot separate them says so */
    view_request_relight(v);
}

static void toggle_gpu(viewer *v, int arg)
{
    (void)arg;
    if (!prt_method_gpu_passes(prt_transfer_method(v->t))) {
        snprintf(v->message, sizeof v->message, "method %s has no GPU passes", prt_method_name(prt_transfer_method(v->t)));
        return;
    }
    v->want.gpu = !v->want.gpu;
    snprintf(v->message, sizeof v->message, "transfer passes on the %s%s", v->want.gpu ? "GPU" : "CPU",
             !v->want.gpu && v->side_by_side ? " (side by side needs the GPU's: off)" : "");
    if (!v->want.gpu) v->side_by_side = false;
    view_request_relight(v);
}
static void toggle_side_by_side(viewer *v, int arg)
{
    (void)arg;
    if (!prt_method_gpu_passes(prt_transfer_method(v->t))) {
        snprintf(v->message, sizeof v->message, "side by side shows the first-order light of methods with GPU passes");
        return;
    }
    v->side_by_side = !v->side_by_side;
    v->message[0] = 0;
    if (v->side_by_side && !v->want.gpu) {   /* the GPU passes make both maps */
        v->want.gpu = true;
        snprintf(v->message, sizeof v->message, "side by side: transfer passes on the GPU");
    }
    view_request_relight(v);
}

static const view_control core[] = {
    {PRT_KEY_ESCAPE, "escape", "quit", quit, 0},
    {'Q', "q", "quit", quit, 0},
    {'H', "h", "show or hide this help", toggle_help, 0},
    {'I', "i", "show or hide the status line", toggle_hud, 0},
    {'F', "f", "fly mode: w a s d move, e z rise and sink, drag looks around", toggle_fly, 0},
    {'W', "w", "fly mode: forward", fly_key, 0},
    {'S', "s", "fly mode: back", fly_key, 0},
    {'E', "e", "fly mode: rise", fly_key, 0},
    {'Z', "z", "fly mode: sink", fly_key, 0},
    {'=', "+", "exposure +1/2 stop", exposure, 1},
    {'-', "-", "exposure -1/2 stop", exposure, -1},
    {'T', "t", "tone mapping: Reinhard / clamp", cycle_tonemap, 0},
    {'0', "0", "reset camera and lighting rotation", reset_view, 0},
    {'L', "l", "reload the lighting (probe and lights) from disk", reload_probe, 0},
    {'P', "p", "screenshot (prt-screenshot-N.png)", screenshot, 0},
    {'K', "k", "relight the file as its next kind (prt info lists them)", next_variant, 0},
    {'D', "d", "full / direct only / indirect only", next_component, 0},
    {'G', "g", "the method's GPU passes on the GPU / the CPU (where it has them)", toggle_gpu, 0},
    {'B', "b", "first-order and final light side by side (with the GPU passes)", toggle_side_by_side, 0},
};

void view_register_core(viewer *v) { view_register(v, core, (int)(sizeof core / sizeof core[0])); }

/* ---- the method's controls ---- */
static void control_step(viewer *v, int arg)
{
    const int i = (arg < 0 ? -arg : arg) - 1;
    const prt_control_desc *cd;
    prt_transfer_controls(v->t, &cd);
    int lo, hi, value = v->want.controls[i];
    prt_transfer_control_range(v->t, i, &lo, &hi, NULL);
    if (cd[i].multiplicative) value = arg < 0 ? value / 2 : value * 2;
    else value += arg < 0 ? -1 : 1;
    v->want.controls[i] = value < lo ? lo : value > hi ? hi : value;
    view_request_relight(v);
}

void view_register_method(viewer *v)
{
    static char help[PRT_MAX_CONTROLS][2][96];
    static char names[PRT_MAX_CONTROLS][2][4];
    const prt_control_desc *cd;
    const int n = prt_transfer_controls(v->t, &cd);
    for (int i = 0; i < n && i < PRT_MAX_CONTROLS; ++i)
        for (int up = 0; up < 2; ++up) {
            const int key = up ? cd[i].key_up : cd[i].key_down;
            snprintf(names[i][up], sizeof names[i][up], "%c", (char)(key >= 'A' && key <= 'Z' ? key - 'A' + 'a' : key));
            snprintf(help[i][up], sizeof help[i][up], "%s %s: %s", cd[i].name, cd[i].multiplicative ? (up ? "x2" : "/2") : (up ? "+1" : "-1"), cd[i].help);
            view_control c = {key, names[i][up], help[i][up], control_step, up ? i + 1 : -(i + 1)};
            view_register(v, &c, 1);
        }
}

/* ---- lights ---- */
unsigned view_light_types(const viewer *v)
{
    return prt_method_lighting(prt_transfer_method(v->t)) & (PRT_LIGHTS_POINT | PRT_LIGHTS_SPOT | PRT_LIGHTS_DIRECTIONAL | PRT_LIGHTS_SPHERE);
}

static void scene_frame(const viewer *v, float centre[3], float *size)
{
    const float *p = prt_transfer_positions(v->t);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < prt_transfer_vertex_count(v->t) * 3; ++i) {
        lo[i % 3] = fminf(lo[i % 3], p[i]);
        hi[i % 3] = fmaxf(hi[i % 3], p[i]);
    }
    *size = 0;
    for (int k = 0; k < 3; ++k) {
        centre[k] = 0.5f * (lo[k] + hi[k]);
        *size = fmaxf(*size, hi[k] - lo[k]);
    }
}

bool view_light_add(viewer *v, prt_light_type type, const float *position)
{
    if (prt_method_check_lighting(prt_transfer_method(v->t), prt_light_type_bit(type))) {
        snprintf(v->message, sizeof v->message, "%s", prt_last_error());
        return false;
    }
    if (v->want.light_count == CLI_MAX_LIGHTS) { snprintf(v->message, sizeof v->message, "at most %d lights", CLI_MAX_LIGHTS); return false; }
    float centre[3], size;
    scene_frame(v, centre, &size);
    prt_light l;
    memset(&l, 0, sizeof l);
    l.type = type;
    /* A new light sits above the scene's centre, aimed at it, bright enough to see at once. */
    const float above[3] = {centre[0], centre[1] + 0.75f * size, centre[2]};
    memcpy(l.position, position ? position : above, sizeof l.position);
    const float d[3] = {0.3f, 0.9f, 0.3f};
    if (type == PRT_LIGHT_DIRECTIONAL) {
        memcpy(l.direction, d, sizeof d);
        l.irradiance[0] = l.irradiance[1] = l.irradiance[2] = 3.0f;
    } else if (type == PRT_LIGHT_SPHERE) {
        l.radius = 0.05f * size;
        l.radiance[0] = l.radiance[1] = l.radiance[2] = 20.0f;
    } else {
        for (int k = 0; k < 3; ++k) l.direction[k] = centre[k] - l.position[k];
        l.intensity[0] = l.intensity[1] = l.intensity[2] = size * size;
        l.angle_deg = type == PRT_LIGHT_SPOT ? 30.0f : 0.0f;
    }
    if (prt_light_validate(&l)) { snprintf(v->message, sizeof v->message, "%s", prt_last_error()); return false; }
    v->want.lights[v->want.light_count] = l;
    v->selected = v->want.light_count++;
    view_request_relight(v);
    return true;
}

bool view_light_select(viewer *v, int index)
{
    if (index < 0 || index >= v->want.light_count) {
        snprintf(v->message, sizeof v->message, "no light %d (there %s %d)", index + 1, v->want.light_count == 1 ? "is" : "are", v->want.light_count);
        return false;
    }
    v->selected = index;
    return true;
}

static prt_light *selected(viewer *v)
{
    if (v->selected < 0 || v->selected >= v->want.light_count) {
        snprintf(v->message, sizeof v->message, "no light selected (n adds one, tab selects)");
        return NULL;
    }
    return &v->want.lights[v->selected];
}

bool view_light_remove(viewer *v)
{
    if (!selected(v)) return false;
    memmove(&v->want.lights[v->selected], &v->want.lights[v->selected + 1], (size_t)(v->want.light_count - v->selected - 1) * sizeof(prt_light));
    v->want.light_count--;
    if (v->selected >= v->want.light_count) v->selected = v->want.light_count - 1;
    view_request_relight(v);
    return true;
}

bool view_light_move(viewer *v, float dx, float dy, float dz)
{
    prt_light *l = v->want.probe ? NULL : selected(v);
    if (!l && !v->want.probe) return false;
    prt_camera cam;
    view_camera(v, &cam);
    float f[3] = {cam.target[0] - cam.eye[0], cam.target[1] - cam.eye[1], cam.target[2] - cam.eye[2]}, up[3] = {0, 1, 0}, r[3], u[3];
    float fl = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int k = 0; k < 3; ++k) f[k] /= fl > 0 ? fl : 1;
    r[0] = f[1] * up[2] - f[2] * up[1]; r[1] = f[2] * up[0] - f[0] * up[2]; r[2] = f[0] * up[1] - f[1] * up[0];
    float rl = sqrtf(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int k = 0; k < 3; ++k) r[k] /= rl > 0 ? rl : 1;
    u[0] = r[1] * f[2] - r[2] * f[1]; u[1] = r[2] * f[0] - r[0] * f[2]; u[2] = r[0] * f[1] - r[1] * f[0];
    if (v->want.probe) {   /* the probe, while shown, is what alt+drag moves */
        for (int k = 0; k < 3; ++k) v->want.probe_at[k] += dx * r[k] + dy * u[k] + dz * f[k];
        snprintf(v->message, sizeof v->message, "probe at %.3g, %.3g, %.3g", v->want.probe_at[0], v->want.probe_at[1], v->want.probe_at[2]);
        view_request_relight(v);
        return true;
    }
    prt_light moved = *l;
    if (l->type == PRT_LIGHT_DIRECTIONAL) {
        /* Turn the direction: dx about the view's up, dy about its right (degrees). */
        float a = dx * 3.14159265f / 180.0f * 20.0f, b = dy * 3.14159265f / 180.0f * 20.0f, *d = moved.direction;
        for (int k = 0; k < 3; ++k) d[k] += a * r[k] + b * u[k];
    } else {
        for (int k = 0; k < 3; ++k) moved.position[k] += dx * r[k] + dy * u[k] + dz * f[k];
    }
    if (prt_light_validate(&moved)) { snprintf(v->message, sizeof v->message, "%s", prt_last_error()); return false; }
    *l = moved;
    view_request_relight(v);
    return true;
}

static float *colour_of(prt_light *l)
{
    return l->type == PRT_LIGHT_DIRECTIONAL ? l->irradiance : l->type == PRT_LIGHT_SPHERE ? l->radiance : l->intensity;
}

bool view_light_scale(viewer *v, float factor)
{
    prt_light *l = selected(v);
    if (!l || !(factor >= 0) || !isfinite(factor)) return false;
    float *c = colour_of(l);
    for (int k = 0; k < 3; ++k) c[k] *= factor;
    view_request_relight(v);
    return true;
}

bool view_light_colour(viewer *v, const float rgb[3])
{
    prt_light *l = selected(v);
    if (!l) return false;
    for (int k = 0; k < 3; ++k)
        if (!(rgb[k] >= 0) || !isfinite(rgb[k])) { snprintf(v->message, sizeof v->message, "a light's colour is three numbers >= 0"); return false; }
    /* Keep the power, change the hue: the new colour is scaled to the old luminance. */
    float *c = colour_of(l);
    const float old = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2], neu = 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
    for (int k = 0; k < 3; ++k) c[k] = neu > 0 && old > 0 ? rgb[k] * old / neu : rgb[k];
    view_request_relight(v);
    return true;
}

static void add_light(viewer *v, int arg)
{
    (void)arg;
    /* The first type the method relights, in the order users reach for them. */
    static const prt_light_type order[] = {PRT_LIGHT_POINT, PRT_LIGHT_SPOT, PRT_LIGHT_SPHERE, PRT_LIGHT_DIRECTIONAL};
    for (size_t i = 0; i < sizeof order / sizeof order[0]; ++i)
        if (view_light_types(v) & prt_light_type_bit(order[i])) { view_light_add(v, order[i], NULL); return; }
}
static void next_light(viewer *v, int arg)
{
    (void)arg;
    if (v->want.light_count) v->selected = (v->selected + 1) % v->want.light_count;
    else snprintf(v->message, sizeof v->message, "no lights (n adds one)");
}
static void remove_light(viewer *v, int arg) { (void)arg; view_light_remove(v); }
static void scale_light(viewer *v, int arg) { view_light_scale(v, arg > 0 ? 1.25f : 0.8f); }
static void recolour_light(viewer *v, int arg)
{
    (void)arg;
    static const float palette[6][3] = {{1, 1, 1}, {1, 0.8f, 0.6f}, {0.6f, 0.8f, 1}, {1, 0.3f, 0.3f}, {0.3f, 1, 0.3f}, {0.3f, 0.3f, 1}};
    static int next;
    view_light_colour(v, palette[next++ % 6]);
}

static const view_control lights[] = {
    {'N', "n", "add a light", add_light, 0},
    {PRT_KEY_TAB, "tab", "select the next light", next_light, 0},
    {'X', "x", "remove the selected light", remove_light, 0},
    {',', ",", "dim the selected light", scale_light, -1},
    {'.', ".", "brighten the selected light", scale_light, 1},
    {'C', "c", "recolour the selected light", recolour_light, 0},
};

void view_register_lights(viewer *v)
{
    if (view_light_types(v)) view_register(v, lights, (int)(sizeof lights / sizeof lights[0]));
}

/* ---- surface colours (methods that change albedo at run time) ---- */
static bool surfaces_editable(viewer *v)
{
    if (prt_method_runtime_albedo(prt_transfer_method(v->t)) && prt_transfer_surface_count(v->t)) return true;
    const char *why = prt_method_baked_albedo_why(prt_transfer_method(v->t));
    if (!prt_transfer_surface_count(v->t)) snprintf(v->message, sizeof v->message, "the file names no surfaces");
    else snprintf(v->message, sizeof v->message, "this method bakes colours in%s%s: changing them needs a rebake", why ? ": " : "", why ? why : "");
    return false;
}

bool view_surface_next(viewer *v)
{
    if (!surfaces_editable(v)) return false;
    v->surface = v->surface % prt_transfer_surface_count(v->t) + 1;
    return true;
}

/* Applies rgb to the selected surface; the worker reads the albedo, so it waits for the worker. */
static bool paint(viewer *v, const float rgb[3])
{
    if (!surfaces_editable(v)) return false;
    if (!v->surface) { snprintf(v->message, sizeof v->message, "no surface selected (m selects one)"); return false; }
    const size_t nv = prt_transfer_vertex_count(v->t);
    view_sync(v);
    if (!v->albedo) {
        if (!(v->albedo = malloc(nv * 3 * sizeof(float)))) { snprintf(v->message, sizeof v->message, "out of memory"); return false; }
        memcpy(v->albedo, prt_transfer_albedo(v->t), nv * 3 * sizeof(float));
    }
    if (prt_transfer_paint_albedo(v->t, prt_transfer_surface_name(v->t, v->surface), rgb, v->albedo)) {
        snprintf(v->message, sizeof v->message, "%s", prt_last_error());
        return false;
    }
    view_request_relight(v);
    return true;
}

/* The selected surface's albedo now: its first vertex's. */
static bool surface_albedo(const viewer *v, float rgb[3])
{
    const uint16_t *s = prt_transfer_surfaces(v->t);
    const float *a = v->albedo ? v->albedo : prt_transfer_albedo(v->t);
    for (size_t i = 0; s && i < prt_transfer_vertex_count(v->t); ++i)
        if (s[i] == v->surface) { memcpy(rgb, a + i * 3, 3 * sizeof(float)); return true; }
    return false;
}

bool view_surface_albedo(viewer *v, const float rgb[3])
{
    for (int k = 0; k < 3; ++k)
        if (!(rgb[k] >= 0.0f && rgb[k] <= 1.0f)) { snprintf(v->message, sizeof v->message, "an albedo is three numbers in [0, 1]"); return false; }
    return paint(v, rgb);
}

bool view_surface_scale(viewer *v, float factor)
{
    float rgb[3];
    if (!surfaces_editable(v)) return false;
    if (!v->surface || !surface_albedo(v, rgb)) { snprintf(v->message, sizeof v->message, "no surface selected (m selects one)"); return false; }
    for (int k = 0; k < 3; ++k) rgb[k] = fminf(1.0f, rgb[k] * factor);
    return paint(v, rgb);
}

bool view_surface_next_brdf(viewer *v)
{
    if (!surfaces_editable(v)) return false;
    if (!v->surface) { snprintf(v->message, sizeof v->message, "no surface selected (m selects one)"); return false; }
    const char *name = prt_transfer_surface_name(v->t, v->surface);
    const int n = prt_transfer_brdf_set(v->t, v->surface, -1, NULL);
    if (n < 2) {
        snprintf(v->message, sizeof v->message, "%s has no BRDF set to switch among (a material's \"brdfs\" in the scene it was baked from)", name);
        return false;
    }
    const int ns = prt_transfer_surface_count(v->t);
    if (!v->brdf_of) {
        if (!(v->brdf_of = malloc(((size_t)ns + 1) * sizeof *v->brdf_of))) { snprintf(v->message, sizeof v->message, "out of memory"); return false; }
        for (int k = 0; k <= ns; ++k) v->brdf_of[k] = -1;
    }
    /* The surface's baked BRDF is the first of its set. */
    const int next = ((v->brdf_of[v->surface] < 0 ? 0 : v->brdf_of[v->surface]) + 1) % n;
    prt_brdf b;
    prt_transfer_brdf_set(v->t, v->surface, next, &b);
    float rgb[3];
    prt_brdf_lambert_albedo(&b, rgb);
    view_sync(v);   /* the worker reads brdf_of */
    v->brdf_of[v->surface] = next;
    if (!paint(v, rgb)) return false;   /* its diffuse part is the colour; relights */
    char spec[128];
    prt_brdf_format(&b, spec, sizeof spec);
    snprintf(v->message, sizeof v->message, "%s: %s (%d of %d)", name, spec, next + 1, n);
    return true;
}

static void next_surface(viewer *v, int arg) { (void)arg; view_surface_next(v); }
static void next_brdf(viewer *v, int arg) { (void)arg; view_surface_next_brdf(v); }
static void recolour_surface(viewer *v, int arg)
{
    (void)arg;
    static const float palette[6][3] = {{0.8f, 0.8f, 0.8f}, {0.8f, 0.15f, 0.1f}, {0.15f, 0.6f, 0.15f}, {0.15f, 0.25f, 0.8f}, {0.85f, 0.75f, 0.2f}, {0.3f, 0.3f, 0.3f}};
    static int next;
    view_surface_albedo(v, palette[next++ % 6]);
}
static void scale_surface(viewer *v, int arg) { view_surface_scale(v, arg > 0 ? 1.25f : 0.8f); }

static const view_control surfaces[] = {
    {'M', "m", "select the next named surface", next_surface, 0},
    {'A', "a", "recolour the selected surface (albedo, no rebake)", recolour_surface, 0},
    {';', ";", "darken the selected surface", scale_surface, -1},
    {'\'', "'", "lighten the selected surface", scale_surface, 1},
    {'R', "r", "the selected surface's next BRDF of the set baked for it", next_brdf, 0},
};

void view_register_surfaces(viewer *v)
{
    if (prt_method_runtime_albedo(prt_transfer_method(v->t)) && prt_transfer_surface_count(v->t))
        view_register(v, surfaces, (int)(sizeof surfaces / sizeof surfaces[0]));
}

/* ---- the probe (neighbourhood transfer) ---- */
static void toggle_probe(viewer *v, int arg)
{
    (void)arg;
    if (!prt_transfer_light_at_box(v->t, NULL, NULL)) {
        snprintf(v->message, sizeof v->message, "no neighbourhood transfer in this file: bake it with --neighbourhood N (SH)");
        return;
    }
    v->want.probe = !v->want.probe;
    if (v->want.probe) {
        prt_camera cam;
        view_camera(v, &cam);
        memcpy(v->want.probe_at, cam.target, sizeof v->want.probe_at);
        snprintf(v->message, sizeof v->message, "probe at %.3g, %.3g, %.3g: alt+drag moves it (alt+wheel in depth), j hides it", cam.target[0],
                 cam.target[1], cam.target[2]);
    } else {
        snprintf(v->message, sizeof v->message, "probe hidden");
    }
    view_request_relight(v);
}

static const view_control probe_keys[] = {
    {'J', "j", "neighbourhood transfer: show or hide a probe sphere lit by the scene (alt+drag moves it)", toggle_probe, 0},
};

void view_register_probe(viewer *v)
{
    if (prt_transfer_light_at_box(v->t, NULL, NULL)) view_register(v, probe_keys, 1);
}

/* ---- key frames: the time moves through the file's poses, a key frame a second ---- */
static void play_pause(viewer *v, int arg)
{
    (void)arg;
    v->playing = !v->playing;
    v->play_clock = -1;   /* view_play starts the clock */
    snprintf(v->message, sizeof v->message, "%s at time %.2f of 0..%d", v->playing ? "playing" : "paused", v->want.time, v->key_frames - 1);
}

static void step_time(viewer *v, int arg)
{
    const double end = v->key_frames - 1;
    v->playing = false;
    v->want.time = fmin(fmax(v->want.time + 0.1 * arg, 0.0), end);
    snprintf(v->message, sizeof v->message, "time %.2f of 0..%d", v->want.time, v->key_frames - 1);
    view_request_relight(v);
}

void view_play(viewer *v, double now_s)
{
    if (!v->playing) return;
    if (v->play_clock < 0) { v->play_clock = now_s; return; }
    /* One relight at a time: a slow relight shows fewer poses, not a growing queue. */
    pthread_mutex_lock(&v->lock);
    const bool busy = v->job_posted || v->result_version != v->want.version;
    pthread_mutex_unlock(&v->lock);
    if (busy) return;
    const double end = v->key_frames - 1;
    v->want.time = fmod(v->want.time + (now_s - v->play_clock), end);
    v->play_clock = now_s;
    view_request_relight(v);
    v->dirty = true;
}

void view_register_frames(viewer *v)
{
    static const view_control table[] = {
        {' ', "space", "key frames: play / pause (a key frame a second, looping)", play_pause, 0},
        {'/', "/", "key frames: a tenth of a frame on", step_time, 1},
        {'\\', "\\", "key frames: a tenth of a frame back", step_time, -1},
    };
    if (v->key_frames > 1) view_register(v, table, (int)(sizeof table / sizeof table[0]));
}
