/* prt/prt.h - precomputed radiance transfer: the whole public API.
 * Typical use: create a context, load a scene, bake with a method of the method table
 * (prt/method.h), save, relight under a prt_lighting (prt/lighting.h) and draw. See
 * examples/minimal.c and docs/ARCHITECTURE.md. */
#ifndef PRT_PRT_H
#define PRT_PRT_H

#include "prt/base.h"
#include "prt/sh.h"
#include "prt/haar.h"
#include "prt/image.h"
#include "prt/lighting.h"
#include "prt/brdf.h"
#include "prt/scene.h"
#include "prt/method.h"
#include "prt/transfer.h"
#include "prt/render.h"
#include "prt/reference.h"
#include "prt/compress.h"
#include "prt/sh_transfer.h"
#include "prt/wavelet.h"
#include "prt/spectral.h"
#include "prt/offset.h"
#include "prt/paint.h"
#include "prt/volume.h"

#endif
