/* floe_image.h - image codes of a periodic cell (docs/periodic.md): the image x_j + H n of a
 * point, n an integer vector packed 10 bits per component (-512..511; 0 = no image). The
 * neighbour list's pairs (core/world/neighbor.c) and the PD bonds across the cell's faces
 * (floe_pd.h, floe_pd_make_periodic) carry them; here, in the lowest layer that uses them. */
#ifndef FLOE_IMAGE_H
#define FLOE_IMAGE_H

static inline int floe_img_encode(int a, int b, int c) { return (a & 1023) | (b & 1023) << 10 | (c & 1023) << 20; }
static inline void floe_img_decode(int code, int n[3]) {
    n[0] = ((code & 1023) ^ 512) - 512;
    n[1] = (((code >> 10) & 1023) ^ 512) - 512;
    n[2] = (((code >> 20) & 1023) ^ 512) - 512;
}
/* the shift H n of image code `code` (H row-major, its columns the cell vectors) */
static inline void floe_img_shift(const double H[9], int code, double s[3]) {
    int n[3];
    floe_img_decode(code, n);
    for (int r = 0; r < 3; r++) s[r] = H[3 * r] * n[0] + H[3 * r + 1] * n[1] + H[3 * r + 2] * n[2];
}

#endif
