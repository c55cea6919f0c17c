"""hsr.matplotlib: exact hidden surfaces for matplotlib's mplot3d (docs/matplotlib.md).

mplot3d paints each polygon whole, ordered by one depth per polygon, so intersecting, interlocking
or cyclically overlapping surfaces come out wrong in PNG, SVG and PDF alike. The collection here
is a drop-in for ``mpl_toolkits.mplot3d.art3d.Poly3DCollection``: at each draw it takes the axes'
projection, orders and splits the polygons with hsr's ``bsp`` or ``newell`` and hands matplotlib
2-D polygons in the right order, so every backend draws the exact picture and an interactive
window re-sorts at every rotation.

    import matplotlib.pyplot as plt
    import hsr.matplotlib as hmpl
    ax = plt.figure().add_subplot(projection="3d")
    hmpl.plot_surface(ax, X, Y, Z1, cmap="viridis")
    hmpl.plot_surface(ax, X, Y, Z2, color="tab:orange", collection=ax.collections[0])

Why the split is exact: matplotlib projects each vertex with the axes' 4x4 matrix and the
perspective divide. That map takes planes to planes (it is projective, and every point in view
has w > 0), so the projected polygons are planar polygons in a 3-D space (x, y, depth) whose
picture is the orthographic view along the depth axis. hsr orders and splits them there, seen by
an orthographic camera looking down that axis; the pieces' (x, y) are then exactly the 2-D
coordinates matplotlib's own collection would draw.
"""
import numpy as np

try:
    import matplotlib.colors as mcolors
    from matplotlib.path import Path
    from matplotlib.tri import Triangulation
    from mpl_toolkits.mplot3d import art3d, proj3d
except ImportError as error:  # pragma: no cover - import error is the message
    raise ImportError("hsr.matplotlib needs matplotlib (Debian: python3-matplotlib)") from error

from . import _hsr

__all__ = ["Poly3DCollection", "plot_surface", "plot_trisurf", "shade_colors", "projected_scene"]

ALGORITHMS = ("bsp", "newell")

# The largest image side hsr's cameras take.
_MAX_SIDE = 16384


def _check_algorithm(algorithm):
    if algorithm not in ALGORITHMS:
        raise ValueError("algorithm: %r is not one of %s" % (algorithm, ", ".join(ALGORITHMS)))
    return algorithm


def projected_scene(points, lengths, width, height, colors=None):
    """The hsr scene of polygons given in image pixels and depth, and the camera that sees them.

    points: (P, 3) float, the polygons' vertices one polygon after the other, as (x right, y down)
    pixels of a width x height image and a depth, larger farther (any affine function of
    matplotlib's projected depth); lengths: (N,) vertex counts; colors: (N, 4) RGBA floats 0-1 or
    None. Polygons with a non-finite vertex or fewer than three vertices are left out. The camera
    is orthographic down the depth axis, its pixels those of the points. Returns (scene, camera,
    polygon_of_face), polygon_of_face mapping hsr face ids to polygon indices; None when no
    polygon is left.
    """
    points = np.asarray(points, np.float64)
    lengths = np.asarray(lengths, np.int64)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    if not len(lengths):
        return None
    finite = np.isfinite(points).all(axis=1)
    ok_poly = (np.add.reduceat(~finite, starts) == 0) & (lengths >= 3)
    if not ok_poly.any():
        return None
    used = points[np.repeat(ok_poly, lengths), 2]
    lo, hi = used.min(), used.max()
    world = points.copy()
    world[:, 2] = (points[:, 2] - lo) / max(hi - lo, 1e-300) * 2.0 - 1.0  # depth into [-1, 1]: affine
    vertices, faces, face_colors, polygon_of_face = [], [], [], []
    for k in np.unique(lengths[ok_poly]):
        chosen = np.flatnonzero(ok_poly & (lengths == k))
        index = (starts[chosen][:, None] + np.arange(k)).ravel()
        vertices.append(world[index])
        faces.append(np.arange(len(index), dtype=np.int64).reshape(-1, int(k)))
        face_colors.append(np.ones((len(chosen), 4)) if colors is None else np.clip(colors[chosen], 0, 1))
        polygon_of_face.append(chosen)
    scene = _hsr.Scene.from_arrays(vertices, faces, colors=face_colors)
    # Looking down +depth with up = -y: world (x, y) is pixel (x, y) (the tests check it).
    camera = _hsr.Camera.orthographic((width / 2, height / 2, -4.0), (width / 2, height / 2, 0.0), height, width,
                                      height, up=(0.0, -1.0, 0.0), near=1.0, far=8.0)
    return scene, camera, np.concatenate(polygon_of_face)


