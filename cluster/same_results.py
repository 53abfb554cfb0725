#!/usr/bin/env python3
"""Checks that two hexsim batch results files hold the same results, bit for bit.

    same_results.py A.jsonl B.jsonl

Every field of every scenario must be equal (JSON numbers are printed shortest-round-trip, so equal
text is equal bits), but those that say how and when a result was made, not what it is: the wall
time, the steps per second and which shard ran it. Exit 0 when equal, 1 with the first difference.
"""
import json
import sys

# How a result was made, not what it is.
CIRCUMSTANCES = ("wall_time_s", "steps_per_second", "shard")


def load(path):
    results = {}
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            record = json.loads(line)
            for key in CIRCUMSTANCES:
                record.pop(key, None)
            name = record["name"]
            if name in results:
                sys.exit(f"{path}:{number}: {name} appears twice")
            results[name] = record
    return results


def first_difference(a, b, where):
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if key not in a or key not in b:
                return f"{where}.{key}: only in {'the second' if key not in a else 'the first'}"
            found = first_difference(a[key], b[key], f"{where}.{key}")
            if found:
                return found
        return None
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            found = first_difference(x, y, f"{where}[{i}]")
            if found:
                return found
        return None
    return None if a == b and type(a) is type(b) else f"{where}: {a!r} != {b!r}"


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    a, b = (load(path) for path in sys.argv[1:])
    if set(a) != set(b):
        only = sorted(set(a) ^ set(b))
        sys.exit(f"the files hold different scenarios: {only[:5]}")
    for name in sorted(a):
        found = first_difference(a[name], b[name], name)
        if found:
            sys.exit(f"results differ: {found}")
    print(f"same results: {len(a)} scenarios, every field but {', '.join(CIRCUMSTANCES)}")


main()
