/* The window target: GLFW for the window and input, the shared drawing code for the scene, then
 * a full-screen pass that tone-maps the float image for display, then the text overlay. */
#include "render/draw.h"

#include <GLFW/glfw3.h>
#include <string.h>

#include <stb/stb_easy_font.h>

#define QUEUE 256

struct prt_window {
    GLFWwindow *win;
    prt__draw draw;
    prt__target target;
    int samples;
    GLuint tm_program, tm_vao, text_program, text_vao, text_vbo, text_ibo;
    GLint tm_exposure, tm_mode, text_screen;
    prt_event queue[QUEUE];
    int head, count;
    /* An upload that failed (GPU accumulation the GPU cannot run): reported by the next draw. */
    prt_status upload_status;
    char upload_error[256];
};

static void uploaded(prt_window *w, prt_status st)
{
    if (!st || w->upload_status) return;
    w->upload_status = st;
    snprintf(w->upload_error, sizeof w->upload_error, "%s", prt_last_error());
}

static _Thread_local char glfw_message[512];
static void on_glfw_error(int code, const char *msg) { snprintf(glfw_message, sizeof glfw_message, "%s (GLFW error 0x%x)", msg, code); }

static void push(prt_window *w, prt_event ev)
{
    if (w->count == QUEUE) return;   /* a stalled consumer loses the oldest input rather than memory */
    w->queue[(w->head + w->count) % QUEUE] = ev;
    w->count++;
}

static int mods_of(int m) { return (m & GLFW_MOD_SHIFT ? PRT_MOD_SHIFT : 0) | (m & GLFW_MOD_CONTROL ? PRT_MOD_CTRL : 0) | (m & GLFW_MOD_ALT ? PRT_MOD_ALT : 0); }

static void on_key(GLFWwindow *g, int key, int sc, int action, int m)
{
    (void)sc;
    push(glfwGetWindowUserPointer(g), (prt_event){PRT_EVENT_KEY, key, 0, action, mods_of(m), 0, 0});
}
/* Cursor positions in framebuffer pixels, the image's (they differ from the window's screen
 * coordinates on high-density displays), so that a position picks what is drawn there. */
static void to_pixels(GLFWwindow *g, double *x, double *y)
{
    int ww, wh, fw, fh;
    glfwGetWindowSize(g, &ww, &wh);
    glfwGetFramebufferSize(g, &fw, &fh);
    if (ww > 0 && wh > 0) { *x *= (double)fw / ww; *y *= (double)fh / wh; }
}
static void on_button(GLFWwindow *g, int button, int action, int m)
{
    double x, y;
    glfwGetCursorPos(g, &x, &y);
    to_pixels(g, &x, &y);
    push(glfwGetWindowUserPointer(g), (prt_event){PRT_EVENT_BUTTON, 0, button, action, mods_of(m), x, y});
}
static void on_move(GLFWwindow *g, double x, double y)
{
    to_pixels(g, &x, &y);
    push(glfwGetWindowUserPointer(g), (prt_event){PRT_EVENT_MOVE, 0, 0, 0, 0, x, y});
}
static void on_scroll(GLFWwindow *g, double dx, double dy) { (void)dx; push(glfwGetWindowUserPointer(g), (prt_event){PRT_EVENT_SCROLL, 0, 0, 0, 0, 0, dy}); }
static void on_close(GLFWwindow *g) { push(glfwGetWindowUserPointer(g), (prt_event){PRT_EVENT_CLOSE, 0, 0, 0, 0, 0, 0}); }

static GLuint program(const char *vs_src, const char *fs_src)
{
    GLuint vs = glCreateShader(GL_VERTEX_SHADER), fs = glCreateShader(GL_FRAGMENT_SHADER), p = glCreateProgram();
    glShaderSource(vs, 1, &vs_src, NULL);
    glShaderSource(fs, 1, &fs_src, NULL);
    glCompileShader(vs);
    glCompileShader(fs);
    glAttachShader(p, vs);
    glAttachShader(p, fs);
    glLinkProgram(p);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) { glDeleteProgram(p); return 0; }
    return p;
}

