/* Orthonormal 2D Haar wavelets (non-standard decomposition) on square power-of-two images. */
#ifndef PRT_CORE_HAAR_H
#define PRT_CORE_HAAR_H

#define PRT__HAAR_MAX 128

/* In place, n x n floats (row-major, n a power of two, 1 <= n <= PRT__HAAR_MAX). After the
 * forward transform the scaling coefficient sits at [0][0]; the details of the level whose
 * averages fill the top-left s x s square lie in the three quadrants beside it (horizontal right,
 * vertical below, diagonal below right), Mallat's layout. Each 2 x 2 step is an orthonormal
 * 4 x 4 matrix, so the transform preserves inner products and the inverse is its transpose. */
void prt__haar2d_forward(float *img, int n);
void prt__haar2d_inverse(float *img, int n);

#endif
