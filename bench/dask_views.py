#!/usr/bin/python3
"""Views per second of the ways hsr renders many views on one machine: one process (hsr.render
batches written by hsr.distributed's writer), `hsr batch` in 2 shards, hsr.distributed on Dask with
1 and 2 workers; Dask's cost per task (no-op tasks); and a model of 100 workers. Prints markdown.

Run: PYTHONPATH=build/python /usr/bin/python3 bench/dask_views.py [--views 300] [--repeat 3] [--hsr build/hsr]
"""
import argparse
import datetime
import json
import logging
import os
import shutil
import statistics
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


def one_process(scene, cameras, outputs, out_dir, chunk, threads):
    """hsr.render batches of `chunk` views in this process, each view's files written as render_views writes them."""
    for first in range(0, len(cameras), chunk):
        out = hsr.render(scene, cameras[first:first + chunk], outputs=("face_id", *outputs), threads=threads)
        for k in range(len(cameras[first:first + chunk])):
            for name in outputs:
                hd.write_npy(os.path.join(out_dir, f"view-{first + k:06d}.{name}.npy"),
                             out[name][k].astype(hd.NPY_OUTPUTS[name], copy=False))


def batch_shards(cli, manifest, out_dir, shards):
    runs = [subprocess.Popen([cli, "batch", manifest, "--out", out_dir, "--shard", f"{i}/{shards}", "--threads", "1"],
                             stdout=subprocess.DEVNULL) for i in range(shards)]
    if any(run.wait() for run in runs):
        raise SystemExit("hsr batch failed")


def noop(x):
    return x


def timed(run):
    start = time.perf_counter()
    run()
    return time.perf_counter() - start


