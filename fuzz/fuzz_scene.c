/* libFuzzer harness: scene JSON (materials, BRDF specs, lights, emission, environment) over a
 * small mesh file beside it, through loading, cleaning and subdivision. */
#include <prt/prt.h>

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static prt_context *ctx;
static char dir[64], json[128];

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!ctx) {
        if (prt_context_create(&(prt_context_desc){.threads = 1}, &ctx) != PRT_OK) abort();
        snprintf(dir, sizeof dir, "/tmp/prt_fuzz_scene_%ld", (long)getpid());
        char cmd[256], obj[128];
        snprintf(cmd, sizeof cmd, "mkdir -p %s", dir);
        if (system(cmd) != 0) abort();
        /* Two named materials, so that JSON materials called like them replace them. */
        snprintf(obj, sizeof obj, "%s/tri.mtl", dir);
        FILE *f = fopen(obj, "w");
        if (!f) abort();
        fputs("newmtl m\nKd 0.5 0.5 0.5\nnewmtl n\nKd 0.2 0.3 0.4\n", f);
        fclose(f);
        snprintf(obj, sizeof obj, "%s/tri.obj", dir);
        f = fopen(obj, "w");
        if (!f) abort();
        fputs("mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 -1\nv 1 0 -1\nusemtl m\nf 1 2 3\nusemtl n\nf 2 4 3\n", f);
        fclose(f);
        snprintf(json, sizeof json, "%s/scene.json", dir);
    }
    FILE *f = fopen(json, "wb");
    if (!f) abort();
    fwrite(data, 1, size, f);
    fclose(f);
    prt_scene_desc d = {0};
    d.max_edge = 0.25f;
    d.import_in_process = 1;   /* the JSON is under test, not assimp: no process per input */
    prt_scene *s = NULL;
    if (prt_scene_load(ctx, json, &d, &s) == PRT_OK) {
        /* The default sky is the same for every input and costs most of an execution: build the
         * lighting only when the JSON names some. */
        prt_environment_desc env;
        prt_lighting *l = NULL;
        if ((prt_scene_environment(s, &env) || prt_scene_light_count(s) > 0) && prt_scene_lighting(ctx, s, &l) == PRT_OK)
            prt_lighting_release(l);
        prt_scene_release(s);
    }
    return 0;
}
