#!/usr/bin/env python3
"""Per function (or per source line) share of the instructions stepcount counted.

    scripts/stepcount-report.py HISTOGRAM EXECUTABLE PIXELS [--lines] [--top N]

Addresses are turned into functions and lines by binutils' addr2line (the release profile keeps
line tables); a function inlined into another counts under the outer one, as a profiler's
"self" time would. Prints instructions and taken branches per pixel.
"""
import argparse
import collections
import subprocess


def main():
    p = argparse.ArgumentParser()
    p.add_argument("histogram")
    p.add_argument("executable")
    p.add_argument("pixels", type=int)
    p.add_argument("--lines", action="store_true", help="per innermost source line")
    p.add_argument("--top", type=int, default=15)
    a = p.parse_args()

    with open(a.histogram) as f:
        base = int(f.readline().split()[1], 16)
        rows = [line.split() for line in f if line.strip()]
    entries = [(int(addr, 16) - base, int(taken), int(executed)) for addr, taken, executed in rows]
    out = subprocess.run(
        ["addr2line", "-e", a.executable, "-f", "-C", "-i", "-a"] + [hex(e[0]) for e in entries],
        capture_output=True, text=True, check=True,
    ).stdout.splitlines()
    # addr2line -a -i: the address, then (function, file:line) pairs, innermost first.
    chains, address, chain, i = {}, None, [], 0
    while i < len(out):
        if out[i].startswith("0x"):
            if address is not None:
                chains[address] = chain
            address, chain, i = int(out[i], 16), [], i + 1
        else:
            chain.append((out[i], out[i + 1] if i + 1 < len(out) else "?"))
            i += 2
    if address is not None:
        chains[address] = chain

    def key(addr):
        chain = chains.get(addr) or [("?", "?")]
        function = chain[-1][0][:80]
        if a.lines:
            return f"{function} @ {chain[0][1].rsplit('/', 1)[-1]}"
        return function

    executed, taken = collections.Counter(), collections.Counter()
    for addr, t, n in entries:
        executed[key(addr)] += n
        taken[key(addr)] += t
    total, total_taken = sum(executed.values()), sum(taken.values())
    print(f"{total / a.pixels:8.1f} instructions and {total_taken / a.pixels:.1f} taken branches a pixel")
    for k, n in executed.most_common(a.top):
        print(f"{n / a.pixels:8.1f} {100 * n / total:5.1f} %  taken {taken[k] / a.pixels:5.1f}  {k}")


if __name__ == "__main__":
    main()
