"""hsr.render: the same bits as the CLI (the C++ render()), OpenCV projection, batches, and the
attributes the module resolves (barycentrics, instance ids, normals)."""
import numpy as np
import pytest

import hsr
from conftest import random_pose, read_png

ALL = ("depth", "face_id", "instance_id", "triangle_id", "barycentric", "normal", "color")


def opencv_camera(width=160, height=120, pose=None, near=None, far=None):
    K = np.array([[150.0, 0.0, 71.3], [0.0, 190.0, 66.8], [0.0, 0.0, 1.0]])  # fx != fy, off centre
    return hsr.Camera.opencv(K, random_pose(np.random.default_rng(3)) if pose is None else pose, width, height,
                             near, far)


@pytest.mark.parametrize("scene_name", ["builtin:cubes", "builtin:sphere?n=20000", "builtin:clutter"])
def test_same_bits_as_the_cli_files(tmp_path, cli, scene_name):
    scene = hsr.load(scene_name)
    camera = scene.default_camera(200, 150)
    (tmp_path / "cam.json").write_text(camera.to_json())
    status, err = cli("render", scene_name, "--camera", tmp_path / "cam.json", "--size", "200x150", "-q",
                      "--depth", tmp_path / "d.npy", "--ids", tmp_path / "ids.npy", "-o", tmp_path / "c.png")
    assert status == 0, err
    out = hsr.render(scene, camera, outputs=("depth", "face_id", "color"))
    assert out["depth"].tobytes() == np.load(tmp_path / "d.npy").tobytes()
    assert np.array_equal(out["face_id"], np.load(tmp_path / "ids.npy"))
    png = read_png(tmp_path / "c.png")
    assert np.array_equal(out["color"][..., :png.shape[2]], png)
    # Other outputs asked for do not change depth or ids (the CLI wrote all buffers).
    more = hsr.render(scene, camera, outputs=ALL)
    assert more["depth"].tobytes() == out["depth"].tobytes()
    assert np.array_equal(more["face_id"], out["face_id"])


def test_depth_only_is_the_clis_depth_only(tmp_path, cli, cubes):
    camera = hsr.Camera.look_at((4, 3, 5), (0, 0, 0), 120, 90, fovy_deg=50)
    status, err = cli("render", "builtin:cubes", "--eye", "4,3,5", "--target", "0,0,0", "--fov", "50", "--size",
                      "120x90", "--outputs", "depth", "--depth-format", "u16:z", "-q", "--depth", tmp_path / "d.npy")
    assert status == 0, err
    out = hsr.render(cubes, camera, outputs="depth", depth_format="u16:z")
    assert out["depth"].tobytes() == np.load(tmp_path / "d.npy").tobytes()


def test_orthographic_and_algorithms_match_the_cli(tmp_path, cli, cubes):
    camera = hsr.Camera.orthographic((3, 4, 5), (0, 0, 0), 6.0, 100, 80)
    for algorithm, params, flags in [("zbuffer", None, []), ("painter", None, []),
                                     ("zbuffer", {"raster": "scanline"}, ["--param", "raster=scanline"])]:
        status, err = cli("render", "builtin:cubes", "--eye", "3,4,5", "--target", "0,0,0", "--ortho", "6", "--size",
                          "100x80", "--algorithm", algorithm, *flags, "-q", "--ids", tmp_path / "i.npy", "--depth",
                          tmp_path / "d.npy")
        assert status == 0, err
        out = hsr.render(cubes, camera, algorithm=algorithm, params=params)
        assert np.array_equal(out["face_id"], np.load(tmp_path / "i.npy")), algorithm
        assert out["depth"].tobytes() == np.load(tmp_path / "d.npy").tobytes(), algorithm


def tiny_triangle_scene(K, pose, pixel, offset, depth=5.0):
    """A triangle of circumradius 0.4 pixel whose centre K projects to pixel + offset (OpenCV
    coordinates: pixel centres at integers), `depth` ahead of the camera."""
    Kinv, R, t = np.linalg.inv(K), pose[:3, :3], pose[:3, 3]
    centre = np.array([pixel[0] + offset[0], pixel[1] + offset[1], 1.0])
    corners = []
    for k in range(3):
        a = 2 * np.pi * k / 3 + 0.3
        uv = centre + 0.4 * np.array([np.cos(a), np.sin(a), 0.0])
        corners.append(R.T @ (Kinv @ uv * depth - t))  # back to world
    return hsr.Scene.from_arrays(np.array(corners), np.array([[0, 1, 2]]))


