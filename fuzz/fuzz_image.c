/* libFuzzer harness: every image format prt reads (.hdr, .pfm, .exr, .png, .jpg) from memory,
 * then what an environment does with the pixels (validation, layout). */
#include <prt/prt.h>

#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    prt_image img;
    if (prt_image_load_memory(data, size, &img) != PRT_OK) return 0;
    prt_envmap *env = NULL;
    if (prt_envmap_from_image(&img, PRT_ENV_AUTO, &env) == PRT_OK) {
        prt_sh_light sh;
        prt_envmap_project_sh(env, 2, &sh);
        prt_envmap_release(env);
    }
    prt_image_free(&img);
    return 0;
}
