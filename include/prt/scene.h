/* prt/scene.h - the static scene a bake runs over: one triangle mesh with per-vertex normals
 * and per-vertex diffuse albedo, assembled from mesh files (anything assimp reads: OBJ+MTL,
 * PLY, glTF 2.0, FBX, ...) or a JSON scene file that names meshes and materials.
 *
 * Loading cleans the input: zero-area triangles are dropped (with a warning through the log
 * hook), missing or non-finite normals are recomputed from the geometry, unreferenced vertices
 * are removed. A scene whose triangles are all degenerate is rejected with PRT_ERR_EMPTY.
 * A scene is immutable after creation and safe to read from many threads. */
#ifndef PRT_SCENE_H
#define PRT_SCENE_H

#include "prt/base.h"
#include "prt/brdf.h"
#include "prt/lighting.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct prt_scene prt_scene;

/* Which side of an imported triangle is its front. Files that carry normals are trusted in AUTO
 * mode; for files without normals, AUTO looks at each connected piece: one that is nearly closed
 * and whose counter-clockwise normals would point inwards (negative signed volume), as scanned
 * meshes such as Stanford's bun_zipper.ply are wound, is flipped - unless another piece, a light
 * (point, spot or sphere) or camera eye of the JSON scene, or one of prt_scene_desc.inside_points
 * lies inside its bounds, which makes it an enclosure (a room, walls facing in on purpose) that
 * is kept. Both decisions are said through the log hook. */
typedef enum prt_winding {
    PRT_WINDING_AUTO = 0,
    PRT_WINDING_KEEP,     /* counter-clockwise is the front, as the file says */
    PRT_WINDING_FLIP      /* clockwise is the front: reverse every triangle (and file normals) */
} prt_winding;

typedef struct prt_scene_desc {
    float max_edge;          /* subdivide until no edge is longer (scene units); 0 = no subdivision */
    float default_albedo[3]; /* for meshes without a material colour; all zero = 0.7 grey unless
                              * default_albedo_given */
    int override_albedo;     /* non-zero: default_albedo for every surface: mesh files' materials
                              * and a JSON scene's albedos and BRDF kd alike (BRDFs keep their
                              * glossy lobes) */
    float crease_angle_deg;  /* when normals are computed: split at dihedral angles above this; 0 = 45 */
    prt_winding winding;     /* triangle orientation of imported files; 0 = PRT_WINDING_AUTO */
    /* Mesh files are parsed by assimp in a child process, so that a file that makes it loop or
     * abort ends in an error instead of taking the caller with it (and a failed import leaks
     * nothing into the caller). Time limit of one file's import in seconds; 0 = 60 s plus 10 s
     * per MB of the file. The context's cancel hook stops an import within 100 ms. */
    float import_seconds;
    int import_in_process;   /* non-zero: call assimp in this process (no time limit, no containment) */
    /* Last, so that older zero-initialisers keep meaning "0.7 grey". */
    int default_albedo_given; /* non-zero: default_albedo as given, black included */
    /* World points that count as inside the scene's rooms for PRT_WINDING_AUTO, beside the lights
     * and the camera a JSON scene names: the positions of lights given elsewhere (the command
     * line's --light) and the camera's eye. A closed piece wound inwards around one of them is a
     * room seen from inside and keeps its winding. 3 floats per point, borrowed for the call;
     * NULL / 0 = none. */
    const float *inside_points;
    size_t inside_point_count;
} prt_scene_desc;

/* path: a mesh file, or a .json scene file (see docs/SCENE.md). */
prt_status prt_scene_load(prt_context *ctx, const char *path, const prt_scene_desc *desc, prt_scene **out);

/* Builds a scene by copying caller arrays. normals may be NULL (computed); albedo may be NULL
 * (desc default); albedo is per vertex RGB. */
prt_status prt_scene_create_copy(prt_context *ctx, const float *positions, const float *normals,
                                 const float *albedo, size_t vertex_count,
                                 const uint32_t *indices, size_t triangle_count,
                                 const prt_scene_desc *desc, prt_scene **out);
void prt_scene_release(prt_scene *scene);
/* Gives vertices [first, first + count) of the scene (as it is now, after cleaning) a BRDF
 * material; their albedo becomes the BRDF's Lambertian part. */
prt_status prt_scene_set_brdf(prt_scene *scene, size_t first, size_t count, const prt_brdf *brdf);
int prt_scene_brdf_count(const prt_scene *scene);
/* Sets the albedo of every vertex of the surface called name (a material of the mesh files or
 * of the JSON scene) to rgb in [0, 1]; an unknown name is an error listing the names. */
