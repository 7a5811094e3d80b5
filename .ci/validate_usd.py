#!/usr/bin/env python3
"""Runs every validator usd-core registers (UsdValidation) on each .usda under a folder and counts
the issues of any severity. Exit 1 on any issue, on no file found, or when usd-core is missing."""
import os
import sys

try:
    from pxr import Usd, UsdValidation
except ImportError as e:  # a missing tool fails CI rather than skipping
    print(f"validate_usd: usd-core is not installed ({e}); run .ci/setup-validators", file=sys.stderr)
    sys.exit(1)


def main(root):
    files = sorted(
        os.path.join(d, f) for d, _, fs in os.walk(root) for f in fs if f.endswith((".usda", ".usd", ".usdc"))
    )
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    ctx = UsdValidation.ValidationContext(validators)
    issues = 0
    for path in files:
        stage = Usd.Stage.Open(path)
        if stage is None:
            print(f"  {path}: usd-core cannot open it")
            issues += 1
            continue
        errors = ctx.Validate(stage)
        for e in errors:
            print(f"  {path}: {e.GetErrorType()} {e.GetName()}: {e.GetMessage()}")
        issues += len(errors)
    print(f"usd: {len(files)} files checked with {len(validators)} usd-core validators, {issues} issues")
    if not files:
        print(f"usd: no .usda under {root}: the test suite must write some", file=sys.stderr)
        return 1
    return 1 if issues else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