@pytest.mark.parametrize("pixel,offset", [((10, 20), (0.1, -0.15)), ((150, 3), (-0.12, 0.1)), ((71, 67), (0.0, 0.0))])
def test_opencv_point_lands_in_the_pixel_the_convention_says(pixel, offset):
    K = np.array([[150.0, 0.0, 71.3], [0.0, 190.0, 66.8], [0.0, 0.0, 1.0]])
    pose = random_pose(np.random.default_rng(11))
    scene = tiny_triangle_scene(K, pose, pixel, offset)
    out = hsr.render(scene, hsr.Camera.opencv(K, pose, 160, 120, near=0.5, far=50.0))
    covered = np.argwhere(out["face_id"] == 0)
    assert covered.tolist() == [[pixel[1], pixel[0]]]  # (row, column): floor(u + 0.5), floor(v + 0.5)
    assert out["depth"][pixel[1], pixel[0]] == pytest.approx(5.0, rel=1e-6)


def test_opencv_pose_as_R_t_and_batch_of_poses():
    rng = np.random.default_rng(5)
    poses = np.stack([random_pose(rng) for _ in range(3)])
    K = np.array([[150.0, 0.0, 71.3], [0.0, 190.0, 66.8], [0.0, 0.0, 1.0]])
    cams = hsr.Camera.opencv(K, poses, 160, 120)
    assert isinstance(cams, list) and len(cams) == 3
    scene = hsr.load("builtin:cubes")
    a = hsr.render(scene, hsr.Camera.opencv(K, (poses[1][:3, :3], poses[1][:3, 3]), 160, 120))
    b = hsr.render(scene, cams[1])
    assert np.array_equal(a["face_id"], b["face_id"]) and a["depth"].tobytes() == b["depth"].tobytes()


# 160x120: views rendered straight into the batch's arrays (a view's pixels fill whole cache
# lines); 161x121: rendered in the module's frames and copied there.
@pytest.mark.parametrize("threads", [1, 2, 3])
@pytest.mark.parametrize("size", [(160, 120), (161, 121)])
def test_batch_equals_views_one_by_one(cubes, threads, size):
    rng = np.random.default_rng(7)
    cams = [opencv_camera(*size, pose=random_pose(rng, 5 + i)) for i in range(5)]
    batch = hsr.render(cubes, cams, outputs=ALL, threads=threads)
    for name in ALL:
        assert batch[name].shape[:3] == (5, size[1], size[0])
    for i, cam in enumerate(cams):
        one = hsr.render(cubes, cam, outputs=ALL)
        for name in ALL:
            assert one[name].tobytes() == batch[name][i].tobytes(), (name, i)
    single = hsr.render(cubes, [cams[0]], outputs=ALL)  # a list of one is a batch of one
    assert single["depth"].shape == (1, size[1], size[0])


def test_barycentrics_reconstruct_the_pixel_centre():
    scene = hsr.load("builtin:sphere?n=5000")
    K = np.array([[220.0, 0.0, 80.5], [0.0, 180.0, 57.25], [0.0, 0.0, 1.0]])
    pose = random_pose(np.random.default_rng(2), distance=3.5)
    out = hsr.render(scene, hsr.Camera.opencv(K, pose, 160, 120), outputs=("depth", "triangle_id", "barycentric"))
    ys, xs = np.nonzero(out["triangle_id"] >= 0)
    assert ys.size > 1000
    b = out["barycentric"][ys, xs].astype(np.float64)
    tri = scene.triangles[out["triangle_id"][ys, xs]]
    v = scene.vertices
    world = b[:, 0:1] * v[tri[:, 0]] + b[:, 1:2] * v[tri[:, 1]] + b[:, 2:3] * v[tri[:, 2]]
    cam = world @ pose[:3, :3].T + pose[:3, 3]
    uv = cam @ K.T
    u, w = uv[:, 0] / uv[:, 2], uv[:, 1] / uv[:, 2]
    # OpenCV puts pixel centres at integers: pixel (x, y)'s centre is (x, y).
    assert np.abs(u - xs).max() < 2e-4 and np.abs(w - ys).max() < 2e-4
    assert np.allclose(b.sum(axis=1), 1.0, atol=1e-6)
    assert b.min() > -0.02  # slightly outside only on edges (coverage uses snapped vertices)
    assert np.allclose(cam[:, 2], out["depth"][ys, xs], rtol=1e-5)
    assert not out["barycentric"][out["triangle_id"] < 0].any()  # background: 0