/* The same curve as prt_image_save's PNG path: exposure, Reinhard on luminance (or clamp), sRGB. */
static const char *TM_VS =
    "#version 330 core\n"
    "out vec2 uv;\n"
    "void main() { vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2); uv = p; gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }\n";
static const char *TM_FS =
    "#version 330 core\n"
    "in vec2 uv;\n"
    "uniform sampler2D image;\n"
    "uniform float exposure;\n"
    "uniform int mode;\n"
    "out vec4 color;\n"
    "float srgb(float c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055; }\n"
    "void main() {\n"
    "  vec3 c = texture(image, uv).rgb * exposure;\n"
    "  if (mode != 2) { float lum = dot(c, vec3(0.2126, 0.7152, 0.0722)); c *= lum > 0.0 ? 1.0 / (1.0 + lum) : 1.0; }\n"
    "  c = clamp(c, 0.0, 1.0);\n"
    "  color = vec4(srgb(c.r), srgb(c.g), srgb(c.b), 1.0);\n"
    "}\n";
static const char *TEXT_VS =
    "#version 330 core\n"
    "layout(location = 0) in vec3 pos;\n"
    "layout(location = 1) in vec4 col;\n"
    "uniform vec2 screen;\n"
    "out vec4 c;\n"
    "void main() { c = col; gl_Position = vec4(pos.x / screen.x * 2.0 - 1.0, 1.0 - pos.y / screen.y * 2.0, 0.0, 1.0); }\n";
static const char *TEXT_FS =
    "#version 330 core\nin vec4 c;\nout vec4 color;\nvoid main() { color = c; }\n";

prt_status prt_window_create(prt_context *ctx, const prt_window_desc *desc, prt_window **out)
{
    prt_window_desc d = desc ? *desc : (prt_window_desc){0};
    *out = NULL;
    if (d.width == 0) d.width = 1024;
    if (d.height == 0) d.height = 768;
    if (d.samples == 0) d.samples = 4;
    if (d.width < 1 || d.height < 1 || d.width > 16384 || d.height > 16384 || d.samples < 1 || d.samples > 16)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "window size %dx%d or samples %d out of range", d.width, d.height, d.samples);
    glfw_message[0] = 0;
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit())
        return prt__fail(ctx, PRT_ERR_BACKEND, "cannot open a window: %s (is there a display? set DISPLAY, or run under xvfb-run)",
                         glfw_message[0] ? glfw_message : "GLFW failed to start");
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);   /* the float target has the window's size */
    prt_window *w = prt__calloc(1, sizeof *w);
    if (!w) { glfwTerminate(); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    w->samples = d.samples;
    w->win = glfwCreateWindow(d.width, d.height, d.title ? d.title : "prt", NULL, NULL);
    if (!w->win) {
        free(w);
        glfwTerminate();
        return prt__fail(ctx, PRT_ERR_BACKEND, "cannot create an OpenGL 3.3 core window: %s", glfw_message);
    }
    glfwSetWindowUserPointer(w->win, w);
    glfwSetKeyCallback(w->win, on_key);
    glfwSetMouseButtonCallback(w->win, on_button);
    glfwSetCursorPosCallback(w->win, on_move);
    glfwSetScrollCallback(w->win, on_scroll);
    glfwSetWindowCloseCallback(w->win, on_close);
    glfwMakeContextCurrent(w->win);
    glfwSwapInterval(0);   /* measure frames, do not wait for vertical sync */
    int fw, fh;
    glfwGetFramebufferSize(w->win, &fw, &fh);
    prt_status st = prt__draw_init(&w->draw);
    w->draw.ctx = ctx;
    if (!st) st = prt__target_init(&w->target, fw, fh, d.samples);
    w->tm_program = st ? 0 : program(TM_VS, TM_FS);
    w->text_program = st ? 0 : program(TEXT_VS, TEXT_FS);
    if (!st && (!w->tm_program || !w->text_program)) st = prt__fail(NULL, PRT_ERR_BACKEND, "window shaders failed to build");
    if (st) { prt_window_release(w); return prt__fail(ctx, st, "%s", prt_last_error()); }
    w->tm_exposure = glGetUniformLocation(w->tm_program, "exposure");
    w->tm_mode = glGetUniformLocation(w->tm_program, "mode");
    w->text_screen = glGetUniformLocation(w->text_program, "screen");
    glGenVertexArrays(1, &w->tm_vao);
    glGenVertexArrays(1, &w->text_vao);
    glGenBuffers(1, &w->text_vbo);
    glGenBuffers(1, &w->text_ibo);
    *out = w;
    return PRT_OK;
}