def noop_rate(client, tasks=2000):
    """Dask's tasks per second for tasks that do nothing: the cost of a task to the client, the
    scheduler and a worker."""
    client.gather(client.map(noop, range(200), pure=False))  # warm
    return tasks / timed(lambda: client.gather(client.map(noop, range(tasks), pure=False)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="builtin:city")
    parser.add_argument("--views", type=int, default=300)
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--outputs", default="depth,face_id")
    parser.add_argument("--views-per-task", type=int, default=20)
    parser.add_argument("--repeat", type=int, default=3, help="runs of each way, interleaved")
    parser.add_argument("--hsr", default=os.environ.get("HSR_CLI", "build/hsr"), help="the hsr executable")
    parser.add_argument("--fs-gbytes-per-s", default="1,10",
                        help="the model's shared file system write bandwidths, GB/s (assumptions)")
    args = parser.parse_args()
    import distributed

    width, height = map(int, args.size.split("x"))
    outputs, per_task = args.outputs.split(","), args.views_per_task
    scene = hsr.load(args.scene)
    cameras = cameras_around(scene, args.views, width, height)
    scratch = tempfile.mkdtemp(prefix="hsr-dask-bench-")
    manifest = os.path.join(scratch, "views.jsonl")
    with open(manifest, "w") as f:
        f.write("\n".join(hd.manifest_lines(args.scene, cameras, outputs=outputs)) + "\n")
    clusters = {n: distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                                            silence_logs=logging.ERROR) for n in (1, 2)}
    clients = {n: distributed.Client(cluster) for n, cluster in clusters.items()}
    for client in clients.values():  # what a cluster that has run before has done: imports, the scene loaded
        hd.render_views(client, args.scene, cameras[:4], os.path.join(scratch, "warm"), outputs=outputs,
                        views_per_task=1)
        shutil.rmtree(os.path.join(scratch, "warm"))

    def dask(n, views_per_task):
        return lambda out: hd.render_views(clients[n], args.scene, cameras, out, outputs=outputs,
                                           views_per_task=views_per_task)

    ways = {
        "1 process: hsr.render batches, 1 thread": lambda out: one_process(scene, cameras, outputs, out, per_task, 1),
        "1 process: hsr.render batches, 2 threads": lambda out: one_process(scene, cameras, outputs, out, per_task, 2),
        "hsr batch, 2 shards (2 processes, 1 thread each)": lambda out: batch_shards(args.hsr, manifest, out, 2),
        f"hsr.distributed, 1 worker x 1 thread, {per_task} views/task": dask(1, per_task),
        f"hsr.distributed, 2 workers x 1 thread, {per_task} views/task": dask(2, per_task),
        "hsr.distributed, 2 workers x 1 thread, 1 view/task": dask(2, 1),
    }
    seconds = {name: [] for name in ways}
    reference = None
    try:
        for _ in range(args.repeat):
            for name, run in ways.items():
                out = os.path.join(scratch, "out")
                os.makedirs(out)
                seconds[name].append(timed(lambda: run(out)))
                # Every way writes the same bytes.
                names = sorted(n for n in os.listdir(out) if n.endswith(".npy"))
                files = {n: hd.sha256_of_file(os.path.join(out, n)) for n in names}
                reference = reference or files
                assert files == reference and len(files) == len(cameras) * len(outputs), name
                bytes_per_view = sum(os.path.getsize(os.path.join(out, n)) for n in files) / len(cameras)
                shutil.rmtree(out)
        rates = {n: noop_rate(client) for n, client in clients.items()}
    finally:
        for client in clients.values():
            client.close()
        for cluster in clusters.values():
            cluster.close()
        shutil.rmtree(scratch)

    print(f"{args.views} views of {args.scene} at {args.size}, outputs {args.outputs}; "
          f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f} at the end; {args.repeat} runs of each, interleaved\n")
    print("| run | views/s (best) | views/s (median) |\n|---|---|---|")
    best = {name: min(s) for name, s in seconds.items()}
    for name, s in seconds.items():
        print(f"| {name} | {args.views / best[name]:.1f} | {args.views / statistics.median(s):.1f} |")
    # The slope: what each task of one view adds, per worker, over tasks of `per_task` views.
    extra_tasks = args.views - -(-args.views // per_task)
    slope = (best["hsr.distributed, 2 workers x 1 thread, 1 view/task"]
             - best[f"hsr.distributed, 2 workers x 1 thread, {per_task} views/task"]) * 2 / extra_tasks
    print("\n| Dask's cost per task | tasks/s | ms per task |\n|---|---|---|")
    for n, rate in rates.items():
        print(f"| no-op tasks, {n} worker(s) | {rate:.0f} | {1000 / rate:.2f} |")
    print(f"| render_views, 1 view/task against {per_task}: extra time x 2 workers / extra tasks | "
          f"| {1000 * slope:.1f} |")

    # Model: 100 workers of one core, each as fast as the best 1-worker run here, capped by the
    # scheduler's task rate (the no-op rate with 2 workers here, where scheduler, client and workers
    # share two cores: a lower bound) and by the file system's write bandwidth (assumed).
    per_worker = args.views / best[f"hsr.distributed, 1 worker x 1 thread, {per_task} views/task"]
    workers = 100
    print(f"\n| model, {workers} workers | views/s |\n|---|---|")
    print(f"| workers x per-worker rate: {workers} x {per_worker:.1f} | {workers * per_worker:.0f} |")
    print(f"| scheduler: {rates[2]:.0f} tasks/s x {per_task} views/task | {rates[2] * per_task:.0f} |")
    for gbytes in map(float, args.fs_gbytes_per_s.split(",")):
        fs = gbytes * 1e9 / bytes_per_view
        print(f"| file system: {gbytes:g} GB/s / {bytes_per_view / 1e6:.2f} MB per view | {fs:.0f} |")
        least = min(fs, workers * per_worker, rates[2] * per_task)
        print(f"| **throughput with {gbytes:g} GB/s (the least)** | **{least:.0f}** |")
    print("\n" + json.dumps({"seconds": seconds, "noop_tasks_per_s": rates, "bytes_per_view": bytes_per_view}))


if __name__ == "__main__":
    main()
