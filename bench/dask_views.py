#!/usr/bin/python3
"""Views per second of the ways hsr renders many views on one machine: one process (hsr.render
batches written by hsr.distributed's writer), `hsr batch` in 2 shards, hsr.distributed on Dask with
1 and 2 workers; Dask's cost per task (no-op tasks); and a model of 100 workers. Prints markdown.

Run: PYTHONPATH=build/python /usr/bin/python3 bench/dask_views.py [--views 400] [--hsr build/hsr]
"""
import argparse
import datetime
import json
import logging
import os
import shutil
import subprocess
import tempfile
import time

import numpy as np

import hsr
import hsr.distributed as hd


def cameras_around(scene, n, width, height):
    """n look-at cameras on a circle above the scene, looking at its centre (a fixed set)."""
    lo, hi = scene.bounds
    centre, radius = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) * 0.6
    return [hsr.Camera.look_at(centre + [radius * np.cos(a), radius * (0.3 + 0.2 * (i % 3)), radius * np.sin(a)],
                               centre, width, height)
            for i, a in enumerate(np.linspace(0.0, 2 * np.pi, n, endpoint=False))]


def one_process(scene_name, cameras, outputs, out_dir, chunk, threads):
    """hsr.render batches of `chunk` views in this process, each view's files written as render_views writes them."""
    scene = hsr.load(scene_name)
    start = time.perf_counter()
    for first in range(0, len(cameras), chunk):
        out = hsr.render(scene, cameras[first:first + chunk], outputs=("face_id", *outputs), threads=threads)
        for k in range(len(cameras[first:first + chunk])):
            for name in outputs:
                hd.write_npy(os.path.join(out_dir, f"view-{first + k:06d}.{name}.npy"),
                             out[name][k].astype(hd.NPY_OUTPUTS[name], copy=False))
    return time.perf_counter() - start


def batch_shards(cli, manifest, out_dir, shards):
    start = time.perf_counter()
    runs = [subprocess.Popen([cli, "batch", manifest, "--out", out_dir, "--shard", f"{i}/{shards}", "--threads", "1"])
            for i in range(shards)]
    if any(run.wait() for run in runs):
        raise SystemExit("hsr batch failed")
    return time.perf_counter() - start


def noop(x):
    return x


def dask_runs(workers, scene_name, cameras, outputs, out_dir, views_per_task):
    """(seconds of render_views, no-op tasks per second) on a LocalCluster of `workers` processes."""
    import distributed
    with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=logging.ERROR) as cluster, distributed.Client(cluster) as client:
        client.run(lambda: __import__("hsr.distributed"))  # what a long-lived cluster has done already
        start = time.perf_counter()
        hd.render_views(client, scene_name, cameras, out_dir, outputs=outputs, views_per_task=views_per_task)
        seconds = time.perf_counter() - start
        client.gather(client.map(noop, range(200), pure=False))  # warm
        tasks = 2000
        start = time.perf_counter()
        client.gather(client.map(noop, range(tasks), pure=False))
        return seconds, tasks / (time.perf_counter() - start)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="builtin:city")
    parser.add_argument("--views", type=int, default=400)
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--outputs", default="depth,face_id")
    parser.add_argument("--views-per-task", type=int, default=20)
    parser.add_argument("--hsr", default=os.environ.get("HSR_CLI", "build/hsr"), help="the hsr executable")
    parser.add_argument("--fs-gbytes-per-s", type=float, default=1.0,
                        help="the model's shared file system write bandwidth, GB/s (an assumption)")
    args = parser.parse_args()
    width, height = map(int, args.size.split("x"))
    outputs = args.outputs.split(",")
    cameras = cameras_around(hsr.load(args.scene), args.views, width, height)
    scratch = tempfile.mkdtemp(prefix="hsr-dask-bench-")
    rows = []
    try:
        def folder(name):
            path = os.path.join(scratch, name)
            os.makedirs(path)
            return path

        for threads in (1, 2):
            seconds = one_process(args.scene, cameras, outputs, folder(f"one-{threads}"), args.views_per_task, threads)
            rows.append((f"1 process, hsr.render batches of {args.views_per_task}, {threads} thread(s)", seconds))
        manifest = os.path.join(scratch, "views.jsonl")
        with open(manifest, "w") as f:
            f.write("\n".join(hd.manifest_lines(args.scene, cameras, outputs=outputs)) + "\n")
        rows.append(("hsr batch, 2 shards (2 processes, 1 thread each)",
                     batch_shards(args.hsr, manifest, folder("batch"), 2)))
        noop_rate = {}
        for workers in (1, 2):
            seconds, noop_rate[workers] = dask_runs(workers, args.scene, cameras, outputs, folder(f"dask-{workers}"),
                                                    args.views_per_task)
            rows.append((f"hsr.distributed, {workers} worker(s) x 1 thread, {args.views_per_task} views/task",
                         seconds))
        # The folders must hold the same bytes, whichever way they were made.
        reference = sorted(os.listdir(os.path.join(scratch, "batch")))
        for name in reference:
            if name.endswith(".npy"):
                data = open(os.path.join(scratch, "batch", name), "rb").read()
                for other in ("one-1", "one-2", "dask-1", "dask-2"):
                    assert open(os.path.join(scratch, other, name), "rb").read() == data, (other, name)
        bytes_per_view = sum(os.path.getsize(os.path.join(scratch, "batch", n))
                             for n in reference if n.endswith(".npy")) / args.views
    finally:
        shutil.rmtree(scratch)

    print(f"{args.views} views of {args.scene} at {args.size}, outputs {args.outputs}; "
          f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f} at the end\n")
    print("| run | seconds | views/s |\n|---|---|---|")
    for name, seconds in rows:
        print(f"| {name} | {seconds:.2f} | {args.views / seconds:.1f} |")
    print("\n| Dask cost per task | no-op tasks/s | ms per task |\n|---|---|---|")
    for workers, rate in noop_rate.items():
        print(f"| {workers} worker(s) | {rate:.0f} | {1000 / rate:.2f} |")

    # Model: 100 workers, each as fast as one worker here, capped by the scheduler's task rate
    # (as measured here with 2 workers: it runs on the same two cores) and the file system.
    per_worker = args.views / dict(rows)[f"hsr.distributed, 1 worker(s) x 1 thread, {args.views_per_task} views/task"]
    workers = 100
    caps = {"workers x per-worker rate": workers * per_worker,
            f"scheduler: {noop_rate[2]:.0f} tasks/s x {args.views_per_task} views/task": noop_rate[2] * args.views_per_task,
            f"file system: {args.fs_gbytes_per_s:g} GB/s / {bytes_per_view / 1e6:.2f} MB per view":
                args.fs_gbytes_per_s * 1e9 / bytes_per_view}
    print(f"\n| model, {workers} workers | views/s |\n|---|---|")
    for name, rate in caps.items():
        print(f"| {name} | {rate:.0f} |")
    limit = min(caps, key=caps.get)
    print(f"| **throughput (the least)** | **{caps[limit]:.0f}** ({limit.split(':')[0]}) |")
    print("\n" + json.dumps({"per_worker_views_per_s": per_worker, "bytes_per_view": bytes_per_view,
                              "noop_tasks_per_s": noop_rate}))


if __name__ == "__main__":
    main()
