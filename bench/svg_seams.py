#!/usr/bin/python3
"""Seam pixels of `hsr render --svg` under real SVG renderers (docs/vector-output.md).

For each scene and algorithm: the SVG with faceid fills, rasterized by librsvg (rsvg-convert) and
by Chromium (headless screenshot) with their default anti-aliasing, compared with raycast's
colour image of the same faceid shading. A pixel is interior when the 3x3 pixels around it show
one face (or all background) at each of 4x4 points a pixel in raycast's face ids: no edge of the
visible picture passes near it. A seam pixel is an interior pixel whose colour differs from
raycast's: there the renderer blended a face with what lies beneath, along the edge of a piece
the face was split into. Prints a Markdown table, seam pixels counted at any difference and at
more than 2 of 255 (Chromium rounds some repainted edges by 1). Chromium is skipped when not
installed.

Usage: /usr/bin/python3 bench/svg_seams.py HSR_BINARY OUT_DIR [WxH] [SCENE ...]
"""
import os
import shutil
import subprocess
import sys
import time

import numpy as np

try:
    import matplotlib.image
except ImportError:
    print("svg_seams: needs python3-matplotlib to read PNGs; skipped", file=sys.stderr)
    sys.exit(0)

# Scenes and the algorithms run on them (newell's depth sort of random?n=5000 holds more than its
# max-fragments, so it runs on the smaller random scene).
SAMPLES = 4  # face ids at 4x4 points a pixel, to find the pixels away from edges
SCENES = [("builtin:random?n=5000", ["bsp"]), ("builtin:random?n=1000", ["bsp", "newell"]),
          ("builtin:city", ["bsp", "newell"])]


def read_png(path):
    img = matplotlib.image.imread(path)
    return np.round(img[:, :, :3] * 255).astype(np.int64)


def interior(fine, samples):
    """Pixels whose 3x3 neighbourhood shows one face at every one of its samples x samples points
    (face ids rendered at `samples` times the size): no visible edge, however thin the sliver it
    bounds, comes near."""
    h, w = fine.shape[0] // samples, fine.shape[1] // samples
    blocks = fine.reshape(h, samples, w, samples)
    ids = blocks[:, 0, :, 0]
    one = (blocks == ids[:, None, :, None]).all(axis=(1, 3))
    pad, same = np.pad(one, 1), np.pad(ids, 1, mode="edge")
    inside = np.ones((h, w), bool)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            inside &= pad[dy:dy + h, dx:dx + w] & (same[dy:dy + h, dx:dx + w] == ids)
    return inside


def rasterize(renderer, svg, png, w, h):
    if renderer == "librsvg":
        subprocess.run(["rsvg-convert", "-w", str(w), "-h", str(h), "--background-color=black", svg, "-o", png], check=True)
    else:
        subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                        "--force-device-scale-factor=1", "--default-background-color=000000ff",
                        "--window-size=%d,%d" % (w, h), "--screenshot=" + png,
                        os.path.abspath(svg)], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return read_png(png)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    hsr, out = sys.argv[1], sys.argv[2]
    size = sys.argv[3] if len(sys.argv) > 3 else "800x600"
    scenes = [(name, ["bsp", "newell"]) for name in sys.argv[4:]] or SCENES
    w, h = map(int, size.split("x"))
    os.makedirs(out, exist_ok=True)
    renderers = ["librsvg"] + (["chromium"] if shutil.which("chromium") else [])
    print("| scene | algorithm | renderer | interior pixels | seam pixels | of them > 2/255 | SVG elements | SVG KB |")
    print("|---|---|---|---|---|---|---|---|")
    for k, (scene, algorithms) in enumerate(scenes):
        base = os.path.join(out, "s%d" % k)
        common = [hsr, "render", scene, "--size", size, "--shading", "faceid", "-q"]
        subprocess.run(common + ["--algorithm", "raycast", "--out", base + ".ref.png"], check=True)
        fine = [hsr, "render", scene, "--size", "%dx%d" % (SAMPLES * w, SAMPLES * h), "-q"]
        subprocess.run(fine + ["--algorithm", "raycast", "--ids", base + ".ids.npy"], check=True)
        want, inside = read_png(base + ".ref.png"), interior(np.load(base + ".ids.npy"), SAMPLES)
        for algorithm in algorithms:
            svg = "%s.%s.svg" % (base, algorithm)
            subprocess.run(common + ["--algorithm", algorithm, "--svg", svg], check=True)
            text = open(svg).read()
            elements = text.count("<polygon") + text.count("<path")
            for renderer in renderers:
                got = rasterize(renderer, svg, "%s.%s.%s.png" % (base, algorithm, renderer), w, h)
                differs = np.abs(got - want).max(axis=2)
                seams, beyond = int(((differs > 0) & inside).sum()), int(((differs > 2) & inside).sum())
                print("| %s | %s | %s | %d | %d | %d | %d | %.0f |" % (
                    scene, algorithm, renderer, int(inside.sum()), seams, beyond, elements, len(text) / 1e3))
                sys.stdout.flush()


if __name__ == "__main__":
    main()
