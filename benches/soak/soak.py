#!/usr/bin/env python3
"""Soak benchmark: resident memory of a long GPU render, sampled once a second.

    python3 benches/soak/soak.py [--seconds 60] [--binary target/release/rt-gpu] [-- RENDER ARGS]

Runs `rt-gpu RENDER ARGS` (default: two cases, the Cornell box at 512x512 and a 1x1 image, whose
dispatches are many and short), samples VmRSS from /proc every second, stops the render after
--seconds, and prints the curve. Memory counts as flat when it grows by at most --limit-mb
(default 50) after the first --warmup seconds (default 5: device, kernel compilation, buffers).
Exits 1 when a case is not flat.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

DEFAULT_CASES = [
    ["cornell", "--spp", "1000000"],
    ["cornell", "--size", "1x1", "--spp", "1000000000"],
]


def rss_mb(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024
    except FileNotFoundError:
        return None
    return None


def soak(binary, args, seconds, warmup, limit_mb, out_dir):
    cmd = [binary, *args, "-o", os.path.join(out_dir, "soak.exr")]
    print("$", " ".join(cmd), flush=True)
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    curve = []
    start = time.monotonic()
    while time.monotonic() - start < seconds and proc.poll() is None:
        time.sleep(1.0)
        mb = rss_mb(proc.pid)
        if mb is not None:
            curve.append((time.monotonic() - start, mb))
    ended_early = proc.poll() is not None
    proc.terminate()
    _, err = proc.communicate()
    if ended_early and proc.returncode != 0:
        print(f"  render failed: {err.strip().splitlines()[-1] if err.strip() else proc.returncode}")
        return False
    print("  t(s)  RSS(MB)")
    for t, mb in curve:
        print(f"  {t:5.1f} {mb:8.1f}")
    settled = [mb for t, mb in curve if t >= warmup]
    if len(settled) < 2:
        print("  too short to judge")
        return False
    growth = max(settled) - settled[0]
    flat = growth <= limit_mb
    print(f"  growth after {warmup:.0f} s: {growth:.1f} MB over {curve[-1][0]:.0f} s "
          f"({'flat' if flat else 'NOT flat'}, limit {limit_mb} MB)")
    return flat


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=60)
    parser.add_argument("--warmup", type=float, default=5)
    parser.add_argument("--limit-mb", type=float, default=50)
    parser.add_argument("--binary", default="target/release/rt-gpu")
    parser.add_argument("render", nargs="*", help="render arguments (after --)")
    a = parser.parse_args()
    cases = [a.render] if a.render else DEFAULT_CASES
    with tempfile.TemporaryDirectory() as out_dir:
        results = [soak(a.binary, c, a.seconds, a.warmup, a.limit_mb, out_dir) for c in cases]
    sys.exit(0 if all(results) else 1)


if __name__ == "__main__":
    main()