def _on_boundary(piece, outline, tolerance):
    """Per edge of `piece` (K, 2): whether it lies on an edge of the polygon `outline` (M, 2)."""
    a, b = piece, np.roll(piece, -1, axis=0)
    o, e = outline, np.roll(outline, -1, axis=0) - outline
    length = np.maximum(np.hypot(e[:, 0], e[:, 1]), 1e-300)

    def distance(p):  # (K, M): distance of each point from each outline edge's line
        d = p[:, None, :] - o[None, :, :]
        return np.abs(d[..., 0] * e[None, :, 1] - d[..., 1] * e[None, :, 0]) / length[None, :]

    return ((distance(a) <= tolerance) & (distance(b) <= tolerance)).any(axis=1)


class Poly3DCollection(art3d.Poly3DCollection):
    """``mpl_toolkits.mplot3d.art3d.Poly3DCollection`` drawn with exact hidden surfaces.

    The same arguments (``zsort`` is accepted and ignored: hsr orders), plus ``algorithm`` ("bsp",
    the default, or "newell") and ``params`` (hsr's parameters of that algorithm, a dict). Polygons
    should be planar (as for matplotlib's own: a non-planar one is drawn as hsr's triangles of it).
    Edges (``edgecolors``, ``linewidths``) are drawn along the polygons' own outlines only, never
    along the lines where hsr split them. Exact among the polygons of one collection; put surfaces
    that meet in one collection (``add_polygons`` or the helpers' ``collection=``).
    """

    def __init__(self, verts, *args, algorithm="bsp", params=None, zsort="average", **kwargs):
        self._algorithm = _check_algorithm(algorithm)
        if params is not None and not isinstance(params, dict):
            raise ValueError("params: expected a dict of name: value")
        self._params = params
        super().__init__(verts, *args, zsort=zsort, **kwargs)

    def set_algorithm(self, algorithm):
        """Sets the ordering algorithm, "bsp" or "newell"."""
        self._algorithm = _check_algorithm(algorithm)
        self.stale = True

    def get_algorithm(self):
        return self._algorithm

    def add_polygons(self, verts, facecolors):
        """Appends polygons (a list of (K, 3) arrays) with their face colours (one colour or one per
        polygon), so that they are ordered exactly with the ones already here."""
        old = [self._vec[:3, sl].T for sl in self._segslices]
        colors = mcolors.to_rgba_array(facecolors)
        if len(colors) == 1:
            colors = np.repeat(colors, len(verts), axis=0)
        if len(colors) != len(verts):
            raise ValueError("facecolors: %d colours for %d polygons" % (len(colors), len(verts)))
        mine = self._facecolor3d
        if len(mine) != len(old):
            mine = np.repeat(mine, len(old), axis=0)
        self.set_verts(old + [np.asarray(v, float) for v in verts])
        self.set_facecolor(np.concatenate([mine, colors]))

    @staticmethod
    def _per_polygon(colors, n):
        colors = np.asarray(colors).reshape(-1, 4)
        if len(colors) == n:
            return colors
        if len(colors) == 0:
            return np.zeros((n, 4))
        return np.repeat(colors[:1], n, axis=0)

    def do_3d_projection(self):
        # Colour mapping as matplotlib's own (the 3-D colours stay in the user's order).
        if self._A is not None:
            self.update_scalarmappable()
            if self._face_is_mapped:
                self._facecolor3d = self._facecolors
            if self._edge_is_mapped:
                self._edgecolor3d = self._edgecolors
        n = len(self._segslices)
        txs, tys, tzs = proj3d._proj_transform_vec(self._vec, self.axes.M)
        faces = self._per_polygon(self._facecolor3d, n)
        edges = self._per_polygon(self._edgecolor3d, n)  # none: no edges, as matplotlib's own
        lengths = np.array([sl.stop - sl.start for sl in self._segslices], np.int64)
        points = np.column_stack([txs, tys, tzs])
        paths, face2d, edge2d = self._painted(points, lengths, faces, edges)
        self._paths = paths
        self._facecolors2d = np.asarray(face2d).reshape(-1, 4)
        self._edgecolors2d = np.asarray(edge2d).reshape(-1, 4)
        if self._sort_zpos is not None:
            zvec = np.array([[0], [0], [self._sort_zpos], [1]])
            return proj3d._proj_transform_vec(zvec, self.axes.M)[2][0]
        return np.min(tzs) if tzs.size else np.nan

    def _draws_edges(self, edges):
        widths = np.atleast_1d(self.get_linewidth())
        return len(edges) > 0 and (edges[:, 3] > 0).any() and (widths > 0).any()

    def _painted(self, points, lengths, faces, edges):
        """The 2-D paths in painting order: per paint group one compound path of its pieces
        (filled), followed, when edges show, by a path of the group's pieces' outline edges."""
        # In the pixels of the image being drawn (the canvas at the renderer's dpi), so that hsr's
        # paint groups and repaints work at the scale of the anti-aliasing.
        to_display = self.axes.transData
        width = int(min(max(np.ceil(self.figure.bbox.width), 1), _MAX_SIDE))
        height = int(min(max(np.ceil(self.figure.bbox.height), 1), _MAX_SIDE))
        pixels = to_display.transform(points[:, :2])
        pixels[:, 1] = height - pixels[:, 1]
        found = projected_scene(np.column_stack([pixels, points[:, 2]]), lengths, width, height, faces)
        if found is None:
            return [], np.zeros((0, 4)), np.zeros((0, 4))
        scene, camera, polygon_of_face = found
        painted = _hsr.screen_polygons(scene, camera, algorithm=self._algorithm, params=self._params, shading="flat")
        offsets, group = painted["offsets"], painted["group"]
        polygon = polygon_of_face[painted["face_id"]]
        drawn = painted["points"].copy()
        drawn[:, 1] = height - drawn[:, 1]
        xy = to_display.inverted().transform(drawn)
        count = np.diff(offsets)
        # Each piece's vertices, then one more (ignored) for CLOSEPOLY.
        n = len(count)
        if n == 0:
            return [], np.zeros((0, 4)), np.zeros((0, 4))
        closed = np.empty((len(xy) + n, 2))
        where = np.arange(len(xy)) + np.repeat(np.arange(n), count)
        closed[where] = xy
        ends = offsets[1:] + np.arange(n)
        closed[ends] = xy[offsets[:-1]]
        codes = np.full(len(closed), Path.LINETO, np.uint8)
        codes[offsets[:-1] + np.arange(n)] = Path.MOVETO
        codes[ends] = Path.CLOSEPOLY
        group_start = np.flatnonzero(np.r_[True, group[1:] != group[:-1]])
        cut = (offsets[group_start] + group_start)[1:]
        vertex_groups, code_groups = np.split(closed, cut), np.split(codes, cut)
        first_polygon = polygon[group_start]
        draw_edges = self._draws_edges(edges)
        paths, face2d, edge2d = [], [], []
        none = np.zeros(4)
        starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
        ends_of_group = np.r_[group_start[1:], n]
        for g, (v, c) in enumerate(zip(vertex_groups, code_groups)):
            p = first_polygon[g]
            paths.append(Path(v, c))
            face2d.append(faces[p])
            edge2d.append(none if draw_edges else edges[p])
            if draw_edges:
                paths.append(self._outline_path(xy, offsets, group_start[g], ends_of_group[g],
                                                points[starts[p]:starts[p] + lengths[p], :2]))
                face2d.append(none)
                edge2d.append(edges[p])
        return paths, face2d, edge2d

    @staticmethod
    def _outline_path(xy, offsets, first, last, outline):
        """The edges of pieces first..last-1 that lie on the polygon's outline (a repaint's too:
        its fill covers the stroke drawn with its piece)."""
        tolerance = 1e-9 * max(np.ptp(outline[:, 0]), np.ptp(outline[:, 1]), 1e-300)
        vertices, codes = [], []
        for i in range(first, last):
            piece = xy[offsets[i]:offsets[i + 1]]
            on = _on_boundary(piece, outline, tolerance)
            for k in np.flatnonzero(on):
                vertices += [piece[k], piece[(k + 1) % len(piece)]]
                codes += [Path.MOVETO, Path.LINETO]
        if not vertices:
            return Path(np.zeros((1, 2)), [Path.MOVETO])
        return Path(np.array(vertices), codes)


