"""Many views on Dask distributed: hsr.distributed.render_views (docs/distributed.md, "Dask").

The client checks the input, reads the folder's index files and submits tasks of a few views each;
a worker loads the scene once (cached per worker process), renders its views with hsr.render's
batch call, writes each file atomically and returns small records; the client appends the index.
Files, file names and index lines are those of `hsr batch`, so either tool reads and resumes both.
"""
import collections
import hashlib
import json
import os
import re
import threading

import numpy as np

from . import _hsr as hsr

__all__ = ["render_views", "manifest_lines"]

# Outputs as .npy files, with the dtype `hsr batch` writes them in (little-endian).
NPY_OUTPUTS = {"depth": "<f4", "face_id": "<i4", "instance_id": "<i4", "barycentric": "<f4"}
INDEX_FILE = "index-dask.jsonl"  # "index-*.jsonl": hsr batch reads it too
ID_PATTERN = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9_.-]{0,127}")


# ---------------------------------------------------------------------------------------------
# The views: checked on the client, each with its manifest line and digest.

class View:
    """One view: its id, camera, the files it writes and its manifest line's SHA-256."""

    def __init__(self, view_id, camera, line, outputs):
        self.id = view_id
        self.camera = camera
        self.line = line
        self.digest = hashlib.sha256(canonical_json(line).encode()).hexdigest()
        self.files = [(name, f"{view_id}.{name}.npy") for name in outputs]


def canonical_json(value):
    """JSON with sorted keys and no spaces: the text `hsr batch` takes a view's digest of."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False)


def checked_scene(scene):
    """The scene as workers load it: a built-in's name, or a file's absolute path (shared storage)."""
    if not isinstance(scene, (str, os.PathLike)):
        raise ValueError(f"scene: expected a file path or 'builtin:NAME', not {type(scene).__name__} "
                         "(each worker loads the scene itself; meshes are never sent with the tasks)")
    scene = os.fspath(scene)
    if scene.startswith("builtin:"):
        if scene.split("?")[0] not in hsr.builtin_scenes():
            raise ValueError(f"scene '{scene}': no such built-in scene (hsr.builtin_scenes() lists them)")
        return scene
    path = os.path.abspath(scene)
    if not os.path.isfile(path):
        raise ValueError(f"scene '{scene}': no such file ({path})")
    return path


def checked_outputs(outputs):
    outputs = [outputs] if isinstance(outputs, str) else list(outputs)
    names = []
    for item in outputs:
        name = item[:-4] if isinstance(item, str) and item.endswith(".npy") else item
        if name not in NPY_OUTPUTS:
            raise ValueError(f"outputs: {item!r}: expected any of {', '.join(NPY_OUTPUTS)} (written as .npy)")
        if name in names:
            raise ValueError(f"outputs: {name} is asked for twice")
        names.append(name)
    if not names:
        raise ValueError(f"outputs: expected at least one of {', '.join(NPY_OUTPUTS)}")
    return names


def checked_settings(algorithm, params, depth_format):
    """Checks the render settings with the module's own messages: one 1x1 render of one triangle."""
    triangle = hsr.Scene.from_arrays(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))
    hsr.render(triangle, hsr.Camera.look_at((0, 0, 3), (0, 0, 0), 1, 1), outputs=("depth",), algorithm=algorithm,
               params=params, depth_format=depth_format, threads=1)