prt_status prt_scene_paint_albedo(prt_scene *scene, const char *name, const float rgb[3]);
/* Adds brdf to the BRDFs the surface called name can switch among at run time (as a JSON
 * material's "brdfs" does; spectral bakes keep them, prt_transfer_brdf_set): the first call for a
 * surface lists the BRDF it wears first (its material's, or a Lambertian one of its albedo). At
 * most 64 in all; an unknown name is an error listing the names. */
prt_status prt_scene_add_brdf_choice(prt_scene *scene, const char *name, const prt_brdf *brdf);
/* Makes vertices [first, first + count) emit radiance rgb (W / (m^2 sr), from the front of their
 * triangles; 0 turns emission off), as an emissive material of a mesh file does. */
prt_status prt_scene_set_emission(prt_scene *scene, size_t first, size_t count, const float rgb[3]);
/* Sets texture coordinates (2 per vertex) of vertices [first, first + count); mesh files bring
 * their own (the first UV channel). Per-texel transfer needs them on every vertex. */
prt_status prt_scene_set_uv(prt_scene *scene, size_t first, size_t count, const float *uv);

size_t prt_scene_vertex_count(const prt_scene *scene);
size_t prt_scene_triangle_count(const prt_scene *scene);
const float *prt_scene_positions(const prt_scene *scene);   /* 3 per vertex */
const float *prt_scene_normals(const prt_scene *scene);     /* 3 per vertex, unit length */
const float *prt_scene_albedo(const prt_scene *scene);      /* 3 per vertex */
const uint32_t *prt_scene_indices(const prt_scene *scene);  /* 3 per triangle */
void prt_scene_bounds(const prt_scene *scene, float lo[3], float hi[3]);
/* The lighting a JSON scene names ("environment"); returns 0 when it names none. */
int prt_scene_environment(const prt_scene *scene, prt_environment_desc *out);
/* The local lights a JSON scene names ("lights"), in file order. */
int prt_scene_light_count(const prt_scene *scene);
const prt_light *prt_scene_light(const prt_scene *scene, int index);
/* Replaces the scene's local lights by a copy of lights[0, count) (count 0: none), as if its JSON
 * had named them: a bake stores them in its file and refinement probes them. Each is validated. */
prt_status prt_scene_set_lights(prt_scene *scene, const prt_light *lights, int count);
/* The camera a JSON scene names ("camera": eye, target, vertical field of view in degrees, 0 when
 * not given); returns 0 when it names none. */
int prt_scene_camera(const prt_scene *scene, float eye[3], float target[3], float *fov_deg);
/* Emitted radiance per vertex (3 floats, W/(m^2 sr), leaving the front side), from emissive
 * materials (Ke in MTL, emissiveFactor in glTF, "emission" in scene JSON); NULL when nothing emits. */
const float *prt_scene_emission(const prt_scene *scene);
/* A lighting object with everything the scene names: its environment (the procedural sky when
 * it names neither an environment nor lights; none when it names lights only), its lights, and
 * its emissive surfaces at scale 1. */
prt_status prt_scene_lighting(prt_context *ctx, const prt_scene *scene, prt_lighting **out);

/* Adaptive refinement: splits triangles only where transfer changes faster than the vertices
 * sample it (contact shadows, shadow edges crossing big triangles), instead of everywhere as
 * max_edge does. What shapes transfer is probed at vertices, edge midpoints and inside triangles:
 * ambient occlusion within a tenth of the scene, and the share of each light of the scene (its
 * first 15 "lights", and its emitting surfaces together) that arrives unshadowed. Where two probes differ, or a midpoint
 * differs from what its corners interpolate, by more than `threshold`, edges are split at their
 * midpoints (longest-edge bisection keeps triangles well shaped and the mesh conforming, creases
 * included); levels repeat until nothing differs, edges reach min_edge or the budget is spent.
 * Deterministic for any thread count. Run it before baking: the bake and its file see the
 * refined mesh. A cancelled call keeps the levels it finished (a valid, less refined mesh). */
typedef struct prt_refine_desc {
    size_t max_new_vertices;  /* vertex budget; 0 = as many as the scene has, at least 100,000 */
    float threshold;          /* probe difference that splits, in (0, 1); 0 = 0.1 */
    float min_edge;           /* edges at most twice this are not split; 0 = the larger of 1/2000 of the
                               * diagonal and an eighth of the spacing the budget's vertices would have */
    int max_levels;           /* 0 = 10 (each halves the edges it splits) */
    prt_progress_fn progress; /* a stage per level; return non-zero to cancel (PRT_ERR_CANCELLED) */
    void *progress_user;
    /* Lights probed besides the scene's own (for example the sun of the sky the file will be
     * relit under), within the 15 probed in all; NULL / 0 = none. */
    const prt_light *extra_lights;
    int extra_light_count;
} prt_refine_desc;