def test_instance_ids_match_the_mesh_of_each_face():
    box = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    quads = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
    offsets = [(-1.2, 0, 0), (0, 0, 0), (1.2, 0.3, -0.4)]
    scene = hsr.Scene.from_arrays([box + o for o in offsets], [quads] * 3, instance_ids=[7, 3, 11],
                                  colors=[None, (255, 0, 0), np.full((6, 3), 0.5)])
    assert scene.face_count == 18 and scene.triangle_count == 36
    assert [m["instance_id"] for m in scene.meshes] == [7, 3, 11]
    out = hsr.render(scene, hsr.Camera.look_at((0, 1, 6), (0, 0, 0), 200, 100), outputs=("face_id", "instance_id"))
    face, inst = out["face_id"], out["instance_id"]
    expected = np.where(face >= 0, np.repeat([7, 3, 11], 6)[np.maximum(face, 0)], -1)
    assert np.array_equal(inst, expected)
    assert set(np.unique(inst)) == {-1, 3, 7, 11}
    assert np.array_equal(scene.face_instance_ids, np.repeat([7, 3, 11], 6))


def test_loaded_scene_instances_are_mesh_positions(cubes):
    out = hsr.render(cubes, cubes.default_camera(160, 120), outputs=("face_id", "instance_id"))
    first = [m["first_face"] for m in cubes.meshes]
    mesh_of_face = np.searchsorted(first, np.arange(cubes.face_count), side="right") - 1
    f = out["face_id"]
    assert np.array_equal(out["instance_id"], np.where(f >= 0, mesh_of_face[np.maximum(f, 0)], -1))
    assert len(set(np.unique(out["instance_id"])) - {-1}) == len(cubes.meshes)


def test_normals_are_the_visible_triangles(cubes):
    out = hsr.render(cubes, cubes.default_camera(160, 120), outputs=("triangle_id", "normal"))
    t = out["triangle_id"]
    v, tri = cubes.vertices, cubes.triangles
    n = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    shown = t >= 0
    assert np.allclose(out["normal"][shown], n[t[shown]], atol=1e-6)
    assert not out["normal"][~shown].any()


def test_cli_instance_ids_and_barycentrics_are_the_modules(tmp_path, cli):
    scene = hsr.load("builtin:cubes")
    camera = scene.default_camera(160, 120)
    (tmp_path / "cam.json").write_text(camera.to_json())
    status, err = cli("render", "builtin:cubes", "--camera", tmp_path / "cam.json", "--size", "160x120", "-q",
                      "--instance-ids", tmp_path / "inst.npy", "--barycentric", tmp_path / "bary.npy")
    assert status == 0, err
    out = hsr.render(scene, camera, outputs=("instance_id", "barycentric"))
    assert np.array_equal(np.load(tmp_path / "inst.npy"), out["instance_id"])
    bary = np.load(tmp_path / "bary.npy")
    assert bary.shape == (120, 160, 3) and bary.tobytes() == out["barycentric"].tobytes()
    status, err = cli("render", "builtin:cubes", "--size", "160x120", "-q", "--instance-ids", tmp_path / "inst.png")
    assert status == 0, err
    png = read_png(tmp_path / "inst.png").astype(np.int64)
    assert np.array_equal((png[..., 0] << 16 | png[..., 1] << 8 | png[..., 2]) - 1,
                          hsr.render(scene, camera, outputs="instance_id")["instance_id"])
    status, err = cli("render", "builtin:cubes", "--outputs", "depth,face", "--barycentric", tmp_path / "b.npy")
    assert status == 2 and "no triangle ids" in err
    status, err = cli("render", "builtin:cubes", "--barycentric", tmp_path / "b.png")
    assert status == 2 and "written as .npy" in err


@pytest.mark.parametrize("algorithm", hsr.algorithms())
def test_every_algorithm_gives_triangle_ids_of_its_faces(cubes, algorithm):
    out = hsr.render(cubes, cubes.default_camera(120, 90), outputs=("face_id", "triangle_id", "barycentric"),
                     algorithm=algorithm)
    t, f = out["triangle_id"], out["face_id"]
    assert (t < cubes.triangle_count).all()
    assert np.array_equal(np.where(t >= 0, cubes.triangle_faces[np.maximum(t, 0)], -1), f)
    assert np.allclose(out["barycentric"][t >= 0].sum(axis=1), 1.0, atol=1e-5)
