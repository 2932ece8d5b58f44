/* The viewer's painting of first-order light (the offset paper's toolbox, prt/paint.h): a brush
 * dabbed where a ray from the eye through the cursor meets the surface, the painting relit with
 * the lamps by the worker (so a stroke costs what moving a light costs), saved as an image that
 * prt render --paint takes. The viewer never names the method: files whose method takes no
 * painting refuse with the library's reason. */
#include "view.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const float palette[][3] = {{1, 1, 1}, {1, 0.75f, 0.45f}, {1, 0.2f, 0.1f}, {0.2f, 1, 0.25f}, {0.2f, 0.35f, 1}, {1, 0.9f, 0.2f}, {0.8f, 0.3f, 1}};
static const char *const palette_names[] = {"white", "warm", "red", "green", "blue", "yellow", "violet"};
#define PALETTE (int)(sizeof palette / sizeof palette[0])

/* The painter and the painting, made on first use; false (message set) when the file takes none. */
static bool ready(viewer *v)
{
    if (v->painter) return true;
    int w, h;
    if (prt_paint_size(v->t, &w, &h) || prt_painter_create(v->c->ctx, v->t, &v->painter)) {
        snprintf(v->message, sizeof v->message, "%s", prt_last_error());
        return false;
    }
    if (!v->paint) {
        float *p = calloc((size_t)w * h * 3, sizeof *p), *jp = calloc((size_t)w * h * 3, sizeof *jp);
        if (!p || !jp) {
            free(p);
            free(jp);
            prt_painter_release(v->painter);
            v->painter = NULL;
            snprintf(v->message, sizeof v->message, "out of memory");
            return false;
        }
        pthread_mutex_lock(&v->lock);
        v->paint = p;
        v->job_paint = jp;
        v->paint_w = w;
        v->paint_h = h;
        pthread_mutex_unlock(&v->lock);
    }
    return true;
}

/* The brush starts at 3% of the scene (known once the window is up) and light 2. */
static void brush_defaults(viewer *v)
{
    if (!(v->brush_radius > 0)) v->brush_radius = 0.03f * (v->scene_size > 0 ? v->scene_size : 1.0f);
    if (!(v->brush_light > 0)) v->brush_light = 2.0f;
}

/* The ray from the eye through window pixel (x, y), as prt_render projects (side by side: each
 * half its own view). */
static void pixel_ray(const viewer *v, double x, double y, float eye[3], float dir[3])
{
    prt_camera cam;
    view_camera(v, &cam);
    int w, h;
    prt_window_size(v->win, &w, &h);
    double x0 = 0, width = w;
    if (v->side_by_side && v->shown.gpu_input) {
        const int half = w / 2;
        x0 = x < half ? 0 : half;
        width = x < half ? half : w - half;
    }
    float f[3], s[3], u[3], up[3] = {cam.up[0], cam.up[1], cam.up[2]};
    if (up[0] == 0 && up[1] == 0 && up[2] == 0) up[1] = 1;
    for (int k = 0; k < 3; ++k) f[k] = cam.target[k] - cam.eye[k];
    float fl = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int k = 0; k < 3; ++k) f[k] /= fl > 0 ? fl : 1;
    s[0] = f[1] * up[2] - f[2] * up[1]; s[1] = f[2] * up[0] - f[0] * up[2]; s[2] = f[0] * up[1] - f[1] * up[0];
    float sl = sqrtf(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    if (!(sl > 0)) { s[0] = f[1]; s[1] = -f[0]; s[2] = 0; sl = sqrtf(s[0] * s[0] + s[1] * s[1]); }   /* looking straight up or down */
    for (int k = 0; k < 3; ++k) s[k] /= sl > 0 ? sl : 1;
    u[0] = s[1] * f[2] - s[2] * f[1]; u[1] = s[2] * f[0] - s[0] * f[2]; u[2] = s[0] * f[1] - s[1] * f[0];
    const float th = tanf(0.5f * (cam.fov_y_deg > 0 ? cam.fov_y_deg : 40.0f) * 3.14159265f / 180.0f), aspect = (float)(width / h);
    const float px = (float)(2.0 * (x - x0) / width - 1.0) * th * aspect, py = (float)(1.0 - 2.0 * y / h) * th;
    for (int k = 0; k < 3; ++k) {
        eye[k] = cam.eye[k];
        dir[k] = f[k] + px * s[k] + py * u[k];
    }
}

bool view_paint_at(viewer *v, double x, double y, float radius, const float rgb[3])
{
    if (!ready(v)) return false;
    float eye[3], dir[3], hit[3], n[3];
    pixel_ray(v, x, y, eye, dir);
    if (!prt_painter_pick(v->painter, eye, dir, hit, n)) {
        snprintf(v->message, sizeof v->message, "nothing under pixel %.0f, %.0f to paint", x, y);
        return false;
    }
    prt_paint_brush b = {{hit[0], hit[1], hit[2]}, {n[0], n[1], n[2]}, radius, {rgb[0], rgb[1], rgb[2]}, 1.0f};
    int changed = 0;
    pthread_mutex_lock(&v->lock);   /* the worker copies the painting under the lock */
    prt_status st = prt_painter_dab(v->painter, &b, v->paint, &changed);
    pthread_mutex_unlock(&v->lock);
    if (st) { snprintf(v->message, sizeof v->message, "%s", prt_last_error()); return false; }
    if (!changed) {
        snprintf(v->message, sizeof v->message, "the brush (radius %.3g) covers no texel at %.3g, %.3g, %.3g: make it larger (wheel)", (double)radius,
                 (double)hit[0], (double)hit[1], (double)hit[2]);
        return false;
    }
    v->want.painted = true;
    view_request_relight(v);
    return true;
}

