/* The headless target: an EGL context without a window (Mesa's surfaceless platform, which
 * runs on llvmpipe where there is no GPU) and a multisampled float framebuffer. */
#include "render/draw.h"
#include "render/volumes.h"

#include <epoxy/egl.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

struct prt_renderer {
    const prt_context *ctx;   /* its cancel hook stops a big image between bands */
    EGLDisplay dpy;
    EGLContext egl;
    prt__target target;
    prt__draw draw;
    char name[256];
    int volume_slices;
};

/* EGL hands every caller the same display, and eglTerminate ends every context on it, so the
 * display stays initialised while any renderer holds it: releasing one renderer must not pull the
 * context from under another. */
static pthread_mutex_t display_lock = PTHREAD_MUTEX_INITIALIZER;
static EGLDisplay shared_display = EGL_NO_DISPLAY;
static int display_users;

static EGLDisplay initialise_display(void)
{
    /* Surfaceless needs no X server or DRM device; fall back to the default display. */
    if (epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
        if (d != EGL_NO_DISPLAY && eglInitialize(d, NULL, NULL)) return d;
    }
    EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (d != EGL_NO_DISPLAY && eglInitialize(d, NULL, NULL)) return d;
    return EGL_NO_DISPLAY;
}

static EGLDisplay open_display(void)
{
    pthread_mutex_lock(&display_lock);
    if (display_users == 0) shared_display = initialise_display();
    EGLDisplay d = shared_display;
    if (d != EGL_NO_DISPLAY) display_users++;
    pthread_mutex_unlock(&display_lock);
    return d;
}

static void close_display(void)
{
    pthread_mutex_lock(&display_lock);
    if (display_users > 0 && --display_users == 0) {
        eglTerminate(shared_display);
        shared_display = EGL_NO_DISPLAY;
    }
    pthread_mutex_unlock(&display_lock);
}

prt_status prt_renderer_create(prt_context *ctx, const prt_renderer_desc *desc, prt_renderer **out)
{
    prt_renderer_desc d = desc ? *desc : (prt_renderer_desc){0};
    *out = NULL;
    if (d.width == 0) d.width = 800;
    if (d.height == 0) d.height = 600;
    if (d.samples == 0) d.samples = 4;
    if (d.width < 1 || d.height < 1 || d.width > 16384 || d.height > 16384 || d.samples < 1 || d.samples > 16)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "image size %dx%d or samples %d out of range", d.width, d.height, d.samples);
    prt_renderer *r = prt__calloc(1, sizeof *r);
    if (!r) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    r->ctx = ctx;
    r->dpy = open_display();
    if (r->dpy == EGL_NO_DISPLAY) { free(r); return prt__fail(ctx, PRT_ERR_BACKEND, "no EGL display (is Mesa's libegl-mesa0 installed?)"); }
    /* Surface type 0: the context renders only into framebuffer objects, never a window. */
    const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig cfg;
    EGLint ncfg = 0;
    if (!eglBindAPI(EGL_OPENGL_API) || !eglChooseConfig(r->dpy, cfg_attr, &cfg, 1, &ncfg) || ncfg < 1) {
        close_display(); free(r);
        return prt__fail(ctx, PRT_ERR_BACKEND, "EGL has no desktop OpenGL config");
    }
    const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                               EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    r->egl = eglCreateContext(r->dpy, cfg, EGL_NO_CONTEXT, ctx_attr);
    if (r->egl == EGL_NO_CONTEXT || !eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, r->egl)) {
        const EGLint error = eglGetError();   /* before the calls below set their own */
        if (r->egl != EGL_NO_CONTEXT) eglDestroyContext(r->dpy, r->egl);
        close_display(); free(r);
        return prt__fail(ctx, PRT_ERR_BACKEND, "cannot create a surfaceless OpenGL 3.3 core context (EGL error 0x%x)", error);
    }
    snprintf(r->name, sizeof r->name, "%s", (const char *)glGetString(GL_RENDERER));
    prt_status st = prt__draw_init(&r->draw);
    if (st) { prt_renderer_release(r); return prt__fail(ctx, st, "%s", prt_last_error()); }
    r->draw.ctx = ctx;

    st = prt__target_init(&r->target, d.width, d.height, d.samples);
    if (st) { prt_renderer_release(r); return prt__fail(ctx, st, "%s", prt_last_error()); }
    *out = r;
    return PRT_OK;
}

