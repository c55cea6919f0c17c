"""hsr.matplotlib: mplot3d figures drawn through matplotlib's Agg, each polygon filled with its
own colour (8 levels apart from any other's), decoded pixel by pixel against hsr's exact face ids of the
same projected polygons (raycast). Away from the edges of the visible picture, hsr.matplotlib's
picture is exact on the scenes of bench/peer/vector_peer.py, intersecting planes and interlocking
tori, in two views each (the order is made again at each draw); matplotlib's own
Poly3DCollection is wrong there. SVG and PDF hold polygons, not an embedded image."""
import io
import os
import sys

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.mplot3d import art3d, proj3d  # noqa: E402

import hsr  # noqa: E402
import hsr.matplotlib as hmpl  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench", "peer"))
import vector_peer  # noqa: E402  (the peer's scenes, NumPy only)

W, H = 400, 300
VIEWS = [(55, -60), (-35, 130)]
SCENES = dict(vector_peer.SCENES)


def palette(n):
    """Colour i: i in base 32, a digit per channel, 8 levels apart (so any two faces differ by 8
    of 255 in some channel; up to 32,768 faces)."""
    i = np.arange(n)
    return np.column_stack([i >> 10 & 31, i >> 5 & 31, i & 31]) * 8 + 4


def decode(rgb, n):
    """The face whose palette colour is within 2 of 255 of the pixel in every channel, else -2;
    within 2 of black is -1, the background. The tolerance admits the renderer's rounding of
    coverage (Agg places vertices to 1/256 pixel), no blend of two faces beyond a faint one."""
    rgb = rgb.astype(np.int64)
    digits = (rgb - 4 + 4) // 8  # nearest level
    face = digits[..., 0] << 10 | digits[..., 1] << 5 | digits[..., 2]
    close = (np.abs(rgb - (digits * 8 + 4)) <= 2).all(axis=-1) & (face < n)
    return np.where((rgb <= 2).all(axis=-1), -1, np.where(close, face, -2))


def figure(polys, view, make, colors=None, background="black"):
    """A bare 3-D axes filling a W x H figure, the polygons added by make(ax, verts, colors)
    (colors: the palette unless given; make may shade them)."""
    fig = plt.figure(figsize=(W / 100, H / 100), dpi=100, facecolor=background)
    ax = fig.add_axes([0, 0, 1, 1], projection="3d")
    ax.set_axis_off()
    ax.patch.set_visible(False)
    pts = np.array([v for p in polys for v in p])
    lo, hi = pts.min(0), pts.max(0)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(hi - lo)
    ax.view_init(*view)
    col = make(ax, [np.asarray(p, float) for p in polys], palette(len(polys)) / 255.0 if colors is None else colors)
    return fig, ax, col


def hsr_collection(ax, verts, colors, algorithm="bsp"):
    col = hmpl.Poly3DCollection(verts, facecolors=colors, edgecolors="none", algorithm=algorithm)
    ax.add_collection3d(col)
    return col


# Scenes made of several objects, each in its own collection as a user adds them (two
# plot_surface calls): matplotlib orders whole collections by one depth each.
OBJECTS = {"surfaces": 2, "interlocking-tori": 2}


def own_collections(name):
    def make(ax, verts, colors):
        parts = OBJECTS.get(name, 1)
        size = len(verts) // parts
        for k in range(parts):
            ax.add_collection3d(art3d.Poly3DCollection(verts[k * size:(k + 1) * size],
                                                       facecolors=colors[k * size:(k + 1) * size], edgecolors="none"))
    return make


def agg_pixels(fig):
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()


