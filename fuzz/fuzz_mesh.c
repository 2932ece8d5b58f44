/* libFuzzer harness: a mesh as the importer's child process hands it back (io/mesh_message.h),
 * through the reader, the post-import validation and cleaning, and subdivision: everything prt
 * does with an imported mesh before it becomes a scene. */
#include "geom/mesh.h"
#include "io/mesh_message.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    prt__mesh m = {0};
    uint32_t flags;
    if (prt__mesh_message_read(NULL, data, size, "fuzz", &flags, &m) == PRT_OK && prt__mesh_clean(NULL, &m, "fuzz") == PRT_OK) {
        /* Relative to the mesh's size, so that each triangle becomes at most ~64: a fixed length
         * lets a large mesh legitimately ask for tens of millions (slow, not wrong). */
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < m.vertex_count * 3; ++i) {
            lo[i % 3] = fminf(lo[i % 3], m.positions[i]);
            hi[i % 3] = fmaxf(hi[i % 3], m.positions[i]);
        }
        float diag = sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
        if (diag > 0 && isfinite(diag)) prt__mesh_subdivide(NULL, &m, diag / 16);
    }
    prt__mesh_free(&m);
    return 0;
}
