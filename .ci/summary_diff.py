#!/usr/bin/env python3
"""Compare the summary.json files of two output trees (e.g. `cargo xtask repro --quick` before and
after a refactor): every run present in both must have the same keys, and every non-timing figure
must be bit-identical (compared as the exact JSON number text).

usage: summary_diff.py BEFORE_DIR AFTER_DIR [--only PREFIX] [--timing REGEX]

Timing figures (wall times, per-step times, rates, speed-ups, overheads and ratios measured from
times, thread counts) are listed as such and not compared. Exit status 1 if anything differs.
"""
import json
import math
import os
import re
import sys

TIMING = re.compile(
    r"(^|_)(wall|time|times|s_per|ms_per|per_step|per_frame|per_s|fps|speedup|overhead|threads|"
    r"profile|hz_achieved|throughput|elapsed|cost_ratio|time_ratio|kkt_over)(_|$)"
    r"|_(s|ms|us|ns)$|_s_|_ms_|_seconds|seconds_|^t_|_t_(assembly|factor|solve|collision)"
)


def load(root):
    runs = {}
    for dirpath, _dirs, files in os.walk(root):
        if "summary.json" in files:
            rel = os.path.relpath(dirpath, root)
            with open(os.path.join(dirpath, "summary.json")) as f:
                # Keep numbers as their exact text so that "bit-identical" means what it says.
                runs[rel] = json.load(f, parse_float=lambda s: ("num", s), parse_int=lambda s: ("num", s))
    return runs


def main(argv):
    args = [a for a in argv[1:]]
    only = None
    timing = TIMING
    if "--only" in args:
        i = args.index("--only")
        only = args[i + 1]
        del args[i : i + 2]
    if "--timing" in args:
        i = args.index("--timing")
        timing = re.compile(TIMING.pattern + "|" + args[i + 1])
        del args[i : i + 2]
    if len(args) != 2:
        print(__doc__)
        return 2
    before, after = load(args[0]), load(args[1])
    bad = 0
    compared = 0
    for run in sorted(set(before) | set(after)):
        if only and not run.startswith(only):
            continue
        if run not in before or run not in after:
            print(f"{run}: only in {'before' if run in before else 'after'}")
            bad += 1
            continue
        a, b = before[run], after[run]
        ka, kb = set(a), set(b)
        for k in sorted(ka - kb):
            print(f"{run}: key '{k}' missing after")
            bad += 1
        for k in sorted(kb - ka):
            print(f"{run}: key '{k}' new after")
            bad += 1
        for k in sorted(ka & kb):
            if timing.search(k) or k == "mode":
                continue
            compared += 1
            if a[k] != b[k]:
                va = a[k][1] if isinstance(a[k], tuple) else a[k]
                vb = b[k][1] if isinstance(b[k], tuple) else b[k]
                print(f"{run}: {k}: {va} -> {vb}")
                bad += 1
    print(f"{len(set(before) & set(after))} runs in both, {compared} non-timing figures compared, {bad} differences")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
