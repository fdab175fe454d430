#!/usr/bin/env python3
"""Replays a chisel operation sequence (JSON lines) with Manifold, timing each step.

    python3 benches/peer/manifold_replay.py OPS.jsonl [--json]

The file is what `chisel mill|cheese|sweep|replay --record OPS.jsonl` writes:
a first line `{"base": {"box": [[x0,y0,z0],[x1,y1,z1]]}}` (or `{"base": "empty"}`,
or `{"base": {"mesh": "FILE.obj"}}`), then one line per step
`{"op": "subtract"|"union"|"intersect", "hull": [[x,y,z], ...]}` in millimetres.
The points are the exact 1 um grid points chisel used, so both libraries cut with
the same tools.

One step = `Manifold.hull_points(points)` and the Boolean with the workpiece,
evaluated (Manifold's Booleans are lazy: `num_tri()` forces them). That is the
same work a chisel step does before re-extraction: build the tool, apply it.
"""

import json
import os
import resource
import statistics
import sys
import time

import manifold3d
from manifold3d import Manifold, Mesh
import numpy as np


def read_obj(path):
    """Positions and triangles of an OBJ file (fan-triangulated faces)."""
    positions, triangles = [], []
    with open(path, encoding="utf-8") as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                positions.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(p.split("/")[0]) for p in parts[1:]]
                idx = [i - 1 if i > 0 else len(positions) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    triangles.append([idx[0], idx[k], idx[k + 1]])
    return positions, triangles


def base_manifold(base, folder):
    """The starting solid of a sequence; a relative mesh path is taken from `folder`."""
    if base == "empty":
        return Manifold()
    if "box" in base:
        lo, hi = base["box"]
        size = [hi[a] - lo[a] for a in range(3)]
        return Manifold.cube(size).translate(lo)
    if "mesh" in base:
        path = os.path.join(folder, base["mesh"])
        if not path.lower().endswith(".obj"):
            sys.exit(f"manifold_replay: only OBJ mesh bases are supported here, got {path}")
        positions, triangles = read_obj(path)
        mesh = Mesh(
            vert_properties=np.array(positions, dtype=np.float32),
            tri_verts=np.array(triangles, dtype=np.uint32),
        )
        mesh.merge()
        solid = Manifold(mesh)
        if solid.status() != manifold3d.Error.NoError:
            sys.exit(f"manifold_replay: {path} is not a manifold mesh: {solid.status()}")
        return solid
    sys.exit(f"manifold_replay: unknown base {base}")


def read_sequence(path):
    """(base, [(op, points)]) from a JSON-lines file; exits with the line number on errors."""
    base, steps = None, []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            try:
                item = json.loads(line)
                if base is None:
                    base = item["base"]
                else:
                    steps.append((item["op"], np.array(item["hull"], dtype=np.float64)))
            except (ValueError, KeyError, TypeError) as e:
                sys.exit(f"manifold_replay: {path}:{number}: {e}")
    if base is None:
        sys.exit(f"manifold_replay: {path}: empty file")
    return base, steps


def latency(seconds):
    """Per-step statistics in milliseconds, as chisel reports them."""
    ms = sorted(s * 1e3 for s in seconds)
    n = len(ms)
    per_step = [s * 1e3 for s in seconds]
    k = min(n, 100)
    return {
        "median_ms": statistics.median(ms) if n else 0.0,
        "p99_ms": ms[max(1, -(-99 * n // 100)) - 1] if n else 0.0,
        "mean_ms": statistics.fmean(ms) if n else 0.0,
        "first100_mean_ms": statistics.fmean(per_step[:k]) if n else 0.0,
        "last100_mean_ms": statistics.fmean(per_step[n - k:]) if n else 0.0,
    }


def replay(path, progress=False):
    """Runs the sequence; returns the figures as a dict."""
    base, steps = read_sequence(path)
    t0 = time.perf_counter()
    work = base_manifold(base, os.path.dirname(os.path.abspath(path)))
    work.num_tri()
    setup = time.perf_counter() - t0
    seconds, cpu_seconds, process_cpu_seconds = [], [], []
    start = time.perf_counter()
    start_cpu = time.thread_time()
    start_process_cpu = time.process_time()
    for i, (op, points) in enumerate(steps):
        t = time.perf_counter()
        c = time.thread_time()
        pc = time.process_time()
        tool = Manifold.hull_points(points)
        if op == "subtract":
            work = work - tool
        elif op == "union":
            work = work + tool
        elif op == "intersect":
            work = work ^ tool
        else:
            sys.exit(f"manifold_replay: step {i + 1}: unknown op {op}")
        work.num_tri()
        cpu_seconds.append(time.thread_time() - c)
        process_cpu_seconds.append(time.process_time() - pc)
        seconds.append(time.perf_counter() - t)
        if progress and (i + 1) % 100 == 0:
            print(f"\rmanifold {i + 1}/{len(steps)}", end="", file=sys.stderr, flush=True)
    total = time.perf_counter() - start
    total_cpu = time.thread_time() - start_cpu
    total_process_cpu = time.process_time() - start_process_cpu
    if progress:
        print(file=sys.stderr)
    return {
        "peer": "manifold3d",
        "steps": len(seconds),
        "setup_seconds": setup,
        "total_seconds": total,
        # CPU time of this thread, as chisel reports it with --threads 1,
        # and of the whole process: manifold3d's Booleans also run parts
        # on worker threads (spiral, 1,500 steps: 25.6 s on this thread,
        # 34.0 s in all), so the process figures are its whole cost
        "total_cpu_seconds": total_cpu,
        "total_process_cpu_seconds": total_process_cpu,
        **latency(seconds),
        "cpu": latency(cpu_seconds),
        "process_cpu": latency(process_cpu_seconds),
        "triangles": work.num_tri(),
        "volume_mm3": work.volume(),
        "status": str(work.status()),
        "peak_memory_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) != 1:
        sys.exit(__doc__)
    figures = replay(args[0], progress=sys.stderr.isatty() and "--json" not in sys.argv)
    if "--json" in sys.argv:
        print(json.dumps(figures))
    else:
        for key, value in figures.items():
            print(f"{key:<18}{value}")


if __name__ == "__main__":
    main()
