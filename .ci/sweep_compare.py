#!/usr/bin/env python3
"""Compare two collected sweeps (issue 28), or two CSV tables, cell by cell as text.

usage: sweep_compare.py SWEEP_DIR_A SWEEP_DIR_B
       sweep_compare.py --csv A.csv B.csv

Sweeps: both sweep.csv files must have the same header, the same tasks and parameters, and every
non-timing figure must be bit-identical (the same number text; summary.json writes the shortest
text that reads back to the same f64). Timing figures are the keys any task listed in timing.json
(collected into sweep-status.json), plus those summary_diff.py's TIMING pattern names (runners and
benches that do not write timing.json), plus `mode`.

Tables (--csv): same header and row count; every column the TIMING pattern does not name must be
equal. Used to check that a benchmark's sweep run as separate tasks gives the table the bench
writes in one process.

Exit status 1 if anything differs.
"""
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from summary_diff import TIMING  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def compare(a_path, b_path, timing_keys, key_cols):
    ha, ra = read(a_path)
    hb, rb = read(b_path)
    bad = 0
    if ha != hb:
        print(f"headers differ:\n  {ha}\n  {hb}")
        return 1, 0, 0
    if len(ra) != len(rb):
        print(f"{a_path}: {len(ra)} rows, {b_path}: {len(rb)} rows")
        return 1, 0, 0
    compared = 0
    skipped = sorted({h for h in ha[key_cols:] if h in timing_keys or TIMING.search(h) or h == "mode"})
    for i, (x, y) in enumerate(zip(ra, rb)):
        if x[:key_cols] != y[:key_cols]:
            print(f"row {i}: {x[:key_cols]} != {y[:key_cols]}")
            bad += 1
            continue
        for h, u, v in zip(ha[key_cols:], x[key_cols:], y[key_cols:]):
            if h in skipped:
                continue
            compared += 1
            if u != v:
                print(f"row {i} ({', '.join(x[:key_cols])}): {h}: {u} != {v}")
                bad += 1
    return bad, compared, len(skipped)


def main(argv):
    args = argv[1:]
    if len(args) == 3 and args[0] == "--csv":
        bad, compared, skipped = compare(args[1], args[2], set(), 0)
        what = "table cells"
    elif len(args) == 2:
        timing = set()
        for d in args:
            with open(os.path.join(d, "sweep-status.json")) as f:
                st = json.load(f)
            timing |= set(st["timing"])
            nparams = len(st["parameters"])
        bad, compared, skipped = compare(
            os.path.join(args[0], "sweep.csv"), os.path.join(args[1], "sweep.csv"), timing, 1 + nparams
        )
        what = "non-timing figures"
    else:
        print(__doc__)
        return 2
    print(f"{compared} {what} compared ({skipped} timing columns left out), {bad} differences")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