void prt_window_release(prt_window *w)
{
    if (!w) return;
    if (w->win) {
        glfwMakeContextCurrent(w->win);
        prt__draw_free(&w->draw);
        prt__target_free(&w->target);
        if (w->tm_program) glDeleteProgram(w->tm_program);
        if (w->text_program) glDeleteProgram(w->text_program);
        GLuint vaos[2] = {w->tm_vao, w->text_vao}, bufs[2] = {w->text_vbo, w->text_ibo};
        glDeleteVertexArrays(2, vaos);
        glDeleteBuffers(2, bufs);
        glfwDestroyWindow(w->win);
    }
    glfwTerminate();
    free(w);
}

int prt_window_next_event(prt_window *w, prt_event *ev)
{
    if (!w->count) glfwPollEvents();
    if (!w->count) return 0;
    *ev = w->queue[w->head];
    w->head = (w->head + 1) % QUEUE;
    w->count--;
    return 1;
}

void prt_window_wait(prt_window *w, double timeout)
{
    if (!w->count) glfwWaitEventsTimeout(timeout);
}

void prt_window_set_mesh(prt_window *w, const prt_render_mesh *mesh)
{
    glfwMakeContextCurrent(w->win);
    uploaded(w, prt__draw_upload(&w->draw, mesh));
}

void prt_window_set_gpu_input(prt_window *w, const prt_render_mesh *mesh)
{
    glfwMakeContextCurrent(w->win);
    uploaded(w, prt__draw_upload_gpu(&w->draw, mesh));
}

void prt_window_set_gpu_sums(prt_window *w, const prt_render_mesh *mesh)
{
    glfwMakeContextCurrent(w->win);
    uploaded(w, prt__draw_upload_sums(&w->draw, mesh));
}

void prt_window_set_lights(prt_window *w, const prt_render_mesh *mesh)
{
    glfwMakeContextCurrent(w->win);
    prt__draw_set_lights(&w->draw, mesh);
}

void prt_window_set_volumes(prt_window *w, const prt_render_mesh *mesh)
{
    glfwMakeContextCurrent(w->win);
    prt__volume_gl_upload(&w->draw.volumes, mesh->volumes, mesh->volumes ? mesh->volume_count : 0);
}

void prt_window_set_radiance(prt_window *w, const float *rgb, size_t nv)
{
    glfwMakeContextCurrent(w->win);
    glBindBuffer(GL_ARRAY_BUFFER, w->draw.vbo_rad);
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)(nv * 3 * sizeof(float)), rgb);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void prt_window_set_texels(prt_window *w, const float *rgb, int width, int height)
{
    glfwMakeContextCurrent(w->win);
    prt__draw_upload_texels(&w->draw, rgb, width, height);
}

void prt_window_set_exit(prt_window *w, const float *exit_sh, size_t nv)
{
    glfwMakeContextCurrent(w->win);
    prt__draw_upload_exit(&w->draw, exit_sh, nv);
}

void prt_window_set_kvec(prt_window *w, const float *kvec, size_t nv)
{
    glfwMakeContextCurrent(w->win);
    prt__draw_upload_kvec(&w->draw, kvec, nv);
}

