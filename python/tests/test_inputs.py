"""Scenes and cameras from Python, and bad input: exceptions with the CLI's messages (a setting named
as the module names it), never a crash."""
import numpy as np
import pytest

import hsr

TRI_V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
TRI_F = np.array([[0, 1, 2]])


def cli_message(cli, *args):
    status, err = cli(*args)
    assert status == 2 and err.startswith("hsr: "), err
    return err[len("hsr: "):]


def test_load_formats_and_builtins(tmp_path):
    (tmp_path / "quad.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    scene = hsr.load(str(tmp_path / "quad.obj"))
    assert scene.face_count == 1 and scene.triangle_count == 2 and scene.vertex_count == 4
    assert np.array_equal(scene.triangle_faces, [0, 0])
    for name in hsr.builtin_scenes():
        assert hsr.load(name).face_count > 0
    assert "zbuffer" in hsr.algorithms()


def test_missing_file_is_an_oserror_with_the_clis_message(tmp_path, cli):
    path = str(tmp_path / "missing.obj")
    with pytest.raises(FileNotFoundError) as e:
        hsr.load(path)
    assert e.value.strerror == cli_message(cli, "info", path)
    with pytest.raises(IsADirectoryError):
        hsr.load(str(tmp_path))


def test_bad_file_content_is_a_valueerror_with_the_clis_message(tmp_path, cli):
    path = tmp_path / "bad.obj"
    path.write_text("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(ValueError) as e:
        hsr.load(str(path))
    assert str(e.value) == cli_message(cli, "info", path)
    with pytest.raises(ValueError) as e:
        hsr.load("builtin:nope")
    assert str(e.value) == cli_message(cli, "info", "builtin:nope")


def test_from_arrays_accepts_float32_and_int_kinds():
    for vdtype in (np.float32, np.float64):
        for fdtype in (np.int32, np.int64, np.uint32, np.uint16):
            s = hsr.Scene.from_arrays(TRI_V.astype(vdtype), TRI_F.astype(fdtype))
            assert s.triangle_count == 1
    s = hsr.Scene.from_arrays(TRI_V[::-1].copy()[::-1], np.asfortranarray(TRI_F))  # any memory layout
    assert s.triangle_count == 1


@pytest.mark.parametrize("vertices,faces,words", [
    (TRI_V.astype(np.int64), TRI_F, "float32 or float64"),
    (TRI_V[:, :2], TRI_F, "shape (N, 3)"),
    (np.zeros((0, 3)), np.zeros((0, 3), np.int32), "no vertices"),
    (TRI_V, np.zeros((0, 3), np.int32), "no faces"),
    (TRI_V, TRI_F.astype(np.float64), "integer vertex indices"),
    (TRI_V, np.array([[0, 1]]), "(M, 3)"),
    (TRI_V, np.array([[0, 1, 3]]), "vertex index 3 out of range (3 vertices)"),
    (TRI_V, np.array([[0, -1, 2]]), "vertex index -1 out of range"),
    (np.array([[0.0, 0, 0], [1, np.nan, 0], [0, 1, 0]]), TRI_F, "vertex 1 has a non-finite coordinate"),
    (np.array([[0.0, 0, 0], [1, np.inf, 0], [0, 1, 0]]), TRI_F, "non-finite"),
    (np.array([[0.0, 0, 0], [1e31, 0, 0], [0, 1, 0]]), TRI_F, "beyond 1e30"),
    ("not an array", TRI_F, "float32 or float64"),
    (None, TRI_F, "got None"),
])
def test_from_arrays_refuses_bad_arrays(vertices, faces, words):
    with pytest.raises(ValueError, match=None) as e:
        hsr.Scene.from_arrays(vertices, faces)
    assert words in str(e.value)


def test_from_arrays_refuses_bad_meshes_colours_and_ids():
    with pytest.raises(ValueError, match="colors: expected shape"):
        hsr.Scene.from_arrays(TRI_V, TRI_F, colors=np.zeros((2, 3), np.uint8))
    with pytest.raises(ValueError, match="colour component out of range"):
        hsr.Scene.from_arrays(TRI_V, TRI_F, colors=(1.5, 0.0, 0.0))
    with pytest.raises(ValueError, match="colour component out of range"):
        hsr.Scene.from_arrays(TRI_V, TRI_F, colors=(300, 0, 0))
    with pytest.raises(ValueError, match="faces: expected a list of 2"):
        hsr.Scene.from_arrays([TRI_V, TRI_V], TRI_F)
    with pytest.raises(ValueError, match="instance_ids: 1 entries for 2 meshes"):
        hsr.Scene.from_arrays([TRI_V, TRI_V], [TRI_F, TRI_F], instance_ids=[4])
    with pytest.raises(ValueError, match="-1 marks the background"):
        hsr.Scene.from_arrays([TRI_V, TRI_V], [TRI_F, TRI_F], instance_ids=[4, -1])
    with pytest.raises(ValueError, match=r"faces\[1\]: no faces"):
        hsr.Scene.from_arrays([TRI_V, TRI_V], [TRI_F, np.zeros((0, 3), int)])
    with pytest.raises(ValueError, match="empty list of meshes"):
        hsr.Scene.from_arrays([], [])


def test_degenerate_faces_are_kept_and_not_drawn():
    s = hsr.Scene.from_arrays(TRI_V, np.array([[0, 1, 2], [0, 0, 1]]))
    assert s.face_count == 2 and s.triangle_count == 1


def test_cameras_refuse_bad_values(cli):
    K = np.array([[100.0, 0, 50], [0, 100, 50], [0, 0, 1]])
    bad = [
        lambda: hsr.Camera.opencv(K, np.eye(4), 0, 10),
        lambda: hsr.Camera.opencv(K, np.eye(4), 100, 20000),
        lambda: hsr.Camera.opencv(np.zeros((3, 3)), np.eye(4), 100, 100),
        lambda: hsr.Camera.opencv(K[:2], np.eye(4), 100, 100),
        lambda: hsr.Camera.opencv(np.where(K == 100, np.nan, K), np.eye(4), 100, 100),
        lambda: hsr.Camera.opencv(K, np.diag([1.0, 2.0, 1.0, 1.0]), 100, 100),
        lambda: hsr.Camera.opencv(K, np.eye(4), 100, 100, near=2.0, far=1.0),
        lambda: hsr.Camera.opencv(K, "pose", 100, 100),
        lambda: hsr.Camera.look_at((0, 0, 5), (0, 0, 5), 100, 100),
        lambda: hsr.Camera.look_at((0, 0, 5), (0, 0, 0), 100, 100, up=(0, 0, 1)),
        lambda: hsr.Camera.look_at((0, 0, 5), (0, 0, 0), 100, 100, fovy_deg=180),
        lambda: hsr.Camera.look_at((0, np.nan, 5), (0, 0, 0), 100, 100),
        lambda: hsr.Camera.orthographic((0, 0, 5), (0, 0, 0), -1.0, 100, 100),
        lambda: hsr.Camera.from_json('{"eye": [0, 0, 5]}', 100, 100),
    ]
    for make in bad:
        with pytest.raises(ValueError):
            make()
    # The same messages as the CLI gives for the same camera (the source name aside).
    with pytest.raises(ValueError) as e:
        hsr.Camera.look_at((0, 0, 5), (0, 0, 5), 100, 100)
    assert str(e.value).split(": ", 1)[1] == cli_message(cli, "render", "builtin:cubes", "--eye", "0,0,5", "--target",
                                                         "0,0,5").split(": ", 1)[1]
    with pytest.raises(FileNotFoundError):
        hsr.Camera.from_json("/nonexistent/cam.json", 100, 100)


def test_camera_json_round_trip(cubes):
    K = np.array([[120.0, 0.5, 40.2], [0, 110, 33.3], [0, 0, 1]])
    pose = np.eye(4)
    pose[2, 3] = 6.0
    cam = hsr.Camera.opencv(K, pose, 90, 70, near=1.0, far=20.0)
    again = hsr.Camera.from_json(cam.to_json(), 90, 70)
    assert again.kind == "opencv" and again.near == 1.0 and again.far == 20.0
    a, b = hsr.render(cubes, cam), hsr.render(cubes, again)
    assert a["depth"].tobytes() == b["depth"].tobytes()


def test_cameras_pickle_exactly(cubes):
    import pickle
    K = np.array([[151.3, 0.2, 71.31], [0.0, 190.7, 66.8], [0.0, 0.0, 1.0]])
    pose = np.eye(4)
    pose[:3, :3] = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))[0] * [1, 1, -1]
    pose[:3, :3] *= np.sign(np.linalg.det(pose[:3, :3]))
    pose[:3, 3] = [0.1, -0.2, 6.0 + 1e-9]
    cameras = [hsr.Camera.opencv(K, pose, 160, 120, near=0.1, far=1 / 3 * 100),
               hsr.Camera.look_at((4.1, 3.3, 5.7), (0.1, 0, 0), 161, 119, fovy_deg=47.3),
               hsr.Camera.orthographic((3, 4, 5), (0, 0, 0), 6.0, 100, 80, up=(0, 0, 1)),
               cubes.default_camera(90, 70)]
    for camera in cameras:
        copy = pickle.loads(pickle.dumps(camera))
        assert type(copy) is hsr.Camera and repr(copy) == repr(camera)
        assert (copy.width, copy.height, copy.to_json()) == (camera.width, camera.height, camera.to_json())
        for name, value in camera.resolve(cubes).items():
            assert np.array_equal(copy.resolve(cubes)[name], value), name
        assert hsr.render(cubes, copy)["depth"].tobytes() == hsr.render(cubes, camera)["depth"].tobytes()


