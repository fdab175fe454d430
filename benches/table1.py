#!/usr/bin/env python3
"""Prints paper 1's Table 1 as measured by `cargo bench -p chisel_bsp --bench predicates`.

Reads criterion's estimates (median ns per operation) from
$CARGO_TARGET_DIR/criterion (default: $HOME/.cache/bevy_chisel/target/criterion)
and prints a Markdown table with the speed-up over the num-bigint version of each
operation and the issue's targets.
"""
import json
import os
import sys

TARGET_DIR = os.environ.get(
    "CARGO_TARGET_DIR", os.path.join(os.path.expanduser("~"), ".cache/bevy_chisel/target")
)
ROOT = os.path.join(TARGET_DIR, "criterion")

# (group, variant, label, target in ns or None)
ROWS = [
    ("plane_from_points", "fixed", "plane_from_points", None),
    ("plane_from_points_normalized", "fixed", "plane_from_points (gcd-normalized)", None),
    ("are_planes_parallel", "fixed", "are_planes_parallel", None),
    ("intersect_3_planes", "fixed", "intersect_3_planes (with f64 cache)", 40.0),
    ("classify_vertex", "exact", "classify_vertex, exact path", 12.0),
    ("classify_vertex", "filtered", "classify_vertex, filtered", 5.0),
    ("classify_vertex", "filtered_on_plane", "classify_vertex, filtered, vertex on plane", None),
]


def median_ns(group, variant):
    """Median time per operation: criterion's median per batch over the batch size."""
    base = os.path.join(ROOT, group, variant, "new")
    try:
        with open(os.path.join(base, "estimates.json")) as f:
            per_batch = json.load(f)["median"]["point_estimate"]
        with open(os.path.join(base, "benchmark.json")) as f:
            elements = (json.load(f).get("throughput") or {}).get("Elements", 1)
        return per_batch / elements
    except (OSError, KeyError, ValueError, TypeError):
        return None


def main():
    print("| operation | median ns/op | num-bigint ns/op | speed-up | target | met |")
    print("|---|---:|---:|---:|---|---|")
    missing = False
    for group, variant, label, target in ROWS:
        ns = median_ns(group, variant)
        big = median_ns(group, "bigint")
        if ns is None:
            missing = True
            print(f"| {label} | (not measured) | | | | |")
            continue
        speedup = big / ns if big else None
        goals, met = [], []
        if target is not None:
            goals.append(f"<= {target:g} ns")
            met.append(ns <= target)
        if speedup is not None:
            goals.append(">= 20x bigint")
            met.append(speedup >= 20.0)
        verdict = "yes" if met and all(met) else ("no" if met else "")
        print(
            f"| {label} | {ns:.1f} | {big:.0f} | {speedup:.0f}x | {', '.join(goals)} | {verdict} |"
            if big
            else f"| {label} | {ns:.1f} | | | {', '.join(goals)} | {verdict} |"
        )
    if missing:
        print("\nSome results are missing: run `cargo bench -p chisel_bsp --bench predicates` first.",
              file=sys.stderr)


if __name__ == "__main__":
    main()
