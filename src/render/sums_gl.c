/* Per-vertex light finished on the GPU: sparse products as transform-feedback passes (GL 3.3
 * core has no compute shaders). Each product is one point per row drawn with the rasterizer off;
 * its vertex shader walks the row's entries in buffer textures and writes the row's sum into a
 * buffer the next product reads as a buffer texture. The course notes' split: the light projected
 * per cluster (or the light vector) on the CPU, the weighted sums per vertex here. */
#include "render/sums_gl.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One product's pass; %s is the body of its map (prt_render_product.map_glsl), "return y;" when
 * it has none. Map arguments a_j read row r times u_n<j> (0 where they have one row). */
static const char *VS_PRODUCT =
    "#version 330 core\n"
    "uniform usamplerBuffer u_start, u_index;\n"
    "uniform samplerBuffer u_weight, u_scale, u_x, u_a0, u_a1, u_a2;\n"
    "uniform int u_has_scale, u_clamp, u_argc, u_n0, u_n1, u_n2;\n"
    "out vec4 y;\n"
    "vec3 map(vec3 y, vec3 a0, vec3 a1, vec3 a2) {\n%s\n}\n"
    "void main() {\n"
    "  int r = gl_VertexID;\n"
    "  int e0 = int(texelFetch(u_start, r).r), e1 = int(texelFetch(u_start, r + 1).r);\n"
    "  vec3 s = vec3(0.0);\n"
    "  for (int e = e0; e < e1; ++e) s += texelFetch(u_weight, e).rgb * texelFetch(u_x, int(texelFetch(u_index, e).r)).rgb;\n"
    "  if (u_clamp != 0) s = max(s, vec3(0.0));\n"
    "  if (u_has_scale != 0) s *= texelFetch(u_scale, r).rgb;\n"
    "  vec3 a0 = u_argc > 0 ? texelFetch(u_a0, r * u_n0).rgb : vec3(0.0);\n"
    "  vec3 a1 = u_argc > 1 ? texelFetch(u_a1, r * u_n1).rgb : vec3(0.0);\n"
    "  vec3 a2 = u_argc > 2 ? texelFetch(u_a2, r * u_n2).rgb : vec3(0.0);\n"
    "  y = vec4(map(s, a0, a1, a2), 0.0);\n"
    "}\n";
/* Radiance (three floats a vertex, read as single floats) plus one shown product. */
static const char *VS_COMBINE =
    "#version 330 core\n"
    "uniform samplerBuffer u_base, u_y;\n"
    "out vec3 rgb;\n"
    "void main() {\n"
    "  int v = gl_VertexID;\n"
    "  vec3 b = vec3(texelFetch(u_base, 3 * v).r, texelFetch(u_base, 3 * v + 1).r, texelFetch(u_base, 3 * v + 2).r);\n"
    "  rgb = b + texelFetch(u_y, v).rgb;\n"
    "}\n";

static GLuint link_tf(const char *src, const char *varying)
{
    GLuint sh = glCreateShader(GL_VERTEX_SHADER);
    glShaderSource(sh, 1, &src, NULL);
    glCompileShader(sh);
    GLint ok = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetShaderInfoLog(sh, sizeof log, NULL, log);
        glDeleteShader(sh);
        prt__fail(NULL, PRT_ERR_BACKEND, "GPU sums shader: %s", log);
        return 0;
    }
    GLuint p = glCreateProgram();
    glAttachShader(p, sh);
    glTransformFeedbackVaryings(p, 1, &varying, GL_INTERLEAVED_ATTRIBS);
    glLinkProgram(p);
    glDeleteShader(sh);
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetProgramInfoLog(p, sizeof log, NULL, log);
        glDeleteProgram(p);
        prt__fail(NULL, PRT_ERR_BACKEND, "GPU sums program: %s", log);
        return 0;
    }
    return p;
}

/* The pass's program for a map body. */
static GLuint link_product(const char *map)
{
    const size_t n = strlen(VS_PRODUCT) + strlen(map) + 1;
    char *src = malloc(n);
    if (!src) { prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); return 0; }
    snprintf(src, n, VS_PRODUCT, map);
    const GLuint p = link_tf(src, "y");
    free(src);
    return p;
}

