#!/usr/bin/python3
"""The painter's family on the SIMD tile kernel against the tiled z-buffer, in alternating rounds:
each round runs `hsr bench SCENE --size WxH --frames F --threads T --algorithm A --param
raster=tiled` for every algorithm in turn, the z-buffer included, so that each ratio is taken
within one round while the machine's speed drifts. Prints a Markdown table: the median of the
rounds' medians, and the median (range) of the per-round ratios to the z-buffer.

Run: /usr/bin/python3 bench/painter_family.py [--rounds 5] [--hsr build/hsr]
"""
import argparse
import json
import statistics
import subprocess

CASES = {
    "builtin:city": ["zbuffer", "painter", "reverse-painter", "bsp", "newell", "sorted-zbuffer"],
    "builtin:random?n=10000": ["zbuffer", "painter", "reverse-painter", "bsp", "sorted-zbuffer"],
}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--hsr", default="build/hsr")
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--threads", type=int, default=2)
    args = p.parse_args()
    times = {}
    for _ in range(args.rounds):
        for scene, algorithms in CASES.items():
            frames = "5" if "random" in scene else "10"  # (random's BSP frames take ~0.2 s each)
            for a in algorithms:
                cmd = [args.hsr, "bench", scene, "--size", args.size, "--frames", frames, "--threads",
                       str(args.threads), "--json", "--algorithm", a]
                if a != "zbuffer":
                    cmd += ["--param", "raster=tiled"]
                out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
                times.setdefault((scene, a), []).append(json.loads(out)["median_ms"])
    print("| scene | algorithm | ms (median of rounds) | / zbuffer, median (range) of rounds |")
    print("|---|---|---:|---:|")
    for scene, algorithms in CASES.items():
        z = times[(scene, "zbuffer")]
        for a in algorithms:
            ms = times[(scene, a)]
            ratios = [m / zz for m, zz in zip(ms, z)]
            label = a if a == "zbuffer" else a + " raster=tiled"
            print(f"| {scene} | {label} | {statistics.median(ms):.2f} | "
                  f"{statistics.median(ratios):.2f} ({min(ratios):.2f}–{max(ratios):.2f}) |")


if __name__ == "__main__":
    main()
