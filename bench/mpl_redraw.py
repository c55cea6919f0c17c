#!/usr/bin/python3
"""Redraw time and SVG size: matplotlib's own Poly3DCollection against hsr.matplotlib (bsp, newell)
at 640x480 (Agg) on bench/peer/vector_peer.py's scenes: two interpenetrating height fields of
1,024 and 10,000 triangles (what plot_surface draws; matplotlib's own with a collection per
surface, as two plot_surface calls make) and 1,000 random interpenetrating triangles. A redraw is fig.canvas.draw() after turning the
view by 7 degrees (so hsr orders again); the median of DRAWS redraws after one warm-up. Also the
SVG's size, and wrong pixels away from edges against raycast (python/tests/test_matplotlib.py's
check). Prints a Markdown table. With "wrong": instead, the tests' wrong-pixel table (every scene
of vector_peer.py in the tests' two views at 400x300, matplotlib's own collections against
hsr.matplotlib). See docs/matplotlib.md.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/mpl_redraw.py [DRAWS | wrong]
"""
import io
import os
import sys
import time

import numpy as np

import matplotlib

matplotlib.use("agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peer"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python", "tests"))
import vector_peer  # noqa: E402
import test_matplotlib as check  # noqa: E402  (the figure, palette and reference of the tests)


def tools(scene):
    return [("matplotlib", check.own_collections(scene)), ("hsr bsp", check.hsr_collection),
            ("hsr newell", lambda ax, v, c: check.hsr_collection(ax, v, c, "newell"))]


CASES = [("surfaces", lambda: vector_peer.surfaces(16)), ("surfaces", lambda: vector_peer.surfaces(50)),
         ("random-triangles", lambda: vector_peer.random_triangles(1000, seed=7))]


def wrong_table():
    print("| scene | polygons | view (elev, azim) | matplotlib | hsr bsp | pixels tested |")
    print("|---|---|---|---|---|---|")
    for name, make in vector_peer.SCENES:
        for view in check.VIEWS:
            theirs, tested = check.wrong_pixels(name, view, check.own_collections(name))
            ours, _ = check.wrong_pixels(name, view, check.hsr_collection)
            print("| %s | %d | %s | %d | %d | %d |" % (name, len(make()), view, theirs, ours, tested))
            sys.stdout.flush()


def main():
    if sys.argv[1:] == ["wrong"]:
        return wrong_table()
    draws = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    check.W, check.H = 640, 480
    print("| scene | polygons | tool | redraw s (median of %d) | SVG KB | SVG s | wrong pixels | pixels tested |" % draws)
    print("|---|---|---|---|---|---|---|---|")
    sys.stdout.flush()
    for scene, make_polys in CASES:
        polys = make_polys()
        for name, make in tools(scene):
            fig, ax, _ = check.figure(polys, (30, -60), make)
            fig.canvas.draw()  # warm-up
            times = []
            for k in range(draws):
                ax.view_init(30, -60 + 7 * (k + 1))
                start = time.perf_counter()
                fig.canvas.draw()
                times.append(time.perf_counter() - start)
            ax.view_init(30, -60)
            got = check.decode(check.agg_pixels(fig), len(polys))
            want, inside = check.reference(ax, polys)
            svg = io.BytesIO()
            start = time.perf_counter()
            fig.savefig(svg, format="svg")
            svg_s = time.perf_counter() - start
            plt.close(fig)
            print("| %s | %d | %s | %.3f | %.0f | %.2f | %d | %d |" % (
                scene, len(polys), name, float(np.median(times)), len(svg.getvalue()) / 1e3, svg_s,
                int((inside & (got != want)).sum()), int(inside.sum())))
            sys.stdout.flush()


if __name__ == "__main__":
    main()
