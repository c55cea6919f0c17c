#!/usr/bin/env python3
"""hsr-mpi's render and composite per rank, and the bytes each rank sends, as a markdown table.

  python3 bench/mpi_composite.py [--hsr-mpi build/hsr-mpi] [--ranks 1,2,4,8] [--size 1920x1080]
                                 [--scenes builtin:city,builtin:sphere] [--modes sparse,dense] [--repeat 3]

Each run is `mpirun -q --oversubscribe -n K hsr-mpi render SCENE --size WxH --threads 1 --depth
FILE --verbose` (one thread per rank); the figures are hsr-mpi's own per-rank lines, each the
least of --repeat runs. On a machine
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
                  r"stored depth ([\d.]+) ms, waited ([\d.]+) ms, composite ([\d.]+) ms, sent (\d+) bytes")


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


SAMPLE, PIXEL = 24, 16  # bytes: a composited Sample (key and payload), a gathered Pixel (payload)


def model(ranks, pixels, latency, bandwidth, coverage=1.0):
    """Seconds per stage on one rank's link (latency per message + bytes / bandwidth, messages one
    after another; reduction arithmetic and contention left out):
      binary swap:    log2 K rounds, each exchanging half of what a rank holds
      direct send:    K - 1 messages of 1/K of the image each (sparse: `coverage` of them carry data)
      reduce-scatter: MPI's recursive halving for a commutative operator: as binary swap
      gather:         the K - 1 other strips arriving at rank 0's link."""
    share = pixels * (1 - 1 / ranks)
    rounds = math.ceil(math.log2(ranks)) if ranks > 1 else 0
    swap = rounds * latency + SAMPLE * share / bandwidth
    direct = (ranks - 1) * latency + coverage * SAMPLE * share / bandwidth
    gather = (ranks - 1) * latency + PIXEL * share / bandwidth
    return swap, direct, swap, gather


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--hsr-mpi", default="build/hsr-mpi")
    p.add_argument("--mpirun", default="mpirun")
    p.add_argument("--ranks", default="1,2,4,8")
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--scenes", default="builtin:city,builtin:sphere")
    p.add_argument("--modes", default="sparse,dense")
    p.add_argument("--repeat", type=int, default=3, help="runs of each case; each figure is its least over them")
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
                    runs = [run(a.hsr_mpi, a.mpirun, k, scene, a.size, mode, os.path.join(tmp, "d.npy"))
                            for _ in range(a.repeat)]
                    rows = [[min(field) for field in zip(*rank)] for rank in zip(*(r[0] for r in runs))]
                    wall = min(r[1] for r in runs)
                    cpu = [r[5] for r in rows]
                    rect = max(r[2] * r[3] for r in rows) / 1e6
                    sent = [r[9] for r in rows]
                    print(f"| {scene} | {k} | {mode} | {max(cpu):.1f} / {sum(cpu):.1f} | {rect:.2f} "
                          f"| {max(r[6] for r in rows):.1f} | {max(r[8] for r in rows):.1f} "
                          f"| {max(sent) / 1e6:.1f} | {sum(sent) / 1e6:.1f} | {wall:.2f} |")

    # The model on an assumed interconnect: 2 us per message, 10 GB/s per link.
    latency, bandwidth = 2e-6, 10e9
    print(f"\nCost model: {latency * 1e6:g} us per message, {bandwidth / 1e9:g} GB/s per link, {SAMPLE} bytes a "
          f"composited pixel, {PIXEL} gathered; seconds per stage on one rank's link:\n")
    print("| ranks | megapixels | binary swap | direct send, dense | direct send, 10% covered | reduce-scatter "
          "| gather to rank 0 | best total |")
    print("|---|---|---|---|---|---|---|---|")
    for ranks, mpx in ((8, 2.07), (1000, 2.07), (1000, 64), (32768, 64)):
        swap, direct, rs, gather = model(ranks, mpx * 1e6, latency, bandwidth)
        sparse = model(ranks, mpx * 1e6, latency, bandwidth, 0.1)[1]
        best = min(swap, direct, sparse, rs) + gather
        print(f"| {ranks} | {mpx} | {swap:.4f} | {direct:.4f} | {sparse:.4f} | {rs:.4f} | {gather:.4f} | {best:.4f} |")


if __name__ == "__main__":
    main()