def test_render_refuses_bad_arguments(cubes, cli):
    cam = cubes.default_camera(64, 48)
    with pytest.raises(ValueError, match="outputs: unknown 'zdepth'"):
        hsr.render(cubes, cam, outputs=("zdepth",))
    with pytest.raises(ValueError, match="outputs: none"):
        hsr.render(cubes, cam, outputs=())
    with pytest.raises(ValueError, match="algorithm 'nope': unknown"):
        hsr.render(cubes, cam, algorithm="nope")
    # The library's errors about a setting: the CLI's detail, the setting named as the module names it.
    with pytest.raises(ValueError) as e:
        hsr.render(cubes, cam, depth_format="u17")
    cli_text = cli_message(cli, "render", "builtin:cubes", "--depth-format", "u17")
    assert str(e.value) == "depth_format" + cli_text.removeprefix("--depth-format")
    assert str(e.value) == "depth_format: unknown storage 'u17' (u16, u24, u32, f32)"
    with pytest.raises(ValueError) as e:
        hsr.render(cubes, cam, params={"raster": "nope"})
    cli_text = cli_message(cli, "render", "builtin:cubes", "--param", "raster=nope")
    assert str(e.value) == "params={'raster': 'nope'}" + cli_text.removeprefix("--param raster=nope")
    assert str(e.value).startswith("params={'raster': 'nope'}: not a value of zbuffer's raster")
    with pytest.raises(ValueError, match="cull 'sideways'"):
        hsr.render(cubes, cam, cull="sideways")
    with pytest.raises(ValueError, match="background"):
        hsr.render(cubes, cam, background=(0, 0, 300))
    with pytest.raises(ValueError, match="threads"):
        hsr.render(cubes, cam, threads=-1)
    with pytest.raises(ValueError, match="a batch has one image size"):
        hsr.render(cubes, [cam, cubes.default_camera(32, 48)])
    with pytest.raises(ValueError, match="empty sequence"):
        hsr.render(cubes, [])
    with pytest.raises(ValueError, match=r"cameras\[1\]: not an hsr.Camera"):
        hsr.render(cubes, [cam, "camera"])
    with pytest.raises(ValueError, match="expected an hsr.Camera"):
        hsr.render(cubes, 42)
    with pytest.raises(TypeError):
        hsr.render("builtin:cubes", cam)


