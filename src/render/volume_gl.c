/* Participating media in OpenGL: per volume four 3D textures (the source's band 0 and the
 * extinction; the source's band 1 as a gradient per colour) and a stack of slices across the axis
 * of the box nearest the view direction, drawn back to front over the surfaces with the depth
 * test on (slices behind a surface are hidden: depth-correct) and premultiplied blending:
 *     dst = (1 - e) S(d) + e dst,   e = exp(-sigma_t slab / |d . axis|),
 * the same emission-absorption step as the CPU's ray march, one slab per half voxel. */
#include "render/volume_gl.h"
#include "render/draw.h"

#include <stdlib.h>
#include <string.h>

static const char *VS_V =
    "#version 330 core\n"
    "uniform mat4 mvp; uniform vec3 lo, hi; uniform int axis, count, reverse;\n"
    "out vec3 world;\n"
    "void main() {\n"
    "  int i = reverse != 0 ? count - 1 - gl_InstanceID : gl_InstanceID;\n"
    "  vec2 c = vec2(gl_VertexID & 1, gl_VertexID >> 1);\n"
    "  float t = (float(i) + 0.5) / float(count);\n"
    "  vec3 f = axis == 0 ? vec3(t, c.x, c.y) : axis == 1 ? vec3(c.x, t, c.y) : vec3(c.x, c.y, t);\n"
    "  world = lo + (hi - lo) * f;\n"
    "  gl_Position = mvp * vec4(world, 1.0);\n"
    "}\n";

static const char *FS_V =
    "#version 330 core\n"
    "uniform vec3 lo, hi, eye; uniform int axis, count, bands;\n"
    "uniform sampler3D t0, t1, t2, t3;\n"
    "in vec3 world; out vec4 frag;\n"
    "void main() {\n"
    "  vec3 uvw = (world - lo) / (hi - lo);\n"
    "  vec4 a = texture(t0, uvw);\n"
    "  vec3 d = normalize(world - eye);\n"
    "  vec3 S = a.rgb;\n"
    "  if (bands > 1) S += texture(t1, uvw).rgb * d.x + texture(t2, uvw).rgb * d.y + texture(t3, uvw).rgb * d.z;\n"
    "  float slab = (hi[axis] - lo[axis]) / float(count);\n"
    "  float e = exp(-a.a * slab / max(abs(d[axis]), 1e-3));\n"
    "  frag = vec4(max(S, vec3(0.0)) * (1.0 - e), 1.0 - e);\n"
    "}\n";

prt_status prt__volume_gl_init(prt__volume_gl *g)
{
    memset(g, 0, sizeof *g);
    g->program = prt__gl_program(VS_V, NULL, FS_V);
    if (!g->program) return PRT_ERR_BACKEND;
    glGenVertexArrays(1, &g->vao);
    g->u_mvp = glGetUniformLocation(g->program, "mvp");
    g->u_lo = glGetUniformLocation(g->program, "lo");
    g->u_hi = glGetUniformLocation(g->program, "hi");
    g->u_axis = glGetUniformLocation(g->program, "axis");
    g->u_count = glGetUniformLocation(g->program, "count");
    g->u_reverse = glGetUniformLocation(g->program, "reverse");
    g->u_eye = glGetUniformLocation(g->program, "eye");
    g->u_bands = glGetUniformLocation(g->program, "bands");
    static const char *names[4] = {"t0", "t1", "t2", "t3"};
    for (int k = 0; k < 4; ++k) g->u_tex[k] = glGetUniformLocation(g->program, names[k]);
    return PRT_OK;
}

static void drop(prt__volume_gl *g)
{
    for (int q = 0; q < g->count; ++q) glDeleteTextures(4, g->v[q].tex);
    g->count = 0;
}

void prt__volume_gl_free(prt__volume_gl *g)
{
    drop(g);
    if (g->program) glDeleteProgram(g->program);
    if (g->vao) glDeleteVertexArrays(1, &g->vao);
    memset(g, 0, sizeof *g);
}

