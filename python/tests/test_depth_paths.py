"""One depth for every set of outputs: the module's depth (single views and batches), the CLI's
`--depth` with and without ids, `--depth-only` and `hsr batch` are the same bits, and so are ids
and the other outputs, whatever else is asked for."""
import itertools
import json

import numpy as np
import pytest

import hsr

OTHERS = ("face_id", "instance_id", "triangle_id", "barycentric", "normal", "color")
FORMATS = ("f32:reversed", "u16:z", "u24:inv", "f32:linear")


def issue_camera(scale=1.0):
    """The OpenCV camera the defect was found with (scale 1): fx = fy = 300, 320x240, looking
    down -z from z = 8."""
    K = np.array([[300.0, 0.0, 160.0], [0.0, 300.0, 120.0], [0.0, 0.0, 1.0]])
    K[:2] *= scale
    width, height = round(320 * scale), round(240 * scale)
    pose = np.diag([1.0, -1.0, -1.0, 1.0])
    pose[2, 3] = 8.0
    return hsr.Camera.opencv(K, pose, width, height, near=0.1, far=100.0)


def orbit_cameras(scene, count, width, height):
    (lo, hi) = np.array(scene.bounds)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    cams = []
    for a in np.linspace(0.3, 2.0, count):
        eye = centre + radius * np.array([1.4 * np.cos(a), 0.8, 1.4 * np.sin(a)])
        cams.append(hsr.Camera.look_at(tuple(eye), tuple(centre), width, height, fovy_deg=55))
    return cams


def same_bits(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("depth_format", FORMATS)
def test_every_set_of_outputs_gives_the_same_bits(depth_format):
    scene = hsr.load("builtin:cubes")
    camera = issue_camera()
    full = hsr.render(scene, camera, outputs=("depth",) + OTHERS, depth_format=depth_format)
    assert np.isfinite(full["depth"]).sum() > 10000  # the cubes fill a good part of the image
    for r in range(len(OTHERS) + 1):
        for chosen in itertools.combinations(OTHERS, r):
            out = hsr.render(scene, camera, outputs=("depth",) + chosen, depth_format=depth_format)
            assert set(out) == {"depth", *chosen}
            for name, array in out.items():
                assert same_bits(array, full[name]), (depth_format, chosen, name)


@pytest.mark.parametrize("scene_name", ["builtin:city", "builtin:random?n=3000", "builtin:sphere?n=20000"])
def test_batches_and_single_views_agree_for_depth_alone_and_with_ids(scene_name):
    # The city has enough meshes and triangles for mesh culling: its depth-only frames take the
    # same path as those with ids.
    scene = hsr.load(scene_name)
    cameras = orbit_cameras(scene, 3, 256, 192)
    alone = hsr.render(scene, cameras, outputs=("depth",), threads=2)
    with_ids = hsr.render(scene, cameras, outputs=("depth", "face_id"), threads=1)
    assert same_bits(alone["depth"], with_ids["depth"])
    for i, camera in enumerate(cameras):
        single = hsr.render(scene, camera, outputs=("depth",))
        assert same_bits(single["depth"], alone["depth"][i])


@pytest.mark.parametrize("algorithm", hsr.algorithms())
def test_every_algorithm_gives_the_same_depth_alone_and_with_ids(algorithm):
    scene = hsr.load("builtin:cubes")
    camera = issue_camera(0.4)
    alone = hsr.render(scene, camera, outputs=("depth",), algorithm=algorithm)
    more = hsr.render(scene, camera, outputs=("depth", "face_id", "color"), algorithm=algorithm)
    assert np.isfinite(alone["depth"]).any()
    assert same_bits(alone["depth"], more["depth"]), algorithm


def test_the_cli_single_and_batch_write_the_modules_depth(tmp_path, cli):
    scene = hsr.load("builtin:cubes")
    camera = issue_camera()
    (tmp_path / "cam.json").write_text(camera.to_json())
    expected = {fmt: hsr.render(scene, camera, outputs=("depth", "face_id"), depth_format=fmt) for fmt in FORMATS[:2]}
    for fmt in FORMATS[:2]:
        base = ("render", "builtin:cubes", "--camera", tmp_path / "cam.json", "--size", "320x240", "-q",
                "--depth-format", fmt)
        runs = {
            "ids": ["--ids", tmp_path / "i.npy"],
            "outputs-depth": ["--outputs", "depth"],
            "depth-only": ["--depth-only"],
            "colour": ["-o", tmp_path / "c.png"],
        }
        for name, flags in runs.items():
            path = tmp_path / f"d-{name}.npy"
            status, err = cli(*base, *flags, "--depth", path)
            assert status == 0, err
            assert np.load(path).tobytes() == expected[fmt]["depth"].tobytes(), (fmt, name)
    # hsr batch: the depth file of a view alone, with ids and with colour.
    camera_json = json.loads(camera.to_json())
    lines = []
    for i, outputs in enumerate((["depth"], ["depth", "face_id"], ["depth", "color"], ["depth_image", "depth"])):
        for fmt in FORMATS[:2]:
            lines.append(json.dumps({"id": f"v{i}-{fmt.replace(':', '-')}", "scene": "builtin:cubes",
                                     "camera": camera_json, "size": "320x240", "outputs": outputs,
                                     "depth_format": fmt}))
    (tmp_path / "views.jsonl").write_text("\n".join(lines) + "\n")
    status, err = cli("batch", tmp_path / "views.jsonl", "--out", tmp_path / "out")
    assert status == 0, err
    for i in range(4):
        for fmt in FORMATS[:2]:
            depth = np.load(tmp_path / "out" / f"v{i}-{fmt.replace(':', '-')}.depth.npy")
            assert depth.tobytes() == expected[fmt]["depth"].tobytes(), (i, fmt)
