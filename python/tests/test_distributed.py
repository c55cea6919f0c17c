"""hsr.distributed.render_views on a LocalCluster of two worker processes: the files are hsr batch's
and a single process's bytes, whatever the tasks' size; a folder resumes (either tool's); a worker
killed mid-run loses nothing and indexes each view once; bad input fails before any task."""
import json
import logging
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import hsr

distributed = pytest.importorskip("distributed")
import hsr.distributed as hd  # noqa: E402 (after the skip: it needs Dask)

OUTPUTS = ("depth", "face_id", "instance_id", "barycentric")


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=logging.ERROR) as cluster, distributed.Client(cluster) as c:
        yield c


def orbit(n, width=96, height=72, radius=6.0):
    """n look-at cameras around the origin, at several heights."""
    return [hsr.Camera.look_at((radius * np.cos(a), 1.0 + (i % 3), radius * np.sin(a)), (0, 0, 0), width, height)
            for i, a in enumerate(np.linspace(0.0, 2 * np.pi, n, endpoint=False))]


def files_of(folder):
    """{name: bytes} of the views' files (.npy) in `folder`."""
    return {name: open(os.path.join(folder, name), "rb").read() for name in sorted(os.listdir(folder))
            if name.endswith(".npy")}


def index_lines(folder, name=hd.INDEX_FILE):
    return open(os.path.join(folder, name)).read().splitlines()


def check_against_single_process(folder, scene_name, cameras, ids):
    """Every file holds hsr.render's array of its view, rendered here in one process and one call."""
    out = hsr.render(hsr.load(scene_name), cameras, outputs=OUTPUTS, threads=1)
    assert all((ids >= 0).any() and (ids < 0).any() for ids in out["face_id"])  # no view empty or all one surface
    for k, view_id in enumerate(ids):
        for name in OUTPUTS:
            saved = np.load(os.path.join(folder, f"{view_id}.{name}.npy"))
            assert saved.dtype == out[name].dtype and saved.tobytes() == out[name][k].tobytes(), (view_id, name)


