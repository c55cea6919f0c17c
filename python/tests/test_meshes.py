"""Scene.from_open3d and Scene.from_trimesh: the same scene, bit for bit, as from_arrays of the same
arrays, one instance id per mesh, colours per face or averaged from the vertices, and a clear
ValueError for what is not a mesh. Open3D tests run where Debian's python3-open3d is installed;
trimesh (not in Debian) is stood in for by a class with its attributes."""
import numpy as np
import pytest

import hsr

OUTPUTS = ("depth", "face_id", "instance_id", "color")


def same_render(a, b, camera):
    ra, rb = hsr.render(a, camera, outputs=OUTPUTS), hsr.render(b, camera, outputs=OUTPUTS)
    for name in OUTPUTS:
        assert ra[name].tobytes() == rb[name].tobytes(), name
    return ra


def camera():
    return hsr.Camera.look_at((3.5, 2.5, 4.0), (0.5, 0.3, 0.2), 160, 120, fovy_deg=50, near=0.5, far=20)


def box(offset, size=1.0):
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float) * size + offset
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    f = np.array([[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads], np.int64)
    return v, f


# --- Open3D --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def o3d():
    return pytest.importorskip("open3d")


def test_open3d_meshes_render_as_their_arrays(o3d):
    rng = np.random.default_rng(1)
    sphere = o3d.geometry.TriangleMesh.create_sphere(radius=0.7, resolution=12)
    sphere.translate((0.6, 0.4, 0.3))
    sphere.vertex_colors = o3d.utility.Vector3dVector(rng.uniform(0, 1, (len(sphere.vertices), 3)))
    cube = o3d.geometry.TriangleMesh.create_box(1.2, 0.8, 1.0)  # no colours: from_arrays' grey
    cube.translate((-0.4, -0.3, -0.5))
    scene = hsr.Scene.from_open3d([sphere, cube])
    assert list(scene.instance_ids) == [0, 1]
    colors = np.asarray(sphere.vertex_colors)[np.asarray(sphere.triangles)].mean(axis=1)
    arrays = hsr.Scene.from_arrays([np.asarray(sphere.vertices), np.asarray(cube.vertices)],
                                   [np.asarray(sphere.triangles), np.asarray(cube.triangles)], colors=[colors, None])
    out = same_render(scene, arrays, camera())
    assert set(np.unique(out["instance_id"])) == {-1, 0, 1}
    # A face's colour is its vertices' mean: the render of the averaged colours, not of the grey.
    assert hsr.render(hsr.Scene.from_arrays(np.asarray(sphere.vertices), np.asarray(sphere.triangles)), camera(),
                      outputs="color")["color"].tobytes() != \
        hsr.render(hsr.Scene.from_open3d(sphere), camera(), outputs="color")["color"].tobytes()


def test_open3d_one_mesh_and_instance_ids(o3d):
    meshes = [o3d.geometry.TriangleMesh.create_box().translate((2.0 * i, 0, 0)) for i in range(3)]
    assert list(hsr.Scene.from_open3d(meshes, instance_ids=[7, 3, 7]).instance_ids) == [7, 3, 7]
    one = hsr.Scene.from_open3d(meshes[0])
    assert list(one.instance_ids) == [0] and one.face_count == len(meshes[0].triangles)
    same_render(one, hsr.Scene.from_arrays(np.asarray(meshes[0].vertices), np.asarray(meshes[0].triangles)), camera())


def test_open3d_objects_that_are_not_meshes(o3d):
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.zeros((4, 3))))
    with pytest.raises(ValueError, match=r"^mesh: not an Open3D TriangleMesh \(a PointCloud has no \.vertices\)"):
        hsr.Scene.from_open3d(cloud)
    with pytest.raises(ValueError, match=r"^meshes\[1\]: not an Open3D TriangleMesh"):
        hsr.Scene.from_open3d([o3d.geometry.TriangleMesh.create_box(), "box.obj"])
    with pytest.raises(ValueError, match=r"^mesh\.triangles: no faces"):
        hsr.Scene.from_open3d(o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(np.eye(3)),
                                                        o3d.utility.Vector3iVector(np.zeros((0, 3), np.int32))))


# --- trimesh (a stand-in with trimesh's attributes) -----------------------------------------------


class Visual:
    def __init__(self, kind, face_colors=None, vertex_colors=None):
        self.kind, self.face_colors, self.vertex_colors = kind, face_colors, vertex_colors


class Trimesh:
    def __init__(self, vertices, faces, visual=None):
        self.vertices, self.faces, self.visual = vertices, faces, visual


def test_trimesh_face_colours_render_as_their_arrays():
    rng = np.random.default_rng(2)
    (v0, f0), (v1, f1) = box((0, 0, 0)), box((0.5, 0.4, -0.8), 1.3)
    c0 = rng.integers(0, 256, (len(f0), 4), dtype=np.uint8)
    c0[:, 3] = 255
    meshes = [Trimesh(v0, f0, Visual("face", face_colors=c0)), Trimesh(v1, f1, Visual(None))]
    scene = hsr.Scene.from_trimesh(meshes, instance_ids=[4, 9])
    assert list(scene.instance_ids) == [4, 9]
    out = same_render(scene, hsr.Scene.from_arrays([v0, v1], [f0, f1], colors=[c0, None], instance_ids=[4, 9]),
                      camera())
    assert set(np.unique(out["instance_id"])) == {-1, 4, 9}


def test_trimesh_vertex_colours_are_averaged_per_face():
    v, f = box((0, 0, 0))
    vc = np.random.default_rng(3).integers(0, 256, (len(v), 4), dtype=np.uint8)
    scene = hsr.Scene.from_trimesh(Trimesh(v, f, Visual("vertex", vertex_colors=vc)))
    mean = np.rint(vc.astype(float)[f].mean(axis=1)).astype(np.uint8)
    same_render(scene, hsr.Scene.from_arrays(v, f, colors=mean), camera())


def test_trimesh_objects_that_are_not_meshes():
    v, f = box((0, 0, 0))
    with pytest.raises(ValueError, match=r"^mesh: not a trimesh\.Trimesh \(a ndarray has no \.vertices\)"):
        hsr.Scene.from_trimesh(v)
    with pytest.raises(ValueError, match=r"^meshes: an empty list"):
        hsr.Scene.from_trimesh([])
    bad = f.copy()
    bad[0, 0] = 99
    with pytest.raises(ValueError, match=r"^meshes\[1\]\.faces: face 0: vertex index 99 out of range"):
        hsr.Scene.from_trimesh([Trimesh(v, f), Trimesh(v, bad)])
    with pytest.raises(ValueError, match=r"^meshes\[0\]\.vertices: expected shape \(N, 3\)"):
        hsr.Scene.from_trimesh([Trimesh(v[:, :2], f)])
