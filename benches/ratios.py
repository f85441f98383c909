#!/usr/bin/env python3
"""Prints the ratios BENCHMARKS.md reports from the last `cargo bench -p busspec-benches` run
(criterion's target/criterion/*/new/estimates.json; medians). Standard library only."""
import json
import pathlib
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "target/criterion")


def median(group, bench):
    """Median time of one benchmark, in ns."""
    path = root / group / bench / "new" / "estimates.json"
    return json.loads(path.read_text())["median"]["point_estimate"]


def units(group, bench):
    t = json.loads((root / group / bench / "new" / "benchmark.json").read_text())["throughput"]
    return next(iter(t.values()))


def row(*cells):
    print("| " + " | ".join(cells) + " |")


for p in ["ub2", "sd"]:
    print(f"\n### {p}\n")
    row("group", "contender", "median per iteration", "per frame", "vs generated")
    row(*["---"] * 5)
    for op in ["decode", "encode"]:
        g = f"{p}_{op}"
        base = median(g, "generated/frames")
        frames = units(g, "generated/frames")
        for who in ["generated", "hand-written", "deku", "interpreter"]:
            t = median(g, f"{who}/frames")
            row(f"{p}/{op}", who, f"{t / 1000:.2f} µs", f"{t / frames:.1f} ns", f"{t / base:.2f}×")
    g = f"{p}_stream"
    floor = median(g, "plain-sum")
    capture = units(g, "generated")
    for who in ["generated", "plain-sum", "interpreter-64KiB"]:
        t = median(g, who)
        n = units(g, who)
        row(f"{p}/stream", who, f"{t / 1e6:.3f} ms ({n} B)", f"{t / n:.3f} ns/B",
            f"{(t / n) / (floor / capture):.1f}× the plain pass")
    g = f"{p}_checksum"
    base = median(g, "generated")
    others = sorted(d.name for d in (root / g).iterdir() if (d / "new").is_dir())
    for who in ["generated"] + [o for o in others if o != "generated"]:
        t = median(g, who)
        row(f"{p}/checksum", who, f"{t / 1000:.3f} µs", f"{t / 128:.1f} ns", f"{t / base:.2f}×")