def _add(ax, verts, colors, collection, algorithm, params, kwargs):
    if collection is not None:
        if not isinstance(collection, Poly3DCollection):
            raise ValueError("collection: expected an hsr.matplotlib.Poly3DCollection")
        collection.add_polygons(verts, colors)
        return collection
    col = Poly3DCollection(verts, facecolors=colors, algorithm=algorithm, params=params, **kwargs)
    ax.add_collection3d(col)
    return col


def _colors(ax, verts, color, cmap, norm, vmin, vmax, shade, lightsource, zvalues):
    """Per polygon RGBA as mplot3d colours its surfaces: a colormap of each polygon's mean z
    (not shaded), else one colour shaded by the polygons' normals (shade=True, the axes' light)."""
    if cmap is not None:
        norm = norm if norm is not None else mcolors.Normalize(vmin, vmax)
        norm.autoscale_None(zvalues)
        return mcolors.to_rgba_array(_colormap(cmap)(norm(zvalues)))
    color = color if color is not None else ax._get_lines.get_next_color()
    colors = np.repeat(mcolors.to_rgba_array(color), len(verts), axis=0)
    return shade_colors(ax, verts, colors, lightsource) if shade else colors


def shade_colors(ax, verts, colors, lightsource=None):
    """Per-polygon colours (N, 4) shaded by the polygons' normals as mplot3d shades its surfaces
    (``shade=True``; its default light unless ``lightsource``)."""
    colors = mcolors.to_rgba_array(colors)
    # matplotlib 3.6 has them on the axes, later versions in art3d.
    generate = getattr(art3d, "_generate_normals", None) or ax._generate_normals
    shade = getattr(art3d, "_shade_colors", None) or ax._shade_colors
    return shade(colors, generate(verts), lightsource)