static void drop_products(prt__sums_gl *g)
{
    for (int k = 0; k < g->count; ++k) {
        prt__sums_product_gl *p = &g->p[k];
        if (p->program) glDeleteProgram(p->program);
        GLuint b[5] = {p->start, p->index, p->weight, p->scale, p->out}, t[5] = {p->t_start, p->t_index, p->t_weight, p->t_scale, p->t_out};
        glDeleteBuffers(5, b);
        glDeleteTextures(5, t);
    }
    free(g->p);
    g->p = NULL;
    g->count = 0;
    g->id = 0;
}

void prt__sums_gl_free(prt__sums_gl *g)
{
    drop_products(g);
    if (g->vector) glDeleteBuffers(1, &g->vector);
    GLuint t[2] = {g->t_vector, g->base_tex};
    glDeleteTextures(2, t);
    if (g->program) glDeleteProgram(g->program);
    if (g->combine) glDeleteProgram(g->combine);
    if (g->vao) glDeleteVertexArrays(1, &g->vao);
    if (g->fbo) glDeleteFramebuffers(1, &g->fbo);
    if (g->rb) glDeleteRenderbuffers(1, &g->rb);
    free(g->pack);
    memset(g, 0, sizeof *g);
}

/* A buffer of `bytes` from data (NULL: uninitialized) viewed as a buffer texture of format fmt. */
static void tbo(GLuint *buf, GLuint *tex, GLenum fmt, size_t bytes, const void *data)
{
    if (!*buf) glGenBuffers(1, buf);
    if (!*tex) glGenTextures(1, tex);
    glBindBuffer(GL_TEXTURE_BUFFER, *buf);
    glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)(bytes ? bytes : 16), data, GL_STATIC_DRAW);
    glBindTexture(GL_TEXTURE_BUFFER, *tex);
    glTexBuffer(GL_TEXTURE_BUFFER, fmt, *buf);
}

/* RGB rows as RGBA (buffer textures of GL 3.3 have no three-channel float format). */
static float *rgba(const float *rgb, size_t n)
{
    float *q = malloc((n ? n : 1) * 4 * sizeof(float));
    if (!q) return NULL;
    for (size_t i = 0; i < n; ++i) {
        memcpy(q + i * 4, rgb + i * 3, 3 * sizeof(float));
        q[i * 4 + 3] = 0;
    }
    return q;
}

/* Uploads the description; false where the GL limits or memory do not allow it (why in `why`). */
static bool load(prt__sums_gl *g, const prt_render_sums *s, size_t vertex_count, char *why, size_t why_size)
{
    GLint max_texels = 0;
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    size_t need = vertex_count * 3 > s->vector_length ? vertex_count * 3 : s->vector_length;
    for (int k = 0; k < s->product_count; ++k) {
        const prt_render_product *p = &s->products[k];
        if (p->rows + 1 > need) need = p->rows + 1;
        if (p->start[p->rows] > need) need = p->start[p->rows];
    }
    if (g->max_texels && g->max_texels < (size_t)max_texels) max_texels = (GLint)g->max_texels;
    if (need > (size_t)max_texels) {
        snprintf(why, why_size, "%zu texels exceed the buffer textures' %d (GL_MAX_TEXTURE_BUFFER_SIZE, or the renderer's limit)", need, max_texels);
        return false;
    }
    if (!(g->p = prt__calloc((size_t)s->product_count, sizeof *g->p))) { snprintf(why, why_size, "out of memory"); return false; }
    g->count = s->product_count;
    while (glGetError() != GL_NO_ERROR) {}
    bool ok = true;
    for (int k = 0; ok && k < s->product_count; ++k) {
        const prt_render_product *p = &s->products[k];
        prt__sums_product_gl *q = &g->p[k];
        const size_t entries = p->start[p->rows];
        float *w = rgba(p->weight, entries), *sc = p->scale ? rgba(p->scale, p->rows) : NULL;
        if (!w || (p->scale && !sc)) { free(w); free(sc); snprintf(why, why_size, "out of memory"); return false; }
        tbo(&q->start, &q->t_start, GL_R32UI, (p->rows + 1) * sizeof(uint32_t), p->start);
        tbo(&q->index, &q->t_index, GL_R32UI, entries * sizeof(uint32_t), p->index);
        tbo(&q->weight, &q->t_weight, GL_RGBA32F, entries * 4 * sizeof(float), w);
        if (sc) tbo(&q->scale, &q->t_scale, GL_RGBA32F, p->rows * 4 * sizeof(float), sc);
        tbo(&q->out, &q->t_out, GL_RGBA32F, p->rows * 4 * sizeof(float), NULL);
        free(w);
        free(sc);
        if (p->map_glsl && !(q->program = link_product(p->map_glsl))) {
            snprintf(why, why_size, "%s", prt_last_error());
            ok = false;
        }
        if (glGetError() == GL_OUT_OF_MEMORY) { snprintf(why, why_size, "the GPU's memory cannot hold them"); ok = false; }
    }
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
    glBindTexture(GL_TEXTURE_BUFFER, 0);
    return ok;
}