def make_views(scene, cameras, outputs, ids, algorithm, params, depth_format):
    """The views as `hsr batch` manifest lines would give them; ValueError for bad input."""
    scene = checked_scene(scene)
    outputs = checked_outputs(outputs)
    checked_settings(algorithm, params, depth_format)
    if isinstance(cameras, hsr.Camera):
        cameras = [cameras]
    cameras = list(cameras)
    if not cameras:
        raise ValueError("cameras: expected at least one hsr.Camera")
    for i, camera in enumerate(cameras):
        if not isinstance(camera, hsr.Camera):
            raise ValueError(f"cameras[{i}]: expected an hsr.Camera (hsr.Camera.opencv(K, poses, W, H) makes "
                             f"a list), not {type(camera).__name__}")
    width = max(6, len(str(len(cameras) - 1)))
    ids = [f"view-{i:0{width}d}" for i in range(len(cameras))] if ids is None else list(ids)
    if len(ids) != len(cameras):
        raise ValueError(f"ids: {len(ids)} ids for {len(cameras)} cameras")
    seen = {}
    for i, view_id in enumerate(ids):
        if not isinstance(view_id, str) or not ID_PATTERN.fullmatch(view_id):
            raise ValueError(f"ids[{i}]: {view_id!r}: expected 1 to 128 letters, digits, '_', '-' or '.', "
                             "not starting with '.'")
        if view_id in seen:
            raise ValueError(f"ids[{i}]: '{view_id}' is also ids[{seen[view_id]}]")
        seen[view_id] = i
    views = []
    for view_id, camera in zip(ids, cameras):
        line = {"id": view_id, "scene": scene, "camera": json.loads(camera.to_json()),
                "size": f"{camera.width}x{camera.height}", "outputs": outputs}
        if algorithm != "zbuffer":
            line["algorithm"] = algorithm
        if params:
            line["params"] = dict(params)
        if depth_format:
            line["depth_format"] = depth_format
        views.append(View(view_id, camera, line, outputs))
    return scene, views


def manifest_lines(scene, cameras, outputs=("depth", "face_id"), ids=None, algorithm="zbuffer", params=None,
                   depth_format=""):
    """The views render_views renders, as the JSON lines of an `hsr batch` manifest (one str per view).

    `hsr batch` renders them to the same files, and either tool resumes the other's folder."""
    return [json.dumps(v.line, separators=(",", ":"), ensure_ascii=False)
            for v in make_views(scene, cameras, outputs, ids, algorithm, params, depth_format)[1]]


# ---------------------------------------------------------------------------------------------
# Files: NPY bytes as hsr writes them, written atomically; the index and what it records.

def npy_header(array):
    """NPY 1.0 header of a C-order array: the dict padded with spaces so that the data is 64-byte aligned."""
    text = f"{{'descr': '{array.dtype.str}', 'fortran_order': False, 'shape': {tuple(array.shape)}, }}"
    length = (10 + len(text) + 1 + 63) // 64 * 64 - 10
    text = text + " " * (length - len(text) - 1) + "\n"
    return b"\x93NUMPY\x01\x00" + length.to_bytes(2, "little") + text.encode("latin1")


def write_npy(path, array):
    """Writes `array` to `path` through a temporary beside it renamed into place; returns (bytes, SHA-256)."""
    header = npy_header(array)
    data = memoryview(np.ascontiguousarray(array)).cast("B")
    digest = hashlib.sha256(header)
    digest.update(data)
    temporary = f"{path}.tmp-{os.getpid()}-{threading.get_ident()}"
    with open(temporary, "wb") as f:
        f.write(header)
        f.write(data)
    os.replace(temporary, path)
    return len(header) + len(data), digest.hexdigest()


def sha256_of_file(path):
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def index_line(view_id, digest, files):
    record = {"id": view_id, "view_sha256": digest, "files": files}
    return json.dumps(record, separators=(",", ":"), ensure_ascii=False)


def read_indexes(out_dir):
    """Every whole line of the folder's index files (any tool's, any shard count's), by view id."""
    by_id = collections.defaultdict(list)
    for name in sorted(os.listdir(out_dir)):
        path = os.path.join(out_dir, name)
        if not (name.startswith("index-") and name.endswith(".jsonl") and os.path.isfile(path)):
            continue
        with open(path, "rb") as f:
            text = f.read().decode("utf-8", "replace")
        for line in text.split("\n")[:-1]:  # the last piece has no newline: empty, or torn by a kill
            try:
                record = json.loads(line)
                by_id[record["id"]].append((record["view_sha256"], record["files"]))
            except (ValueError, KeyError, TypeError):
                continue
    return by_id


