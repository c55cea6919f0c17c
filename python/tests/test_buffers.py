"""The arrays hsr.render returns are the module's own buffers (no copy), outlive the scene and
camera, and the GIL is released while rendering."""
import ctypes
import gc
import threading
import time

import numpy as np

import hsr

ALL = ("depth", "face_id", "instance_id", "triangle_id", "barycentric", "normal", "color")

_get_pointer = ctypes.pythonapi.PyCapsule_GetPointer
_get_pointer.restype = ctypes.c_void_p
_get_pointer.argtypes = [ctypes.py_object, ctypes.c_char_p]


def module_buffer(array):
    """The address of the module's buffer behind `array` (its base capsule, "hsr.buffer")."""
    assert type(array.base).__name__ == "PyCapsule"
    return _get_pointer(array.base, b"hsr.buffer")


def check_zero_copy(out):
    for name, a in out.items():
        assert not a.flags.owndata, name
        assert a.flags.c_contiguous and a.flags.writeable, name
        assert module_buffer(a) == a.ctypes.data, name  # the array's memory is the buffer itself
        assert a.ctypes.data % 64 == 0, name            # cache-line aligned, as hsr allocates it


def test_single_view_arrays_are_the_modules_buffers():
    scene = hsr.load("builtin:cubes")
    check_zero_copy(hsr.render(scene, scene.default_camera(96, 64), outputs=ALL))


def test_batch_arrays_are_the_modules_buffers():
    scene = hsr.load("builtin:cubes")
    cam = scene.default_camera(96, 64)
    out = hsr.render(scene, [cam] * 3, outputs=ALL)
    check_zero_copy(out)
    buffers = {module_buffer(a) for a in out.values()}
    assert len(buffers) == len(ALL)  # one buffer per output, the views inside it


def test_arrays_outlive_scene_camera_and_other_arrays():
    scene = hsr.load("builtin:cubes")
    cam = scene.default_camera(96, 64)
    expected = {k: v.copy() for k, v in hsr.render(scene, cam, outputs=ALL).items()}
    out = hsr.render(scene, cam, outputs=ALL)
    depth = out["depth"]
    view = out["barycentric"][10:20, 5:50]  # a NumPy view keeps the buffer too
    del scene, cam, out
    gc.collect()
    hsr.render(hsr.load("builtin:sphere?n=2000"), hsr.Camera.look_at((0, 0, 4), (0, 0, 0), 96, 64), outputs=ALL)
    assert np.array_equal(depth, expected["depth"])
    assert np.array_equal(view, expected["barycentric"][10:20, 5:50])


def test_gil_is_released_while_rendering():
    scene = hsr.load("builtin:sphere?n=200000")
    cams = [scene.default_camera(320, 240)] * 24
    started, done = threading.Event(), threading.Event()
    timing = {}

    def work():  # renders for at least half a second, whatever the machine's speed
        started.set()
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < 0.5:
            hsr.render(scene, cams, threads=1)
        timing["render"] = time.perf_counter() - t0
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    started.wait()
    last, longest_gap = time.perf_counter(), 0.0
    while not done.is_set():  # Python work on this thread while the other one renders
        now = time.perf_counter()
        longest_gap, last = max(longest_gap, now - last), now
    thread.join()
    # Had the renders held the GIL, this loop would have stood still for each whole render.
    assert longest_gap < 0.5 * timing["render"], (longest_gap, timing["render"])


def test_freed_buffers_are_reused_and_kept_arrays_are_never_overwritten():
    scene = hsr.load("builtin:cubes")
    a_cam, b_cam = scene.default_camera(96, 64), hsr.Camera.look_at((0, 5, 1), (0, 0, 0), 96, 64)
    first = hsr.render(scene, a_cam, outputs=ALL)
    expected = {k: v.copy() for k, v in first.items()}
    del first
    gc.collect()
    again = hsr.render(scene, a_cam, outputs=ALL)  # freed buffers, taken from the module's pool
    check_zero_copy(again)
    other = hsr.render(scene, b_cam, outputs=ALL)  # `again` is alive: its buffers are not reused
    assert not any(np.shares_memory(again[k], other[k]) for k in ALL)
    for k in ALL:
        assert again[k].tobytes() == expected[k].tobytes(), k
    assert not np.array_equal(other["face_id"], again["face_id"])


def test_batches_reuse_freed_blocks_and_never_kept_ones():
    scene = hsr.load("builtin:cubes")
    cams = [scene.default_camera(96, 64), hsr.Camera.look_at((0, 5, 1), (0, 0, 0), 96, 64)] * 3
    first = hsr.render(scene, cams, outputs=ALL)
    expected = {k: v.copy() for k, v in first.items()}
    addresses = {module_buffer(v) for v in first.values()}
    del first
    gc.collect()
    again = hsr.render(scene, cams, outputs=ALL)  # the freed blocks, taken from the module's pool
    check_zero_copy(again)
    assert {module_buffer(v) for v in again.values()} == addresses  # (outputs of one size may swap blocks)
    other = hsr.render(scene, cams[::-1], outputs=ALL)  # `again` is alive: its blocks are not reused
    assert not any(np.shares_memory(again[k], other[k]) for k in ALL)
    for k in ALL:
        assert again[k].tobytes() == expected[k].tobytes(), k
        assert np.array_equal(other[k][::-1], again[k]), k
