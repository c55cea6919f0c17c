#!/usr/bin/python3
"""The before/after pictures of docs/matplotlib.md: classic mplot3d failures drawn by matplotlib's
own Poly3DCollection (left; an object per collection, as separate plot calls make them) and by
hsr.matplotlib (right, one collection), same polygons, colours and shading, Agg.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/mpl_pictures.py OUT_DIR
"""
import os
import sys

import numpy as np

import matplotlib
import matplotlib.image

matplotlib.use("agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.mplot3d import art3d  # noqa: E402

import hsr.matplotlib as hmpl  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peer"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python", "tests"))
import vector_peer  # noqa: E402
import test_matplotlib as check  # noqa: E402  (the tests' bare 3-D figure)

# Scene, its objects (polygon counts, in order), their colours, the view.
PICTURES = [
    ("intersecting-planes", [1, 1, 1], ["tab:blue", "tab:orange", "tab:green"], (25, -55)),
    ("interlocking-tori", [256, 256], ["tab:red", "tab:cyan"], (35, -60)),
    ("cycle", [1, 1, 1], ["tab:blue", "tab:orange", "tab:green"], (55, -60)),
    ("surfaces", [1152, 1152], ["tab:purple", "gold"], (25, -60)),
]


def draw(polys, counts, colors, view, exact):
    base = np.concatenate([np.repeat(matplotlib.colors.to_rgba_array(c), k, axis=0) for c, k in zip(colors, counts)])

    def make(ax, verts, colors):
        shaded = hmpl.shade_colors(ax, verts, colors)
        if exact:
            return check.hsr_collection(ax, verts, shaded)
        start = 0
        for k in counts:
            ax.add_collection3d(art3d.Poly3DCollection(verts[start:start + k], facecolors=shaded[start:start + k],
                                                       edgecolors="none"))
            start += k

    fig, _, _ = check.figure(polys, view, make, colors=base, background="white")
    image = check.agg_pixels(fig)
    plt.close(fig)
    return image


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    check.W, check.H = 240, 200
    scenes = dict(vector_peer.SCENES)
    for name, counts, colors, view in PICTURES:
        polys = scenes[name]()
        assert sum(counts) == len(polys), (name, len(polys))
        left, right = draw(polys, counts, colors, view, False), draw(polys, counts, colors, view, True)
        gap = np.full((left.shape[0], 6, 3), 255, np.uint8)
        path = os.path.join(out, "matplotlib-%s.png" % name)
        matplotlib.image.imsave(path, np.concatenate([left, gap, right], axis=1))
        print(path, os.path.getsize(path), "bytes")


if __name__ == "__main__":
    main()
