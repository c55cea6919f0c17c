#!/usr/bin/env python3
"""hsr-mpi against hsr, end to end (registered by tests/mpi/CMakeLists.txt).

  mpi_check.py same HSR HSR_MPI MPIRUN RANKS SCENE [FLAG ...]
      `hsr render` and `mpirun -n RANKS hsr-mpi render` with the same flags write the same bytes
      (ids, depth, colour), and hsr-mpi's --verify finds no wrong pixel. With --expect-empty-rank
      among the flags (taken out before running), some rank must have had no triangles; with
      --expect-share, every rank must have loaded only its share of the scene's entries (the
      shares' triangles add up to the scene's).
  mpi_check.py fails HSR HSR_MPI MPIRUN RANKS STATUS EXPECTED SCENE [FLAG ...]
      hsr-mpi ends with exit status STATUS (2: bad input, 1: an output not written), exactly one
      line on stderr (containing EXPECTED), no output file, and well within the test's timeout
      (no rank waits forever).

--composite MODE is hsr-mpi's alone: it is passed to hsr-mpi only.
"""
import json
import os
import re
import subprocess
import sys
import tempfile

TIMEOUT = 100  # seconds; ctest's TIMEOUT is above it


def run(cmd):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT)


def mpi(mpirun, ranks, hsr_mpi, args):
    # -q: mpirun's own notice of a non-zero exit status would add lines to stderr.
    return run([mpirun, "-q", "--oversubscribe", "-n", str(ranks), hsr_mpi, "render"] + args)


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def same(hsr, hsr_mpi, mpirun, ranks, scene, flags):
    expect_empty = "--expect-empty-rank" in flags
    expect_share = "--expect-share" in flags
    flags = [f for f in flags if f not in ("--expect-empty-rank", "--expect-share")]
    mpi_flags = []
    if "--composite" in flags:
        at = flags.index("--composite")
        mpi_flags, flags = flags[at:at + 2], flags[:at] + flags[at + 2:]
    with tempfile.TemporaryDirectory() as tmp:
        outs = {}
        for name in ("one", "many"):
            d = os.path.join(tmp, name)
            os.mkdir(d)
            outs[name] = {k: os.path.join(d, k) for k in ("ids.npy", "depth.npy", "color.png")}
        files = lambda o: ["--ids", o["ids.npy"], "--depth", o["depth.npy"], "-o", o["color.png"]]
        one = run([hsr, "render", scene] + flags + files(outs["one"]) + ["--quiet"])
        if one.returncode != 0:
            fail(f"hsr render exited {one.returncode}: {one.stderr}")
        stats = os.path.join(tmp, "many", "stats.json")
        many = mpi(mpirun, ranks, hsr_mpi,
                   [scene] + flags + mpi_flags + files(outs["many"]) + ["--verify", "--stats", stats, "--verbose"])
        if many.returncode != 0:
            fail(f"hsr-mpi exited {many.returncode}: {many.stderr}")
        for k in ("ids.npy", "depth.npy", "color.png"):
            a = open(outs["one"][k], "rb").read()
            b = open(outs["many"][k], "rb").read()
            if a != b:
                fail(f"{k} differs from hsr render's ({len(a)} and {len(b)} bytes) with {ranks} ranks on {scene}")
        s = json.load(open(stats))
        if s.get("wrong_pixels") != 0:
            fail(f"--verify: {s.get('wrong_pixels')} wrong pixels")
        if s["zbuffer"]["mpi_ranks"] != ranks:
            fail(f"statistics name {s['zbuffer']['mpi_ranks']} ranks, not {ranks}")
        rank_lines = [l for l in many.stdout.splitlines() if l.strip().startswith("rank ")]
        if len(rank_lines) != ranks:
            fail(f"--verbose printed {len(rank_lines)} rank lines for {ranks} ranks:\n{many.stdout}")
        empty = [l for l in rank_lines if "triangles 0," in l]
        if expect_share:
            shares = [re.search(r"loaded entries (\d+)\.\.(\d+) \((\d+) triangles\)", l) for l in rank_lines]
            if not all(shares):
                fail("a rank did not load a share of the entries:\n" + many.stdout)
            if sum(int(m.group(3)) for m in shares) != s["triangles"]:
                fail(f"the shares' triangles do not add up to the scene's {s['triangles']}:\n" + many.stdout)
            if any(a.group(2) != b.group(1) for a, b in zip(shares, shares[1:])):
                fail("the ranks' entries are not consecutive runs:\n" + many.stdout)
        if expect_empty and not empty:
            fail("no rank was empty:\n" + many.stdout)
        print(f"ok: {scene} {' '.join(flags)} on {ranks} ranks: ids, depth and colour equal hsr render's;"
              f" {len(empty)} empty ranks; {s['zbuffer']['mpi_bytes_sent']} bytes sent")


def fails(hsr, hsr_mpi, mpirun, ranks, status, expected, scene, flags):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "depth.npy")
        r = mpi(mpirun, ranks, hsr_mpi, [scene, "--depth", out] + flags)
        lines = r.stderr.splitlines()
        if r.returncode != status:
            fail(f"exit status {r.returncode}, not {status}; stderr:\n{r.stderr}")
        if len(lines) != 1 or not lines[0].startswith("hsr-mpi: ") or expected not in lines[0]:
            fail(f"expected one line 'hsr-mpi: ...{expected}...', got {len(lines)}:\n{r.stderr}")
        if os.listdir(tmp):
            fail(f"files left behind: {os.listdir(tmp)}")
        print(f"ok: {lines[0]}")


def main(argv):
    mode, hsr, hsr_mpi, mpirun, ranks = argv[1], argv[2], argv[3], argv[4], int(argv[5])
    if mode == "same":
        same(hsr, hsr_mpi, mpirun, ranks, argv[6], argv[7:])
    elif mode == "fails":
        fails(hsr, hsr_mpi, mpirun, ranks, int(argv[6]), argv[7], argv[8], argv[9:])
    else:
        fail("unknown mode " + mode)


if __name__ == "__main__":
    main(sys.argv)
