#!/usr/bin/env python3
"""chisel against Manifold on one scenario, in the same run, on the same tools.

    python3 benches/peer/compare.py CHISEL_BINARY SCENARIO N [chisel flags...]
        [--chisel-only] [--json] [--keep DIR]

SCENARIO is mill, cutter or fluted (N steps), cheese (N carves), sweep (N samples) or replay (N is
the JSON-lines file). chisel runs first with `--json --record OPS.jsonl`; the
recorded sequence (the exact 1 um grid points chisel used, in mm) is then
replayed with Manifold by manifold_replay.py in this process. Ratios are
Manifold / chisel, so a ratio above 1 means chisel is faster. Beside the wall
figures both report per-step CPU time, which unlike wall time is not inflated
by other processes on a loaded machine: chisel's of the thread that runs the
steps (its whole CPU cost with `--threads 1`), Manifold's of the whole process
(manifold3d runs parts of its Booleans on worker threads).
"""

import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import manifold_replay  # noqa: E402

SIZE_FLAG = {
    "mill": "--steps",
    "cutter": "--steps",
    "fluted": "--steps",
    "cheese": "--count",
    "sweep": "--samples",
}


def chisel_command(binary, scenario, n, extra, ops):
    if scenario == "replay":
        command = [binary, "replay", n]
    elif scenario in SIZE_FLAG:
        command = [binary, scenario, SIZE_FLAG[scenario], n]
    else:
        sys.exit(f"compare: unknown scenario {scenario}; use mill, cheese, cutter, fluted, sweep or replay")
    return command + extra + ["--json", "--record", ops]


def ratio(a, b):
    return a / b if b else float("nan")


def main():
    argv = sys.argv[1:]
    own = {"--chisel-only": False, "--json": False}
    keep = None
    rest = []
    i = 0
    while i < len(argv):
        if argv[i] in own:
            own[argv[i]] = True
        elif argv[i] == "--keep":
            keep = argv[i + 1]
            i += 1
        else:
            rest.append(argv[i])
        i += 1
    if len(rest) < 3:
        sys.exit(__doc__)
    binary, scenario, n, extra = rest[0], rest[1], rest[2], rest[3:]
    folder = keep or tempfile.mkdtemp(prefix="chisel-compare-")
    os.makedirs(folder, exist_ok=True)
    ops = os.path.join(folder, f"{scenario}-{os.path.basename(n)}.jsonl")
    command = chisel_command(binary, scenario, n, extra, ops)
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"compare: {' '.join(command)} failed:\n{run.stderr}")
    chisel = json.loads(run.stdout)
    result = {"command": " ".join(command), "ops": ops, "chisel": chisel}
    if not own["--chisel-only"]:
        peer = manifold_replay.replay(ops)
        result["manifold"] = peer
        result["ratios"] = {
            "total": ratio(peer["total_seconds"], chisel["total_seconds"]),
            # Manifold's whole CPU (all its threads) against chisel's one
            # stepping thread: the fair ratio with --threads 1
            "total_cpu": ratio(peer["total_process_cpu_seconds"], chisel["total_cpu_seconds"]),
            "chisel_cpu_last_over_first": ratio(
                chisel["cpu"]["last100_mean_ms"], chisel["cpu"]["first100_mean_ms"]
            ),
            "manifold_cpu_last_over_first": ratio(
                peer["process_cpu"]["last100_mean_ms"], peer["process_cpu"]["first100_mean_ms"]
            ),
            "median": ratio(peer["median_ms"], chisel["median_ms"]),
            "last100_mean": ratio(peer["last100_mean_ms"], chisel["last100_mean_ms"]),
            "chisel_last_over_first": ratio(chisel["last100_mean_ms"], chisel["first100_mean_ms"]),
            "manifold_last_over_first": ratio(peer["last100_mean_ms"], peer["first100_mean_ms"]),
            "volume_relative_difference": ratio(
                abs(peer["volume_mm3"] - chisel["volume_mm3"]), abs(chisel["volume_mm3"])
            ),
        }
    if own["--json"]:
        print(json.dumps(result))
        return
    print(f"chisel:   {result['command']}")
    print(f"sequence: {ops}")
    rows = [
        ("total s", "total_seconds", 3),
        ("total CPU s", "total_cpu_seconds", 3),
        ("median ms", "median_ms", 3),
        ("p99 ms", "p99_ms", 3),
        ("first 100 mean ms", "first100_mean_ms", 3),
        ("last 100 mean ms", "last100_mean_ms", 3),
        ("CPU median ms", ("cpu", "median_ms"), 3),
        ("CPU p99 ms", ("cpu", "p99_ms"), 3),
        ("CPU first 100 ms", ("cpu", "first100_mean_ms"), 3),
        ("CPU last 100 ms", ("cpu", "last100_mean_ms"), 3),
        ("triangles", "triangles", 0),
        ("volume mm^3", "volume_mm3", 6),
        ("peak memory MiB", "peak_memory_mib", 1),
    ]
    peer = result.get("manifold")
    print(f"{'':<20}{'chisel':>18}{'manifold':>18}{'ratio m/c':>12}")
    def figure(figures, key):
        # Manifold's CPU figures: its whole process (worker threads too).
        if figures is not chisel:
            key = {"total_cpu_seconds": "total_process_cpu_seconds"}.get(key, key)
            if isinstance(key, tuple) and key[0] == "cpu":
                key = ("process_cpu", key[1])
        return figures[key[0]][key[1]] if isinstance(key, tuple) else figures[key]

    for label, key, digits in rows:
        c = figure(chisel, key)
        line = f"{label:<20}{c:>18.{digits}f}"
        if peer is not None:
            m = figure(peer, key)
            line += f"{m:>18.{digits}f}{ratio(m, c):>12.2f}"
        print(line)
    if peer is not None:
        r = result["ratios"]
        print(f"last/first 100: chisel x{r['chisel_last_over_first']:.2f}, "
              f"manifold x{r['manifold_last_over_first']:.2f}; in CPU time chisel "
              f"x{r['chisel_cpu_last_over_first']:.2f}, manifold x{r['manifold_cpu_last_over_first']:.2f}")
        print(f"relative volume difference: {r['volume_relative_difference']:.3e}")
    o = chisel["octree"]
    print(f"chisel octree: {o['leaves']} leaves, {o['bsp_nodes']} BSP nodes, "
          f"{o['bytes_per_bsp_node']:.1f} B per node; threads {chisel['threads']}; "
          f"medians hull {chisel['hull_median_ms']:.3f} ms, apply {chisel['apply_median_ms']:.3f} ms")


if __name__ == "__main__":
    main()
