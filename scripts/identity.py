#!/usr/bin/env python3
"""Fingerprints of every shipped scenario's results: a behaviour-preserving
change (a refactor) must leave them byte-identical.

    python3 scripts/identity.py BINARY OUT.json [PATH...]
    python3 scripts/identity.py --compare A.json B.json

The first form runs every scenario of the PATHs (files or directories;
default scenarios/)
with BINARY (logs in a temporary directory) and writes, per scenario, the
SHA-256 of its metrics (summary.json's `metrics`, canonical JSON) and of
its run.mcap. The second form lists every scenario whose fingerprints
differ; exit 1 when any does.
"""

import hashlib
import json
import pathlib
import subprocess
import sys
import tempfile


def sha(b):
    return hashlib.sha256(b).hexdigest()


def fingerprints(binary, scenarios):
    out = {}
    with tempfile.TemporaryDirectory() as logs:
        subprocess.run(
            [binary, "run", *scenarios, "--logs", logs, "--quiet"],
            check=False,
            stdout=subprocess.DEVNULL,
        )
        for d in sorted(pathlib.Path(logs).iterdir()):
            summary = d / "summary.json"
            if not summary.is_file():
                continue
            metrics = json.loads(summary.read_text())["metrics"]
            mcap = d / "run.mcap"
            out[d.name] = {
                "metrics": sha(json.dumps(metrics, sort_keys=True).encode()),
                "run.mcap": sha(mcap.read_bytes()) if mcap.is_file() else None,
            }
    return out


def main():
    if sys.argv[1] == "--compare":
        a = json.loads(pathlib.Path(sys.argv[2]).read_text())
        b = json.loads(pathlib.Path(sys.argv[3]).read_text())
        differ = 0
        for name in sorted(set(a) | set(b)):
            for key in ("metrics", "run.mcap"):
                if a.get(name, {}).get(key) != b.get(name, {}).get(key):
                    print(f"{name}: {key} differs")
                    differ += 1
        print(f"{len(set(a) & set(b))} scenarios compared, {differ} fingerprints differ")
        sys.exit(1 if differ else 0)
    binary, out = sys.argv[1], sys.argv[2]
    scenarios = sys.argv[3:] or ["scenarios"]
    fp = fingerprints(binary, scenarios)
    pathlib.Path(out).write_text(json.dumps(fp, indent=1, sort_keys=True) + "\n")
    print(f"{len(fp)} scenarios fingerprinted into {out}")


if __name__ == "__main__":
    main()