def run_batch(tmp_path, lines, out_dir):
    manifest = tmp_path / "views.jsonl"
    manifest.write_text("\n".join(lines) + "\n")
    done = subprocess.run([os.environ["HSR_CLI"], "batch", str(manifest), "--out", str(out_dir), "--threads", "1"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_files_are_hsr_batch_bytes_and_a_single_process_render(client, tmp_path):
    cameras = orbit(13)
    result = hd.render_views(client, "builtin:clutter", cameras, tmp_path / "dask", outputs=OUTPUTS, views_per_task=4)
    ids = [r["id"] for r in result]
    assert ids == [f"view-{k:06d}" for k in range(13)] and all(r["rendered"] for r in result)
    check_against_single_process(tmp_path / "dask", "builtin:clutter", cameras, ids)
    # hsr batch, given the same views as a manifest, writes the same files and the same index lines.
    run_batch(tmp_path, hd.manifest_lines("builtin:clutter", cameras, outputs=OUTPUTS), tmp_path / "batch")
    assert files_of(tmp_path / "dask") == files_of(tmp_path / "batch")
    assert len(files_of(tmp_path / "dask")) == 13 * len(OUTPUTS)
    assert index_lines(tmp_path / "dask") == index_lines(tmp_path / "batch", "index-0-of-1.jsonl")
    # The records returned are the index's.
    assert [hd.index_line(r["id"], r["view_sha256"], r["files"]) for r in result] == index_lines(tmp_path / "dask")
    # Each tool resumes the other's folder: nothing to render.
    assert not any(r["rendered"] for r in hd.render_views(client, "builtin:clutter", cameras, tmp_path / "batch",
                                                          outputs=OUTPUTS))
    run_batch(tmp_path, hd.manifest_lines("builtin:clutter", cameras, outputs=OUTPUTS), tmp_path / "dask")
    assert not os.path.exists(tmp_path / "dask" / "index-0-of-1.jsonl")  # hsr batch found every view complete


def test_views_per_task_and_worker_count_do_not_change_the_bytes(client, tmp_path):
    K = np.array([[80.0, 0, 47.5], [0, 80.0, 35.5], [0, 0, 1]])
    poses = []
    for a in np.linspace(0.0, 2 * np.pi, 9, endpoint=False):  # OpenCV poses on a circle, looking at the origin
        eye = np.array([9 * np.cos(a), 2.0, 9 * np.sin(a)])
        z = -eye / np.linalg.norm(eye)
        x = np.cross(z, [0.0, -1.0, 0.0])
        x /= np.linalg.norm(x)
        R = np.stack([x, np.cross(z, x), z])
        poses.append(np.block([[R, (-R @ eye)[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]]))
    cameras = hsr.Camera.opencv(K, np.array(poses), 96, 72)
    ids = [f"pose{k}" for k in range(9)]
    folders = []
    for views_per_task in (1, 4, 100):
        folders.append(tmp_path / f"vpt{views_per_task}")
        hd.render_views(client, "builtin:cubes", cameras, folders[-1], outputs=OUTPUTS, ids=ids,
                        views_per_task=views_per_task)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=logging.ERROR) as cluster, distributed.Client(cluster) as one:
        folders.append(tmp_path / "one-worker")
        hd.render_views(one, "builtin:cubes", cameras, folders[-1], outputs=OUTPUTS, ids=ids, views_per_task=2)
    for folder in folders[1:]:
        assert files_of(folder) == files_of(folders[0]), folder
        assert index_lines(folder) == index_lines(folders[0]), folder
    assert len(files_of(folders[0])) == 9 * len(OUTPUTS) and len(index_lines(folders[0])) == 9
    check_against_single_process(folders[0], "builtin:cubes", cameras, ids)


def test_each_worker_loads_the_scene_once(client, tmp_path):
    scene = "builtin:sphere?n=3000"

    def loads():
        return client.run(lambda: dict(__import__("hsr.distributed").distributed.SCENE_LOADS).get(scene, 0))

    before = loads()
    hd.render_views(client, scene, orbit(24), tmp_path / "out", views_per_task=2)
    after = loads()
    assert sum(after.values()) - sum(before.values()) >= 1
    assert all(after[worker] - before.get(worker, 0) <= 1 for worker in after), (before, after)


def test_resume_renders_only_what_is_missing_or_damaged(client, tmp_path):
    cameras = orbit(8)
    folder = tmp_path / "out"
    first = hd.render_views(client, "builtin:cubes", cameras, folder, outputs=("depth", "face_id"), views_per_task=3)
    expected, lines = files_of(folder), index_lines(folder)
    os.remove(folder / "view-000002.face_id.npy")                       # a file lost
    damaged = bytearray(expected["view-000005.depth.npy"])
    damaged[-1] ^= 1                                                    # a bit flipped, same size
    (folder / "view-000005.depth.npy").write_bytes(bytes(damaged))
    (folder / "view-000006.depth.npy.tmp-123-4").write_bytes(b"left by a kill")
    with open(folder / hd.INDEX_FILE, "a") as f:
        f.write(lines[0][:40])                                          # a line torn by a kill
    again = hd.render_views(client, "builtin:cubes", cameras, folder, outputs=("depth", "face_id"), views_per_task=3)
    assert [r["rendered"] for r in again] == [k in (2, 5) for k in range(8)]
    assert [{k: r[k] for k in ("id", "view_sha256", "files")} for r in again] == \
        [{k: r[k] for k in ("id", "view_sha256", "files")} for r in first]
    assert files_of(folder) == expected
    assert not [name for name in os.listdir(folder) if ".tmp-" in name]
    # The torn line stays a line of its own, ignored; the two views rendered again are appended.
    assert index_lines(folder) == lines + [lines[0][:40], lines[2], lines[5]]
    # A complete folder: nothing rendered, nothing written.
    before = open(folder / hd.INDEX_FILE, "rb").read()
    assert not any(r["rendered"] for r in hd.render_views(client, "builtin:cubes", cameras, folder,
                                                          outputs=("depth", "face_id")))
    assert open(folder / hd.INDEX_FILE, "rb").read() == before
    # Another camera, outputs or size is another view: rendered again.
    changed = hd.render_views(client, "builtin:cubes", cameras[:1] + orbit(7, radius=7.0), folder,
                              outputs=("depth", "face_id"))
    assert [r["rendered"] for r in changed] == [False] + [True] * 7


def test_a_worker_killed_mid_run_loses_nothing(client, tmp_path):
    scene, cameras = "builtin:sphere?n=100000", orbit(48, 320, 240, radius=3.0)
    folder = tmp_path / "out"
    pids = client.run(os.getpid)                                        # worker address -> process id
    outcome = {}

    def run():
        try:
            outcome["result"] = hd.render_views(client, scene, cameras, folder, outputs=OUTPUTS, views_per_task=2)
        except BaseException as e:  # noqa: B036 (reported by the test below)
            outcome["error"] = e

    thread = threading.Thread(target=run)
    thread.start()
    deadline = time.monotonic() + 30
    while not (folder.exists() and any(n.endswith(".npy") for n in os.listdir(folder))):
        assert time.monotonic() < deadline, "no file written in 30 s"
        time.sleep(0.005)
    busy = [worker for worker, keys in client.processing().items() if keys]
    assert busy, "no worker is rendering"
    os.kill(pids[busy[0]], signal.SIGKILL)                             # a worker dies while rendering
    indexed_at_kill = len(index_lines(folder)) if (folder / hd.INDEX_FILE).exists() else 0
    assert thread.is_alive() and indexed_at_kill < len(cameras), "the kill came after the run"
    thread.join(120)
    assert not thread.is_alive() and "error" not in outcome, outcome.get("error")
    # Every view exactly once in the index, every file as recorded and as one process renders it.
    lines = [json.loads(line) for line in index_lines(folder)]
    ids = [f"view-{k:06d}" for k in range(len(cameras))]
    assert [line["id"] for line in lines] == ids
    assert all(hd.verified(folder, line["files"]) for line in lines)
    assert [r["id"] for r in outcome["result"]] == ids
    assert not [name for name in os.listdir(folder) if ".tmp-" in name]
    assert len(files_of(folder)) == len(cameras) * len(OUTPUTS)
    check_against_single_process(folder, scene, cameras, ids)
    # The nanny started a new worker process in place of the one killed.
    client.wait_for_workers(2, timeout=30)
    assert set(client.run(os.getpid).values()) != set(pids.values())


@pytest.mark.parametrize("kwargs, message", [
    ({"scene": hsr.load("builtin:cubes")}, "scene: expected a file path or 'builtin:NAME', not Scene"),
    ({"scene": "no/such/mesh.obj"}, "scene 'no/such/mesh.obj': no such file"),
    ({"scene": "builtin:nothing"}, "scene 'builtin:nothing': no such built-in scene"),
    ({"outputs": ("depth", "color")}, "outputs: 'color': expected any of depth, face_id, instance_id, barycentric"),
    ({"outputs": ("depth", "depth.npy")}, "outputs: depth is asked for twice"),
    ({"outputs": ()}, "outputs: expected at least one of"),
    ({"cameras": []}, "cameras: expected at least one hsr.Camera"),
    ({"cameras": [None]}, "cameras[0]: expected an hsr.Camera"),
    ({"ids": ["a", "b"]}, "ids: 2 ids for 3 cameras"),
    ({"ids": ["a", ".b", "c"]}, "ids[1]: '.b': expected 1 to 128 letters"),
    ({"ids": ["a", "b", "a"]}, "ids[2]: 'a' is also ids[0]"),
    ({"ids": ["a", "b/c", "d"]}, "ids[1]: 'b/c'"),
    ({"views_per_task": 0}, "views_per_task: expected an integer >= 1, not 0"),
    ({"threads": -1}, "threads: expected an integer >= 0"),
    ({"algorithm": "raytrace9"}, "algorithm 'raytrace9'"),
    ({"params": {"raster": "x"}}, "params={'raster': 'x'}"),
    ({"depth_format": "u17"}, "depth_format"),
    ({"client": "tcp://127.0.0.1:8786"}, "client: expected a distributed.Client, not str"),
])
def test_bad_input_is_one_line_before_anything_is_written(client, tmp_path, kwargs, message):
    args = {"client": client, "scene": "builtin:cubes", "cameras": orbit(3), "out_dir": tmp_path / "out", **kwargs}
    with pytest.raises(ValueError) as error:
        hd.render_views(**args)
    assert message in str(error.value) and "\n" not in str(error.value), str(error.value)
    assert not (tmp_path / "out").exists()


def test_an_error_in_a_task_is_raised_and_finished_views_are_indexed(client, tmp_path):
    # A camera whose far plane lies before the near plane hsr fits to the scene: found on the worker.
    cameras = orbit(4) + [hsr.Camera.look_at((6, 1, 0), (0, 0, 0), 96, 72, far=0.5)]
    with pytest.raises(ValueError, match="near"):
        hd.render_views(client, "builtin:cubes", cameras, tmp_path / "out", views_per_task=4)
    assert [json.loads(line)["id"] for line in index_lines(tmp_path / "out")] == [f"view-{k:06d}" for k in range(4)]


def test_the_manuals_example_runs(tmp_path):
    example = os.path.join(os.path.dirname(__file__), "..", "examples", "dask_views.py")
    for expected in ("100 views rendered, 0 complete already", "0 views rendered, 100 complete already"):
        done = subprocess.run([sys.executable, example],
                              cwd=tmp_path, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0 and expected in done.stdout, done.stdout + done.stderr
    assert len(index_lines(tmp_path / "out")) == 100 and len(files_of(tmp_path / "out")) == 200
