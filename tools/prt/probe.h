/* Probe spheres drawn by prt render --probe, lit by a file's neighbourhood transfer. */
#ifndef PRT_TOOLS_PROBE_H
#define PRT_TOOLS_PROBE_H

#include "cli.h"

#define CLI_MAX_PROBES 8

/* "X,Y,Z" or "X,Y,Z,R" (R > 0; 0 = 3% of the grid's size). */
bool cli_parse_probe(const char *arg, float out[4]);

typedef struct cli_probe_mesh {
    float *positions, *radiance, *normals;
    uint32_t *indices;
} cli_probe_mesh;

/* The light arriving at p (SH of the file's order) under l's distant part: prt_sh_light_at. */
prt_status cli_probe_arriving(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float p[3], prt_sh_light *out);
/* The default probe radius: 3% of the grid's largest side. */
float cli_probe_radius(const prt_transfer *t);
/* Whether in is plain per-vertex radiance a probe can join (no per-pixel parts). */
bool cli_probe_drawable(const prt_render_mesh *in);
/* out: in with a grey sphere at each probe (radius probes[k][3], or `radius` when 0) shaded by
 * the light arriving there; false when out of memory. */
bool cli_probe_spheres(const prt_render_mesh *in, const float (*probes)[4], const prt_sh_light *arriving, int count, float radius, cli_probe_mesh *keep,
                       prt_render_mesh *out);
/* out: in with a sphere (grey, albedo 0.8) at each probe, lit by the light arriving there under
 * l's distant part (prt_sh_light_at); its arrays live in keep until cli_probe_mesh_free. An error,
 * printed, when t has no grid or in draws per-pixel parts. */
prt_status cli_probe_append(cli *c, const prt_transfer *t, const prt_lighting *l, const float (*probes)[4], int count, const prt_render_mesh *in,
                            cli_probe_mesh *keep, prt_render_mesh *out);
void cli_probe_mesh_free(cli_probe_mesh *p);

#endif
