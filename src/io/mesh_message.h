/* An imported mesh as bytes: what the importer (running in a child process, io/isolate.h) hands
 * back to prt. The reader treats the bytes as hostile input: every count is checked against the
 * bytes that remain before it sizes anything, and the mesh goes through prt__mesh_append's index
 * checks and, later, prt__mesh_clean. */
#ifndef PRT_IO_MESH_MESSAGE_H
#define PRT_IO_MESH_MESSAGE_H

#include "geom/mesh.h"

#define PRT__IMPORT_FLIPPED 1u          /* the importer reversed the winding of closed inside-out pieces */
#define PRT__IMPORT_KEPT_ENCLOSURE 2u   /* ... and left closed pieces wound inwards around other geometry */
/* Bits 8..19: pieces flipped, 20..31: pieces kept (each at most 4095). */

/* Starts a message: the importer's status and, on failure, its one-line reason. */
void prt__mesh_message_begin(prt__bytes *b, prt_status status, uint32_t flags, const char *message);
/* Adds one part (one material, called name; NULL or "" = unnamed): nv vertices with positions, normals (zero = compute), optional
 * UVs (NULL), nt triangles indexing the part's own vertices. Parts are counted by the reader. */
void prt__mesh_message_part(prt__bytes *b, const char *name, const float albedo[3], const float emission[3], size_t nv, const float *pos,
                            const float *nrm, const float *uv, size_t nt, const uint32_t *idx);

/* Appends the message's parts to m; path names the file in errors. Returns the importer's own
 * failure as it reported it, or PRT_ERR_FORMAT for a malformed message. *flags gets the flags. */
prt_status prt__mesh_message_read(const prt_context *ctx, const unsigned char *data, size_t size, const char *path, uint32_t *flags,
                                  prt__mesh *m);

#endif
