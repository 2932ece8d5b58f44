/* The headless target: an EGL context without a window (Mesa's surfaceless platform, which
 * runs on llvmpipe where there is no GPU) and a multisampled float framebuffer. */
#include "render/draw.h"

#include <epoxy/egl.h>
#include <stdio.h>
#include <string.h>

struct prt_renderer {
    EGLDisplay dpy;
    EGLContext egl;
    int width, height, samples;
    GLuint fbo_ms, color_ms, depth_ms, fbo, color;
    prt__draw draw;
    char name[256];
};

static EGLDisplay open_display(void)
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
    r->width = d.width; r->height = d.height; r->samples = d.samples;
    r->dpy = open_display();
    if (r->dpy == EGL_NO_DISPLAY) { free(r); return prt__fail(ctx, PRT_ERR_BACKEND, "no EGL display (is Mesa's libegl-mesa0 installed?)"); }
    /* Surface type 0: the context renders only into framebuffer objects, never a window. */
    const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig cfg;
    EGLint ncfg = 0;
    if (!eglBindAPI(EGL_OPENGL_API) || !eglChooseConfig(r->dpy, cfg_attr, &cfg, 1, &ncfg) || ncfg < 1) {
        eglTerminate(r->dpy); free(r);
        return prt__fail(ctx, PRT_ERR_BACKEND, "EGL has no desktop OpenGL config");
    }
    const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                               EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    r->egl = eglCreateContext(r->dpy, cfg, EGL_NO_CONTEXT, ctx_attr);
    if (r->egl == EGL_NO_CONTEXT || !eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, r->egl)) {
        if (r->egl != EGL_NO_CONTEXT) eglDestroyContext(r->dpy, r->egl);
        eglTerminate(r->dpy); free(r);
        return prt__fail(ctx, PRT_ERR_BACKEND, "cannot create a surfaceless OpenGL 3.3 core context (EGL error 0x%x)", eglGetError());
    }
    snprintf(r->name, sizeof r->name, "%s", (const char *)glGetString(GL_RENDERER));
    prt_status st = prt__draw_init(&r->draw);
    if (st) { prt_renderer_release(r); return prt__fail(ctx, st, "%s", prt_last_error()); }

    glGenFramebuffers(1, &r->fbo_ms);
    glGenRenderbuffers(1, &r->color_ms);
    glGenRenderbuffers(1, &r->depth_ms);
    glBindRenderbuffer(GL_RENDERBUFFER, r->color_ms);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, r->samples, GL_RGBA32F, r->width, r->height);
    glBindRenderbuffer(GL_RENDERBUFFER, r->depth_ms);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, r->samples, GL_DEPTH_COMPONENT24, r->width, r->height);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_ms);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, r->color_ms);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, r->depth_ms);
    GLenum ms_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glGenFramebuffers(1, &r->fbo);
    glGenRenderbuffers(1, &r->color);
    glBindRenderbuffer(GL_RENDERBUFFER, r->color);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, r->width, r->height);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, r->color);
    if (ms_status != GL_FRAMEBUFFER_COMPLETE || glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        prt_renderer_release(r);
        return prt__fail(ctx, PRT_ERR_BACKEND, "float framebuffer is not supported by this OpenGL driver");
    }
    *out = r;
    return PRT_OK;
}

void prt_renderer_release(prt_renderer *r)
{
    if (!r) return;
    if (r->egl) {
        eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, r->egl);
        prt__draw_free(&r->draw);
        GLuint fbos[2] = {r->fbo_ms, r->fbo}, rbs[3] = {r->color_ms, r->depth_ms, r->color};
        glDeleteFramebuffers(2, fbos);
        glDeleteRenderbuffers(3, rbs);
        eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(r->dpy, r->egl);
    }
    if (r->dpy != EGL_NO_DISPLAY) eglTerminate(r->dpy);
    eglReleaseThread();   /* frees the per-thread state EGL keeps for the calling thread */
    free(r);
}

const char *prt_renderer_name(const prt_renderer *r) { return r->name; }

prt_status prt_render(prt_renderer *r, const prt_render_mesh *mesh, const prt_camera *cam, const float background[3], prt_image *out)
{
    memset(out, 0, sizeof *out);
    if (!mesh || !cam || !mesh->positions || !mesh->radiance || !mesh->indices)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render: mesh arrays and camera are required");
    if (mesh->triangle_count * 3 > (size_t)INT32_MAX) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh too large to draw");
    eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, r->egl);
    prt__draw_upload(&r->draw, mesh);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_ms);
    prt__draw_mesh(&r->draw, cam, r->width, r->height, background);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, r->fbo_ms);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, r->fbo);
    glBlitFramebuffer(0, 0, r->width, r->height, 0, 0, r->width, r->height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, r->fbo);
    size_t n = (size_t)r->width * r->height;
    float *rgba = malloc(n * 4 * sizeof(float));
    out->rgb = malloc(n * 3 * sizeof(float));
    if (!rgba || !out->rgb) { free(rgba); free(out->rgb); out->rgb = NULL; return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, r->width, r->height, GL_RGBA, GL_FLOAT, rgba);
    GLenum err = glGetError();
    out->width = r->width;
    out->height = r->height;
    for (int y = 0; y < r->height; ++y)   /* GL's rows run bottom-up; prt images top-down */
        for (int x = 0; x < r->width; ++x)
            for (int c = 0; c < 3; ++c)
                out->rgb[((size_t)y * r->width + x) * 3 + c] = rgba[((size_t)(r->height - 1 - y) * r->width + x) * 4 + c];
    free(rgba);
    if (err != GL_NO_ERROR) { prt_image_free(out); return prt__fail(NULL, PRT_ERR_BACKEND, "OpenGL error 0x%x while drawing", err); }
    return PRT_OK;
}