bool view_paint_stroke(viewer *v, double x, double y, bool erase)
{
    if (!ready(v)) return false;
    brush_defaults(v);
    float rgb[3] = {0, 0, 0};
    for (int k = 0; k < 3 && !erase; ++k) rgb[k] = palette[v->brush_colour][k] * v->brush_light;
    return view_paint_at(v, x, y, v->brush_radius, rgb);
}

bool view_paint_clear(viewer *v)
{
    if (!ready(v)) return false;
    pthread_mutex_lock(&v->lock);
    memset(v->paint, 0, (size_t)v->paint_w * v->paint_h * 3 * sizeof *v->paint);
    pthread_mutex_unlock(&v->lock);
    v->want.painted = false;
    view_request_relight(v);
    return true;
}

bool view_paint_save(viewer *v, const char *path)
{
    if (!ready(v)) return false;
    if (prt_paint_save(path, v->paint, v->paint_w, v->paint_h)) {
        snprintf(v->message, sizeof v->message, "saving the painting failed: %s", prt_last_error());
        return false;
    }
    snprintf(v->message, sizeof v->message, "wrote %s (prt render FILE.prt --paint %s renders it)", path, path);
    return true;
}

bool view_paint_load(viewer *v, const char *path)
{
    if (!ready(v)) return false;
    float *map = NULL;
    if (prt_paint_load(v->t, path, &map)) { snprintf(v->message, sizeof v->message, "%s", prt_last_error()); return false; }
    pthread_mutex_lock(&v->lock);
    memcpy(v->paint, map, (size_t)v->paint_w * v->paint_h * 3 * sizeof *map);
    memcpy(v->job_paint, map, (size_t)v->paint_w * v->paint_h * 3 * sizeof *map);   /* for a relight before the worker runs */
    pthread_mutex_unlock(&v->lock);
    free(map);
    v->want.painted = true;
    return true;
}

bool view_paint_key(viewer *v, int key)
{
    if (!v->paint_mode || (key != ',' && key != '.')) return false;
    v->brush_light *= key == '.' ? 1.25f : 0.8f;
    v->message[0] = 0;
    v->dirty = true;
    return true;
}

void view_paint_resize(viewer *v, float steps)
{
    v->brush_radius *= powf(1.1f, steps);
    v->dirty = true;
}

void view_paint_status(const viewer *v, char *buf, size_t n)
{
    if (!v->paint_mode) { buf[0] = 0; return; }
    const float *c = palette[v->brush_colour];
    snprintf(buf, n, "paint: brush radius %.3g, %s light %.2f (%.2f, %.2f, %.2f): drag paints, right-drag erases, wheel sizes, , . dim/brighten, "
                     "u colour, v clear, y save, o leaves",
             (double)v->brush_radius, palette_names[v->brush_colour], (double)v->brush_light, (double)(c[0] * v->brush_light),
             (double)(c[1] * v->brush_light), (double)(c[2] * v->brush_light));
}

void view_paint_free(viewer *v)
{
    prt_painter_release(v->painter);
    free(v->paint);
    free(v->job_paint);
    v->painter = NULL;
    v->paint = v->job_paint = NULL;
}

/* ---- keys ---- */
static void toggle_paint(viewer *v, int arg)
{
    (void)arg;
    if (!v->paint_mode && !ready(v)) return;
    brush_defaults(v);
    v->paint_mode = !v->paint_mode;
    if (!v->paint_mode) snprintf(v->message, sizeof v->message, "orbit mode");
}
static void next_colour(viewer *v, int arg)
{
    (void)arg;
    v->brush_colour = (v->brush_colour + 1) % PALETTE;
    snprintf(v->message, sizeof v->message, "brush: %s", palette_names[v->brush_colour]);
}
static void clear_key(viewer *v, int arg) { (void)arg; if (view_paint_clear(v)) snprintf(v->message, sizeof v->message, "painting cleared"); }
static void save_key(viewer *v, int arg)
{
    (void)arg;
    char path[64];
    snprintf(path, sizeof path, "prt-paint-%d.exr", ++v->paintings);
    if (view_paint_save(v, path) && !v->c->quiet) fprintf(stderr, "prt view: %s\n", v->message);
}

static const view_control paint_keys[] = {
    {'O', "o", "paint mode: drag paints first-order light, right-drag erases, wheel sizes the brush, , . dim/brighten it", toggle_paint, 0},
    {'U', "u", "paint mode: the brush's next colour", next_colour, 0},
    {'V', "v", "clear the painted light", clear_key, 0},
    {'Y', "y", "save the painted light (prt-paint-N.exr, for prt render --paint)", save_key, 0},
};

void view_register_paint(viewer *v)
{
    if (prt_method_paintable(prt_transfer_method(v->t))) view_register(v, paint_keys, (int)(sizeof paint_keys / sizeof paint_keys[0]));
}
