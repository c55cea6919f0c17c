"""Scenes from the meshes vision users hold: Open3D and trimesh, duck-typed (neither is imported).

hsr.Scene.from_open3d(mesh_or_list) and hsr.Scene.from_trimesh(mesh_or_list) read each mesh's
vertices, faces and colours as NumPy arrays and build the scene with hsr.Scene.from_arrays: one mesh
of the scene, with one instance id, per mesh given (default 0, 1, 2, ...).
"""
import re

import numpy as np

from . import _hsr


def _array(mesh, attribute, name, kind):
    """np.asarray(mesh.attribute), or ValueError naming the mesh when it has no such attribute."""
    if not hasattr(mesh, attribute):
        raise ValueError(f"{name}: not {kind} (a {type(mesh).__name__} has no .{attribute})")
    try:
        return np.asarray(getattr(mesh, attribute))
    except Exception as e:  # an attribute NumPy cannot read as an array
        raise ValueError(f"{name}: .{attribute} is not convertible to a NumPy array ({e})") from None


def _face_colors_from_vertices(colors, faces):
    """Per-face colours, the mean of each face's vertex colours: floats 0-1 stay floats; integer
    0-255 colours are rounded back to uint8 (from_arrays reads floats as 0-1)."""
    if colors.ndim != 2 or colors.shape[1] not in (3, 4) or faces.min() < 0 or faces.max() >= len(colors):
        return None  # (from_arrays then names what is wrong with the faces, or leaves the mesh grey)
    mean = colors.astype(np.float64)[faces].mean(axis=1)
    return mean if colors.dtype.kind == "f" else np.rint(mean).astype(np.uint8)


def _scene(meshes, kind, faces_attribute, colors_of, instance_ids, names):
    """from_arrays of one mesh or a list of them: each mesh's .vertices, its faces (attribute
    `faces_attribute`) and colors_of(mesh, faces) (None: from_arrays' grey). ValueErrors name the
    mesh and its attribute ("meshes[2].triangles: ...") instead of from_arrays' parameters."""
    many = isinstance(meshes, (list, tuple))
    if many and not meshes:
        raise ValueError("meshes: an empty list of meshes")
    vertices, faces, colors = [], [], []
    for i, mesh in enumerate(meshes if many else [meshes]):
        name = f"meshes[{i}]" if many else "mesh"
        vertices.append(_array(mesh, "vertices", name, kind))
        faces.append(_array(mesh, faces_attribute, name, kind))
        f = faces[-1]
        colors.append(colors_of(mesh, f) if f.ndim == 2 and f.size and f.dtype.kind in "iu" else None)
    try:
        if not many:
            return _hsr.Scene.from_arrays(vertices[0], faces[0], colors=colors[0], instance_ids=instance_ids,
                                          names=names)
        return _hsr.Scene.from_arrays(vertices, faces, colors=colors if any(c is not None for c in colors) else None,
                                      instance_ids=instance_ids, names=names)
    except ValueError as e:
        attributes = {"vertices": "vertices", "faces": faces_attribute, "colors": "colors"}

        def renamed(m):
            where = f"meshes{m.group(2)}" if m.group(2) else "mesh"
            return f"{where}.{attributes[m.group(1)]}:"

        raise ValueError(re.sub(r"^(vertices|faces|colors)(\[\d+\])?:", renamed, str(e))) from None


def _open3d_colors(mesh, faces):
    """Open3D: the mean of the vertex colours (floats 0-1) per face, when the mesh has them."""
    colors = np.asarray(getattr(mesh, "vertex_colors", []))
    return _face_colors_from_vertices(colors, faces) if len(colors) else None


def _trimesh_colors(mesh, faces):
    """trimesh: visual.kind "vertex": the mean of the vertex colours per face; "face" (or no .kind):
    the face colours; None (no colours set): none."""
    visual = getattr(mesh, "visual", None)
    kind = getattr(visual, "kind", "face")
    if kind == "vertex":
        return _face_colors_from_vertices(np.asarray(visual.vertex_colors), faces)
    face_colors = getattr(visual, "face_colors", None) if kind == "face" else None
    return None if face_colors is None else np.asarray(face_colors)


def from_open3d(meshes, instance_ids=None, names=None):
    """A scene from an Open3D TriangleMesh or a list of them, one scene mesh (and instance id) each.

    Reads .vertices (Vector3dVector) and .triangles (Vector3iVector) through np.asarray, keeping the
    triangles' winding; a mesh with .vertex_colors (floats 0-1) gets per-face colours, the mean of
    its vertices' colours, otherwise from_arrays' default grey. instance_ids: one integer >= 0 per
    mesh (default 0, 1, 2, ...); names: one per mesh. Open3D is not imported: any object with these
    attributes is read. Raises ValueError for an object that is not such a mesh.
    """
    return _scene(meshes, "an Open3D TriangleMesh", "triangles", _open3d_colors, instance_ids, names)


def from_trimesh(meshes, instance_ids=None, names=None):
    """A scene from a trimesh.Trimesh or a list of them, one scene mesh (and instance id) each.

    Reads .vertices and .faces; colours from .visual when it holds some: with visual.kind "vertex",
    the mean of .vertex_colors per face; with "face" (or no .kind), .face_colors (uint8 RGBA);
    otherwise (kind None: no colours set) from_arrays' default grey. instance_ids: one integer >= 0
    per mesh (default 0, 1, 2, ...); names: one per mesh. trimesh is not imported: any object with
    these attributes is read. Raises ValueError for an object that is not such a mesh.
    """
    return _scene(meshes, "a trimesh.Trimesh", "faces", _trimesh_colors, instance_ids, names)