def _colormap(cmap):
    import matplotlib

    return matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap


def _check_shape(name, a, shape=None):
    a = np.asarray(a, dtype=float)
    if shape is not None and a.shape != shape:
        raise ValueError("%s: shape %s, expected %s" % (name, a.shape, shape))
    return a


def plot_surface(ax, X, Y, Z, *, color=None, cmap=None, facecolors=None, norm=None, vmin=None, vmax=None, shade=None,
                 lightsource=None, rstride=1, cstride=1, algorithm="bsp", params=None, collection=None, **kwargs):
    """``ax.plot_surface(X, Y, Z, ...)`` with exact hidden surfaces: each grid cell is two triangles
    (planar, so hsr splits them exactly) coloured as mplot3d colours the cell (``color`` shaded,
    ``cmap`` of the cell's mean z, or ``facecolors`` per grid point, shaded; ``shade`` defaults to
    no colormap). Returns the
    collection (``collection``, when given, receives the triangles instead: several surfaces in one
    collection are ordered exactly with each other). Other keywords go to the collection."""
    shade = cmap is None if shade is None else shade
    Z = _check_shape("Z", Z)
    if Z.ndim != 2 or Z.shape[0] < 2 or Z.shape[1] < 2:
        raise ValueError("Z: expected a 2-D grid of at least 2x2 values, got shape %s" % (Z.shape,))
    X, Y = _check_shape("X", np.broadcast_to(X, Z.shape), Z.shape), _check_shape("Y", np.broadcast_to(Y, Z.shape), Z.shape)
    for name, stride in (("rstride", rstride), ("cstride", cstride)):
        if int(stride) != stride or stride < 1:
            raise ValueError("%s: expected a positive integer, got %r" % (name, stride))
    rows = np.unique(np.r_[np.arange(0, Z.shape[0], rstride), Z.shape[0] - 1])
    cols = np.unique(np.r_[np.arange(0, Z.shape[1], cstride), Z.shape[1] - 1])
    P = np.stack([X[np.ix_(rows, cols)], Y[np.ix_(rows, cols)], Z[np.ix_(rows, cols)]], axis=-1)
    # Each cell's corners in mplot3d's order (its normals, so its shading, point the same way).
    a, b, c, d = P[:-1, :-1], P[:-1, 1:], P[1:, 1:], P[1:, :-1]
    quads = np.stack([a, b, c, d], axis=2).reshape(-1, 4, 3)
    keep = np.isfinite(quads).all(axis=(1, 2))  # cells with a NaN are left out (masked data)
    if facecolors is not None:
        cells = mcolors.to_rgba_array(np.asarray(facecolors)[np.ix_(rows[:-1], cols[:-1])].reshape(-1, np.shape(facecolors)[-1]))
        colors = shade_colors(ax, quads, cells, lightsource) if shade else cells
    else:
        colors = _colors(ax, quads, color, cmap, norm, vmin, vmax, shade, lightsource, quads[:, :, 2].mean(axis=1))
    quads, colors = quads[keep], colors[keep]
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]], axis=1).reshape(-1, 3, 3)
    had_data = ax.has_data()
    col = _add(ax, list(triangles), np.repeat(colors, 2, axis=0), collection, algorithm, params, kwargs)
    ax.auto_scale_xyz(X, Y, Z, had_data)
    return col


