#!/usr/bin/env python3
"""Compares two linear images of the same size (.pfm, as prt render and prt reference write them):
relative L2 of the luminance over the image, and the worst 16 x 16-pixel blocks by the relative
error of their mean - over all blocks, and over those whose reference mean is at least a quarter
of the image's (dark blocks are mostly the reference's noise). Plain Python (no numpy).
Usage: image_blocks.py IMAGE.pfm REFERENCE.pfm [--block N] [--list K]"""
import argparse
import math
import struct


def read_pfm(path):
    """Rows top to bottom of the mean of the channels."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        channels = 3 if kind == b"PF" else 1
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * channels
        data = struct.unpack(("<" if scale < 0 else ">") + "f" * n, f.read(n * 4))
    rows = [[sum(data[(y * w + x) * channels:(y * w + x + 1) * channels]) / channels for x in range(w)] for y in range(h)]
    return w, h, rows[::-1]   # PFM stores the bottom row first


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("image")
    ap.add_argument("reference")
    ap.add_argument("--block", type=int, default=16)
    ap.add_argument("--list", type=int, default=3)
    a = ap.parse_args()
    w, h, img = read_pfm(a.image)
    w2, h2, ref = read_pfm(a.reference)
    if (w, h) != (w2, h2):
        raise SystemExit("image_blocks: %dx%d against %dx%d" % (w, h, w2, h2))
    num = sum((img[y][x] - ref[y][x]) ** 2 for y in range(h) for x in range(w))
    den = sum(ref[y][x] ** 2 for y in range(h) for x in range(w))
    mean = sum(map(sum, ref)) / (w * h)
    B = a.block
    blocks = []
    for by in range(h // B):
        for bx in range(w // B):
            si = sum(img[y][x] for y in range(by * B, by * B + B) for x in range(bx * B, bx * B + B)) / (B * B)
            sr = sum(ref[y][x] for y in range(by * B, by * B + B) for x in range(bx * B, bx * B + B)) / (B * B)
            blocks.append((abs(si - sr) / max(sr, 1e-12), bx * B, by * B, si, sr))
    blocks.sort(reverse=True)
    lit = [b for b in blocks if b[4] >= 0.25 * mean]
    print("  relative L2 %.4f; image mean %.4f" % (math.sqrt(num / den), mean))
    for name, group in (("all %d blocks" % len(blocks), blocks), ("%d lit blocks" % len(lit), lit)):
        print("  worst of %s:" % name)
        for e, x, y, si, sr in group[:a.list]:
            print("    %5.1f%% at pixel (%d, %d): %.4f against %.4f" % (100 * e, x, y, si, sr))


if __name__ == "__main__":
    main()
