#!/usr/bin/env python3
"""Summarises repeated runs of `cargo bench --bench peers -- --json` as Markdown tables of ranges.

    for i in 1 2 3; do cargo bench --bench peers -- --json; done > /tmp/peers.jsonl
    python3 scripts/peers-table.py /tmp/peers.jsonl

Each figure becomes "lowest–highest" over the runs (one value when they agree to the digit
shown). The ratio is taken within each run (raylab and obvhs alternate run by run, so they
share the machine's moment) and then given as its range. Lines that are not JSON (cargo's own
output) are skipped.
"""

import json
import sys
from collections import defaultdict


def rng(values, digits=1, suffix=""):
    lo, hi = min(values), max(values)
    a, b = f"{lo:.{digits}f}", f"{hi:.{digits}f}"
    return f"{a}{suffix}" if a == b else f"{a}–{b}{suffix}"


def main():
    rays = defaultdict(list)
    builds = defaultdict(list)
    cpu = obvhs = None
    for path in sys.argv[1:] or ["/dev/stdin"]:
        with open(path) as f:
            for line in f:
                line = line.strip()
                if not line.startswith("{"):
                    continue
                r = json.loads(line)
                if "rays" in r:
                    rays[(r["threads"], r["scene"], r["rays"])].append(r)
                    cpu, obvhs = r.get("cpu", cpu), r.get("obvhs", obvhs)
                else:
                    builds[(r["threads"], r["scene"])].append(r)
    runs = max((len(v) for v in rays.values()), default=0)
    print(f"<!-- {runs} run(s); {cpu}; obvhs {obvhs} -->")
    for threads in sorted({k[0] for k in rays}):
        print(f"\n**{threads} thread(s)**, Mrays/s (ranges over {runs} runs)\n")
        print("| scene | rays | raylab (batches of 64) | raylab (1 ray a call) | obvhs CWBVH "
              "| obvhs BVH2 | raylab / CWBVH | rays agreeing with CWBVH |")
        print("|---|---|---:|---:|---:|---:|---:|---:|")
        for (t, scene, kind), rs in rays.items():
            if t != threads:
                continue
            agree = [100 * r["agree_cwbvh"] for r in rs]
            print(f"| {scene} | {kind} "
                  f"| {rng([r['raylab_mrays_per_s'] for r in rs])} "
                  f"| {rng([r['raylab_single_mrays_per_s'] for r in rs])} "
                  f"| {rng([r['cwbvh_mrays_per_s'] for r in rs])} "
                  f"| {rng([r['bvh2_mrays_per_s'] for r in rs])} "
                  f"| {rng([r['ratio_cwbvh'] for r in rs], 2, '×')} "
                  f"| {rng(agree, 3, ' %')} |")
    for threads in sorted({k[0] for k in builds}):
        print(f"\n**{threads} thread(s)**, build ms\n")
        print("| scene | triangles | raylab | raylab structure | obvhs CWBVH | obvhs BVH2 |")
        print("|---|---:|---:|---|---:|---:|")
        for (t, scene), bs in builds.items():
            if t != threads:
                continue
            digits = 3 if max(b["raylab_build_ms"] for b in bs) < 1 else 1
            print(f"| {scene} | {bs[0]['triangles']:,} "
                  f"| {rng([b['raylab_build_ms'] for b in bs], digits)} "
                  f"| {bs[0]['raylab_structure']} "
                  f"| {rng([b['cwbvh_build_ms'] for b in bs], digits)} "
                  f"| {rng([b['bvh2_build_ms'] for b in bs], digits)} |")


if __name__ == "__main__":
    main()
