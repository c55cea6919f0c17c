#!/usr/bin/env python3
"""hsr-mpi's render and composite per rank, and the bytes each rank sends, as a markdown table.

  python3 bench/mpi_composite.py [--hsr-mpi build/hsr-mpi] [--ranks 1,2,4,8] [--size 1920x1080]
                                 [--scenes builtin:city,builtin:sphere] [--modes sparse,dense]

Each run is `mpirun -q --oversubscribe -n K hsr-mpi render SCENE --size WxH --threads 1 --depth
FILE --verbose` (one thread per rank); the figures are hsr-mpi's own per-rank lines. On a machine
with fewer cores than ranks the ranks share the cores: the CPU time of a rank's render and the
bytes are what carries over to a cluster, the wall times are not. Then the cost model of
docs/distributed.md, extrapolated to 1,000 ranks and 64 megapixels.
"""
import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time

RANK = re.compile(r"rank (\d+): triangles (\d+), covers (\d+)x(\d+), render ([\d.]+) ms \(([\d.]+) ms CPU\), "
                  r"stored depth ([\d.]+) ms, composite ([\d.]+) ms, sent (\d+) bytes")


def run(hsr_mpi, mpirun, ranks, scene, size, mode, out):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = [mpirun, "-q", "--oversubscribe", "-n", str(ranks), hsr_mpi, "render", scene, "--size", size,
           "--threads", "1", "--depth", out, "--composite", mode, "--verbose"]
    start = time.monotonic()
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.monotonic() - start
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr}")
    rows = [RANK.search(line) for line in r.stdout.splitlines()]
    rows = [[float(x) for x in m.groups()] for m in rows if m]
    return rows, wall


def model(ranks, pixels, bytes_per_pixel, latency, bandwidth):
    """Seconds to composite `pixels` over `ranks` by three schemes (latency + bytes/bandwidth per
    message, a rank's messages one after another): binary swap, direct send, reduce-scatter."""
    image = pixels * bytes_per_pixel
    stages = math.ceil(math.log2(ranks))
    # Binary swap: log2 K rounds, each exchanging half of what a rank holds: (1 - 1/K) of the image.
    swap = stages * latency + image * (1 - 1 / ranks) / bandwidth
    # Direct send, dense: K - 1 messages of 1/K of the image each.
    direct = (ranks - 1) * latency + image * (1 - 1 / ranks) / bandwidth
    # Reduce-scatter (recursive halving for large messages, as MPICH and OpenMPI pick): as binary swap.
    reduce_scatter = stages * latency + image * (1 - 1 / ranks) / bandwidth
    # The gather of the final image to one rank: K - 1 strips arrive at rank 0's link.
    gather = (ranks - 1) * latency + image * (1 - 1 / ranks) / bandwidth
    return swap, direct, reduce_scatter, gather


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--hsr-mpi", default="build/hsr-mpi")
    p.add_argument("--mpirun", default="mpirun")
    p.add_argument("--ranks", default="1,2,4,8")
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--scenes", default="builtin:city,builtin:sphere")
    p.add_argument("--modes", default="sparse,dense")
    a = p.parse_args()
    print(f"date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
          f"commit: {subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], capture_output=True, text=True).stdout.strip()}")
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "unknown")
    print(f"cpu: {cpu}, {os.cpu_count()} cores; ranks oversubscribed, one thread each; size {a.size}\n")
    print("| scene | K | composite | render CPU ms per rank (max / sum) | covered rect per rank (max, Mpx) "
          "| stored depth ms (max) | composite ms (max) | MB sent per rank (max) | MB sent (all ranks) | job wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in a.scenes.split(","):
            for k in [int(x) for x in a.ranks.split(",")]:
                for mode in a.modes.split(","):
                    rows, wall = run(a.hsr_mpi, a.mpirun, k, scene, a.size, mode, os.path.join(tmp, "d.npy"))
                    cpu = [r[5] for r in rows]
                    rect = max(r[2] * r[3] for r in rows) / 1e6
                    sent = [r[8] for r in rows]
                    print(f"| {scene} | {k} | {mode} | {max(cpu):.1f} / {sum(cpu):.1f} | {rect:.2f} "
                          f"| {max(r[6] for r in rows):.1f} | {max(r[7] for r in rows):.1f} "
                          f"| {max(sent) / 1e6:.1f} | {sum(sent) / 1e6:.1f} | {wall:.2f} |")

    # The model: 24 bytes per pixel (key 8, depth 4, face 4, triangle 4, colour 4), a link of
    # 1 us latency and 10 GB/s (an InfiniBand-class interconnect), 1,000 ranks, 64 megapixels.
    print("\nCost model (latency 1 us, 10 GB/s per link, 24 bytes a pixel; one rank's link, messages in sequence):\n")
    print("| ranks | megapixels | binary swap s | direct send s | reduce-scatter s | gather to rank 0 s |")
    print("|---|---|---|---|---|---|")
    for ranks, mpx in ((8, 2.07), (1000, 64), (32768, 64)):
        s = model(ranks, mpx * 1e6, 24, 1e-6, 10e9)
        print(f"| {ranks} | {mpx} | {s[0]:.4f} | {s[1]:.4f} | {s[2]:.4f} | {s[3]:.4f} |")


if __name__ == "__main__":
    main()