typedef struct prt_refine_stats {
    int levels;               /* levels that split something */
    size_t marked_edges;      /* edges found differing at the first level */
    size_t marked_triangles;  /* prt_scene_refine_estimate: triangles estimated to need it */
    size_t new_vertices, triangles;   /* added; triangles after */
    size_t probes;            /* points probed */
    int budget_spent;         /* non-zero when the budget stopped it */
} prt_refine_stats;

prt_status prt_scene_refine(prt_context *ctx, prt_scene *scene, const prt_refine_desc *desc, prt_refine_stats *stats);
/* Estimates, from 2,000 evenly spread triangles and in a fraction of a second, how many triangles
 * span edges their corners cannot resolve (stats->marked_triangles); changes nothing. What a tool
 * needs to suggest refinement. */
prt_status prt_scene_refine_estimate(prt_context *ctx, const prt_scene *scene, const prt_refine_desc *desc, prt_refine_stats *stats);

/* A translucent medium (offset transfer maps scatter light under its surface with Jensen's
 * dipole): absorption and reduced scattering per mm, relative index of refraction. */
typedef struct prt_medium {
    float sigma_a[3], sigma_s[3];
    float eta;
    /* > 0: instead of the dipole, the paper's simpler kernel - an exponential falloff with this
     * mean distance (mm) that scatters what the surface's albedo reflects; sigma and eta unused. */
    float falloff_mm;
} prt_medium;

/* Jensen et al. 2001's measured "skin", "marble" and "ketchup"; an unknown name is an error
 * that lists them. */
prt_status prt_medium_preset(const char *name, prt_medium *out);
/* Whether the coefficients are usable: sigma_a > 0, sigma_s >= 0 (at most 1e6), eta in [1, 4];
 * or a falloff distance in (0, 1e6] mm. */
prt_status prt_medium_check(const prt_medium *m);
/* Makes the surface called name (a material of the mesh files or of the JSON scene) translucent;
 * an unknown name is an error listing the names. JSON scenes do this with a material's
 * "subsurface". */
prt_status prt_scene_set_medium(prt_scene *scene, const char *surface, const prt_medium *m);
/* The medium of the surface called name: 1 and *out when it has one, else 0. */
int prt_scene_medium(const prt_scene *scene, const char *surface, prt_medium *out);

/* A specular surface: light meets it as a perfect mirror or a smooth dielectric (glass, water)
 * instead of a diffuse reflector. Bakes that follow specular paths (SH transfer: caustics) and
 * the reference path tracer turn rays at it; elsewhere it is the diffuse surface of its albedo. */
typedef enum prt_specular_type {
    PRT_SPECULAR_NONE = 0,
    PRT_SPECULAR_MIRROR,   /* reflects `reflectance` of the light (one number: grey) */
    PRT_SPECULAR_GLASS     /* reflects and refracts as Fresnel's equations say for `ior` */
} prt_specular_type;
typedef struct prt_specular {
    prt_specular_type type;
    float reflectance;     /* mirror: in [0, 1] */
    float ior;             /* glass: index of refraction inside over outside, in [1, 4]; the
                            * surface's front (its normals' side) is the outside */
} prt_specular;
/* Whether s is usable: a mirror's reflectance in [0, 1], a glass's ior in [1, 4]. */
prt_status prt_specular_check(const prt_specular *s);
/* Makes the surface called name specular (type NONE makes it diffuse again); an unknown name is
 * an error listing the names. JSON scenes do this with a material's "specular". */
prt_status prt_scene_set_specular(prt_scene *scene, const char *surface, const prt_specular *s);
/* The specular material of the surface called name: 1 and *out when it has one, else 0. */
int prt_scene_specular(const prt_scene *scene, const char *surface, prt_specular *out);

/* Writes the procedural demo scene (a ribbed bowl and a torus knot-like ring of spheres over a
 * ground plane between a red and a green wall) as OBJ+MTL. */
prt_status prt_demo_scene_write(const char *obj_path);
/* Writes a closed 6 x 3 x 4 m room with a 1.2 x 1 m window in its front wall (z = 2), a box and a
 * shelf, every surface a grid of squares of side `cell` metres (0.0625 gives about 30,000
 * vertices), as OBJ+MTL: indirect light dominates once a light shines in through the window. */
prt_status prt_demo_room_write(const char *obj_path, float cell);

#ifdef __cplusplus
}
#endif
#endif