def plot_trisurf(ax, *args, color=None, cmap=None, norm=None, vmin=None, vmax=None, shade=None, lightsource=None,
                 algorithm="bsp", params=None, collection=None, **kwargs):
    """``ax.plot_trisurf(...)`` with exact hidden surfaces: the same triangulation arguments
    (x, y[, triangles], z, or a Triangulation and z), the triangles coloured as mplot3d colours
    them. Returns the collection (see plot_surface for ``collection``)."""
    shade = cmap is None if shade is None else shade
    tri, args, kwargs = Triangulation.get_from_args_and_kwargs(*args, **kwargs)
    if not args:
        raise ValueError("z: missing (plot_trisurf(ax, x, y, z) or plot_trisurf(ax, triangulation, z))")
    z = _check_shape("z", args[0], (len(tri.x),))
    triangles = tri.get_masked_triangles()
    verts = np.stack([tri.x[triangles], tri.y[triangles], z[triangles]], axis=-1)
    colors = _colors(ax, verts, color, cmap, norm, vmin, vmax, shade, lightsource, verts[:, :, 2].mean(axis=1))
    had_data = ax.has_data()
    col = _add(ax, list(verts), colors, collection, algorithm, params, kwargs)
    ax.auto_scale_xyz(tri.x, tri.y, z, had_data)
    return col