def candidates(view, by_id):
    """The index records of `view` with its digest and exactly its files: complete if the files verify."""
    found = []
    for digest, files in by_id.get(view.id, []):
        try:
            names = [(f["output"], f["file"]) for f in files]
        except (KeyError, TypeError):
            continue
        if digest == view.digest and names == view.files and files not in found:
            found.append(files)
    return found


def verified(out_dir, files):
    """Whether every recorded file is on disk with its recorded size and SHA-256."""
    for f in files:
        path = os.path.join(out_dir, f["file"])
        if not os.path.isfile(path) or os.path.getsize(path) != f["bytes"] or sha256_of_file(path) != f["sha256"]:
            return False
    return True


def remove_temporaries(out_dir, views):
    """The temporaries ("FILE.tmp-...") killed tasks left of these views' files."""
    files = {name for v in views for _, name in v.files}
    for name in os.listdir(out_dir):
        cut = name.rfind(".tmp-")
        if cut > 0 and name[:cut] in files:
            os.remove(os.path.join(out_dir, name))


class IndexAppender:
    """Appends whole lines (one write each) to an index; a line a kill tore is ended first."""

    def __init__(self, path):
        self.path = path
        self.fd = None

    def append(self, lines):
        if not lines:
            return
        if self.fd is None:
            self.fd = os.open(self.path, os.O_RDWR | os.O_APPEND | os.O_CREAT, 0o666)
            size = os.fstat(self.fd).st_size
            if size and os.pread(self.fd, 1, size - 1) != b"\n":
                os.write(self.fd, b"\n")
        for line in lines:
            data = (line + "\n").encode()
            while data:
                data = data[os.write(self.fd, data):]

    def close(self):
        if self.fd is not None:
            os.close(self.fd)


# ---------------------------------------------------------------------------------------------
# Worker side: the scene cache and the task.

SCENES = collections.OrderedDict()  # (scene, file stamp) -> hsr.Scene, in this worker process
SCENES_KEPT = 2
SCENES_LOCK = threading.Lock()
SCENE_LOADS = collections.Counter()  # scene -> times this process loaded it (tests check "once")


def cached_scene(scene, stamp):
    """The scene loaded once per worker process; the stamp (size, mtime) of a file reloads an edited one."""
    key = (scene, stamp)
    with SCENES_LOCK:
        if key not in SCENES:
            SCENES[key] = hsr.load(scene)
            SCENE_LOADS[scene] += 1
            while len(SCENES) > SCENES_KEPT:
                SCENES.popitem(last=False)
        SCENES.move_to_end(key)
        return SCENES[key]


def render_task(scene, stamp, out_dir, settings, views):
    """Renders one task's views (id, camera, files, index candidates); returns per view (id, files,
    rendered). A view whose recorded files verify is not rendered again."""
    results = {}
    todo = []
    for view_id, camera, files, found in views:
        complete = next((c for c in found if verified(out_dir, c)), None)
        if complete is not None:
            results[view_id] = (complete, False)
        else:
            todo.append((view_id, camera, files))
    # One hsr.render batch per image size; face ids are always asked for, so that depth is the
    # exact eye depth of the visible surface whatever else is asked (as hsr batch writes it).
    by_size = collections.defaultdict(list)
    for item in todo:
        by_size[(item[1].width, item[1].height)].append(item)
    outputs = tuple(dict.fromkeys(["face_id", *settings["outputs"]]))
    for group in by_size.values():
        out = hsr.render(cached_scene(scene, stamp), [camera for _, camera, _ in group], outputs=outputs,
                         algorithm=settings["algorithm"], params=settings["params"],
                         depth_format=settings["depth_format"], threads=settings["threads"])
        for i, (view_id, _, files) in enumerate(group):
            records = []
            for output, name in files:
                array = out[output][i].astype(NPY_OUTPUTS[output], copy=False)
                size, sha = write_npy(os.path.join(out_dir, name), array)
                records.append({"output": output, "file": name, "bytes": size, "sha256": sha})
            results[view_id] = (records, True)
    return [(view_id, *results[view_id]) for view_id, _, _, _ in views]


