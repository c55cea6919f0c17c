#!/usr/bin/python3
"""The vector-output peer: matplotlib's Poly3DCollection saved as SVG against `hsr render --svg`
(newell), on the same polygons and camera, each SVG rasterized by rsvg-convert and its faceid
colours decoded against hsr's raycast. Prints a Markdown table per scene: each tool's time (SVG: making the
order and the file in process, hsr's statistics stage `svg`; wall: hsr's whole command, which also
renders the raster frame), file
size and wrong pixels (away from the edges of its own polygons, where anti-aliasing blends), and
writes the side by side picture of the first scene (matplotlib left, hsr right). Optional: needs Debian's python3-matplotlib and librsvg2-bin
(scripts/bench-vector.sh installs them). See docs/vector-output.md.

Usage: /usr/bin/python3 bench/peer/vector_peer.py HSR_BINARY OUT_DIR [WIDTH HEIGHT]
"""
import json
import math
import os
import re
import subprocess
import sys
import time

import numpy as np

# matplotlib is imported by main() (the scenes below need NumPy only: python/tests and
# bench/mpl_redraw.py import them).
matplotlib = plt = proj3d = Poly3DCollection = None


def import_matplotlib():
    global matplotlib, plt, proj3d, Poly3DCollection
    try:
        import matplotlib

        matplotlib.use("svg")
        import matplotlib.image
        import matplotlib.pyplot as plt
        from mpl_toolkits.mplot3d import proj3d
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    except ImportError:
        print("vector_peer: matplotlib not installed (Debian: python3-matplotlib); skipped", file=sys.stderr)
        sys.exit(0)


# --- Scenes: polygons (lists of 3D points), written as OBJ so both tools read the same faces. ---

def cycle_bars():
    """Three bars overlapping cyclically, none intersecting (the painter's cycle)."""
    polys = []
    for i in range(3):
        a = 2 * math.pi * i / 3
        d = np.array([math.cos(a), math.sin(a), 0.0])
        n = np.array([-d[1], d[0], 0.0])
        c = -0.35 * n
        for_end, back_end = c + 1.1 * d, c - 1.1 * d
        for_end[2], back_end[2] = 0.15, -0.15
        w = 0.12 * n
        polys.append([back_end - w, for_end - w, for_end + w, back_end + w])
    return polys


def surfaces(n=24):
    """Two interpenetrating height fields on a grid, as triangles: what plot_surface draws."""
    polys = []
    xs = np.linspace(-1, 1, n + 1)
    for f in (lambda x, y: 0.4 * math.sin(3 * x) * math.cos(2 * y), lambda x, y: 0.3 * x - 0.2 * y):
        for i in range(n):
            for j in range(n):
                p = [np.array([xs[i + a], xs[j + b], f(xs[i + a], xs[j + b])]) for a, b in ((0, 0), (1, 0), (1, 1), (0, 1))]
                polys += [[p[0], p[1], p[2]], [p[0], p[2], p[3]]]
    return polys


def random_triangles(n=300, seed=5):
    rng = np.random.default_rng(seed)
    polys = []
    for _ in range(n):
        c = rng.uniform(-1, 1, 3)
        polys.append([c + 0.6 * rng.uniform(-0.5, 0.5, 3) for _ in range(3)])
    return polys


def random_polygons(n=40, seed=4):
    """Planar convex quads and pentagons of random orientation, interpenetrating."""
    rng = np.random.default_rng(seed)
    polys = []
    for i in range(n):
        c = rng.uniform(-1, 1, 3)
        a = rng.normal(size=3)
        a /= np.linalg.norm(a)
        b = rng.normal(size=3)
        b -= a * a.dot(b)
        b /= np.linalg.norm(b)
        k, r, turn = 4 + i % 2, rng.uniform(0.25, 0.6), rng.uniform(0, 2 * math.pi)
        polys.append([c + r * (math.cos(turn + 2 * math.pi * j / k) * a + math.sin(turn + 2 * math.pi * j / k) * b)
                      for j in range(k)])
    return polys