void prt__volume_gl_upload(prt__volume_gl *g, const prt_render_volume *v, int count)
{
    drop(g);
    if (!g->program) return;
    /* y_1,-1 = c y, y_1,0 = c z, y_1,1 = c x (prt_sh_eval's band 1), y_0 = 1 / sqrt(4 pi). */
    const float y0 = 0.282094792f, c1 = 0.488602512f;
    for (int q = 0; q < count && q < PRT__GL_VOLUMES; ++q) {
        const size_t n = (size_t)v[q].dims[0] * v[q].dims[1] * v[q].dims[2];
        const int rows = v[q].source_order * v[q].source_order;
        float *t = malloc(n * 4 * 4 * sizeof *t);
        if (!t) break;
        for (size_t k = 0; k < n; ++k) {
            const float *s = v[q].source + k * 3 * (size_t)rows;
            for (int c = 0; c < 3; ++c) {
                t[k * 4 + c] = s[c * rows] * y0;
                for (int a = 0; a < 3; ++a) t[(n * (size_t)(a + 1) + k) * 4 + c] = 0;
                if (rows >= 4) {
                    t[(n * 1 + k) * 4 + c] = c1 * s[c * rows + 3];
                    t[(n * 2 + k) * 4 + c] = c1 * s[c * rows + 1];
                    t[(n * 3 + k) * 4 + c] = c1 * s[c * rows + 2];
                }
            }
            t[k * 4 + 3] = v[q].extinction[k];
            for (int a = 1; a < 4; ++a) t[(n * (size_t)a + k) * 4 + 3] = 0;
        }
        glGenTextures(4, g->v[q].tex);
        for (int a = 0; a < 4; ++a) {
            glBindTexture(GL_TEXTURE_3D, g->v[q].tex[a]);
            glTexImage3D(GL_TEXTURE_3D, 0, GL_RGBA32F, v[q].dims[0], v[q].dims[1], v[q].dims[2], 0, GL_RGBA, GL_FLOAT, t + n * 4 * (size_t)a);
            glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
            glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
        }
        glBindTexture(GL_TEXTURE_3D, 0);
        free(t);
        memcpy(g->v[q].dims, v[q].dims, sizeof g->v[q].dims);
        memcpy(g->v[q].lo, v[q].lo, sizeof g->v[q].lo);
        memcpy(g->v[q].hi, v[q].hi, sizeof g->v[q].hi);
        g->v[q].bands = v[q].source_order;
        g->count = q + 1;
    }
}

void prt__volume_gl_draw(prt__volume_gl *g, const float mvp[16], const float eye[3])
{
    if (!g->count) return;
    glUseProgram(g->program);
    glUniformMatrix4fv(g->u_mvp, 1, GL_FALSE, mvp);
    glUniform3fv(g->u_eye, 1, eye);
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE);
    glDepthMask(GL_FALSE);
    glBindVertexArray(g->vao);
    for (int q = 0; q < g->count; ++q) {
        float centre[3], dir[3];
        for (int c = 0; c < 3; ++c) { centre[c] = 0.5f * (g->v[q].lo[c] + g->v[q].hi[c]); dir[c] = centre[c] - eye[c]; }
        int axis = 0;
        for (int c = 1; c < 3; ++c)
            if (fabsf(dir[c]) > fabsf(dir[axis])) axis = c;
        const int count = 2 * g->v[q].dims[axis];
        glUniform3fv(g->u_lo, 1, g->v[q].lo);
        glUniform3fv(g->u_hi, 1, g->v[q].hi);
        glUniform1i(g->u_axis, axis);
        glUniform1i(g->u_count, count);
        glUniform1i(g->u_reverse, dir[axis] > 0);   /* back to front: from the far side of the box */
        glUniform1i(g->u_bands, g->v[q].bands);
        for (int a = 0; a < 4; ++a) {
            glActiveTexture(GL_TEXTURE0 + (GLenum)a);
            glBindTexture(GL_TEXTURE_3D, g->v[q].tex[a]);
            glUniform1i(g->u_tex[a], a);
        }
        glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, count);
    }
    glBindVertexArray(0);
    glActiveTexture(GL_TEXTURE0);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
}