def reference(ax, polys, samples=4):
    """raycast's face ids of the polygons as the axes project them, pixel for pixel (row 0 at the
    top), in an orthographic view down the projected depth axis; and the pixels away from edges:
    the samples x samples points of each pixel of the 3x3 pixels around it all show one face (or
    the background), so no visible edge, however thin the sliver it bounds, comes near."""
    pts = np.array([v for p in polys for v in p], float)
    x, y, z = proj3d.proj_transform(pts[:, 0], pts[:, 1], pts[:, 2], ax.get_proj())
    disp = ax.transData.transform(np.column_stack([x, y]))
    # The figure's pixels times `samples`, y down, and matplotlib's depth.
    points = np.column_stack([disp[:, 0] * samples, (H - disp[:, 1]) * samples, z])
    scene, camera, order = hmpl.projected_scene(points, [len(p) for p in polys], W * samples, H * samples)
    r = camera.resolve(scene)
    m = np.asarray(r["pixel_from_camera"]) @ np.asarray(r["camera_from_world"])
    assert np.allclose(m[:2, :2], np.eye(2)) and np.allclose(m[:2, 3], 0), m  # world (x, y) is pixel (x, y)
    fine = hsr.render(scene, camera, outputs=("face_id",), algorithm="raycast")["face_id"]
    fine = np.where(fine >= 0, np.asarray(order)[np.maximum(fine, 0)], -1).reshape(H, samples, W, samples)
    ids = fine[:, samples // 2, :, samples // 2]  # the sample at each pixel's centre
    one = (fine == ids[:, None, :, None]).all(axis=(1, 3))  # every sample of the pixel shows its face
    pad, same = np.pad(one, 1), np.pad(ids, 1, mode="edge")
    inside = np.ones(ids.shape, bool)
    for dy in range(3):
        for dx in range(3):
            inside &= pad[dy:dy + H, dx:dx + W] & (same[dy:dy + H, dx:dx + W] == ids)
    return ids, inside


def wrong_pixels(name, view, make):
    polys = SCENES[name]()
    fig, ax, _ = figure(polys, view, make)
    got = decode(agg_pixels(fig), len(polys))
    want, inside = reference(ax, polys)
    plt.close(fig)
    return int((inside & (got != want)).sum()), int(inside.sum())


@pytest.mark.parametrize("name", sorted(SCENES))
@pytest.mark.parametrize("view", VIEWS)
def test_hsr_collection_is_exact_away_from_edges(name, view):
    wrong, tested = wrong_pixels(name, view, hsr_collection)
    assert tested > W * H // 3
    assert wrong == 0, "%d of %d pixels away from edges show the wrong face" % (wrong, tested)


def test_newell_is_exact_too():
    wrong, _ = wrong_pixels("random-polygons", VIEWS[0], lambda ax, v, c: hsr_collection(ax, v, c, "newell"))
    assert wrong == 0


@pytest.mark.parametrize("name", sorted(SCENES))
def test_matplotlibs_own_collections_are_wrong_on_the_same_scenes(name):
    # The check can fail: mplot3d's one depth per polygon (and per collection) misorders these.
    assert sum(wrong_pixels(name, view, own_collections(name))[0] for view in VIEWS) > 0


def test_rotation_orders_again_at_each_draw():
    polys = SCENES["intersecting-planes"]()
    fig, ax, col = figure(polys, VIEWS[0], hsr_collection)
    for view in VIEWS:
        ax.view_init(*view)
        got = decode(agg_pixels(fig), len(polys))
        want, inside = reference(ax, polys)
        assert int((inside & (got != want)).sum()) == 0, view
    plt.close(fig)


def test_svg_and_pdf_hold_polygons_not_images():
    polys = SCENES["interlocking-tori"]()
    fig, _, _ = figure(polys, VIEWS[0], hsr_collection)
    svg, pdf = io.BytesIO(), io.BytesIO()
    fig.savefig(svg, format="svg")
    fig.savefig(pdf, format="pdf")
    plt.close(fig)
    text = svg.getvalue().decode()
    assert "<image" not in text
    assert text.count("<path") > len(polys) // 4
    data = pdf.getvalue()
    assert b"/Subtype /Image" not in data


def test_helpers_draw_surfaces_and_keep_matplotlibs_colours():
    X, Y = np.meshgrid(np.linspace(-1, 1, 12), np.linspace(-1, 1, 10))
    fig = plt.figure(figsize=(3, 2), dpi=50)
    ax = fig.add_subplot(projection="3d")
    col = hmpl.plot_surface(ax, X, Y, np.sin(2 * X) * Y, color="tab:blue")
    theirs = ax.plot_surface(X, Y, np.sin(2 * X) * Y, color="tab:blue")
    fig.canvas.draw()
    assert len(col._vec[0]) == 11 * 9 * 2 * 3  # two triangles a cell
    # Each cell's two triangles carry the cell's shaded colour, as mplot3d shades the cell.
    np.testing.assert_allclose(col._facecolor3d[::2], theirs._facecolor3d, atol=1e-12)
    tri = hmpl.plot_trisurf(ax, X.ravel(), Y.ravel(), (X * Y).ravel(), cmap="viridis", collection=col)
    assert tri is col and len(col._segslices) == 11 * 9 * 2 + len(tri._segslices) - 11 * 9 * 2
    fig.canvas.draw()
    plt.close(fig)


def test_bad_arguments_raise_value_error_naming_the_parameter():
    with pytest.raises(ValueError, match="algorithm"):
        hmpl.Poly3DCollection([np.zeros((3, 3))], algorithm="zbuffer")
    ax = plt.figure().add_subplot(projection="3d")
    with pytest.raises(ValueError, match="Z"):
        hmpl.plot_surface(ax, np.zeros(3), np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="rstride"):
        hmpl.plot_surface(ax, np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((2, 2)), rstride=0)
    with pytest.raises(ValueError, match="collection"):
        hmpl.plot_surface(ax, np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((2, 2)), collection=object())
    plt.close("all")


def test_screen_polygons_arrays():
    scene = hsr.load("builtin:painter-cycle")
    camera = scene.default_camera(160, 120)
    r = hsr.screen_polygons(scene, camera, algorithm="newell", shading="faceid")
    n = len(r["face_id"])
    assert n > 3 and r["offsets"].shape == (n + 1,) and r["points"].shape == (r["offsets"][-1], 2)
    assert r["color"].shape == (n, 4) and r["color"].dtype == np.uint8
    c = r["color"].astype(np.int64)  # faceid colours: face index + 1 as 24-bit RGB
    assert ((c[:, 0] << 16 | c[:, 1] << 8 | c[:, 2]) - 1 == r["face_id"]).all()
    assert (np.diff(r["group"]) >= 0).all() and r["group"][0] == 0
    assert ((r["points"] >= 0) & (r["points"] <= [160, 120])).all()
    with pytest.raises(ValueError, match="algorithm 'zbuffer'"):
        hsr.screen_polygons(scene, camera, algorithm="zbuffer")
    with pytest.raises(ValueError, match="shading"):
        hsr.screen_polygons(scene, camera, shading="pretty")


def test_edges_follow_the_polygons_outlines_not_the_splits():
    polys = SCENES["intersecting-planes"]()
    fig, ax, _ = figure(polys, VIEWS[0], lambda ax, v, c: ax.add_collection3d(
        hmpl.Poly3DCollection(v, facecolors=c, edgecolors="white", linewidths=1.0)))
    fig.canvas.draw()
    col = ax.collections[0]
    # Fill paths (no edge) and edge paths (no fill) alternate. Every stroked segment lies on a
    # polygon's outline (none on a split), and together they cover the outlines (a repainted
    # part's edge may be stroked twice).
    edges = [p for p, f in zip(col.get_paths(), col.get_facecolor()) if f[3] == 0]
    assert len(edges) == len(col.get_paths()) // 2
    pts = np.array([v for p in polys for v in p], float)
    x, y, _ = proj3d.proj_transform(pts[:, 0], pts[:, 1], pts[:, 2], ax.get_proj())
    corners = np.split(np.c_[x, y], 3)
    starts = np.concatenate(corners)
    directions = np.concatenate([np.roll(q, -1, axis=0) - q for q in corners])

    def off_outline(p):  # (K,) distance of points from the nearest outline edge's line
        d = p[:, None, :] - starts[None]
        cross = np.abs(d[..., 0] * directions[None, :, 1] - d[..., 1] * directions[None, :, 0])
        return cross / np.hypot(directions[:, 0], directions[:, 1])[None]

    for p in edges:
        a, b = p.vertices[0::2], p.vertices[1::2]
        assert (np.maximum(off_outline(a), off_outline(b)).min(axis=1) < 1e-9).all()
    drawn = sum(np.hypot(*(p.vertices[1::2] - p.vertices[0::2]).T).sum() for p in edges)
    outline = np.hypot(directions[:, 0], directions[:, 1]).sum()
    assert outline * (1 - 1e-9) <= drawn < outline * 1.05
    plt.close(fig)
