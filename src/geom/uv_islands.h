/* The charts of a mesh's UV layout as it stands: triangles joined where they share a corner of
 * the same position and texture coordinates, whether the corner is one vertex or duplicates. */
#ifndef PRT_GEOM_UV_ISLANDS_H
#define PRT_GEOM_UV_ISLANDS_H

#include "geom/mesh.h"

/* island gets each triangle's chart, 0 .. *count - 1 numbered by first triangle. */
prt_status prt__uv_islands(const prt_context *ctx, const prt__mesh *m, uint32_t *island, uint32_t *count);

#endif
