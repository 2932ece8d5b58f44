/* prt/haar.h - the orthonormal 2D Haar wavelet transform: the all-frequency lighting basis of
 * the wavelet method (prt/wavelet.h) and of anyone projecting square images onto it. Pure and
 * thread-safe. */
#ifndef PRT_HAAR_H
#define PRT_HAAR_H

#include "prt/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The non-standard decomposition (Mallat layout), in place on an n x n image, n a power of two
 * from 1 to 128; inverse != 0 undoes it. */
prt_status prt_haar2d(float *img, int n, int inverse);

#ifdef __cplusplus
}
#endif
#endif