static void draw_text(prt_window *w, const char *text, int fw, int fh)
{
    static char quads[1 << 20];   /* stb_easy_font: 4 vertices of 16 bytes per quad; room for a full help page */
    float scale = 1.5f;
    int nq = stb_easy_font_print(0, 0, (char *)text, NULL, quads, sizeof quads);
    if (nq <= 0) return;
    float *v = (float *)quads;
    /* Scale, offset, and a dark shadow quad set under the text for legibility. */
    size_t nv = (size_t)nq * 4;
    const size_t quads_all = 1 + (size_t)nq * 2;   /* a backing panel, then shadow and text */
    float *buf = malloc(quads_all * 4 * 7 * sizeof(float));
    uint32_t *idx = malloc(quads_all * 6 * sizeof(uint32_t));
    if (!buf || !idx) { free(buf); free(idx); return; }
    /* The panel: the text's box and a margin, dark and translucent, so text reads over any scene. */
    float x1 = 0, y1 = 0;
    for (size_t i = 0; i < nv; ++i) { x1 = fmaxf(x1, v[i * 4]); y1 = fmaxf(y1, v[i * 4 + 1]); }
    const float px[4] = {2, 14 + x1 * scale, 14 + x1 * scale, 2}, py[4] = {2, 2, 14 + y1 * scale, 14 + y1 * scale};
    for (int k = 0; k < 4; ++k) {
        float *o = buf + (size_t)k * 7;
        o[0] = px[k]; o[1] = py[k]; o[2] = 0;
        o[3] = o[4] = o[5] = 0.02f; o[6] = 0.6f;
    }
    for (int pass = 0; pass < 2; ++pass)
        for (size_t i = 0; i < nv; ++i) {
            float *o = buf + (4 + (size_t)pass * nv + i) * 7;
            float off = pass == 0 ? 1.0f : 0.0f;
            o[0] = 8 + v[i * 4] * scale + off; o[1] = 8 + v[i * 4 + 1] * scale + off; o[2] = 0;
            o[3] = o[4] = o[5] = pass == 0 ? 0.0f : 1.0f; o[6] = 1.0f;
        }
    for (size_t q = 0; q < quads_all; ++q) {
        uint32_t b = (uint32_t)(q * 4), t[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
        memcpy(idx + q * 6, t, sizeof t);
    }
    glUseProgram(w->text_program);
    glUniform2f(w->text_screen, (float)fw, (float)fh);
    glBindVertexArray(w->text_vao);
    glBindBuffer(GL_ARRAY_BUFFER, w->text_vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(quads_all * 4 * 7 * sizeof(float)), buf, GL_STREAM_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 7 * sizeof(float), NULL);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, 7 * sizeof(float), (void *)(3 * sizeof(float)));
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, w->text_ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(quads_all * 6 * sizeof(uint32_t)), idx, GL_STREAM_DRAW);
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDrawElements(GL_TRIANGLES, (GLsizei)(quads_all * 6), GL_UNSIGNED_INT, NULL);
    glDisable(GL_BLEND);
    glBindVertexArray(0);
    free(buf);
    free(idx);
}

prt_status prt_window_draw(prt_window *w, const prt_camera *cam, const float background[3], float exposure_stops, int tonemap,
                           const char *overlay)
{
    glfwMakeContextCurrent(w->win);
    if (w->upload_status) {
        const prt_status st = w->upload_status;
        w->upload_status = PRT_OK;
        return prt__fail(NULL, st, "%s", w->upload_error);
    }
    int fw = w->target.width, fh = w->target.height;
    prt__target_draw(&w->target, &w->draw, cam, background);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fw, fh);
    glDisable(GL_DEPTH_TEST);
    glUseProgram(w->tm_program);
    glUniform1f(w->tm_exposure, exp2f(exposure_stops));
    glUniform1i(w->tm_mode, tonemap);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, w->target.color_tex);
    glBindVertexArray(w->tm_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    if (overlay && overlay[0]) draw_text(w, overlay, fw, fh);
    glfwSwapBuffers(w->win);
    GLenum err = glGetError();
    return err == GL_NO_ERROR ? PRT_OK : prt__fail(NULL, PRT_ERR_BACKEND, "OpenGL error 0x%x while drawing the window", err);
}

prt_status prt_window_read(prt_window *w, prt_image *out)
{
    glfwMakeContextCurrent(w->win);
    return prt__target_read(&w->target, out);
}

void prt_window_size(const prt_window *w, int *width, int *height)
{
    *width = w->target.width;
    *height = w->target.height;
}
