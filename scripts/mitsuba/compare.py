#!/usr/bin/env python3
"""Compares two linear RGB EXR images (e.g. raylab's and Mitsuba's) channel by channel.

    python3 scripts/mitsuba/compare.py raylab.exr mitsuba.exr [--scale-b X] [--tolerance 0.01]

Prints the per-channel image means of A and B (B times --scale-b), the relative difference
(B - A) / A per channel, and two per-pixel checks that catch a flipped or shifted image: the
mean absolute pixel difference relative to A's mean, and the largest relative difference of
BLOCKxBLOCK-pixel block means. Exits 1 if any channel's mean differs by more than --tolerance,
or (with --block-tolerance) if a block does. EXRs are read with Mitsuba's own Bitmap (the
scalar_rgb variant: no LLVM needed).
"""

import argparse
import sys

import mitsuba as mi
import numpy as np


def read(path):
    return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32,
                                            srgb_gamma=False), dtype=np.float64)


def block_means(img, n):
    h, w = img.shape[0] // n * n, img.shape[1] // n * n
    return img[:h, :w].reshape(h // n, n, w // n, n, 3).mean(axis=(1, 3))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("a")
    p.add_argument("b")
    p.add_argument("--scale-b", type=float, default=1.0, help="multiply B by this first")
    p.add_argument("--tolerance", type=float, default=0.01, help="relative, per channel mean")
    p.add_argument("--block", type=int, default=32, help="block side for the block check")
    p.add_argument("--block-tolerance", type=float, default=None,
                   help="also fail if a block mean (summed over RGB) differs by more than this")
    args = p.parse_args()
    mi.set_variant("scalar_rgb")
    a, b = read(args.a), read(args.b) * args.scale_b
    if a.shape != b.shape:
        print(f"size differs: {args.a} {a.shape}, {args.b} {b.shape}")
        return 1
    ma, mb = a.reshape(-1, 3).mean(axis=0), b.reshape(-1, 3).mean(axis=0)
    rel = (mb - ma) / np.where(ma == 0, 1, ma)
    print(f"A {args.a}: {a.shape[1]}x{a.shape[0]}")
    print(f"B {args.b}" + (f" x {args.scale_b}" if args.scale_b != 1 else ""))
    for i, c in enumerate("RGB"):
        print(f"  {c}: mean A {ma[i]:.6f}  B {mb[i]:.6f}  (B-A)/A {rel[i]:+.4%}")
    mad = np.abs(a - b).mean() / a.mean()
    ba, bb = block_means(a, args.block).sum(-1), block_means(b, args.block).sum(-1)
    block = np.abs(bb - ba) / np.maximum(ba, 0.01 * ba.mean())  # floor: dark blocks
    print(f"  per pixel: mean |B-A| / mean A = {mad:.4%}")
    print(f"  {args.block}x{args.block} blocks: max |B-A|/A = {block.max():.4%}, "
          f"median {np.median(block):.4%}")
    bad = [c for i, c in enumerate("RGB") if abs(rel[i]) > args.tolerance]
    if bad:
        print(f"FAIL: channel(s) {','.join(bad)} differ by more than {args.tolerance:.2%}")
        return 1
    if args.block_tolerance is not None and block.max() > args.block_tolerance:
        print(f"FAIL: a block differs by more than {args.block_tolerance:.2%}")
        return 1
    print(f"OK: every channel mean within {args.tolerance:.2%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