void prt_renderer_release(prt_renderer *r)
{
    if (!r) return;
    if (r->egl) {
        eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, r->egl);
        prt__draw_free(&r->draw);
        prt__target_free(&r->target);
        eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(r->dpy, r->egl);
    }
    if (r->dpy != EGL_NO_DISPLAY) close_display();
    eglReleaseThread();   /* frees the per-thread state EGL keeps for the calling thread */
    free(r);
}

const char *prt_renderer_name(const prt_renderer *r) { return r->name; }

prt_status prt_render_light_map(prt_renderer *r, const prt_render_mesh *mesh, float *rgb, float *first_rgb)
{
    if (!r || !mesh || !rgb || !mesh->positions || !mesh->radiance || !mesh->indices)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render_light_map: renderer, mesh arrays and output are required");
    eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, r->egl);
    prt_status st = prt__draw_upload(&r->draw, mesh);
    if (st) return st;
    if (!r->draw.texel_width) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render_light_map: the mesh draws no per-texel map");
    if (first_rgb && !mesh->gpu_passes) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render_light_map: a first-order map comes only from GPU accumulation");
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glBindTexture(GL_TEXTURE_2D, r->draw.tex);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGB, GL_FLOAT, rgb);
    if (first_rgb) {
        glBindTexture(GL_TEXTURE_2D, r->draw.tex_first);
        glGetTexImage(GL_TEXTURE_2D, 0, GL_RGB, GL_FLOAT, first_rgb);
    }
    glBindTexture(GL_TEXTURE_2D, 0);
    return PRT_OK;
}

void prt_renderer_set_volume_slices(prt_renderer *r, int on)
{
    if (r) r->volume_slices = on != 0;
}

prt_status prt_render_vertex_radiance(prt_renderer *r, const prt_render_mesh *mesh, float *rgb)
{
    if (!r || !mesh || !rgb || !mesh->positions || !mesh->radiance || !mesh->indices)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render_vertex_radiance: renderer, mesh arrays and output are required");
    eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, r->egl);
    prt_status st = prt__draw_upload(&r->draw, mesh);
    if (st) return st;
    glBindBuffer(GL_ARRAY_BUFFER, r->draw.vbo_rad);
    glGetBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)(mesh->vertex_count * 3 * sizeof(float)), rgb);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    return PRT_OK;
}

int prt_render_sums_on_gpu(const prt_renderer *r) { return r ? r->draw.sums.on_gpu : -1; }

void prt_renderer_limit_buffer_texels(prt_renderer *r, size_t texels)
{
    r->draw.sums.max_texels = texels;
    r->draw.sums.id = 0;   /* the next description is checked against the new limit */
}

prt_status prt_render(prt_renderer *r, const prt_render_mesh *mesh, const prt_camera *cam, const float background[3], prt_image *out)
{
    memset(out, 0, sizeof *out);
    if (!mesh || !cam || !mesh->positions || !mesh->radiance || !mesh->indices)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render: mesh arrays and camera are required");
    if (mesh->triangle_count * 3 > (size_t)INT32_MAX) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh too large to draw");
    eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, r->egl);
    /* Media are ray-marched on the CPU below (exact per pixel), not drawn as the window's slices,
     * unless the caller asks for the slices (prt_renderer_set_volume_slices: what the viewer shows). */
    prt_render_mesh surfaces = *mesh;
    if (!r->volume_slices) { surfaces.volumes = NULL; surfaces.volume_count = 0; }
    prt_status st = prt__draw_upload(&r->draw, &surfaces);
    if (st) return st;
    if (!prt__target_draw_cancellable(&r->target, &r->draw, cam, background, r->ctx)) return prt__fail(r->ctx, PRT_ERR_CANCELLED, "drawing cancelled");
    st = prt__target_read(&r->target, out);
    if (!st && mesh->volume_count && !r->volume_slices) st = prt__render_volumes(r->ctx, mesh, cam, out);
    return st;
}