static void bind_tex(int unit, GLuint tex, GLint loc)
{
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
    glBindTexture(GL_TEXTURE_BUFFER, tex);
    glUniform1i(loc, unit);
}

prt_status prt__sums_gl_run(prt__sums_gl *g, const prt_context *ctx, const prt_render_mesh *m, GLuint rad, GLuint rad2)
{
    const prt_render_sums *s = m->gpu_sums;
    g->on_gpu = -1;
    if (!s) return PRT_OK;
    if (!m->gpu_vector) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums need their vector");
    const size_t nv = m->vertex_count;
    if (s->id != g->id || !s->id) {
        prt_status st = prt__render_sums_check(s, nv);
        if (st) return st;
        drop_products(g);
        g->cpu = false;
        char why[200] = "";
        if (!g->program) g->program = link_product("return y;");
        if (g->program && !g->combine) g->combine = link_tf(VS_COMBINE, "rgb");
        if (!g->program || !g->combine) {
            snprintf(why, sizeof why, "%s", prt_last_error());
            g->cpu = true;
        } else if (!load(g, s, nv, why, sizeof why)) {
            drop_products(g);
            g->cpu = true;
        }
        if (g->cpu && !g->noted) {
            prt__log(ctx, PRT_LOG_WARN, "per-vertex light summed on the CPU instead of the GPU: %s", why);
            g->noted = true;
        }
        g->id = s->id;
        if (g->program && g->combine) {
            g->c_base = glGetUniformLocation(g->combine, "u_base");
            g->c_y = glGetUniformLocation(g->combine, "u_y");
        }
    }
    if (g->cpu) {
        float *rgb = malloc(nv * 3 * sizeof(float));
        if (!rgb) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(rgb, m->radiance, nv * 3 * sizeof(float));
        prt_status st = prt_render_sums_cpu(s, m->gpu_vector, nv, rgb);
        glBindBuffer(GL_ARRAY_BUFFER, rad);
        if (!st) glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)(nv * 3 * sizeof(float)), rgb);
        glBindBuffer(GL_ARRAY_BUFFER, 0);
        free(rgb);
        g->on_gpu = 0;
        return st;
    }
    /* The frame's vector. */
    if (g->pack_length < s->vector_length || !g->pack) {
        free(g->pack);
        g->pack_length = 0;
        if (!(g->pack = malloc((s->vector_length ? s->vector_length : 1) * 4 * sizeof(float)))) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
        g->pack_length = s->vector_length;
    }
    for (size_t i = 0; i < s->vector_length; ++i) {
        memcpy(g->pack + i * 4, m->gpu_vector + i * 3, 3 * sizeof(float));
        g->pack[i * 4 + 3] = 0;
    }
    tbo(&g->vector, &g->t_vector, GL_RGBA32F, s->vector_length * 4 * sizeof(float), g->pack);
    if (!g->vao) glGenVertexArrays(1, &g->vao);
    glBindVertexArray(g->vao);
    /* Draws need a complete framebuffer even with the rasterizer off, and a surfaceless context
     * has no default one: a 1x1 target of its own. */
    if (!g->fbo) {
        glGenFramebuffers(1, &g->fbo);
        glGenRenderbuffers(1, &g->rb);
        glBindRenderbuffer(GL_RENDERBUFFER, g->rb);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, 1, 1);
        glBindRenderbuffer(GL_RENDERBUFFER, 0);
        glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, g->rb);
    }
    GLint was = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &was);
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
    glEnable(GL_RASTERIZER_DISCARD);
    for (int k = 0; k < g->count; ++k) {
        const prt_render_product *p = &s->products[k];
        const prt__sums_product_gl *q = &g->p[k];
        const GLuint prog = q->program ? q->program : g->program;
        glUseProgram(prog);
        bind_tex(0, q->t_start, glGetUniformLocation(prog, "u_start"));
        bind_tex(1, q->t_index, glGetUniformLocation(prog, "u_index"));
        bind_tex(2, q->t_weight, glGetUniformLocation(prog, "u_weight"));
        bind_tex(3, p->scale ? q->t_scale : q->t_weight, glGetUniformLocation(prog, "u_scale"));
        bind_tex(4, p->input < 0 ? g->t_vector : g->p[p->input].t_out, glGetUniformLocation(prog, "u_x"));
        glUniform1i(glGetUniformLocation(prog, "u_has_scale"), p->scale != NULL);
        glUniform1i(glGetUniformLocation(prog, "u_clamp"), p->clamp != 0);
        const int argc = p->map_glsl ? p->map_argc : 0;
        glUniform1i(glGetUniformLocation(prog, "u_argc"), argc);
        for (int j = 0; j < 3; ++j) {
            static const char *const tex[3] = {"u_a0", "u_a1", "u_a2"}, *const step[3] = {"u_n0", "u_n1", "u_n2"};
            const int a = j < argc ? p->map_args[j] : -1;
            const size_t rows = a < 0 ? s->vector_length : s->products[a].rows;
            bind_tex(5 + j, a < 0 ? g->t_vector : g->p[a].t_out, glGetUniformLocation(prog, tex[j]));
            glUniform1i(glGetUniformLocation(prog, step[j]), rows == 1 ? 0 : 1);
        }
        glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, q->out);
        glBeginTransformFeedback(GL_POINTS);
        glDrawArrays(GL_POINTS, 0, (GLsizei)p->rows);
        glEndTransformFeedback();
    }
    /* Shown rows into the radiance buffer, one product at a time through the scratch buffer. */
    glUseProgram(g->combine);
    if (!g->base_tex) glGenTextures(1, &g->base_tex);
    for (int k = 0; k < g->count; ++k) {
        if (!s->products[k].shown) continue;
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_BUFFER, g->base_tex);
        glTexBuffer(GL_TEXTURE_BUFFER, GL_R32F, rad);
        glUniform1i(g->c_base, 0);
        bind_tex(1, g->p[k].t_out, g->c_y);
        glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, rad2);
        const size_t rows = s->products[k].rows;   /* the first vertices (a probe's sphere may follow) */
        glBeginTransformFeedback(GL_POINTS);
        glDrawArrays(GL_POINTS, 0, (GLsizei)rows);
        glEndTransformFeedback();
        glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
        glBindBuffer(GL_COPY_READ_BUFFER, rad2);
        glBindBuffer(GL_COPY_WRITE_BUFFER, rad);
        if (rows) glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, 0, (GLsizeiptr)(rows * 3 * sizeof(float)));
    }
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
    glDisable(GL_RASTERIZER_DISCARD);
    glBindFramebuffer(GL_FRAMEBUFFER, (GLuint)was);
    glUseProgram(0);
    glBindVertexArray(0);
    for (int u = 0; u < 8; ++u) {
        glActiveTexture(GL_TEXTURE0 + (GLenum)u);
        glBindTexture(GL_TEXTURE_BUFFER, 0);
    }
    glActiveTexture(GL_TEXTURE0);
    g->on_gpu = 1;
    return PRT_OK;
}
