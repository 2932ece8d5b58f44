/* libFuzzer harness: a mesh as the importer's child process hands it back (io/mesh_message.h),
 * through the reader, the post-import validation and cleaning, and subdivision: everything prt
 * does with an imported mesh before it becomes a scene. */
#include "geom/mesh.h"
#include "io/mesh_message.h"

#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    prt__mesh m = {0};
    uint32_t flags;
    if (prt__mesh_message_read(NULL, data, size, "fuzz", &flags, &m) == PRT_OK && prt__mesh_clean(NULL, &m, "fuzz") == PRT_OK)
        prt__mesh_subdivide(NULL, &m, 0.3f);
    prt__mesh_free(&m);
    return 0;
}