# ---------------------------------------------------------------------------------------------
# The client: check, submit, index.

def render_views(client, scene, cameras, out_dir, outputs=("depth", "face_id"), views_per_task=16, ids=None,
                 algorithm="zbuffer", params=None, depth_format="", threads=1):
    """Renders one view per camera on the workers of a dask.distributed `client` into `out_dir`.

    scene: a file path (on storage every worker reads, made absolute here) or "builtin:NAME[?k=v]";
    each worker process loads it once. cameras: hsr.Camera objects (hsr.Camera.opencv(K, poses, W, H)
    gives a list). outputs: any of depth, face_id, instance_id, barycentric, written as
    OUT_DIR/ID.OUTPUT.npy. ids: the views' names (default view-000000, ...). views_per_task: views per
    Dask task, rendered by one hsr.render call with `threads` threads. algorithm, params,
    depth_format: as hsr.render's.

    Files are written atomically and recorded in OUT_DIR/index-dask.jsonl in view order, in
    `hsr batch`'s format; views an index of the folder records with verified files are skipped
    (resume). Returns one dict per view, in order: id, view_sha256, files (output, file, bytes,
    sha256) and rendered (False when found complete). Bad input raises ValueError before any
    task is submitted; an error in a task (a camera bad for the scene) is raised here once the
    other tasks have ended, their views indexed."""
    import distributed  # imported here: `import hsr` does not need Dask

    scene, views = make_views(scene, cameras, outputs, ids, algorithm, params, depth_format)
    if not isinstance(views_per_task, int) or isinstance(views_per_task, bool) or views_per_task < 1:
        raise ValueError(f"views_per_task: expected an integer >= 1, not {views_per_task!r}")
    if not isinstance(threads, int) or isinstance(threads, bool) or threads < 0:
        raise ValueError(f"threads: expected an integer >= 0 (0: every core of the worker), not {threads!r}")
    if not isinstance(client, distributed.Client):
        raise ValueError(f"client: expected a distributed.Client, not {type(client).__name__}")
    out_dir = os.path.abspath(os.fspath(out_dir))
    os.makedirs(out_dir, exist_ok=True)

    stat = None if scene.startswith("builtin:") else os.stat(scene)
    stamp = None if stat is None else (stat.st_size, stat.st_mtime_ns)
    settings = {"outputs": [name for name, _ in views[0].files], "algorithm": algorithm, "params": params,
                "depth_format": depth_format, "threads": threads}
    by_id = read_indexes(out_dir)
    remove_temporaries(out_dir, views)
    tasks = [views[i:i + views_per_task] for i in range(0, len(views), views_per_task)]
    futures = [client.submit(render_task, scene, stamp, out_dir, settings,
                             [(v.id, v.camera, v.files, candidates(v, by_id)) for v in task], pure=False)
               for task in tasks]
    task_of = {f.key: k for k, f in enumerate(futures)}

    # Index lines go out in view order (the index of a run does not depend on the scheduling): a
    # task's lines are appended once every earlier task's are. A task that failed is skipped over;
    # the first error in view order is raised once every other task has ended and been indexed.
    digest_of = {v.id: v.digest for v in views}
    results = [None] * len(tasks)
    appender = IndexAppender(os.path.join(out_dir, INDEX_FILE))
    written = 0
    try:
        for future in distributed.as_completed(futures):
            k = task_of[future.key]
            try:
                results[k] = future.result()
            except Exception as error:  # noqa: BLE001 (raised below)
                results[k] = error
            while written < len(tasks) and results[written] is not None:
                if not isinstance(results[written], Exception):
                    appender.append([index_line(i, digest_of[i], files)
                                     for i, files, rendered in results[written] if rendered])
                written += 1
    finally:
        appender.close()
    errors = [r for r in results if isinstance(r, Exception)]
    if errors:
        raise errors[0]
    remove_temporaries(out_dir, views)
    return [{"id": i, "view_sha256": digest_of[i], "files": files, "rendered": rendered}
            for result in results for i, files, rendered in result]