def test_huge_batches_raise_memoryerror_not_crash(cubes):
    cam = cubes.default_camera(16384, 16384)
    with pytest.raises(MemoryError, match="more than the memory limit"):
        hsr.render(cubes, [cam] * 4096, outputs=("depth", "face_id", "color"))


def test_max_memory_bounds_batches_and_scenes(cubes):
    default = hsr.max_memory()
    cam = cubes.default_camera(256, 256)
    try:
        hsr.set_max_memory("64M")
        assert hsr.max_memory() == 64 << 20
        # 300 views x 256 x 256 x (4 + 4) bytes = 150 MiB of outputs.
        with pytest.raises(MemoryError, match=r"300 view\(s\) of 256x256 needs about 150 MiB.*\(hsr.set_max_memory\)$"):
            hsr.render(cubes, [cam] * 300)
        assert hsr.render(cubes, [cam] * 10)["depth"].shape == (10, 256, 256)
        with pytest.raises(ValueError, match=r"more than the memory limit of 64 MiB \(hsr.set_max_memory\)$") as e:
            hsr.load("builtin:random?n=1000000")
        assert "--max-memory" not in str(e.value)
        hsr.set_max_memory(1 << 30)
        assert hsr.max_memory() == 1 << 30
    finally:
        hsr.set_max_memory(None)
    assert hsr.max_memory() == default
    for bad in ("banana", "12Q", "-5G", "", 1000, 2.5):
        with pytest.raises(ValueError, match="set_max_memory"):
            hsr.set_max_memory(bad)
