/* Radiance RGBE (.hdr) decoding, prt's own: every length is checked against the bytes present,
 * so truncated or hostile run-length data ends in an error, never a hang or an overread. */
#ifndef PRT_IO_RGBE_H
#define PRT_IO_RGBE_H

#include "core/internal.h"
#include "prt/image.h"

/* True when data starts like a Radiance file ("#?RADIANCE" or "#?RGBE"). */
bool prt__is_rgbe(const unsigned char *data, size_t size);
/* Decodes into out (linear RGB floats, row 0 at the top); max_dim bounds width and height. */
prt_status prt__load_rgbe(const unsigned char *data, size_t size, int max_dim, prt_image *out);

#endif