def intersecting_planes():
    """Three mutually perpendicular squares through one point: each passes through the others."""
    polys = []
    for axis in range(3):
        u, v = [np.eye(3)[(axis + 1) % 3], np.eye(3)[(axis + 2) % 3]]
        polys.append([s * u + t * v for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    return polys


def interlocking_tori(n=16, m=8):
    """Two tori linked like chain links, as triangles (two per planar-split quad of each)."""
    polys = []
    for shift, rotate in ((np.array([-0.5, 0, 0]), False), (np.array([0.5, 0, 0]), True)):
        def point(i, j):
            a, b = 2 * math.pi * i / n, 2 * math.pi * j / m
            p = np.array([(0.9 + 0.3 * math.cos(b)) * math.cos(a), (0.9 + 0.3 * math.cos(b)) * math.sin(a), 0.3 * math.sin(b)])
            return shift + (np.array([p[0], p[2], p[1]]) if rotate else p)
        for i in range(n):
            for j in range(m):
                a, b, c, d = point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)
                polys += [[a, b, c], [a, c, d]]
    return polys


SCENES = [("cycle", cycle_bars), ("surfaces", surfaces), ("random-triangles", random_triangles),
          ("random-polygons", random_polygons), ("intersecting-planes", intersecting_planes),
          ("interlocking-tori", interlocking_tori)]


def write_obj(polys, path):
    with open(path, "w") as f:
        for p in polys:
            for v in p:
                f.write("v %.17g %.17g %.17g\n" % tuple(v))
        k = 1
        for p in polys:
            f.write("f " + " ".join(str(k + j) for j in range(len(p))) + "\n")
            k += len(p)


# --- The camera: OpenCV style, so that projecting here is the documented arithmetic. ---

def camera(polys, w, h, direction=(0.35, -0.5, 0.8), fovy_deg=40):
    pts = np.array([v for p in polys for v in p])
    centre = 0.5 * (pts.min(0) + pts.max(0))
    radius = np.linalg.norm(pts - centre, axis=1).max()
    f = 0.5 * h / math.tan(math.radians(fovy_deg) / 2)
    dist = radius / math.sin(math.radians(fovy_deg) / 2) * 1.05
    eye = centre + dist * np.array(direction) / np.linalg.norm(direction)
    z = (centre - eye) / np.linalg.norm(centre - eye)  # forward
    x = np.cross(z, [0, 0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)  # down
    R = np.array([x, y, z])
    pose = np.eye(4)
    pose[:3, :3] = R
    pose[:3, 3] = -R @ eye
    K = np.array([[f, 0, w / 2 - 0.5], [0, f, h / 2 - 0.5], [0, 0, 1]])
    return {"K": K.tolist(), "world_to_camera": pose.tolist(), "near": max(1e-3, dist - 1.5 * radius),
            "far": dist + 1.5 * radius}


def project(cam, v):
    """World point -> (pixel x, pixel y, eye depth): OpenCV's K, then +1/2 (pixel centres)."""
    p = np.array(cam["world_to_camera"]) @ np.append(v, 1.0)
    u = np.array(cam["K"]) @ p[:3]
    return u[0] / p[2] + 0.5, u[1] / p[2] + 0.5, p[2]


def face_id_color(face):
    """hsr's faceid colour (docs/conventions.md): face index + 1 as 24-bit RGB, R the high byte."""
    v = face + 1
    return (v >> 16) & 255, (v >> 8) & 255, v & 255


# --- matplotlib: the camera's projection done here, matplotlib's 3D axes looking straight down the
# depth axis (orthographic), so its depth sort (zsort='average') and drawing are its own. ---

def matplotlib_svg(polys, cam, w, h, path):
    start = time.perf_counter()
    projected = [[project(cam, v) for v in p] for p in polys]
    fig = plt.figure(figsize=(w / 72, h / 72), dpi=72)
    ax = fig.add_axes([0, 0, 1, 1], projection="3d", proj_type="ortho")
    ax.view_init(elev=90, azim=-90)
    depths = [d for p in projected for (_, _, d) in p]
    ax.set_xlim(0, w)
    ax.set_ylim(0, h)
    ax.set_zlim(-max(depths), -min(depths))
    ax.set_box_aspect((w, h, min(w, h)))
    ax.set_axis_off()
    ax.patch.set_visible(False)  # no axes background: the figure's black, as hsr's background
    fig.patch.set_facecolor("black")
    fig.canvas.draw()
    # Where data (x, y) lands on the figure (points from the bottom left; affine for this view), to
    # place each projected vertex at its pixel.
    corners = np.array([[0, w, 0], [0, 0, h], [-min(depths)] * 3])
    px, py, _ = proj3d.proj_transform(corners[0], corners[1], corners[2], ax.get_proj())
    disp = ax.transData.transform(np.c_[px, py])
    sx, bx = (disp[1, 0] - disp[0, 0]) / w, disp[0, 0]
    sy, by = (disp[2, 1] - disp[0, 1]) / h, disp[0, 1]
    verts = [[((x - bx) / sx, ((h - y) - by) / sy, -d) for (x, y, d) in p] for p in projected]
    colors = ["#%02x%02x%02x" % face_id_color(i) for i in range(len(polys))]
    ax.add_collection3d(Poly3DCollection(verts, facecolors=colors, edgecolors="none", linewidths=0))
    fig.savefig(path, format="svg", facecolor="black")
    plt.close(fig)
    return time.perf_counter() - start


# --- Decoding: rsvg-convert to PNG, faceid colours against raycast's ids, away from edges. ---

def rasterize(svg, png, w, h):
    subprocess.run(["rsvg-convert", "-w", str(w), "-h", str(h), "--background-color=black", svg, "-o", png],
                   check=True)
    img = matplotlib.image.imread(png)
    return np.round(img[:, :, :3] * 255).astype(np.int64)


def edge_mask(polygons2d, w, h):
    mask = np.zeros((h, w), bool)
    for p in polygons2d:
        for i in range(len(p)):
            (ax_, ay), (bx_, by_) = p[i], p[(i + 1) % len(p)]
            steps = 1 + int(4 * math.hypot(bx_ - ax_, by_ - ay))
            t = np.linspace(0, 1, steps + 1)
            xs, ys = np.floor(ax_ + t * (bx_ - ax_)).astype(int), np.floor(ay + t * (by_ - ay)).astype(int)
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    x, y = xs + dx, ys + dy
                    ok = (x >= 0) & (y >= 0) & (x < w) & (y < h)
                    mask[y[ok], x[ok]] = True
    return mask


def svg_polygons(path):
    text = open(path).read()
    out = []
    # <polygon points="x,y ..."> and <path d="Mx,y ...ZMx,y ...Z"> (one polygon per subpath).
    for m in re.finditer(r'<(?:polygon points|path d)="([^"]*)"', text):
        for ring in m.group(1).replace("M", " ").split("Z"):
            if ring.strip():
                out.append([tuple(map(float, pair.split(","))) for pair in ring.split()])
    return out


def wrong_pixels(img, ids, mask, ncolors):
    want = np.zeros(ids.shape + (3,), np.int64)
    table = np.array([face_id_color(i) for i in range(ncolors)], np.int64)
    covered = ids >= 0
    want[covered] = table[ids[covered]]
    differs = (img != want).any(axis=2) & ~mask
    return int(differs.sum()), int((~mask).sum())


def run_scene(hsr, out, name, polys, w, h):
    obj, cam_path = os.path.join(out, name + ".obj"), os.path.join(out, name + ".camera.json")
    write_obj(polys, obj)
    cam = camera(polys, w, h)
    with open(cam_path, "w") as f:
        json.dump(cam, f)
    common = [hsr, "render", obj, "--camera", cam_path, "--size", "%dx%d" % (w, h), "--shading", "faceid", "-q"]
    ids_path = os.path.join(out, name + ".ids.npy")
    subprocess.run(common + ["--algorithm", "raycast", "--ids", ids_path], check=True)
    ids = np.load(ids_path)

    ours, stats = os.path.join(out, name + ".hsr.svg"), os.path.join(out, name + ".stats.json")
    start = time.perf_counter()
    subprocess.run(common + ["--algorithm", "newell", "--svg", ours, "--stats", stats], check=True)
    ours_wall = time.perf_counter() - start
    ours_s = json.load(open(stats))["time_ms"]["svg"] / 1e3  # the order and the file, as matplotlib's time
    theirs = os.path.join(out, name + ".matplotlib.svg")
    theirs_s = matplotlib_svg(polys, cam, w, h, theirs)

    # Each tool is judged away from the edges of its own polygons (where an SVG renderer blends):
    # matplotlib's are the faces, hsr's the faces and the pieces newell split them into.
    faces = [[project(cam, v)[:2] for v in p] for p in polys]
    rows = []
    for tool, svg, seconds, wall, edges in (("hsr newell", ours, ours_s, ours_wall, svg_polygons(ours)),
                                            ("matplotlib", theirs, theirs_s, theirs_s, faces)):
        mask = edge_mask(edges, w, h)
        img = rasterize(svg, svg[:-4] + ".png", w, h)
        wrong, tested = wrong_pixels(img, ids, mask, len(polys))
        rows.append((name, len(polys), tool, seconds, wall, os.path.getsize(svg), wrong, tested))
    return rows


def matplotlib_start_s():
    """What a new process pays before matplotlib's 3D SVG export can start: Python and the imports
    (the median of 3), to set beside hsr's whole command, which is a new process too."""
    code = ("import matplotlib; matplotlib.use('svg'); import matplotlib.pyplot; "
            "from mpl_toolkits.mplot3d.art3d import Poly3DCollection; import numpy")
    times = []
    for _ in range(3):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True)
        times.append(time.perf_counter() - start)
    return sorted(times)[1]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    hsr, out = sys.argv[1], sys.argv[2]
    import_matplotlib()
    w, h = (int(sys.argv[3]), int(sys.argv[4])) if len(sys.argv) > 4 else (640, 480)
    os.makedirs(out, exist_ok=True)
    print("| scene | polygons | tool | SVG s | wall s | file KB | wrong pixels | pixels tested |")
    print("|---|---|---|---|---|---|---|---|")
    for name, make in SCENES:
        for r in run_scene(hsr, out, name, make(), w, h):
            print("| %s | %d | %s | %.3f | %.3f | %.1f | %d | %d |" % (r[0], r[1], r[2], r[3], r[4], r[5] / 1e3, r[6], r[7]))
    print("\nmatplotlib's wall s is in process; a new process first spends %.3f s starting Python and "
          "importing matplotlib (median of 3)." % matplotlib_start_s())
    # The picture: matplotlib's and hsr's SVG of the first scene, side by side.
    first = SCENES[0][0]
    # faceid colours of a few faces are nearly black: stretched to full brightness to be seen.
    a = matplotlib.image.imread(os.path.join(out, first + ".matplotlib.png"))[:, :, :3]
    b = matplotlib.image.imread(os.path.join(out, first + ".hsr.png"))[:, :, :3]
    a, b = a / max(a.max(), 1e-9), b / max(b.max(), 1e-9)
    gap = np.ones((a.shape[0], 8, 3), a.dtype)
    matplotlib.image.imsave(os.path.join(out, "side-by-side.png"), np.concatenate([a, gap, b], axis=1))


if __name__ == "__main__":
    main()
