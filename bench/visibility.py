#!/usr/bin/python3
"""Per-instance visibility (px_count_all, px_count_visib, visib_fract) of a scene of 30 objects:
hsr.render(..., outputs=("instance_id", "visibility")) in one call, against the per-object way
dataset tools use today: one render of the whole scene for the visible pixels and one render of
each object alone for the pixels it covers (30 + 1 renders; the 30 one-object scenes built once,
outside the timing). Both give the same counts (checked); times are medians over the views, with
the render of the instance_id image alone for scale.

The objects: ellipsoids of about --triangles triangles each (a UV sphere, stretched and turned), on
a jittered 6 x 5 grid, seen from an orbit of --views cameras, so that they hide each other.

Run: PYTHONPATH=build/python /usr/bin/python3 bench/visibility.py [--threads 1] [--markdown]
"""
import argparse
import statistics
import time

import numpy as np

import hsr


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--objects", type=int, default=30, help="objects in the scene")
    p.add_argument("--triangles", type=int, default=2000, help="triangles per object, about")
    p.add_argument("--size", default="640x480", help="image size")
    p.add_argument("--views", type=int, default=12, help="views timed (median)")
    p.add_argument("--threads", type=int, default=0, help="hsr threads (0: all cores)")
    p.add_argument("--markdown", action="store_true", help="print a Markdown table row")
    return p.parse_args()


def ellipsoid(triangles, rng):
    """A UV sphere of about `triangles` triangles, stretched, turned and placed by rng."""
    stacks = max(2, int(round(np.sqrt(triangles / 4))))
    slices = 2 * stacks
    theta = np.linspace(0, np.pi, stacks + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, slices, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], -1).reshape(-1, 3)
    v = np.vstack([[0, 1, 0], ring, [0, -1, 0]])
    faces = []
    for j in range(slices):  # the caps
        k = (j + 1) % slices
        faces.append([0, 1 + k, 1 + j])
        last = 1 + (stacks - 2) * slices
        faces.append([len(v) - 1, last + j, last + k])
    for i in range(stacks - 2):  # the bands between rings i and i + 1
        for j in range(slices):
            k = (j + 1) % slices
            a, b, c, d = 1 + i * slices + j, 1 + i * slices + k, 1 + (i + 1) * slices + j, 1 + (i + 1) * slices + k
            faces += [[a, b, d], [a, d, c]]
    rot, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return (v * rng.uniform(0.35, 0.8, 3)) @ rot.T, np.array(faces, np.int64)


def build(objects, triangles):
    rng = np.random.default_rng(66)
    meshes = []
    for i in range(objects):
        v, f = ellipsoid(triangles, rng)
        meshes.append((v + [1.1 * (i % 6) - 2.75 + rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3),
                            1.1 * (i // 6) - 2.2 + rng.uniform(-0.3, 0.3)], f))
    colors = [rng.integers(40, 256, 3).astype(np.uint8) for _ in meshes]
    scene = hsr.Scene.from_arrays([v for v, _ in meshes], [f for _, f in meshes], colors=colors)
    alone = [hsr.Scene.from_arrays(v, f, colors=c) for (v, f), c in zip(meshes, colors)]
    return scene, alone


def main():
    args = parse_args()
    width, height = map(int, args.size.split("x"))
    scene, alone = build(args.objects, args.triangles)
    cameras = [hsr.Camera.look_at((7 * np.cos(a), 3.2, 7 * np.sin(a)), (0, 0, 0), width, height, fovy_deg=55,
                                  near=0.5, far=30) for a in np.linspace(0, 2 * np.pi, args.views, endpoint=False)]
    render, one_pass, per_object, visible = [], [], [], []
    for camera in cameras:
        t0 = time.perf_counter()
        vis = hsr.render(scene, camera, outputs=("instance_id", "visibility"), threads=args.threads)["visibility"]
        t1 = time.perf_counter()
        ids = hsr.render(scene, camera, outputs="instance_id", threads=args.threads)["instance_id"]
        visib = np.bincount(ids[ids >= 0], minlength=args.objects)
        t2 = time.perf_counter()
        covered = [int(np.count_nonzero(hsr.render(s, camera, outputs="face_id", threads=args.threads)["face_id"] >= 0))
                   for s in alone]
        t3 = time.perf_counter()
        assert list(vis["px_count_visib"]) == list(visib) and list(vis["px_count_all"]) == covered
        render.append(t2 - t1)
        one_pass.append(t1 - t0)
        per_object.append(t3 - t1)
        visible.append(float(np.mean(vis["visib_fract"])))
    r = statistics.median(render) * 1e3
    a, b = statistics.median(one_pass) * 1e3, statistics.median(per_object) * 1e3
    row = (f"{args.objects} x {args.triangles // 1000}k triangles ({scene.triangle_count:,}), {width}x{height}, "
           f"threads {args.threads or 'all'}")
    if args.markdown:
        print(f"| {row} | {r:.1f} ms | {a:.1f} ms | {b:.1f} ms | {b / a:.1f}x |")
    else:
        print(f"{row}: the render alone {r:.1f} ms; one pass {a:.1f} ms, per object (1 + {args.objects} renders) "
              f"{b:.1f} ms, {b / a:.1f}x; "
              f"counts equal in all {len(cameras)} views; mean visib_fract {statistics.mean(visible):.2f}")


if __name__ == "__main__":
    main()
